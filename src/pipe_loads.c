/* Pipe loads in design terms (pipe_loads.h, docs/loads.md). */
#include "pipe_loads.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/vmath.h"
#include "geom/geom.h"

double sd_pipe_resultant_position(sd_vec3 a, sd_vec3 f, sd_vec3 t, double *f_across)
{
    /* F at s a (plus a radial offset parallel to F for a normal force): t = s a x F, so
     * (a x F) . t = s |a x F|^2, and |a x F| is the force across the axis */
    const sd_vec3 axf = v3_cross(a, f);
    const double q = v3_dot(axf, axf);
    *f_across = sqrt(q);
    return q > 0.0 ? v3_dot(axf, t) / q : 0.0;
}

double sd_pipe_bending_moment(int support, double span, double x, double p)
{
    if (span <= 0.0) return 0.0;
    x = fmin(fmax(x, 0.0), span);
    const double y = span - x;
    if (support == SD_SUPPORT_FIXED) return p * fmax(x * y * y, x * x * y) / (span * span);
    return p * x * y / span;
}

static int attach(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                  const char *csv_path, const char *events_path, int append)
{
    L->support = s->dam_support;
    L->window = (int)lround(s->quiet_time / s->log_interval);
    if (L->window < 2) L->window = 2;
    L->n = info->n_pipes;
    L->ev_time = s->event_time;
    L->gravity = sd_world_definition(w)->gravity;
    L->near_step = -1;
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
        p->gid = info->pipe_gid[k];
        p->kind = info->pipe_kind[k];
        p->coord = info->pipe_coord[k];
        sd_body_state st;
        if (sd_world_body(w, p->gid, &st)) {
            p->span = 0.0;
            p->lo = p->hi = v3(0, 0, 0);
            continue;
        }
        p->span = st.length;
        /* the pipe's box: its axis' ends grown by the radius on every axis */
        const sd_vec3 h = v3_scale(st.axis, 0.5 * st.length), e = v3(st.radius, st.radius, st.radius);
        p->lo = v3_sub(v3_sub(st.pos, v3(fabs(h.x), fabs(h.y), fabs(h.z))), e);
        p->hi = v3_add(v3_add(st.pos, v3(fabs(h.x), fabs(h.y), fabs(h.z))), e);
    }
    if (csv_path) {
        L->csv = fopen(csv_path, append ? "a" : "w");
        if (!L->csv) return -1;
        if (!append) fprintf(L->csv, "t_s,pipe,kind,axis_m,fx_N,fy_N,fz_N,f_N,f_peak_interval_N,s_m,m_bend_Nm\n");
    }
    if (events_path) {
        L->ev_csv = fopen(events_path, append ? "a" : "w");
        if (!L->ev_csv) return -1;
        if (!append)
            fprintf(L->ev_csv, "pipe,kind,axis_m,t_start_s,duration_s,peak_N,t_peak_s,impulse_Ns,impulse_x_Ns,"
                               "impulse_y_Ns,impulse_z_Ns,energy_J,baseline_N,end\n");
    }
    return 0;
}

int sd_pipe_loads_start(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                        const char *csv_path, const char *events_path)
{
    memset(L, 0, sizeof *L);
    /* the threshold: given, or four times the weight of the heaviest moving body, so that an
     * event ends (below half of it) once a boulder has come to rest on the pipe */
    L->ev_threshold = s->event_threshold;
    if (!(L->ev_threshold > 0.0)) {
        const sd_body_view b = sd_world_bodies(w);
        double m = 0.0;
        for (int i = 0; i < b.n; i++)
            if (!b.fixed[i]) m = fmax(m, b.mass[i]);
        L->ev_threshold = 4.0 * m * v3_norm(sd_world_definition(w)->gravity);
    }
    return attach(L, s, info, w, csv_path, events_path, 0);
}

int sd_pipe_loads_resume(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                         const char *csv_path, const char *events_path)
{
    if (L->n != info->n_pipes) return -1;
    return attach(L, s, info, w, csv_path, events_path, 1);
}

/* a pipe's force across its axis, the resultant's position from the pipe's start (m) and the
 * bending moment, from its body state */
