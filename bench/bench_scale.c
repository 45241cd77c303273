/* Scaling benchmark: a dense bed of spheres of the paper's four sizes (SPEC §8 proportions) at
 * N = 1e3, 1e4, 1e5 (and 1e6 with --big) in a box of triangles whose floor grows with N, so the
 * bed depth stays the same. Spheres start on a jittered lattice at touching distance, settle
 * for a few hundred steps, then `steps` steps are timed. Cost per particle-step should be flat.
 * usage: bench_scale [steps] [--threads N] [--big] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

static void quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d)
{
    sd_world_add_triangle(w, a, b, c, 0);
    sd_world_add_triangle(w, a, c, d, 0);
}

static double run_case(int n, long steps)
{
    sd_world_def d = sd_world_def_default();
    d.gravity = v3(0, 0, -9.81);
    sd_world *w;
    if (sd_world_create(&d, &w)) return 0;
    /* lattice pitch 21 mm holds the largest sphere; bed 10 layers deep */
    const double pitch = 0.021;
    int layers = 10, side = (int)ceil(sqrt((double)n / layers));
    double L = side * pitch;
    const double diam[4] = {0.020, 0.015, 0.010, 0.005};
    const double frac[4] = {376.0 / 4619, 891.0 / 4619, 3010.0 / 4619, 342.0 / 4619};
    sd_rng rng = {42};
    int placed = 0;
    for (int k = 0; k < layers && placed < n; k++)
        for (int j = 0; j < side && placed < n; j++)
            for (int i = 0; i < side && placed < n; i++) {
                double u = sd_rng_uniform(&rng), acc = 0;
                int c = 3;
                for (int q = 0; q < 4; q++) {
                    acc += frac[q];
                    if (u < acc) {
                        c = q;
                        break;
                    }
                }
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = 0.5 * diam[c];
                s.pos = v3((i + 0.5) * pitch + sd_rng_range(&rng, -5e-4, 5e-4), (j + 0.5) * pitch,
                           (k + 0.5) * pitch + 0.0005);
                s.tag = c;
                sd_world_add_sphere(w, &s);
                placed++;
            }
    double H = (layers + 2) * pitch;
    quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, L, 0), v3(0, L, 0));
    quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, 0, H), v3(0, 0, H));
    quad(w, v3(0, L, 0), v3(L, L, 0), v3(L, L, H), v3(0, L, H));
    quad(w, v3(0, 0, 0), v3(0, L, 0), v3(0, L, H), v3(0, 0, H));
    quad(w, v3(L, 0, 0), v3(L, L, 0), v3(L, L, H), v3(L, 0, H));
    sd_world_run(w, 3000); /* collapse the lattice into a bed */
    double t0 = sd_now();
    sd_world_run(w, steps);
    double wall = sd_now() - t0;
    double ps = (double)n * steps / wall;
    printf("N %8d  steps %6ld  wall %8.3f s  particle-steps/s %.4e  ns/particle-step %6.1f  contacts/sphere %.2f\n", n,
           steps, wall, ps, 1e9 / ps, 2.0 * sd_world_contact_count(w) / n);
    fflush(stdout);
    sd_world_destroy(w);
    return ps;
}

int main(int argc, char **argv)
{
    long steps = 2000;
    int threads = 1, big = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--big")) big = 1;
        else steps = atol(argv[i]);
    }
#ifdef _OPENMP
    omp_set_num_threads(threads);
#endif
    printf("threads %d\n", threads);
    run_case(1000, steps);
    run_case(10000, steps);
    run_case(100000, steps / 4 > 100 ? steps / 4 : 100);
    if (big) run_case(1000000, 100);
    return 0;
}
