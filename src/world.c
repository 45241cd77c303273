/* The world owns every store; sd_world_step() is a short list of timed phases. */
#include <assert.h>
#include <string.h>

#include "core/cpu.h"
#include "core/hash.h"
#include "tuning.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

sd_world_def sd_world_def_default(void)
{
    sd_world_def d;
    memset(&d, 0, sizeof(d));
    d.gravity = v3(9.81 * sin(15.0 * M_PI / 180.0), 0.0, -9.81 * cos(15.0 * M_PI / 180.0));
    d.dt = 1.0e-5;
    d.margin = 5.0e-3;
    d.t_reset = 1.0e-3;
    d.contact.k_n = 1.0e4;
    d.contact.k_s = 4.0e3;
    d.contact.damping = 0.2;
    d.contact.tan_phi = 0.404;
    d.contact.cohesion = 0.0;
    d.threads = 0;
    d.parallel_min = 2048;
    d.check_dt = 1;
    d.tuning = sd_tuning_default();
    return d;
}

sd_sphere_def sd_sphere_def_default(void)
{
    sd_sphere_def d;
    memset(&d, 0, sizeof(d));
    d.radius = 0.005;
    d.density = 1900.0;
    return d;
}

sd_cylinder_def sd_cylinder_def_default(void)
{
    sd_cylinder_def d;
    memset(&d, 0, sizeof(d));
    d.axis = v3(1.0, 0.0, 0.0);
    d.radius = 0.005;
    d.length = 0.1;
    d.density = 800.0;
    return d;
}

