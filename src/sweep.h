/* `sabodem sweep`: a matrix of runs over scenario parameters and seeds (issue: experiment
 * matrix), run in parallel processes, resumable, summarised in CSV and figures. */
#ifndef SD_SWEEP_H
#define SD_SWEEP_H

#include <signal.h>
#include <stdio.h>

#include "run.h"
#include "scenario.h"

typedef struct {
    int parallel;  /* processes at once (0: the sweep file's, else the number of cores) */
    int dry_run;   /* list the runs and branches (and what is done) without running anything */
    int no_branch; /* every run packs and flows on its own, even when capture keys vary */
    /* Sharding, for several processes sharing one sweep (MPI ranks, a Slurm job array): the
     * work units (a branch group's flow and its runs, or one unbranched run), numbered in run
     * order, are dealt round-robin; this process takes unit u when u % shards == shard.
     * shards 0 or 1: every unit. A shard writes no results.csv (collect does). */
    int shard, shards;
    int collect;   /* run nothing: write results.csv from the finished runs; 1 if some are missing */
    const char *emit; /* "slurm": write DIR/slurm/ (a job array, one task per unit, and the job
                       * that collects) and run nothing */
    const char *program; /* this program's path, for the scripts emit writes */
    sd_tuning tuning; /* how each run's engine runs (zero: the defaults) */
    sd_scenario_limits limits; /* each case's estimate must keep to them (zero: the defaults) */
    /* called in each run's process when its run has finished (the caller draws its pictures
     * there: the sweep starts no program); NULL: nothing */
    void (*run_done)(const sd_run_result *res, FILE *log);
} sd_sweep_opts;

/* Returns 0 when every run finished, 1 when some failed, 2 on bad input (including a damaged
 * or foreign flow checkpoint to reuse), 130 when stopped. */
int sd_sweep_run(const char *sweep_file, const char *outdir, const sd_sweep_opts *opts, volatile sig_atomic_t *stop,
                 FILE *log, FILE *err);

#endif
