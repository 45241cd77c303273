/* `sabodem check`'s report: the scene in a designer's terms (see scene_report.h). */
#include "scene_report.h"

#include <math.h>
#include <string.h>

#include "core/vmath.h"

void sd_dam_report_make(const sd_scenario *s, sd_dam_report *d)
{
    memset(d, 0, sizeof *d);
    for (int k = 0; k < s->n_classes; k++)
        if (s->class_count[k] > 0 && s->class_diam[k] > d->d_max) d->d_max = s->class_diam[k];
    if (!s->flume_on || !s->dam_on) return;
    sd_dam_grid g;
    sd_build_dam_grid(s, &g);
    d->n_col = g.n_col;
    d->n_beam = g.n_beam;
    d->top_beam = g.top_beam;
    d->col_top = g.col_top;
    memcpy(d->col_y, g.col_y, sizeof d->col_y);
    memcpy(d->beam_z, g.beam_z, sizeof d->beam_z);
    d->n_member = s->n_members;
    memcpy(d->member, s->members, sizeof d->member);
    const double dp = s->pipe_diam;
    double prev = 0.0; /* the near wall, then each column's far side */
    for (int k = 0; k < d->n_col; k++) {
        d->gap_y[k] = d->col_y[k] - 0.5 * dp - prev;
        prev = d->col_y[k] + 0.5 * dp;
    }
    d->gap_y[d->n_col] = s->width - prev;
    prev = 0.0; /* the bed, then each beam's top */
    for (int k = 0; k < d->n_beam; k++) {
        d->gap_z[k] = d->beam_z[k] - 0.5 * dp - prev;
        prev = d->beam_z[k] + 0.5 * dp;
    }
    d->gap_z[d->n_beam] = s->wall_height - prev;
}

double sd_scene_k_w(const sd_scenario *s)
{
    double vs = 0.0;
    for (int k = 0; k < s->n_classes; k++)
        vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
    double vlog;
    if (sd_build_log_sizes_vary(s)) {
        sd_log_stats ls;
        sd_build_log_stats(s, &ls);
        vlog = ls.volume;
    } else
        vlog = sd_build_log_count(s) * M_PI * 0.25 * s->log_diam * s->log_diam * s->log_length;
    return vs + vlog > 0.0 ? vlog / (vs + vlog) : 0.0;
}

static void list_mm(FILE *f, const double *v, int n)
{
    for (int k = 0; k < n; k++)
        fprintf(f, "%s%.1f", k ? ", " : "", 1e3 * v[k]);
}

