/* sabodem: 3-D DEM of debris flow with boulders and driftwood against a grid-type sabo dam.
 * The one public header. Units: SI everywhere. Frame: SPEC §8 (x downstream, z normal to bed).
 * The API hands out stable global ids (gid), never pointers into arrays that get re-sorted. */
#ifndef SABODEM_H
#define SABODEM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#ifndef SD_VEC_TYPES_DEFINED
#define SD_VEC_TYPES_DEFINED
typedef struct {
    double x, y, z;
} sd_vec3;

typedef struct {
    double w, x, y, z; /* unit quaternion, w scalar part */
} sd_quat;
#endif

/* Status codes: one table, with messages. */
#define SD_STATUS_TABLE(X)                                                       \
    X(SD_OK, "ok")                                                               \
    X(SD_ERR_NOMEM, "out of memory")                                             \
    X(SD_ERR_ARG, "invalid argument")                                            \
    X(SD_ERR_IO, "input/output error")                                           \
    X(SD_ERR_PARSE, "invalid scenario")                                          \
    X(SD_ERR_UNSTABLE, "time step too large for the stiffness and smallest mass") \
    X(SD_ERR_NONFINITE, "non-finite state (simulation blew up)")                 \
    X(SD_ERR_OVERLAP, "overlap beyond half a radius (time step or stiffness)")   \
    X(SD_ERR_NOTFOUND, "no such element")                                        \
    X(SD_ERR_FORMAT, "corrupt or foreign file")                                  \
    X(SD_ERR_INTERRUPTED, "interrupted")

typedef enum {
#define SD_X_ENUM(name, msg) name,
    SD_STATUS_TABLE(SD_X_ENUM)
#undef SD_X_ENUM
        SD_STATUS_COUNT
} sd_status;

const char *sd_status_message(sd_status s);

enum { SD_SHAPE_SPHERE = 0, SD_SHAPE_CYLINDER = 1 };

/* Contact springs (SPEC §3). */
typedef struct {
    double k_n;      /* normal spring, N/m */
    double k_s;      /* tangential spring, N/m */
    double damping;  /* damping ratio h (dimensionless); c = 2h sqrt(m* k) */
    double tan_phi;  /* friction coefficient tan(phi) */
    double cohesion; /* c in the Mohr–Coulomb limit, N */
} sd_contact_def;

/* Materials: every body and triangle has a material id, 0 .. SD_MATERIALS_MAX - 1 (0 unless
 * given), and a contact between materials a and b follows the springs set for that pair
 * (sd_world_set_pair_contact), or the world's def.contact where none were set. With one
 * material, or no pair set, every contact has def.contact's springs (SPEC §3). */
#define SD_MATERIALS_MAX 16

/* How the engine runs, never what it computes: every setting gives the same bits. The library
 * reads no environment; sd_tuning_from_env is the one place that does, for programs that want
 * the environment to choose (the sabodem CLI does). */
/* (zero is AUTO: a zeroed sd_tuning is the default one) */
enum { SD_SIMD_AUTO = 0, SD_SIMD_SCALAR = 1, SD_SIMD_AVX2 = 2, SD_SIMD_AVX512 = 3 };
enum { SD_PREFETCH_AUTO = 0, SD_PREFETCH_OFF = 1, SD_PREFETCH_ON = 2 };
typedef struct {
    int simd;       /* SD_SIMD_*: the hand-written kernels' width; AUTO: the CPU's best, but AVX2
                     * on AMD CPUs (their AVX-512 gathers are slower); capped at the CPU's */
    int prefetch;   /* SD_PREFETCH_*: the body pass's prefetch of the bodies it reaches first;
                     * AUTO: tried on and off during the run, the faster kept */
    long llc_bytes; /* last-level cache per core, bytes: the prefetch's guess before its first
                     * trial; 0: unknown (32 MiB assumed) */
} sd_tuning;

sd_tuning sd_tuning_default(void);
/* t from the process's environment: SD_SIMD (scalar, avx2, avx512), SD_NO_AVX512 (1: scalar),
 * SD_PREFETCH (on, off, auto) and the last-level cache's size from the operating system.
 * Returns SD_ERR_ARG for a value it does not know, naming it in msg (t is filled either way,
 * with that value left at its default). */
