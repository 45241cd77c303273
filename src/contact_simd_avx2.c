/* The contact pass's AVX2 kernels (4 lanes): the touch filter, gather and sums of the sphere
 * pairs, the sphere law's spring loop, the sphere-log geometry and the near test. Their
 * references are the scalar loops (contact_bb.c, lane_law.c, contact_kernels.h); the same
 * bits. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <threads.h>

#include "contact_kernels.h"
#include "core/simd.h"

#ifdef SD_FILTER512
#include <immintrin.h>

/* p[a[k]] - p[b[k]] for the four vec3 rows of the array p, in lanes x, y, z */
__attribute__((target("avx2"))) static inline void diff_lanes(const double *p, const int32_t *a, const int32_t *b,
                                                              __m256d *x, __m256d *y, __m256d *z)
{
    __m256d r[4];
    sd_transpose4(_mm256_sub_pd(SD_XYZ_LOAD(p, a[0]), SD_XYZ_LOAD(p, b[0])),
                  _mm256_sub_pd(SD_XYZ_LOAD(p, a[1]), SD_XYZ_LOAD(p, b[1])),
                  _mm256_sub_pd(SD_XYZ_LOAD(p, a[2]), SD_XYZ_LOAD(p, b[2])),
                  _mm256_sub_pd(SD_XYZ_LOAD(p, a[3]), SD_XYZ_LOAD(p, b[3])), r);
    *x = r[0], *y = r[1], *z = r[2];
}

/* Lane compress for AVX2, indexed by a 4-bit mask of kept lanes: the kept lanes moved down in
 * order. perm_pd: _mm256_permutevar8x32 indices for 4 doubles; shuf_i32: _mm_shuffle_epi8
 * bytes for 4 int32. Filled once, by the first world's first contact pass (call_once). */
static int32_t perm_pd[16][8];
static uint8_t shuf_i32[16][16];
static int32_t bit_i32[16][4]; /* lane k: bit k of the mask, 0 or 1 */
static uint32_t bit_u8[16];    /* byte k: bit k of the mask, 0 or 1 */

static once_flag simd_tables_once = ONCE_FLAG_INIT;

static void simd_tables_init(void)
{
    for (int mask = 0; mask < 16; mask++) {
        int n = 0;
        bit_u8[mask] = 0;
        for (int k = 0; k < 4; k++) {
            bit_i32[mask][k] = (mask >> k) & 1;
            bit_u8[mask] |= (uint32_t)((mask >> k) & 1) << (8 * k);
            if (!((mask >> k) & 1)) continue;
            perm_pd[mask][2 * n] = 2 * k, perm_pd[mask][2 * n + 1] = 2 * k + 1;
            for (int c = 0; c < 4; c++)
                shuf_i32[mask][4 * n + c] = (uint8_t)(4 * k + c);
            n++;
        }
        for (; n < 4; n++) { /* the rest: anything (never read) */
            perm_pd[mask][2 * n] = 0, perm_pd[mask][2 * n + 1] = 1;
            for (int c = 0; c < 4; c++)
                shuf_i32[mask][4 * n + c] = 0x80;
        }
    }
}

/* the tables filled, once for the process (the contact pass calls it before each pass) */
void sd_avx2_tables_ready(void) { call_once(&simd_tables_once, simd_tables_init); }

/* Step 1 of sd_bb_chunk in AVX2, 4 pairs at a time: ss_filter_range's operations in its order
 * (same bits), the centres read as rows (SD_XYZ_LOAD) and turned into lanes,
 * the touching pairs packed into the batch by a permutation from a table and stored 4 lanes
 * wide (the arrays are padded by SS_PAD). The group's other entries go to gen as they are (not
 * through filter_other: sd_bb_chunk's step 2 takes them through other_pair). Runs while 4 pairs
 * remain and returns where it stopped; gen has room for 4 past *ngp (*ngp <= i). */
__attribute__((target("avx2,popcnt"))) int sd_avx2_ss_filter(const sd_world *w, const soa_view *v, int i, int n,
                                                             int *used, ss_batch *q, int *mp, int *gen, int *ngp)
{
    sd_hist *hist = v->sh;
    const double *pos = &w->b.pos[0].x;
    /* the view's arrays in locals: the packing's 16-byte stores may alias anything, and gcc
     * loaded each address from *v again after them */
    const int32_t *const va = v->a, *const vb = v->b, *const voff = v->off;
    const double *const vsqm = v->sqm, *const rad = w->b.radius;
    const float *const vrs2 = v->rs2;
    uint8_t *const vact = v->act;
    const int lsq = v->lsq;
    int m = *mp, ng = *ngp;
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    for (; i + 4 <= n; i += 4) {
        /* the lanes of sphere pairs, by the sign of the entries' rs2 (-1 for any other:
         * entry_rs2; ck is not read); a log's pair takes the scalar loop's path after the
         * group (in pair order among the log pairs) */
        const __m128 rs2f = _mm_loadu_ps(vrs2 + i);
        const int ss = ~_mm_movemask_ps(rs2f) & 15;
        __m256d dx, dy, dz;
        diff_lanes(pos, va + i, vb + i, &dx, &dy, &dz);
        const __m256d d2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
        /* t = !(d2 >= rs^2), as the scalar loop (true for an unordered pair too), from the
         * entry's rs^2 as a float (4 bytes of stream, not 8): below it less a relative 2^-22, a
         * pair touches; at or above it plus as much, it does not (the float is within 2^-24 of
         * rs^2); in between, or with a NaN, the radii are read and the test made exactly (a
         * gap within ~1e-7 of the radii: seldom). The radii themselves are read by the gather
         * for the touching lanes (sd_avx2_ss_gather) */
        const __m256d r = _mm256_cvtps_pd(rs2f);
        const int in = _mm256_movemask_pd(
                      _mm256_cmp_pd(d2, _mm256_mul_pd(r, _mm256_set1_pd(1.0 - RS2_EDGE)), _CMP_LT_OQ)),
                  out = _mm256_movemask_pd(
                      _mm256_cmp_pd(d2, _mm256_mul_pd(r, _mm256_set1_pd(1.0 + RS2_EDGE)), _CMP_GE_OQ));
        int t = in & ss, edge = ~(in | out) & ss & 15;
        if (edge) {
            double d2l[4];
            _mm256_storeu_pd(d2l, d2);
            for (; edge; edge &= edge - 1) {
                const int l = __builtin_ctz((unsigned)edge);
                const double rs = rad[va[i + l]] + rad[vb[i + l]];
                t |= !(d2l[l] >= rs * rs) << l;
            }
        }
        /* the slots' features from the entries' flags (0 with a spring, else -1), not from the
         * slots: a line of its own for each near pair, most of them apart in a flow (the
         * slots' load was a tenth of this loop's samples in the paper's capture) */
        uint32_t act4;
        memcpy(&act4, vact + i, sizeof act4);
        const __m128i was = _mm_sub_epi32(_mm_cvtepu8_epi32(_mm_cvtsi32_si128((int)act4)), _mm_set1_epi32(1));
        const int had = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(was, _mm_setzero_si128())));
        _mm_storeu_si128((__m128i *)(used + i), _mm_loadu_si128((const __m128i *)bit_i32[t]));
        /* the flags for the next step: a spring where they touch now */
        memcpy(vact + i, &bit_u8[t], sizeof act4);
        /* a contact that has just ended loses its spring (few in a step, so the branch is
         * seldom taken) */
        int gone = lsq ? 0 : ~t & had & ss;
        for (; gone; gone &= gone - 1)
            hist[voff[i + __builtin_ctz((unsigned)gone)]].feature = -1;
        const __m256i pp = _mm256_loadu_si256((const __m256i *)perm_pd[t]);
        const __m128i ps = _mm_loadu_si128((const __m128i *)shuf_i32[t]);
