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

/* Four rows (x, y, z, -) of a vec3 array into lanes: x, y, z of the four (AVX2 kernels). */
__attribute__((target("avx2"))) static inline void sd_rows_to_lanes(__m256d r0, __m256d r1, __m256d r2, __m256d r3,
                                                                    __m256d *x, __m256d *y, __m256d *z)
{
    const __m256d lo01 = _mm256_unpacklo_pd(r0, r1), hi01 = _mm256_unpackhi_pd(r0, r1);
    const __m256d lo23 = _mm256_unpacklo_pd(r2, r3), hi23 = _mm256_unpackhi_pd(r2, r3);
    *x = _mm256_permute2f128_pd(lo01, lo23, 0x20);
    *y = _mm256_permute2f128_pd(hi01, hi23, 0x20);
    *z = _mm256_permute2f128_pd(lo01, lo23, 0x31);
}

/* vec3 i of the array at p (3 doubles each) as the row (x, y, z, 0): a masked load, which reads
 * nothing past z (the last element of an array has nothing after it) */
#define SD_XYZ_LOAD(p, i) _mm256_maskload_pd((p) + 3 * (i), _mm256_setr_epi64x(-1, -1, -1, 0))
#endif

#endif
