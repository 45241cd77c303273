/* Scenes shared by the tests: a jittered lattice of spheres dropped into an open box of
 * triangles (test_determinism's pile, test_reference's bed), and the random numbers that jitter
 * it. Header-only, static: each test program is one translation unit. */
#ifndef SD_TEST_SCENES_H
#define SD_TEST_SCENES_H

#include <stdint.h>

#include "check.h"
#include "core/vmath.h"
#include "sabodem.h"

static uint64_t scene_rng = 0x9E3779B97F4A7C15ULL;

/* uniform in [0, 1) (xorshift64*) */
static inline double scene_urand(void)
{
    scene_rng ^= scene_rng >> 12;
    scene_rng ^= scene_rng << 25;
    scene_rng ^= scene_rng >> 27;
    return (double)((scene_rng * 2685821657736338717ULL) >> 11) / 9007199254740992.0;
}

static inline void scene_quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d, int group)
{
    CHECK(sd_world_add_triangle(w, a, b, c, group) >= 0);
    CHECK(sd_world_add_triangle(w, a, c, d, group) >= 0);
}

/* an open box over [0, lx] x [0, ly], walls h high: the floor in group 0, the walls in 1 */
static inline void scene_open_box(sd_world *w, double lx, double ly, double h)
{
    scene_quad(w, v3(0, 0, 0), v3(lx, 0, 0), v3(lx, ly, 0), v3(0, ly, 0), 0);
    scene_quad(w, v3(0, 0, 0), v3(0, ly, 0), v3(0, ly, h), v3(0, 0, h), 1);
    scene_quad(w, v3(lx, 0, 0), v3(lx, ly, 0), v3(lx, ly, h), v3(lx, 0, h), 1);
    scene_quad(w, v3(0, 0, 0), v3(lx, 0, 0), v3(lx, 0, h), v3(0, 0, h), 1);
    scene_quad(w, v3(0, ly, 0), v3(lx, ly, 0), v3(lx, ly, h), v3(0, ly, h), 1);
}

/* nx x ny x nz spheres of radius 5.6-6.1 mm on a lattice of spacing sp from the floor up,
 * jittered by 0.4 mm, with random velocities (within 0.15 m/s) and spins (10 rad/s), each
 * tagged with its layer */
static inline void scene_lattice(sd_world *w, int nx, int ny, int nz, double sp)
{
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = 0.0056 + 0.0005 * scene_urand();
                s.pos = v3(sp * (i + 0.5) + 0.0004 * (scene_urand() - 0.5),
                           sp * (j + 0.5) + 0.0004 * (scene_urand() - 0.5),
                           0.0062 + sp * k + 0.0004 * (scene_urand() - 0.5));
                s.vel = v3(0.3 * (scene_urand() - 0.5), 0.3 * (scene_urand() - 0.5), 0.3 * (scene_urand() - 0.5));
                s.omega = v3(20 * (scene_urand() - 0.5), 20 * (scene_urand() - 0.5), 20 * (scene_urand() - 0.5));
                s.tag = k;
                CHECK(sd_world_add_sphere(w, &s) >= 0);
            }
}

#endif
