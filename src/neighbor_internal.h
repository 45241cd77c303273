/* The candidate search's files among themselves: neighbor.c (the rebuild's orchestration, the
 * sort by cell, the moving list), grid.c (the cell grids), bed_cache.c (the bed's cache),
 * pair_history.c (the springs carried across a rebuild), candidates.c (the scan). The helpers
 * that several of them use in their hot loops are here, inline; the rest of the engine sees
 * world_internal.h only. */
#ifndef SD_NEIGHBOR_INTERNAL_H
#define SD_NEIGHBOR_INTERNAL_H

#include "world_internal.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#include <immintrin.h>
#define SD_SCAN512 1
#endif

/* room past a grid's last entry in its items and flags (and the body grid's gq): the scan's
 * prefilter reads 8 entries at a time, past a cell's end into the next cell or this pad */
#define SD_GRID_PAD 8

/* The threads for one of the rebuild's parallel parts over n items: all the process has (at most
 * SD_MAX_OWNERS), or one for a small part (start-up costs more). */
static inline int rebuild_threads(const sd_world *w, int n)
{
    int T = 1;
#ifdef _OPENMP
    T = w->nthreads;
    if (T > SD_MAX_OWNERS) T = SD_MAX_OWNERS;
    if (n <= w->def.parallel_min) T = 1;
#else
    (void)w, (void)n;
#endif
    return T;
}

/* fmax(0.0, t) without the library call (gcc calls libm's on x86-64, for its NaN rules): the
 * same values, NaN included, up to the sign of a zero (sd_clamp01 likewise) */
static inline double max0(double t) { return t > 0.0 ? t : 0.0; }

static inline void body_box(const sd_bodies *b, int i, double half_margin, sd_vec3 *lo, sd_vec3 *hi)
{
    sd_vec3 c = b->pos[i];
    double r = b->radius[i];
    sd_vec3 e;
    if (b->shape[i] == SD_SHAPE_SPHERE) {
        e = v3(r, r, r);
    } else {
        /* exact box of a cylinder: hl|a_k| + r sqrt(1 - a_k^2) per axis */
        sd_vec3 a = b->axis[i];
        double hl = b->hl[i];
        e = v3(hl * fabs(a.x) + r * sqrt(max0(1.0 - a.x * a.x)), hl * fabs(a.y) + r * sqrt(max0(1.0 - a.y * a.y)),
               hl * fabs(a.z) + r * sqrt(max0(1.0 - a.z * a.z)));
    }
    e = v3_add(e, v3(half_margin, half_margin, half_margin));
    *lo = v3_sub(c, e);
    *hi = v3_add(c, e);
}

/* A floored cell coordinate clamped to [0, hi] as a double before the conversion (as the AVX2
 * cell_range256): NaN gives 0, and no value outside long's range reaches the cast (undefined
 * behaviour; a checkpoint read with a body at 1e300 m/s moved it there in one step). */
static inline int clamp_cell(double v, int hi) { return v >= 0.0 ? (v <= (double)hi ? (int)v : hi) : 0; }

#ifdef SD_SCAN512
/* cell_range's six divisions and floors in two AVX2 operations (each lane correctly rounded, as
 * the scalar ones), clamped as doubles before the conversion: the same ranges (a NaN gives 0,
 * like the scalar conversion here). */
