/* The loads on the dam's pipes in design terms (docs/loads.md): per pipe the force over time
 * (pipes.csv), the peak and when, the impulse, the resultant's point of application along the
 * pipe, the bending moment for a stated support model, the sustained load at the end, and
 * whether the load was still rising when the capture was cut by its time limit. */
#ifndef SD_PIPE_LOADS_H
#define SD_PIPE_LOADS_H

#include <stdio.h>

#include "build.h"
#include "core/binio.h"
#include "scenario.h"

enum { SD_SUPPORT_SIMPLE = 0, SD_SUPPORT_FIXED = 1 };

typedef struct {
    int gid, kind; /* kind: SD_PIPE_* (build.h) */
    double coord;  /* a column's axis y, a beam's axis z, m; a member's index in dam.members */
    double span;   /* its length between supports, m: bed to top for a column, wall to wall for a beam, end to
                      end for a member */
    /* over the capture */
    double peak, t_peak;          /* largest |F| of one step, N, and when, s */
    double impulse;               /* ∫|F| dt, N s */
    sd_vec3 impulse_vec;          /* ∫F dt, N s */
    double m_peak, t_m_peak;      /* largest bending moment, N m, and when */
    double s_at_m_peak;           /* the resultant's position then, m from the pipe's start */
    double interval_peak;         /* largest |F| since the last sample, N */
    /* the samples (one per log interval) for the end-of-capture statistics */
    sd_vec3 *f;
    int n_f, cap_f;
    /* at the end */
    sd_vec3 sustained;            /* mean force over the last window, N */
    int rising;                   /* 1: the load rose over the last window of a capture cut by its limit */
} sd_pipe_load;

typedef struct {
    int n;
    sd_pipe_load p[SD_MAX_DAM_PIPES];
    int support;                  /* SD_SUPPORT_* */
    int window;                   /* the end window in samples: phases.quiet_time / output.log_interval */
    FILE *csv;                    /* pipes.csv, NULL when not written */
} sd_pipe_loads;

/* The resultant of force f and torque t (about the pipe's centre) on a pipe with unit axis a:
 * the position s of its line of action along the axis from the centre, m, and the force
 * across the axis, N. Exact for forces through the axis; a friction force along the axis
 * shifts s by at most R |F_axial| / |F_across| (docs/loads.md). */
double sd_pipe_resultant_position(sd_vec3 a, sd_vec3 f, sd_vec3 t, double *f_across);
/* The largest bending moment of a pipe of span L under a point load P at distance x from one
 * support: simple supports P x (L - x) / L; fixed ends the larger end moment P x (L - x)^2 / L^2
 * (or P x^2 (L - x) / L^2). A point load at the resultant's position bounds the moment of any
 * load with that resultant on a simple span (the influence line is concave). */
double sd_pipe_bending_moment(int support, double span, double x, double p);

/* Start with the pipes in info (after sd_build_dam); csv_path NULL: no pipes.csv. 0, or -1
 * (errno) when pipes.csv cannot be opened. */
int sd_pipe_loads_start(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                        const char *csv_path);
/* The same for a run restarted after its capture began: the accumulators kept (as unpacked
 * from the checkpoint), pipes.csv continued (appended to, no header). */
int sd_pipe_loads_resume(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                         const char *csv_path);
/* Every step: the forces of the last step. Returns the sum of |F| over the pipes. */
double sd_pipe_loads_step(sd_pipe_loads *L, const sd_world *w, double t, double dt);
/* At each log interval: a row per pipe in pipes.csv; 0, or -1 when the write failed. */
int sd_pipe_loads_sample(sd_pipe_loads *L, const sd_world *w, double t);
/* At the end: the sustained load (the mean force over the last window of samples) and the
 * rising flag: the capture ended at its time limit (cut_by_limit, not settled) and the mean
 * |F| of the last window is more than 10 % above that of the window before. */
void sd_pipe_loads_finish(sd_pipe_loads *L, int cut_by_limit);
/* pipes.csv closed; 0, or -1 when it could not be written. */
int sd_pipe_loads_close(sd_pipe_loads *L);
void sd_pipe_loads_free(sd_pipe_loads *L);
/* The accumulators in a checkpoint (the samples included; not the open file), and back
 * (unpack: 0, or -1 for a malformed record). */
void sd_pipe_loads_pack(const sd_pipe_loads *L, sd_bin_writer *b);
int sd_pipe_loads_unpack(sd_pipe_loads *L, sd_bin_reader *r);

#endif
