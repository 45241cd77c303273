/* Scaling benchmark (issues: engine core, speed): the settled dense bed of the flume benchmark
 * (a LAMMPS-format data file of 4619 spheres of the paper's four sizes at rest in the 0.3 m x
 * 0.3 m reservoir, as written by bench/run.sh or `bench_flume --write-settled`) tiled side by
 * side over the floor and cut to N spheres (the N with the smallest y), in an open box of
 * triangles, gravity vertical. The bed depth and the local structure are those of the flume's
 * dense bed at every N, but not the contact count per sphere: a small bed is mostly edge (the
 * cut, and the walls, whose contacts are not counted), and the count grows with N (2.85 at
 * 1e3, 3.7-3.8 at 1e4, 4.0 at 1e5, 4.4 at 1e6 on 2026-11-27), so the cost per contact-step is
 * printed beside the cost per particle-step. After a short warm-up (and, the front prefetch on
 * auto, past its first trial: docs/performance.md §8), `steps` steps are timed.
 *
 * --same: every sphere in the same surroundings at every N. A unit of ~1000 spheres (a square
 * corner of the bed) is settled once in its own box, then copied: N / unit copies side by
 * side, each in its own walls (2 mm apart, so no two copies touch). Every copy is the same
 * settled bed, so the work per sphere (contacts, walls, drift) is the same at 1e3 and at 1e6,
 * and what changes with N is only where the data live.
 * In both modes the timed steps are a multiple of 100 at every N (steps, steps/2, steps/10,
 * steps/20), so that each size takes its share of the candidate rebuilds (every t_reset = 1 ms).
 * usage: bench_scale SETTLED.data [steps] [--threads N] [--big] [--only N] [--same] [--stages]
 *   N = 1e3, 1e4, 1e5 (steps, steps/2, steps/10) and with --big 1e6 (steps/20); --only N runs
 *   that one size for `steps` steps (for profiling).
 * --ab prefetch|avx512|springs|slot_sqm|ext [--ab-groups G]: at each size, after the warm-up, instead of the
 *   timed steps, G groups (default 8) of eight 100-step blocks with the switch off (A) and on (B)
 *   in the order A B B A B A A B; prints the median and quartiles of B/A (prefetch: the pass's front
 *   prefetch forced off and on; avx512: the AVX2 kernels against the AVX-512 ones; springs: the
 *   sphere pairs' springs in their candidates' slots against the near list's order; slot_sqm:
 *   each pair's sqrt_m_eff streamed with its record against kept in its spring's slot; ext: the
 *   store's external forces, all zero here, read by the moves against skipped).
 * --stages: after each size, the candidate rebuild's stages (sd_neighbor_stage_name), ms a
 *   rebuild over the timed steps' rebuilds. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "world_internal.h"

/* the timed steps alone instrumented when run under callgrind (bench/work.sh); no-ops
 * otherwise */
#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define SD_HAVE_CALLGRIND 1
#endif
#endif

#ifdef _OPENMP
#include <omp.h>
#endif

typedef struct {
    double d, x, y, z;
    int type;
} grain;

static grain *g_src;
static int g_n;

static int read_data(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        perror(path);
        return -1;
    }
    char line[512];
    int in_atoms = 0, cap = 8192;
    g_src = malloc((size_t)cap * sizeof(grain));
    while (g_src && fgets(line, sizeof line, f)) {
        if (!strncmp(line, "Atoms", 5)) {
            in_atoms = 1;
            continue;
        }
        if (!in_atoms) continue;
        if ((line[0] >= 'A' && line[0] <= 'Z') || (line[0] >= 'a' && line[0] <= 'z')) break;
        int id, type;
        double d, rho, x, y, z;
        if (sscanf(line, "%d %d %lf %lf %lf %lf %lf", &id, &type, &d, &rho, &x, &y, &z) == 7) {
            if (g_n == cap) {
                cap *= 2;
                grain *t = realloc(g_src, (size_t)cap * sizeof(grain));
                if (!t) break;
                g_src = t;
            }
            g_src[g_n++] = (grain){d, x, y, z, type};
        }
    }
    fclose(f);
    return g_n > 0 ? 0 : -1;
}

