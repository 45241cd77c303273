/* The files a run writes (series.csv, trajectories.csv, VTK snapshots and walls, summary.json),
 * the pictures it asks its caller for, and the progress line. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/status.h"
#include "core/vmath.h"
#include "run_ctx.h"

/* the first write that failed is kept (a full disk fails every later one too) */
static void out_failed(run_ctx *c, const char *file, int e)
{
    if (c->out_errno) return;
    c->out_errno = e ? e : EIO;
    snprintf(c->out_file, sizeof c->out_file, "%s", file);
}

int sd_output_failed(const run_ctx *c) { return c->out_errno; }

void sd_output_note_failure(run_ctx *c, const char *file, int e) { out_failed(c, file, e); }

void sd_output_series_row(run_ctx *c)
{
    if (!c->series) return;
    double cls[SD_MAX_CLASSES], logs;
    int n_up;
    sd_trap_volumes_upstream(c, cls, &logs, &n_up);
    double up = logs;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        up += cls[k];
    double pv = c->s->flume_on ? sd_trap_ratio(c, NULL, NULL, &n_up) : 0.0;
    /* what the debris does to the bed: the load on the bed roughness (the fixed spheres) and on
     * the bed's triangles */
    sd_vec3 rough, tri_bed;
    sd_trap_fixed_loads(c, &rough, &tri_bed);
    /* and on the dam body of meshes (role dam) */
    const sd_vec3 mesh_dam = c->n_dam_tri ? sd_world_group_force(c->w, SD_GROUP_DAM) : v3(0.0, 0.0, 0.0);
    fprintf(c->series, "%.6f,%s,%.6f,%.9e,%.9e,%ld,%.6e,%.6f,%.6f,%d,%d,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n",
            sd_world_time(c->w), sd_run_phase_name(c->phase), sd_world_body_count(c->w) ? sd_trap_front_x(c) : 0.0, up,
            sd_world_kinetic_energy(c->w), c->sys ? c->sys_contacts : sd_world_contact_count(c->w), c->dam_force_now, pv, c->h_d,
            sd_world_body_count(c->w), c->n_passed, rough.x, rough.z, tri_bed.x, tri_bed.z, mesh_dam.x, mesh_dam.y,
            mesh_dam.z);
    if (ferror(c->series)) out_failed(c, "series.csv", errno);
}

void sd_output_traj(run_ctx *c)
{
    if (!c->traj) return;
    for (int k = 0; k < c->s->n_traj; k++) {
        sd_body_state st;
        if (sd_world_body(c->w, c->s->traj_ids[k], &st)) continue;
        fprintf(c->traj,
                "%.9f,%d,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.9f,%.9f,%.9f,%.9e,%.9e,%.9e\n",
                sd_world_time(c->w), st.gid, st.pos.x, st.pos.y, st.pos.z, st.vel.x, st.vel.y, st.vel.z, st.omega.x, st.omega.y,
                st.omega.z, st.axis.x, st.axis.y, st.axis.z, st.force.x, st.force.y, st.force.z);
    }
    if (ferror(c->traj)) out_failed(c, "trajectories.csv", errno);
}

