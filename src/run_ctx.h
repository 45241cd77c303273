/* The driver's internals, shared by its files (run.c: the phases; trap.c: what the dam holds
 * and how the flow goes; run_output.c: the files a run writes; run_state.c: the driver's state
 * in a flow-end checkpoint and a restart from it). Not an interface: run.h is. */
#ifndef SD_RUN_CTX_H
#define SD_RUN_CTX_H

#include <stdio.h>

#include "build.h"
#include "core/binio.h"
#include "io_vtk.h"
#include "pipe_loads.h"
#include "run.h"
#include "trap.h"
#include "water.h"

enum { PH_PACK = 0, PH_FLOW = 1, PH_CAPTURE = 2, PH_DONE = 3, PH_RUN = 4 };
static inline const char *sd_run_phase_name(int phase)
{
    static const char *const names[] = {"packing", "flow", "capture", "done", "run"};
    return names[phase];
}

/* a decomposed run's numbers at its end, summed over the ranks */
typedef struct {
    int ranks;
    double ghost_width;                 /* m */
    long redistributions, migrations;   /* the pairs remade (each with the bodies' new owners), owners changed */
    long boundary_moves;                /* inner boundaries moved (by the counted work) */
    double bytes;                       /* records and springs sent between the ranks */
    double bounds[65];                  /* the inner boundaries at the end, x, m: bounds[1 .. ranks-1] */
} sd_run_slabs_report;

typedef struct {
    const sd_scenario *s;
    const sd_run_opts *o;
    sd_world *w;
    sd_build_info info;
    FILE *series, *traj;
    char dir[1024];
    int phase;
    double vol_total_class[SD_MAX_CLASSES], vol_total_logs;
    double vol_passed_class[SD_MAX_CLASSES], vol_passed_logs;
    int n_passed;
    double h_d;
    double last_cross_time;
    double ke_peak;
    sd_pipe_loads loads; /* the pipes' loads (from the capture start, when the pipes go in) */
    int capture_cut;     /* the capture ended at its time limit, not settled */
    double progress_wall; /* when the last progress line was written (sd_now) */
    long progress_lines;  /* how many */
    double dam_force_now;
    /* the dam body of meshes (role dam, group SD_GROUP_DAM): its triangles, the largest |F| of
     * a step and when, and the impulses ∫|F| dt and ∫F dt */
    int n_dam_tri;
    double mesh_dam_peak, mesh_dam_t_peak, mesh_dam_impulse;
    sd_vec3 mesh_dam_impulse_vec;
    double phase_end[4];
    int pack_at_rest;      /* the packing ended at rest (else at phases.packing_time) */
    double pack_speed[3];  /* the moving elements' speeds at the packing end: max, p99, mean, m/s */
    double phase_wall[4];
    int flow_len_done;
    double flow_len, flow_q05, flow_q95, flow_front, flow_len_time;
    int n_snap;
    sd_vtk_series pvd;
    int pvd_on;
    double wall0;
    long rate_step0;           /* world step and wall clock when this process started stepping */
    double rate_wall0;         /* (a restart continues from the checkpoint's step) */
    double phase_t0, phase_w0; /* simulated and wall time at the start of the current phase */
    int flow_ended;            /* the flow phase has ended; the capture starts at the next step */
    int flow_ckpt_written;     /* the flow-end checkpoint (opts.checkpoint_flow_end) is written */
    int dam_built;             /* the pipes are in the world (sd_build_dam at the capture start) */
    const char *restarted_from;
    double flow_wall; /* wall time from the start to the flow end, build included (a restarted
                       * run: that of the run that wrote the checkpoint) */
    sd_water fluid; /* what the step's water forces need (set_fluid) */
    /* the first output that could not be written (a full disk): its errno and file; the run
     * stops with an error at the next step (sd_output_failed) */
    int out_errno;
    char out_file[280];
    /* the side views asked for so far (the arrival's, the end's), for the caller to draw */
    int n_plots;
    sd_run_picture plots[SD_RUN_PICTURES];
    /* A decomposed run (run_slabs.c): the slabs step, and c->w is the whole system's copy that
     * the driver reads, never stepped, its bodies refreshed from their owners (sd_run_slabs_sync)
     * whenever the driver reads more than the clock, the front and the pipes. NULL: c->w steps. */
    struct sd_run_slabs *sys;
    int rank;               /* this process among the run's (0 writes the files) */
    long sys_contacts;      /* at the last refresh: the contact points */
    sd_vec3 sys_wall;       /* the walls' forces on the bodies, N, summed in gid order */
    sd_vec3 sys_bed;        /* of those, the bed's triangles' */
    double sys_front;       /* the front after the last step (the maximum over the slabs) */
    int sys_front_stale;    /* bodies removed since: the front is the copy's */
    uint64_t sys_hash;      /* the state hash at the end */
    int sys_flags;          /* SD_AGREE_* as agreed after the last step */
    long sys_synced_step;   /* the step of the last refresh */
    int ckpt_pending;       /* a periodic checkpoint is due (a decomposed run's waits for a rebuild) */
    sd_run_slabs_report sys_report; /* at the end, for summary.json */
} run_ctx;

