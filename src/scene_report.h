/* What `sabodem check` prints: the scene a scenario builds, in a designer's terms. */
#ifndef SD_SCENE_REPORT_H
#define SD_SCENE_REPORT_H

#include <stdio.h>

#include "build.h"
#include "scenario.h"

/* The dam's pipes and clear openings: what `check` prints and what `check --png` draws. */
typedef struct {
    int n_col, n_beam, n_member;
    double col_y[SD_MAX_PIPES];  /* column axes across the flume, m (the wall at y = 0), ascending */
    double beam_z[SD_MAX_PIPES]; /* beam axes above the bed, m, lowest first */
    double gap_y[SD_MAX_PIPES + 1]; /* clear gaps across: wall–column, column–column, ..., column–wall */
    double gap_z[SD_MAX_PIPES + 1]; /* clear gaps up: bed–beam, beam–beam, ..., highest beam–wall top */
    int top_beam;                /* 1: the highest beam is dam.top_beam's */
    double col_top;              /* the columns reach from the bed to here, m */
    double d_max;                /* the largest sphere diameter */
    sd_dam_member member[SD_MAX_MEMBERS]; /* dam.members */
} sd_dam_report;

/* The dam of a flume scenario (no pipe without one). */
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
 * (every pipe of the dam: kind,axis_m,x0,y0,z0,x1,y1,z1,diameter_m: its kind, a column's y or a
 * beam's axis z (empty for a member), the ends of its axis, its diameter) and bodies.csv (the
 * built scene's bodies). 0, or -1 with a message on err. */
int sd_scene_write_design(const char *dir, const sd_scenario *s, const sd_world *w, FILE *err);

#endif
