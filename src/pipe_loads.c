/* Pipe loads in design terms (pipe_loads.h, docs/loads.md). */
#include "pipe_loads.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/vmath.h"

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
                  const char *csv_path, int append)
{
    L->support = s->dam_support;
    L->window = (int)lround(s->quiet_time / s->log_interval);
    if (L->window < 2) L->window = 2;
    L->n = info->n_pipes;
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
        p->gid = info->pipe_gid[k];
        p->kind = info->pipe_kind[k];
        p->coord = info->pipe_coord[k];
        sd_body_state st;
        p->span = sd_world_body(w, p->gid, &st) ? 0.0 : st.length;
    }
    if (!csv_path) return 0;
    L->csv = fopen(csv_path, append ? "a" : "w");
    if (!L->csv) return -1;
    if (!append) fprintf(L->csv, "t_s,pipe,kind,axis_m,fx_N,fy_N,fz_N,f_N,f_peak_interval_N,s_m,m_bend_Nm\n");
    return 0;
}

int sd_pipe_loads_start(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                        const char *csv_path)
{
    memset(L, 0, sizeof *L);
    return attach(L, s, info, w, csv_path, 0);
}

int sd_pipe_loads_resume(sd_pipe_loads *L, const sd_scenario *s, const sd_build_info *info, const sd_world *w,
                         const char *csv_path)
{
    if (L->n != info->n_pipes) return -1;
    return attach(L, s, info, w, csv_path, 1);
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

double sd_pipe_loads_step(sd_pipe_loads *L, const sd_world *w, double t, double dt)
{
    double tot = 0.0;
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
    return bad ? -1 : 0;
}

void sd_pipe_loads_finish(sd_pipe_loads *L, int cut_by_limit)
{
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
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
    if (!L->csv) return 0;
    const int bad = ferror(L->csv) | fclose(L->csv);
    L->csv = NULL;
    return bad ? -1 : 0;
}

void sd_pipe_loads_free(sd_pipe_loads *L)
{
    if (L->csv) fclose(L->csv);
    L->csv = NULL;
    for (int k = 0; k < L->n; k++) {
        free(L->p[k].f);
        L->p[k].f = NULL;
        L->p[k].n_f = L->p[k].cap_f = 0;
    }
}

void sd_pipe_loads_pack(const sd_pipe_loads *L, sd_bin_writer *b)
{
    sd_bin_put_i32(b, L->n);
    for (int k = 0; k < L->n; k++) {
        const sd_pipe_load *p = &L->p[k];
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
    for (int k = 0; k < L->n; k++) {
        sd_pipe_load *p = &L->p[k];
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