sd_status sd_tuning_from_env(sd_tuning *t, char *msg, size_t msg_len);

typedef struct {
    sd_vec3 gravity;      /* m/s^2 */
    double dt;            /* time step, s */
    double margin;        /* candidate margin r_dam, m */
    double t_reset;       /* candidate list rebuild interval, s */
    sd_contact_def contact;
    int threads;          /* OpenMP threads of this world, 0 = the runtime's default when created */
    int parallel_min;     /* loops shorter than this run on one thread (start-up costs more) */
    int check_dt;         /* 1: refuse a dt that is unstable for k_n and the smallest mass */
    sd_tuning tuning;
} sd_world_def;

sd_world_def sd_world_def_default(void);

typedef struct {
    sd_vec3 pos;     /* m */
    sd_vec3 vel;     /* m/s */
    sd_vec3 omega;   /* rad/s */
    double radius;   /* m */
    double density;  /* kg/m^3 */
    int fixed;       /* 1: never integrated (bed roughness) */
    int tag;         /* user class (size class, 0..); reported back, no physics */
    int material;    /* material id, 0 .. SD_MATERIALS_MAX - 1 */
} sd_sphere_def;

typedef struct {
    sd_vec3 pos;     /* centre, m */
    sd_vec3 axis;    /* axis direction (normalised by the library) */
    sd_vec3 vel;     /* m/s */
    sd_vec3 omega;   /* rad/s */
    double radius;   /* m */
    double length;   /* full length 2l, m */
    double density;  /* kg/m^3 */
    int fixed;       /* 1: dam pipe */
    int tag;
    int material;    /* material id, 0 .. SD_MATERIALS_MAX - 1 */
} sd_cylinder_def;

sd_sphere_def sd_sphere_def_default(void);
sd_cylinder_def sd_cylinder_def_default(void);

typedef struct {
    int gid;
    int shape;       /* SD_SHAPE_* */
    int fixed, tag;
    sd_vec3 pos, vel, omega, axis;
    sd_vec3 force;   /* total contact force of the last step, N */
    sd_vec3 torque;  /* total contact torque of the last step, N m */
    double radius, length, mass;
    int material;
} sd_body_state;

typedef struct sd_world sd_world;

sd_status sd_world_create(const sd_world_def *def, sd_world **out);
void sd_world_destroy(sd_world *w);

/* Add elements; return the new gid (>= 0) or -(sd_status) on bad input. */
int sd_world_add_sphere(sd_world *w, const sd_sphere_def *d);
int sd_world_add_cylinder(sd_world *w, const sd_cylinder_def *d);
/* Static triangle wall; group names a set (floor, walls, gate...) that can be disabled. */
int sd_world_add_triangle(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, int group);
sd_status sd_world_set_group_active(sd_world *w, int group, int active);
sd_status sd_world_remove_body(sd_world *w, int gid);
/* Triangle i's material (0 when added). */
sd_status sd_world_set_triangle_material(sd_world *w, int triangle, int material);
int sd_world_triangle_material(const sd_world *w, int triangle); /* -1: no such triangle */
/* The springs of a contact between materials a and b (and b and a) from the next step on;
 * c NULL: def.contact again. SD_ERR_ARG for an id out of range or springs that
 * sd_world_create would refuse in def.contact. */
sd_status sd_world_set_pair_contact(sd_world *w, int a, int b, const sd_contact_def *c);
/* The springs of the pair (a, b) into *c (may be NULL): 1 when set for the pair, 0 when they are
 * def.contact, -1 for an id out of range. */
int sd_world_pair_contact(const sd_world *w, int a, int b, sd_contact_def *c);
/* dst takes src's springs per pair of materials and its triangles' materials (dst holds the
 * same triangles, in the same order: SD_ERR_ARG otherwise); for a world made from another's
 * triangles and body records, which carry the bodies' materials themselves. */
