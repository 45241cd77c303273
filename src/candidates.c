/* The candidate scan (SPEC §4): each body's body-body candidates (j > i, taken in the lowest
 * cell the two ranges share) and body-triangle candidates, found on the grids by chunks of
 * bodies in parallel and joined in body order (the same lists, entry for entry, as one
 * thread); the moving index of the fixed bodies' scans; the float prefilter and the SIMD cell
 * scans (each the scalar scan's candidates in its order). */
#include <stdlib.h>
#include <string.h>
#include <threads.h>

#include "neighbor_internal.h"

static const int hist_cap_of_kind[SD_PAIR_KINDS] = {1, 1, SD_MANIFOLD_MAX, 1, SD_MANIFOLD_MAX};

typedef struct {
    int32_t a, b;
    int kind;
} cand;
/* One chunk's candidates. Padded to a cache line: the scan's threads fill neighbouring
 * chunks' buffers at once, and with four to a line each push of one thread (n, cap) waited
 * for the line the other had just written: a tenth of the scan's samples. */
typedef struct {
    cand *c;
    int n, cap;
    char pad[64 - sizeof(cand *) - 2 * sizeof(int)];
} cand_buf;

/* The scan's m chunk buffers, emptied, their arrays as large as they grew before (w->scan_bufs,
 * one to a cache line); NULL when out of memory. */
static cand_buf *scan_bufs(sd_world *w, int m)
{
    if (w->scan_bufs_n < m) {
        sd_cand_bufs_free(w);
        w->scan_bufs = aligned_alloc(64, (size_t)m * sizeof(cand_buf));
        if (!w->scan_bufs) return NULL;
        memset(w->scan_bufs, 0, (size_t)m * sizeof(cand_buf));
        w->scan_bufs_n = m;
    }
    cand_buf *buf = w->scan_bufs;
    for (int c = 0; c < m; c++)
        buf[c].n = 0;
    return buf;
}

void sd_cand_bufs_free(sd_world *w)
{
    cand_buf *buf = w->scan_bufs;
    for (int c = 0; c < w->scan_bufs_n; c++)
        free(buf[c].c);
    free(buf);
    w->scan_bufs = NULL;
    w->scan_bufs_n = 0;
}

/* The moving bodies of each cell of the body grid, ascending like the grid's own lists: all
 * that the scan of a fixed body needs (fixed-fixed pairs are never candidates). The bed
 * roughness is half the paper's elements and fills its cells: its scans get short. */
typedef struct {
    int32_t *start, *items;
    uint8_t *flags; /* the entries' gflag */
} moving_index;

static int moving_index_make(const sd_world *w, moving_index *mi)
{
    const sd_grid *g = &w->grid;
    const int ncell = g->nx * g->ny * g->nz;
    const int total = g->cell_start[ncell];
    mi->start = malloc((size_t)(ncell + 1) * sizeof(int32_t));
    mi->items = malloc((size_t)(total + 1) * sizeof(int32_t));
    mi->flags = malloc((size_t)(total + 1));
    if (!mi->start || !mi->items || !mi->flags) return 1;
    int m = 0;
    for (int c = 0; c < ncell; c++) {
        mi->start[c] = m;
        for (int k = g->cell_start[c]; k < g->cell_start[c + 1]; k++)
            if (!w->b.fixed[g->items[k]]) {
                mi->flags[m] = w->gflag[k];
                mi->items[m++] = g->items[k];
            }
    }
    mi->start[ncell] = m;
    return 0;
}

/* Body i's box: as the rebuild's range loop stored it (the bodies before the bed), else made
 * here (a bed sphere: c ± (r + hm), no square root) */
static inline void box_of(const sd_world *w, int i, double hm, sd_vec3 *lo, sd_vec3 *hi)
{
    if (i < w->box_n) {
        *lo = w->box[2 * i];
        *hi = w->box[2 * i + 1];
    } else {
        body_box(&w->b, i, hm, lo, hi);
    }
}

/* Body j found by body i's scan, within reach and in the lowest cell their ranges share: the
 * exact box and capsule tests where a log is involved, then the candidate, ordered by (shape,
 * gid). Returns nonzero when out of memory. */
