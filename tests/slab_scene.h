/* The scene of the decomposition's tests (test_slabs, mpi_slabs): a pile of spheres and logs in a
 * box along x, a fixed grid over it, and a push downstream. Header-only, static. */
#ifndef SD_TEST_SLAB_SCENE_H
#define SD_TEST_SLAB_SCENE_H

#include <string.h>

#include "check.h"
#include "scenes.h"
#include "core/vmath.h"
#include "sabodem.h"

#define NX 32
#define NY 6
#define NZ 4
#define SP 0.0115

static inline sd_grid_def grid_of(const sd_world *w)
{
    sd_grid_def g;
    g.cell = sd_world_min_grid_cell(w);
    g.lo = v3(-0.06, -0.06, -0.06);
    g.nx = (int)((NX * SP + 0.12) / g.cell) + 1;
    g.ny = (int)((NY * SP + 0.12) / g.cell) + 1;
    g.nz = (int)((0.25 + 0.12) / g.cell) + 1;
    return g;
}

/* NX x NY x NZ spheres on a jittered lattice in a box NX SP long,
 * and eight logs 40 mm long on top; gravity 15° along x (the default); test_slabs throws them
 * downstream (give_speed) */
static inline sd_world *make_scene(sd_grid_def *g)
{
    scene_rng = 0x9E3779B97F4A7C15ULL;
    sd_world_def def = sd_world_def_default();
    def.threads = 1;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    scene_open_box(w, NX * SP, NY * SP, 0.25);
    scene_lattice(w, NX, NY, NZ, SP);
    for (int q = 0; q < 8; q++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.pos = v3(0.03 + 0.04 * q, 0.02 + 0.012 * (q % 4), 0.06);
        c.axis = v3(scene_urand() - 0.5, scene_urand() - 0.5, 0.3 * (scene_urand() - 0.5));
        c.length = 0.04;
        c.radius = 0.004;
        c.vel = v3(0.3, 0, -0.3);
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    *g = grid_of(w);
    CHECK(sd_world_set_fixed_grid(w, g) == SD_OK);
    return w;
}

static inline void give_speed(sd_world *w, double vx)
{
    /* every body's velocity along x raised by vx, through its record (the record's own field) */
    const size_t sz = sd_body_record_size();
    char *rec = malloc(sz);
    const int n = sd_world_body_count(w);
    for (int gid = 0; gid < n; gid++) {
        sd_body_state b;
        CHECK(sd_world_body(w, gid, &b) == SD_OK);
        if (b.fixed) continue;
        CHECK(sd_world_body_record(w, gid, rec) == SD_OK);
        /* the velocity follows the position in the record: find it by its value */
        for (size_t off = 0; off + sizeof(sd_vec3) <= sz; off += 1) {
            sd_vec3 v;
            memcpy(&v, rec + off, sizeof v);
            if (memcmp(&v, &b.vel, sizeof v) == 0) {
                v.x += vx;
                memcpy(rec + off, &v, sizeof v);
                break;
            }
        }
        CHECK(sd_world_body_put(w, rec, 0) == SD_OK);
    }
    free(rec);
}

#endif
