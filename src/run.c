/* The driver: builds the scene, runs the phases of SPEC §6, writes the outputs. Output and
 * phase logic happen between steps, never inside them. */
#include "run_ctx.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "build.h"
#include "core/binio.h"
#include "core/status.h"
#include "core/vmath.h"
#include "io_vtk.h"
#include "water.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* The fluid forces of the current phase for the coming step: handed to the world, which calls
 * sd_water_forces inside the step; none while packing, nor in a scene without a flume unless
 * water.scene asks for water (the external forces stay as they are). */
static void set_fluid(run_ctx *c)
{
    const sd_scenario *s = c->s;
    sd_world *moved = sd_run_slabs_world(c); /* (the slab's, in a decomposed run) */
    if (!s->water_on || c->phase == PH_PACK || (c->phase == PH_RUN && s->water_scene == SD_SCENE_WATER_NONE)) {
        sd_world_set_external_force_fn(moved, NULL, NULL);
        return;
    }
    /* the flume frame; a scene's frame is the world's (x downstream, bed z = 0, normal +z) */
    sd_fluid_params fp = sd_fluid_params_default(c->phase == PH_RUN ? 0.0 : s->slope_deg * M_PI / 180.0);
    fp.U = c->phase == PH_RUN && s->water_scene == SD_SCENE_WATER_STILL ? 0.0 : s->water_u;
    fp.h = s->water_h;
    fp.rho = s->water_rho;
    fp.C_D = s->water_cd;
    fp.gravity = sd_world_definition(c->w)->gravity;
    /* the pond is still water: its buoyancy is vertical whatever water.buoyancy says */
    if (s->water_buoyancy == SD_BUOYANCY_BED_NORMAL && c->phase != PH_CAPTURE)
        fp.gravity = v3_scale(fp.bed_normal, v3_dot(fp.gravity, fp.bed_normal));
    c->fluid.fp = fp;
    c->fluid.capture = c->phase == PH_CAPTURE;
    c->fluid.uniform = c->phase == PH_RUN && s->water_scene != SD_SCENE_WATER_FLOW;
    /* the pond's region: from capture_length upstream of the dam face to the trap plane (or the face) */
    c->fluid.xd = s->water_capture_end == SD_CAPTURE_END_DAM_FACE ? s->x_dam : sd_trap_plane_x(c);
    c->fluid.x_from = s->water_capture_length > 0.0 ? s->x_dam - s->water_capture_length : -INFINITY;
    c->fluid.h_d = c->h_d;
    sd_world_set_external_force_fn(moved, sd_water_forces, &c->fluid);
}

static void update_h_d(run_ctx *c) { c->h_d = sd_trap_capture_depth(c->s, c->w); }

static void remove_passed(run_ctx *c)
{
    sd_body_view bv = sd_world_bodies(c->w);
    const sd_body_view *b = &bv;
    for (int i = b->n - 1; i >= 0; i--) {
        if (b->fixed[i] || b->pos[i].x <= c->s->x_end) continue;
        if (b->shape[i] == SD_SHAPE_CYLINDER)
            c->vol_passed_logs += sd_trap_body_volume(b, i);
        else if (b->tag[i] >= 0 && b->tag[i] < SD_MAX_CLASSES)
            c->vol_passed_class[b->tag[i]] += sd_trap_body_volume(b, i);
        c->n_passed++;
        const int gid = b->gid[i];
        sd_world_remove_body(c->w, gid);
        if (c->sys) sd_run_slabs_remove(c, gid);
        bv = sd_world_bodies(c->w); /* (the last body took i's place: those above i are done) */
    }
}

/* The capture phase begins: the grid dam's pipes go in now, not at the build, so that packing
 * and flow do not depend on the dam layout (SPEC §6, docs/physics.md "Flow end and branching").
 * A straight run and a run restarted from a flow-end checkpoint both come through here. */