static int finite3(sd_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

sd_status sd_world_create(const sd_world_def *def, sd_world **out)
{
    *out = NULL;
    if (!def || !(def->dt > 0.0) || !(def->margin >= 0.0) || !(def->t_reset > 0.0) || !(def->contact.k_n > 0.0) ||
        !(def->contact.k_s >= 0.0) || !(def->contact.damping >= 0.0) || !(def->contact.tan_phi >= 0.0) ||
        !(def->contact.cohesion >= 0.0) || !finite3(def->gravity))
        return SD_ERR_ARG;
    sd_world *w = calloc(1, sizeof(*w));
    if (!w) return SD_ERR_NOMEM;
    w->def = *def;
    w->need_rebuild = 1;
    w->mov_stamp = -1;
    w->near_stamp = -1;
    w->near_mark_rb = -1;
    w->pf.verdict = -1;
    w->pf.blk = -1;
    w->nthreads = 1;
#ifdef _OPENMP
    w->nthreads = def->threads > 0 ? def->threads : omp_get_max_threads();
#endif
    static const int sw_default[SD_SWITCH_COUNT] = {
#define SD_X_SWITCH(name, def, doc) def,
        SD_SWITCH_TABLE(SD_X_SWITCH)
#undef SD_X_SWITCH
    };
    memcpy(w->sw, sw_default, sizeof w->sw);
    sd_world_set_tuning(w, &def->tuning);
    *out = w;
    return SD_OK;
}

void sd_world_destroy(sd_world *w)
{
    if (!w) return;
    sd_bodies_free(&w->b);
    sd_walls_free(&w->w);
    sd_pairlist_free(&w->bb);
    sd_pairlist_free(&w->bt);
    sd_grid_free(&w->grid);
    sd_grid_free(&w->tgrid);
    free(w->bt_man);
    if (w->owned) {
        free(w->owned->cross);
        free(w->owned->xo);
        free(w->owned->xout);
        free(w->owned->xact);
        free(w->owned->list);
        free(w->owned->hist);
        sd_pair_soa_free(&w->owned->soa);
        sd_pair_soa_free(&w->owned->xsoa);
    }
    free(w->owned);
    free(w->bb_scratch);
    free(w->csr.bt_start);
    free(w->gid_map);
    free(w->old_hist);
    free(w->old_keys);
    free(w->old_start);
    free(w->old_cnt);
    free(w->rb_perm);
    free(w->old_rng);
    free(w->range);
    free(w->box);
    sd_bed_cache_free(&w->bed);
    sd_cand_bufs_free(w);
    free(w->reg0);
    free(w->slot);
    free(w->gflag);
    free(w->gq);
    free(w->trange);
    free(w->tflag);
    free(w->mov);
    free(w->near);
    free(w->near_hist);
    free(w->near_mark);
    free(w->ghost);
    free(w->wall_list);
    sd_pair_soa_free(&w->near_soa);
    free(w);
}

static int add_body(sd_world *w, int shape, sd_vec3 pos, sd_vec3 vel, sd_vec3 omega, sd_vec3 axis, double r, double hl,
                    double density, int fixed, int tag, int material)
{
    if (!(r > 0.0) || !(density > 0.0) || !(hl >= 0.0) || !finite3(pos) || !finite3(vel) || !finite3(omega) ||
        !finite3(axis) || !isfinite(r) || !isfinite(hl) || !isfinite(density) || material < 0 ||
        material >= SD_MATERIALS_MAX)
        return -SD_ERR_ARG;
    if (shape == SD_SHAPE_CYLINDER && !(v3_norm(axis) > 0.0)) return -SD_ERR_ARG;
    /* history taken before the store grows; pairs are rebuilt before the next force pass */
    if (sd_history_collect(w)) return -SD_ERR_NOMEM;
    sd_bodies *b = &w->b;
    if (sd_bodies_reserve(b, b->n + 1)) return -SD_ERR_NOMEM;
    if (sd_grow((void **)&w->gid_map, &w->gid_cap, w->next_gid + 1, sizeof(int32_t))) return -SD_ERR_NOMEM;
    int i = b->n++;
    int gid = w->next_gid++;
    w->body_version++;
    w->gid_map[gid] = i;
    b->gid[i] = gid;
    b->shape[i] = (uint8_t)shape;
    b->fixed[i] = (uint8_t)(fixed != 0);
    b->mat[i] = (uint8_t)material;
    b->tag[i] = tag;
    b->pos[i] = pos;
    b->vel[i] = fixed ? v3(0, 0, 0) : vel;
    b->force[i] = b->torque[i] = b->ext_force[i] = v3(0, 0, 0);
    b->radius[i] = r;
    b->hl[i] = hl;
    double mass, i_ax, i_tr;
    if (shape == SD_SHAPE_SPHERE) {
        mass = density * 4.0 / 3.0 * M_PI * r * r * r;
        i_ax = i_tr = 0.4 * mass * r * r;
        b->axis[i] = v3(0.0, 0.0, 1.0);
        b->quat[i] = quat_identity();
        b->bound_r[i] = r;
    } else {
        double len = 2.0 * hl;
        mass = density * M_PI * r * r * len;
        i_ax = 0.5 * mass * r * r;
        i_tr = mass * (3.0 * r * r + len * len) / 12.0;
        sd_vec3 a = v3_normalize(axis);
        b->quat[i] = quat_from_z_to(a);
        b->axis[i] = quat_rotate(b->quat[i], v3(0.0, 0.0, 1.0));
        b->bound_r[i] = sqrt(r * r + hl * hl);
    }
    b->mass[i] = mass;
    b->inv_mass[i] = 1.0 / mass;
    b->inv_i_ax[i] = 1.0 / i_ax;
    b->inv_i_tr[i] = 1.0 / i_tr;
    if (fixed) omega = v3(0, 0, 0);
    if (shape == SD_SHAPE_SPHERE) {
        b->omega[i] = omega;
        b->angmom[i] = v3_scale(omega, i_ax);
    } else {
        /* L = A I Aᵀ ω */
        sd_vec3 a = b->axis[i];
        double wa = v3_dot(omega, a);
        sd_vec3 L = v3_madd(v3_scale(omega, i_tr), a, (i_ax - i_tr) * wa);
        b->angmom[i] = L;
        b->omega[i] = omega;
    }
    b->pos_ref[i] = pos;
    b->axis_ref[i] = b->axis[i];
    w->need_rebuild = 1;
    w->checked = 0;
    return gid;
}

int sd_world_add_sphere(sd_world *w, const sd_sphere_def *d)
{
    return add_body(w, SD_SHAPE_SPHERE, d->pos, d->vel, d->omega, v3(0, 0, 1), d->radius, 0.0, d->density, d->fixed,
                    d->tag, d->material);
}

int sd_world_add_cylinder(sd_world *w, const sd_cylinder_def *d)
{
    if (!(d->length > 0.0)) return -SD_ERR_ARG;
    return add_body(w, SD_SHAPE_CYLINDER, d->pos, d->vel, d->omega, d->axis, d->radius, 0.5 * d->length, d->density,
                    d->fixed, d->tag, d->material);
}

int sd_world_add_triangle(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, int group)
{
    if (!finite3(a) || !finite3(b) || !finite3(c)) return -SD_ERR_ARG;
    if (!(v3_norm(v3_cross(v3_sub(b, a), v3_sub(c, a))) > 0.0)) return -SD_ERR_ARG; /* degenerate */
    if (sd_history_collect(w)) return -SD_ERR_NOMEM;
    sd_walls *wl = &w->w;
    if (sd_walls_reserve(wl, wl->n + 1)) return -SD_ERR_NOMEM;
    int t = wl->n++;
    sd_tri_init(&wl->tri[t], a, b, c);
    wl->group[t] = group;
    wl->active[t] = 1;
    wl->mat[t] = 0;
    wl->force[t] = v3(0, 0, 0);
    wl->dirty = 1;
    w->need_rebuild = 1;
    return t;
}

sd_status sd_world_set_group_active(sd_world *w, int group, int active)
{
    int found = 0;
    for (int t = 0; t < w->w.n; t++)
        if (w->w.group[t] == group) {
            w->w.active[t] = (uint8_t)(active != 0);
            found = 1;
        }
    if (!found) return SD_ERR_NOTFOUND;
    /* pairs keep triangle indices; the grid is rebuilt without the inactive ones */
    sd_status st = sd_history_collect(w);
    if (st) return st;
    w->w.dirty = 1;
    w->need_rebuild = 1;
    return SD_OK;
}

sd_status sd_world_set_triangle_material(sd_world *w, int t, int material)
{
    if (!w || t < 0 || t >= w->w.n) return SD_ERR_NOTFOUND;
    if (material < 0 || material >= SD_MATERIALS_MAX) return SD_ERR_ARG;
    w->w.mat[t] = (uint8_t)material;
    w->checked = 0;
    return SD_OK;
}

int sd_world_triangle_material(const sd_world *w, int t) { return w && t >= 0 && t < w->w.n ? w->w.mat[t] : -1; }

/* the checks of sd_world_create on a contact definition */
static int contact_ok(const sd_contact_def *c)
{
    return c->k_n > 0.0 && c->k_s >= 0.0 && c->damping >= 0.0 && c->tan_phi >= 0.0 && c->cohesion >= 0.0 &&
           isfinite(c->k_n) && isfinite(c->k_s) && isfinite(c->damping) && isfinite(c->tan_phi) && isfinite(c->cohesion);
}

sd_status sd_world_set_pair_contact(sd_world *w, int a, int b, const sd_contact_def *c)
{
    if (!w || a < 0 || b < 0 || a >= SD_MATERIALS_MAX || b >= SD_MATERIALS_MAX || (c && !contact_ok(c))) return SD_ERR_ARG;
    const int k[2] = {sd_mat_pair(a, b), sd_mat_pair(b, a)};
    for (int s = 0; s < 2; s++) {
        w->mat_set[k[s]] = c != NULL;
        memset(&w->mat_pair[k[s]], 0, sizeof w->mat_pair[k[s]]);
        if (c) w->mat_pair[k[s]] = *c;
    }
    w->mat_version++;
    w->checked = 0;
    return SD_OK;
}

int sd_world_pair_contact(const sd_world *w, int a, int b, sd_contact_def *c)
{
    if (!w || a < 0 || b < 0 || a >= SD_MATERIALS_MAX || b >= SD_MATERIALS_MAX) return -1;
    if (c) *c = *sd_mat_contact(w, a, b);
    return w->mat_set[sd_mat_pair(a, b)];
}

sd_status sd_world_copy_materials(sd_world *dst, const sd_world *src)
{
    if (!dst || !src || dst->w.n != src->w.n) return SD_ERR_ARG;
    memcpy(dst->mat_pair, src->mat_pair, sizeof dst->mat_pair);
    memcpy(dst->mat_set, src->mat_set, sizeof dst->mat_set);
    if (src->w.n > 0) memcpy(dst->w.mat, src->w.mat, (size_t)src->w.n);
    dst->mat_version++;
    dst->checked = 0;
    return SD_OK;
}

sd_status sd_world_remove_body(sd_world *w, int gid)
{
    if (gid < 0 || gid >= w->next_gid || w->gid_map[gid] < 0) return SD_ERR_NOTFOUND;
    sd_status st = sd_history_collect(w);
    if (st) return st;
    int i = w->gid_map[gid];
    int last = w->b.n - 1;
    sd_bodies_swap_remove(&w->b, i);
    w->body_version++;
    if (i != last) w->gid_map[w->b.gid[i]] = i;
    w->gid_map[gid] = -1;
    if (gid < w->ghost_cap) w->ghost[gid] = 0;
    w->mov_stamp = -1;
    w->need_rebuild = 1;
    return SD_OK;
}

/* Stability (model.md, the time step): the stiffest mode of a contact between two equal
 * smallest spheres (m* = m/2), resolved by at least 8 steps per half period π/ω; leapfrog itself
 * goes unstable at Δt = 2/ω ≈ 0.64 half periods. Two modes: the normal one, ω_n² = K_n/m*, and
 * the tangential spring against translation and rotation together: the contact point's slip
 * u moves by the force F through 1/m and r²/I = 5/(2m) on each sphere, ü = −(7/2) K_s u/m*, so
 * ω_t² = (7/2) K_s/m* (ω_t = 1.18 ω_n at K_s/K_n = 0.4, 1.87 ω_n at K_s = K_n). */
double sd_stable_dt_max(double k_n, double k_s, double m_min)
{
    if (!(m_min > 0.0) || !isfinite(m_min) || !(k_n > 0.0)) return INFINITY;
    const double k = fmax(k_n, 3.5 * fmax(k_s, 0.0));
    const double omega = sqrt(k / (0.5 * m_min));
    return M_PI / omega / 8.0;
}

double sd_world_stable_dt(const sd_world *w, int *pa, int *pb)
{
    /* each moving material's smallest mass, and the materials present (bodies, triangles) */
    double mmin[SD_MATERIALS_MAX];
    uint8_t present[SD_MATERIALS_MAX] = {0};
    for (int m = 0; m < SD_MATERIALS_MAX; m++)
        mmin[m] = INFINITY;
    /* (by the mass alone, a log as a sphere: the modes of a contact at a log's end rim, where
     * rotation adds hl² m/I_tr and r² m/I_ax to the 1 of translation, are left out) */
    for (int i = 0; i < w->b.n; i++) {
        const int m = w->b.mat[i];
        present[m] = 1;
        if (!w->b.fixed[i] && w->b.mass[i] < mmin[m]) mmin[m] = w->b.mass[i];
    }
    for (int t = 0; t < w->w.n; t++)
        present[w->w.mat[t]] = 1;
    /* the pair's m* taken as two of a's smallest spheres': a bound for any partner of a */
    double dt = INFINITY;
    int best_a = 0, best_b = 0;
    for (int a = 0; a < SD_MATERIALS_MAX; a++)
        for (int b = 0; b < SD_MATERIALS_MAX && isfinite(mmin[a]); b++) {
            if (!present[b]) continue;
            const sd_contact_def *c = sd_mat_contact(w, a, b);
            const double d = sd_stable_dt_max(c->k_n, c->k_s, mmin[a]);
            if (d < dt) {
                dt = d;
                best_a = a;
                best_b = b;
            }
        }
    if (pa) *pa = best_a;
    if (pb) *pb = best_b;
    return dt;
}

sd_status sd_world_check(const sd_world *w)
{
    if (!w->def.check_dt) return SD_OK;
    return w->def.dt > sd_world_stable_dt(w, NULL, NULL) ? SD_ERR_UNSTABLE : SD_OK;
}

static sd_status health(const sd_world *w)
{
    const sd_bodies *b = &w->b;
    for (int i = 0; i < b->n; i++)
        if (!finite3(b->pos[i]) || !finite3(b->vel[i]) || !finite3(b->omega[i])) return SD_ERR_NONFINITE;
    return SD_OK;
}

double sd_world_front_x(const sd_world *w)
{
    if (w->front_step == w->step && w->front_bn == w->b.n && w->step > 0) return w->front;
    const sd_bodies *b = &w->b;
    double f = -INFINITY;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && !sd_body_is_ghost(w, i) && b->pos[i].x + sd_body_x_extent(b, i) > f)
            f = b->pos[i].x + sd_body_x_extent(b, i);
    return f;
}

