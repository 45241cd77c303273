/* Determinism: the same input twice gives the same sd_world_state_hash; 1 and 2 OpenMP threads
 * give the same hash (the pile is above SD_OMP_MIN_ITEMS, so the loops really run in parallel);
 * rebuilding the candidate lists every step instead of by margin changes only rounding, so the
 * final contact count agrees within 2 % and positions within a small tolerance. The moves skip
 * the store's external forces while none was set: the same hash as reading its zeros, and one
 * body's force set is read whether or not the skip is on. */
#include <string.h>

#include "check.h"
#include "scenes.h"
#include "core/vmath.h"
#include "sabodem.h"
#include "world_internal.h" /* (sd_world_switch) */

#ifdef _OPENMP
#include <omp.h>
#endif

/* 2400 spheres of 11.2–12.2 mm on a jittered lattice of 11.5 mm, touching and slightly overlapping, with random
 * velocities, in a box of triangles; a few logs on top. */
static sd_world *make_pile(int threads, int rebuild_every_step)
{
    scene_rng = 0x9E3779B97F4A7C15ULL;
    sd_world_def def = sd_world_def_default(); /* paper springs, 15° gravity, dt 1e-5 */
    def.threads = threads;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    sd_world_set_rebuild_every_step(w, rebuild_every_step);
    const int nx = 20, ny = 12, nz = 10;
    const double sp = 0.0115;
    scene_open_box(w, nx * sp, ny * sp, 0.2);
    scene_lattice(w, nx, ny, nz, sp);
    for (int q = 0; q < 6; q++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.pos = v3(0.03 + 0.035 * q, 0.03 + 0.01 * (q % 3), 0.135);
        c.axis = v3(scene_urand() - 0.5, scene_urand() - 0.5, 0.3 * (scene_urand() - 0.5));
        c.vel = v3(0, 0, -0.5);
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    return w;
}

typedef struct {
    uint64_t hash;
    long contacts;
    sd_vec3 *pos; /* by gid */
    int n;
} result;

static result run(int threads, int rebuild_every_step, long steps)
{
#ifdef _OPENMP
    if (threads > 0) omp_set_num_threads(threads);
#endif
    sd_world *w = make_pile(threads, rebuild_every_step);
    sd_status st = sd_world_run(w, steps);
    CHECK(st == SD_OK);
    result r;
    r.hash = sd_world_state_hash(w);
    r.contacts = sd_world_contact_count(w);
    r.n = sd_world_body_count(w);
    r.pos = malloc((size_t)r.n * sizeof(sd_vec3));
    for (int g = 0; g < r.n; g++) {
        sd_body_state b;
        CHECK(sd_world_body(w, g, &b) == SD_OK);
        r.pos[g] = b.pos;
    }
    sd_world_destroy(w);
    return r;
}

/* the pile on one thread, the store's external forces skipped while none is set (skip) or
 * always read, body gid 5 given fx along x when fx is not 0 */
static uint64_t run_ext(int skip, double fx, long steps)
{
    sd_world *w = make_pile(1, 0);
    sd_world_switch(w, SD_SW_EXT_SKIP, skip);
    if (fx != 0.0) CHECK(sd_world_set_external_force(w, 5, v3(fx, 0.0, 0.0)) == SD_OK);
    CHECK(sd_world_run(w, steps) == SD_OK);
    const uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    return h;
}

int main(void)
{
    const long steps = 300;
    int max_threads = 1;
#ifdef _OPENMP
    max_threads = omp_get_max_threads();
#endif
    /* single-threaded except where threads are the point: an oversubscribed machine makes
     * OpenMP barriers very slow */
    result a = run(1, 0, steps);
    result b = run(1, 0, steps);
    result t2 = run(2, 0, steps);
    result e = run(1, 1, steps);
    printf("bodies %d, %ld steps; hashes: run1 %016llx run2 %016llx 2 threads %016llx (runtime default threads "
           "%d)\n",
           a.n, steps, (unsigned long long)a.hash, (unsigned long long)b.hash, (unsigned long long)t2.hash,
           max_threads);
    CHECK(a.n == 2406);
    CHECK(a.contacts > 2048); /* the pair loop runs in parallel */
    CHECK(a.hash == b.hash);
    CHECK(a.hash == t2.hash);
    CHECK(a.contacts == t2.contacts);
    double dmax = 0.0;
    for (int g = 0; g < a.n; g++) dmax = fmax(dmax, v3_dist(a.pos[g], e.pos[g]));
    printf("rebuild every step vs by margin: contacts %ld vs %ld, hash %s, max position difference %.3g m\n",
           e.contacts, a.contacts, e.hash == a.hash ? "equal" : "differs", dmax);
    CHECK(labs(e.contacts - a.contacts) <= 0.02 * a.contacts);
    CHECK(dmax < 1e-6);
    const uint64_t read0 = run_ext(0, 0.0, steps), skip1 = run_ext(1, 1e-3, steps), read1 = run_ext(0, 1e-3, steps);
    printf("external forces: none set, read as zeros %016llx (skipped: run1); 1 mN on one body %016llx skip on, "
           "%016llx read\n",
           (unsigned long long)read0, (unsigned long long)skip1, (unsigned long long)read1);
    CHECK(read0 == a.hash);
    CHECK(skip1 == read1 && skip1 != a.hash);
    free(a.pos);
    free(b.pos);
    free(t2.pos);
    free(e.pos);
    return check_report("test_determinism");
}
