/* The decomposed run (docs/decomposition.md): run.c's phases over slabs along x, one a rank of
 * the run's transport (sd_run_comm, the program's MPI) or one in this process. Each rank steps
 * its slab (src/slabs.c: ghosts, migration, moving boundaries) and keeps a copy of the whole
 * system (c->w, never stepped) that run.c, trap.c and the outputs read as they read the one
 * world: its bodies are refreshed from their owners, every rank receiving every record in rank
 * order and putting it in place, so the copy's store order is the same on any count of ranks
 * and every sum over it comes out the same. Every rank makes the same decisions from the same
 * copy; rank 0 writes the files. The per-step agreement (the rebuild, the step's status, the
 * stop, the front, the pipes' states) is one allgather of a small block; the ghosts' refresh
 * and the migrations one alltoallv. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/vmath.h"
#include "run_ctx.h"
#include "slabs.h"

struct sd_run_slabs {
    const sd_run_comm *cm;
    sd_run_comm local; /* one slab in this process */
    sd_slab *slab;
    sd_grid_def grid;
    int any;       /* the next step remakes the pairs (agreed after the last step) */
    int force_any; /* the system changed between steps (every rank alike) */
    size_t rsz;
    double *bins, *sum;
    char *rec;
};

/* ---- the transport of one process ---- */

static int local_allgather(void *ctx, const void *mine, size_t len, void *all)
{
    (void)ctx;
    if (len) memcpy(all, mine, len);
    return 0;
}

static int local_allgatherv(void *ctx, const void *mine, size_t len, void **all, size_t *lens)
{
    (void)ctx;
    *all = malloc(len + 1);
    if (!*all) return -1;
    if (len) memcpy(*all, mine, len);
    lens[0] = len;
    return 0;
}

static int local_alltoallv(void *ctx, const void *const *out, const size_t *outlen, void **in, size_t *inlen)
{
    return local_allgatherv(ctx, out[0], outlen[0], in, inlen);
}

/* ---- the layout: the fixed grid and the ghost width ---- */

/* From the scenario's scene built with its dam into a scratch world, so that a run and its
 * restart (whose bodies may have passed the end, whose pipes are not in yet) take the same
 * grid: the cell from the largest sphere or cylinder diameter, the extent from the triangles
 * and the bodies; the ghost width from the largest bounding radius (a log's or a pipe's half
 * length), twice, plus the margin. */
static sd_status layout(const run_ctx *c, sd_grid_def *g, double *G)
{
    const sd_scenario *s = c->s;
    sd_world *w = NULL;
    sd_build_info info;
    memset(&info, 0, sizeof info);
    sd_status st = sd_world_create(&s->world, &w);
    if (!st) st = sd_build_scene_ex(w, s, &info, c->o->err, 1);
    if (st) {
        sd_world_destroy(w);
        return st;
    }
    sd_vec3 lo = v3(INFINITY, INFINITY, INFINITY), hi = v3(-INFINITY, -INFINITY, -INFINITY);
    for (int t = 0; t < sd_world_triangle_count(w); t++) {
        sd_vec3 q[3];
        int group, active;
        sd_world_triangle(w, t, q, &group, &active);
        for (int k = 0; k < 3; k++) {
            lo = v3(fmin(lo.x, q[k].x), fmin(lo.y, q[k].y), fmin(lo.z, q[k].z));
            hi = v3(fmax(hi.x, q[k].x), fmax(hi.y, q[k].y), fmax(hi.z, q[k].z));
        }
    }
    const sd_body_view v = sd_world_bodies(w);
    double br = 0.0;
    for (int i = 0; i < v.n; i++) {
        const double r = v.bound_radius[i];
        br = fmax(br, r);
        lo = v3(fmin(lo.x, v.pos[i].x - r), fmin(lo.y, v.pos[i].y - r), fmin(lo.z, v.pos[i].z - r));
        hi = v3(fmax(hi.x, v.pos[i].x + r), fmax(hi.y, v.pos[i].y + r), fmax(hi.z, v.pos[i].z + r));
    }
    const double margin = sd_world_definition(w)->margin;
    g->cell = sd_world_min_grid_cell(w);
    sd_world_destroy(w);
    if (!(lo.x <= hi.x)) lo = hi = v3(0.0, 0.0, 0.0);
    g->lo = v3_sub(lo, v3(g->cell, g->cell, g->cell));
    const sd_vec3 ext = v3_sub(v3_add(hi, v3(g->cell, g->cell, g->cell)), g->lo);
    g->nx = (int)ceil(ext.x / g->cell);
    g->ny = (int)ceil(ext.y / g->cell);
    g->nz = (int)ceil(ext.z / g->cell);
    *G = (2.0 * br + margin) * (1.0 + 1e-9) + 1e-12;
    return (double)g->nx * g->ny * g->nz > 2e9 ? SD_ERR_ARG : SD_OK;
}

