/* Scenario files (YAML via libyaml) → definitions. One parameter table drives the loader, the
 * range checks, `sabodem params`, docs/scenario.md and the echo in each run's summary. */
#ifndef SD_SCENARIO_H
#define SD_SCENARIO_H

#include <stdint.h>
#include <stdio.h>

#include "debris.h"
#include "sabodem.h"
#include "sabodem_run.h"

#define SD_MAX_CLASSES 16
#define SD_MAX_IDS 64
#define SD_MAX_PIPES 32
/* The most arbitrary dam members (dam.members). */
#define SD_MAX_MEMBERS 32
/* Every coordinate and size in a scenario lies within this many metres of the origin. */
#define SD_MAX_EXTENT 1.0e4

/* The choices of the scenario's enumerated keys (their index is the stored value). */
enum { SD_BUOYANCY_VERTICAL = 0, SD_BUOYANCY_BED_NORMAL = 1 };
enum { SD_CAPTURE_END_TRAP_PLANE = 0, SD_CAPTURE_END_DAM_FACE = 1 };
enum { SD_CLASSES_COUNTS = 0, SD_CLASSES_GRADING = 1, SD_CLASSES_CURVE = 2 };
enum { SD_SCENE_WATER_NONE = 0, SD_SCENE_WATER_FLOW = 1, SD_SCENE_WATER_UNIFORM = 2, SD_SCENE_WATER_STILL = 3 };

typedef struct {
    int type; /* 0 sphere, 1 cylinder, 2 triangle */
    sd_vec3 pos, vel, omega, axis;
    double radius, length, density;
    int fixed, tag, group, material;
    sd_vec3 v[3];
    int line;
} sd_elem_def;

/* A dam member (dam.members): a fixed steel pipe from one point to another, any orientation. */
typedef struct {
    sd_vec3 from, to; /* the ends of its axis, m (the flume frame) */
    double diameter;  /* m */
    int line, col;    /* where it was given (the file's, or the --set's) */
} sd_dam_member;
/* A mesh's role: the wall group its triangles join (build.h: SD_GROUP_BED, _WALLS, _DAM). */
enum { SD_MESH_BED = 0, SD_MESH_WALL = 1, SD_MESH_DAM = 2 };
/* The most entries of meshes: */
#define SD_MAX_MESHES 64

/* One entry of meshes: (docs/meshes.md): an STL file's triangles, read and transformed when the
 * scenario is loaded (corner' = R (scale corner) + translate, R = Rz Ry Rx of rotate_deg). */
typedef struct {
    char file[1024]; /* the path read: relative paths are taken from the scenario file's directory */
    int role;        /* SD_MESH_* */
    double scale;
    sd_vec3 translate, rotate_deg;
    sd_vec3 (*tri)[3]; /* the triangles, transformed, m */
    int n_tri;
    int binary;   /* the file was binary STL */
    int material; /* its triangles' material (an id) */
    int line;     /* the entry's line in the scenario */
} sd_mesh_def;

/* Materials (scenario_materials.c): names by id, id 0 the implicit "default" of everything not
 * given one; a pair's springs (contact_pairs) give some of the five constants of contact.*, in
 * its order (k_n, k_s, damping, tan_phi, cohesion), the others are contact.*'s. */
#define SD_MATERIAL_NAME_MAX 32
#define SD_MAX_PAIRS (SD_MATERIALS_MAX * (SD_MATERIALS_MAX + 1) / 2)
enum { SD_PAIR_KEYS = 5 };
typedef struct {
    int a, b;                 /* material ids, a <= b */
    double v[SD_PAIR_KEYS];   /* the constants given */
    unsigned given;           /* bit k: v[k] given */
    int line, col;            /* where the entry is */
} sd_pair_def;