#ifndef NDEBUG
/* The caches' invariants (debug and RelWithDebInfo builds, every 256 steps): the gid map, the
 * bed roughness trailing the store, the moving bodies' list while it claims to be current, the
 * wall pairs grouped by body after a rebuild. A broken one aborts at once, near its cause. */
static void check_caches(const sd_world *w)
{
    const sd_bodies *b = &w->b;
    for (int i = 0; i < b->n; i++)
        assert(b->gid[i] >= 0 && b->gid[i] < w->next_gid && w->gid_map[b->gid[i]] == i);
    const int nb = sd_bed_start(b);
    for (int i = 0; i < nb; i++)
        assert(!sd_body_is_bed(b, i) || w->need_rebuild); /* (an added bed sphere waits for the sort) */
    if (w->mov && w->mov_stamp == w->timers.rebuilds && w->mov_bn == b->n) {
        int moving = 0;
        for (int i = 0; i < b->n; i++)
            moving += !b->fixed[i] && !sd_body_is_ghost(w, i);
        assert(w->mov_n == moving);
        for (int k = 0; k < w->mov_n; k++) {
            assert(!b->fixed[w->mov[k]]);
            assert(k == 0 || w->mov[k - 1] < w->mov[k]);
        }
    }
    if (!w->need_rebuild && w->csr.bt_start && w->timers.rebuilds > 0) {
        assert(w->csr.bt_start[0] == 0 && w->csr.bt_start[b->n] == w->bt.n);
        for (int i = 0; i < b->n; i++) {
            assert(w->csr.bt_start[i] <= w->csr.bt_start[i + 1]);
            for (int k = w->csr.bt_start[i]; k < w->csr.bt_start[i + 1]; k++)
                assert(w->bt.p[k].a == i);
        }
    }
}
#endif