__attribute__((target("avx2"))) static inline void cell_range256(const sd_grid *g, sd_vec3 lo, sd_vec3 hi, int32_t r[6])
{
    const __m256d o = _mm256_setr_pd(g->lo.x, g->lo.y, g->lo.z, g->lo.x), c = _mm256_set1_pd(g->cell),
                  zero = _mm256_setzero_pd();
    const __m256d top = _mm256_setr_pd(g->nx - 1, g->ny - 1, g->nz - 1, g->nx - 1);
    const __m256d a = _mm256_setr_pd(lo.x, lo.y, lo.z, hi.x), b = _mm256_setr_pd(hi.y, hi.z, hi.y, hi.z);
    const __m256d ob = _mm256_setr_pd(g->lo.y, g->lo.z, g->lo.y, g->lo.z),
                  topb = _mm256_setr_pd(g->ny - 1, g->nz - 1, g->ny - 1, g->nz - 1);
    __m256d fa = _mm256_round_pd(_mm256_div_pd(_mm256_sub_pd(a, o), c), _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
    __m256d fb = _mm256_round_pd(_mm256_div_pd(_mm256_sub_pd(b, ob), c), _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
    fa = _mm256_min_pd(_mm256_max_pd(fa, zero), top); /* (max_pd gives its second operand for a NaN) */
    fb = _mm256_min_pd(_mm256_max_pd(fb, zero), topb);
    int32_t ia[4], ib[4];
    _mm_storeu_si128((__m128i *)ia, _mm256_cvttpd_epi32(fa));
    _mm_storeu_si128((__m128i *)ib, _mm256_cvttpd_epi32(fb));
    r[0] = ia[0], r[1] = ia[1], r[2] = ia[2], r[3] = ia[3], r[4] = ib[0], r[5] = ib[1];
}
#endif

/* The cells {x0, y0, z0, x1, y1, z1} that the box [lo, hi] covers, clamped to the grid */
static inline void cell_range(const sd_grid *g, sd_vec3 lo, sd_vec3 hi, int32_t r[6], int simd)
{
#ifdef SD_SCAN512
    if (simd >= SD_SIMD_AVX2) {
        cell_range256(g, lo, hi, r);
        return;
    }
#endif
    r[0] = clamp_cell(floor((lo.x - g->lo.x) / g->cell), g->nx - 1);
    r[1] = clamp_cell(floor((lo.y - g->lo.y) / g->cell), g->ny - 1);
    r[2] = clamp_cell(floor((lo.z - g->lo.z) / g->cell), g->nz - 1);
    r[3] = clamp_cell(floor((hi.x - g->lo.x) / g->cell), g->nx - 1);
    r[4] = clamp_cell(floor((hi.y - g->lo.y) / g->cell), g->ny - 1);
    r[5] = clamp_cell(floor((hi.z - g->lo.z) / g->cell), g->nz - 1);
}

/* An entry's flag byte: along which axes (bit 0 x, 1 y, 2 z) cell (x, y, z) is the first of
 * the entry's range r (the scans take a pair only in the lowest cell the two ranges share) */
static inline uint8_t range_begins(const int32_t *r, int x, int y, int z)
{
    return (uint8_t)((x == r[0]) | (y == r[1]) << 1 | (z == r[2]) << 2);
}

/* grid.c */
sd_status sd_grid_layout(sd_grid *g, sd_vec3 lo, sd_vec3 hi, double cell, long max_cells, const sd_vec3 *anchor);
sd_status sd_grid_layout_fixed(sd_grid *g, sd_vec3 lo, double cell, int nx, int ny, int nz);
sd_status sd_grid_fill(sd_grid *g, int n, const int32_t (*range)[6], const uint8_t *skip, int32_t *reg0, int32_t **slot,
                       int *slot_cap, uint8_t **flag, int *flag_cap, const sd_bed_cache *bed);
#ifdef _OPENMP
sd_status sd_grid_fill_par(sd_grid *g, int n, const int32_t (*range)[6], int32_t *reg0, int32_t **slot, int *slot_cap,
                           uint8_t **flag, int *flag_cap, const sd_bed_cache *bed, int T);
#endif
void sd_grid_flags(const sd_grid *g, const int32_t (*range)[6], uint8_t *flag);
sd_status sd_grid_tri_rebuild(sd_world *w, double cell);

/* bed_cache.c */
int sd_bed_cache_fits(const sd_bed_cache *c, const sd_grid *g);
sd_status sd_bed_cache_make(sd_world *w, double hm);

/* pair_history.c (and sd_history_collect, world_internal.h) */
sd_status sd_history_restore(sd_world *w, int by_index);

/* candidates.c (and sd_cand_bufs_free, world_internal.h) */
#ifdef SD_SCAN512
sd_status sd_cand_grid_coords(sd_world *w);
#endif
sd_status sd_cand_scan(sd_world *w, double hm, int K, int T);
sd_status sd_cand_join(sd_world *w, int K, int T);

#endif