static sd_status capture_start(run_ctx *c)
{
    const sd_scenario *s = c->s;
    const int n0 = c->info.n_pipes;
    sd_status st = sd_build_dam(c->w, s, &c->info);
    for (int k = n0; k < c->info.n_pipes && !st && c->sys; k++) /* (built into the copy, handed to the slabs) */
        st = sd_run_slabs_add(c, c->info.pipe_gid[k]);
    if (st) return st;
    c->dam_built = 1;
    char csv[1200], ev[1200];
    snprintf(csv, sizeof csv, "%s/pipes.csv", c->dir);
    snprintf(ev, sizeof ev, "%s/events.csv", c->dir);
    if (sd_pipe_loads_start(&c->loads, s, &c->info, c->w, c->series ? csv : NULL, c->series ? ev : NULL))
        sd_output_note_failure(c, c->loads.csv ? "events.csv" : "pipes.csv", errno);
    c->loads.no_energy = c->sys != NULL;
    c->phase = PH_CAPTURE;
    c->phase_t0 = sd_world_time(c->w);
    c->phase_w0 = sd_now();
    c->last_cross_time = sd_world_time(c->w);
    update_h_d(c);
    sd_output_snapshot(c, "arrival");
    sd_output_picture(c, "arrival", "side_arrival.png", s->x_dam - 1.2, s->x_end);
    return SD_OK;
}

/* The dam body of meshes after a step: its peak and impulses, every step as the pipes' (an impact
 * lasts a few milliseconds, less than a log interval). This gathers the walls' loads every step,
 * which only scenes with a dam mesh pay for (contact.c, sd_contact_gather). */
static void dam_mesh_step(run_ctx *c, double interval)
{
    const sd_vec3 f = sd_world_group_force(c->w, SD_GROUP_DAM);
    const double a = v3_norm(f);
    if (a > c->mesh_dam_peak) {
        c->mesh_dam_peak = a;
        c->mesh_dam_t_peak = sd_world_time(c->w);
    }
    c->mesh_dam_impulse += a * interval;
    c->mesh_dam_impulse_vec = v3_madd(c->mesh_dam_impulse_vec, f, interval);
}

/* ---------------------------------------------------------------- the run ---- */

/* Build (or restart) the run's world and open its outputs; 0, or the exit code (1, 2) of a run
 * that cannot start, with the world gone. */