void sd_scene_report(FILE *f, const sd_scenario *s, const sd_build_info *info, int n_bodies, int n_triangles)
{
    fprintf(f, "scene: %d elements (%d moving), %d triangles\n", n_bodies, n_bodies - info->n_rough - info->n_pipes,
            n_triangles);
    static const char *const role[3] = {"bed", "wall", "dam"};
    for (int k = 0; k < s->n_meshes; k++) {
        const sd_mesh_def *m = &s->meshes[k];
        sd_vec3 lo = m->tri[0][0], hi = lo;
        for (int t = 0; t < m->n_tri; t++)
            for (int v = 0; v < 3; v++) {
                lo = v3(fmin(lo.x, m->tri[t][v].x), fmin(lo.y, m->tri[t][v].y), fmin(lo.z, m->tri[t][v].z));
                hi = v3(fmax(hi.x, m->tri[t][v].x), fmax(hi.y, m->tri[t][v].y), fmax(hi.z, m->tri[t][v].z));
            }
        fprintf(f, "mesh %s (%s STL), role %s: %d triangles, x %.4g to %.4g, y %.4g to %.4g, z %.4g to %.4g m\n",
                m->file, m->binary ? "binary" : "ASCII", role[m->role], m->n_tri, lo.x, hi.x, lo.y, hi.y, lo.z, hi.z);
    }
    sd_scenario_materials_report(f, s);
    if (!s->flume_on) return;
    fprintf(f, "flume: %.3f m to the end of the bed, %.3f m wide, walls %.3f m high, slope %.1f deg; gate at x = %.3f m, "
               "dam face at x = %.3f m\n",
            s->x_end, s->width, s->wall_height, s->slope_deg, s->x_gate, s->x_dam);
    fprintf(f, "  bed roughness: %d fixed spheres\n", info->n_rough);
    double vs = 0.0;
    fprintf(f, "debris released at the gate:\n");
    for (int k = 0; k < s->n_classes; k++)
        vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
    if (s->class_source == SD_CLASSES_GRADING)
        fprintf(f, "  spheres from spheres.grading and spheres.volume = %.3f L (counts by largest remainder):\n",
                1e3 * s->sphere_volume);
    else if (s->class_source == SD_CLASSES_CURVE)
        fprintf(f, "  spheres from spheres.distribution (%d classes of equal width in ln d from %.1f to %.1f mm) and "
                   "spheres.volume = %.3f L (counts by largest remainder):\n",
                s->n_classes, 1e3 * s->curve.d_min, 1e3 * s->curve.d_max, 1e3 * s->sphere_volume);
    for (int k = 0; k < s->n_classes; k++) {
        const double v = s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
        fprintf(f, "  spheres class %d: d = %.1f mm, %d, solid volume %.3f L", k, 1e3 * s->class_diam[k],
                s->class_count[k], 1e3 * v);
        if (s->class_source != SD_CLASSES_COUNTS)
            fprintf(f, ", mass fraction %.4f (asked %.4f)", vs > 0 ? v / vs : 0.0, s->class_target[k]);
        fputc('\n', f);
    }
    sd_log_stats ls;
    sd_build_log_stats(s, &ls);
    const int n_logs = ls.n;
    const double vlog = ls.volume;
    if (!sd_build_log_sizes_vary(s))
        fprintf(f, "  logs: %d, d = %.1f mm, L = %.1f mm, solid volume %.3f L\n", n_logs, 1e3 * s->log_diam,
                1e3 * s->log_length, 1e3 * vlog);
    else {
        fprintf(f, "  logs: %d, solid volume %.3f L, sizes drawn per log\n", n_logs, 1e3 * vlog);
        if (n_logs > 0)
            fprintf(f, "    L = %.1f to %.1f mm, mean %.1f mm, sd %.1f mm; d = %.1f to %.1f mm, mean %.1f mm, sd %.1f mm\n",
                    1e3 * ls.len_min, 1e3 * ls.len_max, 1e3 * ls.len_mean, 1e3 * ls.len_sd, 1e3 * ls.d_min,
                    1e3 * ls.d_max, 1e3 * ls.d_mean, 1e3 * ls.d_sd);
    }
    fprintf(f, "  solid volume %.3f L (spheres %.3f L); K_w = V_logs / (V_spheres + V_logs) = %.2f %%\n",
            1e3 * (vs + vlog), 1e3 * vs, vs + vlog > 0 ? 100.0 * vlog / (vs + vlog) : 0.0);
    sd_dam_report d;
    sd_dam_report_make(s, &d);
    if (d.n_col + d.n_beam + d.n_member == 0) {
        fprintf(f, "dam: none\n");
        return;
    }
    const double r = 0.5 * s->pipe_diam;
    fprintf(f, "dam: steel pipes d = %.1f mm, upstream face at x = %.3f m; d_max = %.1f mm (largest sphere)\n",
            1e3 * s->pipe_diam, s->x_dam, 1e3 * d.d_max);
    if (d.n_col > 0) {
        fprintf(f, "  %d column%s, axes at y = ", d.n_col, d.n_col > 1 ? "s" : "");
        list_mm(f, d.col_y, d.n_col);
        fprintf(f, " mm, from the bed to %.1f mm\n  clear gaps across (wall, between columns, wall): ", 1e3 * d.col_top);
        list_mm(f, d.gap_y, d.n_col + 1);
        fprintf(f, " mm\n");
    } else
        fprintf(f, "  no columns\n");
    if (d.n_beam > 0) {
        double under[SD_MAX_PIPES];
        for (int k = 0; k < d.n_beam; k++)
            under[k] = d.beam_z[k] - r;
        fprintf(f, "  %d beam%s, axes at z = ", d.n_beam, d.n_beam > 1 ? "s" : "");
        list_mm(f, d.beam_z, d.n_beam);
        fprintf(f, " mm above the bed (undersides ");
        list_mm(f, under, d.n_beam);
        fprintf(f, " mm; %s)\n  clear gaps up (bed, between beams, above the %s beam to the wall top): ",
                d.top_beam ? "the top beam at dam.top_beam" : s->n_beams > 0 ? "as dam.beams lists them" : "no top beam",
                d.top_beam ? "top" : "highest");
        list_mm(f, d.gap_z, d.n_beam + 1);
        fprintf(f, " mm\n");
    } else
        fprintf(f, "  no beams\n");
    /* the openings a designer compares with the debris: the widest column gap and the lowest
     * (bed to first beam) gap, against the largest boulder and the log length */
    if (d.n_col > 0) {
        double wide = 0.0;
        for (int k = 1; k < d.n_col; k++)
            if (d.gap_y[k] > wide) wide = d.gap_y[k];
        if (d.n_col < 2) wide = fmax(d.gap_y[0], d.gap_y[1]);
        if (d.d_max > 0)
            fprintf(f, "  l_H = %.1f mm: l_H/d_max = %.2f", 1e3 * wide, wide / d.d_max);
        else
            fprintf(f, "  l_H = %.1f mm", 1e3 * wide);
        if (n_logs > 0 && !sd_build_log_sizes_vary(s)) fprintf(f, ", l_H/L_log = %.2f", wide / s->log_length);
        if (n_logs > 0 && sd_build_log_sizes_vary(s))
            fprintf(f, ", l_H/L_log = %.2f (longest log) to %.2f (shortest)", wide / ls.len_max, wide / ls.len_min);
        fputc('\n', f);
    }
    if (d.n_beam > 1 || (d.n_beam == 1 && !d.top_beam)) {
        if (d.d_max > 0)
            fprintf(f, "  l_V = %.1f mm (bed to the lowest beam): l_V/d_max = %.2f\n", 1e3 * d.gap_z[0],
                    d.gap_z[0] / d.d_max);
        else
            fprintf(f, "  l_V = %.1f mm (bed to the lowest beam)\n", 1e3 * d.gap_z[0]);
    } else if (d.n_beam == 1 && d.d_max > 0)
        fprintf(f, "  no intermediate beam: bed to the top beam %.1f mm = %.2f d_max\n", 1e3 * d.gap_z[0],
                d.gap_z[0] / d.d_max);
    if (d.n_member > 0) fprintf(f, "  %d member%s (dam.members):\n", d.n_member, d.n_member > 1 ? "s" : "");
    for (int k = 0; k < d.n_member; k++) {
        const sd_dam_member *m = &d.member[k];
        const sd_vec3 a = v3_sub(m->to, m->from);
        const double len = v3_norm(a);
        fprintf(f, "    %d: from [%.4f, %.4f, %.4f] to [%.4f, %.4f, %.4f] m, d = %.1f mm, length %.1f mm, "
                   "%.1f deg from the bed plane\n",
                k, m->from.x, m->from.y, m->from.z, m->to.x, m->to.y, m->to.z, 1e3 * m->diameter, 1e3 * len,
                asin(fmin(1.0, fabs(a.z) / len)) * 180.0 / M_PI);
    }
}

