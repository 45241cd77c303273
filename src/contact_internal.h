/* What the files of the contact pass share (contact.c orchestrates it; contact_bb.c,
 * contact_bt.c, owners.c, near_list.c, lane_law.c, contact_manifold.c, contact_mesh.c,
 * front_prefetch.c, pair_records.c and the SIMD kernels in contact_simd_avx2.c and
 * contact_simd_avx512.c): the batches' and records' types, the chunk sizes, and the functions
 * each file exports to the others. The hot helpers several of them inline are in
 * contact_kernels.h. Nothing here is used outside the pass (world_internal.h holds what is). */
#ifndef SD_CONTACT_INTERNAL_H
#define SD_CONTACT_INTERNAL_H

#include <stdint.h>

#include "world_internal.h"

/* the hand-written AVX2 and AVX-512 kernels (contact_simd_avx2.c, contact_simd_avx512.c) */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#define SD_FILTER512 1
#endif

/* Sphere–sphere, the most common pair, in batches (sd_bb_chunk, contact_bb.c): a filter pass keeps the
 * touching pairs, a branch-free pass over arrays applies case 1 of the kernel and the law of
 * contact_law.h to all of them at once (the compiler vectorizes it), and the results go back in
 * pair order. The arithmetic is that of sd_contact_law, operation for operation (both sides of
 * every branch are computed and one is kept), so it gives the same bits as the scalar law. */
#define SS_CHUNK 128
#define SS_PAD 8
#define SC_CAP (SS_CHUNK + SS_PAD) /* (the sphere-log lanes: sd_avx2_sc_geom stores four at a time) */

typedef struct {
    /* (the filter's lanes padded by SS_PAD: its AVX-512 form stores 8 lanes at a time) */
    double dx[SS_CHUNK + SS_PAD], dy[SS_CHUNK + SS_PAD], dz[SS_CHUNK + SS_PAD], ra[SS_CHUNK + SS_PAD],
        rb[SS_CHUNK + SS_PAD], sqm[SS_CHUNK + SS_PAD];
    double vx[SS_CHUNK], vy[SS_CHUNK], vz[SS_CHUNK];    /* v_a - v_b */
    double wax[SS_CHUNK], way[SS_CHUNK], waz[SS_CHUNK]; /* omega_a */
    double wbx[SS_CHUNK], wby[SS_CHUNK], wbz[SS_CHUNK]; /* omega_b */
    double sx[SS_CHUNK], sy[SS_CHUNK], sz[SS_CHUNK];    /* shear spring in, then out */
    double fx[SS_CHUNK], fy[SS_CHUNK], fz[SS_CHUNK];    /* force on A */
    double nfx[SS_CHUNK], nfy[SS_CHUNK], nfz[SS_CHUNK]; /* n x f */
    double la[SS_CHUNK], lb[SS_CHUNK];                  /* lever arms */
    double redo[SS_CHUNK];                              /* nonzero: redo with the scalar law */
    int32_t ia[SS_CHUNK + SS_PAD], ib[SS_CHUNK + SS_PAD], off[SS_CHUNK + SS_PAD]; /* bodies, history slot */
    int32_t was[SS_CHUNK + SS_PAD]; /* the slot's feature before this step */
    int32_t sel[SS_CHUNK + SS_PAD]; /* the pair's place in the chunk */
    int bed_lim;                    /* the sums' bed test (bed_at): set by each pass before its chunks */
    sd_hist *sh;                    /* the sphere lanes' slots: off[] into here (the chunk's view's) */
    int lsq;                        /* sh is a list's own springs: see soa_view.lsq */
    sd_vec3 sink[8];                /* where a bed body's sums go (sd_avx2_ss_sums, add_pair_sink): never read */
    /* an owner's cross entries in pass 2 (ks < 0: pair cross[~ks], computed in pass 1): their
     * results and flags, and the owner's bodies [own_lo, own_hi), whose side alone it adds */
    const sd_pair_out *xout;
    const uint8_t *xact;
    int own_lo, own_hi;
    struct sc_lanes { /* sphere-log pairs touching at one point (sd_bb_chunk step 2) */
        double nx[SC_CAP], ny[SC_CAP], nz[SC_CAP], ov[SC_CAP]; /* normal (on the sphere), overlap */
        double px[SC_CAP], py[SC_CAP], pz[SC_CAP];             /* contact point */
        double rax[SC_CAP], ray[SC_CAP], raz[SC_CAP];          /* point - centre, sphere */
        double rbx[SC_CAP], rby[SC_CAP], rbz[SC_CAP];          /* point - centre, log */
        double vax[SC_CAP], vay[SC_CAP], vaz[SC_CAP], wax[SC_CAP], way[SC_CAP], waz[SC_CAP];
        double vbx[SC_CAP], vby[SC_CAP], vbz[SC_CAP], wbx[SC_CAP], wby[SC_CAP], wbz[SC_CAP];
        double sqm[SC_CAP];
        double sx[SC_CAP], sy[SC_CAP], sz[SC_CAP]; /* spring in, then out */
        double fx[SC_CAP], fy[SC_CAP], fz[SC_CAP], tax[SC_CAP], tay[SC_CAP], taz[SC_CAP];
        double tbx[SC_CAP], tby[SC_CAP], tbz[SC_CAP];
        double redo[SC_CAP];
        int32_t feature[SC_CAP], i[SC_CAP]; /* the contact's feature, the pair's place */
        long n_run, n_redo,
            n_geom; /* lanes run, sent back, and filled by sd_avx2_sc_geom since the last fold (tests) */
    } sc;
} ss_batch;