sd_status sd_world_copy_materials(sd_world *dst, const sd_world *src);

/* The largest stable time step for the springs k_n, k_s (N/m) and the smallest moving sphere
 * mass m_min (kg): 8 steps per half period of the stiffest mode of a contact between two such
 * spheres, the normal one (ω_n² = k_n/m*) or the tangential–rotational one (ω_t² = (7/2) k_s/m*),
 * m* = m_min/2 (docs/physics.md §1). INFINITY when there is no moving mass. */
double sd_stable_dt_max(double k_n, double k_s, double m_min);
/* The world's largest stable time step: sd_stable_dt_max for each pair of materials a, b that
 * can meet (a of a moving body, b of any body or triangle) with the smallest moving mass of
 * material a, the smallest of them; *a, *b (may be NULL) get the pair that sets it. */
double sd_world_stable_dt(const sd_world *w, int *a, int *b);
/* Validate settings against the elements present (time-step stability); called by step. */
sd_status sd_world_check(const sd_world *w);
sd_status sd_world_step(sd_world *w);
sd_status sd_world_run(sd_world *w, long steps);

double sd_world_time(const sd_world *w);
long sd_world_step_count(const sd_world *w);
int sd_world_body_count(const sd_world *w);
int sd_world_triangle_count(const sd_world *w);
/* Body by position in the store (0..count-1); the order may change between steps. */
sd_status sd_world_body_at(const sd_world *w, int index, sd_body_state *out);
sd_status sd_world_body(const sd_world *w, int gid, sd_body_state *out);
/* Sum of contact forces on the active triangles of a group in the last step, N. */
sd_vec3 sd_world_group_force(const sd_world *w, int group);
/* Number of active contacts (manifold points) in the last step. */
long sd_world_contact_count(const sd_world *w);
/* Kinetic energy (translation + rotation) of the moving bodies, J. */
double sd_world_kinetic_energy(const sd_world *w);
/* Elastic energy stored in the normal and tangential springs, J. */
double sd_world_spring_energy(const sd_world *w);
/* Gravitational potential energy of the moving bodies (-m g.x), J. */
double sd_world_potential_energy(const sd_world *w);
/* The body store's arrays, read-only, in store order (0 .. n-1; the order changes when the
 * candidates are rebuilt): for code that visits every body each step (a water model, outputs,
 * statistics) without a call per body. Valid until the next step, addition or removal. */
typedef struct {
    int n;
    const int32_t *gid, *tag;
    const uint8_t *shape, *fixed;  /* SD_SHAPE_*; 1 for a fixed body */
    const sd_vec3 *pos, *vel;      /* centre, m; velocity, m/s */
    const sd_vec3 *omega, *axis;   /* angular velocity, rad/s; a cylinder's unit axis */
    const sd_vec3 *force, *torque; /* contact force and torque of the last step, N, N m */
    const double *radius;          /* m */
    const double *half_length;     /* a cylinder's half length, m (0 for a sphere) */
    const double *bound_radius;    /* the bounding sphere's radius, m */
    const double *mass;            /* kg */
} sd_body_view;
sd_body_view sd_world_bodies(const sd_world *w);
/* The farthest downstream point (largest x of a surface) of the moving bodies, m; -inf when
 * none moves. */
double sd_world_front_x(const sd_world *w);
/* Triangle i's corners, group and whether its group is active. */
sd_status sd_world_triangle(const sd_world *w, int i, sd_vec3 corner[3], int *group, int *active);
/* The world's definition as created (its threads and tuning as set since). */
const sd_world_def *sd_world_definition(const sd_world *w);
/* The prefetch's state for reports: SD_PREFETCH_ON or _OFF as it runs now; *trial: the last
 * trial's verdict in auto mode (-1 none yet, 0 off, 1 on) and *ratio its time on over off. */
int sd_world_prefetch(const sd_world *w, int *trial, double *ratio);

