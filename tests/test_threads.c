/* OpenMP identity (issue: speed): the reduced flume with logs, every loop forced parallel,
 * gives the same bits on 1 and 2 threads, through packing, gate removal and flow. */
#include <string.h>

#include "build.h"
#include "check.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

static uint64_t run(int threads, long *contacts)
{
#ifdef _OPENMP
    omp_set_num_threads(threads);
#else
    (void)threads;
#endif
    sd_scenario s;
    /* a coarser step so that the spheres land on the bed and pile at the gate within the test */
    const char *sets[] = {"solver.dt=4e-5"};
    if (sd_scenario_load(&s, "examples/flume_small.yaml", sets, 1, stderr)) return 0;
    s.world.parallel_min = 0; /* parallel even for this small scene */
    sd_world *w;
    if (sd_world_create(&s.world, &w)) return 0;
    sd_build_info info;
    if (sd_build_scene(w, &s, &info, stderr)) return 0;
    CHECK(sd_world_run(w, 6000) == SD_OK);
    sd_world_set_group_active(w, SD_GROUP_GATE, 0);
    CHECK(sd_world_run(w, 2000) == SD_OK);
    *contacts = sd_world_contact_count(w);
    uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    sd_scenario_free(&s);
    return h;
}

int main(void)
{
    long c1 = 0, c2 = 0;
    uint64_t h1 = run(1, &c1);
    uint64_t h2 = run(2, &c2);
    printf("1 thread: hash %016llx, %ld contacts; 2 threads: hash %016llx, %ld contacts\n", (unsigned long long)h1, c1,
           (unsigned long long)h2, c2);
    CHECK(h1 != 0);
    CHECK(c1 > 100);
    CHECK(h1 == h2);
    CHECK(c1 == c2);
    return check_report("test_threads");
}