sd_status sd_world_step(sd_world *w)
{
    sd_status st;
    sd_law_ctx_ready(w);
    if (!w->checked) {
        if ((st = sd_world_check(w))) return st;
        w->checked = 1;
    }
    if (w->ghost_drift > 0.0) { /* (a decomposition's ghosts moved by their owners, decomp.c) */
        w->near_drift += w->ghost_drift;
        w->ghost_drift = 0.0;
    }
    double t0 = sd_now();
    if (sd_neighbor_needs_rebuild(w)) {
        if ((st = sd_neighbor_rebuild(w))) return st;
    }
    double t1 = sd_now();
    if ((st = sd_neighbor_moving_update(w))) return st;
    sd_front_prefetch_trial_before(w);
    int integrated;
    if ((st = sd_contact_compute(w, &integrated))) return st;
    double t2 = sd_now();
    sd_front_prefetch_trial_after(w, t2 - t1);
    /* (the wall loads are summed when asked for, sd_contact_gather) */
    if (!integrated) sd_integrate(w);
    double t3 = sd_now();
    w->step++;
    w->time = (double)w->step * w->def.dt;
    w->timers.rebuild += t1 - t0;
    w->timers.contacts += t2 - t1;
    w->timers.moves += t3 - t2;
#ifndef NDEBUG
    if ((w->step & 255) == 0) check_caches(w);
#endif
    if ((w->step & 1023) == 0) {
        st = health(w);
        w->timers.checks += sd_now() - t3;
        if (st) return st;
    }
    return SD_OK;
}

