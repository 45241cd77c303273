/* What the dam holds and how the flow goes: the trap ratio P_V and the volumes behind it, an
 * element crossing the dam, the pond depth h_D, the front, the flow length. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/status.h"
#include "core/vmath.h"
#include "run_ctx.h"

double sd_trap_body_volume(const sd_body_view *b, int i)
{
    double r = b->radius[i];
    return b->shape[i] == SD_SHAPE_SPHERE ? 4.0 / 3.0 * M_PI * r * r * r : M_PI * r * r * 2.0 * b->half_length[i];
}

static int is_debris(const sd_body_view *b, int i) { return !b->fixed[i]; }

/* Volume still upstream of the dam: centre upstream of the pipes' axis plane. */
double sd_trap_plane_x(const run_ctx *c) { return c->s->x_dam + 0.5 * c->s->pipe_diam; }

/* An element crossing the dam (SPEC §6: the capture settles when none has crossed for
 * quiet_time): a moving element whose centre is past the trap plane xt by less than 2 cm and
 * moves downstream faster than the rest speed of SPEC §6 (~1 mm/s). An element lodged among
 * the pipes with its centre just past the plane is at rest there, not crossing: counted, it
 * held the default run's capture to its time limit (docs/physics.md §13). */
#define SD_REST_SPEED 1e-3

int sd_trap_crossing(const sd_world *w, double xt)
{
    const sd_body_view bv = sd_world_bodies(w), *b = &bv;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && b->pos[i].x >= xt && b->pos[i].x < xt + 0.02 && b->vel[i].x > SD_REST_SPEED) return 1;
    return 0;
}

void sd_trap_volumes_upstream(const run_ctx *c, double *cls, double *logs, int *n_up)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        cls[k] = 0.0;
    *logs = 0.0;
    *n_up = 0;
    double xt = sd_trap_plane_x(c);
    for (int i = 0; i < b->n; i++) {
        if (!is_debris(b, i) || b->pos[i].x >= xt) continue;
        (*n_up)++;
        if (b->shape[i] == SD_SHAPE_CYLINDER)
            *logs += sd_trap_body_volume(b, i);
        else if (b->tag[i] >= 0 && b->tag[i] < SD_MAX_CLASSES)
            cls[b->tag[i]] += sd_trap_body_volume(b, i);
    }
}

double sd_trap_ratio(const run_ctx *c, double *per_class, double *logs_ratio, int *n_up)
{
    double cls[SD_MAX_CLASSES], logs;
    sd_trap_volumes_upstream(c, cls, &logs, n_up);
    double up = logs, tot = c->vol_total_logs;
    for (int k = 0; k < SD_MAX_CLASSES; k++) {
        up += cls[k];
        tot += c->vol_total_class[k];
        if (per_class) per_class[k] = c->vol_total_class[k] > 0 ? cls[k] / c->vol_total_class[k] : 0.0;
    }
    if (logs_ratio) *logs_ratio = c->vol_total_logs > 0 ? logs / c->vol_total_logs : 0.0;
    return tot > 0 ? up / tot : 0.0;
}

double sd_trap_capture_depth(const sd_scenario *s, const sd_world *w)
{
    const sd_body_view bv = sd_world_bodies(w), *b = &bv;
    double h = s->water_h, xd = s->x_dam, lo = xd - s->water_probe;
    for (int i = 0; i < b->n; i++) {
        if (b->fixed[i] || b->pos[i].x < lo || b->pos[i].x > xd || b->pos[i].z <= h) continue;
        /* the deposit sets the pond level; a log floating on the pond does not (docs/physics.md) */
        if (!s->water_hd_floating && b->mass[i] <= s->water_rho * sd_trap_body_volume(b, i)) continue;
        h = b->pos[i].z;
    }
    return h;
}

/* The front: the farthest downstream surface of any moving element (kept by the step). */
double sd_trap_front_x(const run_ctx *c)
{
    /* a decomposed run: the slabs' fronts after the step (the copy's bodies are refreshed only
     * now and then), or the copy's own once bodies were removed since */
    if (c->sys && !c->sys_front_stale) return c->sys_front;
    return sd_world_front_x(c->w);
}