static double pipe_moment(const sd_pipe_loads *L, const sd_pipe_load *p, const sd_body_state *st, double *s_from_start)
{
    double fa;
    const double sc = sd_pipe_resultant_position(st->axis, st->force, st->torque, &fa);
    /* the pipe's start: the bed for a column, the wall at y = 0 for a beam (the axis may point
     * either way along them), a member's first end (its axis was made from the first end to the
     * second, build.c) */
    const double along = p->kind == SD_PIPE_COLUMN ? st->axis.z : p->kind == SD_PIPE_BEAM ? st->axis.y : 1.0;
    const double x = 0.5 * p->span + (along >= 0.0 ? sc : -sc);
    *s_from_start = fmin(fmax(x, 0.0), p->span);
    return sd_pipe_bending_moment(L->support, p->span, *s_from_start, fa);
}

double sd_pipe_impact_power(const sd_body_state *pipe, sd_vec3 f, const sd_body_view *b, const sd_pipe_near *near,
                            int n, sd_vec3 gravity, double dt, int *stale)
{
    const sd_cyl cy = {pipe->pos, pipe->axis, pipe->radius, 0.5 * pipe->length};
    const sd_vec3 h = v3_scale(pipe->axis, 0.5 * pipe->length);
    const sd_vec3 ext = v3(fabs(h.x) + pipe->radius, fabs(h.y) + pipe->radius, fabs(h.z) + pipe->radius);
    sd_vec3 u_sum = v3(0, 0, 0);
    double w_sum = 0.0;
    *stale = 0;
    for (int j = 0; j < n; j++) {
        const int i = near[j].index;
        if (i >= b->n || b->gid[i] != near[j].gid) {
            *stale = -1;
            return 0.0;
        }
        /* grown by the step's travel: the force was found where the body was a step ago */
        const double slack = v3_norm(b->vel[i]) * dt + 1e-9, reach = b->bound_radius[i] + slack;
        const sd_vec3 d = v3_sub(b->pos[i], pipe->pos);
        if (fabs(d.x) > ext.x + reach || fabs(d.y) > ext.y + reach || fabs(d.z) > ext.z + reach) continue;
        sd_manifold m;
        int hit;
        if (b->shape[i] == SD_SHAPE_SPHERE)
            hit = sd_geom_sphere_cyl(b->pos[i], b->radius[i] + slack, &cy, &m);
        else {
            const sd_cyl a = {b->pos[i], b->axis[i], b->radius[i] + slack, b->half_length[i] + slack};
            hit = sd_geom_cyl_cyl(&a, &cy, &m);
        }
        if (!hit) continue;
        double wt = 0.0;
        sd_vec3 pc = v3(0, 0, 0);
        for (int k = 0; k < m.n; k++) {
            wt += m.overlap[k];
            pc = v3_madd(pc, m.point[k], m.overlap[k]);
        }
        if (!(wt > 0.0)) continue;
        pc = v3_scale(pc, 1.0 / wt);
        /* the velocity at the middle of the step: leapfrog's v(t + Δt/2) less half the step's
         * acceleration (contact and gravity; the water's, not in the view, is small beside them) */
        const sd_vec3 acc = v3_add(v3_scale(b->force[i], 1.0 / b->mass[i]), gravity);
        const sd_vec3 v = v3_madd(b->vel[i], acc, -0.5 * dt);
        sd_vec3 om = b->omega[i];
        if (b->shape[i] == SD_SHAPE_SPHERE)
            om = v3_madd(om, b->torque[i], -0.5 * dt / (0.4 * b->mass[i] * b->radius[i] * b->radius[i]));
        const sd_vec3 u = v3_add(v, v3_cross(om, v3_sub(pc, b->pos[i])));
        u_sum = v3_madd(u_sum, u, wt);
        w_sum += wt;
    }
    return w_sum > 0.0 ? v3_dot(f, u_sum) / w_sum : 0.0;
}

static int cmp_near(const void *a, const void *b)
{
    const int x = ((const sd_pipe_near *)a)->gid, y = ((const sd_pipe_near *)b)->gid;
    return (x > y) - (x < y);
}

