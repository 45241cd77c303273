/* The candidate rebuild alone (SPEC §4: every t_reset), timed on a saved state: a checkpoint
 * (for instance the paper's flow-end one, `sabodem run ... --checkpoint-at flow_end`) is read,
 * stepped a few times, then rebuilt R times in a row without stepping, so every rebuild does
 * the same work (the store already in cell order, the bed's cache held, the same springs
 * carried). Prints the median and the quartiles of the wall time per rebuild: a change to the
 * rebuild can be judged by A/B runs of this, which move far less than a whole run's timers on
 * a shared machine.
 * With --steps K, K steps (not timed) come before each rebuild: the store then leaves cell
 * order a little, and the springs change, as between the rebuilds of a run. The mean time of
 * each of the rebuild's stages (sd_neighbor_stages_take) is printed too.
 *   usage: bench_rebuild CHECKPOINT [R] [--threads N] [--steps K] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io_checkpoint.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* op(w) R times, each timed into t[r], with K untimed steps before each (a step rebuilds when
 * its lists say so); the rebuild's stages of the timed calls summed into stage (when not NULL) */
static sd_status timed(sd_world *w, sd_status (*op)(sd_world *), int reps, int steps, double *t, double *stage)
{
    sd_status st = SD_OK;
    double s0[SD_RB_STAGES];
    for (int r = 0; r < reps && !st; r++) {
        for (int s = 0; s < steps && !st; s++)
            st = sd_world_step(w);
        if (st) break;
        sd_neighbor_stages_take(s0); /* (the steps' own rebuilds left out) */
        const double t0 = sd_now();
        st = op(w);
        t[r] = sd_now() - t0;
        sd_neighbor_stages_take(s0);
        if (stage)
            for (int k = 0; k < SD_RB_STAGES; k++)
                stage[k] += s0[k];
    }
    return st;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    int reps = 200, threads = 0, steps = 0;
    for (int k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--threads") && k + 1 < argc)
            threads = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--steps") && k + 1 < argc)
            steps = atoi(argv[++k]);
        else if (!path)
            path = argv[k];
        else
            reps = atoi(argv[k]);
    }
    if (!path || reps < 1) {
        fprintf(stderr, "usage: %s CHECKPOINT [R] [--threads N] [--steps K]\n", argv[0]);
        return 2;
    }
    sd_world *w = NULL;
    char msg[512] = "";
    sd_status st = sd_checkpoint_read(path, &w, NULL, NULL, msg, sizeof msg);
    if (st) {
        fprintf(stderr, "%s\n", msg[0] ? msg : sd_status_message(st));
        return 1;
    }
    sd_tuning tuning;
    sd_tuning_from_env(&tuning, NULL, 0);
    sd_world_set_tuning(w, &tuning);
    if (threads > 0) {
        sd_world_set_threads(w, threads);
        w->def.threads = threads;
    }
    threads = sd_world_threads(w);
    /* a few steps: the lists, the owners and the bed's cache made as a run has them */
    for (int s = 0; s < 5 && !st; s++)
        st = sd_world_step(w);
    for (int s = 0; s < 3 && !st; s++)
        st = sd_neighbor_rebuild(w);
    double *t = malloc((size_t)reps * sizeof *t), *tn = malloc((size_t)reps * sizeof *tn);
    if (!t || !tn) {
        fprintf(stderr, "%s: out of memory\n", path);
        free(t);
        free(tn);
        sd_world_destroy(w);
        return 1;
    }
    double stage[SD_RB_STAGES] = {0};
    st = timed(w, sd_neighbor_rebuild, reps, steps, t, stage);
    /* the near pairs remade alone, R times (after a step: the lists as a run has them) */
    if (!st) st = sd_world_step(w);
    if (!st) st = timed(w, sd_contact_near_remake, reps, 0, tn, NULL);
    if (st) {
        fprintf(stderr, "%s: %s\n", path, sd_status_message(st));
        free(t);
        free(tn);
        sd_world_destroy(w);
        return 1;
    }
    qsort(tn, (size_t)reps, sizeof *tn, cmp_double);
    qsort(t, (size_t)reps, sizeof *t, cmp_double);
    printf("bodies %d (moving %d) candidates %d+%d threads %d rebuilds %d | per rebuild: median %.3f ms, "
           "quartiles %.3f-%.3f ms, fastest %.3f ms | bed cache used %ld\n",
           w->b.n, w->mov_n, w->bb.n, w->bt.n, threads, reps, 1e3 * t[reps / 2], 1e3 * t[reps / 4],
           1e3 * t[3 * reps / 4], 1e3 * t[0], w->bed.used);
    printf("per rebuild, by stage (means):");
    for (int k = 0; k < SD_RB_STAGES; k++)
        printf(" %s %.3f", sd_neighbor_stage_name(k), 1e3 * stage[k] / reps);
    printf(" ms\n");
    printf("near pairs remade: median %.3f ms, quartiles %.3f-%.3f ms, fastest %.3f ms (%d near pairs of %d)\n",
           1e3 * tn[reps / 2], 1e3 * tn[reps / 4], 1e3 * tn[3 * reps / 4], 1e3 * tn[0], sd_contact_near_count(w), w->bb.n);
    free(tn);
    printf("grid %d x %d x %d cells (cell %.4f m), %d entries (bed %d in %d cells)\n", w->grid.nx, w->grid.ny,
           w->grid.nz, w->grid.cell, w->grid.cell_start[w->grid.nx * w->grid.ny * w->grid.nz], w->bed.nitems,
           w->bed.ncells);
    free(t);
    sd_world_destroy(w);
    return 0;
}