#define PACK_PD(dst, x) _mm256_storeu_pd((dst) + m, _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(x), pp)))
#define PACK_I32(dst, x) _mm_storeu_si128((__m128i *)((dst) + m), _mm_shuffle_epi8((x), ps))
        PACK_PD(q->dx, dx);
        PACK_PD(q->dy, dy);
        PACK_PD(q->dz, dz);
        if (!lsq) PACK_PD(q->sqm, _mm256_loadu_pd(vsqm + i)); /* (else the gather: the slot) */
        PACK_I32(q->ia, _mm_loadu_si128((const __m128i *)(va + i)));
        PACK_I32(q->ib, _mm_loadu_si128((const __m128i *)(vb + i)));
        /* (in a list's own slots, off is the entry's index: not read) */
        PACK_I32(q->off,
                 lsq ? _mm_add_epi32(_mm_set1_epi32(v->k0 + i), lane) : _mm_loadu_si128((const __m128i *)(voff + i)));
        PACK_I32(q->was, was);
        PACK_I32(q->sel, _mm_add_epi32(_mm_set1_epi32(i), lane));
#undef PACK_PD
#undef PACK_I32
        m += __builtin_popcount((unsigned)t);
        /* the group's other entries (a log's pair, an owner's cross entry) listed in gen as they
         * are, by the same table, and sorted out in step 2 (other_pair; a sphere-log pair's
         * apart test left to sd_avx2_sc_geom's lanes, its kind read from the view there). A loop over
         * them here, like the scalar filter's, ran a number of times that changes from group to
         * group where logs are, and its exit was mispredicted: the packing ~2.5 % slower */
        const int om = ~ss & 15;
        _mm_storeu_si128((__m128i *)(gen + ng), _mm_shuffle_epi8(_mm_add_epi32(_mm_set1_epi32(i), lane),
                                                                 _mm_loadu_si128((const __m128i *)shuf_i32[om])));
        ng += __builtin_popcount((unsigned)om);
    }
    *mp = m;
    *ngp = ng;
    return i;
}

/* Step 3 of sd_bb_chunk in AVX2, 4 touching lanes at a time: each body's velocity and spin read as
 * a row and turned into lanes, the slot's spring likewise, masked to +0.0 for a new contact as
 * ss_gather_range does (same bits). Returns where it stopped (the rest: ss_gather_range). */
_Static_assert(sizeof(sd_hist) == 32 && offsetof(sd_hist, shear) == 8, "sd_avx2_ss_gather reads a slot as 4 doubles");

__attribute__((target("avx2"))) int sd_avx2_ss_gather(const sd_world *w, ss_batch *q, int m)
{
    const double *vel = &w->b.vel[0].x, *om = &w->b.omega[0].x, *rad = w->b.radius;
    const sd_hist *hist = q->sh;
    int j = 0;
    for (; j + 4 <= m; j += 4) {
        const int a0 = q->ia[j], a1 = q->ia[j + 1], a2 = q->ia[j + 2], a3 = q->ia[j + 3];
        const int b0 = q->ib[j], b1 = q->ib[j + 1], b2 = q->ib[j + 2], b3 = q->ib[j + 3];
        __m256d r[4];
        __m256d x, y, z;
        /* the radii (the AVX2 filter tests the entries' (r_a + r_b)^2 and leaves them) */
        _mm256_storeu_pd(q->ra + j, _mm256_setr_pd(rad[a0], rad[a1], rad[a2], rad[a3]));
        _mm256_storeu_pd(q->rb + j, _mm256_setr_pd(rad[b0], rad[b1], rad[b2], rad[b3]));
        diff_lanes(vel, q->ia + j, q->ib + j, &x, &y, &z);
        _mm256_storeu_pd(q->vx + j, x);
        _mm256_storeu_pd(q->vy + j, y);
        _mm256_storeu_pd(q->vz + j, z);
        sd_transpose4(SD_XYZ_LOAD(om, a0), SD_XYZ_LOAD(om, a1), SD_XYZ_LOAD(om, a2), SD_XYZ_LOAD(om, a3), r);
        _mm256_storeu_pd(q->wax + j, r[0]);
        _mm256_storeu_pd(q->way + j, r[1]);
        _mm256_storeu_pd(q->waz + j, r[2]);
        sd_transpose4(SD_XYZ_LOAD(om, b0), SD_XYZ_LOAD(om, b1), SD_XYZ_LOAD(om, b2), SD_XYZ_LOAD(om, b3), r);
        _mm256_storeu_pd(q->wbx + j, r[0]);
        _mm256_storeu_pd(q->wby + j, r[1]);
        _mm256_storeu_pd(q->wbz + j, r[2]);
        /* the slots as rows (feature and padding, shear x, y, z): a held contact's (was 0) kept */
        sd_transpose4(_mm256_loadu_pd((const double *)&hist[q->off[j]]),
                      _mm256_loadu_pd((const double *)&hist[q->off[j + 1]]),
                      _mm256_loadu_pd((const double *)&hist[q->off[j + 2]]),
                      _mm256_loadu_pd((const double *)&hist[q->off[j + 3]]), r);
        const __m256d keep = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(
            _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(q->was + j)), _mm_setzero_si128())));
        if (q->lsq) _mm256_storeu_pd(q->sqm + j, r[0]); /* (a list's own slot: sqm first) */
        _mm256_storeu_pd(q->sx + j, _mm256_and_pd(r[1], keep));
        _mm256_storeu_pd(q->sy + j, _mm256_and_pd(r[2], keep));
        _mm256_storeu_pd(q->sz + j, _mm256_and_pd(r[3], keep));
    }
    return j;
}

