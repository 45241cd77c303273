/* What the machine itself takes from a two-thread step (docs/performance.md §5): no sabodem
 * code, only the CPUs. Four probes, each with one thread busy and then both (pinned with
 * OMP_PROC_BIND=true OMP_PLACES=cores, as the runs are):
 *   1. interruptions: a thread reads the clock in a loop; a gap above 2 µs between two reads is
 *      time the CPU was taken away (timer ticks, the hypervisor). Events per second by length,
 *      and the share of the time lost;
 *   2. arithmetic: eight independent multiply-add chains (throughput-bound), per thread, both
 *      busy against one: what a second busy vCPU costs the first in pure compute;
 *   3. a 1 MiB array summed again and again (past a 512 KiB L2, within the L3): the same for a
 *      loop that streams from the shared cache;
 *   4. a synchronised step: both threads do the same fixed work of W µs and meet at a barrier,
 *      N times, against the same work without the barrier. The difference is what the machine's
 *      interruptions and uneven speeds cost a code that synchronises every W µs (sabodem's
 *      two-thread step is ~150-350 µs on the paper's run);
 *   5. the caches as one thread sees them: over blocks of 256 KiB to 256 MiB, the time of a
 *      dependent walk through the block's lines in a random order (each load waits for the one
 *      before: the latency, TLB included) and the rate of a plain read of it. Where the walk's
 *      time jumps is the cache a step's data must fit in (docs/performance.md §6: sysconf and
 *      cpuid tell a VM's guest the host's sizes, not its share).
 *   usage: bench_machine [SECONDS per probe, default 2] [--step W_us, default 170] */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "world_internal.h" /* (sd_now: the library's monotonic clock) */

#ifdef _OPENMP
#include <omp.h>
#endif

static int nthreads_max(void)
{
#ifdef _OPENMP
    return omp_get_max_threads();
#else
    return 1;
#endif
}

static int thread_id(void)
{
#ifdef _OPENMP
    return omp_get_thread_num();
#else
    return 0;
#endif
}

#define NCLASS 6
static const double class_hi[NCLASS] = {10e-6, 20e-6, 50e-6, 100e-6, 1e-3, 1e30};
static const char *const class_name[NCLASS] = {"2-10 us", "10-20 us", "20-50 us", "50-100 us", "0.1-1 ms", ">1 ms"};

typedef struct {
    long n[NCLASS];
    double t[NCLASS];
    double lost, span;
} gaps;

/* 1. the gaps above 2 µs between two clock reads in a loop of `secs` seconds */
static void gap_probe(double secs, gaps *g)
{
    memset(g, 0, sizeof *g);
    const double t0 = sd_now();
    double last = t0, t = t0;
    do {
        t = sd_now();
        const double d = t - last;
        last = t;
        if (d > 2e-6) {
            int k = 0;
            while (d > class_hi[k])
                k++;
            g->n[k]++;
            g->t[k] += d;
            g->lost += d;
        }
    } while (t - t0 < secs);
    g->span = t - t0;
}

static void gap_print(const char *what, const gaps *g)
{
    printf("  %s: %.2f %% of the time lost |", what, 100.0 * g->lost / g->span);
    for (int k = 0; k < NCLASS; k++)
        if (g->n[k]) printf(" %s %.1f/s (mean %.1f us)", class_name[k], g->n[k] / g->span, 1e6 * g->t[k] / g->n[k]);
    printf("\n");
}

/* 2. multiply-adds in eight independent chains: `reps` rounds; returns the seconds */
static double fma_probe(long reps, double *sink)
{
    double a[8];
    for (int k = 0; k < 8; k++)
        a[k] = 1.0 + 1e-9 * k;
    const double m = 0.9999999, c = 1e-9;
    const double t0 = sd_now();
    for (long r = 0; r < reps; r++)
        for (int k = 0; k < 8; k++)
            a[k] = a[k] * m + c;
    const double t = sd_now() - t0;
    double s = 0.0;
    for (int k = 0; k < 8; k++)
        s += a[k];
    *sink += s;
    return t;
}