int sd_run_slabs_agree(run_ctx *c, int v)
{
    const sd_run_comm *cm = c->sys->cm;
    int *all = malloc((size_t)cm->size * sizeof(int));
    int m = v;
    if (!all || cm->allgather(cm->ctx, &v, sizeof v, all)) m = v > 1 ? v : 1;
    else
        for (int r = 0; r < cm->size; r++)
            m = all[r] > m ? all[r] : m;
    free(all);
    return m;
}

int sd_run_slabs_begin(run_ctx *c)
{
    struct sd_run_slabs *x = calloc(1, sizeof *x);
    if (!x) return 1;
    x->local = (sd_run_comm){0, 1, NULL, local_allgather, local_allgatherv, local_alltoallv};
    x->cm = c->o->comm ? c->o->comm : &x->local;
    x->rsz = sd_body_record_size();
    x->rec = malloc(x->rsz);
    c->sys = x;
    c->rank = x->cm->rank;
    c->sys_front_stale = 1;
    double G = 0.0;
    sd_status st = x->rec ? layout(c, &x->grid, &G) : SD_ERR_NOMEM;
    const int n = x->cm->size;
    if (!st && (n < 1 || n > SD_SLABS_MAX)) st = SD_ERR_ARG;
    if (!st) {
        sd_slabs_opts so = {.n = n, .ghost_width = G, .rebalance = 2, .work_time = 0,
                            .threads = c->s->world.threads > 0 ? c->s->world.threads : 1};
        double xb[SD_SLABS_MAX + 1];
        sd_slab_first_bounds(c->w, n, xb);
        st = sd_slab_create(c->w, &x->grid, &so, x->cm->rank, xb, &x->slab);
    }
    if (!st) {
        x->bins = malloc((size_t)(x->grid.nx + 1) * sizeof(double));
        x->sum = malloc((size_t)(x->grid.nx + 1) * (size_t)n * sizeof(double));
        if (!x->bins || !x->sum) st = SD_ERR_NOMEM;
    }
    x->any = 1;
    const int bad = sd_run_slabs_agree(c, st != SD_OK);
    if (bad) {
        if (st) fprintf(c->o->err, "%s: cannot lay out the slabs: %s\n", c->s->path, sd_status_message(st));
        sd_run_slabs_end(c);
        return 1;
    }
    if (c->rank == 0 && c->o->log)
        fprintf(c->o->log, "decomposed: %d slab%s along x, ghost width %.4f m, grid %d x %d x %d of %.4f m\n", n,
                n > 1 ? "s" : "", G, x->grid.nx, x->grid.ny, x->grid.nz, x->grid.cell);
    return 0;
}

void sd_run_slabs_end(run_ctx *c)
{
    struct sd_run_slabs *x = c->sys;
    if (!x) return;
    sd_slab_destroy(x->slab);
    free(x->bins);
    free(x->sum);
    free(x->rec);
    free(x);
    c->sys = NULL;
}

sd_world *sd_run_slabs_world(run_ctx *c) { return c->sys ? sd_slab_world(c->sys->slab) : c->w; }

/* the records and springs of the redistribution, or the ghosts' refresh, between the slabs */
static sd_status exchange(struct sd_run_slabs *x, int any)
{
    const sd_run_comm *cm = x->cm;
    sd_status st = sd_slab_pack(x->slab, any);
    const void *out[SD_SLABS_MAX];
    size_t outlen[SD_SLABS_MAX], inlen[SD_SLABS_MAX];
    for (int r = 0; r < cm->size; r++)
        out[r] = sd_slab_outbox(x->slab, r, &outlen[r]);
    void *in = NULL;
    if (cm->alltoallv(cm->ctx, out, outlen, &in, inlen)) st = st ? st : SD_ERR_IO;
    if (!st) {
        const void *from[SD_SLABS_MAX];
        size_t off = 0;
        for (int r = 0; r < cm->size; r++) {
            from[r] = (const char *)in + off;
            off += inlen[r];
        }
        st = sd_slab_unpack(x->slab, any, from, inlen);
    }
    free(in);
    return st;
}

/* the per-step block: status, flags, wants a rebuild, the front, then each pipe: owned here,
 * its record */