/* A chunk's pair records field by field (sd_pair_soa, offset to the chunk's first entry): what
 * the touch filter reads of each pair, in entry order. */
typedef struct {
    const int32_t *a, *b, *off, *ck;
    const double *sqm;
    const float *rs2;
    uint8_t *act; /* (written by the touch filter) */
    sd_hist *sh;  /* where the sphere pairs' off point: bb.hist, or the list's own springs */
    /* sh is a near list's own springs (springs_out): there a sphere pair's slot holds its
     * sqrt_m_eff where bb.hist has the feature (slot_sqm), so that the law's mass comes with
     * the spring for the touching pairs instead of in a stream of its own for every entry, and
     * the feature is the entry's flag (act) */
    int lsq;
    int k0; /* the chunk's first entry (with lsq, a sphere pair's off is its entry's index) */
} soa_view;

/* Sphere–wall contacts on a face, in batches like the sphere pairs: a sphere whose wall
 * candidates give one face contact and nothing near an edge (nearly every sphere on a floor or
 * a side wall) skips the manifold and the mesh dedup, and its contact goes through the law in
 * lanes. The arithmetic is sd_manifold_apply's for a one-point manifold, operation for operation
 * (same bits). */
#define BT_CHUNK 64
typedef struct {
    double nx[BT_CHUNK], ny[BT_CHUNK], nz[BT_CHUNK], ov[BT_CHUNK]; /* normal on the sphere, overlap */
    double rx[BT_CHUNK], ry[BT_CHUNK], rz[BT_CHUNK];               /* contact point - centre */
    double vx[BT_CHUNK], vy[BT_CHUNK], vz[BT_CHUNK];               /* the sphere's velocity */
    double wx[BT_CHUNK], wy[BT_CHUNK], wz[BT_CHUNK];               /* its spin */
    double sqm[BT_CHUNK];
    double sx[BT_CHUNK], sy[BT_CHUNK], sz[BT_CHUNK]; /* spring in, then out */
    double fx[BT_CHUNK], fy[BT_CHUNK], fz[BT_CHUNK]; /* force on the sphere */
    double tx[BT_CHUNK], ty[BT_CHUNK], tz[BT_CHUNK]; /* torque on it */
    double redo[BT_CHUNK];
    int32_t k[BT_CHUNK]; /* the pair */
} bt_batch;

/* per-thread scratch of the body-body pass */
typedef struct {
    ss_batch q;
    sd_pair_out out[SS_CHUNK];
    int used[SS_CHUNK];
    bt_batch wq;
    sd_bed_split bed; /* the serial pass's (the owners keep theirs in sd_owned) */
} bb_scratch;

#define NEAR_BLOCK 512 /* candidates whose answers are made at a time, then kept (sd_owned_update, near_filter) */
/* the chunks ahead of the pass that the front prefetch reaches (front_prefetch.c) */
#define PF_CHUNKS 2