int sd_run_begin(sd_run *r)
{
    run_ctx *c = &r->c;
    const sd_scenario *s = c->s;
    const sd_run_opts *o = c->o;
    sd_status st;
    sd_run_restored rs;
    memset(&rs, 0, sizeof rs);
    c->rank = o->decompose && o->comm ? o->comm->rank : 0;
    if (o->restart) {
        char msg[1600];
        void *blob = NULL;
        size_t blen = 0;
        st = sd_checkpoint_read(o->restart, &c->w, &blob, &blen, msg, sizeof msg);
        if (st) {
            fprintf(o->err, "%s\n", msg[0] ? msg : sd_status_message(st));
            return 2;
        }
        int bad = sd_run_state_unpack(c, blob, blen, &rs, msg, sizeof msg);
        free(blob);
        if (bad) {
            fprintf(o->err, "%s: %s\n", o->restart, msg);
            sd_pipe_loads_free(&c->loads);
            sd_world_destroy(c->w);
            return 2;
        }
        /* the thread count is the caller's (the bits do not depend on it) */
        int threads = s->world.threads;
#ifdef _OPENMP
        if (threads <= 0) threads = omp_get_max_threads();
#endif
        if (threads > 0) sd_world_set_threads(c->w, threads);
        sd_world_set_tuning(c->w, &s->world.tuning); /* (and how it runs, too) */
        c->restarted_from = o->restart;
        if (rs.kind == SD_CKPT_PERIODIC) { /* the same run goes on: its wall times too */
            c->wall0 = sd_now() - rs.wall_before;
            c->phase_w0 = sd_now() - rs.phase_wall_in;
        }
    } else {
        st = sd_world_create(&s->world, &c->w);
        if (st) {
            fprintf(o->err, "%s: %s\n", s->path, sd_status_message(st));
            return 2;
        }
        /* without the dam pipes: they go in at the start of the capture phase (capture_start) */
        st = sd_build_scene_ex(c->w, s, &c->info, o->err, 0);
        if (!st) st = sd_world_check(c->w);
        if (st) {
            if (st == SD_ERR_UNSTABLE)
                fprintf(o->err, "%s: solver.dt: %s\n", s->path, sd_status_message(st));
            else
                fprintf(o->err, "%s: cannot build the scene: %s\n", s->path, sd_status_message(st));
            sd_pipe_loads_free(&c->loads);
            sd_world_destroy(c->w);
            return 2;
        }
    }
    /* a decomposed run: the slabs over the world, which stays as the whole system's copy (a dam
     * body of meshes is not summed over the slabs yet: refused rather than reported wrong) */
    int dam_mesh = 0;
    for (int k = 0; k < s->n_meshes; k++)
        dam_mesh |= s->meshes[k].role == SD_MESH_DAM;
    if (o->decompose && dam_mesh) {
        fprintf(o->err, "%s: meshes: a mesh with role dam is not supported in a decomposed run (mpirun -np N > 1 or "
                        "--decompose); run it in one process\n", s->path);
        sd_run_state_free(&rs);
        sd_pipe_loads_free(&c->loads);
        sd_world_destroy(c->w);
        return 2;
    }
    if (o->decompose && sd_run_slabs_begin(c)) {
        sd_run_state_free(&rs);
        sd_pipe_loads_free(&c->loads);
        sd_world_destroy(c->w);
        return 1;
    }
    /* only now, with valid input, does the output directory appear (rank 0's) */
    snprintf(c->dir, sizeof c->dir, "%s", o->outdir);
    int code = 0;
    if (c->rank == 0) {
        char msg[1800];
        const int resume = c->restarted_from && sd_run_dir_holds(c->dir, c->restarted_from);
        if (sd_run_dir_claim(c->dir, o->overwrite, resume, msg, sizeof msg)) {
            fprintf(o->err, "%s\n", msg);
            code = 2;
        }
    }
    if (!code && c->restarted_from && c->rank == 0) {
        char msg[1600];
        if (sd_run_state_restore_outputs(c, &rs, msg, sizeof msg)) {
            fprintf(o->err, "%s: cannot continue the outputs of %s: %s\n", c->dir, o->restart, msg);
            code = 1;
        }
    }
    if (c->sys) code = sd_run_slabs_agree(c, code);
    if (code) {
        sd_run_state_free(&rs);
        sd_pipe_loads_free(&c->loads);
        sd_run_slabs_end(c);
        sd_world_destroy(c->w);
        return code;
    }
    char path[1200];
    const char *mode = c->restarted_from ? "a" : "w";
    const int writer = c->rank == 0; /* (the other ranks of a decomposed run write nothing) */
    snprintf(path, sizeof path, "%s/series.csv", c->dir);
    c->series = writer ? fopen(path, mode) : NULL;
    if (c->series && !c->restarted_from)
        fprintf(c->series,
                "t,phase,front_x,volume_upstream_m3,kinetic_energy_J,contacts,dam_force_N,p_v,h_d,elements,passed,"
                "roughness_force_x_N,roughness_force_z_N,bed_force_x_N,bed_force_z_N,dam_mesh_force_x_N,"
                "dam_mesh_force_y_N,dam_mesh_force_z_N\n");
    if (s->n_traj > 0 && writer) {
        snprintf(path, sizeof path, "%s/trajectories.csv", c->dir);
        c->traj = fopen(path, mode);
        if (c->traj && !c->restarted_from) fprintf(c->traj, "t,id,x,y,z,vx,vy,vz,wx,wy,wz,ax,ay,az,fx,fy,fz\n");
    }
    int pvd_bad = 0;
    if (s->vtk_on && writer) {
        snprintf(path, sizeof path, "%s/series.pvd", c->dir);
        c->pvd_on = sd_vtk_series_init(&c->pvd, path) == 0;
        for (int k = 0; c->pvd_on && k < rs.npvd; k++)
            if (sd_vtk_series_add(&c->pvd, rs.pvd_time[k], rs.pvd_part[k], rs.pvd_file[k])) pvd_bad = 1;
    }
    const int rs_kind = rs.kind;
    if (c->restarted_from && c->dam_built) { /* a restart in the capture: its pipe loads go on */
        char ev[1200];
        snprintf(path, sizeof path, "%s/pipes.csv", c->dir);
        snprintf(ev, sizeof ev, "%s/events.csv", c->dir);
        if (sd_pipe_loads_resume(&c->loads, s, &c->info, c->w, writer ? path : NULL, writer ? ev : NULL)) pvd_bad = 1;
        c->loads.no_energy = c->sys != NULL;
    }
    sd_run_state_free(&rs);
    if (writer && (!c->series || (s->n_traj > 0 && !c->traj) || (s->vtk_on && !c->pvd_on) || pvd_bad ||
                   (!c->restarted_from && sd_output_walls(c)))) {
        fprintf(o->err, "%s: cannot write output files: %s\n", c->dir, strerror(errno));
        code = 1;
    }
    if (c->sys) code = sd_run_slabs_agree(c, code);
    if (code) {
        sd_output_close(c);
        sd_pipe_loads_free(&c->loads);
        sd_run_slabs_end(c);
        sd_world_destroy(c->w);
        return code;
    }
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    const double dt = s->world.dt;
    c->n_dam_tri = 0;
    for (int k = 0; k < s->n_meshes; k++)
        if (s->meshes[k].role == SD_MESH_DAM) c->n_dam_tri += s->meshes[k].n_tri;
    for (int k = 0; k < s->n_elems; k++) /* (explicit triangles may join the dam body) */
        c->n_dam_tri += s->elems[k].type == 2 && s->elems[k].group == SD_GROUP_DAM;
    if (!c->restarted_from) {
        for (int i = 0; i < b->n; i++) {
            if (b->fixed[i]) continue;
            if (b->shape[i] == SD_SHAPE_CYLINDER)
                c->vol_total_logs += sd_trap_body_volume(b, i);
            else if (b->tag[i] >= 0 && b->tag[i] < SD_MAX_CLASSES)
                c->vol_total_class[b->tag[i]] += sd_trap_body_volume(b, i);
        }
        c->phase = s->flume_on ? PH_PACK : PH_RUN;
        c->h_d = s->water_h;
        c->phase_t0 = 0.0;
        c->phase_w0 = sd_now();
    } else if (rs_kind != SD_CKPT_PERIODIC) {
        c->phase_w0 = sd_now();
    }
    if (c->restarted_from && c->dam_built) /* the arrival's side view, asked again for this process */
        sd_output_picture(c, "arrival", "side_arrival.png", s->x_dam - 1.2, s->x_end);
    if (c->restarted_from && o->log)
        fprintf(o->log, "restart from %s: t = %.4f s, step %ld, phase %s\n", c->restarted_from, sd_world_time(c->w),
                sd_world_step_count(c->w), sd_run_phase_name(c->phase));
    r->log_every = (long)llround(s->log_interval / dt);
    if (r->log_every < 1) r->log_every = 1;
    r->traj_every = (long)llround(s->traj_interval / dt);
    if (r->traj_every < 1) r->traj_every = 1;
    r->snap_every = s->snapshot_interval > 0 ? (long)llround(s->snapshot_interval / dt) : 0;
    r->ckpt_every = s->checkpoint_interval > 0 ? (long)llround(s->checkpoint_interval / dt) : 0;
    if (s->checkpoint_interval > 0 && r->ckpt_every < 1) r->ckpt_every = 1;
    r->progress_every = 2000;
    r->t_end_est = s->flume_on ? s->packing_time + 4.0 + s->capture_limit : s->duration;
    if (!c->restarted_from) {
        sd_output_snapshot(c, "initial");
        sd_output_series_row(c);
        sd_output_traj(c);
    }
    c->rate_step0 = sd_world_step_count(c->w);
    c->rate_wall0 = sd_now();
    r->msg = "finished";
    return 0;
}