static int cmp_y(const void *a, const void *b)
{
    double p = ((const grain *)a)->y, q = ((const grain *)b)->y;
    return (p > q) - (p < q);
}

static void quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d)
{
    sd_world_add_triangle(w, a, b, c, 0);
    sd_world_add_triangle(w, a, c, d, 0);
}

/* an open box of triangles over [0, X] x [0, Y], walls H high */
static void open_box(sd_world *w, double X, double Y, double H)
{
    quad(w, v3(0, 0, 0), v3(X, 0, 0), v3(X, Y, 0), v3(0, Y, 0));
    quad(w, v3(0, 0, 0), v3(X, 0, 0), v3(X, 0, H), v3(0, 0, H));
    quad(w, v3(0, Y, 0), v3(X, Y, 0), v3(X, Y, H), v3(0, Y, H));
    quad(w, v3(0, 0, 0), v3(0, Y, 0), v3(0, Y, H), v3(0, 0, H));
    quad(w, v3(X, 0, 0), v3(X, Y, 0), v3(X, Y, H), v3(X, 0, H));
}

static int g_threads = 1; /* --threads */

/* a world with vertical gravity, or NULL; its tuning from the environment (SD_SIMD, SD_PREFETCH) */
static sd_world *new_world(void)
{
    sd_world_def d = sd_world_def_default();
    d.gravity = v3(0, 0, -9.81);
    d.threads = g_threads;
    sd_tuning_from_env(&d.tuning, NULL, 0);
    sd_world *w;
    return sd_world_create(&d, &w) ? NULL : w;
}

/* grain g as a sphere, moved by (ox, oy); its gid */
static int add_grain(sd_world *w, const grain *g, double ox, double oy)
{
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = 0.5 * g->d;
    s.pos = v3(g->x + ox, g->y + oy, g->z);
    s.tag = g->type - 1;
    return sd_world_add_sphere(w, &s);
}

/* `warm` steps, then `steps` timed; one line: the rate, the cost per particle-step and per
 * contact-step, the rebuilds in the timed steps and their time (neighbor). `what` goes after
 * the count. Destroys w; returns particle-steps per second. */
static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* --ab: the switch alternated, and how many groups */
static const char *ab_name;
static int ab_groups = 8;
static int stages; /* --stages: the rebuild's stages printed */

/* the switch named ab_name (main checks it) of w off or on, as bench_flume --ab has them: one
 * of the engine's (prefetch, springs_list, slot_sqm, ext_skip) or avx512; returns its setting
 * before (for ab_restore) */
static int ab_set(sd_world *w, int on)
{
    if (!strcmp(ab_name, "avx512")) {
        const int was = sd_world_simd_level(w);
        sd_world_set_simd_level(w, on ? SD_SIMD_AVX512 : SD_SIMD_AVX2);
        return was;
    }
    const int k = sd_switch_by_name(ab_name);
    if (k == SD_SW_PREFETCH) return sd_world_switch(w, SD_SW_PREFETCH, on ? SD_PREFETCH_ON : SD_PREFETCH_OFF);
    return sd_world_switch(w, (sd_switch)k, on);
}

static void ab_restore(sd_world *w, int was)
{
    if (!strcmp(ab_name, "avx512"))
        sd_world_set_simd_level(w, was);
    else
        sd_world_switch(w, (sd_switch)sd_switch_by_name(ab_name), was);
}

/* ab_groups groups of eight blocks of 100 steps, the switch off (A) and on (B) in the order
 * A B B A B A A B; prints the median and quartiles of each group's B/A time. The switch is left
 * as it was. Why eight: the tiled bed rings (at 1e4 the step's cost swings a few per cent over a
 * period of ~400 steps), and A B B A alone, four blocks of 100 steps, put B on the dear half of
 * each swing: a switch that changes nothing read 1.045-1.050 at 1e4 (performance pass P40, in
 * the git history). The second half turns the first around, so a swing of four blocks cancels,
 * as does a steady drift. */