int sd_output_snapshot(run_ctx *c, const char *name)
{
    if (!c->s->vtk_on || c->rank != 0) return 0; /* (a decomposed run's rank 0 writes the whole copy) */
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    size_t cap = (size_t)(b->n + 1);
    sd_vec3 *pos = malloc(cap * sizeof(sd_vec3)), *vel = malloc(cap * sizeof(sd_vec3)),
            *ax = malloc(cap * sizeof(sd_vec3));
    double *rad = malloc(cap * sizeof(double)), *len = malloc(cap * sizeof(double));
    int *id = malloc(cap * sizeof(int)), *tag = malloc(cap * sizeof(int));
    int rc = -1;
    if (pos && vel && ax && rad && len && id && tag) {
        char r1[256], r2[256], f[1400];
        snprintf(r1, sizeof r1, "spheres_%s.vtp", name);
        snprintf(r2, sizeof r2, "cylinders_%s.vtp", name);
        for (int pass = 0; pass < 2; pass++) {
            size_t m = 0;
            for (int i = 0; i < b->n; i++) {
                if ((b->shape[i] == SD_SHAPE_SPHERE) != (pass == 0)) continue;
                pos[m] = b->pos[i];
                vel[m] = b->vel[i];
                ax[m] = b->axis[i];
                rad[m] = b->radius[i];
                len[m] = 2.0 * b->half_length[i];
                id[m] = b->gid[i];
                tag[m] = b->tag[i];
                m++;
            }
            snprintf(f, sizeof f, "%s/%s", c->dir, pass == 0 ? r1 : r2);
            rc = pass == 0 ? sd_vtk_write_spheres(f, m, pos, rad, vel, id, tag)
                           : sd_vtk_write_cylinders(f, m, pos, ax, len, rad, vel, id, tag);
            if (rc) {
                out_failed(c, pass == 0 ? r1 : r2, errno);
                break;
            }
        }
        if (!rc && c->pvd_on) {
            rc = sd_vtk_series_add(&c->pvd, sd_world_time(c->w), 0, r1);
            if (!rc) rc = sd_vtk_series_add(&c->pvd, sd_world_time(c->w), 1, r2);
            if (rc) out_failed(c, "series.pvd", errno);
        }
    } else {
        out_failed(c, "snapshot", ENOMEM);
    }
    free(pos);
    free(vel);
    free(ax);
    free(rad);
    free(len);
    free(id);
    free(tag);
    c->n_snap++;
    return rc;
}

int sd_output_walls(run_ctx *c)
{
    if (!c->s->vtk_on || c->rank != 0) return 0;
    const int nt = sd_world_triangle_count(c->w);
    char f[1200];
    snprintf(f, sizeof f, "%s/walls.vtp", c->dir);
    sd_vec3 *v = malloc((size_t)(3 * nt + 1) * sizeof(sd_vec3));
    int *g = malloc((size_t)(nt + 1) * sizeof(int));
    int rc = -1;
    if (v && g) {
        for (int t = 0; t < nt; t++)
            sd_world_triangle(c->w, t, &v[3 * t], &g[t], NULL);
        rc = sd_vtk_write_triangles(f, (size_t)nt, v, g);
    }
    free(v);
    free(g);
    return rc;
}

/* A side view of snapshot `name` into png, from the snapshot's files, for the caller to draw
 * after the run (sd_run_result.pictures: the driver starts no program). The arrival's picture,
 * drawn when the front reached the dam, held the two threads up for the ~1.5 s of a Python
 * process; drawn at the end beside the final one, the two cost the run ~1.5 s instead of ~3. */
void sd_output_picture(run_ctx *c, const char *name, const char *png, double xmin, double xmax)
{
    if (!c->s->png_on || !c->s->vtk_on || c->n_plots >= SD_RUN_PICTURES) return;
    sd_run_picture *p = &c->plots[c->n_plots++];
    snprintf(p->spheres, sizeof p->spheres, "%s/spheres_%s.vtp", c->dir, name);
    snprintf(p->logs, sizeof p->logs, "%s/cylinders_%s.vtp", c->dir, name);
    snprintf(p->png, sizeof p->png, "%s/%s", c->dir, png);
    p->x_dam = c->s->x_dam;
    p->x_min = xmin;
    p->x_max = xmax;
}