/* what a checkpoint's driver state holds beside run_ctx's fields */
enum { SD_CKPT_FLOW_END = 0, SD_CKPT_PERIODIC = 1 };

/* A run between its steps: the driver's context and the loop's settings. sd_run_scenario goes
 * through it from start to end; the public API (sabodem_run.h) one stretch at a time. */
struct sd_run {
    run_ctx c;
    sd_run_opts o;
    sd_run_result res;
    long log_every, traj_every, snap_every, ckpt_every, progress_every;
    double t_end_est;
    int code;         /* the run's exit code so far (0 while it goes on well) */
    const char *msg;  /* the summary's status */
    int ended;        /* the loop has ended (the phases are done, or stopped, or failed) */
    int finished;     /* the final outputs and the summary are written */
    FILE *err_stream; /* the API's runs (run_api.c): their messages, into err_text */
    char *err_text;
    size_t err_len;
};

/* run.c: a run in three parts. begin: build (or restart) the world and open the outputs (r->c.s,
 * r->c.o and r->c.wall0 set by the caller); 0, or the exit code of a run that cannot start, its
 * world gone. step_once: one step and what follows it; 1 when the loop ends there (r->code and
 * r->msg say how). end: the final outputs and the summary, r->res filled; the world stays. */
int sd_run_begin(sd_run *r);
int sd_run_step_once(sd_run *r);
void sd_run_end(sd_run *r);

typedef struct {
    int kind; /* SD_CKPT_FLOW_END or SD_CKPT_PERIODIC */
    long series_len, traj_len, pipes_len, events_len; /* the outputs' lengths at the checkpoint (-1: none) */
    double wall_before;   /* wall time of the run(s) before the checkpoint, s */
    double phase_wall_in; /* of that, in the phase the checkpoint was taken in */
    int npvd;
    double *pvd_time;
    int *pvd_part;
    char **pvd_file;
} sd_run_restored;

/* trap.c */
/* a body's volume, m^3 */
double sd_trap_body_volume(const sd_body_view *b, int i);
/* the trap plane: the pipes' axis plane, x_dam + d/2 (what is upstream of it is held) */
double sd_trap_plane_x(const run_ctx *c);
/* the volumes upstream of the trap plane, per size class and of the logs, and how many bodies */
void sd_trap_volumes_upstream(const run_ctx *c, double *cls, double *logs, int *n_up);
/* the trap ratio P_V (model.md eq. (55)), per class and for the logs */
double sd_trap_ratio(const run_ctx *c, double *per_class, double *logs_ratio, int *n_up);
/* the farthest downstream surface of the moving bodies, m */
double sd_trap_front_x(const run_ctx *c);
/* the kinetic energy upstream of the trap plane, J, and the moving bodies' top speed, m/s */
double sd_trap_upstream_ke(const run_ctx *c);
double sd_trap_max_speed(const run_ctx *c);
/* the moving bodies' speeds: max, 99th percentile, mean, m/s, into v[0..2] */
void sd_trap_speed_stats(const run_ctx *c, double v[3]);
/* the loads of the last step on the fixed spheres (the bed roughness) and on the bed's triangles
 * (group SD_GROUP_BED), N. The engine leaves the fixed spheres' own sums at zero (the contact
 * pass's speed): their load is what the moving bodies' contact forces leave over once the
 * triangles' and the fixed cylinders' loads are taken out (each pair force acts on both sides). */
void sd_trap_fixed_loads(const run_ctx *c, sd_vec3 *roughness, sd_vec3 *bed);
/* the highest point of body i above the bed (z): a sphere's centre + r, a log's from its axis
 * and radius, z + hl |a_z| + r sqrt(1 - a_z^2) */
double sd_trap_body_top(const sd_body_view *b, int i);
/* the deposit at the dam, between x_dam - water.probe and the trap plane: the highest true
 * top of its elements (a log jam included), and the floating logs among them (lighter than the
 * water, the centre within one diameter of the pond's surface h_D, a contact force under a
 * tenth of the weight): how many and their highest top (0 if none) */
void sd_trap_deposit(const run_ctx *c, double *height, int *n_floating, double *floating_top);
/* the flow length 1 m before the dam (model.md), into c->flow_len and its fields */
void sd_trap_flow_length(run_ctx *c);
/* the debris volumes at the end: held at the dam (the deposit against it, from *deposit_x0 to
 * the trap plane), in the channel upstream of it, and passed (m^3) */
void sd_trap_split(const run_ctx *c, double *held, double *channel, double *passed, double *deposit_x0);

/* run_output.c: the files a run writes (series.csv, trajectories.csv, VTK snapshots, walls,
 * summary.json), the pictures it asks for, the progress line */