/* every pipe's near list anew; -1 when out of memory */
static int near_lists(sd_pipe_loads *L, const sd_body_view *b, double dt)
{
    const double horizon = 2.0 * SD_PIPE_NEAR_STEPS * dt;
    for (int k = 0; k < L->n; k++)
        L->p[k].n_near = 0;
    for (int i = 0; i < b->n; i++) {
        if (b->fixed[i]) continue;
        const double g = b->bound_radius[i] + v3_norm(b->vel[i]) * horizon + SD_PIPE_NEAR_MARGIN;
        const sd_vec3 x = b->pos[i];
        for (int k = 0; k < L->n; k++) {
            sd_pipe_load *p = &L->p[k];
            if (x.x < p->lo.x - g || x.x > p->hi.x + g || x.y < p->lo.y - g || x.y > p->hi.y + g ||
                x.z < p->lo.z - g || x.z > p->hi.z + g)
                continue;
            if (p->n_near == p->cap_near) {
                const int cap = p->cap_near ? 2 * p->cap_near : 64;
                sd_pipe_near *q = realloc(p->near, (size_t)cap * sizeof *q);
                if (!q) return -1;
                p->near = q;
                p->cap_near = cap;
            }
            p->near[p->n_near++] = (sd_pipe_near){b->gid[i], i};
        }
    }
    for (int k = 0; k < L->n; k++)
        if (L->p[k].n_near > 1) /* (an empty list has no array: qsort may not be given NULL) */
            qsort(L->p[k].near, (size_t)L->p[k].n_near, sizeof(sd_pipe_near), cmp_near);
    return 0;
}

/* the power on pipe k's strikers (sd_pipe_impact_power), its near lists made anew when stale */
static double event_power(sd_pipe_loads *L, int k, const sd_body_state *st, const sd_world *w, double dt)
{
    const sd_body_view b = sd_world_bodies(w);
    const long step = sd_world_step_count(w);
    sd_pipe_load *p = &L->p[k];
    int stale = L->near_step < 0 || step - L->near_step >= SD_PIPE_NEAR_STEPS;
    for (int pass = 0; pass < 2; pass++) {
        if (stale) {
            if (near_lists(L, &b, dt)) {
                L->ev_csv_bad = 1; /* (out of memory: reported as a failed write) */
                return 0.0;
            }
            L->near_step = step;
        }
        const double pw = sd_pipe_impact_power(st, st->force, &b, p->near, p->n_near, L->gravity, dt, &stale);
        if (!stale) return pw;
    }
    return 0.0; /* (not reached: a list just made holds its indices) */
}

static int event_row(sd_pipe_loads *L, int k, int why)
{
    static const char *const end[] = {"fell", "sustained", "run_end"};
    sd_pipe_load *p = &L->p[k];
    const sd_pipe_event *e = &p->ev;
    p->in_event = 0;
    p->n_events++;
    p->ev_peak = fmax(p->ev_peak, e->peak);
    p->ev_impulse = fmax(p->ev_impulse, e->impulse);
    p->ev_energy = fmax(p->ev_energy, e->energy);
    if (!L->ev_csv) return 0;
    /* a member has no one axis coordinate (as in pipes.csv) */
    fprintf(L->ev_csv, "%d,%s,", k, sd_build_pipe_kind_name(p->kind));
    if (p->kind != SD_PIPE_MEMBER) fprintf(L->ev_csv, "%.6f", p->coord);
    fprintf(L->ev_csv, ",%.6f,%.6e,%.6e,%.6f,%.6e,%.6e,%.6e,%.6e,", e->t0, e->duration, e->peak, e->t_peak, e->impulse,
            e->impulse_vec.x, e->impulse_vec.y, e->impulse_vec.z);
    if (!L->no_energy) fprintf(L->ev_csv, "%.6e", e->energy); /* (none: the field left empty) */
    fprintf(L->ev_csv, ",%.6e,%s\n", e->base, end[why]);
    return ferror(L->ev_csv) ? -1 : 0;
}

