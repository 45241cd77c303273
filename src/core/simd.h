/* Loops over independent lanes, built three times on x86-64 (AVX-512, AVX2 and the baseline)
 * and picked at load time by the CPU. The lanes are independent and nothing is contracted
 * (-ffp-contract=off), so every build gives the same bits. */
#ifndef SD_CORE_SIMD_H
#define SD_CORE_SIMD_H

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#define SD_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define SD_SIMD_CLONES
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#include <immintrin.h>

/* The 4 x 4 transpose (AVX2 kernels): r[k] = (a_k, b_k, c_k, d_k). Four rows (x, y, z, -) of a
 * vec3 array become lanes x, y, z (r[0..2]); lanes x, y, z, - become rows. */
__attribute__((target("avx2"))) static inline void sd_transpose4(__m256d a, __m256d b, __m256d c, __m256d d,
                                                                 __m256d r[4])
{
    const __m256d lo_ab = _mm256_unpacklo_pd(a, b), hi_ab = _mm256_unpackhi_pd(a, b);
    const __m256d lo_cd = _mm256_unpacklo_pd(c, d), hi_cd = _mm256_unpackhi_pd(c, d);
    r[0] = _mm256_permute2f128_pd(lo_ab, lo_cd, 0x20);
    r[1] = _mm256_permute2f128_pd(hi_ab, hi_cd, 0x20);
    r[2] = _mm256_permute2f128_pd(lo_ab, lo_cd, 0x31);
    r[3] = _mm256_permute2f128_pd(hi_ab, hi_cd, 0x31);
}

/* Four vec3 that sit next to each other (12 doubles: rows a = x0 y0 z0 x1, b = y1 z1 x2 y2,
 * c = z2 x3 y3 z3) into lanes x, y, z (lane l: vec3 l), and back: three loads or stores
 * instead of four, and fewer shuffles than sd_transpose4. */
__attribute__((target("avx2"))) static inline void sd_rows3_lanes(__m256d a, __m256d b, __m256d c, __m256d *x,
                                                                  __m256d *y, __m256d *z)
{
    const __m256d p = _mm256_permute2f128_pd(a, c, 0x20), q = _mm256_permute2f128_pd(a, c, 0x31);
    /* p = x0 y0 z2 x3, q = z0 x1 y3 z3 */
    *x = _mm256_blend_pd(_mm256_blend_pd(p, q, 0x2), b, 0x4);
    *y = _mm256_shuffle_pd(_mm256_blend_pd(p, b, 0xC), _mm256_blend_pd(b, q, 0xC), 0x5);
    *z = _mm256_blend_pd(_mm256_blend_pd(q, p, 0x4), b, 0x2);
}

__attribute__((target("avx2"))) static inline void sd_lanes_rows3(__m256d x, __m256d y, __m256d z, __m256d *a,
                                                                  __m256d *b, __m256d *c)
{
    const __m256d xy = _mm256_unpacklo_pd(x, y); /* x0 y0 x2 y2 */
    const __m256d zx = _mm256_shuffle_pd(z, x, 0xA); /* z0 x1 z2 x3 */
    const __m256d yz = _mm256_shuffle_pd(y, z, 0xF); /* y1 z1 y3 z3 */
    *a = _mm256_permute2f128_pd(xy, zx, 0x20);
    *b = _mm256_permute2f128_pd(yz, xy, 0x30);
    *c = _mm256_permute2f128_pd(zx, yz, 0x31);
}

/* vec3 i of the array at p (3 doubles each) as the row (x, y, z, w), w the next element's x and
 * never used: a plain 32-byte load (the body store keeps an element past its capacity) */
#ifdef SD_XYZ_MASKED
#define SD_XYZ_LOAD(p, i) _mm256_maskload_pd((p) + 3 * (i), _mm256_setr_epi64x(-1, -1, -1, 0))
#else
#define SD_XYZ_LOAD(p, i) _mm256_loadu_pd((p) + 3 * (i))
#endif
#endif

#endif