static inline int take_pair(const sd_world *w, int i, int j, double hm, cand_buf *out)
{
    const sd_bodies *b = &w->b;
    const int spheres = b->shape[i] == SD_SHAPE_SPHERE && b->shape[j] == SD_SHAPE_SPHERE;
    if (!spheres) {
        /* (two spheres within reach have overlapping boxes: the distance test is the box test
         * and more) */
        sd_vec3 li, hi_, lj, hj;
        box_of(w, i, hm, &li, &hi_);
        box_of(w, j, hm, &lj, &hj);
        if (li.x > hj.x || lj.x > hi_.x || li.y > hj.y || lj.y > hi_.y || li.z > hj.z || lj.z > hi_.z) return 0;
        /* capsule test: a cylinder lies within radius r of its axis segment */
        if (sd_axis_gap(b, i, j) > b->radius[i] + b->radius[j] + w->def.margin) return 0;
    }
    int a = i, bb = j;
    if (b->shape[a] > b->shape[bb] || (b->shape[a] == b->shape[bb] && b->gid[a] > b->gid[bb])) {
        a = j;
        bb = i;
    }
    int kind =
        b->shape[a] == SD_SHAPE_SPHERE ? (b->shape[bb] == SD_SHAPE_SPHERE ? SD_PAIR_SS : SD_PAIR_SC) : SD_PAIR_CC;
    if (sd_grow((void **)&out->c, &out->cap, out->n + 1, sizeof(cand))) return 1;
    out->c[out->n++] = (cand){a, bb, kind};
    return 0;
}

#ifdef SD_SCAN512
#define SD_SCAN_BUF 64
/* The entries items[k0 .. k1) (k1 - k0 <= SD_SCAN_BUF) of cell (x, y, z) that moving body i
 * (centre pi, bounding radius bri, cell range ri) takes up, in entry order, into js; returns
 * how many. The scalar loop's two tests (within reach, then this cell the lowest the two ranges
 * share) in AVX-512, 8 entries at a time, with its operations: the same candidates in the same
 * order. */
__attribute__((target("avx512f,avx512vl"))) static int scan_cell512(const sd_world *w, const int32_t *items, int k0,
                                                                    int k1, sd_vec3 pi, double bri, const int32_t *ri,
                                                                    int x, int y, int z, int32_t *js)
{
    const double *pos = &w->b.pos[0].x, *br = w->b.bound_r;
    const int *rng = &w->range[0][0];
    const __m512d px = _mm512_set1_pd(pi.x), py = _mm512_set1_pd(pi.y), pz = _mm512_set1_pd(pi.z),
                  b0 = _mm512_set1_pd(bri), mg = _mm512_set1_pd(w->def.margin), zero = _mm512_setzero_pd();
    const __m256i cx = _mm256_set1_epi32(x), cy = _mm256_set1_epi32(y), cz = _mm256_set1_epi32(z),
                  r0 = _mm256_set1_epi32(ri[0]), r1 = _mm256_set1_epi32(ri[1]), r2 = _mm256_set1_epi32(ri[2]);
    int n = 0;
    for (int k = k0; k < k1; k += 8) {
        const __mmask8 live = (__mmask8)(k1 - k >= 8 ? 0xFF : (1u << (k1 - k)) - 1u);
        const __m256i j = _mm256_maskz_loadu_epi32(live, items + k);
        const __m256i j3 = _mm256_add_epi32(j, _mm256_add_epi32(j, j));
        const __m512d dx = _mm512_sub_pd(px, _mm512_mask_i32gather_pd(zero, live, j3, pos, 8));
        const __m512d dy = _mm512_sub_pd(py, _mm512_mask_i32gather_pd(zero, live, j3, pos + 1, 8));
        const __m512d dz = _mm512_sub_pd(pz, _mm512_mask_i32gather_pd(zero, live, j3, pos + 2, 8));
        /* reach = bri + r_j + margin; out of reach when |pi - pj|^2 > reach^2 (v3_norm2's order) */
        const __m512d reach = _mm512_add_pd(_mm512_add_pd(b0, _mm512_mask_i32gather_pd(zero, live, j, br, 8)), mg);
        const __m512d d2 =
            _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
        const __mmask8 in = (__mmask8)(live & _mm512_cmp_pd_mask(d2, _mm512_mul_pd(reach, reach), _CMP_NGT_UQ));
        if (!in) continue;
        /* the pair is taken in the lowest cell the two ranges share (6 ints a body) */
        const __m256i j6 = _mm256_add_epi32(j3, j3);
        const __m256i q0 = _mm256_mmask_i32gather_epi32(cx, in, j6, rng, 4);
        const __m256i q1 = _mm256_mmask_i32gather_epi32(cy, in, j6, rng + 1, 4);
        const __m256i q2 = _mm256_mmask_i32gather_epi32(cz, in, j6, rng + 2, 4);
        const __mmask8 low = (__mmask8)(_mm256_mask_cmpeq_epi32_mask(in, cx, _mm256_max_epi32(r0, q0)) &
                                        _mm256_cmpeq_epi32_mask(cy, _mm256_max_epi32(r1, q1)) &
                                        _mm256_cmpeq_epi32_mask(cz, _mm256_max_epi32(r2, q2)));
        _mm256_storeu_si256((__m256i *)(js + n), _mm256_maskz_compress_epi32(low, j));
        n += __builtin_popcount(low);
    }
    return n;
}
#endif