/* contact_manifold.c: the shape-pair dispatch (a pair's manifold) and the law applied to a
 * manifold's points */
int sd_manifold_bb(const sd_bodies *b, const sd_pair *p, sd_manifold *m);
int sd_manifold_bt(const sd_bodies *b, const sd_walls *wl, const sd_pair *p, sd_manifold *m);
int sd_manifold_apply(const sd_world *w, const sd_law *law, const sd_manifold *m, int ia, int ib, int b_is_static,
                      double sqm, sd_hist *slots, int cap, const sd_vec3 *seed, int weighted, sd_pair_out *out);
/* The shares of the points of nm manifolds (one pair's, or a log's wall pairs' after the mesh
 * rule) made weights: each raw share over the sum of the raw shares of the points whose
 * normals agree with its own (within 10 deg fully, fading out to 30 deg), so that the points
 * of one flat or line contact share the dashpot and K_s with weights summing to 1; and each
 * point's overlap made the one its spring sees, so that the weighted springs sum to K_n times
 * the deepest overlap among those points (contact_manifold.c). At most SD_SHARE_MAX points are
 * shared; a log with more wall contacts gets each at full weight and its own overlap. */
#define SD_SHARE_MAX 64
void sd_manifold_shares(sd_manifold *ms, int nm);
/* The springs of a log-log pair's contacts whose feature changed (seed[k], zero if none): an
 * end disk turning from the other's side to its end face keeps its spring, and so does the one
 * contact of a pair that changed its type (side-side, end disk, last resort). Returns the count. */
int sd_manifold_carry_cc(const sd_manifold *m, const sd_hist *slots, int cap, sd_vec3 *seed);
/* a pair of another shape than two spheres (chunk entry i): a one-point sphere-log contact into
 * lane msc of q (returns 1), anything else through sd_manifold_apply now (returns 0) */
int sd_manifold_general_pair(const sd_world *w, const sd_law *law, const sd_pair *p, int i, struct sc_lanes *q,
                             int msc, sd_pair_out *out, int *used);

/* lane_law.c: the law in lanes over a batch (sphere pairs in two loops, sphere-log pairs,
 * sphere-wall face contacts) */
void sd_lane_law_ss_normal(ss_batch *restrict q, int m);
void sd_lane_law_ss_spring(const sd_lane_law *lanes, ss_batch *restrict q, int j0, int m);
void sd_lane_law_sc(const sd_lane_law *lanes, struct sc_lanes *restrict q, int m);
void sd_lane_law_bt(const sd_lane_law *lanes, bt_batch *restrict q, int m);
/* the same with several materials: lane j's law is table[lw[j]] (sd_step_ctx.lanes) */
void sd_lane_law_ss_spring_mat(const sd_lane_law *table, const int32_t *lw, ss_batch *restrict q, int m);
void sd_lane_law_sc_mat(const sd_lane_law *table, const int32_t *lw, struct sc_lanes *restrict q, int m);
void sd_lane_law_bt_mat(const sd_lane_law *table, const int32_t *lw, bt_batch *restrict q, int m);

/* pair_records.c: room for n records (nonzero when out of memory) */
int sd_pair_soa_reserve(sd_pair_soa *s, int n);

/* contact_bb.c: the body-body pass */
void sd_bb_bed_split(const sd_world *w, sd_bed_split *s);
void sd_bb_chunk(const sd_world *w, const sd_law *law, const int32_t *ks, const soa_view *v, int n, sd_pair_out *out,
                 int *used, ss_batch *q, sd_bodies *acc);
long sd_bb_serial_pass(sd_world *w, const sd_law *law, bb_scratch *x);

/* contact_bt.c: the body-wall pass over the bodies list[0 .. nl) */
long sd_bt_range(sd_world *w, const sd_law *law, const int32_t *list, int nl, bt_batch *q);

/* near_list.c: the near lists, the wall-near list, the springs held in list order */
int sd_near_mark_ready(sd_world *w);
int sd_near_block(sd_world *w, double skin, int kb, int ke, int fresh, int nf, int32_t *near);
int sd_near_walls(sd_world *w, double skin, int i0, int i1, int32_t *list, long *skip);
sd_status sd_near_springs_to(sd_world *w, int out);
int sd_near_still_good(const sd_world *w);
void sd_near_made(sd_world *w, double skin);
sd_status sd_near_update(sd_world *w);