typedef struct {
    int32_t status, flags, wants, pad;
    double front;
} step_head;

sd_status sd_run_slabs_step(run_ctx *c, int *flags)
{
    struct sd_run_slabs *x = c->sys;
    const sd_run_comm *cm = x->cm;
    const int n = cm->size, any = x->any || x->force_any;
    x->force_any = 0;
    sd_status st = SD_OK;
    if (any && sd_slab_balance_due(x->slab)) {
        /* the work bins summed in rank order on every rank: every rank takes the same bounds */
        const int nb = sd_slab_bins(x->slab);
        sd_slab_work_bins(x->slab, x->bins);
        if (cm->allgather(cm->ctx, x->bins, (size_t)nb * sizeof(double), x->sum)) st = SD_ERR_IO;
        for (int b = 0; b < nb && !st; b++) {
            double t = 0.0;
            for (int r = 0; r < n; r++)
                t += x->sum[(size_t)r * nb + b];
            x->bins[b] = t;
        }
        if (!st) sd_slab_balance(x->slab, x->bins);
    }
    sd_status xs = exchange(x, any);
    if (!st) st = xs;
    if (!st) st = sd_slab_step_world(x->slab);
    sd_world *sw = sd_slab_world(x->slab);
    const int np = c->dam_built ? c->info.n_pipes : 0;
    const size_t per = sizeof(int32_t) + x->rsz, blk = sizeof(step_head) + (size_t)np * per;
    char *mine = calloc(1, blk), *all = malloc(blk * (size_t)n);
    if (!mine || !all) {
        free(mine);
        free(all);
        return SD_ERR_NOMEM; /* (the others wait: out of memory here ends the run badly anyway) */
    }
    step_head h = {(int32_t)st, *flags, sd_world_needs_rebuild(sw), 0, sd_world_front_x(sw)};
    memcpy(mine, &h, sizeof h);
    for (int k = 0; k < np; k++) {
        char *p = mine + sizeof h + (size_t)k * per;
        const int32_t own = sd_slab_owns(x->slab, c->info.pipe_gid[k]);
        memcpy(p, &own, sizeof own);
        if (own) sd_world_body_record(sw, c->info.pipe_gid[k], p + sizeof own);
    }
    if (cm->allgather(cm->ctx, mine, blk, all)) st = st ? st : SD_ERR_IO;
    int f = 0, wants = 0, worst = st;
    double front = -INFINITY;
    for (int r = 0; r < n; r++) {
        step_head q;
        memcpy(&q, all + (size_t)r * blk, sizeof q);
        if (q.status && !worst) worst = q.status;
        f |= q.flags;
        wants |= q.wants;
        front = q.front > front ? q.front : front;
        for (int k = 0; k < np; k++) {
            const char *p = all + (size_t)r * blk + sizeof q + (size_t)k * per;
            int32_t own;
            memcpy(&own, p, sizeof own);
            if (own && sd_world_body_put(c->w, p + sizeof own, 0) && !worst) worst = SD_ERR_ARG;
        }
    }
    free(mine);
    free(all);
    x->any = wants;
    *flags = f;
    c->sys_front = front;
    c->sys_front_stale = 0;
    if (sd_world_set_clock(c->w, sd_world_time(sw), sd_world_step_count(sw)) && !worst) worst = SD_ERR_ARG;
    return (sd_status)worst;
}