/* One pass of the loop: a step and what follows it. 1 when the loop ends here (r->code and
 * r->msg say how), else 0. */
int sd_run_step_once(sd_run *r)
{
    run_ctx *c = &r->c;
    const sd_scenario *s = c->s;
    const sd_run_opts *o = c->o;
    sd_run_result *res = &r->res;
    const double dt = s->world.dt;
    sd_status st;
    /* (a decomposed run's ranks stop together: as they agreed after the last step) */
    if (c->sys ? (c->sys_flags & SD_AGREE_STOP) != 0 : (o->stop && *o->stop)) {
        r->code = 130;
        r->msg = "interrupted";
        res->interrupted = 1;
        return 1;
    }
    if (c->sys ? (c->sys_flags & SD_AGREE_OUTPUT) != 0 : sd_output_failed(c) != 0) {
        /* a full disk: stop, with an error, not a run that says done */
        if (c->rank == 0) fprintf(o->err, "%s/%s: cannot write: %s\n", c->dir, c->out_file, strerror(c->out_errno));
        r->code = 1;
        r->msg = "output failed";
        return 1;
    }
    if (c->phase == PH_RUN && sd_world_time(c->w) >= s->duration - 0.5 * dt) return 1;
    if (c->phase == PH_DONE) return 1;
    if (c->flow_ended && !c->dam_built) {
        /* the branch point: a flow-end checkpoint holds the state of exactly this moment, and
         * a restart from it comes in here, so both go through capture_start alike */
        if (c->sys && (st = sd_run_slabs_sync(c))) {
            r->code = 1;
            r->msg = sd_status_message(st);
            return 1;
        }
        if (o->checkpoint_flow_end && !c->flow_ckpt_written) {
            st = sd_run_state_checkpoint(c, o->checkpoint_flow_end);
            if (c->sys) st = (sd_status)sd_run_slabs_agree(c, st);
            if (st) {
                fprintf(o->err, "%s: cannot write the flow-end checkpoint: %s (%s)\n", o->checkpoint_flow_end,
                        sd_status_message(st), strerror(errno));
                r->code = 1;
                r->msg = "checkpoint failed";
                return 1;
            }
            if (o->log && !o->progress_tty)
                fprintf(o->log, "flow-end checkpoint %s written at t = %.4f s\n", o->checkpoint_flow_end,
                        sd_world_time(c->w));
        }
        if (o->stop_at_flow_end) {
            res->stopped_at_flow_end = 1;
            r->msg = "stopped at the flow end";
            return 1;
        }
        st = capture_start(c);
        if (st) {
            fprintf(o->err, "%s: cannot add the dam pipes: %s\n", s->path, sd_status_message(st));
            r->code = 1;
            r->msg = sd_status_message(st);
            return 1;
        }
    }
    set_fluid(c);
    if (c->sys) {
        c->sys_flags = (o->stop && *o->stop ? SD_AGREE_STOP : 0) | (sd_output_failed(c) ? SD_AGREE_OUTPUT : 0);
        st = sd_run_slabs_step(c, &c->sys_flags);
    } else {
        st = sd_world_step(c->w);
    }
    if (st) {
        fprintf(o->err, "%s: step %ld, t = %.6f s: %s\n", s->path, sd_world_step_count(c->w), sd_world_time(c->w), sd_status_message(st));
        r->code = 1;
        r->msg = sd_status_message(st);
        return 1;
    }
    long step = sd_world_step_count(c->w);
    if (c->loads.n) c->dam_force_now = sd_pipe_loads_step(&c->loads, c->w, sd_world_time(c->w), dt);
    if (c->n_dam_tri) dam_mesh_step(c, dt);
    /* a decomposed run's copy of the system, refreshed where the driver reads it */
    if (c->sys && ((s->flume_on && step % 100 == 0) || step % r->log_every == 0 ||
                   (s->n_traj > 0 && step % r->traj_every == 0) || (r->snap_every && step % r->snap_every == 0)) &&
        (st = sd_run_slabs_sync(c))) {
        r->code = 1;
        r->msg = sd_status_message(st);
        return 1;
    }
    int next = c->phase;
    if (s->flume_on && step % 100 == 0) {
        int before = c->n_passed;
        remove_passed(c);
        double tph = sd_world_time(c->w) - c->phase_t0;
        if (sd_trap_crossing(c->w, sd_trap_plane_x(c))) c->last_cross_time = sd_world_time(c->w);
        if (c->n_passed != before) c->last_cross_time = sd_world_time(c->w);
        if (c->phase == PH_PACK) {
            /* at rest (model.md §6: speeds below ~1 mm/s), or at the time limit */
            if (tph >= s->packing_time - 0.5 * dt)
                next = PH_FLOW;
            else if (s->packing_rest_speed > 0.0 && tph >= s->packing_min_time - 0.5 * dt &&
                     sd_trap_max_speed(c) <= s->packing_rest_speed) {
                next = PH_FLOW;
                c->pack_at_rest = 1;
            }
        } else if (c->phase == PH_CAPTURE) {
            update_h_d(c);
            double ke = sd_trap_upstream_ke(c);
            if (ke > c->ke_peak) c->ke_peak = ke;
            int quiet = sd_world_time(c->w) - c->last_cross_time >= s->quiet_time && ke < s->ke_fraction * c->ke_peak;
            if (tph >= s->capture_limit || (tph > s->quiet_time && quiet)) next = PH_DONE;
            c->capture_cut = next == PH_DONE && !(tph > s->quiet_time && quiet);
        }
    }
    if (c->phase == PH_FLOW && !c->flow_ended) {
        /* checked at every step, so that the front has moved less than one step's travel
         * (~v dt) past the dam face when the pipes appear (docs/physics.md) */
        double fx = sd_trap_front_x(c), tph = sd_world_time(c->w) - c->phase_t0;
        if (step % 100 == 0 && !c->flow_len_done && s->x_dam - 1.0 > s->x_gate && fx >= s->x_dam - 1.0)
            sd_trap_flow_length(c);
        if (fx >= s->x_dam || tph >= s->flow_limit) next = PH_CAPTURE;
    }
    if (next != c->phase) {
        if (c->sys && step % 100 != 0 && (st = sd_run_slabs_sync(c))) {
            r->code = 1;
            r->msg = sd_status_message(st);
            return 1;
        }
        c->phase_end[c->phase] = sd_world_time(c->w);
        c->phase_wall[c->phase] = sd_now() - c->phase_w0;
        c->phase_w0 = sd_now();
        if (o->log && !o->progress_tty)
            fprintf(o->log, "phase %s ended at t = %.4f s (max speed %.4f m/s)\n", sd_run_phase_name(c->phase), sd_world_time(c->w),
                    sd_trap_max_speed(c));
        if (c->phase == PH_PACK) {
            sd_trap_speed_stats(c, c->pack_speed);
            sd_world_set_group_active(c->w, SD_GROUP_GATE, 0);
            if (c->sys) sd_run_slabs_group_active(c, SD_GROUP_GATE, 0);
            sd_output_snapshot(c, "packed");
            c->phase_t0 = sd_world_time(c->w);
            c->phase = next;
        } else if (next == PH_CAPTURE) {
            /* the capture (pipes, capture fluid) starts at the top of the next iteration */
            c->flow_ended = 1;
            c->flow_wall = sd_now() - c->wall0; /* the build included */
        } else {
            c->phase_t0 = sd_world_time(c->w);
            c->phase = next;
        }
    }
    if (step % r->log_every == 0) {
        sd_output_series_row(c);
        if (c->loads.n && sd_pipe_loads_sample(&c->loads, c->w, sd_world_time(c->w)))
            sd_output_note_failure(c, c->loads.ev_csv_bad || (c->loads.ev_csv && ferror(c->loads.ev_csv)) ? "events.csv"
                                                                                                      : "pipes.csv",
                                   errno);
    }
    if (c->traj && step % r->traj_every == 0) sd_output_traj(c);
    if (r->snap_every && step % r->snap_every == 0) {
        char name[64];
        snprintf(name, sizeof name, "%06d", c->n_snap);
        sd_output_snapshot(c, name);
    }
    if (step % r->progress_every == 0) sd_output_progress(c, r->t_end_est);
    /* after this step's outputs: a restart from it goes on at the top of the loop, as this run
     * does */
    if (r->ckpt_every && step % r->ckpt_every == 0) c->ckpt_pending = 1;
    /* a decomposed run's checkpoint waits for a step after which the pairs are remade (one comes
     * within t_reset): a restart remakes them at its first step, so it goes on as this run does */
    const int ckpt_now = c->ckpt_pending && (!c->sys || sd_run_slabs_rebuilds_next(c));
    const int out_failed = c->sys ? (c->sys_flags & SD_AGREE_OUTPUT) != 0 : sd_output_failed(c) != 0;
    if (ckpt_now && c->phase != PH_DONE && !out_failed) {
        c->ckpt_pending = 0;
        st = c->sys && c->sys_synced_step != step ? sd_run_slabs_sync(c) : SD_OK;
        if (!st) st = sd_run_state_periodic(c);
        if (c->sys) st = (sd_status)sd_run_slabs_agree(c, st);
        if (st) {
            fprintf(o->err, "%s/checkpoint_%010ld.ckpt: cannot write: %s; the checkpoints written before are kept\n",
                    c->dir, step, st == SD_ERR_IO ? strerror(errno) : sd_status_message(st));
            r->code = 1;
            r->msg = "checkpoint failed";
            return 1;
        }
    }
    return 0;
}