static void ab_world(sd_world *w, int n)
{
    enum { BLOCK = 100 };
    double *r = malloc((size_t)ab_groups * sizeof(double));
    if (!r) return;
    const int was = ab_set(w, 0);
    for (int g = 0; g < ab_groups; g++) {
        static const int order[8] = {0, 1, 1, 0, 1, 0, 0, 1};
        double t[2] = {0.0, 0.0};
        for (int k = 0; k < 8; k++) {
            ab_set(w, order[k]);
            const double t0 = sd_now();
            sd_world_run(w, BLOCK);
            t[order[k]] += sd_now() - t0;
        }
        r[g] = t[1] / t[0];
    }
    ab_restore(w, was);
    qsort(r, (size_t)ab_groups, sizeof(double), cmp_double);
    printf("AB N %8d %s: B/A median %.4f quartiles %.4f-%.4f (%d groups of A B B A B A A B, %d steps a block)\n", n,
           ab_name, r[ab_groups / 2], r[ab_groups / 4], r[(3 * ab_groups) / 4], ab_groups, BLOCK);
    fflush(stdout);
    free(r);
}

static double time_world(sd_world *w, int n, const char *what, long warm, long steps)
{
    sd_world_run(w, warm);
    /* past the front prefetch's first trial, which the warm-up's first step began if the world
     * takes one (auto mode: blocks off and on, ~6e7 particle-steps), so that the timed steps run
     * with its verdict */
    while (!ab_name && w->pf.blk >= 0)
        sd_world_run(w, 2);
    if (ab_name) {
        ab_world(w, n);
        sd_world_destroy(w);
        return 1.0;
    }
    double rb[SD_RB_STAGES];
    sd_neighbor_stages_take(rb); /* (the warm-up's rebuilds left out) */
    const sd_world_timers k0 = sd_world_get_timers(w);
    double t0 = sd_now();
#ifdef SD_HAVE_CALLGRIND
    CALLGRIND_START_INSTRUMENTATION;
#endif
    sd_status st = sd_world_run(w, steps);
#ifdef SD_HAVE_CALLGRIND
    CALLGRIND_STOP_INSTRUMENTATION;
#endif
    double wall = sd_now() - t0;
    const sd_world_timers k1 = sd_world_get_timers(w);
    sd_neighbor_stages_take(rb);
    if (st) fprintf(stderr, "N %d: %s\n", n, sd_status_message(st));
    double ps = (double)n * steps / wall;
    const long nc = sd_world_contact_count(w);
    double ratio = 0.0;
    char trial[48] = "";
    if (sd_front_prefetch_verdict(w, &ratio) >= 0) snprintf(trial, sizeof trial, " (trial: on/off %.3f)", ratio);
    printf("N %8d  %ssteps %6ld  wall %8.3f s  particle-steps/s %.4e  ns/particle-step %6.1f  contacts/sphere %.2f  "
           "ns/contact-step %5.1f  rebuilds %ld neighbor %.3f s  front-prefetch %s%s\n",
           n, what, steps, wall, ps, 1e9 / ps, 2.0 * nc / n, 1e9 * wall / ((double)(nc > 0 ? nc : 1) * steps),
           k1.rebuilds - k0.rebuilds, k1.rebuild - k0.rebuild, sd_front_prefetch_on(w) ? "on" : "off", trial);
    if (stages && k1.rebuilds > k0.rebuilds) {
        printf("  rebuild stages, ms a rebuild:");
        for (int k = 0; k < SD_RB_STAGES; k++)
            printf(" %s %.1f", sd_neighbor_stage_name(k), 1e3 * rb[k] / (double)(k1.rebuilds - k0.rebuilds));
        printf("\n");
    }
    fflush(stdout);
    sd_world_destroy(w);
    return ps;
}

