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

/* How an impact event ended: |F| fell below the baseline plus half the threshold; it lasted
 * dam.event_time (a load that stays is sustained, not an impact: the baseline takes its level);
 * the run ended during it. */
enum { SD_EVENT_FELL = 0, SD_EVENT_SUSTAINED = 1, SD_EVENT_RUN_END = 2 };

/* A moving body near a pipe: its gid and its index in the body store when the list was made
 * (valid while the store keeps its order: until the next rebuild or removal). */
typedef struct {
    int gid, index;
} sd_pipe_near;

/* One impact event on a pipe (docs/loads.md "Impact events"): the steps from the first whose
 * |F| exceeds the baseline by the threshold to the last before |F| falls below the baseline plus
 * half the threshold. */
typedef struct {
    double t0;          /* start: the beginning of its first step, s */
    double duration;    /* its steps times Δt, s */
    double peak, t_peak; /* largest |F|, N, and when (the end of that step), s */
    double impulse;     /* ∫|F| dt, N s */
    sd_vec3 impulse_vec; /* ∫F dt, N s */
    double energy;      /* ∫ max(F · u, 0) dt: the work of the pipe's force on what strikes it while
                         * it presses in (u its velocity at the contact), J */
    double base;        /* the baseline when it began, N */
} sd_pipe_event;

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
    /* impact events */
    double base;                  /* the baseline: |F| low-passed (time constant event_time) outside events, N */
    int in_event;                 /* 1 while an event goes on (ev holds it) */
    sd_pipe_event ev;
    int n_events;
    double ev_peak, ev_impulse, ev_energy; /* the largest of its events' peaks, N; impulses, N s; energies, J */
    sd_vec3 lo, hi;               /* the pipe's box (for the bodies touching it), m */
    sd_pipe_near *near;           /* the moving bodies near it, by gid (a cache: not saved) */
    int n_near, cap_near;
} sd_pipe_load;

typedef struct {
    int n;
    sd_pipe_load p[SD_MAX_DAM_PIPES];
    int support;                  /* SD_SUPPORT_* */
    int window;                   /* the end window in samples: phases.quiet_time / output.log_interval */
    FILE *csv;                    /* pipes.csv, NULL when not written */
    FILE *ev_csv;                 /* events.csv, a row per event as it ends; NULL when not written */
    int ev_csv_bad;               /* a row could not be written */
    int no_energy;                /* 1: events get no energy (a decomposed run, where the strikers' velocities
                                   * are not at hand every step; docs/decomposition.md) */
    double ev_threshold;          /* an event's threshold above the baseline, N (dam.event_threshold, or
                                   * four times the weight of the heaviest moving body at the capture's start) */
    double ev_time;               /* dam.event_time, s */
    sd_vec3 gravity;              /* m/s^2 */
    long near_step;               /* the step the near lists were made at (-1: never) */
} sd_pipe_loads;

/* The near lists are remade every SD_PIPE_NEAR_STEPS steps while an event goes on, and when the
 * store has changed its order: the moving bodies whose bounding sphere comes within
 * 2 |v| SD_PIPE_NEAR_STEPS Δt + SD_PIPE_NEAR_MARGIN of a pipe's box, which holds every body that
 * can touch it before the next remake unless one more than doubles its speed on the way. */
#define SD_PIPE_NEAR_STEPS 100
#define SD_PIPE_NEAR_MARGIN 0.005 /* m */

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

/* Start with the pipes in info (after sd_build_dam); csv_path NULL: no pipes.csv, events_path
 * NULL: no events.csv. The events' threshold is dam.event_threshold, or (0) four times the weight of
 * the heaviest moving body in w now. 0, or -1 (errno) when a file cannot be opened. */
int sd_pipe_loads_start(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                        const char *csv_path, const char *events_path);
/* The same for a run restarted after its capture began: the accumulators kept (as unpacked
 * from the checkpoint), pipes.csv and events.csv continued (appended to, no header). */
int sd_pipe_loads_resume(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                         const char *csv_path, const char *events_path);
/* Every step: the forces of the last step, and the impact events (an event that ends writes its
 * row). Returns the sum of |F| over the pipes. */
double sd_pipe_loads_step(sd_pipe_loads *L, const sd_world *w, double t, double dt);
/* The power of force f (on a fixed pipe) on the bodies touching the pipe among the n near ones
 * (by ascending gid, so that the sum's order does not depend on the store's), W: f · u, u the
 * velocity at the contact point at the middle of the last step (v - (F/m + g) Δt / 2 from the
 * velocity after it; a log's spin as it is), of the one body touching it, or the mean of several
 * weighted by their overlaps (their share of the normal springs); 0 when none touches. -1 in
 * *stale (and 0) when an entry's index no longer holds its gid: the list must be made anew. */
double sd_pipe_impact_power(const sd_body_state *pipe, sd_vec3 f, const sd_body_view *b, const sd_pipe_near *near,
                            int n, sd_vec3 gravity, double dt, int *stale);
/* At each log interval: a row per pipe in pipes.csv; 0, or -1 when the write failed (or that of
 * an event's row in events.csv since). */
int sd_pipe_loads_sample(sd_pipe_loads *L, const sd_world *w, double t);
/* At the end: the sustained load (the mean force over the last window of samples) and the
 * rising flag: the capture ended at its time limit (cut_by_limit, not settled) and the mean
 * |F| of the last window is more than 10 % above that of the window before; an event still
 * going on ends (SD_EVENT_RUN_END) with its row. */
void sd_pipe_loads_finish(sd_pipe_loads *L, int cut_by_limit);
/* pipes.csv and events.csv closed; 0, or -1 when one could not be written. */
int sd_pipe_loads_close(sd_pipe_loads *L);
void sd_pipe_loads_free(sd_pipe_loads *L);
/* The accumulators in a checkpoint (the samples included; not the open file), and back
 * (unpack: 0, or -1 for a malformed record). */
void sd_pipe_loads_pack(const sd_pipe_loads *L, sd_bin_writer *b);
int sd_pipe_loads_unpack(sd_pipe_loads *L, sd_bin_reader *r);

#endif
