/* Builders (SPEC §6, §8). */
#include "build.h"

#include <stdlib.h>
#include <string.h>

#include "core/vmath.h"
#include "geom/geom.h"

/* a triangle of the builders, of a group and a material */
static sd_status add_tri(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, int group, int material)
{
    const int t = sd_world_add_triangle(w, a, b, c, group);
    if (t < 0) return SD_ERR_ARG;
    return sd_world_set_triangle_material(w, t, material);
}

sd_status sd_build_box(sd_world *w, sd_vec3 lo, sd_vec3 hi, int group, int material)
{
    sd_vec3 c[8];
    for (int k = 0; k < 8; k++)
        c[k] = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
    /* floor and four sides (open top): two triangles each */
    static const int q[5][4] = {{0, 1, 3, 2}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    for (int f = 0; f < 5; f++) {
        sd_status st = add_tri(w, c[q[f][0]], c[q[f][1]], c[q[f][2]], group, material);
        if (!st) st = add_tri(w, c[q[f][0]], c[q[f][2]], c[q[f][3]], group, material);
        if (st) return st;
    }
    return SD_OK;
}

/* Quad (a, b, c, d in order) as two triangles, split along x into pieces no longer than seg. */
static sd_status add_quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d, int group, int material, double seg)
{
    double len = v3_dist(a, b);
    int n = seg > 0 ? (int)ceil(len / seg) : 1;
    if (n < 1) n = 1;
    for (int k = 0; k < n; k++) {
        double s0 = (double)k / n, s1 = (double)(k + 1) / n;
        sd_vec3 p0 = v3_add(a, v3_scale(v3_sub(b, a), s0)), p1 = v3_add(a, v3_scale(v3_sub(b, a), s1));
        sd_vec3 q0 = v3_add(d, v3_scale(v3_sub(c, d), s0)), q1 = v3_add(d, v3_scale(v3_sub(c, d), s1));
        sd_status st = add_tri(w, p0, p1, q1, group, material);
        if (!st) st = add_tri(w, p0, q1, q0, group, material);
        if (st) return st;
    }
    return SD_OK;
}

typedef struct {
    sd_vec3 pos, axis;
    double r, hl;
} pitem;

struct sd_placer {
    sd_vec3 lo, hi;
    double cell;
    int nx, ny, nz;
    int **cells;
    int *ncell, *ccap;
    pitem *items;
    int n, cap;
};

sd_placer *sd_placer_create(sd_vec3 lo, sd_vec3 hi, double cell)
{
    sd_placer *p = calloc(1, sizeof(*p));
    if (!p) return NULL;
    p->lo = lo;
    p->hi = hi;
    p->cell = cell;
    const double ex = (hi.x - lo.x) / cell, ey = (hi.y - lo.y) / cell, ez = (hi.z - lo.z) / cell;
    /* an inverted or absurd box: no placer (the scenario loader refuses such boxes first) */
    if (!(ex >= 0 && ey >= 0 && ez >= 0) || (floor(ex) + 1) * (floor(ey) + 1) * (floor(ez) + 1) > 1e9) {
        free(p);
        return NULL;
    }
    p->nx = (int)ex + 1;
    p->ny = (int)ey + 1;
    p->nz = (int)ez + 1;
    size_t nc = (size_t)p->nx * p->ny * p->nz;
    p->cells = calloc(nc, sizeof(int *));
    p->ncell = calloc(nc, sizeof(int));
    p->ccap = calloc(nc, sizeof(int));
    if (!p->cells || !p->ncell || !p->ccap) {
        sd_placer_destroy(p);
        return NULL;
    }
    return p;
}

void sd_placer_destroy(sd_placer *p)
{
    if (!p) return;
    if (p->cells) {
        size_t nc = (size_t)p->nx * p->ny * p->nz;
        for (size_t c = 0; c < nc; c++)
            free(p->cells[c]);
    }
    free(p->cells);
    free(p->ncell);
    free(p->ccap);
    free(p->items);
    free(p);
}

static int clampc(double v, int n)
{
    const double f = floor(v); /* (clamped before the conversion: NaN and huge values too) */
    return f >= 0.0 ? (f < n ? (int)f : n - 1) : 0;
}

static void item_range(const sd_placer *p, sd_vec3 c, double ext, int r[6])
{
    r[0] = clampc((c.x - ext - p->lo.x) / p->cell, p->nx);
    r[1] = clampc((c.y - ext - p->lo.y) / p->cell, p->ny);
    r[2] = clampc((c.z - ext - p->lo.z) / p->cell, p->nz);
    r[3] = clampc((c.x + ext - p->lo.x) / p->cell, p->nx);
    r[4] = clampc((c.y + ext - p->lo.y) / p->cell, p->ny);
    r[5] = clampc((c.z + ext - p->lo.z) / p->cell, p->nz);
}