/* After the loop: the final row, snapshot and picture, the files closed, the summary; res filled. */
void sd_run_end(sd_run *r)
{
    run_ctx *c = &r->c;
    const sd_scenario *s = c->s;
    const sd_run_opts *o = c->o;
    sd_run_result *res = &r->res;
    if (o->log && o->progress_tty) fputc('\n', o->log);
    if (c->sys) { /* the final outputs read the whole system */
        const sd_status st = sd_run_slabs_sync(c);
        if (st && !r->code) {
            r->code = 1;
            r->msg = sd_status_message(st);
        }
        c->sys_hash = sd_run_slabs_hash(c);
        sd_run_slabs_stats(c);
    }
    if (res->stopped_at_flow_end) {
        /* a shared flow: its outputs end at the checkpoint, which the branches continue */
        sd_output_close(c);
    } else {
        if (c->phase != PH_DONE && c->phase != PH_RUN && !c->flow_ended) {
            c->phase_end[c->phase] = sd_world_time(c->w);
            c->phase_wall[c->phase] = sd_now() - c->phase_w0;
        } else if (c->phase == PH_CAPTURE) {
            c->phase_end[c->phase] = sd_world_time(c->w);
            c->phase_wall[c->phase] = sd_now() - c->phase_w0;
        }
        sd_output_series_row(c);
        if (c->loads.n) {
            if (sd_pipe_loads_sample(&c->loads, c->w, sd_world_time(c->w))) sd_output_note_failure(c, "pipes.csv", errno);
            sd_pipe_loads_finish(&c->loads, c->capture_cut || c->phase == PH_CAPTURE);
            if (sd_pipe_loads_close(&c->loads)) sd_output_note_failure(c, "pipes.csv or events.csv", errno);
        }
        sd_output_snapshot(c, "final");
        if (s->flume_on && r->code == 0) sd_output_picture(c, "final", "side_final.png", s->x_dam - 1.0, s->x_end);
        const int failed_before = sd_output_failed(c);
        if (sd_output_finish(c) && !failed_before) {
            fprintf(o->err, "%s/%s: cannot write: %s\n", c->dir, c->out_file, strerror(c->out_errno));
            if (r->code == 0 || r->code == 130) r->code = 1;
            r->msg = "output failed";
        }
    }
    if (sd_output_summary(c, res, r->code, r->msg)) {
        fprintf(o->err, "%s: cannot write summary.json: %s\n", c->dir, strerror(errno));
        if (!r->code) r->code = 1;
    }
    res->n_passed = c->n_passed;
    for (int k = 0; k < c->loads.n; k++)
        res->peak_dam_force = fmax(res->peak_dam_force, c->loads.p[k].peak);
    sd_pipe_loads_free(&c->loads);
    res->steps = sd_world_step_count(c->w);
    res->wall_time = sd_now() - c->wall0;
    res->n_pictures = c->n_plots;
    memcpy(res->pictures, c->plots, (size_t)c->n_plots * sizeof c->plots[0]);
    res->flow_wall = c->flow_wall;
    res->restarted = c->restarted_from != NULL;
    res->state_hash = c->sys ? c->sys_hash : sd_world_state_hash(c->w);
    sd_run_slabs_end(c);
    for (int k = 0; k < 4; k++)
        res->phase_end[k] = c->phase_end[k];
    r->finished = 1;
}