void sd_output_progress(run_ctx *c, double t_end_est)
{
    double wall = sd_now() - c->rate_wall0;
    double sps = wall > 0 ? (double)(sd_world_step_count(c->w) - c->rate_step0) / wall : 0.0;
    double eta = sps > 0 && t_end_est > sd_world_time(c->w) ? (t_end_est - sd_world_time(c->w)) / sd_world_definition(c->w)->dt / sps : 0.0;
    if (!c->o->log) return;
    /* to a pipe or a file: a line at most every progress_interval seconds of wall time (the
     * command line's default: 5 s), so that the log of a long run stays short */
    const double now = sd_now();
    if (!c->o->progress_tty && c->progress_lines > 0 && now - c->progress_wall < c->o->progress_interval) return;
    c->progress_wall = now;
    c->progress_lines++;
    if (c->o->progress_tty)
        fprintf(c->o->log, "\r%-8s t = %8.4f s  %9.0f steps/s  %6d elements  ETA %6.0f s   ", sd_run_phase_name(c->phase),
                sd_world_time(c->w), sps, sd_world_body_count(c->w), eta);
    else
        fprintf(c->o->log, "phase=%s t=%.4f steps_per_s=%.0f elements=%d passed=%d eta_s=%.0f\n", sd_run_phase_name(c->phase),
                sd_world_time(c->w), sps, sd_world_body_count(c->w), c->n_passed, eta);
    fflush(c->o->log);
}

/* summary.json, built with cJSON (strings escaped, numbers printed with the digits that read
 * back to the same double), one function per part; a new field goes into its part. Each part
 * returns 0, or -1 when out of memory. */
static int add_num(cJSON *o, const char *key, double v) { return cJSON_AddNumberToObject(o, key, v) ? 0 : -1; }
static int add_str(cJSON *o, const char *key, const char *v) { return cJSON_AddStringToObject(o, key, v) ? 0 : -1; }
static cJSON *add_obj(cJSON *o, const char *key) { return cJSON_AddObjectToObject(o, key); }
static int add_xyz(cJSON *o, const char *key, sd_vec3 v)
{
    const double xyz[3] = {v.x, v.y, v.z};
    cJSON *a = cJSON_CreateDoubleArray(xyz, 3);
    if (a && cJSON_AddItemToObject(o, key, a)) return 0;
    cJSON_Delete(a);
    return -1;
}

/* what ran, how it ended, how long it took */
static int summary_run(run_ctx *c, cJSON *o, int status_code, const char *status_msg)
{
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)(c->sys ? c->sys_hash : sd_world_state_hash(c->w)));
    int bad = add_str(o, "scenario", c->s->path) | add_str(o, "status", status_msg) |
              add_num(o, "exit_code", status_code) | add_num(o, "simulated_time_s", sd_world_time(c->w)) |
              add_num(o, "steps", (double)sd_world_step_count(c->w)) | add_num(o, "wall_time_s", sd_now() - c->wall0) |
              add_str(o, "state_hash", hash);
    if (c->restarted_from)
        bad |= add_str(o, "restarted_from", c->restarted_from) | add_num(o, "restart_flow_wall_s", c->flow_wall);
    return bad;
}

/* how the engine ran (the same bits whatever it says: for the speed) */
static int summary_engine(run_ctx *c, cJSON *o)
{
    static const char *const simd_names[] = {"auto", "scalar", "avx2", "avx512"};
    const sd_world *sw = sd_run_slabs_world(c); /* (a decomposed run: rank 0's slab) */
    int bad = add_str(o, "simd_kernels", simd_names[sd_world_simd_level(sw)]);
    /* the front prefetch and, in auto mode, the last trial's verdict and its time on over off */
    double pf_ratio = 0.0;
    int pf_trial = -1;
    const int pf_on = sd_world_prefetch(sw, &pf_trial, &pf_ratio) == SD_PREFETCH_ON;
    char pf[64];
    if (sd_world_definition(sw)->tuning.prefetch != SD_PREFETCH_AUTO)
        snprintf(pf, sizeof pf, "%s (set)", pf_on ? "on" : "off");
    else if (pf_trial < 0)
        snprintf(pf, sizeof pf, "%s (no trial)", pf_on ? "on" : "off");
    else
        snprintf(pf, sizeof pf, "%s (trial: on/off %.3f)", pf_trial ? "on" : "off", pf_ratio);
    bad |= add_str(o, "front_prefetch", pf);
    const sd_world_timers tm = sd_world_get_timers(sw);
    cJSON *t = add_obj(o, "timers_s");
    if (!t) return -1;
    if (c->sys) { /* the slabs (docs/decomposition.md); the timers are rank 0's */
        const sd_run_slabs_report *r = &c->sys_report;
        cJSON *d = add_obj(o, "decomposition");
        cJSON *xb = cJSON_AddArrayToObject(d, "bounds_m");
        if (!d || !xb) return -1;
        for (int k = 1; k < r->ranks; k++)
            if (!cJSON_AddItemToArray(xb, cJSON_CreateNumber(r->bounds[k]))) bad = 1;
        bad |= add_num(d, "ranks", r->ranks) | add_num(d, "ghost_width_m", r->ghost_width) |
               add_num(d, "redistributions", (double)r->redistributions) | add_num(d, "migrations", (double)r->migrations) |
               add_num(d, "boundary_moves", (double)r->boundary_moves) | add_num(d, "bytes_sent", r->bytes);
    }
    return bad | add_num(t, "rebuild", tm.rebuild) | add_num(t, "contacts", tm.contacts) | add_num(t, "moves", tm.moves) |
           add_num(t, "checks", tm.checks) | add_num(t, "rebuilds", (double)tm.rebuilds);
}

