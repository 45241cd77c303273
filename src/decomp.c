/* What a spatial decomposition needs of a world (docs/decomposition.md): a fixed body grid, whole
 * bodies as records put in and taken out by gid, ghosts (in the contacts, not moved), the
 * springs listed and put back by key, the rebuild asked for and the clock set, and the state's
 * hash in a canonical order that worlds holding parts of one system can compute together.
 * None of it runs in a step's loops: the grid and the sort by gid are the rebuild's
 * (neighbor.c), the ghosts leave the moving list (neighbor.c sd_neighbor_moving_update). */
#include <stdlib.h>
#include <string.h>

#include "core/hash.h"
#include "neighbor_internal.h"

sd_status sd_world_set_fixed_grid(sd_world *w, const sd_grid_def *g)
{
    if (!w) return SD_ERR_ARG;
    if (!g) {
        w->fgrid_on = 0;
        w->need_rebuild = 1;
        return SD_OK;
    }
    if (!(g->cell > 0.0) || !isfinite(g->cell) || !isfinite(g->lo.x) || !isfinite(g->lo.y) || !isfinite(g->lo.z) ||
        g->nx < 1 || g->ny < 1 || g->nz < 1 || (double)g->nx * g->ny * g->nz > 2e9)
        return SD_ERR_ARG;
    w->fgrid = *g;
    w->fgrid_on = 1;
    w->need_rebuild = 1;
    w->bed.made = 0; /* (its layout was the automatic grid's) */
    return SD_OK;
}

double sd_world_min_grid_cell(const sd_world *w)
{
    double dmax = 0.0;
    for (int i = 0; i < w->b.n; i++)
        dmax = 2.0 * w->b.radius[i] > dmax ? 2.0 * w->b.radius[i] : dmax;
    if (dmax <= 0.0) dmax = 0.01;
    return dmax + w->def.margin;
}

size_t sd_body_record_size(void) { return sd_bodies_record_size(); }

sd_status sd_world_body_record(const sd_world *w, int gid, void *rec)
{
    if (!w || !rec) return SD_ERR_ARG;
    if (gid < 0 || gid >= w->next_gid || w->gid_map[gid] < 0) return SD_ERR_NOTFOUND;
    sd_bodies_get_record(&w->b, w->gid_map[gid], rec);
    return SD_OK;
}

int sd_body_record_gid(const void *rec)
{
    int32_t g;
    memcpy(&g, rec, sizeof g); /* (gid is the field table's first field) */
    return g;
}

int sd_world_body_is_ghost(const sd_world *w, int gid)
{
    return w && gid >= 0 && gid < w->ghost_cap && w->ghost[gid];
}

static sd_status set_ghost(sd_world *w, int gid, int ghost)
{
    if (!ghost && (gid >= w->ghost_cap || !w->ghost[gid])) return SD_OK;
    if (gid >= w->ghost_cap) {
        const int was = w->ghost_cap;
        if (sd_grow((void **)&w->ghost, &w->ghost_cap, gid + 1, 1)) return SD_ERR_NOMEM;
        memset(w->ghost + was, 0, (size_t)(w->ghost_cap - was));
    }
    if (w->ghost[gid] != (uint8_t)(ghost != 0)) {
        w->ghost[gid] = (uint8_t)(ghost != 0);
        w->mov_stamp = -1; /* the moving list is remade */
    }
    return SD_OK;
}

