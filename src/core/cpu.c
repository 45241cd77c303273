#include "core/cpu.h"

#include "sabodem.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#define SD_CPU_X86 1
#endif

int sd_cpu_simd_level(void)
{
#ifdef SD_CPU_X86
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl")) return SD_SIMD_AVX512;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt")) return SD_SIMD_AVX2;
#endif
    return SD_SIMD_SCALAR;
}

int sd_cpu_is_amd(void)
{
#ifdef SD_CPU_X86
    __builtin_cpu_init();
    return __builtin_cpu_is("amd") != 0;
#else
    return 0;
#endif
}
