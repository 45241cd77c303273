/* Running a scenario: phases, outputs, results (SPEC §6–7). */
#ifndef SD_RUN_H
#define SD_RUN_H

#include <signal.h>
#include <stdio.h>

#include "scenario.h"

typedef struct {
    const char *outdir;            /* output directory (created) */
    int progress_tty;              /* 1: live progress line; 0: plain log lines */
    volatile sig_atomic_t *stop;   /* set asynchronously to stop cleanly (Ctrl-C) */
    FILE *log;                     /* progress and messages */
    FILE *err;                     /* errors */
} sd_run_opts;

typedef struct {
    double p_v;                    /* trap ratio (eq 55) */
    double p_v_class[SD_MAX_CLASSES];
    double p_v_logs;
    double peak_dam_force; /* largest force on any one pipe, N */
    int n_upstream, n_passed, n_removed;
    double wall_time;
    double phase_end[4];           /* simulated time at the end of packing, flow, capture */
    int interrupted;
    long steps;
} sd_run_result;

/* Build and run; returns 0 on success, 1 on a failed run, 2 on bad input, 130 when stopped. */
/* Capture-phase depth h_D (SPEC §5, eqs 51-53): the highest centre among moving elements
 * within water.probe upstream of the dam face, never below h. Elements lighter than water
 * (floating logs) are left out unless water.h_d_floating is set. */
double sd_run_capture_depth(const sd_scenario *s, const sd_world *w);

int sd_run_scenario(const sd_scenario *s, const sd_run_opts *o, sd_run_result *res);

#endif
