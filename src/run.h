/* Running a scenario: phases, outputs, results (SPEC §6–7). */
#ifndef SD_RUN_H
#define SD_RUN_H

#include <signal.h>
#include <stdint.h>
#include <stdio.h>

#include "scenario.h"

/* The transport between the processes of one decomposed run (docs/decomposition.md): the
 * program's MPI (app/ranks_mpi.c; the library has none). Every function is collective: each
 * rank calls it, in the same order; 0 on success. */
typedef struct sd_run_comm {
    int rank, size;
    void *ctx;
    /* len bytes from every rank (the same len everywhere) into all (size * len bytes), in rank order */
    int (*allgather)(void *ctx, const void *mine, size_t len, void *all);
    /* each rank's own length: *all malloc'ed (the caller frees it), lens[r] bytes from rank r, in rank order */
    int (*allgatherv)(void *ctx, const void *mine, size_t len, void **all, size_t *lens);
    /* out[r] (outlen[r] bytes) to rank r; *in malloc'ed, inlen[r] bytes from rank r, in rank order */
    int (*alltoallv)(void *ctx, const void *const *out, const size_t *outlen, void **in, size_t *inlen);
} sd_run_comm;

typedef struct {
    const char *outdir;          /* output directory (created) */
    int progress_tty;            /* 1: live progress line; 0: plain log lines */
    double progress_interval;    /* plain log lines at most this often, s of wall time (0: every 2000 steps) */
    volatile sig_atomic_t *stop; /* set asynchronously to stop cleanly (Ctrl-C) */
    FILE *log;                   /* progress and messages */
    FILE *err;                   /* errors */
    /* Branching (docs/sweep.md). A flume run builds its scene without the dam pipes and adds
     * them when the capture phase starts, so that everything before depends on no dam-layout
     * or capture-phase key (sd_scenario_is_capture_key). */
    const char *checkpoint_flow_end; /* write a checkpoint (world + driver state) here when the flow ends */
    int stop_at_flow_end;            /* 1: return (0) right after that point: the shared flow of a branch */
    const char *restart;             /* continue from this checkpoint instead of building the
                                      * scene; the scenario may differ from the writer's only in capture
                                      * keys; the time series (and VTK files, from the checkpoint's
                                      * directory) up to the checkpoint are carried into outdir.
                                      * A periodic checkpoint (output.checkpoint_interval) continues
                                      * the same scenario in any phase. */
    int overwrite;                   /* 1: an outdir holding another run's files is cleared, not
                                      * refused (a restart into its checkpoint's directory continues
                                      * there either way) */
    /* The run over slabs along x (docs/decomposition.md): one slab a rank of comm (NULL: one
     * slab in this process), the fixed grid, the diagnostics from the whole system gathered in
     * a fixed order; the same bits, outputs and checkpoints on any count of ranks. Rank 0 writes
     * the files. */
    int decompose;
    const sd_run_comm *comm;
} sd_run_opts;

/* A side view the run asks its caller to draw (the driver starts no program): the snapshot's
 * spheres and logs (.vtp), the dam's x and the x range to show, and the picture to write. */
enum { SD_RUN_PICTURES = 2 };
typedef struct {
    char spheres[1200], logs[1200], png[1200];
    double x_dam, x_min, x_max;
} sd_run_picture;

typedef struct {
    double p_v; /* trap ratio (eq 55) */
    double p_v_class[SD_MAX_CLASSES];
    double p_v_logs;
    double peak_dam_force; /* largest force on any one pipe, N */
    double v_held, v_channel, v_passed; /* debris at the end: held at the dam, in the channel, passed (m^3) */
    int capture_cut;       /* the capture ended at its time limit (not settled) */
    int n_upstream, n_passed, n_removed;
    double wall_time;
    double phase_end[4]; /* simulated time at the end of packing, flow, capture */
    int interrupted;
    long steps;
    uint64_t state_hash;     /* sd_world_state_hash at the end */
    int stopped_at_flow_end; /* stop_at_flow_end was honoured */
    int restarted;           /* the run continued from opts.restart */
    double flow_wall;        /* wall time from the start to the flow end (build, packing, flow), s;
                              * a restarted run: the checkpoint writer's */
    int n_pictures;          /* the side views asked for (output.png), for the caller to draw */
    sd_run_picture pictures[SD_RUN_PICTURES];
} sd_run_result;

/* Build and run; returns 0 on success, 1 on a failed run, 2 on bad input (an output directory
 * that is not this run's included), 130 when stopped. */
int sd_run_scenario(const sd_scenario *s, const sd_run_opts *o, sd_run_result *res);

/* Can the scenario continue from this checkpoint? Reads and checks it whole (format,
 * checksum, driver state, scenario fingerprint); 0 if so, else -1 and msg names the file and
 * what is wrong. */
int sd_run_check_restart(const sd_scenario *s, const char *path, char *msg, size_t msglen);
/* The version of the driver's state that a run's checkpoints carry ("SDRUNv3"): a checkpoint
 * of another is refused. */
const char *sd_run_state_version(void);

#endif