/* External forces computed inside the step (a water model): fn fills out[k - k0] with the
 * force on body index[k] (a store index, sd_world_bodies) for k0 <= k < k1, a block of at most
 * SD_EXTERNAL_BLOCK moving bodies, called by the thread that moves them just before it moves
 * them (their data are then in its cache), so fn must be safe to call from several threads at
 * once. While set, it replaces the forces of sd_world_set_external_force; NULL removes it. The
 * hook is not saved in checkpoints. */
#define SD_EXTERNAL_BLOCK 128
typedef void (*sd_external_force_fn)(void *ctx, const sd_world *w, const int32_t *index, int k0, int k1,
                                     sd_vec3 *out);
void sd_world_set_external_force_fn(sd_world *w, sd_external_force_fn fn, void *ctx);
/* Set an external force (fluid) on a body for the next steps, N. */
sd_status sd_world_set_external_force(sd_world *w, int gid, sd_vec3 f);
/* The threads this world's steps use from now on (>= 1); the same bits for any count. */
sd_status sd_world_set_threads(sd_world *w, int threads);
int sd_world_threads(const sd_world *w);
/* The SIMD level (SD_SIMD_SCALAR, _AVX2, _AVX512) the world's kernels run at, and a new one
 * (capped at the CPU's; returns the level it took). The same bits at every level. */
int sd_world_simd_level(const sd_world *w);
int sd_world_set_simd_level(sd_world *w, int level);
/* The whole tuning replaced (a world read from a checkpoint gets the defaults: the file keeps
 * what the world is, not how it ran). */
sd_status sd_world_set_tuning(sd_world *w, const sd_tuning *t);
/* The best SIMD level this CPU has. */
int sd_cpu_simd_level(void);
/* Force candidate lists to be rebuilt at every step (for tests). */
void sd_world_set_rebuild_every_step(sd_world *w, int on);
/* Hash of the full dynamic state (positions, velocities, attitudes, history). */
uint64_t sd_world_state_hash(const sd_world *w);

/* ---- Spatial decomposition (docs/decomposition.md): one system held by several worlds, each
 * the bodies of a slab along x (owned) plus ghost copies of its neighbours' bodies near it, and
 * each owned body's forces the same bits as in one world holding everything. ---- */

/* A fixed body grid: origin lo, cell size and counts. With it a rebuild sorts the bodies by
 * (cell, gid) instead of (cell, previous order), so that the store's order, and with it every
 * body's pair order, depends on the positions and gids alone: worlds holding parts of one
 * system with the same grid order their common bodies alike. The one-world reference of a
 * decomposed run uses it too (its bits differ from the automatic grid's). Bodies outside the
 * grid count in its edge cells. cell must be at least the largest sphere diameter plus the
 * margin (a rebuild returns SD_ERR_ARG otherwise). NULL: back to the automatic grid. */
typedef struct {
    sd_vec3 lo;
    double cell;
    int nx, ny, nz;
} sd_grid_def;
sd_status sd_world_set_fixed_grid(sd_world *w, const sd_grid_def *g);
/* The grid's cell for a world's bodies (the largest sphere diameter plus the margin) */
double sd_world_min_grid_cell(const sd_world *w);

/* A body's whole state (every field of the store, bit for bit) as an opaque record of
 * sd_body_record_size() bytes, and its gid. */
size_t sd_body_record_size(void);
sd_status sd_world_body_record(const sd_world *w, int gid, void *rec);
int sd_body_record_gid(const void *rec);
/* Puts a record into w: a body of its gid is added when w has none (the pairs are remade at
 * the next step, as after sd_world_add_sphere), else that body's state is overwritten in place
 * (same shape and fixedness, else SD_ERR_ARG; no rebuild). ghost 1: the body takes part in the
 * contacts but is not moved by this world (its owner moves it and sends it back each step); 0:
 * an ordinary body. */
sd_status sd_world_body_put(sd_world *w, const void *rec, int ghost);
int sd_world_body_is_ghost(const sd_world *w, int gid);

/* A tangential spring of a pair: body-body pairs (kind 0-2) by the gids of their bodies in
 * (shape, gid) order, body-triangle pairs (kind 3-4) by the body's gid and the triangle's index;
 * feature: which of the pair's contact points. */