double sd_pipe_loads_step(sd_pipe_loads *L, const sd_world *w, double t, double dt)
{
    double tot = 0.0;
    const double T = L->ev_threshold, a = L->ev_time > dt ? dt / L->ev_time : 1.0;
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
        sd_body_state st;
        if (sd_world_body(w, p->gid, &st)) continue;
        const double f = v3_norm(st.force);
        tot += f;
        if (f > p->peak) {
            p->peak = f;
            p->t_peak = t;
        }
        if (f > p->interval_peak) p->interval_peak = f;
        p->impulse += f * dt;
        p->impulse_vec = v3_madd(p->impulse_vec, st.force, dt);
        if (f > 0.0) {
            double s;
            const double m = pipe_moment(L, p, &st, &s);
            if (m > p->m_peak) {
                p->m_peak = m;
                p->t_m_peak = t;
                p->s_at_m_peak = s;
            }
        }
        /* impact events (docs/loads.md): the baseline follows |F| outside events; an event
         * begins above the baseline plus the threshold, ends below the baseline plus half of it
         * (the hysteresis keeps a load hovering at the threshold from making many events), or
         * after event_time, when the load has become the new baseline */
        if (p->in_event && f < p->base + 0.5 * T) {
            if (event_row(L, k, SD_EVENT_FELL)) L->ev_csv_bad = 1;
        } else if (p->in_event && p->ev.duration >= L->ev_time) {
            if (event_row(L, k, SD_EVENT_SUSTAINED)) L->ev_csv_bad = 1;
            p->base = f;
            continue;
        }
        if (!p->in_event && f > p->base + T) {
            p->in_event = 1;
            memset(&p->ev, 0, sizeof p->ev);
            p->ev.t0 = t - dt;
            p->ev.base = p->base;
        }
        if (!p->in_event) {
            p->base += a * (f - p->base);
            continue;
        }
        sd_pipe_event *e = &p->ev;
        e->duration += dt;
        if (f > e->peak) {
            e->peak = f;
            e->t_peak = t;
        }
        e->impulse += f * dt;
        e->impulse_vec = v3_madd(e->impulse_vec, st.force, dt);
        const double pw = L->no_energy ? 0.0 : event_power(L, k, &st, w, dt);
        if (pw > 0.0) e->energy += pw * dt;
    }
    return tot;
}

static int push_sample(sd_pipe_load *p, sd_vec3 v)
{
    if (p->n_f == p->cap_f) {
        const int cap = p->cap_f ? 2 * p->cap_f : 256;
        sd_vec3 *m = realloc(p->f, (size_t)cap * sizeof *m);
        if (!m) return -1;
        p->f = m;
        p->cap_f = cap;
    }
    p->f[p->n_f++] = v;
    return 0;
}

int sd_pipe_loads_sample(sd_pipe_loads *L, const sd_world *w, double t)
{
    int bad = 0;
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
        sd_body_state st;
        if (sd_world_body(w, p->gid, &st)) continue;
        double s = 0.5 * p->span, m = 0.0;
        const double f = v3_norm(st.force);
        if (f > 0.0) m = pipe_moment(L, p, &st, &s);
        if (push_sample(p, st.force)) bad = 1;
        if (L->csv) {
            /* a member has no one axis coordinate: its ends are in summary.json */
            fprintf(L->csv, "%.6f,%d,%s,", t, k, sd_build_pipe_kind_name(p->kind));
            if (p->kind != SD_PIPE_MEMBER) fprintf(L->csv, "%.6f", p->coord);
            fprintf(L->csv, ",%.6e,%.6e,%.6e,%.6e,%.6e,%.5f,%.6e\n", st.force.x, st.force.y, st.force.z, f,
                    p->interval_peak, s, m);
        }
        p->interval_peak = 0.0;
    }
    if (L->csv && ferror(L->csv)) bad = 1;
    if (L->ev_csv_bad || (L->ev_csv && ferror(L->ev_csv))) bad = 1; /* (the events' rows since the last sample) */
    return bad ? -1 : 0;
}

void sd_pipe_loads_finish(sd_pipe_loads *L, int cut_by_limit)
{
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
        if (p->in_event && event_row(L, k, SD_EVENT_RUN_END)) L->ev_csv_bad = 1;
        const int n = p->n_f;
        int win = L->window;
        if (2 * win > n) win = n / 2;
        if (win < 1) continue;
        sd_vec3 mean = v3(0, 0, 0);
        double last = 0.0, before = 0.0;
        for (int i = n - win; i < n; i++) {
            mean = v3_add(mean, p->f[i]);
            last += v3_norm(p->f[i]);
        }
        for (int i = n - 2 * win; i < n - win; i++)
            before += v3_norm(p->f[i]);
        p->sustained = v3_scale(mean, 1.0 / win);
        p->rising = cut_by_limit && last > 1.1 * before;
    }
}

int sd_pipe_loads_close(sd_pipe_loads *L)
{
    int bad = L->ev_csv_bad;
    if (L->csv) bad |= ferror(L->csv) | fclose(L->csv);
    if (L->ev_csv) bad |= ferror(L->ev_csv) | fclose(L->ev_csv);
    L->csv = L->ev_csv = NULL;
    return bad ? -1 : 0;
}

void sd_pipe_loads_free(sd_pipe_loads *L)
{
    if (L->csv) fclose(L->csv);
    if (L->ev_csv) fclose(L->ev_csv);
    L->csv = L->ev_csv = NULL;
    for (int k = 0; k < L->n; k++) {
        free(L->p[k].f);
        free(L->p[k].near);
        L->p[k].f = NULL;
        L->p[k].near = NULL;
        L->p[k].n_f = L->p[k].cap_f = L->p[k].n_near = L->p[k].cap_near = 0;
    }
}