sd_status sd_world_run(sd_world *w, long steps)
{
    for (long s = 0; s < steps; s++) {
        sd_status st = sd_world_step(w);
        if (st) return st;
    }
    return health(w);
}

double sd_world_time(const sd_world *w) { return w->time; }
long sd_world_step_count(const sd_world *w) { return w->step; }
int sd_world_body_count(const sd_world *w) { return w->b.n; }
int sd_world_triangle_count(const sd_world *w) { return w->w.n; }
long sd_world_contact_count(const sd_world *w) { return w->contacts; }
sd_world_timers sd_world_get_timers(const sd_world *w) { return w->timers; }
void sd_world_set_rebuild_every_step(sd_world *w, int on) { w->rebuild_every_step = on; }

sd_status sd_world_body_at(const sd_world *w, int i, sd_body_state *o)
{
    if (i < 0 || i >= w->b.n) return SD_ERR_NOTFOUND;
    const sd_bodies *b = &w->b;
    o->gid = b->gid[i];
    o->shape = b->shape[i];
    o->fixed = b->fixed[i];
    o->tag = b->tag[i];
    o->pos = b->pos[i];
    o->vel = b->vel[i];
    o->omega = b->omega[i];
    o->axis = b->axis[i];
    o->force = b->force[i];
    o->torque = b->torque[i];
    o->radius = b->radius[i];
    o->length = 2.0 * b->hl[i];
    o->mass = b->mass[i];
    o->material = b->mat[i];
    return SD_OK;
}

