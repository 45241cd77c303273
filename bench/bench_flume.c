/* Sphere-only flume benchmark (issue: engine core / speed). Reads a packing in the LAMMPS data
 * format of ../shared/reference/lammps/gen_particles.py (atom-ID type diameter density x y z,
 * flume frame), builds the same box as flume.in (floor z = 0 over 0..4 m, side walls y = 0 and
 * 0.3 m, back wall x = 0, gate x = 0.3 m) out of triangles, and times the phases:
 *   drop (dilute), settle, dense (settled bed at rest behind the gate), flow (gate removed).
 * Prints particle-steps per second per phase and the time per engine phase.
 * usage: bench_flume DATAFILE [ndrop nsettle ndense nflow] [--threads N] [--write-settled FILE]
 *                    [--t-reset S]
 * --t-reset S: rebuild the candidates every S seconds as well as when anything moved more than
 * half the margin (SPEC §4; default 1e-3 s). A large S leaves only the displacement rule, the
 * policy of LAMMPS's `neigh_modify delay 0 every 1 check yes` in flume.in.
 * --ab SWITCH [--ab-groups G]: instead of timing the dense and flow phases, compare one of the
 * engine's switches off (A) and on (B) inside this process: G groups (default 20) of four
 * blocks of 250 steps in the order A B B A, on the settled bed, then again after the gate has
 * been open for 3000 steps. Prints the median and quartiles of each group's B/A time: a slow
 * spell of the machine falls on both forms alike (docs/performance.md §3). SWITCH is the
 * name of one of the engine's switches (world_internal.h SD_SWITCH_TABLE, in lower case:
 * springs_list, prefetch, ...) or avx512 (the AVX-512 kernels against the AVX2 ones). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

static int read_data(sd_world *w, const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        perror(path);
        return -1;
    }
    char line[512];
    int in_atoms = 0, n = 0;
    while (fgets(line, sizeof line, f)) {
        if (!strncmp(line, "Atoms", 5)) {
            in_atoms = 1;
            continue;
        }
        if (!in_atoms) continue;
        if ((line[0] >= 'A' && line[0] <= 'Z') || (line[0] >= 'a' && line[0] <= 'z')) break; /* next section */
        int id, type;
        double d, rho, x, y, z;
        if (sscanf(line, "%d %d %lf %lf %lf %lf %lf", &id, &type, &d, &rho, &x, &y, &z) == 7) {
            sd_sphere_def s = sd_sphere_def_default();
            s.pos = v3(x, y, z);
            s.radius = 0.5 * d;
            s.density = rho;
            s.tag = type - 1;
            if (sd_world_add_sphere(w, &s) < 0) return -1;
            n++;
        }
    }
    fclose(f);
    return n;
}

static void quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d, int group)
{
    sd_world_add_triangle(w, a, b, c, group);
    sd_world_add_triangle(w, a, c, d, group);
}

/* a switch's table name in lower case, as --ab takes it (a static buffer: one at a time) */
static const char *bench_lower(const char *name)
{
    static char buf[64];
    size_t k = 0;
    for (; name[k] && k + 1 < sizeof buf; k++)
        buf[k] = (char)(name[k] >= 'A' && name[k] <= 'Z' ? name[k] + 32 : name[k]);
    buf[k] = 0;
    return buf;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The switch an A/B run alternates: one of the engine's (world_internal.h SD_SWITCH_TABLE, by its
 * name in lower case: springs_list, prefetch, ...) or avx512 (the AVX-512 kernels against the
 * AVX2 ones). */
enum { AB_AVX512 = SD_SWITCH_COUNT };

/* The switch named `name`; -2 (and a message listing them) when there is none. */
static int ab_find(const char *prog, const char *name)
{
    if (!strcmp(name, "avx512")) return AB_AVX512;
    const int k = sd_switch_by_name(name);
    if (k >= 0 && k != SD_SW_MOVING_INDEX_MIN) return k;
    fprintf(stderr, "%s: --ab: no switch named '%s'; the switches: avx512", prog, name);
    for (int j = 0; j < SD_SWITCH_COUNT; j++)
        if (j != SD_SW_MOVING_INDEX_MIN) fprintf(stderr, " %s", bench_lower(sd_switch_name((sd_switch)j)));
    fprintf(stderr, "\n");
    return -2;
}

/* switch sw of w off (on = 0) or on; returns its setting before, for ab_restore */
static int ab_set(sd_world *w, int sw, int on)
{
    if (sw == AB_AVX512) {
        const int was = sd_world_simd_level(w);
        sd_world_set_simd_level(w, on ? SD_SIMD_AVX512 : SD_SIMD_AVX2);
        return was;
    }
    if (sw == SD_SW_PREFETCH) return sd_world_switch(w, SD_SW_PREFETCH, on ? SD_PREFETCH_ON : SD_PREFETCH_OFF);
    return sd_world_switch(w, (sd_switch)sw, on);
}