#define SD_SCAN_JS 512 /* bb_scan's entries gathered before the reach test (at least 64 more than it flushes at) */

/* The body grid's entries' centres and bounding radii as floats (w->gq), after the grid is
 * filled: the scan's prefilter reads them in entry order, 8 at a time, where the exact test
 * (within_reach) would gather each entry's row. Their rounding is bounded: a coordinate within
 * M of the origin is off by at most M 2^-24 as a float, so a distance by about 3.5e-7 M, and a
 * reach passed to the prefilter grows by gq_slack = 4e-6 M + 4e-6 of itself, ten times that:
 * no pair the exact test takes is left out, and the exact test still decides (the same
 * candidates in the same order). */
#ifdef SD_SCAN512
sd_status sd_cand_grid_coords(sd_world *w)
{
    const sd_grid *g = &w->grid;
    const int all = g->cell_start[g->nx * g->ny * g->nz];
    const int stride = (all + SD_GRID_PAD + 7) & ~7;
    if (sd_grow((void **)&w->gq, &w->gq_cap, 4 * stride, sizeof(float))) return SD_ERR_NOMEM;
    w->gq_stride = stride;
    float *restrict x = w->gq, *restrict y = x + stride, *restrict z = y + stride, *restrict r = z + stride;
    const int32_t *restrict it = g->items;
    const sd_vec3 *restrict pos = w->b.pos;
    const double *restrict br = w->b.bound_r;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) if (all > w->def.parallel_min)
    for (int a = 0; a < all; a++) {
        const int j = it[a];
        x[a] = (float)pos[j].x, y[a] = (float)pos[j].y, z[a] = (float)pos[j].z, r[a] = (float)br[j];
    }
    for (int a = all; a < stride; a++)
        x[a] = y[a] = z[a] = r[a] = 0.0f;
    memset(g->items + all, 0, SD_GRID_PAD * sizeof(int32_t));
    memset(w->gflag + all, 0, SD_GRID_PAD);
    double m = 0.0;
    const double lo[3] = {g->lo.x, g->lo.y, g->lo.z}, n[3] = {g->nx, g->ny, g->nz};
    for (int d = 0; d < 3; d++) {
        const double a = fabs(lo[d]), b = fabs(lo[d] + n[d] * g->cell);
        m = a > m ? a : m;
        m = b > m ? b : m;
    }
    w->gq_slack = (float)(4e-6 * m);
    return SD_OK;
}

/* compress_lut[m]: byte l is the lane of the l-th set bit of m (8 lanes), for a permute that
 * packs the set lanes first; made once, by the first rebuild (call_once). A 16-entry table for each half, combined at
 * each use, ran no faster (the scan's median 1.79 against 1.72 ms, six alternations). */
static uint64_t compress_lut[256];

static once_flag compress_lut_once = ONCE_FLAG_INIT;

static void compress_lut_make(void)
{
    for (int m = 0; m < 256; m++) {
        uint64_t v = 0;
        int n = 0;
        for (int l = 0; l < 8; l++)
            if (m >> l & 1) v |= (uint64_t)l << (8 * n++);
        compress_lut[m] = v;
    }
}

