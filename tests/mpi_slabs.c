/* The decomposition over MPI ranks (built only with MPI; tests/slabs_mpi_test.sh runs it under
 * mpirun -np 1, 2, 3 and 4): test_slabs's scene, each rank one slab (src/slabs.c sd_slab), the
 * exchange by MPI (an allreduce for the rebuild, the work bins reduced on rank 0 and broadcast,
 * alltoallv for the records and springs), 1500 steps; every 250 steps rank 0 gathers the owned
 * bodies and springs and compares their hash with one world's, which it steps itself. Prints
 * one line per check; exits 1 when a hash differs, a step fails, or nothing migrated with
 * several ranks. */
#include <mpi.h>
#include <stdint.h>

#include "slab_scene.h"
#include "slabs.h"

static int rank, size;

static sd_status exchange(sd_slab *s, int any)
{
    sd_status st = sd_slab_pack(s, any);
    if (st) return st;
    int scount[SD_SLABS_MAX], rcount[SD_SLABS_MAX], sdisp[SD_SLABS_MAX], rdisp[SD_SLABS_MAX];
    const void *box[SD_SLABS_MAX];
    int stot = 0;
    for (int r = 0; r < size; r++) {
        size_t len;
        box[r] = sd_slab_outbox(s, r, &len);
        scount[r] = (int)len;
        sdisp[r] = stot;
        stot += scount[r];
    }
    MPI_Alltoall(scount, 1, MPI_INT, rcount, 1, MPI_INT, MPI_COMM_WORLD);
    int rtot = 0;
    for (int r = 0; r < size; r++) {
        rdisp[r] = rtot;
        rtot += rcount[r];
    }
    char *sbuf = malloc((size_t)stot + 1), *rbuf = malloc((size_t)rtot + 1);
    if (!sbuf || !rbuf) return SD_ERR_NOMEM;
    for (int r = 0; r < size; r++)
        memcpy(sbuf + sdisp[r], box[r], (size_t)scount[r]);
    MPI_Alltoallv(sbuf, scount, sdisp, MPI_BYTE, rbuf, rcount, rdisp, MPI_BYTE, MPI_COMM_WORLD);
    const void *in[SD_SLABS_MAX];
    size_t len[SD_SLABS_MAX];
    for (int r = 0; r < size; r++) {
        in[r] = rbuf + rdisp[r];
        len[r] = (size_t)rcount[r];
    }
    st = sd_slab_unpack(s, any, in, len);
    free(sbuf);
    free(rbuf);
    return st;
}

static sd_status step(sd_slab *s, double *bins, double *sum)
{
    int mine = sd_slab_wants_rebuild(s), any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    if (any && sd_slab_balance_due(s)) {
        /* the sums on rank 0, broadcast: every rank takes the same boundaries */
        const int nb = sd_slab_bins(s);
        sd_slab_work_bins(s, bins);
        MPI_Reduce(bins, sum, nb, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
        MPI_Bcast(sum, nb, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        sd_slab_balance(s, sum);
    }
    sd_status st = exchange(s, any);
    if (!st) st = sd_slab_step_world(s);
    return st;
}

/* the owned bodies and springs of every rank, hashed on rank 0 */
static uint64_t gathered_hash(sd_slab *s)
{
    void *recs;
    sd_spring *sp;
    int nb, ns;
    if (sd_slab_state(s, &recs, &nb, &sp, &ns)) MPI_Abort(MPI_COMM_WORLD, 1);
    const int rsz = (int)sd_body_record_size(), ssz = (int)sizeof(sd_spring);
    int mine[2] = {nb * rsz, ns * ssz}, *all = malloc(2 * (size_t)size * sizeof(int));
    MPI_Gather(mine, 2, MPI_INT, all, 2, MPI_INT, 0, MPI_COMM_WORLD);
    int rc[SD_SLABS_MAX], rd[SD_SLABS_MAX], sc[SD_SLABS_MAX], sdp[SD_SLABS_MAX], rt = 0, st = 0;
    for (int r = 0; r < size && rank == 0; r++) {
        rc[r] = all[2 * r], rd[r] = rt, rt += rc[r];
        sc[r] = all[2 * r + 1], sdp[r] = st, st += sc[r];
    }
    char *R = rank == 0 ? malloc((size_t)rt + 1) : NULL, *S = rank == 0 ? malloc((size_t)st + 1) : NULL;
    MPI_Gatherv(recs, mine[0], MPI_BYTE, R, rc, rd, MPI_BYTE, 0, MPI_COMM_WORLD);
    MPI_Gatherv(sp, mine[1], MPI_BYTE, S, sc, sdp, MPI_BYTE, 0, MPI_COMM_WORLD);
    uint64_t h = rank == 0 ? sd_state_hash_records(R, rt / rsz, (const sd_spring *)S, st / ssz) : 0;
    free(R);
    free(S);
    free(all);
    free(recs);
    free(sp);
    return h;
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    int bad = size > SD_SLABS_MAX;
    /* every rank builds the same whole world and runs it to the same state (the same bits) */
    sd_grid_def g;
    sd_world *w = make_scene(&g);
    give_speed(w, 0.6);
    if (sd_world_run(w, 300) != SD_OK) bad = 1;
    double xb[SD_SLABS_MAX + 1];
    sd_slab_first_bounds(w, size, xb);
    sd_slabs_opts o = {.n = size, .rebalance = 2};
    sd_slab *s = NULL;
    if (!bad && sd_slab_create(w, &g, &o, rank, xb, &s) != SD_OK) bad = 1;
    if (rank == 0)
        sd_world_request_rebuild(w); /* (the reference: its pairs made afresh, as the slabs') */
    else
        sd_world_destroy(w);
    double *bins = malloc((size_t)g.nx * sizeof(double)), *sum = malloc((size_t)g.nx * sizeof(double));
    for (int q = 1; q <= 6 && s; q++) {
        for (int k = 0; k < 250; k++)
            if (step(s, bins, sum) != SD_OK) bad = 1;
        const uint64_t h = gathered_hash(s);
        if (rank == 0) {
            if (sd_world_run(w, 250) != SD_OK) bad = 1;
            const uint64_t h1 = sd_world_state_hash_canonical(w);
            printf("step %4d, %d ranks: %016llx, one world %016llx %s\n", 250 * q, size, (unsigned long long)h,
                   (unsigned long long)h1, h == h1 ? "same" : "DIFFERENT");
            bad |= h != h1;
        }
    }
    long mig = s ? sd_slab_stats(s)->migrations : 0, all_mig = 0;
    MPI_Reduce(&mig, &all_mig, 1, MPI_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
    double bytes = s ? sd_slab_stats(s)->bytes : 0.0, all_bytes = 0.0;
    MPI_Reduce(&bytes, &all_bytes, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank == 0) {
        double x[SD_SLABS_MAX + 1];
        if (s) sd_slab_bounds(s, x);
        printf("%d ranks: %ld migrations, %.0f kB sent, boundaries", size, all_mig, all_bytes / 1e3);
        for (int j = 1; j < size && s; j++)
            printf(" %.4f", x[j]);
        printf("\n");
        if (size > 1 && all_mig == 0) bad = 1;
        sd_world_destroy(w);
    }
    sd_slab_destroy(s);
    free(bins);
    free(sum);
    int any_bad = 0;
    MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    MPI_Finalize();
    return any_bad || check_failures ? 1 : 0;
}