void sd_placer_add(sd_placer *p, sd_vec3 pos, sd_vec3 axis, double r, double hl)
{
    if (p->n == p->cap) {
        int nc = p->cap ? 2 * p->cap : 256;
        pitem *q = realloc(p->items, (size_t)nc * sizeof(*q));
        if (!q) return;
        p->items = q;
        p->cap = nc;
    }
    int id = p->n++;
    p->items[id] = (pitem){pos, v3_normalize(axis), r, hl};
    int rg[6];
    item_range(p, pos, sqrt(r * r + hl * hl), rg);
    for (int z = rg[2]; z <= rg[5]; z++)
        for (int y = rg[1]; y <= rg[4]; y++)
            for (int x = rg[0]; x <= rg[3]; x++) {
                size_t c = ((size_t)z * p->ny + y) * p->nx + x;
                if (p->ncell[c] == p->ccap[c]) {
                    int nc = p->ccap[c] ? 2 * p->ccap[c] : 4;
                    int *q = realloc(p->cells[c], (size_t)nc * sizeof(int));
                    if (!q) return;
                    p->cells[c] = q;
                    p->ccap[c] = nc;
                }
                p->cells[c][p->ncell[c]++] = id;
            }
}

/* Does a candidate (pos, axis, r, hl) overlap anything placed (with a clearance)? */
static int collides(const sd_placer *p, sd_vec3 pos, sd_vec3 axis, double r, double hl, double clearance)
{
    int rg[6];
    double ext = sqrt(r * r + hl * hl) + clearance;
    item_range(p, pos, ext, rg);
    sd_manifold m;
    for (int z = rg[2]; z <= rg[5]; z++)
        for (int y = rg[1]; y <= rg[4]; y++)
            for (int x = rg[0]; x <= rg[3]; x++) {
                size_t c = ((size_t)z * p->ny + y) * p->nx + x;
                for (int k = 0; k < p->ncell[c]; k++) {
                    const pitem *o = &p->items[p->cells[c][k]];
                    double reach = ext + sqrt(o->r * o->r + o->hl * o->hl);
                    if (v3_norm2(v3_sub(pos, o->pos)) >= reach * reach) continue;
                    int hit;
                    if (hl == 0.0 && o->hl == 0.0)
                        hit = sd_geom_sphere_sphere(pos, r + clearance, o->pos, o->r, &m);
                    else if (hl == 0.0) {
                        sd_cyl cy = {o->pos, o->axis, o->r, o->hl};
                        hit = sd_geom_sphere_cyl(pos, r + clearance, &cy, &m);
                    } else if (o->hl == 0.0) {
                        sd_cyl cy = {pos, axis, r + clearance, hl + clearance};
                        hit = sd_geom_sphere_cyl(o->pos, o->r, &cy, &m);
                    } else {
                        sd_cyl a = {pos, axis, r + clearance, hl + clearance}, b = {o->pos, o->axis, o->r, o->hl};
                        hit = sd_geom_cyl_cyl(&a, &b, &m);
                    }
                    if (hit) return 1;
                }
            }
    return 0;
}

int sd_placer_try_sphere(sd_placer *p, sd_rng *rng, double r, double clearance, int max_tries, sd_vec3 *pos)
{
    if (!(2 * r < p->hi.x - p->lo.x && 2 * r < p->hi.y - p->lo.y && 2 * r < p->hi.z - p->lo.z)) return 0;
    for (int t = 0; t < max_tries; t++) {
        sd_vec3 c = v3(sd_rng_range(rng, p->lo.x + r, p->hi.x - r), sd_rng_range(rng, p->lo.y + r, p->hi.y - r),
                       sd_rng_range(rng, p->lo.z + r, p->hi.z - r));
        if (!collides(p, c, v3(0, 0, 1), r, 0.0, clearance)) {
            sd_placer_add(p, c, v3(0, 0, 1), r, 0.0);
            *pos = c;
            return 1;
        }
    }
    return 0;
}