/* bb_scan's flag loop for entries k .. k1 - 1 of one cell (k1 - k <= 64) with the prefilter: the
 * entries whose flags say the pair is taken in this cell and whose float centre lies within
 * the float reach (pc: the body's centre, and its bounding radius plus the margin; gq_slack
 * added) go into js in entry order; returns how many (js has room for 8 more). */
__attribute__((target("avx2"))) static int scan_cell256(const sd_world *w, int k, int k1, unsigned need,
                                                        const float pc[4], int32_t *restrict js)
{
    const int32_t *items = w->grid.items;
    const uint8_t *fl = w->gflag;
    const int st = w->gq_stride;
    const float *gx = w->gq, *gy = gx + st, *gz = gy + st, *gr = gz + st;
    const __m256 px = _mm256_set1_ps(pc[0]), py = _mm256_set1_ps(pc[1]), pz = _mm256_set1_ps(pc[2]),
                 rb = _mm256_set1_ps(pc[3] + w->gq_slack), grow = _mm256_set1_ps(1.0f + 4e-6f);
    const __m256i nd = _mm256_set1_epi32((int)need);
    int n = 0;
    for (; k < k1; k += 8) {
        const int left = k1 - k;
        const unsigned live = left >= 8 ? 0xFFu : (1u << left) - 1u;
        uint64_t fw;
        memcpy(&fw, fl + k, sizeof fw);
        const __m256i f = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128((long long)fw));
        const __m256i fm = _mm256_cmpeq_epi32(_mm256_and_si256(f, nd), nd);
        const __m256 dx = _mm256_sub_ps(px, _mm256_loadu_ps(gx + k)), dy = _mm256_sub_ps(py, _mm256_loadu_ps(gy + k)),
                     dz = _mm256_sub_ps(pz, _mm256_loadu_ps(gz + k));
        const __m256 reach = _mm256_mul_ps(_mm256_add_ps(rb, _mm256_loadu_ps(gr + k)), grow);
        const __m256 d2 =
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
        const __m256 in = _mm256_cmp_ps(d2, _mm256_mul_ps(reach, reach), _CMP_NGT_UQ);
        const unsigned m = (unsigned)_mm256_movemask_ps(_mm256_and_ps(in, _mm256_castsi256_ps(fm))) & live;
        const __m256i idx = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128((long long)compress_lut[m]));
        const __m256i it = _mm256_loadu_si256((const __m256i *)(items + k));
        _mm256_storeu_si256((__m256i *)(js + n), _mm256_permutevar8x32_epi32(it, idx));
        n += __builtin_popcount(m);
    }
    return n;
}
#endif

/* Body j within reach of a body at pi with bounding radius bri: |pi - pj| <= bri + r_j + margin. */
static inline int within_reach(const sd_bodies *b, sd_vec3 pi, double bri, double margin, int j)
{
    const double reach = bri + b->bound_r[j] + margin;
    return !(v3_norm2(v3_sub(pi, b->pos[j])) > reach * reach);
}

/* The entries js[0 .. nj) gathered by body i's scan: those within reach, and not two fixed
 * bodies, taken in order (js is overwritten). Returns nonzero when out of memory. */
static int scan_take(const sd_world *w, int i, double hm, int32_t *js, int nj, cand_buf *out)
{
    const sd_bodies *b = &w->b;
    const double bri = b->bound_r[i], margin = w->def.margin;
    const sd_vec3 pi = b->pos[i];
    const int fixed_i = b->fixed[i];
    int nt = 0;
    if (!fixed_i) /* (a moving body's partners are not looked up for being fixed: a line each) */
        for (int q = 0; q < nj; q++) {
            const int j = js[q];
            js[nt] = j;
            nt += within_reach(b, pi, bri, margin, j);
        }
    else
        for (int q = 0; q < nj; q++) {
            const int j = js[q];
            js[nt] = j;
            nt += within_reach(b, pi, bri, margin, j) & !b->fixed[j];
        }
    for (int q = 0; q < nt; q++)
        if (take_pair(w, i, js[q], hm, out)) return 1;
    return 0;
}

