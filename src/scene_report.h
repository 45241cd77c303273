/* What `sabodem check` prints: the scene a scenario builds, in a designer's terms. */
#ifndef SD_SCENE_REPORT_H
#define SD_SCENE_REPORT_H

#include <stdio.h>

#include "build.h"
#include "scenario.h"

/* The dam's members and clear openings: what `check` prints and what `check --png` draws. */
typedef struct {
    int n_col, n_beam;
    double col_y[SD_MAX_PIPES];  /* column axes across the flume, m (the wall at y = 0) */
    double beam_z[SD_MAX_PIPES]; /* beam axes above the bed, m, lowest first */
    double gap_y[SD_MAX_PIPES + 1]; /* clear gaps across: wall–column, column–column, ..., column–wall */
    double gap_z[SD_MAX_PIPES + 1]; /* clear gaps up: bed–beam, beam–beam, ..., top beam–wall top */
    double d_max;                /* the largest sphere diameter */
} sd_dam_report;

/* The dam of a flume scenario (n_col = n_beam = 0 without one). */
void sd_dam_report_make(const sd_scenario *s, sd_dam_report *d);

/* The woody volume ratio K_w = V_logs / (V_spheres + V_logs) of a flume scenario (model.md
 * eq. (54)), from its counts and sizes. */
double sd_scene_k_w(const sd_scenario *s);

/* The scene as text: the flume, the debris (counts, solid volume, K_w per class), the dam
 * (axes, clear gaps, their ratios to d_max and to the log length); info and the element and
 * triangle counts from the built scene. */
void sd_scene_report(FILE *f, const sd_scenario *s, const sd_build_info *info, int n_bodies, int n_triangles);

/* The data `check --png` draws (scripts/plot_design.py), as three CSV files in dir:
 * design.csv (key,value: the flume, the debris sizes, the dam's pipe diameter), members.csv
 * (kind,axis_m: column y or beam z) and bodies.csv (the built scene's bodies). 0, or -1 with
 * a message on err. */
int sd_scene_write_design(const char *dir, const sd_scenario *s, const sd_world *w, FILE *err);

#endif