double sd_trap_upstream_ke(const run_ctx *c)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    double e = 0.0, xt = sd_trap_plane_x(c);
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && b->pos[i].x < xt) e += 0.5 * b->mass[i] * v3_norm2(b->vel[i]);
    return e;
}

double sd_trap_max_speed(const run_ctx *c)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    double v = 0.0;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i]) v = fmax(v, v3_norm2(b->vel[i]));
    return sqrt(v);
}

static int cmp_double(const void *pa, const void *pb)
{
    const double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

void sd_trap_speed_stats(const run_ctx *c, double v[3])
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    v[0] = v[1] = v[2] = 0.0;
    double *sp = malloc((size_t)(b->n + 1) * sizeof(double));
    if (!sp) return;
    int m = 0;
    double sum = 0.0;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i]) {
            sp[m] = v3_norm(b->vel[i]);
            sum += sp[m++];
        }
    if (m > 0) {
        qsort(sp, (size_t)m, sizeof(double), cmp_double);
        v[0] = sp[m - 1];
        v[1] = sp[(int)ceil(0.99 * m) - 1]; /* the nearest-rank percentile */
        v[2] = sum / m;
    }
    free(sp);
}

void sd_trap_fixed_loads(const run_ctx *c, sd_vec3 *roughness, sd_vec3 *bed)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    sd_vec3 r = v3(0.0, 0.0, 0.0);
    for (int i = 0; i < b->n; i++) /* the moving bodies' pairs among themselves cancel */
        if (!b->fixed[i]) r = v3_sub(r, b->force[i]);
        else if (b->shape[i] == SD_SHAPE_CYLINDER)
            r = v3_sub(r, b->force[i]);
    if (c->sys) {
        /* a decomposed run: the walls' forces on the bodies at the last refresh, summed over the
         * bodies in gid order (each body's wall pairs in their order), the same on any count of
         * ranks; the forces on the triangles are their opposite */
        *roughness = v3_add(r, c->sys_wall);
        *bed = v3_scale(c->sys_bed, -1.0);
        return;
    }
    int top = SD_GROUP_DAM; /* the builders' groups (the meshes' too), and the scenario's triangles' */
    for (int k = 0; k < c->s->n_elems; k++)
        if (c->s->elems[k].type == 2 && c->s->elems[k].group > top) top = c->s->elems[k].group;
    for (int g = 0; g <= top; g++)
        r = v3_sub(r, sd_world_group_force(c->w, g));
    *roughness = r;
    *bed = sd_world_group_force(c->w, SD_GROUP_BED);
}

double sd_trap_body_top(const sd_body_view *b, int i)
{
    const double r = b->radius[i];
    if (b->shape[i] != SD_SHAPE_CYLINDER) return b->pos[i].z + r;
    const double az = fabs(b->axis[i].z);
    return b->pos[i].z + b->half_length[i] * az + r * sqrt(fmax(0.0, 1.0 - az * az));
}

void sd_trap_deposit(const run_ctx *c, double *height, int *n_floating, double *floating_top)
{
    const sd_scenario *s = c->s;
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    const double lo = s->x_dam - s->water_probe, hi = sd_trap_plane_x(c);
    *height = *floating_top = 0.0;
    *n_floating = 0;
    for (int i = 0; i < b->n; i++) {
        if (b->fixed[i] || b->pos[i].x < lo || b->pos[i].x > hi) continue;
        const double top = sd_trap_body_top(b, i);
        *height = fmax(*height, top); /* a log jam is deposit too */
        /* floating: lighter than the water, riding on the pond (its centre within one diameter
         * of the surface h_D) and held by the water, not by the others (its contact force under
         * a tenth of its weight); a light log jammed in the deposit is not */
        const int light = s->water_on && b->mass[i] <= s->water_rho * sd_trap_body_volume(b, i);
        const double g = v3_norm(sd_world_definition(c->w)->gravity);
        if (light && fabs(b->pos[i].z - c->h_d) <= 2.0 * b->radius[i] && v3_norm(b->force[i]) < 0.1 * b->mass[i] * g) {
            (*n_floating)++;
            *floating_top = fmax(*floating_top, top);
        }
    }
}

