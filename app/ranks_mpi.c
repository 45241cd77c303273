/* app/ranks.h over MPI: started only under an MPI launcher. */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

#include "ranks.h"

static int launched_by_mpi(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK");
}

int app_ranks_start(app_ranks *r, int *argc, char ***argv)
{
    r->rank = 0;
    r->size = 1;
    r->active = 0;
    if (!launched_by_mpi()) return 0;
    if (MPI_Init(argc, argv) != MPI_SUCCESS) {
        fprintf(stderr, "sabodem: MPI_Init failed\n");
        return 2;
    }
    r->active = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &r->rank);
    MPI_Comm_size(MPI_COMM_WORLD, &r->size);
    return 0;
}

int app_ranks_max(const app_ranks *r, int code)
{
    if (!r->active) return code;
    int all = code;
    MPI_Allreduce(&code, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return all;
}

void app_ranks_finish(app_ranks *r)
{
    if (r->active) MPI_Finalize();
    r->active = 0;
}