/* owners.c: the owners' body ranges, near lists and cross pairs, and the owned pass */
sd_status sd_owned_update(sd_world *w, int T);
long sd_owned_pass(sd_world *w, const sd_law *law, int T, bb_scratch *scratch, int *moved_out, sd_moves *mv);
int sd_owned_count(const sd_world *w);

/* front_prefetch.c: the front prefetch of the bodies' rows that entries j0 .. j1 of a list's
 * records touch (the slots': contact_kernels.h pf_hist) */
void sd_front_prefetch_rows(const sd_bodies *b, const int32_t *pa, const int32_t *pb, int j0, int j1, int lim,
                            int *front);

/* The hand-written SIMD kernels of the contact pass at one width, chosen once per world by its
 * SIMD level (w->kern, sd_contact_kernels_for): each takes what it can, starting where the
 * scalar loop would, and returns where it stopped; the scalar code (contact_bb.c, lane_law.c,
 * contact_kernels.h's near_test) finishes, and is the reference each kernel gives the same
 * bits as. NULL: none at this width. */
struct sd_contact_kernels {
    /* the touch filter (step 1 of sd_bb_chunk) from entry i */
    int (*ss_filter)(const sd_world *w, const int32_t *ks, const soa_view *v, int i, int n, int *used, ss_batch *q,
                     int *mp, int *gen, int *ngp);
    int (*ss_gather)(const sd_world *w, ss_batch *q, int m);                 /* step 3, from 0 */
    int (*ss_law_spring)(const sd_lane_law *lanes, ss_batch *q, int m); /* step 4's springs */
    int (*ss_sums)(ss_batch *q, int j, sd_bodies *acc); /* step 5: lanes j .. j + 3 at once, or 0 */
    /* the sphere-log pairs sg[0 .. n) of step 2 in lanes */
    int (*sc_geom)(const sd_world *w, const sd_law *law, const int32_t *ks, const soa_view *v, const int *sg, int n,
                   struct sc_lanes *q, int msc, sd_pair_out *out, int *used);
    /* the near test of candidates k0 .. k1 */
    int (*near_test)(const sd_world *w, double skin, int k0, int k1, uint8_t *restrict keep, int nf);
};

#ifdef SD_FILTER512
extern const sd_contact_kernels sd_avx2_kernels, sd_avx512_kernels;
/* contact_simd_avx2.c: the AVX2 kernels (their scalar references are in contact_bb.c,
 * lane_law.c and contact_kernels.h's near_test) */
void sd_avx2_tables_ready(void);
__attribute__((target("avx2,popcnt"))) int sd_avx2_ss_filter(const sd_world *w, const soa_view *v, int i, int n,
                                                             int *used, ss_batch *q, int *mp, int *gen, int *ngp);
__attribute__((target("avx2"))) int sd_avx2_ss_gather(const sd_world *w, ss_batch *q, int m);
__attribute__((target("avx2"))) int sd_avx2_ss_sums(ss_batch *q, int j, sd_bodies *acc);
__attribute__((target("avx2"))) int sd_avx2_ss_law_spring(const sd_lane_law *lanes, ss_batch *restrict q, int m);
__attribute__((target("avx2"))) int sd_avx2_sc_geom(const sd_world *w, const sd_law *law, const int32_t *ks,
                                                    const soa_view *v, const int *sg, int n, struct sc_lanes *q,
                                                    int msc, sd_pair_out *out, int *used);
__attribute__((target("avx2"))) int sd_avx2_near_test(const sd_world *w, double skin, int k0, int k1,
                                                      uint8_t *restrict keep, int nf);
/* contact_simd_avx512.c: the AVX-512 kernels */
__attribute__((target("avx512f,avx512vl,popcnt"))) int sd_avx512_ss_filter(const sd_world *w, const int32_t *ks,
                                                                           const soa_view *v, int i, int n, int *used,
                                                                           ss_batch *q, int *mp, int *gen, int *ngp);
__attribute__((target("avx512f,avx512vl"))) void sd_avx512_ss_gather(const sd_world *w, ss_batch *q, int m);
#endif

#endif