typedef struct sd_scenario {
    char path[1024];
    sd_world_def world;
    /* materials: n_materials names (0: "default"), the pairs given their own springs, and the
     * materials of what the builders make (ids) */
    int n_materials;
    char material_name[SD_MATERIALS_MAX][SD_MATERIAL_NAME_MAX];
    int n_pairs;
    sd_pair_def pairs[SD_MAX_PAIRS];
    int sphere_mat[SD_MAX_CLASSES], n_sphere_mats; /* per size class (one: every class; none: 0) */
    int log_mat, pipe_mat, bed_mat, wall_mat, rough_mat, gate_mat, pile_mat, box_mat;
    double duration; /* s */
    long seed;
    /* explicit elements */
    sd_elem_def *elems;
    int n_elems;
    /* STL meshes as fixed walls */
    sd_mesh_def *meshes;
    int n_meshes;
    /* box of triangles (open top) */
    int box_on;
    sd_vec3 box_min, box_max;
    /* random pile of spheres */
    int pile_n_classes, pile_n_counts; /* the two lists' lengths (equal once loaded) */
    double pile_diam[SD_MAX_CLASSES];
    int pile_count[SD_MAX_CLASSES];
    double pile_density;
    sd_vec3 pile_min, pile_max;
    /* flume (SPEC §8); on when flume.on */
    int flume_on;
    int flume_bed; /* the flume's flat bed (0: a mesh with role bed replaces it) */
    double slope_deg, width, wall_height, x_gate, x_dam, x_end;
    int roughness_on;
    double rough_dmin, rough_dmax, rough_coverage;
    int n_classes, n_class_counts; /* the two lists' lengths (equal once loaded) */
    double class_diam[SD_MAX_CLASSES];
    int class_count[SD_MAX_CLASSES];
    double sphere_density;
    /* the classes as designers give them (debris.h), resolved by the loader into class_diam and
     * class_count above: a grading by mass fractions, or a continuous curve cut into classes,
     * with the solid volume to release */
    int n_grading_diam, n_grading_frac; /* the two lists' lengths */
    double grading_diam[SD_MAX_CLASSES], grading_frac[SD_MAX_CLASSES];
    sd_grading_curve curve;             /* curve.type SD_GRADING_NONE: none */
    double sphere_volume;               /* spheres.volume, m^3 (0: the counts are given) */
    int class_source;                   /* derived: SD_CLASSES_COUNTS, _GRADING or _CURVE */
    double class_target[SD_MAX_CLASSES]; /* derived: each class's mass fraction asked for */
    sd_size_dist log_length_dist, log_diam_dist; /* type SD_SIZE_FIXED: log_length, log_diam */
    int log_count;
    double log_kw; /* woody volume ratio; used when >= 0 and log_count < 0 */
    double log_diam, log_length, log_density;
    double pack_x0, pack_height; /* packing box: x from pack_x0 to x_gate, up to pack_height */
    double volume_factor;        /* the counts above as loaded are the file's times this factor */
    /* grid dam: the columns from one of dam.columns, dam.n_columns, dam.l_h (in that order of
     * precedence; the loader lets only one be given); the beams from one of dam.beams (every
     * beam), dam.beam_axes, dam.beam_gaps, dam.l_v (each with the top beam unless
     * dam.top_beam is false); then the members */
    int dam_on;
    double pipe_diam, l_h, l_v, top_beam;
    int top_beam_on;  /* 0: dam.top_beam: false (no top beam) */
    int n_columns, n_beams;
    int column_count; /* dam.n_columns: -1 not given */
    int dam_support; /* bending moments: 0 simple supports, 1 fixed ends (pipe_loads.h) */
    double event_threshold; /* a pipe's impact event: |F| this far above its baseline, N (0: auto) */
    double event_time;      /* the baseline's time constant and the longest event, s */
    double column_y[SD_MAX_PIPES];
    double beam_z[SD_MAX_PIPES]; /* underside heights */
    int n_beam_axes, n_beam_gaps;
    double beam_axis_z[SD_MAX_PIPES]; /* dam.beam_axes: axis heights above the bed */
    double beam_gap[SD_MAX_PIPES];    /* dam.beam_gaps: clear gaps, bed to the lowest beam, then beam to beam */
    int n_members;
    sd_dam_member members[SD_MAX_MEMBERS];
    /* water */
    int water_on;
    double water_u, water_h, water_rho, water_cd, water_probe;
    int water_hd_floating; /* floating elements count in h_D (default 0: only those denser than water) */
    int water_buoyancy;    /* the flow phase's buoyancy: SD_BUOYANCY_VERTICAL or SD_BUOYANCY_BED_NORMAL */
    double water_capture_length; /* the pond reaches this far upstream of the dam face, m (0: the whole flume) */
    int water_capture_end;       /* the pond's downstream end: SD_CAPTURE_END_TRAP_PLANE or _DAM_FACE */
    int water_scene;             /* water in a scene without a flume: SD_SCENE_WATER_* */
    double log_kw_volume;        /* eq 54's V for the log count, m^3 (0: the spheres' solid volume) */
    /* phases */
    double packing_time, capture_limit, quiet_time, ke_fraction, flow_limit;
    double packing_rest_speed, packing_min_time; /* packing ends at rest (m/s), not before (s) */
    /* output */
    double snapshot_interval, log_interval;
    double checkpoint_interval; /* simulated s between periodic checkpoints (0: none) */
    int n_traj;
    int traj_ids[SD_MAX_IDS];
    double traj_interval;
    int vtk_on, png_on;
} sd_scenario;