static double run_case(int n, long steps)
{
    const double tile = 0.3; /* the reservoir: x in [0, 0.3], y in [0, 0.3] */
    int nt = 1;
    while (nt * nt * g_n < n)
        nt++;
    int ntot = nt * nt * g_n;
    grain *all = malloc((size_t)ntot * sizeof(grain));
    if (!all) return 0;
    int k = 0;
    for (int ty = 0; ty < nt; ty++)
        for (int tx = 0; tx < nt; tx++)
            for (int i = 0; i < g_n; i++) {
                grain q = g_src[i];
                q.x += tx * tile;
                q.y += ty * tile;
                all[k++] = q;
            }
    qsort(all, (size_t)ntot, sizeof(grain), cmp_y);
    sd_world *w = new_world();
    if (!w) {
        free(all);
        return 0;
    }
    double ymax = 0;
    for (int i = 0; i < n; i++) {
        add_grain(w, &all[i], 0.0, 0.0);
        if (all[i].y + 0.5 * all[i].d > ymax) ymax = all[i].y + 0.5 * all[i].d;
    }
    free(all);
    open_box(w, nt * tile, ymax, 0.5);
    /* warm-up past the first 1 ms rebuild, as --same: candidate lists, history, caches, and
     * the buffers that grow once (their pages first touched; at 1e6 the first rebuild took
     * ~330 ms more than the next ones, performance pass P41, in the git history) */
    return time_world(w, n, "", 110, steps);
}

/* --same: the settled unit (its spheres and its box) and how each size is timed */
static grain *u_g;
static int u_n;
static double u_ax, u_ay;
static const double u_gap = 0.002, u_h = 0.3;

/* the unit: the bed's spheres with their centres in its corner [0, s)^2, s the smallest
 * multiple of 5 mm that holds 1000 of them (or the whole bed), settled in a box that holds them
 * (walls at 0 and at their furthest extent) for `settle` steps */
static int make_unit(long settle)
{
    u_g = malloc((size_t)g_n * sizeof(grain));
    if (!u_g) return -1;
    for (double s = 0.1; u_n < 1000 && u_n < g_n; s += 0.005) {
        u_n = 0;
        u_ax = u_ay = 0.0;
        for (int i = 0; i < g_n; i++) {
            const grain q = g_src[i];
            if (q.x >= s || q.y >= s) continue;
            u_g[u_n++] = q;
            if (q.x + 0.5 * q.d > u_ax) u_ax = q.x + 0.5 * q.d;
            if (q.y + 0.5 * q.d > u_ay) u_ay = q.y + 0.5 * q.d;
        }
    }
    int *gid = malloc((size_t)(u_n > 0 ? u_n : 1) * sizeof(int));
    sd_world *w = u_n > 0 && gid ? new_world() : NULL;
    if (!w) {
        free(gid);
        return -1;
    }
    for (int i = 0; i < u_n; i++)
        gid[i] = add_grain(w, &u_g[i], 0.0, 0.0);
    open_box(w, u_ax, u_ay, u_h);
    sd_status st = sd_world_run(w, settle);
    const double ke = sd_world_kinetic_energy(w);
    /* the settled centres, found by their gids */
    for (int i = 0; i < u_n && !st; i++) {
        sd_body_state b;
        st = sd_world_body(w, gid[i], &b);
        u_g[i].x = b.pos.x, u_g[i].y = b.pos.y, u_g[i].z = b.pos.z;
    }
    free(gid);
    sd_world_destroy(w);
    if (st) {
        fprintf(stderr, "unit: %s\n", sd_status_message(st));
        return -1;
    }
    printf("unit: %d spheres in %.4f m x %.4f m, settled %ld steps (kinetic energy %.3e J at the end)\n", u_n, u_ax,
           u_ay, settle, ke);
    return 0;
}