sd_status sd_world_body(const sd_world *w, int gid, sd_body_state *o)
{
    if (gid < 0 || gid >= w->next_gid || w->gid_map[gid] < 0) return SD_ERR_NOTFOUND;
    return sd_world_body_at(w, w->gid_map[gid], o);
}

sd_vec3 sd_world_group_force(const sd_world *w, int group)
{
    sd_contact_gather((sd_world *)w); /* a cache of the last step's pairs (never a const object) */
    sd_vec3 f = v3(0, 0, 0);
    for (int t = 0; t < w->w.n; t++)
        if (w->w.group[t] == group && w->w.active[t]) f = v3_add(f, w->w.force[t]);
    return f;
}

sd_status sd_world_set_external_force(sd_world *w, int gid, sd_vec3 f)
{
    if (gid < 0 || gid >= w->next_gid || w->gid_map[gid] < 0) return SD_ERR_NOTFOUND;
    w->b.ext_force[w->gid_map[gid]] = f;
    w->ext_any |= sd_ext_set(f);
    return SD_OK;
}

double sd_world_kinetic_energy(const sd_world *w)
{
    const sd_bodies *b = &w->b;
    double e = 0.0;
    for (int i = 0; i < b->n; i++) {
        if (b->fixed[i]) continue;
        e += 0.5 * b->mass[i] * v3_norm2(b->vel[i]);
        if (b->shape[i] == SD_SHAPE_SPHERE)
            e += 0.5 * v3_norm2(b->omega[i]) / b->inv_i_ax[i];
        else
            e += 0.5 * v3_dot(b->angmom[i], b->omega[i]);
    }
    return e;
}

double sd_world_potential_energy(const sd_world *w)
{
    const sd_bodies *b = &w->b;
    double e = 0.0;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i]) e -= b->mass[i] * v3_dot(w->def.gravity, b->pos[i]);
    return e;
}

/* Elastic energy of the current overlaps (normal springs only; ½ K_n δ²) and of the stored
 * tangential springs (½ |P_s|² / K_s). Recomputed from geometry, so exact for the state.
 * Triangle contacts go through the same mesh rule as the force pass, so that a sphere over a
 * shared edge counts one spring, not two. */