/* *p + (x, y, z) of row r, or *p - it (sub): add_pair_lim's v3_add / v3_sub, x and y in one
 * 16-byte operation */
__attribute__((target("avx2"))) static inline void row_add(sd_vec3 *p, __m256d r, int sub)
{
    const __m128d xy = _mm_loadu_pd(&p->x), rxy = _mm256_castpd256_pd128(r);
    const double rz = _mm_cvtsd_f64(_mm256_extractf128_pd(r, 1));
    _mm_storeu_pd(&p->x, sub ? _mm_sub_pd(xy, rxy) : _mm_add_pd(xy, rxy));
    p->z = sub ? p->z - rz : p->z + rz;
}

/* Step 5 of sd_bb_chunk (with acc) in AVX2 for the lanes j .. j+3, when none is to be redone
 * (returns 0 and does nothing otherwise): the torques of four lanes at once, the slots' springs
 * stored as 32-byte rows (the feature 0), and each pair onto its two bodies in lane order as
 * add_pair_lim does (same bits; a bed body's rows into q->sink, where the bed is from
 * q->bed_lim on). */
__attribute__((target("avx2"))) int sd_avx2_ss_sums(ss_batch *q, int j, sd_bodies *acc)
{
    const __m256d zero = _mm256_setzero_pd();
    if (_mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(q->redo + j), zero, _CMP_NEQ_UQ))) return 0;
    sd_hist *hist = q->sh;
    const __m256d nfx = _mm256_loadu_pd(q->nfx + j), nfy = _mm256_loadu_pd(q->nfy + j),
                  nfz = _mm256_loadu_pd(q->nfz + j);
    const __m256d sign = _mm256_set1_pd(-0.0); /* -la as the scalar loop negates it: the sign bit flipped */
    const __m256d mla = _mm256_xor_pd(_mm256_loadu_pd(q->la + j), sign),
                  mlb = _mm256_xor_pd(_mm256_loadu_pd(q->lb + j), sign);
    __m256d hr[4], fr[4], ta[4], tb[4];
    /* the slot's first 8 bytes: the feature 0 and its padding, or in a list's own slot the sqm
     * it holds */
    sd_transpose4(q->lsq ? _mm256_loadu_pd(q->sqm + j) : zero, _mm256_loadu_pd(q->sx + j), _mm256_loadu_pd(q->sy + j),
                  _mm256_loadu_pd(q->sz + j), hr);
    sd_transpose4(_mm256_loadu_pd(q->fx + j), _mm256_loadu_pd(q->fy + j), _mm256_loadu_pd(q->fz + j), zero, fr);
    sd_transpose4(_mm256_mul_pd(nfx, mla), _mm256_mul_pd(nfy, mla), _mm256_mul_pd(nfz, mla), zero, ta);
    sd_transpose4(_mm256_mul_pd(nfx, mlb), _mm256_mul_pd(nfy, mlb), _mm256_mul_pd(nfz, mlb), zero, tb);
    /* the bodies' arrays in locals: each row's 32-byte store may alias anything, and gcc
     * loaded the addresses from *acc again after every one */
    sd_vec3 *const force = acc->force, *const torque = acc->torque;
    const int lim = q->bed_lim;
    if (lim >= 0) {
        /* the bed from lim on: a lane's B body of the bed (a pair's A never is: its B would be
         * too) adds into a sink row instead of a branch, taken at random where spheres rest on
         * the bed */
        sd_vec3 *const sink = q->sink;
        for (int k = 0; k < 4; k++) {
            const int ia = q->ia[j + k], ib = q->ib[j + k], bed = ib >= lim;
            _mm256_storeu_pd((double *)&hist[q->off[j + k]], hr[k]);
            if (ia < lim) {
                row_add(&force[ia], fr[k], 0);
                row_add(&torque[ia], ta[k], 0);
            }
            /* (the select in integer bits: as a ternary gcc made it a branch again) */
            const uintptr_t m = (uintptr_t)0 - (uintptr_t)bed, pf = (uintptr_t)&force[ib], pt = (uintptr_t)&torque[ib];
            sd_vec3 *const fb = (sd_vec3 *)(pf ^ ((pf ^ (uintptr_t)&sink[2 * k]) & m)),
                           *const tq = (sd_vec3 *)(pt ^ ((pt ^ (uintptr_t)&sink[2 * k + 1]) & m));
            row_add(fb, fr[k], 1);
            row_add(tq, tb[k], 0);
        }
        return 1;
    }
    for (int k = 0; k < 4; k++) {
        const int ia = q->ia[j + k], ib = q->ib[j + k];
        _mm256_storeu_pd((double *)&hist[q->off[j + k]], hr[k]);
        if (!bed_at(acc, lim, ia)) {
            row_add(&force[ia], fr[k], 0);
            row_add(&torque[ia], ta[k], 0);
        }
        if (!bed_at(acc, lim, ib)) {
            row_add(&force[ib], fr[k], 1);
            row_add(&torque[ib], tb[k], 0);
        }
    }
    return 1;
}