static void ab_restore(sd_world *w, int sw, int was)
{
    if (sw == AB_AVX512)
        sd_world_set_simd_level(w, was);
    else
        sd_world_switch(w, (sd_switch)sw, was);
}

/* G groups of A B B A blocks of 250 steps with the switch off (A) and on (B); the switch is
 * left as it was. Returns non-zero if a step fails. */
static int ab_phase(sd_world *w, const char *name, int sw, int groups, int n)
{
    enum { AB_BLOCK = 250 };
    const int was = ab_set(w, sw, 0);
    double *r = malloc((size_t)groups * sizeof(double)), ta = 0.0, tb = 0.0;
    if (!r) return 1;
    sd_status st = SD_OK;
    for (int g = 0; g < groups && !st; g++) {
        static const int order[4] = {0, 1, 1, 0};
        double t[4];
        for (int k = 0; k < 4 && !st; k++) {
            ab_set(w, sw, order[k]);
            const double t0 = sd_now();
            st = sd_world_run(w, AB_BLOCK);
            t[k] = sd_now() - t0;
        }
        r[g] = (t[1] + t[2]) / (t[0] + t[3]);
        ta += t[0] + t[3], tb += t[1] + t[2];
    }
    ab_restore(w, sw, was);
    if (st) {
        fprintf(stderr, "%s: %s\n", name, sd_status_message(st));
        free(r);
        return 1;
    }
    qsort(r, (size_t)groups, sizeof(double), cmp_double);
    const double steps = 2.0 * AB_BLOCK * groups;
    printf("AB %-6s %s: B/A median %.4f quartiles %.4f-%.4f (%d groups) | off %.4e on %.4e particle-steps/s\n", name,
           sw == AB_AVX512 ? "avx512" : bench_lower(sd_switch_name((sd_switch)sw)), r[groups / 2], r[groups / 4],
           r[(3 * groups) / 4], groups, n * steps / ta, n * steps / tb);
    fflush(stdout);
    free(r);
    return 0;
}

static double phase(sd_world *w, const char *name, long steps, int n)
{
    if (steps <= 0) return 0;
    sd_world_timers t0 = sd_world_get_timers(w);
    /* timed in blocks of BLOCK steps too: the median block, for A/B runs on a shared machine
     * (the whole phase's rate moves with the machine's slow spells, a block's median less) */
    enum { BLOCK = 500 };
    const long nblk = steps / BLOCK;
    double *blk = nblk > 0 ? malloc((size_t)nblk * sizeof(double)) : NULL;
    double w0 = sd_now();
    sd_status st = SD_OK;
    for (long k = 0; k < nblk && blk && !st; k++) {
        const double b0 = sd_now();
        st = sd_world_run(w, BLOCK);
        blk[k] = sd_now() - b0;
    }
    if (!st) st = sd_world_run(w, blk ? steps - nblk * BLOCK : steps);
    double wall = sd_now() - w0;
    sd_world_timers t1 = sd_world_get_timers(w);
    if (st) fprintf(stderr, "%s: %s\n", name, sd_status_message(st));
    double ps = (double)n * (double)steps / wall, med = 0.0;
    if (blk) {
        qsort(blk, (size_t)nblk, sizeof(double), cmp_double);
        med = (double)n * BLOCK / (nblk % 2 ? blk[nblk / 2] : 0.5 * (blk[nblk / 2 - 1] + blk[nblk / 2]));
        free(blk);
    }
    printf("PHASE %-7s steps %7ld wall %8.3f s  particle-steps/s %.4e  contacts %6ld  | rebuild %.3f contacts %.3f "
           "moves %.3f rebuilds %ld candidates %d+%d near %d | median of %d-step blocks %.4e\n",
           name, steps, wall, ps, sd_world_contact_count(w), t1.rebuild - t0.rebuild, t1.contacts - t0.contacts,
           t1.moves - t0.moves, t1.rebuilds - t0.rebuilds, w->bb.n, w->bt.n,
           sd_contact_near_count(w), BLOCK, med);
    fflush(stdout);
    return ps;
}

/* Bulk quantities for the cross-check with LAMMPS (bench/crosscheck.sh): mean and 95th
 * percentile of the centre heights, sphere-sphere contacts per sphere by an all-pairs check
 * (what LAMMPS's compute contact/atom counts: walls left out), the front (max x). */