static void event_pack(const sd_pipe_event *e, sd_bin_writer *b)
{
    sd_bin_put_f64(b, e->t0);
    sd_bin_put_f64(b, e->duration);
    sd_bin_put_f64(b, e->peak);
    sd_bin_put_f64(b, e->t_peak);
    sd_bin_put_f64(b, e->impulse);
    sd_bin_put_vec3(b, e->impulse_vec);
    sd_bin_put_f64(b, e->energy);
    sd_bin_put_f64(b, e->base);
}

static void event_unpack(sd_pipe_event *e, sd_bin_reader *r)
{
    e->t0 = sd_bin_get_f64(r);
    e->duration = sd_bin_get_f64(r);
    e->peak = sd_bin_get_f64(r);
    e->t_peak = sd_bin_get_f64(r);
    e->impulse = sd_bin_get_f64(r);
    e->impulse_vec = sd_bin_get_vec3(r);
    e->energy = sd_bin_get_f64(r);
    e->base = sd_bin_get_f64(r);
}

void sd_pipe_loads_pack(const sd_pipe_loads *L, sd_bin_writer *b)
{
    sd_bin_put_i32(b, L->n);
    sd_bin_put_f64(b, L->ev_threshold);
    for (int k = 0; k < L->n; k++) {
        const sd_pipe_load *p = &L->p[k];
        sd_bin_put_f64(b, p->base);
        sd_bin_put_i32(b, p->in_event);
        event_pack(&p->ev, b);
        sd_bin_put_i32(b, p->n_events);
        sd_bin_put_f64(b, p->ev_peak);
        sd_bin_put_f64(b, p->ev_impulse);
        sd_bin_put_f64(b, p->ev_energy);
        sd_bin_put_f64(b, p->peak);
        sd_bin_put_f64(b, p->t_peak);
        sd_bin_put_f64(b, p->impulse);
        sd_bin_put_vec3(b, p->impulse_vec);
        sd_bin_put_f64(b, p->m_peak);
        sd_bin_put_f64(b, p->t_m_peak);
        sd_bin_put_f64(b, p->s_at_m_peak);
        sd_bin_put_f64(b, p->interval_peak);
        sd_bin_put_i32(b, p->n_f);
        sd_bin_put(b, p->f, (size_t)p->n_f * sizeof *p->f);
    }
}

int sd_pipe_loads_unpack(sd_pipe_loads *L, sd_bin_reader *r)
{
    memset(L, 0, sizeof *L);
    L->n = sd_bin_get_i32(r);
    if (L->n < 0 || L->n > SD_MAX_DAM_PIPES) {
        L->n = 0;
        return -1;
    }
    L->ev_threshold = sd_bin_get_f64(r);
    if (!(L->ev_threshold >= 0.0 && isfinite(L->ev_threshold))) return -1;
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
        p->base = sd_bin_get_f64(r);
        p->in_event = sd_bin_get_i32(r);
        event_unpack(&p->ev, r);
        p->n_events = sd_bin_get_i32(r);
        p->ev_peak = sd_bin_get_f64(r);
        p->ev_impulse = sd_bin_get_f64(r);
        p->ev_energy = sd_bin_get_f64(r);
        if ((p->in_event != 0 && p->in_event != 1) || p->n_events < 0 || !isfinite(p->base) ||
            !isfinite(p->ev.duration))
            return -1;
        p->peak = sd_bin_get_f64(r);
        p->t_peak = sd_bin_get_f64(r);
        p->impulse = sd_bin_get_f64(r);
        sd_bin_get(r, &p->impulse_vec, sizeof p->impulse_vec);
        p->m_peak = sd_bin_get_f64(r);
        p->t_m_peak = sd_bin_get_f64(r);
        p->s_at_m_peak = sd_bin_get_f64(r);
        p->interval_peak = sd_bin_get_f64(r);
        const int n = sd_bin_get_i32(r);
        if (n < 0 || (size_t)n * sizeof(sd_vec3) > sd_bin_left(r)) return -1;
        for (int i = 0; i < n; i++) {
            sd_vec3 v;
            sd_bin_get(r, &v, sizeof v);
            if (push_sample(p, v)) return -1;
        }
    }
    return 0;
}