int sd_placer_try_cylinder(sd_placer *p, sd_rng *rng, double r, double hl, double clearance, int max_tries,
                           sd_vec3 *pos, sd_vec3 *axis)
{
    for (int t = 0; t < max_tries; t++) {
        /* axis uniform on the sphere */
        double z = sd_rng_range(rng, -1.0, 1.0), phi = sd_rng_range(rng, 0.0, 2.0 * M_PI);
        double s = sqrt(fmax(0.0, 1.0 - z * z));
        sd_vec3 a = v3(s * cos(phi), s * sin(phi), z);
        /* keep the whole log inside the box */
        sd_vec3 e = v3(hl * fabs(a.x) + r, hl * fabs(a.y) + r, hl * fabs(a.z) + r);
        if (2 * e.x >= p->hi.x - p->lo.x || 2 * e.y >= p->hi.y - p->lo.y || 2 * e.z >= p->hi.z - p->lo.z) continue;
        sd_vec3 c = v3(sd_rng_range(rng, p->lo.x + e.x, p->hi.x - e.x), sd_rng_range(rng, p->lo.y + e.y, p->hi.y - e.y),
                       sd_rng_range(rng, p->lo.z + e.z, p->hi.z - e.z));
        if (!collides(p, c, a, r, hl, clearance)) {
            sd_placer_add(p, c, a, r, hl);
            *pos = c;
            *axis = a;
            return 1;
        }
    }
    return 0;
}

/* ascending, in place (a handful of values) */
static void sort_up(double *v, int n)
{
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            const double t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
}

int sd_build_dam_grid(const sd_scenario *s, sd_dam_grid *g)
{
    memset(g, 0, sizeof *g);
    const double d = s->pipe_diam, r = 0.5 * d;
    int over = 0;
    if (s->n_columns > 0) {
        g->n_col = s->n_columns;
        for (int k = 0; k < s->n_columns; k++)
            g->col_y[k] = s->column_y[k];
        sort_up(g->col_y, g->n_col);
    } else if (s->column_count >= 0) {
        /* n columns centred, every clear gap the same, the two at the walls too: the pitch is
         * (W + d)/(n + 1), each gap (W - n d)/(n + 1) */
        const int n = s->column_count < SD_MAX_PIPES ? s->column_count : SD_MAX_PIPES;
        const double pitch = (s->width + d) / (n + 1);
        g->n_col = n;
        for (int k = 0; k < n; k++)
            g->col_y[k] = 0.5 * s->width + (k - 0.5 * (n - 1)) * pitch;
    } else {
        /* columns centred across the width, clear spacing l_h, wall gaps no wider than l_h */
        double pitch = s->l_h + d;
        const double nd = ceil((s->width - s->l_h) / pitch - 1e-9);
        int n = nd < 1 ? 1 : nd > SD_MAX_PIPES ? SD_MAX_PIPES : (int)nd;
        if (nd > SD_MAX_PIPES) over = 1;
        g->n_col = n;
        for (int k = 0; k < n; k++)
            g->col_y[k] = 0.5 * s->width + (k - 0.5 * (n - 1)) * pitch;
    }
    int n = 0;
    if (s->n_beams > 0) {
        /* every beam, the top one among them, by its underside */
        for (int k = 0; k < s->n_beams; k++)
            g->beam_z[n++] = s->beam_z[k] + r;
    } else {
        if (s->n_beam_axes > 0) {
            for (int k = 0; k < s->n_beam_axes; k++)
                g->beam_z[n++] = s->beam_axis_z[k];
        } else if (s->n_beam_gaps > 0) {
            double below = 0.0; /* the bed, then each beam's top */
            for (int k = 0; k < s->n_beam_gaps; k++) {
                g->beam_z[n++] = below + s->beam_gap[k] + r;
                below = g->beam_z[n - 1] + r;
            }
        } else if (s->l_v > 0.0)
            g->beam_z[n++] = s->l_v + r;
        sort_up(g->beam_z, n);
        if (s->top_beam_on) {
            g->beam_z[n++] = s->top_beam + r;
            g->top_beam = 1;
        }
    }
    if (s->n_beams > 0) sort_up(g->beam_z, n);
    g->n_beam = n;
    double top = -INFINITY;
    for (int k = 0; k < n; k++)
        top = fmax(top, g->beam_z[k] + r);
    g->col_top = n > 0 ? top : s->wall_height;
    return over ? -1 : 0;
}