/* 3. a 1 MiB array summed `reps` times in four running sums; returns the seconds */
static double stream_probe(const double *x, long n, long reps, double *sink)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    const double t0 = sd_now();
    for (long r = 0; r < reps; r++) {
        for (long i = 0; i < n; i += 4) {
            s0 += x[i], s1 += x[i + 1], s2 += x[i + 2], s3 += x[i + 3];
        }
        s0 *= 0.5; /* (keeps the sums finite and the loop from being folded) */
    }
    const double t = sd_now() - t0;
    *sink += s0 + s1 + s2 + s3;
    return t;
}

/* 4. a fixed work unit: `reps` rounds of the multiply-add chains */
static double work(long reps)
{
    double sink = 0.0;
    fma_probe(reps, &sink);
    return sink;
}

/* 5. a walk of `steps` loads through a cycle of the lines of a (n lines), returns ns a load */
static double walk_probe(const uint64_t *a, long steps, uint64_t *sink)
{
    uint64_t p = 0;
    const double t0 = sd_now();
    for (long k = 0; k < steps; k++)
        p = a[p];
    const double t = sd_now() - t0;
    *sink += p;
    return 1e9 * t / (double)steps;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    double secs = 2.0, step_us = 170.0;
    for (int k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--step") && k + 1 < argc) {
            step_us = atof(argv[++k]);
        } else if (argv[k][0] != '-') {
            secs = atof(argv[k]);
        } else {
            fprintf(stderr, "usage: bench_machine [SECONDS] [--step W_us]\n");
            return 2;
        }
    }
    if (!(secs > 0.0) || !(step_us > 0.0)) {
        fprintf(stderr, "bench_machine: SECONDS and --step must be positive\n");
        return 2;
    }
    const int T = nthreads_max() >= 2 ? 2 : 1;
    printf("machine probe: %d thread(s), %.1f s a probe\n", T, secs);
    volatile double keep = 0.0;

    /* 1 */
    printf("1. interruptions (gaps above 2 us between two clock reads)\n");
    {
        gaps g1, g2[2];
        gap_probe(secs, &g1);
        gap_print("one thread busy", &g1);
        if (T == 2) {
#pragma omp parallel num_threads(2)
            gap_probe(secs, &g2[thread_id()]);
            gap_print("both busy, thread 0", &g2[0]);
            gap_print("both busy, thread 1", &g2[1]);
        }
    }

    /* calibrate the multiply-add rounds to ~secs/4 on one thread */
    long reps = 1000000;
    {
        double sink = 0.0, t;
        while ((t = fma_probe(reps, &sink)) < 0.05)
            reps *= 2;
        reps = (long)(reps * (0.25 * secs / t));
        keep += sink;
    }
    /* 2 */
    {
        double sink = 0.0, t1 = 0.0, t2[2] = {0.0, 0.0};
        t1 = fma_probe(reps, &sink);
        if (T == 2) {
#pragma omp parallel num_threads(2) reduction(+ : sink)
            t2[thread_id()] = fma_probe(reps, &sink);
        }
        keep += sink;
        printf("2. arithmetic: one thread %.3f s; both busy %.3f / %.3f s: %.2fx the one thread's rate in all\n", t1,
               t2[0], t2[1], T == 2 ? t1 / t2[0] + t1 / t2[1] : 1.0);
    }
    /* 3 */
    {
        const long n = (1L << 20) / sizeof(double);
        double *x[2];
        for (int k = 0; k < 2; k++) {
            x[k] = malloc((size_t)n * sizeof(double));
            if (!x[k]) {
                fprintf(stderr, "bench_machine: out of memory\n");
                return 1;
            }
            for (long i = 0; i < n; i++)
                x[k][i] = 1.0 + 1e-6 * (double)(i % 1000);
        }
        double sink = 0.0, t;
        long r = 16;
        while ((t = stream_probe(x[0], n, r, &sink)) < 0.05)
            r *= 2;
        r = (long)(r * (0.25 * secs / t));
        const double t1 = stream_probe(x[0], n, r, &sink);
        double t2[2] = {0.0, 0.0};
        if (T == 2) {
#pragma omp parallel num_threads(2) reduction(+ : sink)
            t2[thread_id()] = stream_probe(x[thread_id()], n, r, &sink);
        }
        keep += sink;
        const double gb = (double)n * sizeof(double) * (double)r / 1e9;
        printf("3. 1 MiB stream: one thread %.1f GB/s; both busy %.1f / %.1f GB/s: %.2fx the one thread's rate in all\n",
               gb / t1, T == 2 ? gb / t2[0] : 0.0, T == 2 ? gb / t2[1] : 0.0, T == 2 ? t1 / t2[0] + t1 / t2[1] : 1.0);
        free(x[0]);
        free(x[1]);
    }
    /* 4 */
    if (T == 2) {
        /* the rounds that take step_us on one thread (median of 51 timings) */
        long wr = 1000;
        {
            double sink = 0.0, ts[51];
            for (int k = 0; k < 51; k++)
                ts[k] = fma_probe(wr, &sink);
            qsort(ts, 51, sizeof(double), cmp_double);
            wr = (long)(wr * (step_us * 1e-6 / ts[25]));
            if (wr < 1) wr = 1;
            keep += sink;
        }
        const long steps = (long)(secs / (step_us * 1e-6));
        double t_free = 0.0, t_sync = 0.0, s = 0.0;
        /* each thread its steps, no barrier: the wall time is the slower thread's sum */
        {
            const double t0 = sd_now();
#pragma omp parallel num_threads(2) reduction(+ : s)
            for (long k = 0; k < steps; k++)
                s += work(wr);
            t_free = sd_now() - t0;
        }
        /* the same steps with a barrier after each (one parallel region, as a pass's barrier) */
        {
            const double t0 = sd_now();
#pragma omp parallel num_threads(2) reduction(+ : s)
            for (long k = 0; k < steps; k++) {
                s += work(wr);
#pragma omp barrier
            }
            t_sync = sd_now() - t0;
        }
        keep += s;
        printf("4. %ld steps of %.0f us on both threads: %.3f s free, %.3f s with a barrier a step: %+.1f %% "
               "(%.1f us a step)\n",
               steps, step_us, t_free, t_sync, 100.0 * (t_sync / t_free - 1.0), 1e6 * (t_sync - t_free) / steps);
    }
    /* 5 */
    {
        printf("5. the caches (one thread): a dependent walk through random lines, and a plain read\n");
        uint64_t wsink = 0;
        for (size_t bytes = (size_t)256 << 10; bytes <= (size_t)256 << 20; bytes *= 2) {
            const size_t n = bytes / 64; /* lines; the walk uses the first word of each */
            uint64_t *a = aligned_alloc(64, bytes);
            uint32_t *perm = malloc(n * sizeof(uint32_t));
            if (!a || !perm) {
                free(a);
                free(perm);
                break;
            }
            for (size_t i = 0; i < n; i++)
                perm[i] = (uint32_t)i;
            uint64_t st = 88172645463325252ULL;
            for (size_t i = n - 1; i > 0; i--) { /* a random cycle through every line */
                st ^= st << 13, st ^= st >> 7, st ^= st << 17;
                const size_t j = st % (i + 1);
                const uint32_t t = perm[i];
                perm[i] = perm[j];
                perm[j] = t;
            }
            for (size_t i = 0; i < bytes / 8; i++)
                a[i] = 1;
            for (size_t i = 0; i < n; i++)
                a[(size_t)perm[i] * 8] = (uint64_t)perm[(i + 1) % n] * 8;
            free(perm);
            const long steps = (long)(5e6 * (secs / 2.0)) + (long)n;
            walk_probe(a, (long)n, &wsink); /* (warm) */
            const double ns = walk_probe(a, steps, &wsink);
            double sink = 0.0, t;
            long r = 1;
            while ((t = stream_probe((const double *)a, (long)(bytes / 8), r, &sink)) < 0.05 * secs)
                r *= 2;
            keep += sink;
            printf("  %7zu KiB: walk %6.1f ns a load; read %5.1f GB/s\n", bytes >> 10, ns,
                   (double)bytes * (double)r / t / 1e9);
            free(a);
        }
        keep += (double)(wsink & 1);
    }
    if (keep == 0.12345) printf("(%g)\n", keep);
    return 0;
}