/* The body–body candidates (j > i) of body i, in the order of the serial scan. Returns
 * nonzero when out of memory. */
static int bb_scan(const sd_world *w, int i, double hm, const moving_index *mi, cand_buf *out)
{
    const sd_bodies *b = &w->b;
    const sd_grid *g = &w->grid;
    const int32_t *ri = w->range[i];
    const int fixed_i = b->fixed[i], use_mi = fixed_i && mi->start;
#ifdef SD_SCAN512
    /* a moving body's entries 8 at a time where the CPU has AVX-512 (an AVX2 form, 4 at a
     * time, was measured and dropped: performance pass P11, in the git history) */
    const int vec = !fixed_i && w->simd >= SD_SIMD_AVX512;
    const double bri = b->bound_r[i];
    const sd_vec3 pi = b->pos[i];
    /* a moving body's entries through the float prefilter where the CPU has AVX2 */
    const int pre = !fixed_i && !vec && w->sw[SD_SW_SCAN_PRE] && w->gq_stride > 0 && w->simd >= SD_SIMD_AVX2;
    const float pc[4] = {(float)pi.x, (float)pi.y, (float)pi.z, (float)(bri + w->def.margin)};
#endif
    int e = w->reg0[i]; /* i's entries, in the order of the loops below (grid_fill) */
    int32_t js[SD_SCAN_JS + 8];
    int nj = 0;
    for (int z = ri[2]; z <= ri[5]; z++)
        for (int y = ri[1]; y <= ri[4]; y++)
            for (int x = ri[0]; x <= ri[3]; x++) {
                int c = (z * g->ny + y) * g->nx + x;
                /* a cell lists its bodies in ascending order: start past i (a fixed body
                 * looks at the moving ones only, the same j in the same order) */
                const int32_t *items = use_mi ? mi->items : g->items;
                int k;
                const int kend = use_mi ? mi->start[c + 1] : g->cell_start[c + 1];
                if (use_mi) {
                    k = mi->start[c];
                    for (int hi = kend; k < hi;) {
                        int mid = (k + hi) >> 1;
                        if (items[mid] <= i)
                            k = mid + 1;
                        else
                            hi = mid;
                    }
                } else {
                    k = w->slot[e++] + 1; /* just past i's own entry in this cell */
                }
#ifdef SD_SCAN512
                if (vec) {
                    int32_t j8[SD_SCAN_BUF + 8];
                    for (int k0 = k; k0 < kend; k0 += SD_SCAN_BUF) {
                        const int k1 = kend - k0 < SD_SCAN_BUF ? kend : k0 + SD_SCAN_BUF;
                        const int n8 = scan_cell512(w, items, k0, k1, pi, bri, ri, x, y, z, j8);
                        for (int q = 0; q < n8; q++)
                            if (take_pair(w, i, j8[q], hm, out)) return 1;
                    }
                    continue;
                }
#endif
                /* the entries whose pair is taken in this cell first, from the flags alone
                 * (a byte each, in entry order): along each axis where this cell is past the
                 * start of i's range, j's must start here (this is then the lowest cell the
                 * two ranges share). About half the entries are left, gathered over all of
                 * i's cells before the next two tests run on them (one loop each per body
                 * instead of per cell: their exits were mispredicted); then within reach and
                 * not two fixed bodies; then the takers, in entry order: the same candidates
                 * in the same order. With the prefilter, the entries it finds out of reach
                 * are left out too (5.85 a body reach the exact test instead of 32) */
                const unsigned need = (unsigned)((x > ri[0]) | (y > ri[1]) << 1 | (z > ri[2]) << 2);
                const uint8_t *fl = use_mi ? mi->flags : w->gflag;
                while (k < kend) {
                    if (nj > SD_SCAN_JS - 64) {
                        if (scan_take(w, i, hm, js, nj, out)) return 1;
                        nj = 0;
                    }
                    const int k1 = kend - k < 64 ? kend : k + 64;
#ifdef SD_SCAN512
                    if (pre) {
                        nj += scan_cell256(w, k, k1, need, pc, js + nj);
                        k = k1;
                        continue;
                    }
#endif
                    for (; k < k1; k++) {
                        js[nj] = items[k];
                        nj += (fl[k] & need) == need;
                    }
                }
            }
    return nj && scan_take(w, i, hm, js, nj, out);
}

