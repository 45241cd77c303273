/* Internal state of a world. Not part of the public API. */
#ifndef SD_WORLD_INTERNAL_H
#define SD_WORLD_INTERNAL_H

#include <stdint.h>
#include <stdlib.h>

#include "core/status.h"
#include "core/vmath.h"
#include "geom/geom.h"
#include "sabodem.h"

/* Moving and fixed bodies (spheres and cylinders): one store, one array per field.
 * Every per-body array is listed in the field table of bodies.c, which drives growth,
 * removal (swap with last) and checkpoints, so a new field cannot be forgotten. */
typedef struct {
    int n, cap;
    int32_t *gid;
    uint8_t *shape; /* SD_SHAPE_* */
    uint8_t *fixed;
    uint8_t *mat; /* material id (sd_world_set_pair_contact) */
    int32_t *tag;
    sd_vec3 *pos;
    sd_vec3 *vel;
    sd_vec3 *omega;  /* world frame; derived from angmom for cylinders */
    sd_vec3 *angmom; /* world-frame angular momentum (cylinders) */
    sd_quat *quat;   /* attitude; body z axis = cylinder axis */
    sd_vec3 *axis;   /* derived: quat applied to e_z */
    sd_vec3 *force;  /* contact force of the last step */
    sd_vec3 *torque;
    sd_vec3 *ext_force; /* external (fluid) force, persistent until changed */
    sd_vec3 *pos_ref;   /* position at the last candidate rebuild */
    sd_vec3 *axis_ref;
    double *radius;
    double *hl; /* half length (0 for spheres) */
    double *mass;
    double *inv_mass;
    double *inv_i_ax; /* inverse axial moment of inertia (spheres: 1/I) */
    double *inv_i_tr; /* inverse transverse moment (spheres: 1/I) */
    double *bound_r;  /* bounding-sphere radius */
} sd_bodies;

typedef struct {
    int n, cap;
    sd_tri *tri;
    int32_t *group;
    uint8_t *active;
    uint8_t *mat; /* material id */
    int32_t (*edge_id)[3]; /* welded global ids: shared edges and vertices get one id */
    int32_t (*vert_id)[3];
    int32_t (*edge_vert)[2]; /* per edge id: its two vertex ids (sized n_edges) */
    uint8_t *edge_flat;      /* per edge id: shared by two coplanar triangles (a seam) */
    sd_tri_edges *edges;     /* per triangle: its edge lines (sd_walls_weld) */
    int n_edges, n_verts;
    sd_vec3 *force; /* contact force on each triangle in the last step */
    int dirty;      /* welding and grid need rebuilding */
} sd_walls;

/* A candidate pair. Body–body: a, b are body indices ordered by (shape, gid).
 * Body–triangle: a is the body index, b the triangle index. History slots
 * hist[off .. off+cap) hold the tangential springs keyed by feature. */
typedef struct {
    int32_t a, b;
    int32_t off;
    int16_t cap;
    int16_t kind;      /* SD_PAIR_* */
    double sqrt_m_eff; /* sqrt of the effective mass (SPEC §3), set at rebuild */
} sd_pair;

enum { SD_PAIR_SS = 0, SD_PAIR_SC, SD_PAIR_CC, SD_PAIR_ST, SD_PAIR_CT, SD_PAIR_KINDS };

typedef struct {
    int32_t feature; /* -1: empty; SD_HIST_SEP_AXIS: see below */
    sd_vec3 shear;   /* tangential spring force P_s on A, N */
} sd_hist;
/* The first slot of a log-log pair found apart may keep, in its shear, the unit axis that
 * showed it (sd_geom_cyl_cyl_sep), for the next step to try first: an empty slot to every
 * other reader (they all take feature >= 0 as a contact), and not carried over a rebuild. */
#define SD_HIST_SEP_AXIS (-2)

typedef struct {
    sd_vec3 f_a; /* force on A */
    sd_vec3 t_a; /* torque on A about its centre */
    sd_vec3 t_b; /* torque on B about its centre */
} sd_pair_out;

typedef struct {
    int n, cap;
    sd_pair *p;
    sd_vec3 *out;    /* the body–triangle list only: each pair's force on its body, for the wall
                      * loads (the body–body pass keeps what its threads share in sd_owned) */
    uint8_t *active; /* 1 when the pair touched in the last step (out[] valid) */
    int out_cap, active_cap;
    int nh, hcap;
    sd_hist *hist;
} sd_pairlist;

/* Per-body ranges of the body–triangle pairs (grouped by body), for the per-body passes. */
typedef struct {
    int32_t *bt_start; /* n+1: body-triangle pairs of body i are bt_start[i]..bt_start[i+1] */
    int cap_bt_start;
} sd_csr;

typedef struct {
    double cell;
    int nx, ny, nz;
    sd_vec3 lo;
    int32_t *cell_start; /* ncell + 1 */
    int32_t *items;
    int cap_cells, cap_items;
} sd_grid;