static double manifold_energy(const sd_contact_def *c, const sd_pair *p, const sd_hist *hist, const sd_manifold *m)
{
    double e = 0.0;
    for (int k2 = 0; k2 < m->n; k2++)
        e += 0.5 * c->k_n * m->overlap[k2] * m->overlap[k2];
    if (c->k_s > 0.0)
        for (int s = 0; s < p->cap; s++)
            if (hist[p->off + s].feature >= 0) e += 0.5 * v3_norm2(hist[p->off + s].shear) / c->k_s;
    return e;
}

double sd_world_spring_energy(const sd_world *w)
{
    sd_near_springs_home((sd_world *)w); /* (where the springs sit, not what they are) */
    double e = 0.0;
    const sd_bodies *b = &w->b;
    for (int k = 0; k < w->bb.n; k++) {
        const sd_pair *p = &w->bb.p[k];
        sd_manifold m;
        if (p->kind == SD_PAIR_SS)
            sd_geom_sphere_sphere(b->pos[p->a], b->radius[p->a], b->pos[p->b], b->radius[p->b], &m);
        else if (p->kind == SD_PAIR_SC) {
            sd_cyl c = sd_body_cyl(b, p->b);
            sd_geom_sphere_cyl(b->pos[p->a], b->radius[p->a], &c, &m);
        } else {
            sd_cyl c1 = sd_body_cyl(b, p->a), c2 = sd_body_cyl(b, p->b);
            sd_geom_cyl_cyl(&c1, &c2, &m);
        }
        e += manifold_energy(sd_mat_contact(w, b->mat[p->a], b->mat[p->b]), p, w->bb.hist, &m);
    }
    if (w->bt.n == 0) return e;
    sd_manifold *man = malloc((size_t)w->bt.n * sizeof(*man));
    if (!man) return NAN;
    for (int i = 0; i < b->n; i++) {
        int from = w->csr.bt_start[i], to = w->csr.bt_start[i + 1];
        int multi = 0;
        for (int k = from; k < to; k++) {
            const sd_pair *p = &w->bt.p[k];
            sd_manifold *m = &man[k];
            m->n = 0;
            if (!w->w.active[p->b]) continue;
            if (p->kind == SD_PAIR_ST)
                sd_geom_sphere_tri_e(b->pos[p->a], b->radius[p->a], &w->w.tri[p->b], &w->w.edges[p->b], m);
            else {
                sd_cyl c = sd_body_cyl(b, p->a);
                sd_geom_cyl_tri(&c, &w->w.tri[p->b], m);
            }
            multi += m->n > 0;
        }
        if (multi > 1) sd_contact_mesh_dedup(&w->w, w->bt.p, man, from, to);
        for (int k = from; k < to; k++)
            if (w->w.active[w->bt.p[k].b])
                e += manifold_energy(sd_mat_contact(w, b->mat[i], w->w.mat[w->bt.p[k].b]), &w->bt.p[k], w->bt.hist,
                                     &man[k]);
    }
    free(man);
    return e;
}

/* FNV-1a (core/hash.h) over the bytes of the dynamic state, in gid order. */
uint64_t sd_world_state_hash(const sd_world *w)
{
    sd_near_springs_home((sd_world *)w); /* (where the springs sit, not what they are) */
    uint64_t h = sd_hash_init();
    const sd_bodies *b = &w->b;
    for (int g = 0; g < w->next_gid; g++) {
        int i = w->gid_map[g];
        if (i < 0) continue;
        h = sd_hash_bytes(h, &b->pos[i], sizeof(sd_vec3));
        h = sd_hash_bytes(h, &b->vel[i], sizeof(sd_vec3));
        h = sd_hash_bytes(h, &b->omega[i], sizeof(sd_vec3));
        h = sd_hash_bytes(h, &b->quat[i], sizeof(sd_quat));
        h = sd_hash_bytes(h, &b->force[i], sizeof(sd_vec3));
    }
    for (int k = 0; k < w->bb.nh; k++)
        if (w->bb.hist[k].feature >= 0) h = sd_hash_bytes(h, &w->bb.hist[k].shear, sizeof(sd_vec3));
    for (int k = 0; k < w->bt.nh; k++)
        if (w->bt.hist[k].feature >= 0) h = sd_hash_bytes(h, &w->bt.hist[k].shear, sizeof(sd_vec3));
    return h;
}