int sd_build_dam_pipes(const sd_scenario *s, const sd_dam_grid *g, sd_dam_pipe *out)
{
    const double W = s->width, r = 0.5 * s->pipe_diam, xc = s->x_dam + r, top = g->col_top;
    int n = 0;
    for (int k = 0; k < g->n_col; k++)
        out[n++] = (sd_dam_pipe){SD_PIPE_COLUMN, g->col_y[k],      v3(xc, g->col_y[k], 0.0), v3(xc, g->col_y[k], top),
                                 v3(xc, g->col_y[k], 0.5 * top), v3(0, 0, 1),           top, r};
    for (int k = 0; k < g->n_beam; k++)
        out[n++] = (sd_dam_pipe){SD_PIPE_BEAM, g->beam_z[k],       v3(xc, 0.0, g->beam_z[k]), v3(xc, W, g->beam_z[k]),
                                 v3(xc, 0.5 * W, g->beam_z[k]), v3(0, 1, 0),            W,   r};
    for (int k = 0; k < s->n_members; k++) {
        const sd_dam_member *m = &s->members[k];
        const sd_vec3 ax = v3_sub(m->to, m->from);
        out[n++] = (sd_dam_pipe){SD_PIPE_MEMBER, k, m->from, m->to, v3_scale(v3_add(m->from, m->to), 0.5), ax,
                                 v3_norm(ax), 0.5 * m->diameter};
    }
    return n;
}

const char *sd_build_pipe_kind_name(int kind)
{
    return kind == SD_PIPE_COLUMN ? "column" : kind == SD_PIPE_BEAM ? "beam" : "member";
}

/* the point of segment a + t (b - a), t in [0, 1], nearest p, as its distance */
static double point_segment_distance(sd_vec3 p, sd_vec3 a, sd_vec3 b)
{
    const sd_vec3 ab = v3_sub(b, a);
    const double l2 = v3_dot(ab, ab);
    const double t = l2 > 0.0 ? fmin(fmax(v3_dot(v3_sub(p, a), ab) / l2, 0.0), 1.0) : 0.0;
    return v3_norm(v3_sub(p, v3_madd(a, ab, t)));
}

double sd_build_segment_distance(sd_vec3 p0, sd_vec3 p1, sd_vec3 q0, sd_vec3 q1)
{
    /* the least distance is at an end of one of them, or between two inner points where the
     * common normal of the two lines meets both segments */
    double best = fmin(fmin(point_segment_distance(p0, q0, q1), point_segment_distance(p1, q0, q1)),
                       fmin(point_segment_distance(q0, p0, p1), point_segment_distance(q1, p0, p1)));
    const sd_vec3 u = v3_sub(p1, p0), v = v3_sub(q1, q0), w0 = v3_sub(p0, q0);
    const double a = v3_dot(u, u), b = v3_dot(u, v), c = v3_dot(v, v), dd = v3_dot(u, w0), e = v3_dot(v, w0);
    const double den = a * c - b * b;
    if (den > 1e-12 * a * c) { /* not parallel: the lines' closest points */
        const double sp = (b * e - c * dd) / den, tq = (a * e - b * dd) / den;
        if (sp > 0.0 && sp < 1.0 && tq > 0.0 && tq < 1.0)
            best = fmin(best, v3_norm(v3_sub(v3_madd(p0, u, sp), v3_madd(q0, v, tq))));
    }
    return best;
}

int sd_build_log_sizes_vary(const sd_scenario *s)
{
    return s->log_length_dist.type != SD_SIZE_FIXED || s->log_diam_dist.type != SD_SIZE_FIXED;
}

double sd_build_log_mean_volume(const sd_scenario *s, int paper)
{
    if (!sd_build_log_sizes_vary(s)) /* (the expression eq 54's count has always used) */
        return paper ? s->log_diam * s->log_diam * s->log_length : M_PI * 0.25 * s->log_diam * s->log_diam * s->log_length;
    double l1, l2, d1, d2;
    sd_debris_size_moments(&s->log_length_dist, s->log_length, &l1, &l2);
    sd_debris_size_moments(&s->log_diam_dist, s->log_diam, &d1, &d2);
    return (paper ? 1.0 : M_PI * 0.25) * d2 * l1; /* the length and diameter are drawn apart */
}

/* eq 54's V for the logs' count and whether each log counts as d^2 L (the paper's) */
static double kw_volume(const sd_scenario *s, int *paper)
{
    *paper = s->log_kw_volume > 0.0;
    if (*paper) return s->log_kw_volume;
    double vs = 0.0;
    for (int k = 0; k < s->n_classes; k++)
        vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
    return vs;
}

/* The count from K_w when the sizes are drawn: the logs of the stream in order, as many as
 * bring their volume nearest to V_t = K_w V / (1 - K_w) (a tie: the more) */