static int summary_elements(run_ctx *c, cJSON *o)
{
    cJSON *e = add_obj(o, "elements");
    if (!e) return -1;
    return add_num(e, "moving_spheres", c->info.n_spheres) | add_num(e, "logs", c->info.n_logs) |
           add_num(e, "roughness_spheres", c->info.n_rough) | add_num(e, "pipes", c->info.n_pipes) |
           add_num(e, "triangles", sd_world_triangle_count(c->w)) | add_num(e, "passed", c->n_passed) |
           add_num(e, "remaining", sd_world_body_count(c->w));
}

/* a flume run: what the dam holds (P_V, per class, logs), the deposit, the phases, the flow */
static int summary_trap(run_ctx *c, cJSON *o, sd_run_result *res)
{
    const sd_scenario *s = c->s;
    double per[SD_MAX_CLASSES] = {0}, logs_ratio = 0.0;
    int n_up = 0;
    const double pv = sd_trap_ratio(c, per, &logs_ratio, &n_up);
    res->p_v = pv;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        res->p_v_class[k] = per[k];
    res->p_v_logs = logs_ratio;
    res->n_upstream = n_up;
    int bad = add_num(o, "trap_ratio", pv) | add_num(o, "capture_limit_s", s->capture_limit);
    cJSON *cls = cJSON_AddArrayToObject(o, "trap_ratio_class");
    if (!cls) return -1;
    for (int k = 0; k < s->n_classes; k++) {
        cJSON *e = cJSON_CreateObject();
        if (!e || !cJSON_AddItemToArray(cls, e)) {
            cJSON_Delete(e);
            return -1;
        }
        bad |= add_num(e, "diameter", s->class_diam[k]) | add_num(e, "p_v", per[k]);
    }
    double vt = c->vol_total_logs, vs = 0;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        vs += c->vol_total_class[k];
    bad |= add_num(o, "trap_ratio_logs", logs_ratio) | add_num(o, "k_w", vt + vs > 0 ? vt / (vt + vs) : 0.0);
    cJSON *vol = add_obj(o, "solid_volume_m3");
    if (!vol) return -1;
    bad |= add_num(vol, "spheres", vs) | add_num(vol, "logs", vt);
    /* the deposit at the dam: the highest true top within the probe length; floating logs apart */
    double dep, float_top;
    int n_float;
    sd_trap_deposit(c, &dep, &n_float, &float_top);
    bad |= add_num(o, "deposit_height_at_dam_m", dep);
    cJSON *fl_dam = add_obj(o, "floating_at_dam");
    if (!fl_dam) return -1;
    bad |= add_num(fl_dam, "count", n_float) | add_num(fl_dam, "top_m", float_top);
    cJSON *pk = add_obj(o, "packing_end");
    if (!pk) return -1;
    bad |= add_num(pk, "t_s", c->phase_end[PH_PACK]) | add_str(pk, "ended_by", c->pack_at_rest ? "rest" : "time limit") |
           add_num(pk, "speed_max_m_s", c->pack_speed[0]) | add_num(pk, "speed_p99_m_s", c->pack_speed[1]) |
           add_num(pk, "speed_mean_m_s", c->pack_speed[2]);
    static const char *const phases[3] = {"packing", "flow", "capture"};
    cJSON *pe = add_obj(o, "phase_end_s"), *pw = add_obj(o, "phase_wall_s");
    if (!pe || !pw) return -1;
    for (int k = 0; k < 3; k++)
        bad |= add_num(pe, phases[k], c->phase_end[k]) | add_num(pw, phases[k], c->phase_wall[k]);
    if (c->flow_len_done) {
        cJSON *fl = add_obj(o, "flow_at_1m_before_dam");
        if (!fl) return -1;
        bad |= add_num(fl, "t", c->flow_len_time) | add_num(fl, "length_q05_q95_m", c->flow_len) |
               add_num(fl, "q05_m", c->flow_q05) | add_num(fl, "q95_m", c->flow_q95) | add_num(fl, "front_m", c->flow_front);
    }
    return bad;
}