/* The body–triangle candidates of body i, in triangle-grid order. Returns nonzero when out
 * of memory. */
static int bt_scan(const sd_world *w, int i, double hm, cand_buf *out)
{
    const sd_bodies *b = &w->b;
    const sd_grid *tg = &w->tgrid;
    if (b->fixed[i] || w->w.n == 0) return 0;
    sd_vec3 l, h;
    box_of(w, i, hm, &l, &h);
    const sd_vec3 tlo = tg->lo;
    const sd_vec3 thi = v3_add(tg->lo, v3(tg->nx * tg->cell, tg->ny * tg->cell, tg->nz * tg->cell));
    if (h.x < tlo.x || h.y < tlo.y || h.z < tlo.z || l.x > thi.x || l.y > thi.y || l.z > thi.z) return 0;
    int32_t ri[6];
    cell_range(tg, l, h, ri, w->simd);
    for (int z = ri[2]; z <= ri[5]; z++)
        for (int y = ri[1]; y <= ri[4]; y++)
            for (int x = ri[0]; x <= ri[3]; x++) {
                const int c = (z * tg->ny + y) * tg->nx + x;
                /* the pair is taken in the lowest cell the two ranges share: along each axis
                 * where this cell is past the start of i's range, the triangle's must start
                 * here (its flag byte); the cell is in both ranges */
                const unsigned need = (unsigned)((x > ri[0]) | (y > ri[1]) << 1 | (z > ri[2]) << 2);
                for (int k = tg->cell_start[c]; k < tg->cell_start[c + 1]; k++) {
                    if ((w->tflag[k] & need) != need) continue;
                    const int t = tg->items[k];
                    const sd_tri *tr = &w->w.tri[t];
                    const double s = v3_dot(v3_sub(b->pos[i], tr->v[0]), tr->n);
                    if (fabs(s) > b->bound_r[i] + w->def.margin) continue;
                    int q;
                    const sd_vec3 cp = sd_geom_closest_on_tri(tr, b->pos[i], &q);
                    const double reach = b->bound_r[i] + w->def.margin;
                    if (v3_norm2(v3_sub(cp, b->pos[i])) > reach * reach) continue;
                    if (sd_grow((void **)&out->c, &out->cap, out->n + 1, sizeof(cand))) return 1;
                    out->c[out->n++] = (cand){i, t, b->shape[i] == SD_SHAPE_SPHERE ? SD_PAIR_ST : SD_PAIR_CT};
                }
            }
    return 0;
}

static sd_status push_pair(sd_pairlist *l, int32_t a, int32_t b, int kind)
{
    if (sd_grow((void **)&l->p, &l->cap, l->n + 1, sizeof(sd_pair))) return SD_ERR_NOMEM;
    sd_pair *p = &l->p[l->n++];
    p->a = a;
    p->b = b;
    p->kind = (int16_t)kind;
    p->cap = (int16_t)hist_cap_of_kind[kind];
    p->off = l->nh;
    p->sqrt_m_eff = 0.0;
    l->nh += p->cap;
    return SD_OK;
}

/* The chunks' body-body candidates, in chunk order, into w->bb (emptied by the caller): what
 * push_pair in that order makes (the same pairs, slots and offsets), each chunk written by
 * one of T threads at its place. */