typedef struct {
    int32_t gid_a, kind, id_b, feature;
    sd_vec3 shear; /* N */
} sd_spring;
/* The springs w holds now (its pairs in contact, or those taken out for the coming rebuild):
 * fills out[0 .. min(count, cap)) and returns the count. */
int sd_world_springs(const sd_world *w, sd_spring *out, int cap);
/* Springs for w's next rebuild to give its pairs of those keys (the pairs' own first, where w
 * has them); sets off that rebuild. */
sd_status sd_world_springs_put(sd_world *w, const sd_spring *s, int n);

/* Whether the next step remakes the candidate pairs (a body moved past half the margin,
 * t_reset passed, the store or the walls changed), and a request that it does. */
int sd_world_needs_rebuild(const sd_world *w);
void sd_world_request_rebuild(sd_world *w);
/* The clock of a world made from another's state (time in s, steps done). */
sd_status sd_world_set_clock(sd_world *w, double time, long step);
/* The gids the next added body gets from here on: at least next_gid (a world made of another's
 * bodies gives its additions the gids the other would). SD_ERR_ARG below a gid in use. */
sd_status sd_world_set_next_gid(sd_world *w, int next_gid);
int sd_world_next_gid(const sd_world *w);
/* The last step's force of the active triangles of a group (every group: group < 0) on each
 * body, N, out[i] by store index (sd_world_bodies), each body's wall pairs summed in their
 * order: the same bits in every world that holds the body's wall pairs, so that worlds holding
 * parts of one system can add up the walls' loads over their own bodies. */
sd_status sd_world_body_wall_forces(const sd_world *w, int group, sd_vec3 *out);

/* Hash of a state given as body records and springs, in a canonical order (bodies by gid:
 * position, velocity, spin, attitude, force; springs by key: shear), the same FNV-1a as
 * sd_world_state_hash; equal hashes, the same state bit for bit. The one of a whole world:
 * every body and spring of w. */
uint64_t sd_state_hash_records(const void *recs, int nb, const sd_spring *springs, int ns);
uint64_t sd_world_state_hash_canonical(const sd_world *w);

/* Checkpoints: the whole state of a world in one versioned, checksummed file, from which a run
 * continues bit for bit as if never stopped (the format: src/io_checkpoint.h).
 * Write w and an opaque blob of the caller's (extra) to path atomically: a temporary file in the
 * same directory, fsynced, renamed over path; on any failure the previous file at path is
 * untouched. SD_ERR_ARG: NULL path or world, or extra_len > 0 with extra NULL; SD_ERR_IO: not
 * written (errno kept); SD_ERR_NOMEM. */
sd_status sd_checkpoint_write(const char *path, const sd_world *w, const void *extra, size_t extra_len);
/* Read a checkpoint into a new world (*out, destroy with sd_world_destroy) and the blob (*extra
 * malloc'ed, free() it; NULL when extra_len is 0). extra, extra_len, msg may be NULL.
 * SD_ERR_FORMAT for an empty, truncated, corrupted, foreign or incompatible file; SD_ERR_IO when
 * it cannot be read; SD_ERR_NOMEM. On failure *out and *extra are NULL and msg (msglen bytes)
 * names the file and what is wrong. */
sd_status sd_checkpoint_read(const char *path, sd_world **out, void **extra, size_t *extra_len, char *msg,
                             size_t msglen);
/* The format version of the checkpoints this library writes and reads (a file of another is
 * refused). */
uint32_t sd_checkpoint_version(void);

/* Wall time of the step's stages (seconds, summed over the steps). */
typedef struct {
    double rebuild;  /* the candidate pairs and the grid, when a step needs them anew */
    double contacts; /* the contact pass: forces, and with several threads the moves of the
                      * bodies each thread owns, which it makes in the same pass */
    double moves;    /* the moves made apart from the pass (one thread) */
    double checks;   /* the health check of the state, every 1024 steps */
    long rebuilds;
} sd_world_timers;
sd_world_timers sd_world_get_timers(const sd_world *w);

#ifdef __cplusplus
}
#endif
#endif