/* near_test of candidates k0 .. while 4 remain, the sphere pairs' in AVX2 lanes (the centres
 * as rows, near_test's operations; a log's pair through near_test); returns where it stopped. */
__attribute__((target("avx2"))) int sd_avx2_near_test(const sd_world *w, double skin, int k0, int k1,
                                                      uint8_t *restrict keep, int nf)
{
    const double *pos = &w->b.pos[0].x, *rad = w->b.radius;
    const sd_pair *pairs = w->bb.p;
    const __m256d skv = _mm256_set1_pd(skin), hsv = _mm256_set1_pd(0.5 * skin);
    const __m128i nf1 = _mm_set1_epi32(nf - 1);
    int k = k0;
    for (; k + 4 <= k1; k += 4) {
        const sd_pair *p = pairs + k;
        const int32_t a[4] = {p[0].a, p[1].a, p[2].a, p[3].a}, b[4] = {p[0].b, p[1].b, p[2].b, p[3].b};
        __m256d dx, dy, dz;
        diff_lanes(pos, a, b, &dx, &dy, &dz);
        /* half the skin where a body is of the bed (near_test), chosen by lane masks */
        const __m128i bed = _mm_or_si128(_mm_cmpgt_epi32(_mm_loadu_si128((const __m128i *)a), nf1),
                                         _mm_cmpgt_epi32(_mm_loadu_si128((const __m128i *)b), nf1));
        const __m256d sk = _mm256_blendv_pd(skv, hsv, _mm256_castsi256_pd(_mm256_cvtepi32_epi64(bed)));
        const __m256d reach = _mm256_add_pd(_mm256_add_pd(_mm256_setr_pd(rad[a[0]], rad[a[1]], rad[a[2]], rad[a[3]]),
                                                          _mm256_setr_pd(rad[b[0]], rad[b[1]], rad[b[2]], rad[b[3]])),
                                            sk);
        const __m256d d2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
        const int in = _mm256_movemask_pd(_mm256_cmp_pd(d2, _mm256_mul_pd(reach, reach), _CMP_LE_OQ));
        for (int l = 0; l < 4; l++)
            keep[k + l - k0] = (uint8_t)(p[l].kind == SD_PAIR_SS ? in >> l & 1 : near_test(w, skin, &p[l], nf));
    }
    return k;
}

/* the calling thread's groups run in lanes, and of them those that skipped the limit (tests) */
static _Thread_local long ss_law256_groups, ss_law256_skips;

long sd_avx2_ss_law_count(long *skipped)
{
    if (skipped) *skipped = ss_law256_skips;
    return ss_law256_groups;
}

/* sd_lane_law_ss_spring in AVX2 for the lanes 0 .. m & ~3, four at a time: law_lane's operations in
 * its order, each select a blend (the same bits), and its limit's square root and division
 * left out of a group where no lane slides and no lane's force passes the limit (three groups
 * in four on a bed at rest: they were a fifth of this loop's samples there). Returns the lanes
 * done. */