sd_status sd_world_set_threads(sd_world *w, int threads)
{
    if (!w || threads < 1) return SD_ERR_ARG;
    w->def.threads = threads;
#ifdef _OPENMP
    w->nthreads = threads;
#endif
    return SD_OK;
}

int sd_world_threads(const sd_world *w) { return w->nthreads; }

int sd_world_simd_level(const sd_world *w) { return w->simd; }

int sd_world_set_simd_level(sd_world *w, int level)
{
    w->simd = sd_tuning_simd_level(level, sd_cpu_simd_level(), sd_cpu_is_amd());
    w->kern = sd_contact_kernels_for(w->simd);
    return w->simd;
}

sd_status sd_world_set_tuning(sd_world *w, const sd_tuning *t)
{
    if (!w || !t) return SD_ERR_ARG;
    sd_world_set_simd_level(w, t->simd);
    w->llc_bytes = t->llc_bytes > 0 ? t->llc_bytes : 32L << 20;
    sd_world_switch(w, SD_SW_PREFETCH, t->prefetch);
    w->def.tuning = *t;
    return SD_OK;
}

static const char *const switch_names[SD_SWITCH_COUNT] = {
#define SD_X_SWITCH(name, def, doc) #name,
    SD_SWITCH_TABLE(SD_X_SWITCH)
#undef SD_X_SWITCH
};

int sd_world_switch(sd_world *w, sd_switch which, int value)
{
    if ((int)which < 0 || which >= SD_SWITCH_COUNT) return -1;
    const int was = w->sw[which];
    if (which == SD_SW_PREFETCH) {
        if (value != SD_PREFETCH_OFF && value != SD_PREFETCH_ON) value = SD_PREFETCH_AUTO;
    } else if (which != SD_SW_MOVING_INDEX_MIN)
        value = value != 0;
    w->sw[which] = value;
    return was;
}

const char *sd_switch_name(sd_switch which) { return (int)which >= 0 && which < SD_SWITCH_COUNT ? switch_names[which] : "?"; }

int sd_switch_by_name(const char *name)
{
    for (int k = 0; k < SD_SWITCH_COUNT; k++) {
        const char *a = switch_names[k], *b = name;
        while (*a && *b && (*a | 0x20) == (*b | 0x20))
            a++, b++;
        if (!*a && !*b) return k;
    }
    return -1;
}

sd_body_view sd_world_bodies(const sd_world *w)
{
    const sd_bodies *b = &w->b;
    sd_body_view v = {.n = b->n,
                      .gid = b->gid,
                      .tag = b->tag,
                      .shape = b->shape,
                      .fixed = b->fixed,
                      .pos = b->pos,
                      .vel = b->vel,
                      .omega = b->omega,
                      .axis = b->axis,
                      .force = b->force,
                      .torque = b->torque,
                      .radius = b->radius,
                      .half_length = b->hl,
                      .bound_radius = b->bound_r,
                      .mass = b->mass};
    return v;
}

sd_status sd_world_triangle(const sd_world *w, int i, sd_vec3 corner[3], int *group, int *active)
{
    if (!w || i < 0 || i >= w->w.n) return SD_ERR_NOTFOUND;
    for (int k = 0; k < 3; k++)
        corner[k] = w->w.tri[i].v[k];
    if (group) *group = w->w.group[i];
    if (active) *active = w->w.active[i];
    return SD_OK;
}

const sd_world_def *sd_world_definition(const sd_world *w) { return &w->def; }

int sd_world_prefetch(const sd_world *w, int *trial, double *ratio)
{
    const int v = sd_front_prefetch_verdict(w, ratio);
    if (trial) *trial = w->sw[SD_SW_PREFETCH] == SD_PREFETCH_AUTO ? v : -1;
    return sd_front_prefetch_on(w) ? SD_PREFETCH_ON : SD_PREFETCH_OFF;
}

void sd_world_set_external_force_fn(sd_world *w, sd_external_force_fn fn, void *ctx)
{
    w->ext_fn = fn;
    w->ext_ctx = fn ? ctx : NULL;
}