/* Pair records, field by field (pair_records.c; filled by contact_kernels.h pair_soa_set) */
typedef struct {
    int32_t *a, *b, *off, *ck; /* ck: cap in the low half, kind in the high half */
    double *sqm;
    float *rs2; /* (r_a + r_b)^2 as a float (a sphere pair touches when its centres are nearer);
                 * -1 for any other entry (contact_kernels.h entry_rs2) */
    /* a sphere pair's slot holds a spring (its feature is 0, else -1): set from the slot when
     * the list is made, then by the touch filter at each step (touching now, a spring after
     * the step), so that the filter does not read the slot of every near pair */
    uint8_t *act;
    int cap;
} sd_pair_soa;

/* Body ranges, near lists and cross pairs of the parallel body-body pass (owners.c), derived
 * from the pair list: remade with the near pairs, never saved. */
#define SD_MAX_OWNERS 64
/* The bodies before the trailing bed (nf, sd_bed_start: the passes stop there) and the sums'
 * bed test (bed_lim: nf where no body before it is of the bed, what the rebuild's sort
 * leaves, else -1), as found (contact_bb.c sd_bb_bed_split) for n bodies after `stamp` rebuilds. */
typedef struct {
    int nf, bed_lim, n;
    long stamp;
} sd_bed_split;

typedef struct {
    long stamp; /* w->near_version it was made as (the near lists of both paths count) */
    int T, n, nbb;
    sd_bed_split bed;
    const void *pairs;
    int B[SD_MAX_OWNERS + 1]; /* thread t owns bodies B[t] .. B[t+1]-1 */
    /* the candidates (w->bb, ascending by their lower body) whose lower body owner t owns:
     * K[t] .. K[t+1]-1; owner t filters them itself into its own segment of list */
    int K[SD_MAX_OWNERS + 1];
    long rb; /* timers.rebuilds of the candidates it was made from */
    /* the pairs whose bodies have different owners, in blocks: owner t's candidates that
     * are, cross[K[t] .. xb[t]-1], ascending; xo[c]: the owner of the other body */
    int32_t *cross;
    uint8_t *xo;
    int xb[SD_MAX_OWNERS];
    int cap, xo_cap;
    sd_pair_out *xout; /* cross pair c's result (pass 1), read by both its owners (pass 2) */
    uint8_t *xact;     /* 1 when cross pair c touched in this step */
    int xout_cap, xact_cap;
    /* owner t's near pairs among its candidates, ascending: list[K[t] .. seg1[t]-1]; k for a
     * pair it owns both sides of, ~c (negative) for cross pair c (cross[c]). The cross pairs
     * of lower owners that touch it come before all of these (their lower bodies are lower). */
    int32_t *list;
    int seg1[SD_MAX_OWNERS];
    int list_cap;
    /* the records of list's entries (a cross entry's kind made one of no pair, so that the
     * pass takes its result from pass 1) and of the cross pairs, field by field (sd_pair_soa) */
    sd_pair_soa soa, xsoa;
    /* balance by measured time (any split gives the same bits): the split as fractions of
     * the body-body pairs, and each owner's time since it was set */
    double fo[SD_MAX_OWNERS + 1];
    double tau[SD_MAX_OWNERS];
    /* owner t's bodies near a wall: wall_list[B[t] ..] (wn[t] of them), and how many of its
     * bodies with wall pairs were left out (wskip[t]) */
    int wn[SD_MAX_OWNERS];
    long wskip[SD_MAX_OWNERS];
    /* the sphere pairs' springs of list[K[t] .. seg1[t]) at the same places, while the world's
     * springs_out is 2 (sd_world's near_hist) */
    sd_hist *hist;
    int hist_cap;
    int passes; /* passes timed in tau */
} sd_owned;

/* External forces of a step (sabodem.h sd_external_force_fn) on the moving bodies mov[k0 .. k1),
 * into out[k - k0], not into ext_force, which such a function overrides: a block's buffer stays
 * in L1, where the store's array cost a line's fetch and write-back per body and step. */
#define SD_EXT_BLOCK SD_EXTERNAL_BLOCK
typedef sd_external_force_fn sd_ext_force_fn;

/* The bed bodies nb0 .. n-1 as the last full rebuild placed them in the body grid (lo, cell,
 * nx, ny; the grid's nz may change, the bed's cells do not): the union of their boxes (its low
 * corner anchors the grid's origin), their
 * cell ranges, and their entries cell by cell (cells[c] ascending, entries off[c] ..
 * off[c+1]-1 of items, ascending as grid_fill writes them). */
typedef struct {
    int made;
    long version;
    int n, nb0;
    double cell;
    int nx, ny;
    sd_vec3 lo, blo, bhi;
    int ztop; /* the bed's highest layer, below the top one (its ranges do not depend on nz) */
    int32_t (*range)[6];
    int32_t *cells, *off, *items;
    uint8_t *flags; /* the items' gflag */
    int ncells, nitems;
    long used; /* rebuilds that took the bed from here (for the tests) */
} sd_bed_cache;