__attribute__((target("avx2"))) int sd_avx2_ss_law_spring(const sd_lane_law *lanes, ss_batch *restrict q, int m)
{
    const sd_lane_law L = *lanes;
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5),
                  c375 = _mm256_set1_pd(0.375), c1e4 = _mm256_set1_pd(1e-4), sign = _mm256_set1_pd(-0.0),
                  kn = _mm256_set1_pd(L.k_n), cn = _mm256_set1_pd(L.c_n), mks = _mm256_set1_pd(L.mks_dt),
                  coh = _mm256_set1_pd(L.coh), tphi = _mm256_set1_pd(L.tan_phi), mcsf = _mm256_set1_pd(-L.c_s);
    int j = 0;
    for (; j + 4 <= m; j += 4) {
        const __m256d nx = _mm256_loadu_pd(q->dx + j), ny = _mm256_loadu_pd(q->dy + j), nz = _mm256_loadu_pd(q->dz + j);
        const __m256d vx = _mm256_loadu_pd(q->vx + j), vy = _mm256_loadu_pd(q->vy + j), vz = _mm256_loadu_pd(q->vz + j);
        const __m256d ov = _mm256_loadu_pd(q->ra + j), sqm = _mm256_loadu_pd(q->sqm + j);
        const __m256d s0x = _mm256_loadu_pd(q->sx + j), s0y = _mm256_loadu_pd(q->sy + j),
                      s0z = _mm256_loadu_pd(q->sz + j);
        const __m256d vn =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, nx), _mm256_mul_pd(vy, ny)), _mm256_mul_pd(vz, nz));
        __m256d pn = _mm256_sub_pd(_mm256_mul_pd(kn, ov), _mm256_mul_pd(_mm256_mul_pd(cn, sqm), vn));
        pn = _mm256_blendv_pd(pn, zero, _mm256_cmp_pd(pn, zero, _CMP_LT_OQ));
        const __m256d mvn = _mm256_xor_pd(vn, sign);
        const __m256d tx = _mm256_add_pd(vx, _mm256_mul_pd(mvn, nx)), ty = _mm256_add_pd(vy, _mm256_mul_pd(mvn, ny)),
                      tz = _mm256_add_pd(vz, _mm256_mul_pd(mvn, nz));
        const __m256d s2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(s0x, s0x), _mm256_mul_pd(s0y, s0y)), _mm256_mul_pd(s0z, s0z));
        const __m256d sn =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(s0x, nx), _mm256_mul_pd(s0y, ny)), _mm256_mul_pd(s0z, nz));
        const __m256d msn = _mm256_xor_pd(sn, sign);
        const __m256d px = _mm256_add_pd(s0x, _mm256_mul_pd(msn, nx)), py = _mm256_add_pd(s0y, _mm256_mul_pd(msn, ny)),
                      pz = _mm256_add_pd(s0z, _mm256_mul_pd(msn, nz));
        const __m256d sn2 = _mm256_mul_pd(sn, sn);
        const __m256d r2 = _mm256_sub_pd(s2, sn2);
        const __m256d x = _mm256_div_pd(sn2, r2);
        const __m256d poly =
            _mm256_sub_pd(_mm256_add_pd(one, _mm256_mul_pd(half, x)), _mm256_mul_pd(_mm256_mul_pd(c375, x), x));
        const __m256d has = _mm256_cmp_pd(s2, zero, _CMP_GT_OQ);
        /* redo = sn^2 < 1e-4 s2 ? 0 : (has ? 1 : 0) */
        const __m256d redo =
            _mm256_andnot_pd(_mm256_cmp_pd(sn2, _mm256_mul_pd(c1e4, s2), _CMP_LT_OQ), _mm256_and_pd(has, one));
        __m256d ux = _mm256_blendv_pd(s0x, _mm256_mul_pd(px, poly), has),
                uy = _mm256_blendv_pd(s0y, _mm256_mul_pd(py, poly), has),
                uz = _mm256_blendv_pd(s0z, _mm256_mul_pd(pz, poly), has);
        ux = _mm256_add_pd(ux, _mm256_mul_pd(mks, tx));
        uy = _mm256_add_pd(uy, _mm256_mul_pd(mks, ty));
        uz = _mm256_add_pd(uz, _mm256_mul_pd(mks, tz));
        const __m256d limit = _mm256_add_pd(coh, _mm256_mul_pd(pn, tphi)), lim2 = _mm256_mul_pd(limit, limit);
        const __m256d smag2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ux, ux), _mm256_mul_pd(uy, uy)), _mm256_mul_pd(uz, uz));
        const __m256d slide = _mm256_cmp_pd(smag2, lim2, _CMP_GT_OQ);
        const __m256d mcs = _mm256_mul_pd(mcsf, sqm);
        __m256d gx = _mm256_add_pd(ux, _mm256_mul_pd(mcs, tx)), gy = _mm256_add_pd(uy, _mm256_mul_pd(mcs, ty)),
                gz = _mm256_add_pd(uz, _mm256_mul_pd(mcs, tz));
        const __m256d fmag2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(gx, gx), _mm256_mul_pd(gy, gy)), _mm256_mul_pd(gz, gz));
        const __m256d over = _mm256_cmp_pd(fmag2, lim2, _CMP_GT_OQ);
        ss_law256_groups++;
        if (!_mm256_movemask_pd(_mm256_or_pd(slide, over)))
            ss_law256_skips++;
        else {
            const __m256d cut = _mm256_div_pd(limit, _mm256_sqrt_pd(_mm256_blendv_pd(fmag2, smag2, slide)));
            gx = _mm256_blendv_pd(gx, _mm256_mul_pd(gx, cut), over);
            gy = _mm256_blendv_pd(gy, _mm256_mul_pd(gy, cut), over);
            gz = _mm256_blendv_pd(gz, _mm256_mul_pd(gz, cut), over);
            ux = _mm256_blendv_pd(ux, _mm256_mul_pd(ux, cut), slide);
            uy = _mm256_blendv_pd(uy, _mm256_mul_pd(uy, cut), slide);
            uz = _mm256_blendv_pd(uz, _mm256_mul_pd(uz, cut), slide);
            gx = _mm256_blendv_pd(gx, ux, slide);
            gy = _mm256_blendv_pd(gy, uy, slide);
            gz = _mm256_blendv_pd(gz, uz, slide);
        }
        const __m256d fx = _mm256_add_pd(gx, _mm256_mul_pd(pn, nx)), fy = _mm256_add_pd(gy, _mm256_mul_pd(pn, ny)),
                      fz = _mm256_add_pd(gz, _mm256_mul_pd(pn, nz));
        _mm256_storeu_pd(q->redo + j, redo);
        _mm256_storeu_pd(q->sx + j, ux), _mm256_storeu_pd(q->sy + j, uy), _mm256_storeu_pd(q->sz + j, uz);
        _mm256_storeu_pd(q->fx + j, fx), _mm256_storeu_pd(q->fy + j, fy), _mm256_storeu_pd(q->fz + j, fz);
        _mm256_storeu_pd(q->nfx + j, _mm256_sub_pd(_mm256_mul_pd(ny, fz), _mm256_mul_pd(nz, fy)));
        _mm256_storeu_pd(q->nfy + j, _mm256_sub_pd(_mm256_mul_pd(nz, fx), _mm256_mul_pd(nx, fz)));
        _mm256_storeu_pd(q->nfz + j, _mm256_sub_pd(_mm256_mul_pd(nx, fy), _mm256_mul_pd(ny, fx)));
    }
    return j;
}

/* The vec3 rows i[0..3] of the array p (3 doubles each) as lanes x, y, z (r[0..2]). */
__attribute__((target("avx2"))) static inline void rows4(const double *p, const int i[4], __m256d r[4])
{
    sd_transpose4(SD_XYZ_LOAD(p, i[0]), SD_XYZ_LOAD(p, i[1]), SD_XYZ_LOAD(p, i[2]), SD_XYZ_LOAD(p, i[3]), r);
}

/* Rows i[0..3] of p into the lane arrays x, y, z at j. */
__attribute__((target("avx2"))) static inline void rows4_store(const double *p, const int i[4], double *x, double *y,
                                                               double *z, int j)
{
    __m256d r[4];
    rows4(p, i, r);
    _mm256_storeu_pd(x + j, r[0]), _mm256_storeu_pd(y + j, r[1]), _mm256_storeu_pd(z + j, r[2]);
}

/* Four sphere-log pairs in lanes: the spheres' centres (c) and radii (rs), the logs' centres
 * (b), axes (a), radii (rc) and half-lengths (hl), d = c - b and t = d.a, and w = d + (-t) a with
 * rho2 = |w|^2 (sd_sphere_cyl_apart's and sd_cyl_signed_dist's first operations, in their
 * order). */