/* What a scenario will cost, estimated from its parameters before anything is allocated
 * (scenario_cost.c). */
typedef struct {
    double bodies;  /* elements the scene can hold at most (roughness at its smallest size) */
    double bytes;   /* memory: the elements with their contacts, the placement grids */
    double steps;   /* time steps to the end at most (a flume: to the sum of its phases' limits) */
    double expected_steps; /* time steps expected (a flume's flow: the front at 0.8 water.u) */
    double moving;  /* of the bodies, those that move (not roughness, pipes or fixed elements) */
    double seconds; /* wall time on one core over the expected steps, at SD_COST_S_PER_MOVING_STEP a
                     * moving element and SD_COST_S_PER_FIXED_STEP a fixed one */
    double flow_steps, flow_seconds; /* of the expected, the packing's and the flow's (a flume; else 0):
                                      * what the runs a sweep branches from one flow share */
} sd_scenario_cost;

/* Limits a scenario's estimate must keep to (the command line's --max-memory, --max-steps). */
typedef struct {
    double max_bytes, max_steps;
} sd_scenario_limits;

#define SD_DEFAULT_MAX_MEMORY (8.0 * 1024 * 1024 * 1024) /* bytes */
#define SD_DEFAULT_MAX_STEPS 1.0e8 /* the paper's run takes 0.9e6 */
#define SD_BYTES_PER_ELEMENT 2048.0 /* an element with its contacts; ~1 KB measured on the paper's flume */
/* one core, per element and step: the paper's run (examples/shibuya2009.yaml: 4769 moving
 * elements, 6438 roughness spheres, 1.17e6 steps, ~450 s of one core; docs/performance.md) */
#define SD_COST_S_PER_MOVING_STEP 8.0e-8
#define SD_COST_S_PER_FIXED_STEP 2.0e-9
/* the flow front's mean speed over the flume, a fraction of water.u (the paper's run: 3.65 m in
 * 3.7 s at U = 1.2 m/s) */
#define SD_COST_FRONT_SPEED_OF_U 0.8

void sd_scenario_estimate(const sd_scenario *s, sd_scenario_cost *c);
/* 0 when c keeps to lim; otherwise -1 and a message to err that gives the estimate and says
 * which keys and which option change it. */
int sd_scenario_check_cost(const sd_scenario *s, const sd_scenario_cost *c, const sd_scenario_limits *lim, FILE *err);
sd_scenario_limits sd_scenario_limits_default(void);
/* Seconds as whole milliseconds, the unit in which a sweep adds estimates up (exact in a double
 * below 2^53 ms, 285,000 years), and such a count as text, "12.345 s". */
double sd_scenario_ms(double seconds);
void sd_scenario_ms_text(double ms, char *buf, size_t n);
/* A time in seconds in words: "38 s", "12 min", "3.2 h", "41 days". */
void sd_scenario_human_time(double seconds, char *buf, size_t n);
/* `check`'s line: "time estimate: 12.345 s on one core (packing and flow 8.230 s, capture
 * 4.115 s)", in whole milliseconds, the numbers a sweep's estimate adds up. */
void sd_scenario_print_time(FILE *f, const sd_scenario *s, const sd_scenario_cost *c);

void sd_scenario_default(sd_scenario *s);
/* Load a scenario file and apply "key=value" overrides. Errors are printed to err as
 * file:line:col: message (several collected); returns 0 on success. */
int sd_scenario_load(sd_scenario *s, const char *path, const char *const *overrides, int n_overrides, FILE *err);
/* The same from YAML text; name stands for the file in its messages (and s->path). */
int sd_scenario_load_string(sd_scenario *s, const char *text, const char *name, const char *const *overrides,
                            int n_overrides, FILE *err);
void sd_scenario_free(sd_scenario *s);
/* Print the parameter table: as text (`sabodem params`), markdown (docs/scenario.md) or roff
 * (the man page's KEYS section). */
enum { SD_PARAMS_TEXT = 0, SD_PARAMS_MARKDOWN = 1, SD_PARAMS_ROFF = 2 };
void sd_scenario_print_params(FILE *f, int format);
/* The keys, in table order: how many, and the i-th (NULL out of range). */
int sd_scenario_param_count(void);
const char *sd_scenario_param_key(int i);
/* The effective values as a JSON object, key by key (the run summary's "parameters"); NULL
 * when out of memory. The caller owns it (cJSON_Delete). */