/* about n spheres as whole copies of the unit, each in its own walls, timed over `steps` */
static double run_same(int n, long steps)
{
    int nu = (n + u_n / 2) / u_n;
    if (nu < 1) nu = 1;
    int nx = 1;
    while (nx * nx < nu)
        nx++;
    const int ny = (nu + nx - 1) / nx;
    const double px = u_ax + u_gap, py = u_ay + u_gap, X = nx * px, Y = ny * py;
    sd_world *w = new_world();
    if (!w) return 0;
    for (int c = 0; c < nu; c++)
        for (int i = 0; i < u_n; i++)
            add_grain(w, &u_g[i], (c % nx) * px, (c / nx) * py);
    /* one floor; each column and row of copies between its own two walls */
    quad(w, v3(0, 0, 0), v3(X, 0, 0), v3(X, Y, 0), v3(0, Y, 0));
    for (int i = 0; i < nx; i++)
        for (int e = 0; e < 2; e++) {
            const double x = i * px + e * u_ax;
            quad(w, v3(x, 0, 0), v3(x, Y, 0), v3(x, Y, u_h), v3(x, 0, u_h));
        }
    for (int j = 0; j < ny; j++)
        for (int e = 0; e < 2; e++) {
            const double y = j * py + e * u_ay;
            quad(w, v3(0, y, 0), v3(X, y, 0), v3(X, y, u_h), v3(0, y, u_h));
        }
    /* warm-up past the first 1 ms rebuild: the lists, the springs and the buffers that grow
     * once (their pages first touched) are made before the timing */
    char what[32];
    snprintf(what, sizeof what, "copies %4d  ", nu);
    return time_world(w, nu * u_n, what, 110, steps);
}

int main(int argc, char **argv)
{
    long steps = 2000;
    int threads = 1, big = 0, only = 0, same = 0;
    const char *path = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--big"))
            big = 1;
        else if (!strcmp(argv[i], "--same"))
            same = 1;
        else if (!strcmp(argv[i], "--stages"))
            stages = 1;
        else if (!strcmp(argv[i], "--only") && i + 1 < argc)
            only = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--ab") && i + 1 < argc)
            ab_name = argv[++i];
        else if (!strcmp(argv[i], "--ab-groups") && i + 1 < argc)
            ab_groups = atoi(argv[++i]);
        else if (!path)
            path = argv[i];
        else
            steps = atol(argv[i]);
    }
    if (!path || read_data(path)) {
        fprintf(stderr,
                "usage: %s SETTLED.data [steps] [--threads N] [--big] [--only N] [--same] [--stages] [--ab "
                "prefetch|avx512|springs|slot_sqm|ext "
                "[--ab-groups G]]\n",
                argv[0]);
        return 2;
    }
    if (ab_name) {
        if (strcmp(ab_name, "prefetch") && strcmp(ab_name, "avx512") && strcmp(ab_name, "springs_list") &&
            strcmp(ab_name, "slot_sqm") && strcmp(ab_name, "ext_skip")) {
            fprintf(stderr,
                    "%s: --ab: no switch named '%s'; the switches: prefetch avx512 springs_list slot_sqm ext_skip\n",
                    argv[0], ab_name);
            return 2;
        }
        if (ab_groups < 1 || ab_groups > 1000) {
            fprintf(stderr, "%s: --ab-groups must be between 1 and 1000\n", argv[0]);
            return 2;
        }
        if (!strcmp(ab_name, "avx512") && sd_cpu_simd_level() < SD_SIMD_AVX512) {
            fprintf(stderr, "%s: --ab avx512: this CPU has no AVX-512 (both forms would be AVX2)\n", argv[0]);
            return 2;
        }
    }
    g_threads = threads;
    /* the sizes: 1e3, 1e4, 1e5 (steps, steps/2, steps/10), and with --big 1e6 (steps/20: with
     * the default 2000 steps, 100, so that each size takes its share of the rebuilds every 1 ms,
     * which at 1e6 take ~1.5 s each; until §P37, 40 steps without --same, which held one rebuild
     * or none as the warm-up ended) */
    double (*run)(int, long) = run_case;
    const long big_div = 20;
    if (same) {
        printf("threads %d, copies of one settled unit of the bed of %d spheres, each in its own walls\n", threads,
               g_n);
        if (make_unit(50000)) return 1;
        run = run_same;
    } else {
        printf("threads %d, bed of %d spheres tiled\n", threads, g_n);
    }
    if (only > 0) return run(only, steps) > 0 ? 0 : 1;
    run(1000, steps);
    run(10000, steps / 2);
    run(100000, steps / 10);
    if (big) run(1000000, steps / big_div > 10 ? steps / big_div : 10);
    return 0;
}