static int drawn_log_count(const sd_scenario *s)
{
    int paper;
    const double vt = s->log_kw * kw_volume(s, &paper) / (1.0 - s->log_kw);
    sd_rng r = sd_debris_log_stream(s->seed);
    double sum = 0.0;
    for (int n = 0; n < SD_MAX_LOGS; n++) {
        double len, d;
        sd_debris_log_next(&r, &s->log_length_dist, s->log_length, &s->log_diam_dist, s->log_diam, &len, &d);
        const double v = (paper ? 1.0 : M_PI * 0.25) * d * d * len;
        if (sum + v >= vt) return sum + v - vt <= vt - sum ? n + 1 : n;
        sum += v;
    }
    return SD_MAX_LOGS;
}

void sd_build_log_stats(const sd_scenario *s, sd_log_stats *st)
{
    memset(st, 0, sizeof *st);
    st->n = sd_build_log_count(s);
    sd_rng r = sd_debris_log_stream(s->seed);
    double ml2 = 0.0, md2 = 0.0; /* Welford's sums of squared deviations: no cancellation */
    for (int k = 0; k < st->n; k++) {
        double len = s->log_length, d = s->log_diam;
        if (sd_build_log_sizes_vary(s))
            sd_debris_log_next(&r, &s->log_length_dist, s->log_length, &s->log_diam_dist, s->log_diam, &len, &d);
        st->len_min = k ? fmin(st->len_min, len) : len;
        st->len_max = k ? fmax(st->len_max, len) : len;
        st->d_min = k ? fmin(st->d_min, d) : d;
        st->d_max = k ? fmax(st->d_max, d) : d;
        const double dl = len - st->len_mean, dd = d - st->d_mean;
        st->len_mean += dl / (k + 1);
        st->d_mean += dd / (k + 1);
        ml2 += dl * (len - st->len_mean);
        md2 += dd * (d - st->d_mean);
        st->volume += M_PI * 0.25 * d * d * len;
    }
    if (st->n > 0) { /* the sample's own spread (divided by n): 0 for one log or fixed sizes */
        st->len_sd = sqrt(ml2 / st->n);
        st->d_sd = sqrt(md2 / st->n);
    }
}

double sd_build_placer_cell(const sd_scenario *s, int pile)
{
    double d = SD_PLACER_CELL;
    if (pile) {
        for (int k = 0; k < s->pile_n_classes && k < s->pile_n_counts; k++)
            if (s->pile_count[k] > 0) d = fmax(d, s->pile_diam[k]);
        return d;
    }
    for (int k = 0; k < s->n_classes && k < s->n_class_counts; k++)
        if (s->class_count[k] > 0) d = fmax(d, s->class_diam[k]);
    if (s->log_count != 0 && (s->log_count > 0 || s->log_kw > 0.0))
        d = fmax(d, s->log_diam_dist.type != SD_SIZE_FIXED ? s->log_diam_dist.max : s->log_diam);
    return d;
}

int sd_build_log_count(const sd_scenario *s)
{
    if (s->log_count >= 0) return s->log_count;
    if (s->log_kw > 0.0 && sd_build_log_sizes_vary(s)) return drawn_log_count(s);
    if (s->log_kw <= 0.0) return 0;
    double vs = 0.0, vlog;
    if (s->log_kw_volume > 0.0) {
        /* the paper's count: V its sample's measured volume (6 l), a log counted as d^2 L */
        vs = s->log_kw_volume;
        vlog = s->log_diam * s->log_diam * s->log_length;
    } else {
        for (int k = 0; k < s->n_classes; k++)
            vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
        vlog = M_PI * 0.25 * s->log_diam * s->log_diam * s->log_length;
    }
    /* K_w = V_t / (V + V_t)  =>  V_t = K_w V / (1 - K_w); the loader refuses more than
     * SD_MAX_LOGS */
    const double n = round(s->log_kw * vs / (1.0 - s->log_kw) / vlog);
    return n < SD_MAX_LOGS ? (int)n : SD_MAX_LOGS;
}

sd_status sd_build_dam(sd_world *w, const sd_scenario *s, sd_build_info *info)
{
    if (!s->dam_on) return SD_OK;
    sd_dam_grid g;
    sd_build_dam_grid(s, &g);
    sd_dam_pipe pipe[SD_MAX_DAM_PIPES];
    const int n = sd_build_dam_pipes(s, &g, pipe);
    for (int k = 0; k < n && info->n_pipes < SD_MAX_DAM_PIPES; k++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.pos = pipe[k].centre;
        c.axis = pipe[k].axis;
        c.radius = pipe[k].radius;
        c.length = pipe[k].length;
        c.density = 7850.0;
        c.fixed = 1;
        c.tag = SD_TAG_PIPE;
        c.material = s->pipe_mat;
        int gid = sd_world_add_cylinder(w, &c);
        if (gid < 0) return (sd_status)-gid;
        info->pipe_gid[info->n_pipes] = gid;
        info->pipe_kind[info->n_pipes] = pipe[k].kind;
        info->pipe_coord[info->n_pipes++] = pipe[k].coord;
    }
    return SD_OK;
}