/* a sync's entry per owned body: the record, the walls' force on it, the bed's */
sd_status sd_run_slabs_sync(run_ctx *c)
{
    struct sd_run_slabs *x = c->sys;
    const sd_run_comm *cm = x->cm;
    sd_world *sw = sd_slab_world(x->slab);
    const sd_body_view v = sd_world_bodies(sw);
    const size_t per = x->rsz + 2 * sizeof(sd_vec3);
    sd_vec3 *wall = malloc((size_t)(v.n + 1) * sizeof(sd_vec3)), *bed = malloc((size_t)(v.n + 1) * sizeof(sd_vec3));
    char *mine = malloc(2 * sizeof(int64_t) + (size_t)v.n * per);
    sd_status st = wall && bed && mine ? SD_OK : SD_ERR_NOMEM;
    int64_t m = 0, contacts = sd_slab_contacts(x->slab);
    if (!st) st = sd_world_body_wall_forces(sw, -1, wall);
    if (!st) st = sd_world_body_wall_forces(sw, SD_GROUP_BED, bed);
    for (int i = 0; i < v.n && !st; i++) {
        if (!sd_slab_owns(x->slab, v.gid[i])) continue;
        char *p = mine + 2 * sizeof(int64_t) + (size_t)m * per;
        st = sd_world_body_record(sw, v.gid[i], p);
        memcpy(p + x->rsz, &wall[i], sizeof(sd_vec3));
        memcpy(p + x->rsz + sizeof(sd_vec3), &bed[i], sizeof(sd_vec3));
        m++;
    }
    if (mine) {
        memcpy(mine, &contacts, sizeof contacts);
        memcpy(mine + sizeof(int64_t), &m, sizeof m);
    }
    void *all = NULL;
    size_t lens[SD_SLABS_MAX];
    if (cm->allgatherv(cm->ctx, mine, mine ? 2 * sizeof(int64_t) + (size_t)m * per : 0, &all, lens)) st = SD_ERR_IO;
    free(wall);
    free(bed);
    free(mine);
    /* every record in place in the copy; the walls' forces summed in gid order */
    const int ng = sd_world_next_gid(c->w) + 1;
    sd_vec3 *wg = st ? NULL : calloc((size_t)ng, 2 * sizeof(sd_vec3));
    uint8_t *seen = st ? NULL : calloc((size_t)ng, 1);
    if (!st && (!wg || !seen)) st = SD_ERR_NOMEM;
    long total = 0;
    size_t off = 0;
    for (int r = 0; r < cm->size && !st; r++) {
        if (lens[r] < 2 * sizeof(int64_t)) {
            st = SD_ERR_FORMAT;
            break;
        }
        const char *p = (const char *)all + off;
        int64_t cr, mr;
        memcpy(&cr, p, sizeof cr);
        memcpy(&mr, p + sizeof cr, sizeof mr);
        if (mr < 0 || lens[r] != 2 * sizeof(int64_t) + (size_t)mr * per) {
            st = SD_ERR_FORMAT;
            break;
        }
        total += (long)cr;
        for (int64_t q = 0; q < mr && !st; q++) {
            const char *e = p + 2 * sizeof(int64_t) + (size_t)q * per;
            const int g = sd_body_record_gid(e);
            if (g < 0 || g >= ng - 1) {
                st = SD_ERR_FORMAT;
                break;
            }
            st = sd_world_body_put(c->w, e, 0);
            memcpy(&wg[2 * g], e + x->rsz, 2 * sizeof(sd_vec3));
            seen[g] = 1;
        }
        off += lens[r];
    }
    sd_vec3 ws = v3(0.0, 0.0, 0.0), bs = v3(0.0, 0.0, 0.0);
    for (int g = 0; g < ng - 1 && !st; g++)
        if (seen[g]) {
            ws = v3_add(ws, wg[2 * g]);
            bs = v3_add(bs, wg[2 * g + 1]);
        }
    free(wg);
    free(seen);
    free(all);
    c->sys_synced_step = sd_world_step_count(c->w);
    c->sys_contacts = total;
    c->sys_wall = ws;
    c->sys_bed = bs;
    return st;
}

sd_status sd_run_slabs_remove(run_ctx *c, int gid)
{
    struct sd_run_slabs *x = c->sys;
    x->force_any = 1;
    c->sys_front_stale = 1;
    return sd_slab_owns(x->slab, gid) ? sd_world_remove_body(sd_slab_world(x->slab), gid) : SD_OK;
}

sd_status sd_run_slabs_add(run_ctx *c, int gid)
{
    struct sd_run_slabs *x = c->sys;
    sd_body_state b;
    x->force_any = 1;
    sd_status st = sd_world_body(c->w, gid, &b);
    if (!st) st = sd_world_body_record(c->w, gid, x->rec);
    if (!st) st = sd_slab_add_body(x->slab, x->rec, b.pos.x);
    return st;
}

sd_status sd_run_slabs_group_active(run_ctx *c, int group, int active)
{
    c->sys->force_any = 1;
    return sd_world_set_group_active(sd_slab_world(c->sys->slab), group, active);
}

void sd_run_slabs_request_rebuild(run_ctx *c) { c->sys->force_any = 1; }

int sd_run_slabs_rebuilds_next(const run_ctx *c) { return c->sys->any || c->sys->force_any; }

