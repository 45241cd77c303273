/* `sabodem sweep`: a matrix of runs over scenario parameters and seeds (issue: experiment
 * matrix), run in parallel processes, resumable, summarised in CSV and figures. */
#ifndef SD_SWEEP_H
#define SD_SWEEP_H

#include <signal.h>
#include <stdio.h>

/* Returns 0 when every run finished, 1 when some failed, 2 on bad input, 130 when stopped. */
int sd_sweep_run(const char *sweep_file, const char *outdir, int parallel, volatile sig_atomic_t *stop, FILE *log,
                 FILE *err);

#endif