/* Does the triangle meet the box [lo, hi]? The separating-axis test: the box's three axes, the
 * triangle's normal, and the nine cross products of their edges. */
static int tri_meets_box(const sd_vec3 tri[3], sd_vec3 lo, sd_vec3 hi)
{
    const sd_vec3 c = v3_scale(v3_add(lo, hi), 0.5), h = v3_scale(v3_sub(hi, lo), 0.5);
    const sd_vec3 v[3] = {v3_sub(tri[0], c), v3_sub(tri[1], c), v3_sub(tri[2], c)};
    const sd_vec3 e[3] = {v3_sub(v[1], v[0]), v3_sub(v[2], v[1]), v3_sub(v[0], v[2])};
    const sd_vec3 box_axis[3] = {v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
    sd_vec3 axes[13];
    int na = 0;
    for (int i = 0; i < 3; i++)
        axes[na++] = box_axis[i];
    axes[na++] = v3_cross(e[0], e[1]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            axes[na++] = v3_cross(box_axis[i], e[j]);
    for (int k = 0; k < na; k++) {
        const sd_vec3 a = axes[k];
        if (!(v3_norm2(a) > 0.0)) continue; /* an edge along a box axis: covered by the others */
        double pmin = v3_dot(v[0], a), pmax = pmin;
        for (int i = 1; i < 3; i++) {
            const double p = v3_dot(v[i], a);
            pmin = fmin(pmin, p);
            pmax = fmax(pmax, p);
        }
        const double r = h.x * fabs(a.x) + h.y * fabs(a.y) + h.z * fabs(a.z);
        if (pmin > r || pmax < -r) return 0;
    }
    return 1;
}

/* The scenario's meshes as fixed walls, each in its role's group. */
static sd_status build_meshes(sd_world *w, const sd_scenario *s, FILE *err)
{
    static const int group[3] = {SD_GROUP_BED, SD_GROUP_WALLS, SD_GROUP_DAM};
    for (int k = 0; k < s->n_meshes; k++) {
        const sd_mesh_def *m = &s->meshes[k];
        for (int t = 0; t < m->n_tri; t++)
            if (add_tri(w, m->tri[t][0], m->tri[t][1], m->tri[t][2], group[m->role], m->material)) {
                fprintf(err, "%s:%d: meshes: %s: triangle %d rejected\n", s->path, m->line, m->file, t);
                return SD_ERR_ARG;
            }
    }
    return SD_OK;
}

static sd_status build_flume(sd_world *w, const sd_scenario *s, sd_build_info *info, sd_rng *rng, FILE *err,
                             int with_dam)
{
    double W = s->width, H = s->wall_height, L = s->x_end;
    sd_status st;
    /* bed (unless a mesh stands in for it), side walls and end wall; triangles of at most 0.25 m
     * along x */
    const int mw = s->wall_mat;
    if (s->flume_bed &&
        (st = add_quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, W, 0), v3(0, W, 0), SD_GROUP_BED, s->bed_mat, 0.25)))
        return st;
    if ((st = add_quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, 0, H), v3(0, 0, H), SD_GROUP_WALLS, mw, 0.25))) return st;
    if ((st = add_quad(w, v3(0, W, 0), v3(L, W, 0), v3(L, W, H), v3(0, W, H), SD_GROUP_WALLS, mw, 0.25))) return st;
    if ((st = add_quad(w, v3(0, 0, 0), v3(0, W, 0), v3(0, W, H), v3(0, 0, H), SD_GROUP_END, mw, 0))) return st;
    if ((st = add_quad(w, v3(s->x_gate, 0, 0), v3(s->x_gate, W, 0), v3(s->x_gate, W, H), v3(s->x_gate, 0, H),
                       SD_GROUP_GATE, s->gate_mat, 0)))
        return st;

    /* grid dam of fixed cylinders; upstream face at x_dam (a run adds it later: sd_build_dam) */
    if (s->dam_on && with_dam && (st = sd_build_dam(w, s, info))) return st;

    /* bed roughness: fixed spheres centred on the bed plane, random without overlap; random
     * sequential adsorption until 2000 tries in a row fail (jamming coverage ~0.5) */
    if (s->roughness_on) {
        sd_placer *pl = sd_placer_create(v3(0, 0, -s->rough_dmax), v3(L, W, s->rough_dmax), s->rough_dmax);
        if (!pl) return SD_ERR_NOMEM;
        int fails = 0;
        double covered = 0.0, target = s->rough_coverage * L * W;
        while (fails < 2000 && covered < target) {
            double d = sd_rng_range(rng, s->rough_dmin, s->rough_dmax), r = 0.5 * d;
            sd_vec3 c = v3(sd_rng_range(rng, r, L - r), sd_rng_range(rng, r, W - r), 0.0);
            if (s->dam_on && fabs(c.x - (s->x_dam + 0.5 * s->pipe_diam)) < r + 0.5 * s->pipe_diam + 1e-4) {
                fails++;
                continue; /* keep the dam foot clear */
            }
            if (s->x_gate - r < c.x && c.x < s->x_gate + r) {
                fails++;
                continue; /* the gate stands on the bed */
            }
            if (collides(pl, c, v3(0, 0, 1), r, 0.0, 0.0)) {
                fails++;
                continue;
            }
            fails = 0;
            covered += M_PI * r * r;
            sd_placer_add(pl, c, v3(0, 0, 1), r, 0.0);
            sd_sphere_def sp = sd_sphere_def_default();
            sp.pos = c;
            sp.radius = r;
            sp.density = s->sphere_density;
            sp.fixed = 1;
            sp.tag = SD_TAG_ROUGH;
            sp.material = s->rough_mat;
            int g = sd_world_add_sphere(w, &sp);
            if (g < 0) {
                sd_placer_destroy(pl);
                return (sd_status)-g;
            }
            info->n_rough++;
        }
        sd_placer_destroy(pl);
    }

    /* packing box above the reservoir: logs first (hardest to place), then spheres large to small */
    double gap = 0.002;
    sd_vec3 lo = v3(gap, gap, s->rough_dmax * 0.5 + gap), hi = v3(s->x_gate - gap, W - gap, s->pack_height);
    /* the placer knows nothing of the meshes: none may reach into the box */
    for (int k = 0; k < s->n_meshes; k++)
        for (int t = 0; t < s->meshes[k].n_tri; t++)
            if (tri_meets_box(s->meshes[k].tri[t], lo, hi)) {
                fprintf(err,
                        "%s:%d: meshes: %s: its triangle %d reaches into the flume's packing box (x %g to %g, y %g to "
                        "%g, z %g to %g m): move the mesh, or the gate (flume.x_gate) and flume.pack_height\n",
                        s->path, s->meshes[k].line, s->meshes[k].file, t, lo.x, hi.x, lo.y, hi.y, lo.z, hi.z);
                return SD_ERR_ARG;
            }
    sd_placer *pl = sd_placer_create(lo, hi, sd_build_placer_cell(s, 0));
    if (!pl) return SD_ERR_NOMEM;
    info->first_moving_gid = -1;
    int nlogs = sd_build_log_count(s);
    sd_rng sizes = sd_debris_log_stream(s->seed); /* (drawn only when a size varies) */
    for (int k = 0; k < nlogs; k++) {
        sd_vec3 pos, axis;
        double len = s->log_length, d = s->log_diam;
        if (sd_build_log_sizes_vary(s))
            sd_debris_log_next(&sizes, &s->log_length_dist, s->log_length, &s->log_diam_dist, s->log_diam, &len, &d);
        if (!sd_placer_try_cylinder(pl, rng, 0.5 * d, 0.5 * len, 0.0005, 200000, &pos, &axis)) {
            fprintf(err, "%s: no room for log %d of %d in the packing box; raise flume.pack_height\n", s->path, k + 1,
                    nlogs);
            sd_placer_destroy(pl);
            return SD_ERR_ARG;
        }
        sd_cylinder_def c = sd_cylinder_def_default();
        c.pos = pos;
        c.axis = axis;
        c.radius = 0.5 * d;
        c.length = len;
        c.density = s->log_density;
        c.tag = SD_TAG_LOG;
        c.material = s->log_mat;
        int g = sd_world_add_cylinder(w, &c);
        if (g < 0) {
            sd_placer_destroy(pl);
            return (sd_status)-g;
        }
        if (info->first_moving_gid < 0) info->first_moving_gid = g;
        info->n_logs++;
    }
    for (int cl = 0; cl < s->n_classes; cl++)
        for (int k = 0; k < s->class_count[cl]; k++) {
            sd_vec3 pos;
            double r = 0.5 * s->class_diam[cl];
            if (!sd_placer_try_sphere(pl, rng, r, 0.0005, 200000, &pos)) {
                fprintf(err, "%s: no room for sphere %d of class %d in the packing box; raise flume.pack_height\n",
                        s->path, k + 1, cl);
                sd_placer_destroy(pl);
                return SD_ERR_ARG;
            }
            sd_sphere_def sp = sd_sphere_def_default();
            sp.pos = pos;
            sp.radius = r;
            sp.density = s->sphere_density;
            sp.tag = cl;
            sp.material = s->n_sphere_mats == 0 ? 0 : s->sphere_mat[s->n_sphere_mats == 1 ? 0 : cl];
            int g = sd_world_add_sphere(w, &sp);
            if (g < 0) {
                sd_placer_destroy(pl);
                return (sd_status)-g;
            }
            if (info->first_moving_gid < 0) info->first_moving_gid = g;
            info->n_spheres++;
        }
    sd_placer_destroy(pl);
    return SD_OK;
}

