/* Pictures, drawn by the Python scripts in scripts/ (matplotlib) as programs of their own: run
 * with an argument vector, never through a shell, so that no path or name given by the user is
 * ever read as a command. The scripts are looked for in $SABODEM_SCRIPTS, then beside the
 * program as installed (../share/sabodem), then in the source tree (../scripts). */
#ifndef SD_APP_PLOT_H
#define SD_APP_PLOT_H

#include <stdio.h>

#include "run.h"

/* The side views a run asked for (sd_run_result.pictures), each in its own process, all at
 * once; a note on log for each one not drawn. Returns how many were drawn. */
int app_draw_pictures(const sd_run_result *r, FILE *log);
/* The sweep's figures from DIR/results.csv and cases.csv (scripts/plot_sweep.py), its output in
 * DIR/plot.log. Returns 0 when drawn. */
int app_draw_sweep(const char *outdir);
/* The design view of `check --png` (scripts/plot_design.py) from the CSV files in data_dir
 * (sd_scene_write_design) into png; the script's output goes to log_path. 0 when drawn. */
int app_draw_design(const char *data_dir, const char *png, const char *log_path);

#endif