/* each pipe of the dam (docs/loads.md): where it is, its span, its peak force and moment (when,
 * where), its impulse, the sustained load, whether the load was still rising at the end */
static int summary_pipes(run_ctx *c, cJSON *o)
{
    cJSON *pipes = cJSON_AddArrayToObject(o, "pipes");
    if (!pipes) return -1;
    int bad = add_str(o, "pipe_support", c->s->dam_support ? "fixed ends" : "simply supported") |
              add_num(o, "event_threshold_N", c->loads.ev_threshold) | add_num(o, "event_time_s", c->loads.ev_time);
    for (int k = 0; k < c->loads.n; k++) {
        const sd_pipe_load *L = &c->loads.p[k];
        cJSON *p = cJSON_CreateObject();
        if (!p || !cJSON_AddItemToArray(pipes, p)) {
            cJSON_Delete(p);
            return -1;
        }
        const double sus[3] = {L->sustained.x, L->sustained.y, L->sustained.z};
        cJSON *sv = cJSON_CreateDoubleArray(sus, 3);
        if (!sv || !cJSON_AddItemToObject(p, "sustained_N", sv)) {
            cJSON_Delete(sv);
            return -1;
        }
        bad |= add_num(p, "gid", L->gid) | add_str(p, "kind", sd_build_pipe_kind_name(L->kind));
        if (L->kind == SD_PIPE_MEMBER) {
            /* (the run-driver state's reader made sure the index names a member) */
            const sd_dam_member *m = &c->s->members[(int)L->coord];
            bad |= add_num(p, "member", L->coord) | add_xyz(p, "from_m", m->from) | add_xyz(p, "to_m", m->to) |
                   add_num(p, "diameter_m", m->diameter);
        } else
            bad |= add_num(p, L->kind == SD_PIPE_COLUMN ? "y_m" : "z_axis_m", L->coord);
        bad |= add_num(p, "span_m", L->span) |
               add_num(p, "peak_force_N", L->peak) | add_num(p, "peak_time_s", L->t_peak) |
               add_num(p, "impulse_Ns", L->impulse) | add_num(p, "impulse_x_Ns", L->impulse_vec.x) |
               add_num(p, "peak_moment_Nm", L->m_peak) | add_num(p, "peak_moment_time_s", L->t_m_peak) |
               add_num(p, "peak_moment_at_m", L->s_at_m_peak) |
               (cJSON_AddBoolToObject(p, "rising_at_end", L->rising) ? 0 : -1);
        cJSON *ev = add_obj(p, "events");
        if (!ev) return -1;
        bad |= add_num(ev, "count", L->n_events) | add_num(ev, "largest_peak_N", L->ev_peak) |
               add_num(ev, "largest_impulse_Ns", L->ev_impulse) | (c->loads.no_energy ? (cJSON_AddNullToObject(ev, "largest_energy_J") ? 0 : -1)
                                   : add_num(ev, "largest_energy_J", L->ev_energy));
    }
    return bad;
}