/* The body pass's front prefetch (front_prefetch.c) in auto mode is tried, not guessed from the cache
 * sizes: SD_PF_GROUPS groups of four blocks of steps, off on on off, each block's pass time
 * summed; the verdict is the median over the groups of (on) / (off) below 1. Tried again every
 * SD_PF_RETRY steps and when the body count moves by a quarter. A hint to the memory system
 * only: the same bits whatever the verdict. */
enum { SD_PF_GROUPS = 8, SD_PF_RETRY = 100000, SD_PF_MIN_BODIES = 2048 };
typedef struct {
    int verdict;           /* -1: no trial finished yet (the cache-size rule holds), 0 off, 1 on */
    int blk;               /* the trial's block now (0 .. 4 * SD_PF_GROUPS - 1), -1 none running */
    int in_blk, blk_steps; /* steps done in the block, steps a block */
    int n;                 /* bodies when the last trial began */
    long next;             /* the step from which the next trial may begin */
    double acc, t[4], r[SD_PF_GROUPS];
    double ratio; /* the last verdict's median of (on) / (off) */
} sd_pf_trial;

/* contact_law.c */
typedef struct {
    double k_n, k_s, c_n_factor, c_s_factor, tan_phi, cohesion; /* c = factor * sqrt(m*) */
} sd_law;
sd_law sd_law_make(const sd_contact_def *d);
/* The law's constants as the lanes use them (lane_law.c, the SIMD kernels): the dashpots'
 * factors, and -k_s dt, the tangential spring's change per unit of sliding speed. */
typedef struct {
    double k_n, c_n, c_s, tan_phi, coh, mks_dt;
} sd_lane_law;
/* The law table's index of a contact between materials a and b. */
static inline int sd_mat_pair(int a, int b) { return a * SD_MATERIALS_MAX + b; }
/* What a step's stages read of the definition, made once a step (sd_law_ctx_ready): the time
 * step, the contact law's constants and their lane form; with several materials, each pair's. */
typedef struct {
    double dt;
    sd_law law;
    sd_lane_law lane;
    long step; /* the step it was made for */
    /* multi: a pair of materials has springs of its own other than def.contact's, so the
     * contact pass takes each contact's law from laws / lanes at sd_mat_pair of its materials;
     * 0: every contact has law and lane, and the pass never reads the table (no cost for one
     * material). Remade when the pairs, def.contact or dt change (made: it was ever made). */
    int multi, made;
    long version;
    double made_dt;
    sd_contact_def made_base;
    sd_law laws[SD_MATERIALS_MAX * SD_MATERIALS_MAX];
    sd_lane_law lanes[SD_MATERIALS_MAX * SD_MATERIALS_MAX];
} sd_step_ctx;
/* contact_law.c: w->ctx for the coming step, made unless it already is */
const sd_step_ctx *sd_law_ctx_ready(sd_world *w);

typedef struct sd_contact_kernels sd_contact_kernels;

/* The engine's optimizations that tests and benchmarks switch for A/B runs: every setting
 * gives the same bits (the tests prove it). Each world has its own (sd_world_switch); a new
 * world has every one at its default. X(name, default, what it does when on). */
#define SD_SWITCH_TABLE(X)                                                                          \
    X(SC_LANES, 1, "sphere-log pairs touching at one point go through the law in lanes")          \
    X(SC_GEOM, 1, "their geometry in AVX2 lanes")                                                  \
    X(SS_LAW256, 1, "the sphere law's spring loop in AVX2 lanes (AVX2 level)")                     \
    X(SLOT_SQM, 1, "a sphere pair's sqrt_m_eff kept in its spring's slot")                         \
    X(SPRINGS_LIST, 1, "the sphere pairs' springs kept in the near list's order")                  \
    X(WALL_NEAR, 1, "the wall pass visits only bodies with a wall pair near touching")             \
    X(PREFETCH, SD_PREFETCH_AUTO, "the body pass's front prefetch: SD_PREFETCH_AUTO, _OFF, _ON")  \
    X(MOVE_LANES, 1, "the spheres moved in AVX2 lanes")                                            \
    X(CYL_BATCH, 1, "the logs moved in batches of lanes")                                          \
    X(EXT_SKIP, 1, "the store's external forces not read while none was set")                      \
    X(SCAN_PRE, 1, "the rebuild scan's float prefilter")                                           \
    X(BED_CACHE, 1, "rebuilds take the bed roughness from its cache")                              \
    X(MOVING_INDEX_MIN, 64, "fixed bodies scan the moving bodies' lists when more than this many")

typedef enum {
#define SD_X_SWITCH(name, def, doc) SD_SW_##name,
    SD_SWITCH_TABLE(SD_X_SWITCH)
#undef SD_X_SWITCH
        SD_SWITCH_COUNT
} sd_switch;

