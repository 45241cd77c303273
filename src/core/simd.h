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

#endif
