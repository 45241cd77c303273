/* The engine's tuning (sabodem.h sd_tuning): its defaults, the level a world runs at, and the
 * one place where the library reads the environment and the operating system, for programs that
 * ask it to (sd_tuning_from_env). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/cpu.h"
#include "tuning.h"

sd_tuning sd_tuning_default(void)
{
    sd_tuning t;
    memset(&t, 0, sizeof t);
    t.simd = SD_SIMD_AUTO;
    t.prefetch = SD_PREFETCH_AUTO;
    t.llc_bytes = 0;
    return t;
}

int sd_tuning_simd_level(int asked, int cpu, int amd)
{
    /* AMD: the AVX2 kernels load the bodies' rows and transpose them, the AVX-512 ones gather
     * them lane by lane, which costs more there (the paper's run on a Zen 5 VM: 177-205 s with
     * AVX-512 against 140-158 s without) */
    if (asked < SD_SIMD_SCALAR || asked > SD_SIMD_AVX512) return cpu == SD_SIMD_AVX512 && amd ? SD_SIMD_AVX2 : cpu;
    return asked > cpu ? cpu : asked;
}

/* The last-level cache's size: Linux's sysfs (cpuid through sysconf gave 256 MiB for the 32 MiB
 * L3 of an AMD VM), else sysconf. On AMD a core reaches the L3 of its own complex only, 32 MiB
 * on Zen 2 to 5, where sysconf may give the whole package's (508 MiB on a Zen 5 VM with no cache
 * sizes in sysfs): there a figure from sysconf above 32 MiB counts as 32 MiB. 0 when unknown. */
static long llc_bytes_of_system(void)
{
    long v = -1;
    FILE *f = fopen("/sys/devices/system/cpu/cpu0/cache/index3/size", "r");
    if (f) {
        char unit = 0;
        long n = 0;
        if (fscanf(f, "%ld%c", &n, &unit) >= 1 && n > 0) v = unit == 'K' ? n << 10 : unit == 'M' ? n << 20 : n;
        fclose(f);
    }
#ifdef _SC_LEVEL3_CACHE_SIZE
    if (v <= 0) {
        v = sysconf(_SC_LEVEL3_CACHE_SIZE);
        if (v > 32L << 20 && sd_cpu_is_amd()) v = 32L << 20;
    }
#endif
    return v > 0 ? v : 0;
}

static int set_bad(char *msg, size_t len, const char *name, const char *value, const char *allowed)
{
    if (msg && len) snprintf(msg, len, "%s=%s is not one of %s", name, value, allowed);
    return 1;
}

sd_status sd_tuning_from_env(sd_tuning *t, char *msg, size_t msg_len)
{
    *t = sd_tuning_default();
    if (msg && msg_len) msg[0] = 0;
    int bad = 0;
    const char *e = getenv("SD_SIMD");
    if (e && *e) {
        if (!strcmp(e, "scalar") || !strcmp(e, "0"))
            t->simd = SD_SIMD_SCALAR;
        else if (!strcmp(e, "avx2") || !strcmp(e, "1"))
            t->simd = SD_SIMD_AVX2;
        else if (!strcmp(e, "avx512"))
            t->simd = SD_SIMD_AVX512;
        else if (strcmp(e, "auto"))
            bad |= set_bad(msg, msg_len, "SD_SIMD", e, "scalar, avx2, avx512, auto");
    }
    e = getenv("SD_NO_AVX512"); /* (older name: the scalar loops) */
    if (e && *e && strcmp(e, "0")) t->simd = SD_SIMD_SCALAR;
    e = getenv("SD_PREFETCH");
    if (e && *e) {
        if (!strcmp(e, "on"))
            t->prefetch = SD_PREFETCH_ON;
        else if (!strcmp(e, "off"))
            t->prefetch = SD_PREFETCH_OFF;
        else if (strcmp(e, "auto"))
            bad |= set_bad(msg, msg_len, "SD_PREFETCH", e, "on, off, auto");
    }
    t->llc_bytes = llc_bytes_of_system();
    return bad ? SD_ERR_ARG : SD_OK;
}