/* Sets switch `which` of w to value (from the next step) and returns its value before. The
 * prefetch takes SD_PREFETCH_*; the others 0 or 1 but MOVING_INDEX_MIN, a count. */
int sd_world_switch(sd_world *w, sd_switch which, int value);
/* The switch called `name` (its table name in lower case: "springs_list"), -1 if none. */
int sd_switch_by_name(const char *name);
const char *sd_switch_name(sd_switch which);

/* A world: first its state, what a checkpoint saves (io_checkpoint.c, which fails to build
 * when this part changes size: a field added here must be saved there too); then how it runs
 * and its scratch, derived or set by the caller, never saved, where a new field changes no
 * file format. */
struct sd_world {
    /* ---- state ---- */
    sd_world_def def;
    sd_bodies b;
    sd_walls w;
    sd_pairlist bb;      /* body–body */
    sd_pairlist bt;      /* body–triangle */
    sd_manifold *bt_man; /* narrow-phase result per body–triangle pair (for mesh dedup) */
    int bt_man_cap;
    sd_csr csr;
    sd_grid tgrid;                /* triangles */
    int32_t (*trange)[6];         /* per-triangle cell range in the triangle grid */
    int trange_cap;
    int32_t *gid_map; /* gid -> index, -1 removed */
    int gid_cap, next_gid;
    double time;
    long step;
    double last_rebuild_time;
    int need_rebuild;
    int rebuild_every_step;
    long contacts;
    sd_world_timers timers;
    int checked;
    /* contact history carried across a rebuild by key, collected and not yet restored */
    sd_hist *old_hist;
    uint64_t *old_keys;
    int n_old, old_cap, old_hist_cap;
    int keys_collected;  /* old keys already taken (a body was removed since) */
    int ext_any;         /* a body's external force was ever set non-zero (else the moves skip the
                          * store's zeros; a checkpoint's read sets it from the forces) */
    double ref_drift; /* the same bound as near_drift since the last rebuild (pos_ref) */
    /* the springs of each pair of materials a, b: mat_pair[sd_mat_pair(a, b)] where mat_set is
     * 1 there (set for both orders at once), else def.contact (sd_world_set_pair_contact) */
    sd_contact_def mat_pair[SD_MATERIALS_MAX * SD_MATERIALS_MAX];
    uint8_t mat_set[SD_MATERIALS_MAX * SD_MATERIALS_MAX];
    /* ---- how it runs, and scratch ---- */
    int nthreads;             /* this world's OpenMP threads (def.threads, or the runtime's default) */
    int simd;                 /* the SIMD level its kernels run at (SD_SIMD_*, resolved) */
    long llc_bytes;           /* the last-level cache the prefetch's guess assumes */
    int sw[SD_SWITCH_COUNT];  /* sd_world_switch */
    const sd_contact_kernels *kern; /* the contact pass's SIMD kernels at this level (contact_internal.h) */
    sd_step_ctx ctx;                /* (sd_law_ctx_ready) */
    long mat_version; /* changed by every sd_world_set_pair_contact (the step's law table follows it) */
    sd_ext_force_fn ext_fn; /* NULL: ext_force applies (set by the driver, not saved) */
    void *ext_ctx;
    sd_owned *owned;  /* NULL until a parallel pass needs it */
    void *bb_scratch; /* per-thread scratch of the body-body pass (contact_internal.h bb_scratch) */
    int bb_scratch_n;
    sd_grid grid;     /* bodies */
    /* the old entries are grouped by the first body's store index at the collect (any one
     * run a gid: a checkpoint's, or the gid order of earlier versions, reads the same):
     * old_start[i] .. old_start[i + 1] are body i's, for old_n_bodies bodies; scratch, not
     * saved (neighbor.c) */
    int32_t *old_start, *old_cnt;
    int old_start_cap, old_cnt_cap, old_n_bodies;
    /* the rebuild's sort: body i came from perm[i] for i < rb_perm_m, the rest stayed */
    int32_t *rb_perm;
    int rb_perm_cap, rb_perm_m;
    int32_t (*old_rng)[2]; /* the restore's lookup: new body i's old entries */
    int old_rng_cap;
    int32_t (*range)[6]; /* per-body cell range in the body grid */
    int range_cap;
    /* box[2i], box[2i+1]: body i's margin-expanded box (low, high corner) as the last rebuild
     * made it, for bodies before the bed (neighbor.c; scratch, not saved) */
    sd_vec3 *box;
    int box_cap, box_n;
    /* body i's entries in the body grid are reg0[i] .. reg0[i+1]-1, slot[e] the place of
     * entry e in the grid's items (neighbor.c grid_fill; scratch, not saved) */
    int32_t *reg0, *slot;
    int reg0_cap, slot_cap;
    /* gflag[k]: the body of grid entry k has its range begin at the entry's cell along x (bit
     * 0), y (bit 1), z (bit 2): a pair is taken in a cell only where each axis begins one of
     * the two ranges (the lowest cell they share) */
    uint8_t *gflag;
    int gflag_cap;
    /* the body grid's entries' centres and bounding radii in single precision, field by field
     * (x, y, z, r: gq_stride floats each, zero past the last entry), for the scan's prefilter
     * (neighbor.c grid_coords; scratch, not saved) */
    float *gq;
    int gq_cap, gq_stride;
    float gq_slack; /* what the prefilter adds to a reach: its rounding, bounded (grid_coords) */
    /* the candidate scan's chunk buffers, kept from one rebuild to the next with what they
     * grew to (neighbor.c; scratch, not saved): made afresh, they took ~300 reallocs a
     * rebuild (performance pass P22, in the git history) */
    void *scan_bufs;
    int scan_bufs_n;
    uint8_t *tflag; /* the triangle grid's entries' flags, as gflag for the body grid */
    int tflag_cap;
    /* derived, never saved: the indices of the moving bodies, ascending, for the per-body
     * passes (a static split over all bodies would give one thread the bed, the other the
     * flow); valid while mov_stamp == timers.rebuilds and mov_bn == b.n */
    int32_t *mov;
    int mov_n, mov_cap, mov_bn;
    long mov_stamp;
    int wall_force_stale; /* w.force not yet summed from the last step's wall pairs */
    double front;         /* sd_world_front_x of the bodies as the last step left them ... */
    long front_step;      /* ... valid while step == front_step and b.n == front_bn */
    int front_bn;
    /* derived, never saved: the body-body pairs that can touch before the spheres have
     * drifted by half the near skin (near_list.c: every non-sphere pair, and the sphere pairs
     * with a gap below near_skin), ascending; near_drift bounds how far any moving sphere has
     * gone since the list was made (the largest |v| dt of each step, summed) */
    int32_t *near;
    int near_n, near_cap, near_nbb;
    /* the records of the near pairs (a, b, off, cap | kind << 16, sqrt_m_eff) in near order,
     * field by field: the touch filter loads them 8 at a time instead of gathering them */
    sd_pair_soa near_soa;
    long near_soa_version; /* near_version + 1 when near and near_soa are the current near pairs */
    /* The sphere pairs' springs of a near list, in its own order (near_list.c sd_near_springs_to):
     * near_hist[k] for entry k of the serial list (springs_out 1), sd_owned's hist for the
     * owners' lists (springs_out 2); their records' off then points there, and those pairs'
     * slots in bb.hist are stale until sd_near_springs_home puts them back (springs_out 0).
     * The pass reads and writes them in list order instead of the candidates' sparse slots. */
    sd_hist *near_hist;
    int near_hist_cap;
    int springs_out;
    int springs_lsq; /* those springs' slots hold the pair's sqrt_m_eff where the feature was (contact_kernels.h slot_sqm) */
    long near_stamp, near_version;
    double near_drift, near_skin; /* near_skin: the skin it was made with */
    /* near_mark[k]: candidate k was near when the near pairs were last made (both paths), so
     * only it can hold a spring; valid while near_mark_rb == timers.rebuilds (after a rebuild
     * any candidate can: the carried springs). Its second half, near_mark[bb.n + 1 + k], is
     * the scratch for each candidate's answer while they are remade. */
    uint8_t *near_mark;
    int near_mark_cap;
    /* the bodies with a wall pair (bt) within the near skin of touching, ascending, made with
     * the near pairs (so valid while they are): a body not listed has no wall contact until
     * they are remade, and the wall pass skips it. The serial pass's list: wall_list[0 ..
     * wall_n), wall_skip left out; the owners' in sd_owned. */
    int32_t *wall_list;
    int wall_list_cap, wall_n;
    long wall_skip;
    long wall_skipped; /* bodies the wall pass skipped, summed over the steps (for the tests) */
    long near_mark_rb;
    /* derived, never saved: what the rebuilds know of the bed roughness (the fixed spheres,
     * sorted after everything else), which never moves: valid while bodies are neither added
     * nor removed (body_version) and the body grid keeps its layout (neighbor.c) */
    long body_version;
    sd_bed_cache bed;
    /* derived, never saved: the front prefetch's trial in auto mode (world.c, sd_pf_trial) */
    sd_pf_trial pf;
    /* derived, never saved: the decomposition's settings (decomp.c, docs/decomposition.md): a
     * fixed body grid (fgrid_on), whose rebuilds sort a cell's bodies by gid; the ghosts, by
     * gid (ghost[g] 1: in the contacts, not moved, not in mov) */
    int fgrid_on;
    sd_grid_def fgrid;
    uint8_t *ghost;
    int ghost_cap;
    /* the largest surface move of a ghost put in place since the last step: its owner moved it,
     * so this world's drift bounds (near_drift) must count it too (sd_world_step adds it) */
    double ghost_drift;
};