struct cJSON;
struct cJSON *sd_scenario_params_json(const sd_scenario *s);
/* 1 for the keys that act only from the capture phase on: the dam layout (dam.l_h, dam.l_v,
 * dam.top_beam, dam.columns, dam.beams, dam.n_columns, dam.beam_axes, dam.beam_gaps,
 * dam.members, dam.material) and the capture-phase settings (phases.capture_limit,
 * quiet_time, ke_fraction, water.probe, water.h_d_floating, water.capture_length,
 * water.capture_end). Runs that differ only in these
 * share their packing and flow, bit for bit: a sweep branches them from one flow-end
 * checkpoint (docs/sweep.md). */
int sd_scenario_is_capture_key(const char *key);
/* Fingerprint of everything else (every other parameter, exactly, and the explicit elements):
 * equal for two scenarios whose packing and flow are identical. Stored in a flow-end
 * checkpoint; a restart with a scenario of another fingerprint is refused. */
uint64_t sd_scenario_branch_hash(const sd_scenario *s);
/* 1 for the keys that sd_scenario_branch_hash counts (the explicit elements aside). */
int sd_scenario_in_branch_hash(const char *key);
/* The same with the capture keys too: equal for two scenarios whose whole runs are identical
 * (neither counts solver.threads or output.checkpoint_interval, which change no bit). Stored in
 * a periodic checkpoint. */
uint64_t sd_scenario_run_hash(const sd_scenario *s);

/* ---- materials (scenario_materials.c) ---- */
struct sd_ynode;
/* Where the loader's messages go: file:line:col: message, counted as errors. */
typedef void (*sd_scenario_report_fn)(void *ctx, int line, int col, const char *msg);
/* The `materials:` list (names, or {name: NAME}) into s, after "default". */
void sd_scenario_parse_materials(sd_scenario *s, const struct sd_ynode *list, sd_scenario_report_fn report, void *ctx);
/* The `contact_pairs:` list into s (materials parsed before). value(k, text, v, why, n): 0 with
 * *v when text (NULL: not a scalar) is a number in the range of contact.<key k>, else -1 with
 * why. */
typedef int (*sd_pair_value_fn)(int key, const char *text, double *v, char *why, size_t n);
void sd_scenario_parse_pairs(sd_scenario *s, const struct sd_ynode *list, sd_pair_value_fn value,
                             sd_scenario_report_fn report, void *ctx);
/* The id of the material called name, -1 if none; then hint gets " (did you mean 'x'?)" or
 * the declared names. */
int sd_scenario_material_id(const sd_scenario *s, const char *name, char *hint, size_t hint_len);
/* The contact constants' keys in sd_pair_def.v's order ("k_n", ...). */
const char *sd_scenario_pair_key(int k);
/* The springs of materials a and b: the pair's own where contact_pairs gives them, the others
 * from contact.*; *own (may be NULL): 1 when the pair is in contact_pairs. */
sd_contact_def sd_scenario_pair_contact(const sd_scenario *s, int a, int b, int *own);
/* Gives w the springs of every pair in contact_pairs. */
sd_status sd_scenario_apply_materials(const sd_scenario *s, sd_world *w);
/* What uses each material: bit k of the result for id m is set when the scene's part k
 * (SD_MATERIAL_USES order) has material m. */
#define SD_MATERIAL_USES "spheres", "logs", "dam", "bed", "walls", "roughness", "gate", "pile", "box", "elements", "meshes"
void sd_scenario_material_uses(const sd_scenario *s, unsigned uses[SD_MATERIALS_MAX]);
/* The largest stable time step of the scene (sd_world_stable_dt's rule on the scenario's
 * masses): *a, *b the pair that sets it, *mmin its lightest moving mass (kg). */
double sd_scenario_stable_dt(const sd_scenario *s, int *a, int *b, double *mmin);
/* The materials and the springs of each pair of used materials, as JSON ({"materials": [...],
 * "contact_pairs": [...]}: summary.json) or as text (`sabodem check`). */
struct cJSON *sd_scenario_materials_json(const sd_scenario *s);
void sd_scenario_materials_report(FILE *f, const sd_scenario *s);
/* The materials and the pairs hashed into h (sd_hash_bytes). */
uint64_t sd_scenario_materials_hash(const sd_scenario *s, uint64_t h);

#endif