static sd_status join_chunks(sd_world *w, const cand_buf *buf, int K, int T)
{
    sd_pairlist *l = &w->bb;
    int32_t *at = malloc(2 * ((size_t)K + 1) * sizeof(int32_t));
    if (!at) return SD_ERR_NOMEM;
    int32_t *hat = at + K + 1;
    (void)T; /* (read by the pragmas only) */
    /* each chunk's slots (its pairs' caps summed) */
#pragma omp parallel for schedule(static) num_threads(T) if (T > 1)
    for (int c = 0; c < K; c++) {
        int h = 0;
        for (int k = 0; k < buf[c].n; k++)
            h += hist_cap_of_kind[buf[c].c[k].kind];
        hat[c + 1] = h;
    }
    at[0] = l->n;
    hat[0] = l->nh;
    for (int c = 0; c < K; c++) {
        at[c + 1] = at[c] + buf[c].n;
        hat[c + 1] += hat[c];
    }
    if (sd_grow((void **)&l->p, &l->cap, at[K] + 1, sizeof(sd_pair))) {
        free(at);
        return SD_ERR_NOMEM;
    }
#pragma omp parallel for schedule(static) num_threads(T) if (T > 1)
    for (int c = 0; c < K; c++) {
        int32_t off = hat[c];
        sd_pair *p = l->p + at[c];
        for (int k = 0; k < buf[c].n; k++, p++) {
            const cand *e = &buf[c].c[k];
            p->a = e->a;
            p->b = e->b;
            p->kind = (int16_t)e->kind;
            p->cap = (int16_t)hist_cap_of_kind[e->kind];
            p->off = off;
            p->sqrt_m_eff = 0.0;
            off += p->cap;
        }
    }
    l->n = at[K];
    l->nh = hat[K];
    free(at);
    return SD_OK;
}

/* The candidates, generated in body order: the bodies cut into K chunks of about the same
 * number of moving bodies, scanned by T threads as they come free, each chunk into its own
 * buffers (w->scan_bufs: K body-body, then K body-triangle), which sd_cand_join concatenates
 * in chunk order (the lists of one thread). */
sd_status sd_cand_scan(sd_world *w, double hm, int K, int T)
{
#ifdef SD_SCAN512
    call_once(&compress_lut_once, compress_lut_make);
#endif
    const sd_bodies *b = &w->b;
    (void)T; /* (read by the pragmas only) */
    /* past the last moving body, a fixed body has no candidates (j > i would be fixed) */
    int nscan = b->n, nfixed = 0;
    while (nscan > 0 && b->fixed[nscan - 1])
        nscan--;
    for (int i = 0; i < nscan; i++)
        nfixed += b->fixed[i];
    cand_buf *buf = scan_bufs(w, 2 * K); /* K body-body, K body-triangle */
    /* the moving bodies of each cell, for the fixed bodies' scans: worth making when there
     * are many (the bed, sorted last, has none to scan; the dam's pipes are a few) */
    moving_index mi = {NULL, NULL, NULL};
    if (!buf || (nfixed > w->sw[SD_SW_MOVING_INDEX_MIN] && moving_index_make(w, &mi))) {
        free(mi.start);
        free(mi.items);
        free(mi.flags);
        return SD_ERR_NOMEM;
    }
    const int nm = w->mov_n;
    int nomem = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(T) reduction(| : nomem) if (T > 1)
    for (int c = 0; c < K; c++) {
        const int i0 = c == 0 ? 0 : nm ? w->mov[(long)nm * c / K] : (int)((long)nscan * c / K);
        const int i1 = c + 1 == K ? nscan : nm ? w->mov[(long)nm * (c + 1) / K] : (int)((long)nscan * (c + 1) / K);
        for (int i = i0; i < i1 && !nomem; i++) {
            nomem |= bb_scan(w, i, hm, &mi, &buf[c]);
            nomem |= bt_scan(w, i, hm, &buf[K + c]);
        }
    }
    free(mi.start);
    free(mi.items);
    free(mi.flags);
    return nomem ? SD_ERR_NOMEM : SD_OK;
}

/* The K chunks' candidates of sd_cand_scan into the pair lists w->bb and w->bt (emptied by the
 * caller) and the wall pairs' index w->csr.bt_start (room for n + 1 made by the caller). */
sd_status sd_cand_join(sd_world *w, int K, int T)
{
    const cand_buf *buf = w->scan_bufs;
    sd_status st = join_chunks(w, buf, K, T);
    /* body–triangle pairs grouped by body, ascending (the mesh dedup in contact.c relies
     * on it) */
    int i = 0;
    for (int c = K; c < 2 * K; c++)
        for (int k = 0; k < buf[c].n && !st; k++) {
            const cand *e = &buf[c].c[k];
            while (i <= e->a)
                w->csr.bt_start[i++] = w->bt.n;
            st = push_pair(&w->bt, e->a, e->b, e->kind);
        }
    while (i <= w->b.n)
        w->csr.bt_start[i++] = w->bt.n;
    return st;
}
