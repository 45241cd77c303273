/* app/ranks.h without MPI (the build found none): always one process. An `mpirun` of such a
 * build would start N independent sweeps over the same directory, so it is refused. */
#include <stdio.h>
#include <stdlib.h>

#include "ranks.h"

int app_ranks_start(app_ranks *r, int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    r->rank = 0;
    r->size = 1;
    r->active = 0;
    const char *n = getenv("OMPI_COMM_WORLD_SIZE");
    if (!n) n = getenv("PMI_SIZE");
    if (n && atoi(n) > 1) {
        fprintf(stderr, "sabodem: launched as %s MPI processes, but this build has no MPI (install libopenmpi-dev "
                        "and build again)\n", n);
        return 2;
    }
    return 0;
}

int app_ranks_max(const app_ranks *r, int code)
{
    (void)r;
    return code;
}

void app_ranks_finish(app_ranks *r) { (void)r; }

int app_ranks_comm(const app_ranks *r, struct sd_run_comm *comm)
{
    (void)r;
    (void)comm;
    return -1;
}
