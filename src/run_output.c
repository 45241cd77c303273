/* The files a run writes (series.csv, trajectories.csv, VTK snapshots and walls, summary.json),
 * the pictures it asks its caller for, and the progress line. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    fprintf(c->series, "%.6f,%s,%.6f,%.9e,%.9e,%ld,%.6e,%.6f,%.6f,%d,%d\n", sd_world_time(c->w), sd_run_phase_name(c->phase),
            sd_world_body_count(c->w) ? sd_trap_front_x(c) : 0.0, up, sd_world_kinetic_energy(c->w), sd_world_contact_count(c->w),
            c->dam_force_now, pv, c->h_d, sd_world_body_count(c->w), c->n_passed);
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
    if (!c->s->vtk_on) return 0;
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
    if (!c->s->vtk_on) return 0;
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
    if (c->o->progress_tty)
        fprintf(c->o->log, "\r%-8s t = %8.4f s  %9.0f steps/s  %6d elements  ETA %6.0f s   ", sd_run_phase_name(c->phase),
                sd_world_time(c->w), sps, sd_world_body_count(c->w), eta);
    else
        fprintf(c->o->log, "phase=%s t=%.4f steps_per_s=%.0f elements=%d passed=%d eta_s=%.0f\n", sd_run_phase_name(c->phase),
                sd_world_time(c->w), sps, sd_world_body_count(c->w), c->n_passed, eta);
    fflush(c->o->log);
}

int sd_output_summary(run_ctx *c, sd_run_result *res, int status_code, const char *status_msg)
{
    char path[1200], tmp[1300];
    snprintf(path, sizeof path, "%s/summary.json", c->dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) return -1;
    const sd_scenario *s = c->s;
    double per[SD_MAX_CLASSES] = {0}, logs_ratio = 0.0;
    int n_up = 0;
    double pv = s->flume_on ? sd_trap_ratio(c, per, &logs_ratio, &n_up) : 0.0;
    fprintf(f, "{\n  \"scenario\": \"%s\",\n  \"status\": \"%s\",\n  \"exit_code\": %d,\n", s->path, status_msg,
            status_code);
    fprintf(f, "  \"simulated_time_s\": %.6f,\n  \"steps\": %ld,\n  \"wall_time_s\": %.3f,\n", sd_world_time(c->w), sd_world_step_count(c->w),
            sd_now() - c->wall0);
    fprintf(f, "  \"state_hash\": \"%016llx\",\n", (unsigned long long)sd_world_state_hash(c->w));
    /* the hand-written kernels this run used (the same bits at every level: for the speed) */
    static const char *const simd_names[] = {"auto", "scalar", "avx2", "avx512"};
    fprintf(f, "  \"simd_kernels\": \"%s\",\n", simd_names[sd_world_simd_level(c->w)]);
    /* the front prefetch (a hint: the same bits either way) and, in auto mode, the last trial's
     * verdict and its time on over off */
    double pf_ratio = 0.0;
    int pf_trial = -1;
    const int pf_on = sd_world_prefetch(c->w, &pf_trial, &pf_ratio) == SD_PREFETCH_ON;
    if (sd_world_definition(c->w)->tuning.prefetch != SD_PREFETCH_AUTO)
        fprintf(f, "  \"front_prefetch\": \"%s (set)\",\n", pf_on ? "on" : "off");
    else if (pf_trial < 0)
        fprintf(f, "  \"front_prefetch\": \"%s (no trial)\",\n", pf_on ? "on" : "off");
    else
        fprintf(f, "  \"front_prefetch\": \"%s (trial: on/off %.3f)\",\n", pf_trial ? "on" : "off", pf_ratio);
    if (c->restarted_from) {
        fprintf(f, "  \"restarted_from\": \"");
        for (const char *q = c->restarted_from; *q; q++)
            fprintf(f, *q == '"' || *q == '\\' ? "\\%c" : "%c", *q);
        fprintf(f, "\",\n  \"restart_flow_wall_s\": %.3f,\n", c->flow_wall);
    }
    sd_world_timers tm = sd_world_get_timers(c->w);
    fprintf(f,
            "  \"timers_s\": {\"rebuild\": %.3f, \"contacts\": %.3f, \"moves\": %.3f, \"checks\": %.3f, "
            "\"rebuilds\": %ld},\n",
            tm.rebuild, tm.contacts, tm.moves, tm.checks, tm.rebuilds);
    fprintf(f,
            "  \"elements\": {\"moving_spheres\": %d, \"logs\": %d, \"roughness_spheres\": %d, \"pipes\": %d, "
            "\"triangles\": %d, \"passed\": %d, \"remaining\": %d},\n",
            c->info.n_spheres, c->info.n_logs, c->info.n_rough, c->info.n_pipes, sd_world_triangle_count(c->w),
            c->n_passed, sd_world_body_count(c->w));
    if (s->flume_on) {
        res->p_v = pv;
        for (int k = 0; k < SD_MAX_CLASSES; k++)
            res->p_v_class[k] = per[k];
        res->p_v_logs = logs_ratio;
        res->n_upstream = n_up;
        fprintf(f, "  \"trap_ratio\": %.6f,\n  \"capture_limit_s\": %.3f,\n  \"trap_ratio_class\": [", pv,
                s->capture_limit);
        for (int k = 0; k < s->n_classes; k++)
            fprintf(f, "%s{\"diameter\": %g, \"p_v\": %.6f}", k ? ", " : "", s->class_diam[k], per[k]);
        double vt = c->vol_total_logs, vs = 0;
        for (int k = 0; k < SD_MAX_CLASSES; k++)
            vs += c->vol_total_class[k];
        fprintf(f,
                "],\n  \"trap_ratio_logs\": %.6f,\n  \"k_w\": %.6f,\n  \"solid_volume_m3\": {\"spheres\": %.9e, "
                "\"logs\": %.9e},\n",
                logs_ratio, vt + vs > 0 ? vt / (vt + vs) : 0.0, vs, vt);
        /* deposit height at the dam: top of the highest element within the probe length */
        double dep = 0.0;
        const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
        for (int i = 0; i < b->n; i++)
            if (!b->fixed[i] && b->pos[i].x >= s->x_dam - s->water_probe && b->pos[i].x <= sd_trap_plane_x(c))
                dep = fmax(dep, b->pos[i].z + b->bound_radius[i]);
        fprintf(f, "  \"deposit_height_at_dam_m\": %.5f,\n", dep);
        fprintf(f, "  \"phase_end_s\": {\"packing\": %.4f, \"flow\": %.4f, \"capture\": %.4f},\n", c->phase_end[0],
                c->phase_end[1], c->phase_end[2]);
        fprintf(f, "  \"phase_wall_s\": {\"packing\": %.2f, \"flow\": %.2f, \"capture\": %.2f},\n", c->phase_wall[0],
                c->phase_wall[1], c->phase_wall[2]);
        if (c->flow_len_done)
            fprintf(f,
                    "  \"flow_at_1m_before_dam\": {\"t\": %.4f, \"length_q05_q95_m\": %.4f, \"q05_m\": %.4f, "
                    "\"q95_m\": %.4f, \"front_m\": %.4f},\n",
                    c->flow_len_time, c->flow_len, c->flow_q05, c->flow_q95, c->flow_front);
        double held, channel, passed, dep_x0;
        sd_trap_split(c, &held, &channel, &passed, &dep_x0);
        res->v_held = held;
        res->v_channel = channel;
        res->v_passed = passed;
        res->capture_cut = c->capture_cut;
        fprintf(f,
                "  \"debris_m3\": {\"held_at_dam\": %.9e, \"in_channel\": %.9e, \"passed\": %.9e, "
                "\"deposit_from_x_m\": %.4f},\n",
                held, channel, passed, dep_x0);
        fprintf(f, "  \"capture\": \"%s\",\n",
                c->phase_end[PH_CAPTURE] <= 0.0 ? "not reached" : c->capture_cut ? "cut by its time limit" : "settled");
        fprintf(f, "  \"pipe_support\": \"%s\",\n", s->dam_support ? "fixed ends" : "simply supported");
        fprintf(f, "  \"pipes\": [\n");
        for (int k = 0; k < c->loads.n; k++) {
            const sd_pipe_load *p = &c->loads.p[k];
            fprintf(f,
                    "    {\"gid\": %d, \"kind\": \"%s\", \"%s\": %.4f, \"span_m\": %.4f, \"peak_force_N\": %.6e, "
                    "\"peak_time_s\": %.5f, \"impulse_Ns\": %.6e, \"impulse_x_Ns\": %.6e, \"peak_moment_Nm\": %.6e, "
                    "\"peak_moment_time_s\": %.5f, \"peak_moment_at_m\": %.4f, \"sustained_N\": [%.6e, %.6e, %.6e], "
                    "\"rising_at_end\": %s}%s\n",
                    p->gid, p->is_column ? "column" : "beam", p->is_column ? "y_m" : "z_axis_m", p->coord, p->span,
                    p->peak, p->t_peak, p->impulse, p->impulse_vec.x, p->m_peak, p->t_m_peak, p->s_at_m_peak,
                    p->sustained.x, p->sustained.y, p->sustained.z, p->rising ? "true" : "false",
                    k + 1 < c->loads.n ? "," : "");
        }
        fprintf(f, "  ],\n");
    }
    sd_scenario_echo_json(s, f);
    fprintf(f, "\n}\n");
    int bad = ferror(f);
    if (fclose(f) || bad) return -1;
    return rename(tmp, path);
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