/* every rank's owned records and springs, on every rank */
static sd_status gather_state(struct sd_run_slabs *x, int with_recs, char **recs, int *nb, sd_spring **sp, int *ns)
{
    const sd_run_comm *cm = x->cm;
    void *r = NULL;
    sd_spring *q = NULL;
    int a = 0, b = 0;
    sd_status st = sd_slab_state(x->slab, &r, &a, &q, &b);
    size_t lens[SD_SLABS_MAX];
    void *all = NULL;
    *recs = NULL;
    *sp = NULL;
    *nb = *ns = 0;
    if (cm->allgatherv(cm->ctx, q, st ? 0 : (size_t)b * sizeof(sd_spring), &all, lens)) st = SD_ERR_IO;
    size_t tot = 0;
    for (int k = 0; k < cm->size && !st; k++)
        tot += lens[k];
    *sp = all;
    *ns = (int)(tot / sizeof(sd_spring));
    all = NULL;
    if (cm->allgatherv(cm->ctx, r, st || !with_recs ? 0 : (size_t)a * x->rsz, &all, lens)) st = SD_ERR_IO;
    tot = 0;
    for (int k = 0; k < cm->size && !st; k++)
        tot += lens[k];
    *recs = all;
    *nb = (int)(tot / x->rsz);
    free(r);
    free(q);
    return st;
}

sd_status sd_run_slabs_whole(run_ctx *c, sd_world **out)
{
    struct sd_run_slabs *x = c->sys;
    *out = NULL;
    char *recs;
    sd_spring *sp;
    int nb, ns;
    sd_status st = gather_state(x, 0, &recs, &nb, &sp, &ns);
    free(recs);
    if (st || c->rank != 0) {
        free(sp);
        return st;
    }
    /* the copy's bodies in its store order (that of every rank's copy), its triangles, clock and
     * gids; the springs kept for the rebuild a restart starts with (this run remakes its pairs
     * at the next step too: sd_run_slabs_request_rebuild) */
    sd_world *w = NULL;
    st = sd_world_create(sd_world_definition(c->w), &w);
    const int nt = sd_world_triangle_count(c->w);
    for (int t = 0; t < nt && !st; t++) {
        sd_vec3 q[3];
        int group, active;
        sd_world_triangle(c->w, t, q, &group, &active);
        if (sd_world_add_triangle(w, q[0], q[1], q[2], group) != t) st = SD_ERR_ARG;
    }
    for (int t = 0; t < nt && !st; t++) {
        sd_vec3 q[3];
        int group, active;
        sd_world_triangle(c->w, t, q, &group, &active);
        if (!active) st = sd_world_set_group_active(w, group, 0);
    }
    if (!st) st = sd_world_copy_materials(w, c->w);
    const sd_body_view v = sd_world_bodies(c->w);
    for (int i = 0; i < v.n && !st; i++) {
        st = sd_world_body_record(c->w, v.gid[i], x->rec);
        if (!st) st = sd_world_body_put(w, x->rec, 0);
    }
    if (!st) st = sd_world_set_next_gid(w, sd_world_next_gid(c->w));
    if (!st) st = sd_world_set_clock(w, sd_world_time(c->w), sd_world_step_count(c->w));
    if (!st) st = sd_world_springs_put(w, sp, ns);
    free(sp);
    if (st) {
        sd_world_destroy(w);
        return st;
    }
    *out = w;
    return SD_OK;
}

uint64_t sd_run_slabs_hash(run_ctx *c)
{
    char *recs;
    sd_spring *sp;
    int nb, ns;
    const sd_status st = gather_state(c->sys, 1, &recs, &nb, &sp, &ns);
    const uint64_t h = st ? 0 : sd_state_hash_records(recs, nb, sp, ns);
    free(recs);
    free(sp);
    return h;
}

void sd_run_slabs_stats(run_ctx *c)
{
    struct sd_run_slabs *x = c->sys;
    const sd_run_comm *cm = x->cm;
    const sd_slabs_stats *t = sd_slab_stats(x->slab);
    double mine[4] = {(double)t->migrations, (double)t->boundary_moves, t->bytes, (double)t->rebuilds};
    double *all = malloc((size_t)cm->size * sizeof mine);
    sd_run_slabs_report *r = &c->sys_report;
    memset(r, 0, sizeof *r);
    r->ranks = cm->size;
    r->ghost_width = sd_slab_ghost_width(x->slab);
    sd_slab_bounds(x->slab, r->bounds);
    if (!all || cm->allgather(cm->ctx, mine, sizeof mine, all)) {
        free(all);
        return;
    }
    for (int k = 0; k < cm->size; k++) {
        r->migrations += (long)all[4 * k];
        r->bytes += all[4 * k + 2];
    }
    r->boundary_moves = (long)mine[1]; /* (the same on every rank) */
    r->redistributions = (long)mine[3];
    free(all);
}