static FILE *open_in(const char *dir, const char *name, char *path, size_t n, FILE *err)
{
    snprintf(path, n, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f && err) fprintf(err, "%s: cannot write\n", path);
    return f;
}

static int close_checked(FILE *f, const char *path, FILE *err)
{
    const int bad = ferror(f) | fclose(f);
    if (bad && err) fprintf(err, "%s: write failed\n", path);
    return bad ? -1 : 0;
}

int sd_scene_write_design(const char *dir, const sd_scenario *s, const sd_world *w, FILE *err)
{
    char path[1200];
    sd_dam_report d;
    sd_dam_report_make(s, &d);
    sd_log_stats dm; /* (the logs' mean size when drawn) */
    sd_build_log_stats(s, &dm);
    FILE *f = open_in(dir, "design.csv", path, sizeof path, err);
    if (!f) return -1;
    fprintf(f, "key,value\nflume,%d\nwidth,%.17g\nwall_height,%.17g\nslope_deg,%.17g\nx_gate,%.17g\n"
               "x_dam,%.17g\nx_end,%.17g\npipe_diameter,%.17g\nd_max,%.17g\nlog_diameter,%.17g\n"
               "log_length,%.17g\nlogs,%d\n",
            s->flume_on, s->width, s->wall_height, s->slope_deg, s->x_gate, s->x_dam, s->x_end, s->pipe_diam, d.d_max,
            sd_build_log_sizes_vary(s) ? dm.d_mean : s->log_diam, sd_build_log_sizes_vary(s) ? dm.len_mean : s->log_length,
            dm.n);
    if (close_checked(f, path, err)) return -1;
    if (!(f = open_in(dir, "members.csv", path, sizeof path, err))) return -1;
    fprintf(f, "kind,axis_m,x0,y0,z0,x1,y1,z1,diameter_m\n");
    if (s->flume_on && s->dam_on) {
        sd_dam_grid g;
        sd_build_dam_grid(s, &g);
        sd_dam_pipe pipe[SD_MAX_DAM_PIPES];
        const int n = sd_build_dam_pipes(s, &g, pipe);
        for (int k = 0; k < n; k++) {
            const sd_dam_pipe *p = &pipe[k];
            fprintf(f, "%s,", sd_build_pipe_kind_name(p->kind));
            if (p->kind != SD_PIPE_MEMBER) fprintf(f, "%.17g", p->coord);
            fprintf(f, ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", p->from.x, p->from.y, p->from.z, p->to.x,
                    p->to.y, p->to.z, 2.0 * p->radius);
        }
    }
    if (close_checked(f, path, err)) return -1;
    if (!(f = open_in(dir, "bodies.csv", path, sizeof path, err))) return -1;
    const sd_body_view b = sd_world_bodies(w);
    fprintf(f, "x,y,z,radius,half_length,ax,ay,az,fixed,tag\n");
    for (int i = 0; i < b.n; i++)
        fprintf(f, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d\n", b.pos[i].x, b.pos[i].y, b.pos[i].z, b.radius[i],
                b.half_length[i], b.axis[i].x, b.axis[i].y, b.axis[i].z, b.fixed[i], b.tag[i]);
    return close_checked(f, path, err);
}