sd_status sd_build_scene(sd_world *w, const sd_scenario *s, sd_build_info *info, FILE *err)
{
    return sd_build_scene_ex(w, s, info, err, 1);
}

sd_status sd_build_scene_ex(sd_world *w, const sd_scenario *s, sd_build_info *info, FILE *err, int with_dam)
{
    memset(info, 0, sizeof(*info));
    info->first_moving_gid = -1;
    sd_rng rng = {(uint64_t)s->seed * 0x9E3779B97F4A7C15ULL + 12345};
    sd_status st = sd_scenario_apply_materials(s, w);
    if (st) return st;
    for (int i = 0; i < s->n_elems; i++) {
        const sd_elem_def *d = &s->elems[i];
        int g;
        if (d->type == 0) {
            sd_sphere_def sp = sd_sphere_def_default();
            sp.pos = d->pos;
            sp.vel = d->vel;
            sp.omega = d->omega;
            sp.radius = d->radius;
            sp.density = d->density;
            sp.fixed = d->fixed;
            sp.tag = d->tag;
            sp.material = d->material;
            g = sd_world_add_sphere(w, &sp);
        } else if (d->type == 1) {
            sd_cylinder_def c = sd_cylinder_def_default();
            c.pos = d->pos;
            c.vel = d->vel;
            c.omega = d->omega;
            c.axis = d->axis;
            c.radius = d->radius;
            c.length = d->length;
            c.density = d->density;
            c.fixed = d->fixed;
            c.tag = d->tag;
            c.material = d->material;
            g = sd_world_add_cylinder(w, &c);
        } else {
            g = sd_world_add_triangle(w, d->v[0], d->v[1], d->v[2], d->group);
            if (g >= 0 && sd_world_set_triangle_material(w, g, d->material)) g = -SD_ERR_ARG;
        }
        if (g < 0) {
            fprintf(err, "%s:%d: element rejected: %s\n", s->path, d->line, sd_status_message((sd_status)-g));
            return (sd_status)-g;
        }
    }
    if (s->box_on && (st = sd_build_box(w, s->box_min, s->box_max, SD_GROUP_BOX, s->box_mat))) return st;
    if (s->pile_n_classes > 0) {
        sd_placer *pl = sd_placer_create(s->pile_min, s->pile_max, sd_build_placer_cell(s, 1));
        if (!pl) return SD_ERR_NOMEM;
        for (int cl = 0; cl < s->pile_n_classes; cl++)
            for (int k = 0; k < s->pile_count[cl]; k++) {
                sd_vec3 pos;
                double r = 0.5 * s->pile_diam[cl];
                if (!sd_placer_try_sphere(pl, &rng, r, 0.0005, 200000, &pos)) {
                    fprintf(err, "%s: no room for pile sphere %d of class %d; enlarge pile.min/pile.max\n", s->path,
                            k + 1, cl);
                    sd_placer_destroy(pl);
                    return SD_ERR_ARG;
                }
                sd_sphere_def sp = sd_sphere_def_default();
                sp.pos = pos;
                sp.radius = r;
                sp.density = s->pile_density;
                sp.tag = cl;
                sp.material = s->pile_mat;
                if (sd_world_add_sphere(w, &sp) < 0) {
                    sd_placer_destroy(pl);
                    return SD_ERR_ARG;
                }
                info->n_spheres++;
            }
        sd_placer_destroy(pl);
    }
    if (s->flume_on && (st = build_flume(w, s, info, &rng, err, with_dam))) return st;
    /* after everything else, so that a scene's other walls and bodies keep their order */
    if ((st = build_meshes(w, s, err))) return st;
    return SD_OK;
}