sd_status sd_world_body_put(sd_world *w, const void *rec, int ghost)
{
    if (!w || !rec) return SD_ERR_ARG;
    sd_bodies *b = &w->b;
    const int gid = sd_body_record_gid(rec);
    if (gid < 0 || gid == INT32_MAX) return SD_ERR_ARG;
    if (gid < w->next_gid && w->gid_map[gid] >= 0) {
        const int i = w->gid_map[gid];
        const uint8_t shape = b->shape[i], fixed = b->fixed[i];
        const sd_vec3 p0 = b->pos[i];
        const sd_quat q0 = b->quat[i];
        sd_bodies_set_record(b, i, rec);
        if (ghost) {
            /* how far its surface moved: the centre's move, and for a log the attitude's
             * (|R' - R| <= 2 |q' - q| for unit quaternions) times its bounding radius; the
             * near pairs of this world are remade once its drift passes half their skin, as
             * after a move of its own bodies (a near list left as it was would miss a contact
             * this ghost closed: another world's own body would miss its force) */
            const sd_quat dq = {b->quat[i].w - q0.w, b->quat[i].x - q0.x, b->quat[i].y - q0.y, b->quat[i].z - q0.z};
            double d = v3_norm(v3_sub(b->pos[i], p0));
            if (shape != SD_SHAPE_SPHERE)
                d += 2.0 * sqrt(dq.w * dq.w + dq.x * dq.x + dq.y * dq.y + dq.z * dq.z) * b->bound_r[i];
            d *= 1.0 + 1e-9;
            if (!(d <= w->ghost_drift)) w->ghost_drift = isfinite(d) ? d : INFINITY;
        }
        if (b->shape[i] != shape || b->fixed[i] != fixed) {
            b->shape[i] = shape, b->fixed[i] = fixed;
            return SD_ERR_ARG;
        }
        if (b->ext_force && sd_ext_set(b->ext_force[i])) w->ext_any = 1;
        return set_ghost(w, gid, ghost);
    }
    /* a new body: the springs taken out before the store grows (add_body's way) */
    sd_status st = sd_history_collect(w);
    if (st) return st;
    if (sd_bodies_reserve(b, b->n + 1)) return SD_ERR_NOMEM;
    if (gid >= w->next_gid) {
        if (sd_grow((void **)&w->gid_map, &w->gid_cap, gid + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
        for (int g = w->next_gid; g <= gid; g++)
            w->gid_map[g] = -1;
        w->next_gid = gid + 1;
    }
    const int i = b->n++;
    sd_bodies_set_record(b, i, rec);
    w->gid_map[gid] = i;
    if (sd_ext_set(b->ext_force[i])) w->ext_any = 1;
    w->body_version++;
    w->need_rebuild = 1;
    w->checked = 0;
    w->mov_stamp = -1;
    return set_ghost(w, gid, ghost);
}

static uint64_t spring_key(int32_t gid_a, int kind, int32_t id_b)
{
    return ((uint64_t)(uint32_t)gid_a << 32) | ((uint64_t)(uint32_t)kind << 29) | (uint64_t)(uint32_t)id_b;
}

static sd_spring spring_of(uint64_t key, const sd_hist *h)
{
    sd_spring s;
    s.gid_a = (int32_t)(uint32_t)(key >> 32);
    s.kind = (int32_t)((key >> 29) & 7u);
    s.id_b = (int32_t)(uint32_t)(key & ((1u << 29) - 1u));
    s.feature = h->feature;
    s.shear = h->shear;
    return s;
}

int sd_world_springs(const sd_world *w, sd_spring *out, int cap)
{
    if (!w) return 0;
    sd_near_springs_home((sd_world *)w); /* (where the springs sit, not what they are) */
    int n = 0;
    if (w->keys_collected) {
        for (int k = 0; k < w->n_old; k++) {
            if (w->old_hist[k].feature < 0) continue;
            if (n < cap) out[n] = spring_of(w->old_keys[k], &w->old_hist[k]);
            n++;
        }
        return n;
    }
    const sd_pairlist *lists[2] = {&w->bb, &w->bt};
    for (int l = 0; l < 2; l++)
        for (int k = 0; k < lists[l]->n; k++) {
            const sd_pair *p = &lists[l]->p[k];
            const int32_t ida = w->b.gid[p->a];
            const int32_t idb = l ? p->b : w->b.gid[p->b];
            for (int s = 0; s < p->cap; s++) {
                const sd_hist *h = &lists[l]->hist[p->off + s];
                if (h->feature < 0) continue;
                if (n < cap) out[n] = spring_of(spring_key(ida, p->kind, idb), h);
                n++;
            }
        }
    return n;
}

typedef struct {
    uint64_t key;
    sd_hist h;
    int src; /* 0: the world's own, 1: put */
} keyed;

static int keyed_cmp(const void *x, const void *y)
{
    const keyed *a = x, *b = y;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    if (a->h.feature != b->h.feature) return a->h.feature < b->h.feature ? -1 : 1;
    return a->src - b->src;
}

sd_status sd_world_springs_put(sd_world *w, const sd_spring *s, int n)
{
    if (!w || (n > 0 && !s) || n < 0) return SD_ERR_ARG;
    sd_status st = sd_history_collect(w); /* (the world's own, keyed, for the coming rebuild) */
    if (st) return st;
    const int m = w->n_old + n;
    keyed *all = malloc((size_t)(m + 1) * sizeof(keyed));
    if (!all) return SD_ERR_NOMEM;
    int q = 0;
    for (int k = 0; k < w->n_old; k++)
        if (w->old_hist[k].feature >= 0) all[q++] = (keyed){w->old_keys[k], w->old_hist[k], 0};
    for (int k = 0; k < n; k++) {
        if (s[k].feature < 0 || s[k].kind < 0 || s[k].kind >= SD_PAIR_KINDS || s[k].id_b < 0 ||
            s[k].id_b >= (1 << 29)) {
            free(all);
            return SD_ERR_ARG;
        }
        all[q++] = (keyed){spring_key(s[k].gid_a, s[k].kind, s[k].id_b), {s[k].feature, s[k].shear}, 1};
    }
    /* by key, then feature (a pair's run in feature order, each gid's entries one run, as the
     * rebuild's restore finds them by gid): the world's own first, a put one of the same key
     * and feature dropped */
    qsort(all, (size_t)q, sizeof(keyed), keyed_cmp);
    if (sd_grow((void **)&w->old_keys, &w->old_cap, q + 1, sizeof(uint64_t)) ||
        sd_grow((void **)&w->old_hist, &w->old_hist_cap, q + 1, sizeof(sd_hist))) {
        free(all);
        return SD_ERR_NOMEM;
    }
    int o = 0;
    for (int k = 0; k < q; k++) {
        if (o > 0 && w->old_keys[o - 1] == all[k].key && w->old_hist[o - 1].feature == all[k].h.feature) continue;
        w->old_keys[o] = all[k].key;
        w->old_hist[o] = all[k].h;
        o++;
    }
    free(all);
    w->n_old = o;
    w->old_n_bodies = -1; /* (found by gid, not by the sort's permutation) */
    w->need_rebuild = 1;
    return SD_OK;
}

int sd_world_needs_rebuild(const sd_world *w) { return w && sd_neighbor_needs_rebuild(w); }

void sd_world_request_rebuild(sd_world *w)
{
    if (w) w->need_rebuild = 1;
}

sd_status sd_world_set_clock(sd_world *w, double time, long step)
{
    if (!w || !isfinite(time) || step < 0) return SD_ERR_ARG;
    w->time = time;
    w->step = step;
    w->last_rebuild_time = time;
    w->need_rebuild = 1;
    return SD_OK;
}

sd_status sd_world_set_next_gid(sd_world *w, int next_gid)
{
    if (!w || next_gid < 0 || next_gid == INT32_MAX) return SD_ERR_ARG;
    for (int i = 0; i < w->b.n; i++)
        if (w->b.gid[i] >= next_gid) return SD_ERR_ARG;
    if (next_gid > w->next_gid) {
        if (sd_grow((void **)&w->gid_map, &w->gid_cap, next_gid + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
        for (int g = w->next_gid; g < next_gid; g++)
            w->gid_map[g] = -1;
    }
    w->next_gid = next_gid;
    return SD_OK;
}

int sd_world_next_gid(const sd_world *w) { return w ? w->next_gid : 0; }

sd_status sd_world_body_wall_forces(const sd_world *w, int group, sd_vec3 *out)
{
    if (!w || (w->b.n > 0 && !out)) return SD_ERR_ARG;
    for (int i = 0; i < w->b.n; i++)
        out[i] = v3(0.0, 0.0, 0.0);
    if (w->keys_collected) return SD_OK; /* (no pairs since the store changed: no loads either) */
    for (int k = 0; k < w->bt.n; k++) {
        const int t = w->bt.p[k].b;
        if (!w->bt.active[k] || !w->w.active[t] || (group >= 0 && w->w.group[t] != group)) continue;
        out[w->bt.p[k].a] = v3_add(out[w->bt.p[k].a], w->bt.out[k]);
    }
    return SD_OK;
}

/* ---- the canonical hash ---- */

typedef struct {
    const char *rec;
    int32_t gid;
} rec_ref;

static int rec_cmp(const void *x, const void *y)
{
    const rec_ref *a = x, *b = y;
    return (a->gid > b->gid) - (a->gid < b->gid);
}

static int spring_cmp(const void *x, const void *y)
{
    const sd_spring *a = x, *b = y;
    const uint64_t ka = spring_key(a->gid_a, a->kind, a->id_b), kb = spring_key(b->gid_a, b->kind, b->id_b);
    if (ka != kb) return ka < kb ? -1 : 1;
    return (a->feature > b->feature) - (a->feature < b->feature);
}

/* the offsets of the hashed fields in a record */
typedef struct {
    size_t pos, vel, omega, quat, force;
} rec_layout;

static rec_layout layout_of(void)
{
    return (rec_layout){sd_bodies_record_offset("pos"), sd_bodies_record_offset("vel"),
                        sd_bodies_record_offset("omega"), sd_bodies_record_offset("quat"),
                        sd_bodies_record_offset("force")};
}

uint64_t sd_state_hash_records(const void *recs, int nb, const sd_spring *springs, int ns)
{
    const size_t sz = sd_bodies_record_size();
    const rec_layout L = layout_of();
    rec_ref *r = malloc((size_t)(nb + 1) * sizeof(rec_ref));
    sd_spring *s = malloc((size_t)(ns + 1) * sizeof(sd_spring));
    uint64_t h = sd_hash_init();
    if (!r || !s) {
        free(r);
        free(s);
        return 0;
    }
    for (int k = 0; k < nb; k++) {
        r[k].rec = (const char *)recs + (size_t)k * sz;
        r[k].gid = sd_body_record_gid(r[k].rec);
    }
    qsort(r, (size_t)nb, sizeof(rec_ref), rec_cmp);
    for (int k = 0; k < nb; k++) {
        h = sd_hash_bytes(h, r[k].rec + L.pos, sizeof(sd_vec3));
        h = sd_hash_bytes(h, r[k].rec + L.vel, sizeof(sd_vec3));
        h = sd_hash_bytes(h, r[k].rec + L.omega, sizeof(sd_vec3));
        h = sd_hash_bytes(h, r[k].rec + L.quat, sizeof(sd_quat));
        h = sd_hash_bytes(h, r[k].rec + L.force, sizeof(sd_vec3));
    }
    if (ns > 0) memcpy(s, springs, (size_t)ns * sizeof(sd_spring));
    qsort(s, (size_t)ns, sizeof(sd_spring), spring_cmp);
    for (int k = 0; k < ns; k++)
        h = sd_hash_bytes(h, &s[k].shear, sizeof(sd_vec3));
    free(r);
    free(s);
    return h;
}

uint64_t sd_world_state_hash_canonical(const sd_world *w)
{
    const size_t sz = sd_bodies_record_size();
    const int nb = w->b.n;
    char *recs = malloc((size_t)(nb + 1) * sz);
    const int ns = sd_world_springs(w, NULL, 0);
    sd_spring *s = malloc((size_t)(ns + 1) * sizeof(sd_spring));
    uint64_t h = 0;
    if (recs && s) {
        for (int i = 0; i < nb; i++)
            sd_bodies_get_record(&w->b, i, recs + (size_t)i * sz);
        sd_world_springs(w, s, ns);
        h = sd_state_hash_records(recs, nb, s, ns);
    }
    free(recs);
    free(s);
    return h;
}
