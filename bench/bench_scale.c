/* Scaling benchmark (issues: engine core, speed): the settled dense bed of the flume benchmark
 * (a LAMMPS-format data file of 4619 spheres of the paper's four sizes at rest in the 0.3 m x
 * 0.3 m reservoir, as written by bench/run.sh or `bench_flume --write-settled`) tiled side by
 * side over the floor and cut to N spheres (the N with the smallest y), in an open box of
 * triangles, gravity vertical. The bed depth and the local structure are those of the flume's
 * dense bed at every N, but not the contact count per sphere: a small bed is mostly edge (the
 * cut, and the walls, whose contacts are not counted), and the count grows with N (2.85 at
 * 1e3, 3.7-3.8 at 1e4, 4.0 at 1e5, 4.4 at 1e6 on 2026-11-27), so the cost per contact-step is
 * printed beside the cost per particle-step. After a short warm-up, `steps` steps are timed.
 * usage: bench_scale SETTLED.data [steps] [--threads N] [--big] [--only N]
 *   N = 1e3, 1e4, 1e5 (steps, steps/2, steps/10) and with --big 1e6 (steps/50); --only N runs
 *   that one size for `steps` steps (for profiling). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "world_internal.h"

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
    sd_world_def d = sd_world_def_default();
    d.gravity = v3(0, 0, -9.81);
    sd_world *w;
    if (sd_world_create(&d, &w)) return 0;
    double ymax = 0, L = nt * tile, H = 0.5;
    for (int i = 0; i < n; i++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = 0.5 * all[i].d;
        s.pos = v3(all[i].x, all[i].y, all[i].z);
        s.tag = all[i].type - 1;
        sd_world_add_sphere(w, &s);
        if (all[i].y + s.radius > ymax) ymax = all[i].y + s.radius;
    }
    free(all);
    quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, ymax, 0), v3(0, ymax, 0));
    quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, 0, H), v3(0, 0, H));
    quad(w, v3(0, ymax, 0), v3(L, ymax, 0), v3(L, ymax, H), v3(0, ymax, H));
    quad(w, v3(0, 0, 0), v3(0, ymax, 0), v3(0, ymax, H), v3(0, 0, H));
    quad(w, v3(L, 0, 0), v3(L, ymax, 0), v3(L, ymax, H), v3(L, 0, H));
    sd_world_run(w, 50); /* warm-up: candidate lists, history, caches */
    const sd_world_timers k0 = sd_world_get_timers(w);
    double t0 = sd_now();
    sd_status st = sd_world_run(w, steps);
    double wall = sd_now() - t0;
    const sd_world_timers k1 = sd_world_get_timers(w);
    if (st) fprintf(stderr, "N %d: %s\n", n, sd_status_message(st));
    double ps = (double)n * steps / wall;
    const long nc = sd_world_contact_count(w);
    /* the rebuilds in the timed steps and their time (neighbor), and the cost per contact */
    printf("N %8d  steps %6ld  wall %8.3f s  particle-steps/s %.4e  ns/particle-step %6.1f  contacts/sphere %.2f  "
           "ns/contact-step %5.1f  rebuilds %ld neighbor %.3f s  front-prefetch %s\n",
           n, steps, wall, ps, 1e9 / ps, 2.0 * nc / n, 1e9 * wall / ((double)(nc > 0 ? nc : 1) * steps),
           k1.rebuilds - k0.rebuilds, k1.neighbor - k0.neighbor, sd_front_prefetch_on(w) ? "on" : "off");
    fflush(stdout);
    sd_world_destroy(w);
    return ps;
}

int main(int argc, char **argv)
{
    long steps = 2000;
    int threads = 1, big = 0, only = 0;
    const char *path = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--big"))
            big = 1;
        else if (!strcmp(argv[i], "--only") && i + 1 < argc)
            only = atoi(argv[++i]);
        else if (!path)
            path = argv[i];
        else
            steps = atol(argv[i]);
    }
    if (!path || read_data(path)) {
        fprintf(stderr, "usage: %s SETTLED.data [steps] [--threads N] [--big] [--only N]\n", argv[0]);
        return 2;
    }
#ifdef _OPENMP
    omp_set_num_threads(threads);
#endif
    printf("threads %d, bed of %d spheres tiled\n", threads, g_n);
    if (only > 0) return run_case(only, steps) > 0 ? 0 : 1;
    run_case(1000, steps);
    run_case(10000, steps / 2);
    run_case(100000, steps / 10);
    if (big) run_case(1000000, steps / 50 > 10 ? steps / 50 : 10);
    return 0;
}