/* the dam body of meshes (docs/meshes.md): its triangles, the peak of its load and when, the
 * impulses, the load at the end */
static int summary_dam_mesh(run_ctx *c, cJSON *o)
{
    cJSON *d = add_obj(o, "dam_mesh");
    if (!d) return -1;
    const sd_vec3 f = sd_world_group_force(c->w, SD_GROUP_DAM);
    const double fe[3] = {f.x, f.y, f.z};
    cJSON *fv = cJSON_CreateDoubleArray(fe, 3);
    if (!fv || !cJSON_AddItemToObject(d, "final_force_N", fv)) {
        cJSON_Delete(fv);
        return -1;
    }
    return add_num(d, "triangles", c->n_dam_tri) | add_num(d, "peak_force_N", c->mesh_dam_peak) | add_num(d, "peak_time_s", c->mesh_dam_t_peak) |
           add_num(d, "impulse_Ns", c->mesh_dam_impulse) | add_num(d, "impulse_x_Ns", c->mesh_dam_impulse_vec.x) |
           add_num(d, "impulse_z_Ns", c->mesh_dam_impulse_vec.z);
}

/* where the debris ended (docs/loads.md): held at the dam, in the channel, passed; how the
 * capture ended */
static int summary_debris(run_ctx *c, cJSON *o, sd_run_result *res)
{
    double held, channel, passed, dep_x0;
    sd_trap_split(c, &held, &channel, &passed, &dep_x0);
    res->v_held = held;
    res->v_channel = channel;
    res->v_passed = passed;
    res->capture_cut = c->capture_cut;
    cJSON *d = add_obj(o, "debris_m3");
    if (!d) return -1;
    return add_num(d, "held_at_dam", held) | add_num(d, "in_channel", channel) | add_num(d, "passed", passed) |
           add_num(d, "deposit_from_x_m", dep_x0) |
           add_str(o, "capture", c->phase_end[PH_CAPTURE] <= 0.0 ? "not reached"
                                 : c->capture_cut                ? "cut by its time limit"
                                                                 : "settled");
}

static int add_range(cJSON *o, const char *key, double lo, double mean, double sd, double hi)
{
    cJSON *r = add_obj(o, key);
    return r ? add_num(r, "min", lo) | add_num(r, "mean", mean) | add_num(r, "sd", sd) | add_num(r, "max", hi) : -1;
}

/* the debris a flume run releases (docs/scenario.md "Debris as designers give it"): the sphere
 * classes with their counts, and the mass fractions asked and got when a grading made them; the
 * logs' count and sizes */
static int summary_released(run_ctx *c, cJSON *o)
{
    const sd_scenario *s = c->s;
    cJSON *d = add_obj(o, "debris_released");
    if (!d) return -1;
    static const char *const source[] = {"spheres.counts", "spheres.grading", "spheres.distribution"};
    int bad = add_str(d, "classes_from", source[s->class_source]);
    if (s->class_source != SD_CLASSES_COUNTS) bad |= add_num(d, "volume_asked_m3", s->sphere_volume);
    double vs = 0.0;
    for (int k = 0; k < s->n_classes; k++)
        vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
    cJSON *cls = cJSON_AddArrayToObject(d, "spheres");
    if (!cls) return -1;
    for (int k = 0; k < s->n_classes; k++) {
        cJSON *e = cJSON_CreateObject();
        if (!e || !cJSON_AddItemToArray(cls, e)) {
            cJSON_Delete(e);
            return -1;
        }
        const double v = s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
        bad |= add_num(e, "diameter_m", s->class_diam[k]) | add_num(e, "count", s->class_count[k]) |
               add_num(e, "volume_m3", v) | add_num(e, "mass_fraction", vs > 0 ? v / vs : 0.0);
        if (s->class_source != SD_CLASSES_COUNTS) bad |= add_num(e, "mass_fraction_asked", s->class_target[k]);
    }
    sd_log_stats ls;
    sd_build_log_stats(s, &ls);
    cJSON *lg = add_obj(d, "logs");
    if (!lg) return -1;
    bad |= add_num(lg, "count", ls.n) | add_num(lg, "volume_m3", ls.volume) |
           (cJSON_AddBoolToObject(lg, "sizes_drawn", sd_build_log_sizes_vary(s)) ? 0 : -1) |
           add_range(lg, "length_m", ls.len_min, ls.len_mean, ls.len_sd, ls.len_max) |
           add_range(lg, "diameter_m", ls.d_min, ls.d_mean, ls.d_sd, ls.d_max);
    return bad;
}

