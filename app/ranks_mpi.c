/* app/ranks.h over MPI: started only under an MPI launcher. */
#include <mpi.h>
#include <stdio.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "ranks.h"
#include "run.h"

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

/* ---- the transport of a decomposed run (sd_run_comm): byte blocks over MPI_COMM_WORLD ---- */

static int comm_allgather(void *ctx, const void *mine, size_t len, void *all)
{
    (void)ctx;
    if (len > (size_t)INT_MAX) return -1;
    return MPI_Allgather(mine, (int)len, MPI_BYTE, all, (int)len, MPI_BYTE, MPI_COMM_WORLD) == MPI_SUCCESS ? 0 : -1;
}

/* counts and displacements from byte lengths; -1 past what MPI's int counts hold */
static int displacements(int n, const size_t *len, int *count, int *disp, size_t *total)
{
    size_t t = 0;
    for (int r = 0; r < n; r++) {
        if (len[r] > (size_t)INT_MAX || t > (size_t)INT_MAX) return -1;
        count[r] = (int)len[r];
        disp[r] = (int)t;
        t += len[r];
    }
    *total = t;
    return t > (size_t)INT_MAX ? -1 : 0;
}

static int comm_allgatherv(void *ctx, const void *mine, size_t len, void **all, size_t *lens)
{
    (void)ctx;
    int n = 0;
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    unsigned long long l = len, *ls = malloc((size_t)n * sizeof *ls);
    int *count = malloc((size_t)n * sizeof(int)), *disp = malloc((size_t)n * sizeof(int));
    int bad = !ls || !count || !disp;
    *all = NULL;
    if (MPI_Allgather(&l, 1, MPI_UNSIGNED_LONG_LONG, ls ? ls : &l, ls ? 1 : 0, MPI_UNSIGNED_LONG_LONG,
                      MPI_COMM_WORLD) != MPI_SUCCESS)
        bad = 1;
    size_t total = 0;
    for (int r = 0; r < n && !bad; r++)
        lens[r] = (size_t)ls[r];
    if (!bad && displacements(n, lens, count, disp, &total)) bad = 1;
    if (!bad) *all = malloc(total + 1);
    if (!bad && !*all) bad = 1;
    /* (a rank that cannot go on still takes part, with nothing, so that none waits forever) */
    if (MPI_Allgatherv(mine, bad ? 0 : (int)len, MPI_BYTE, bad ? NULL : *all, bad ? NULL : count, bad ? NULL : disp,
                       MPI_BYTE, MPI_COMM_WORLD) != MPI_SUCCESS)
        bad = 1;
    free(ls);
    free(count);
    free(disp);
    if (bad) {
        free(*all);
        *all = NULL;
    }
    return bad ? -1 : 0;
}

static int comm_alltoallv(void *ctx, const void *const *out, const size_t *outlen, void **in, size_t *inlen)
{
    (void)ctx;
    int n = 0;
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    unsigned long long *so = malloc((size_t)n * sizeof *so), *ri = malloc((size_t)n * sizeof *ri);
    int *sc = malloc((size_t)n * sizeof(int)), *sd = malloc((size_t)n * sizeof(int));
    int *rc = malloc((size_t)n * sizeof(int)), *rd = malloc((size_t)n * sizeof(int));
    int bad = !so || !ri || !sc || !sd || !rc || !rd;
    size_t stot = 0, rtot = 0;
    char *sbuf = NULL;
    *in = NULL;
    for (int r = 0; r < n && !bad; r++)
        so[r] = outlen[r];
    if (bad || MPI_Alltoall(so, 1, MPI_UNSIGNED_LONG_LONG, ri, 1, MPI_UNSIGNED_LONG_LONG, MPI_COMM_WORLD) != MPI_SUCCESS)
        bad = 1;
    for (int r = 0; r < n && !bad; r++)
        inlen[r] = (size_t)ri[r];
    if (!bad && (displacements(n, outlen, sc, sd, &stot) || displacements(n, inlen, rc, rd, &rtot))) bad = 1;
    if (!bad) {
        sbuf = malloc(stot + 1);
        *in = malloc(rtot + 1);
        if (!sbuf || !*in) bad = 1;
    }
    for (int r = 0; r < n && !bad; r++)
        if (outlen[r]) memcpy(sbuf + sd[r], out[r], outlen[r]);
    if (!bad && MPI_Alltoallv(sbuf, sc, sd, MPI_BYTE, *in, rc, rd, MPI_BYTE, MPI_COMM_WORLD) != MPI_SUCCESS) bad = 1;
    free(sbuf);
    free(so);
    free(ri);
    free(sc);
    free(sd);
    free(rc);
    free(rd);
    if (bad) {
        free(*in);
        *in = NULL;
    }
    return bad ? -1 : 0;
}

int app_ranks_comm(const app_ranks *r, struct sd_run_comm *comm)
{
    if (!r->active) return -1;
    comm->rank = r->rank;
    comm->size = r->size;
    comm->ctx = NULL;
    comm->allgather = comm_allgather;
    comm->allgatherv = comm_allgatherv;
    comm->alltoallv = comm_alltoallv;
    return 0;
}
