/* What the CPU offers the hand-written kernels, asked of the CPU itself (cpuid), never of the
 * environment. */
#ifndef SD_CORE_CPU_H
#define SD_CORE_CPU_H

/* The best SIMD level (SD_SIMD_SCALAR, _AVX2, _AVX512 of sabodem.h) the CPU and this build can
 * run: AVX-512 needs avx512f and avx512vl, AVX2 needs avx2 and popcnt. */
int sd_cpu_simd_level(void);
/* 1 on an AMD CPU: their AVX-512 gathers are slower than AVX2's loads and transposes, and a
 * core there reaches only its own complex's L3. */
int sd_cpu_is_amd(void);

#endif