typedef struct {
    __m256d cx, cy, cz, bx, by, bz, ax, ay, az, rs, rc, hl, t, wx, wy, wz, rho2;
} sc_quad;

__attribute__((target("avx2"))) static inline void sc_quad_load(const sd_bodies *b, const int sa[4], const int lc[4],
                                                                sc_quad *s)
{
    const double *pos = &b->pos[0].x, *axis = &b->axis[0].x, *rad = b->radius, *hlen = b->hl;
    __m256d r[4];
    rows4(pos, sa, r);
    s->cx = r[0], s->cy = r[1], s->cz = r[2];
    rows4(pos, lc, r);
    s->bx = r[0], s->by = r[1], s->bz = r[2];
    rows4(axis, lc, r);
    s->ax = r[0], s->ay = r[1], s->az = r[2];
    s->rs = _mm256_setr_pd(rad[sa[0]], rad[sa[1]], rad[sa[2]], rad[sa[3]]);
    s->rc = _mm256_setr_pd(rad[lc[0]], rad[lc[1]], rad[lc[2]], rad[lc[3]]);
    s->hl = _mm256_setr_pd(hlen[lc[0]], hlen[lc[1]], hlen[lc[2]], hlen[lc[3]]);
    const __m256d dx = _mm256_sub_pd(s->cx, s->bx), dy = _mm256_sub_pd(s->cy, s->by), dz = _mm256_sub_pd(s->cz, s->bz);
    s->t = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, s->ax), _mm256_mul_pd(dy, s->ay)), _mm256_mul_pd(dz, s->az));
    const __m256d mt = _mm256_xor_pd(s->t, _mm256_set1_pd(-0.0));
    s->wx = _mm256_add_pd(dx, _mm256_mul_pd(mt, s->ax));
    s->wy = _mm256_add_pd(dy, _mm256_mul_pd(mt, s->ay));
    s->wz = _mm256_add_pd(dz, _mm256_mul_pd(mt, s->az));
    s->rho2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(s->wx, s->wx), _mm256_mul_pd(s->wy, s->wy)),
                            _mm256_mul_pd(s->wz, s->wz));
}

/* Where four sphere centres lie against their logs (sd_cyl_signed_dist's operations, in their
 * order): axd = |t| - hl (> 0 beyond the end plane), rho = |w|, rd = rho - r (> 0 outside the
 * side surface); the masks side, end face and rim (beyond both), known = any of the three (not
 * known: a centre inside the log, left to the scalar path), and sd the distance to the nearest
 * feature where known (0 elsewhere; the rim's sqrt only where a lane is there). */
typedef struct {
    __m256d axd, rho, rd, side, end, rim, known, sd;
} sc_case;

__attribute__((target("avx2"))) static inline void sc_case_of(const sc_quad *u, sc_case *k)
{
    const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0);
    k->axd = _mm256_sub_pd(_mm256_andnot_pd(sign, u->t), u->hl);
    k->rho = _mm256_sqrt_pd(u->rho2);
    k->rd = _mm256_sub_pd(k->rho, u->rc);
    const __m256d ax_in = _mm256_cmp_pd(k->axd, zero, _CMP_LE_OQ), ax_out = _mm256_cmp_pd(k->axd, zero, _CMP_GT_OQ);
    const __m256d rd_in = _mm256_cmp_pd(k->rd, zero, _CMP_LE_OQ), rd_out = _mm256_cmp_pd(k->rd, zero, _CMP_GT_OQ);
    k->side = _mm256_and_pd(ax_in, rd_out);
    k->end = _mm256_and_pd(rd_in, ax_out);
    k->rim = _mm256_and_pd(ax_out, rd_out);
    k->known = _mm256_or_pd(_mm256_or_pd(k->side, k->end), k->rim);
    __m256d sd = zero;
    if (_mm256_movemask_pd(k->rim))
        sd = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(k->rd, k->rd), _mm256_mul_pd(k->axd, k->axd)));
    k->sd = _mm256_blendv_pd(_mm256_blendv_pd(sd, k->axd, k->end), k->rd, k->side);
}

/* The bodies of the sphere-log pairs sg[0 .. nl) (chunk entries, 1 <= nl <= 4) into four
 * lanes, the last pair repeated past nl: from the chunk's view (the pair store's lines are not
 * read). */
static inline void sc_group(const soa_view *v, const int *sg, int nl, int sa[4], int lc[4])
{
    for (int l = 0; l < 4; l++) {
        const int i = sg[l < nl ? l : nl - 1];
        sa[l] = v->a[i], lc[l] = v->b[i];
    }
}

/* Step 2 of sd_bb_chunk for the sphere-log pairs sg[0 .. n) (chunk entries, one spring slot each,
 * whose apart test the touch filter may have left to this pass) in AVX2, 4 at a time (the last
 * 1-3 in a group padded with the last of them): first the apart test, then
 * sd_geom_sphere_cyl's contact on the log's side, an end face or an end rim, and sc_lane_fill,
 * with their operations in their order (same bits), lane by lane into q from msc on. A pair
 * whose centre is on the axis or inside the log, or that does not touch after all (near a
 * rim), goes through sd_manifold_general_pair as before. Returns the lanes filled. The scalar path spent
 * ~12 % of the settled packing's step here. */