/* The near skin as a fraction of the margin. Any skin gives the same bits; 0.05-0.1 ran
 * fastest on the sphere flume (0.2: -5 %, 0.35: -8 %); a skin set by the last step's top
 * speed (wider in flow, fewer remakes) measured no different and was dropped. */
#define SD_NEAR_SKIN 0.1

/* bodies.c */
sd_status sd_bodies_reserve(sd_bodies *b, int cap);
void sd_bodies_free(sd_bodies *b);
void sd_bodies_swap_remove(sd_bodies *b, int i);
/* Reorder every field: new index i takes old index perm[i]. */
/* a[i] <- a[perm[i]] in every field, for the first n bodies (perm maps 0..n-1 onto itself), on
 * up to `threads` threads */
sd_status sd_bodies_permute(sd_bodies *b, const int32_t *perm, int n, int threads);
/* Iterate over the field table: calls fn(ptr, elem_size, ctx) for each field array. */
typedef void (*sd_field_fn)(void *array, size_t elem_size, const char *name, void *ctx);
void sd_bodies_for_each_field(sd_bodies *b, sd_field_fn fn, void *ctx);
/* One body's every field as a record (sd_body_record_size bytes, in the field table's order) */
size_t sd_bodies_record_size(void);
void sd_bodies_get_record(const sd_bodies *b, int i, void *rec);
void sd_bodies_set_record(sd_bodies *b, int i, const void *rec);
size_t sd_bodies_record_offset(const char *field); /* (size_t)-1: no such field */
/* whether body i of w is a ghost (decomp.c) */
static inline int sd_body_is_ghost(const sd_world *w, int i);