void sd_output_series_row(run_ctx *c);
void sd_output_traj(run_ctx *c);
int sd_output_snapshot(run_ctx *c, const char *name);
int sd_output_walls(run_ctx *c);
void sd_output_picture(run_ctx *c, const char *name, const char *png, double xmin, double xmax);
void sd_output_progress(run_ctx *c, double t_end_est);
/* the summary as JSON text (the caller frees it with sd_output_summary_free; NULL when out of memory),
 * and the same written to summary.json atomically; both fill res's trap-ratio fields */
char *sd_output_summary_text(run_ctx *c, sd_run_result *res, int status_code, const char *status_msg);
void sd_output_summary_free(char *text);
int sd_output_summary(run_ctx *c, sd_run_result *res, int status_code, const char *status_msg);
void sd_output_close(run_ctx *c);
/* the first failed write: nonzero (its errno) once one failed, the file in c->out_file */
int sd_output_failed(const run_ctx *c);
/* a failed write of file (errno e) elsewhere in the driver: kept like the outputs' own */
void sd_output_note_failure(run_ctx *c, const char *file, int e);
/* series.csv and trajectories.csv flushed and closed; nonzero when either could not be written */
int sd_output_finish(run_ctx *c);

/* run_state.c: the driver's state in a checkpoint (flow-end or periodic), and a restart */
void sd_run_state_free(sd_run_restored *r);
int sd_run_state_unpack(run_ctx *c, const void *blob, size_t len, sd_run_restored *r, char *msg, size_t msglen);
int sd_run_state_restore_outputs(run_ctx *c, const sd_run_restored *r, char *msg, size_t msglen);
/* the flow-end checkpoint at path */
sd_status sd_run_state_checkpoint(run_ctx *c, const char *path);
/* a periodic checkpoint, DIR/checkpoint_<step>.ckpt, after the time series is synced to disk;
 * then every older periodic checkpoint but the newest one is deleted (the last two are kept).
 * On failure the file is not there (the older ones are untouched) and errno says why. */
sd_status sd_run_state_periodic(run_ctx *c);

/* run_slabs.c: the decomposed run (c->o->decompose; docs/decomposition.md). Every function is
 * collective (each rank calls it at the same point of the same run). */
/* Slabs over c->w (built or read from a checkpoint, the same on every rank); 0, or an exit code. */
int sd_run_slabs_begin(run_ctx *c);
void sd_run_slabs_end(run_ctx *c);
/* the world the step moves and the water pushes: this rank's slab's, or c->w */
sd_world *sd_run_slabs_world(run_ctx *c);
/* One step of the system and what every rank agrees on after it: *flags (in: this rank's
 * SD_AGREE_* bits; out: the OR over the ranks), the step's status (the worst), c->sys_front,
 * c->w's clock and its pipes' states. */
enum { SD_AGREE_STOP = 1, SD_AGREE_OUTPUT = 2 };
sd_status sd_run_slabs_step(run_ctx *c, int *flags);
/* c->w's bodies from their owners, c->sys_contacts, sys_wall, sys_bed */
sd_status sd_run_slabs_sync(run_ctx *c);
/* the system's changes between steps, made in c->w too by the caller: a body removed; a body
 * added to c->w (gid) handed to the slabs; a group of triangles switched; the pairs remade at
 * the next step */
sd_status sd_run_slabs_remove(run_ctx *c, int gid);
sd_status sd_run_slabs_add(run_ctx *c, int gid);
sd_status sd_run_slabs_group_active(run_ctx *c, int group, int active);
void sd_run_slabs_request_rebuild(run_ctx *c);
/* whether the next step remakes the pairs (the same answer on every rank) */
int sd_run_slabs_rebuilds_next(const run_ctx *c);
/* the largest v over the ranks */
int sd_run_slabs_agree(run_ctx *c, int v);
/* the whole system as one world with its springs, for a checkpoint (on rank 0; NULL elsewhere,
 * and *out NULL) */
sd_status sd_run_slabs_whole(run_ctx *c, sd_world **out);
/* sd_world_state_hash_canonical of the whole system (on every rank) */
uint64_t sd_run_slabs_hash(run_ctx *c);
/* c->sys_report filled */
void sd_run_slabs_stats(run_ctx *c);

/* run_dir.c: a run's output directory */
/* Create dir and make it this run's. A directory holding files already is refused (-1, why in
 * msg) unless overwrite (the old run's files are deleted: snapshots, series, summary,
 * checkpoints, pictures, temporary files; other files stay) or resume (a restart into the
 * directory of its checkpoint: the atomic writers' temporary files left by a kill and the
 * stale summary.json are deleted, the rest continues). */
int sd_run_dir_claim(const char *dir, int overwrite, int resume, char *msg, size_t msglen);
/* 1 when path (a file) lies in directory dir */
int sd_run_dir_holds(const char *dir, const char *path);

#endif