typedef struct {
    double x, v;
} xv;

static int cmp_xv(const void *pa, const void *pb)
{
    const xv *a = pa, *b = pb;
    return (a->x > b->x) - (a->x < b->x);
}

/* Flow length (SPEC §8): spread between the 5 % and 95 % volume quantiles of x over the
 * volume that has left the reservoir. */
void sd_trap_flow_length(run_ctx *c)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    xv *a = malloc((size_t)(b->n + 1) * sizeof(*a));
    if (!a) return;
    int m = 0;
    double tot = 0.0;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && b->pos[i].x > c->s->x_gate) {
            a[m].x = b->pos[i].x;
            a[m].v = sd_trap_body_volume(b, i);
            tot += a[m].v;
            m++;
        }
    qsort(a, (size_t)m, sizeof(*a), cmp_xv);
    double acc = 0.0, q05 = NAN, q95 = NAN;
    for (int k = 0; k < m; k++) {
        acc += a[k].v;
        if (isnan(q05) && acc >= 0.05 * tot) q05 = a[k].x;
        if (isnan(q95) && acc >= 0.95 * tot) q95 = a[k].x;
    }
    free(a);
    c->flow_q05 = q05;
    c->flow_q95 = q95;
    c->flow_len = q95 - q05;
    c->flow_front = sd_trap_front_x(c);
    c->flow_len_time = sd_world_time(c->w);
    c->flow_len_done = 1;
}

/* Where the debris is at the end (docs/loads.md): held at the dam (the deposit against it:
 * from the trap plane upstream, bins 2 d_max long across the flume, while a bin's solid volume
 * spread over the flume's width is at least d_max / 2 deep, about a layer of the largest
 * stones), in the channel (upstream of that, never reached the dam's deposit) and passed
 * (past the trap plane, in the world or removed at the end of the bed). */
void sd_trap_split(const run_ctx *c, double *held, double *channel, double *passed, double *deposit_x0)
{
    const sd_scenario *s = c->s;
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    double dmax = 0.0;
    for (int k = 0; k < s->n_classes; k++)
        if (s->class_count[k] > 0) dmax = fmax(dmax, s->class_diam[k]);
    if (dmax <= 0.0) dmax = s->log_diam_dist.type != SD_SIZE_FIXED ? s->log_diam_dist.max : s->log_diam;
    const double xt = sd_trap_plane_x(c), bin = 2.0 * dmax, x0 = 0.0; /* the upstream end of the flume */
    const int nb = (int)ceil((xt - x0) / bin) + 1;
    double *vol = calloc((size_t)nb, sizeof *vol);
    *held = *channel = 0.0;
    *passed = c->vol_passed_logs;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        *passed += c->vol_passed_class[k];
    *deposit_x0 = xt;
    for (int i = 0; i < b->n; i++) {
        if (!is_debris(b, i)) continue;
        const double v = sd_trap_body_volume(b, i);
        if (b->pos[i].x >= xt) {
            *passed += v;
            continue;
        }
        int j = (int)floor((xt - b->pos[i].x) / bin); /* bin 0 touches the trap plane */
        if (j >= nb) j = nb - 1;
        if (j < 0) j = 0;
        if (vol) vol[j] += v;
    }
    if (!vol) return;
    const double full = 0.5 * dmax * bin * s->width;
    int jd = 0;
    while (jd < nb && vol[jd] >= full)
        jd++;
    for (int j = 0; j < nb; j++)
        if (j < jd) *held += vol[j];
        else *channel += vol[j];
    *deposit_x0 = xt - jd * bin;
    free(vol);
}