/* walls.c */
sd_status sd_walls_reserve(sd_walls *w, int cap);
void sd_walls_free(sd_walls *w);
sd_status sd_walls_weld(sd_walls *w);

/* neighbor.c */
sd_status sd_neighbor_rebuild(sd_world *w);
/* The stages of sd_neighbor_rebuild, in order: their wall times, summed over the calling
 * thread's rebuilds since sd_neighbor_stages_take last took them (for bench_rebuild). */
enum {
    SD_RB_COLLECT, /* the springs taken out (sd_history_collect) */
    SD_RB_LAYOUT,  /* the cell size, the bodies' box, the grid's layout */
    SD_RB_SORT,    /* the bodies sorted by cell */
    SD_RB_RANGES,  /* each body's box and cell range */
    SD_RB_FILL,    /* the grid's entries (and the bed's cache) */
    SD_RB_SCAN,    /* the candidates found */
    SD_RB_JOIN,    /* the threads' candidates joined, the wall pairs grouped */
    SD_RB_MASSES,  /* the pairs' effective masses */
    SD_RB_RESTORE, /* the springs put back */
    SD_RB_REFS,    /* the moves' references */
    SD_RB_STAGES
};
/* t[k] (SD_RB_STAGES of them): stage k's time since the last take, in s. The sums restart. */
void sd_neighbor_stages_take(double *t);
const char *sd_neighbor_stage_name(int k);
/* The triangle grid's flag bytes (tflag) made from its lists and ranges (a checkpoint keeps
 * the grid, not the flags). */
sd_status sd_neighbor_tgrid_flags(sd_world *w);
int sd_neighbor_needs_rebuild(const sd_world *w);

/* grid.c */
void sd_grid_free(sd_grid *g);

/* bed_cache.c */
void sd_bed_cache_free(sd_bed_cache *c);

/* pair_history.c */
/* Take the live tangential history out of the pair lists, keyed by gids (before the body
 * store changes order); the next rebuild puts it back. */
sd_status sd_history_collect(sd_world *w);

/* candidates.c */
void sd_cand_bufs_free(sd_world *w);

/* sd_contact_law (contact_law.h, inline in the contact loop): force on A from one contact. */

/* contact.c: the forces of one step. With several threads and integrated != NULL, each thread
 * also moves its own bodies (w->mov must be current) and *integrated is set to 1. */
sd_status sd_contact_compute(sd_world *w, int *integrated);
/* The contact pass's SIMD kernels at a level (contact_internal.h; SD_SIMD_SCALAR: none). */
const sd_contact_kernels *sd_contact_kernels_for(int simd);
/* Sums the last step's wall pairs into w.force if not done yet (lazy: see contact.c). */
void sd_contact_gather(sd_world *w);
/* How many body-body pairs the next step tests (the near pairs of whichever pass made them
 * last: the serial pass's list or the owners' segments). */
int sd_contact_near_count(const sd_world *w);
void sd_pair_soa_free(sd_pair_soa *s);
/* The sphere pairs' springs held by a near list (springs_out) put back into bb.hist, and the
 * list's records pointed at them again: called before anything reads bb.hist or changes the
 * pairs (the rebuild's collect, a checkpoint, the hash and the spring energy, a near remake).
 * It changes where the springs sit, not what they are: the const readers call it too. */