static void bulk(sd_world *w, const char *name, int n)
{
    double *z = malloc((size_t)n * sizeof(double));
    sd_body_state *s = malloc((size_t)n * sizeof(sd_body_state));
    if (!z || !s) exit(1);
    double zsum = 0, xmax = -1e300;
    for (int i = 0; i < n; i++) {
        sd_world_body(w, i, &s[i]);
        z[i] = s[i].pos.z;
        zsum += z[i];
        if (s[i].pos.x > xmax) xmax = s[i].pos.x;
    }
    long touching = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            double rs = s[i].radius + s[j].radius;
            if (v3_norm2(v3_sub(s[i].pos, s[j].pos)) < rs * rs) touching++;
        }
    qsort(z, (size_t)n, sizeof(double), cmp_double);
    printf("BULK %-7s mean_z %.5f z95 %.5f contacts_per_sphere %.3f xmax %.4f\n", name, zsum / n, z[(int)(0.95 * (n - 1))],
           2.0 * (double)touching / n, xmax);
    free(z);
    free(s);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr,
                "usage: %s DATAFILE [ndrop nsettle ndense nflow] [--threads N] [--write-settled FILE] [--t-reset S] "
                "[--ab SWITCH [--ab-groups G]]\n",
                argv[0]);
        return 2;
    }
    long steps[4] = {20000, 40000, 20000, 20000};
    int threads = 1, ns = 0;
    double t_reset = 0.0; /* 0: the engine's default (SPEC §4) */
    const char *settled = NULL;
    int ab = -1, ab_groups = 20;
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "--ab") && i + 1 < argc)
            ab = ab_find(argv[0], argv[++i]);
        else if (!strcmp(argv[i], "--ab-groups") && i + 1 < argc)
            ab_groups = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--write-settled") && i + 1 < argc)
            settled = argv[++i];
        else if (!strcmp(argv[i], "--t-reset") && i + 1 < argc)
            t_reset = atof(argv[++i]);
        else if (ns < 4)
            steps[ns++] = atol(argv[i]);
    }
    if (ab == -2) return 2;
    if (ab == AB_AVX512 && sd_cpu_simd_level() < SD_SIMD_AVX512) {
        fprintf(stderr, "%s: --ab avx512: this CPU has no AVX-512 (both forms would be AVX2)\n", argv[0]);
        return 2;
    }
    if (ab_groups < 1) {
        fprintf(stderr, "%s: --ab-groups must be at least 1\n", argv[0]);
        return 2;
    }
    sd_world_def d = sd_world_def_default(); /* paper's springs, Δt = 1e-5, 15° gravity */
    d.threads = threads;
    sd_tuning_from_env(&d.tuning, NULL, 0);
    if (t_reset > 0.0) d.t_reset = t_reset;
    sd_world *w;
    if (sd_world_create(&d, &w)) return 1;
    int n = read_data(w, argv[1]);
    if (n <= 0) return 1;
    const double L = 4.0, W = 0.3, H = 0.5;
    quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, W, 0), v3(0, W, 0), 0);
    quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, 0, H), v3(0, 0, H), 1);
    quad(w, v3(0, W, 0), v3(L, W, 0), v3(L, W, H), v3(0, W, H), 1);
    quad(w, v3(0, 0, 0), v3(0, W, 0), v3(0, W, H), v3(0, 0, H), 2);
    quad(w, v3(L, 0, 0), v3(L, W, 0), v3(L, W, H), v3(L, 0, H), 2);
    quad(w, v3(0.3, 0, 0), v3(0.3, W, 0), v3(0.3, W, H), v3(0.3, 0, H), 3);
    printf("spheres %d threads %d\n", n, threads);
    phase(w, "drop", steps[0], n);
    phase(w, "settle", steps[1], n);
    bulk(w, "settle", n);
    if (settled) {
        FILE *f = fopen(settled, "w");
        if (f) {
            fprintf(f, "settled by sabodem\n\n%d atoms\n4 atom types\n\n0.0 4.0 xlo xhi\n0.0 0.3 ylo yhi\n0.0 0.5 zlo zhi\n\nAtoms\n\n", n);
            for (int i = 0; i < n; i++) {
                sd_body_state b;
                sd_world_body(w, i, &b);
                fprintf(f, "%d %d %.6f %.1f %.9f %.9f %.9f\n", i + 1, b.tag + 1, 2 * b.radius, 1900.0, b.pos.x, b.pos.y,
                        b.pos.z);
            }
            fclose(f);
        }
    }
    if (ab >= 0) {
        /* the A/B comparison in place of the timed phases */
        if (ab_phase(w, "dense", ab, ab_groups, n)) return 1;
        sd_world_set_group_active(w, 3, 0);
        if (sd_world_run(w, 3000)) return 1;
        if (ab_phase(w, "flow", ab, ab_groups, n)) return 1;
        printf("state hash %016llx\n", (unsigned long long)sd_world_state_hash(w));
        sd_world_destroy(w);
        return 0;
    }
    phase(w, "dense", steps[2], n);
    sd_world_set_group_active(w, 3, 0);
    phase(w, "flow", steps[3], n);
    bulk(w, "flow", n);
    double cn = 2.0 * (double)sd_world_contact_count(w) / n;
    printf("contacts per sphere (incl. walls) at end: %.3f\n", cn);
    /* the same bits for any thread count and any kernel rewrite that keeps the arithmetic */
    printf("state hash %016llx\n", (unsigned long long)sd_world_state_hash(w));
    sd_world_destroy(w);
    return 0;
}