int sd_run_scenario(const sd_scenario *s, const sd_run_opts *o, sd_run_result *res)
{
    sd_run *r = calloc(1, sizeof *r);
    memset(res, 0, sizeof(*res));
    if (!r) {
        fprintf(o->err, "%s: out of memory\n", s->path);
        return 1;
    }
    r->o = *o;
    r->c.s = s;
    r->c.o = &r->o;
    r->c.wall0 = sd_now();
    int code = sd_run_begin(r);
    if (!code) {
        while (!sd_run_step_once(r)) {
        }
        sd_run_end(r);
        code = r->code;
        sd_world_destroy(r->c.w);
    }
    *res = r->res;
    free(r);
    return code;
}

int sd_run_check_restart(const sd_scenario *s, const char *path, char *msg, size_t msglen)
{
    sd_world *w = NULL;
    void *blob = NULL;
    size_t len = 0;
    char m[1600];
    sd_status st = sd_checkpoint_read(path, &w, &blob, &len, m, sizeof m);
    if (st) {
        snprintf(msg, msglen, "%s", m[0] ? m : sd_status_message(st));
        return -1;
    }
    run_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    sd_run_restored r;
    int bad = sd_run_state_unpack(&c, blob, len, &r, m, sizeof m);
    sd_pipe_loads_free(&c.loads);
    free(blob);
    sd_world_destroy(w);
    if (bad) {
        snprintf(msg, msglen, "%s: %s", path, m);
        return -1;
    }
    sd_run_state_free(&r);
    return 0;
}