char *sd_output_summary_text(run_ctx *c, sd_run_result *res, int status_code, const char *status_msg)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    int bad = summary_run(c, o, status_code, status_msg) | summary_engine(c, o) | summary_elements(c, o);
    if (c->s->flume_on)
        bad |= summary_released(c, o) | summary_trap(c, o, res) | summary_debris(c, o, res) | summary_pipes(c, o);
    if (c->n_dam_tri) bad |= summary_dam_mesh(c, o);
    /* the materials and the springs of each pair that can meet (or is given) */
    cJSON *mat = sd_scenario_materials_json(c->s);
    for (int k = 0; k < 2 && mat; k++) {
        const char *key = k ? "contact_pairs" : "materials";
        cJSON *item = cJSON_DetachItemFromObject(mat, key);
        if (!item || !cJSON_AddItemToObject(o, key, item)) {
            cJSON_Delete(item);
            bad = 1;
        }
    }
    bad |= !mat;
    cJSON_Delete(mat);
    cJSON *par = sd_scenario_params_json(c->s);
    if (!par || !cJSON_AddItemToObject(o, "parameters", par)) {
        cJSON_Delete(par);
        bad = 1;
    }
    char *text = bad ? NULL : cJSON_Print(o);
    cJSON_Delete(o);
    return text;
}

void sd_output_summary_free(char *text) { cJSON_free(text); }

int sd_output_summary(run_ctx *c, sd_run_result *res, int status_code, const char *status_msg)
{
    char path[1200], tmp[1300];
    snprintf(path, sizeof path, "%s/summary.json", c->dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    char *text = sd_output_summary_text(c, res, status_code, status_msg);
    if (!text) {
        errno = ENOMEM;
        return -1;
    }
    if (c->rank != 0) { /* (a decomposed run's rank 0 writes it) */
        cJSON_free(text);
        return 0;
    }
    FILE *f = fopen(tmp, "w");
    if (!f) {
        cJSON_free(text);
        return -1;
    }
    fputs(text, f);
    fputc('\n', f);
    cJSON_free(text);
    int bad = ferror(f);
    if (fclose(f) || bad || rename(tmp, path)) { /* (no half-written summary left behind) */
        const int e = errno;
        unlink(tmp);
        errno = e;
        return -1;
    }
    return 0;
}

int sd_output_finish(run_ctx *c)
{
    if (c->series && (fflush(c->series) || ferror(c->series))) out_failed(c, "series.csv", errno);
    if (c->traj && (fflush(c->traj) || ferror(c->traj))) out_failed(c, "trajectories.csv", errno);
    if (c->series && fclose(c->series)) out_failed(c, "series.csv", errno);
    if (c->traj && fclose(c->traj)) out_failed(c, "trajectories.csv", errno);
    c->series = c->traj = NULL;
    if (c->pvd_on) {
        if (sd_vtk_series_flush(&c->pvd)) out_failed(c, "series.pvd", errno);
        sd_vtk_series_free(&c->pvd);
        c->pvd_on = 0;
    }
    return c->out_errno;
}

void sd_output_close(run_ctx *c)
{
    if (c->series) fclose(c->series);
    if (c->traj) fclose(c->traj);
    if (c->pvd_on) sd_vtk_series_free(&c->pvd);
    c->series = c->traj = NULL;
    c->pvd_on = 0;
}