__attribute__((target("avx2"))) int sd_avx2_sc_geom(const sd_world *w, const sd_law *law, const int32_t *ks,
                                                    const soa_view *v, const int *sg, int n, struct sc_lanes *q,
                                                    int msc, sd_pair_out *out, int *used)
{
    const sd_bodies *b = &w->b;
    const double *vel = &b->vel[0].x, *om = &b->omega[0].x;
    const sd_pair *pairs = w->bb.p;
    const sd_hist *hist = w->bb.hist;
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), mone = _mm256_set1_pd(-1.0),
                  sign = _mm256_set1_pd(-0.0), tiny = _mm256_set1_pd(1e-280), mhalf = _mm256_set1_pd(-0.5);
    /* 1. the touch filter's apart test (sd_sphere_cyl_apart, its operations), which
     * sd_avx2_ss_filter leaves to this pass, then sd_geom_sphere_cyl's own (sd >= r past the side,
     * an end face or a rim, as 2 computes it): either way the pair gets what filter_log_pair
     * gives it (no contact, its slot emptied); the others, in order, into sg2. (A pair the
     * scalar filter already found not apart is found so again.) A pass of its own, though 2
     * loads the same rows again (from L1): so that 2 meets touching pairs only and takes its
     * groups four lanes at a time. */
    int sg2[SS_CHUNK], n2 = 0;
    {
        for (int g = 0; g < n; g += 4) {
            /* the last group padded with its last pair (its extra lanes dropped) */
            const int nl = n - g < 4 ? n - g : 4;
            int sa[4], lc[4];
            sc_group(v, sg + g, nl, sa, lc);
            sc_quad u;
            sc_quad_load(b, sa, lc, &u);
            const __m256d rr = _mm256_add_pd(u.rc, u.rs);
            sc_case k;
            sc_case_of(&u, &k);
            const __m256d apart = _mm256_or_pd(_mm256_cmp_pd(k.axd, u.rs, _CMP_GE_OQ),
                                               _mm256_cmp_pd(u.rho2, _mm256_mul_pd(rr, rr), _CMP_GE_OQ));
            const __m256d miss = _mm256_and_pd(_mm256_and_pd(k.known, _mm256_cmp_pd(k.sd, u.rs, _CMP_GE_OQ)),
                                               _mm256_cmp_pd(u.rho2, tiny, _CMP_GT_OQ));
            const int drop = _mm256_movemask_pd(_mm256_or_pd(apart, miss));
            for (int l = 0; l < nl; l++) {
                const int i = sg[g + l];
                if (drop >> l & 1) {
                    used[i] = 0;
                    w->bb.hist[v->off[i]].feature = -1; /* (one slot) */
                } else
                    sg2[n2++] = i;
            }
        }
    }
    sg = sg2;
    n = n2;
    /* 2. the contacts */
    for (int g = 0; g < n; g += 4) {
        const int nl = n - g < 4 ? n - g : 4; /* (the last group padded, as in 1) */
        int sa[4], lc[4];
        sc_group(v, sg + g, nl, sa, lc);
        sc_quad u;
        sc_quad_load(b, sa, lc, &u);
        const __m256d cx = u.cx, cy = u.cy, cz = u.cz, bx = u.bx, by = u.by, bz = u.bz, ax = u.ax, ay = u.ay, az = u.az,
                      rs = u.rs, t = u.t, wx = u.wx, wy = u.wy, wz = u.wz, rho2 = u.rho2;
        sc_case k;
        sc_case_of(&u, &k);
        const __m256d e = _mm256_blendv_pd(mone, one, _mm256_cmp_pd(t, zero, _CMP_GE_OQ));
        const __m256d axd = k.axd, rd = k.rd, side = k.side, end = k.end, rim = k.rim;
        const __m256d inv = _mm256_div_pd(one, k.rho);
        const __m256d radx = _mm256_mul_pd(wx, inv), rady = _mm256_mul_pd(wy, inv), radz = _mm256_mul_pd(wz, inv);
        /* beyond the rim: radial (rd / dist) + a (e ax / dist); only where a lane is there (a
         * sphere on a log's side or end face: nearly all) */
        __m256d nx = zero, ny = zero, nz = zero;
        if (_mm256_movemask_pd(rim)) {
            const __m256d dist = k.sd; /* (the rim's distance in its lanes) */
            const __m256d k1 = _mm256_div_pd(rd, dist), k2 = _mm256_div_pd(_mm256_mul_pd(e, axd), dist);
            nx = _mm256_add_pd(_mm256_mul_pd(radx, k1), _mm256_mul_pd(ax, k2));
            ny = _mm256_add_pd(_mm256_mul_pd(rady, k1), _mm256_mul_pd(ay, k2));
            nz = _mm256_add_pd(_mm256_mul_pd(radz, k1), _mm256_mul_pd(az, k2));
        }
        const __m256d eax = _mm256_mul_pd(ax, e), eay = _mm256_mul_pd(ay, e), eaz = _mm256_mul_pd(az, e);
        nx = _mm256_blendv_pd(_mm256_blendv_pd(nx, eax, end), radx, side);
        ny = _mm256_blendv_pd(_mm256_blendv_pd(ny, eay, end), rady, side);
        nz = _mm256_blendv_pd(_mm256_blendv_pd(nz, eaz, end), radz, side);
        const __m256d sd = k.sd;
        /* the lanes done here: a contact (sd < r) on the side, an end face or a rim, off the
         * axis; the padded lanes of the last group repeat its last pair, so a group of whole
         * lanes is ok == 15 */
        const int ok = _mm256_movemask_pd(_mm256_and_pd(_mm256_and_pd(k.known, _mm256_cmp_pd(rho2, tiny, _CMP_GT_OQ)),
                                                        _mm256_cmp_pd(sd, rs, _CMP_LT_OQ)));
        /* sd_geom_sphere_cyl: overlap, the surface point c + (-sd) n, the point + (-0.5 ov) n */
        const __m256d ov = _mm256_sub_pd(rs, sd), msd = _mm256_xor_pd(sd, sign), mh = _mm256_mul_pd(mhalf, ov);
        const __m256d ptx = _mm256_add_pd(_mm256_add_pd(cx, _mm256_mul_pd(msd, nx)), _mm256_mul_pd(mh, nx)),
                      pty = _mm256_add_pd(_mm256_add_pd(cy, _mm256_mul_pd(msd, ny)), _mm256_mul_pd(mh, ny)),
                      ptz = _mm256_add_pd(_mm256_add_pd(cz, _mm256_mul_pd(msd, nz)), _mm256_mul_pd(mh, nz));
        const int sidem = _mm256_movemask_pd(side), endm = _mm256_movemask_pd(end),
                  negm = _mm256_movemask_pd(_mm256_cmp_pd(e, zero, _CMP_LT_OQ));
        if (ok == 15) { /* (nearly always) four lanes at once, nl of them kept */
            const int j = msc;
            _mm256_storeu_pd(q->nx + j, nx), _mm256_storeu_pd(q->ny + j, ny), _mm256_storeu_pd(q->nz + j, nz);
            _mm256_storeu_pd(q->ov + j, ov);
            _mm256_storeu_pd(q->px + j, ptx), _mm256_storeu_pd(q->py + j, pty), _mm256_storeu_pd(q->pz + j, ptz);
            _mm256_storeu_pd(q->rax + j, _mm256_sub_pd(ptx, cx)), _mm256_storeu_pd(q->ray + j, _mm256_sub_pd(pty, cy));
            _mm256_storeu_pd(q->raz + j, _mm256_sub_pd(ptz, cz));
            _mm256_storeu_pd(q->rbx + j, _mm256_sub_pd(ptx, bx)), _mm256_storeu_pd(q->rby + j, _mm256_sub_pd(pty, by));
            _mm256_storeu_pd(q->rbz + j, _mm256_sub_pd(ptz, bz));
            rows4_store(vel, sa, q->vax, q->vay, q->vaz, j);
            rows4_store(om, sa, q->wax, q->way, q->waz, j);
            rows4_store(vel, lc, q->vbx, q->vby, q->vbz, j);
            rows4_store(om, lc, q->wbx, q->wby, q->wbz, j);
            for (int l = 0; l < nl; l++) {
                const int f = sidem >> l & 1 ? 0 : (negm >> l & 1 ? 1 : 2) + (endm >> l & 1 ? 0 : 2);
                const sd_hist *h = &hist[v->off[sg[g + l]]];
                const int same = h->feature == f;
                q->sqm[j + l] = v->sqm[sg[g + l]];
                q->sx[j + l] = same ? h->shear.x : 0.0, q->sy[j + l] = same ? h->shear.y : 0.0;
                q->sz[j + l] = same ? h->shear.z : 0.0;
                q->feature[j + l] = f;
                q->i[j + l] = sg[g + l];
            }
            msc += nl;
            q->n_geom += nl;
            continue;
        }
        double L[13][4];
        _mm256_storeu_pd(L[0], nx), _mm256_storeu_pd(L[1], ny), _mm256_storeu_pd(L[2], nz);
        _mm256_storeu_pd(L[3], ov);
        _mm256_storeu_pd(L[4], ptx), _mm256_storeu_pd(L[5], pty), _mm256_storeu_pd(L[6], ptz);
        _mm256_storeu_pd(L[7], _mm256_sub_pd(ptx, cx)), _mm256_storeu_pd(L[8], _mm256_sub_pd(pty, cy));
        _mm256_storeu_pd(L[9], _mm256_sub_pd(ptz, cz));
        _mm256_storeu_pd(L[10], _mm256_sub_pd(ptx, bx)), _mm256_storeu_pd(L[11], _mm256_sub_pd(pty, by));
        _mm256_storeu_pd(L[12], _mm256_sub_pd(ptz, bz));
        for (int l = 0; l < nl; l++) {
            const int i = sg[g + l];
            if (!(ok >> l & 1)) {
                msc += sd_manifold_general_pair(w, law, &pairs[ks[i]], i, q, msc, out, used);
                continue;
            }
            /* sc_lane_fill */
            const int j = msc++;
            q->n_geom++;
            const int a = sa[l], c = lc[l];
            /* feature: 0 side, 1 / 2 end face at -hl / +hl, 3 / 4 rim there */
            const int f = sidem >> l & 1 ? 0 : (negm >> l & 1 ? 1 : 2) + (endm >> l & 1 ? 0 : 2);
            q->nx[j] = L[0][l], q->ny[j] = L[1][l], q->nz[j] = L[2][l], q->ov[j] = L[3][l];
            q->px[j] = L[4][l], q->py[j] = L[5][l], q->pz[j] = L[6][l];
            q->rax[j] = L[7][l], q->ray[j] = L[8][l], q->raz[j] = L[9][l];
            q->rbx[j] = L[10][l], q->rby[j] = L[11][l], q->rbz[j] = L[12][l];
            q->vax[j] = vel[3 * a], q->vay[j] = vel[3 * a + 1], q->vaz[j] = vel[3 * a + 2];
            q->wax[j] = om[3 * a], q->way[j] = om[3 * a + 1], q->waz[j] = om[3 * a + 2];
            q->vbx[j] = vel[3 * c], q->vby[j] = vel[3 * c + 1], q->vbz[j] = vel[3 * c + 2];
            q->wbx[j] = om[3 * c], q->wby[j] = om[3 * c + 1], q->wbz[j] = om[3 * c + 2];
            q->sqm[j] = v->sqm[i];
            const sd_hist *h = &hist[v->off[i]];
            const int same = h->feature == f;
            q->sx[j] = same ? h->shear.x : 0.0, q->sy[j] = same ? h->shear.y : 0.0, q->sz[j] = same ? h->shear.z : 0.0;
            q->feature[j] = f;
            q->i[j] = i;
        }
    }
    return msc;
}

/* the table's forms (contact_internal.h sd_contact_kernels): the filter takes no ks */
static int ss_filter2(const sd_world *w, const int32_t *ks, const soa_view *v, int i, int n, int *used, ss_batch *q,
                      int *mp, int *gen, int *ngp)
{
    (void)ks;
    return sd_avx2_ss_filter(w, v, i, n, used, q, mp, gen, ngp);
}

const sd_contact_kernels sd_avx2_kernels = {
    .ss_filter = ss_filter2,
    .ss_gather = sd_avx2_ss_gather,
    .ss_law_spring = sd_avx2_ss_law_spring,
    .ss_sums = sd_avx2_ss_sums,
    .sc_geom = sd_avx2_sc_geom,
    .near_test = sd_avx2_near_test,
};
#else
typedef int sd_contact_simd_avx2_none; /* (ISO C: a translation unit declares something) */
#endif