void sd_near_springs_home(sd_world *w);

/* The bed roughness (fixed spheres, never made free): nobody reads its load, so nothing is
 * added to it and its force and torque stay at the zero they were created with (half the
 * elements of the paper's flume: memory traffic saved every step). Dam pipes (fixed
 * cylinders) are summed. */
/* Whether body i is of the bed (a fixed sphere). */
static inline int sd_body_is_bed(const sd_bodies *b, int i) { return b->fixed[i] && b->shape[i] == SD_SHAPE_SPHERE; }
/* The springs of a contact between materials a and b (sd_world_set_pair_contact). */
static inline const sd_contact_def *sd_mat_contact(const sd_world *w, int a, int b)
{
    const int k = sd_mat_pair(a, b);
    return w->mat_set[k] ? &w->mat_pair[k] : &w->def.contact;
}
static inline int sd_body_is_ghost(const sd_world *w, int i)
{
    const int g = w->b.gid[i];
    return w->ghost && g < w->ghost_cap && w->ghost[g];
}
/* The first body of the trailing bed (n when none): bodies from there on are the bed, which the
 * rebuild sorts after every other body. */
static inline int sd_bed_start(const sd_bodies *b)
{
    int i = b->n;
    while (i > 0 && sd_body_is_bed(b, i - 1))
        i--;
    return i;
}

void sd_pairlist_free(sd_pairlist *l);
/* Mesh rule on the manifolds man[from..to) of one body's triangle pairs: drops edge and vertex
 * contacts already represented by a face or edge contact (used by the force pass and by
 * sd_world_spring_energy, so that the energy counts the springs the forces use). */
/* For benchmarks: the near pairs (the owners' lists, or the serial one) remade now, as when
 * the bodies have drifted past half the near skin. */
sd_status sd_contact_near_remake(sd_world *w);
void sd_contact_mesh_dedup(const sd_walls *wl, const sd_pair *pairs, sd_manifold *man, int from, int to);
/* The hand-written SIMD kernels run at w->simd: SD_SIMD_SCALAR (the scalar loops), _AVX2
 * (the contact pass's touch filter, gather and sums, water.c's forces, 4 lanes) or _AVX512 (the
 * filter, gather and fluid forces in 8 lanes, the sums in 4, neighbor.c's cell scan). The same
 * bits at every level. */
/* The groups of four the calling thread ran through the sphere law's AVX2 spring loop so far,
 * and of them those where no lane slid or passed the limit (*skipped). */
long sd_avx2_ss_law_count(long *skipped);
long sd_integrate_lanes_count(void); /* the groups of four spheres the calling thread moved in lanes */
/* Sphere-log lanes filled by the AVX2 geometry since the start (for the tests). */
long sd_contact_sc_geom_count(void);
/* the sphere-log lanes run so far, and of them the ones sent back to the scalar law (*redo) */
long sd_contact_sc_lanes_count(long *redo);
/* The body-body pass's prefetch of the bodies it is about to reach for the first time (front_prefetch.c),
 * as switch SD_SW_PREFETCH says: SD_PREFETCH_AUTO (the default: tried on and off during the run,
 * sd_pf_trial; before the first verdict, and below SD_PF_MIN_BODIES, on when the step's data
 * outgrow a quarter of the last-level cache), _OFF or _ON. A hint to the memory system only: the
 * same bits either way. sd_front_prefetch_on: whether it runs for w now.
 * sd_front_prefetch_verdict: the last trial's verdict for w (-1 none yet) and its ratio (on / off). */
int sd_front_prefetch_on(const sd_world *w);
int sd_front_prefetch_verdict(const sd_world *w, double *ratio);
/* front_prefetch.c: the trial's bookkeeping around one step's pass (pass_s: its time) */
void sd_front_prefetch_trial_before(sd_world *w);
void sd_front_prefetch_trial_after(sd_world *w, double pass_s);
/* the first k with mov[k] >= i (mov ascends) */
static inline int sd_mov_lower(const int32_t *mov, int n, int i)
{
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = (lo + hi) >> 1;
        if (mov[mid] < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Thread tid's share w->mov[*k0 .. *k1) of the moving bodies in a per-body pass with nthr
 * threads: the bodies of its owner range in the body-body pass when there is one (their data
 * are in its cache), else an even split. */
static inline void sd_mov_share(const sd_world *w, int tid, int nthr, int *k0, int *k1)
{
    const sd_owned *o = w->owned;
    if (o && o->T == nthr && o->n == w->b.n) {
        *k0 = sd_mov_lower(w->mov, w->mov_n, o->B[tid]);
        *k1 = sd_mov_lower(w->mov, w->mov_n, o->B[tid + 1]);
    } else {
        *k0 = (int)((long)w->mov_n * tid / nthr);
        *k1 = (int)((long)w->mov_n * (tid + 1) / nthr);
    }
}

/* Half extent along x of a body's box: r for a sphere, hl|a_x| + r sqrt(1 - a_x²) for a
 * cylinder. */
static inline double sd_body_x_extent(const sd_bodies *b, int i)
{
    if (b->shape[i] == SD_SHAPE_SPHERE) return b->radius[i];
    const double ax = b->axis[i].x;
    return b->hl[i] * fabs(ax) + b->radius[i] * sqrt(fmax(0.0, 1.0 - ax * ax));
}

static inline double sd_clamp01(double t) { return t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0; }

/* Distance between the axis segments of two bodies (a sphere's segment is its centre): the
 * clamped closest points of the two segments (the candidates' capsule test, neighbor.c, and
 * the log pairs' near test, contact_kernels.h near_test). fmin/fmax-free clamps: gcc calls libm for those. */
static inline double sd_axis_gap(const sd_bodies *b, int i, int j)
{
    sd_vec3 p1 = v3_madd(b->pos[i], b->axis[i], -b->hl[i]), d1 = v3_scale(b->axis[i], 2.0 * b->hl[i]);
    sd_vec3 p2 = v3_madd(b->pos[j], b->axis[j], -b->hl[j]), d2 = v3_scale(b->axis[j], 2.0 * b->hl[j]);
    sd_vec3 r = v3_sub(p1, p2);
    double a = v3_dot(d1, d1), e = v3_dot(d2, d2), f = v3_dot(d2, r);
    double s = 0.0, t = 0.0;
    if (a <= 1e-30 && e <= 1e-30) return v3_norm(r);
    if (a <= 1e-30) {
        t = sd_clamp01(f / e);
    } else {
        double c = v3_dot(d1, r);
        if (e <= 1e-30) {
            s = sd_clamp01(-c / a);
        } else {
            double bb = v3_dot(d1, d2), den = a * e - bb * bb;
            s = den > 1e-20 * a * e ? sd_clamp01((bb * f - c * e) / den) : 0.0;
            t = (bb * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = sd_clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = sd_clamp01((bb - c) / a);
            }
        }
    }
    return v3_norm(v3_sub(v3_madd(p1, d1, s), v3_madd(p2, d2, t)));
}

/* Kernel shapes of a body. */
static inline sd_cyl sd_body_cyl(const sd_bodies *b, int i)
{
    sd_cyl c;
    c.c = b->pos[i];
    c.a = b->axis[i];
    c.r = b->radius[i];
    c.hl = b->hl[i];
    return c;
}

/* integrate.c */
void sd_integrate(sd_world *w);
/* The largest moves of a step (sd_integrate_list): |v|² of a sphere, the move of a log's
 * surface, and the farthest downstream point. */
typedef struct {
    double v2, dc, xf;
} sd_moves;
#define SD_MOVES_NONE ((sd_moves){0.0, 0.0, -INFINITY})
/* *a raised to b, field by field */
static inline void sd_moves_max(sd_moves *a, const sd_moves *b)
{
    a->v2 = b->v2 > a->v2 ? b->v2 : a->v2;
    a->dc = b->dc > a->dc ? b->dc : a->dc;
    a->xf = b->xf > a->xf ? b->xf : a->xf;
}
#ifdef _OPENMP
/* reduction(moves_max : m) over the threads of a parallel region */
#pragma omp declare reduction(moves_max:sd_moves : sd_moves_max(&omp_out, &omp_in)) \
    initializer(omp_priv = SD_MOVES_NONE)
#endif
/* Moves the bodies mov[k0 .. k1) (serial); returns 1 when one of them moved more than half
 * the margin since the last rebuild. *m raised to this block's largest moves. */
int sd_integrate_list(sd_world *w, const int32_t *mov, int k0, int k1, sd_moves *m);
/* After the bodies moved (m: the step's largest moves): the near list's and the rebuild's
 * drift, and the front (sd_world_front_x). */
void sd_integrate_after_moves(sd_world *w, const sd_moves *m);
/* (sd_world_front_x, sabodem.h: kept by the step, computed when the store changed since) */

/* neighbor.c: bring w->mov up to date (O(n) when the store changed since it was made; the
 * rebuild makes it with the sort). */
sd_status sd_neighbor_moving_update(sd_world *w);

/* helpers */
/* an external force other than (+0, +0, +0): the moves must add it (a -0 too: f + -0 is not
 * f + +0 when f is -0) */
static inline int sd_ext_set(sd_vec3 f)
{
    return f.x != 0.0 || f.y != 0.0 || f.z != 0.0 || signbit(f.x) || signbit(f.y) || signbit(f.z);
}

static inline int sd_grow(void **p, int *cap, int need, size_t elem)
{
    if (need <= *cap) return 0;
    int nc = *cap > 0 ? *cap : 64;
    while (nc < need)
        nc *= 2;
    void *q = realloc(*p, (size_t)nc * elem);
    if (!q) return -1;
    *p = q;
    *cap = nc;
    return 0;
}


#endif
