/* Candidate search (SPEC §4, sec. 2.4 (9)): uniform cell grids, margin r_dam, rebuild every
 * t_reset or when an element moved more than r_dam/2. Bodies and triangles have one grid each;
 * an element is registered in every cell its margin-expanded box covers, and a pair is taken
 * only in the lowest cell its two boxes share, so each pair is found once. Cost O(N).
 * This file: the rebuild's orchestration and its stage timers, the store's re-sort by cell, the
 * moving bodies' list; the grids are grid.c's, the bed's cache bed_cache.c's, the springs
 * carried across pair_history.c's, the scan candidates.c's (neighbor_internal.h). */

#include <stdlib.h>
#include <string.h>

#include "neighbor_internal.h"

static void set_effective_masses(sd_world *w)
{
    const sd_bodies *b = &w->b;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) if (w->bb.n > w->def.parallel_min)
    for (int k = 0; k < w->bb.n; k++) {
        sd_pair *p = &w->bb.p[k];
        double ma = b->mass[p->a], mb = b->mass[p->b], m;
        if (b->fixed[p->b])
            m = ma;
        else if (b->fixed[p->a])
            m = mb;
        else
            m = ma * mb / (ma + mb);
        p->sqrt_m_eff = sqrt(m);
    }
    for (int k = 0; k < w->bt.n; k++)
        w->bt.p[k].sqrt_m_eff = sqrt(b->mass[w->bt.p[k].a]);
}

sd_status sd_neighbor_tgrid_flags(sd_world *w)
{
    const sd_grid *g = &w->tgrid;
    const int nitems = g->cell_start[g->nx * g->ny * g->nz];
    if (sd_grow((void **)&w->tflag, &w->tflag_cap, nitems + 1, sizeof(uint8_t))) return SD_ERR_NOMEM;
    sd_grid_flags(g, (const int32_t(*)[6])w->trange, w->tflag);
    return SD_OK;
}

/* Re-sort the store by the grid cell of each centre (stable counting sort), so that
 * neighbours in space are neighbours in memory; the history was already taken out by key.
 * Bodies 0 .. n-1 only: the caller knows the rest (the bed, in the bed cache's layout) to be
 * in order already, after every other body. */
/* A counting sort's start of each of the 2 ncell cells (moving, then bed) for the bodies'
 * cells: calloc'ed (the caller frees it), NULL when out of memory. */
static int32_t *cell_starts(const int32_t *cell, int n, int ncell)
{
    int32_t *count = calloc(2 * (size_t)ncell + 1, sizeof(int32_t));
    if (!count) return NULL;
    for (int i = 0; i < n; i++)
        count[cell[i] + 1]++;
    for (int c = 0; c < 2 * ncell; c++)
        count[c + 1] += count[c];
    return count;
}

static sd_status sort_bodies_by_cell(sd_world *w, int n)
{
    sd_bodies *b = &w->b;
    const sd_grid *g = &w->grid;
    int ncell = g->nx * g->ny * g->nz;
    w->rb_perm_m = 0;
    int32_t *cell = malloc((size_t)(n + 1) * sizeof(int32_t));
    int32_t *count = NULL;
    sd_status st = SD_OK;
    if (!cell || sd_grow((void **)&w->rb_perm, &w->rb_perm_cap, n + 1, sizeof(int32_t))) {
        st = SD_ERR_NOMEM;
        goto done;
    }
    int32_t *const perm = w->rb_perm;
    int unsorted = 0;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) reduction(| : unsorted) if (n > w->def.parallel_min)
    for (int i = 0; i < n; i++) {
        sd_vec3 c = b->pos[i];
        int r[6];
        cell_range(g, c, c, r, w->simd);
        /* x slowest: a contiguous index range is a slab across the flume (the thread ranges of
         * contact.c), whatever order the grid's own cells use */
        cell[i] = (r[0] * g->ny + r[1]) * g->nz + r[2];
        /* the bed roughness (fixed spheres, half the paper's elements) after everything
         * else: the per-step passes walk the moving bodies densely, and the bed, which never
         * moves, keeps its place from one rebuild to the next */
        cell[i] += sd_body_is_bed(b, i) ? ncell : 0;
    }
    if (w->fgrid_on) {
        /* a fixed grid (decomp.c): a cell's bodies by gid, whatever the order before, so that
         * worlds holding parts of one system order their common bodies alike: the bodies in
         * gid order, then a stable counting sort over the cells */
        for (int i = 1; i < n; i++)
            unsorted |= cell[i] < cell[i - 1] || (cell[i] == cell[i - 1] && b->gid[i] < b->gid[i - 1]);
        if (!unsorted) goto done;
        if (!(count = cell_starts(cell, n, ncell))) {
            st = SD_ERR_NOMEM;
            goto done;
        }
        for (int id = 0; id < w->next_gid; id++) {
            const int i = w->gid_map[id];
            if (i >= 0 && i < n) perm[count[cell[i]]++] = i;
        }
        goto permute;
    }
    for (int i = 1; i < n; i++)
        unsorted |= cell[i] < cell[i - 1];
    if (!unsorted) goto done;
    /* between two rebuilds a few bodies change cells, each passing a few others: a stable
     * insertion sort, while its moves stay under 8 per body; else (a store out of order, the
     * first rebuild) a stable counting sort over the cells. The same order either way. */
    long moves = 0;
    const long max_moves = 8L * n + 64;
    for (int i = 0; i < n; i++)
        perm[i] = i;
    for (int i = 1; i < n && moves <= max_moves; i++) {
        const int x = perm[i], cx = cell[x];
        int j = i - 1;
        for (; j >= 0 && cell[perm[j]] > cx && moves <= max_moves; j--, moves++)
            perm[j + 1] = perm[j];
        perm[j + 1] = x;
    }
    if (moves > max_moves) {
        if (!(count = cell_starts(cell, n, ncell))) {
            st = SD_ERR_NOMEM;
            goto done;
        }
        for (int i = 0; i < n; i++)
            perm[count[cell[i]]++] = i;
    }
permute:;
    /* the bed at the end stays where it was: permute the part before it only */
    int m = n;
    while (m > 0 && perm[m - 1] == m - 1)
        m--;
    st = sd_bodies_permute(b, perm, m, w->nthreads);
    if (st) goto done;
    w->rb_perm_m = m; /* (for restore_history) */
    for (int i = 0; i < m; i++)
        w->gid_map[b->gid[i]] = i;
done:
    free(cell);
    free(count);
    return st;
}

int sd_neighbor_needs_rebuild(const sd_world *w)
{
    return w->need_rebuild || w->rebuild_every_step || w->w.dirty ||
           w->time - w->last_rebuild_time >= w->def.t_reset - 0.5 * w->def.dt;
}

static _Thread_local double rb_stage[SD_RB_STAGES];

void sd_neighbor_stages_take(double *t)
{
    for (int k = 0; k < SD_RB_STAGES; k++) {
        t[k] = rb_stage[k];
        rb_stage[k] = 0.0;
    }
}

const char *sd_neighbor_stage_name(int k)
{
    static const char *const names[SD_RB_STAGES] = {"collect", "layout", "sort",   "ranges",  "fill",
                                                    "scan",    "join",   "masses", "restore", "refs"};
    return k >= 0 && k < SD_RB_STAGES ? names[k] : "?";
}

/* stage k ends now: its time since the last mark into rb_stage[k] */
#define RB_STAGE(k)                                                                                                    \
    do {                                                                                                               \
        const double t_ = sd_now();                                                                                    \
        rb_stage[k] += t_ - rb_t;                                                                                      \
        rb_t = t_;                                                                                                     \
    } while (0)

sd_status sd_neighbor_rebuild(sd_world *w)
{
    sd_bodies *b = &w->b;
    double rb_t = sd_now();
    const int fresh = !w->keys_collected; /* the collect is this rebuild's own */
    sd_status st = sd_history_collect(w);
    if (st) return st;
    RB_STAGE(SD_RB_COLLECT);
    w->keys_collected = 0;
    double hm = 0.5 * w->def.margin;

    /* the bed as the last full rebuild left it, while no body came or went: its boxes, ranges
     * and grid entries are taken from there if the grid keeps its layout (same bits) */
    const sd_bed_cache *bc = &w->bed;
    const int bed0 = w->sw[SD_SW_BED_CACHE] && bc->made && bc->version == w->body_version && bc->n == b->n;
    const int nb = bed0 ? bc->nb0 : b->n;

    /* cell size: the largest sphere diameter plus the margin; cylinders span several cells */
    double dmax = 0.0;
    const int par = b->n > w->def.parallel_min;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) reduction(max : dmax) if (par)
    for (int i = 0; i < b->n; i++)
        dmax = 2.0 * b->radius[i] > dmax ? 2.0 * b->radius[i] : dmax;
    if (dmax <= 0.0) dmax = 0.01;
    double cell = dmax + w->def.margin;
    if (w->fgrid_on) { /* a fixed grid (decomp.c): the same cells in every world that has it */
        if (!(w->fgrid.cell >= cell)) return SD_ERR_ARG;
        cell = w->fgrid.cell;
    }

    if (w->w.dirty) {
        st = sd_grid_tri_rebuild(w, cell);
        if (st) return st;
    }

    /* the box of all bodies, and the bed's low corner (the grid's anchor): the bed's part from
     * the cache, else found with the rest */
    double lx = 1e300, ly = 1e300, lz = 1e300, hx = -1e300, hy = -1e300, hz = -1e300;
    double ax = 1e300, ay = 1e300, az = 1e300;
    int nbed = 0;
    if (bed0) {
        lx = ax = bc->blo.x, ly = ay = bc->blo.y, lz = az = bc->blo.z;
        hx = bc->bhi.x, hy = bc->bhi.y, hz = bc->bhi.z;
        nbed = b->n - bc->nb0;
    }
#pragma omp parallel for num_threads(w->nthreads) schedule(static) reduction(min : lx, ly, lz, ax, ay, az) reduction(max : hx, hy, hz) \
    reduction(+ : nbed) if (par)
    for (int i = 0; i < nb; i++) {
        sd_vec3 l, h;
        body_box(b, i, hm, &l, &h);
        /* (not fmin / fmax: library calls here) */
        lx = l.x < lx ? l.x : lx, ly = l.y < ly ? l.y : ly, lz = l.z < lz ? l.z : lz;
        hx = h.x > hx ? h.x : hx, hy = h.y > hy ? h.y : hy, hz = h.z > hz ? h.z : hz;
        if (sd_body_is_bed(b, i)) {
            ax = l.x < ax ? l.x : ax, ay = l.y < ay ? l.y : ay, az = l.z < az ? l.z : az;
            nbed++;
        }
    }
    sd_vec3 lo = v3(lx, ly, lz), hi = v3(hx, hy, hz);
    if (b->n == 0) lo = hi = v3(0, 0, 0);
    const sd_vec3 anchor = v3(ax, ay, az);
    long max_cells = 8L * b->n + 4096;
    if (w->fgrid_on)
        st = sd_grid_layout_fixed(&w->grid, w->fgrid.lo, cell, w->fgrid.nx, w->fgrid.ny, w->fgrid.nz);
    else
        st = sd_grid_layout(&w->grid, lo, hi, cell, max_cells, nbed ? &anchor : NULL);
    if (st) return st;
    RB_STAGE(SD_RB_LAYOUT);
    const sd_grid *g = &w->grid;
    const int bed = bed0 && sd_bed_cache_fits(bc, g);
    const int nr = bed ? bc->nb0 : b->n; /* the bodies whose cells and ranges are made here */
    if ((st = sort_bodies_by_cell(w, nr))) return st;
    w->mov_stamp = -1; /* the store was reordered */
    if ((st = sd_neighbor_moving_update(w))) return st;
    RB_STAGE(SD_RB_SORT);
    if (sd_grow((void **)&w->range, &w->range_cap, b->n + 1, sizeof(*w->range)) ||
        sd_grow((void **)&w->box, &w->box_cap, 2 * b->n + 2, sizeof(sd_vec3)))
        return SD_ERR_NOMEM;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) if (nr > w->def.parallel_min)
    for (int i = 0; i < nr; i++) {
        sd_vec3 l, h;
        body_box(b, i, hm, &l, &h);
        w->box[2 * i] = l;
        w->box[2 * i + 1] = h;
        cell_range(&w->grid, l, h, w->range[i], w->simd);
    }
    w->box_n = nr;
    RB_STAGE(SD_RB_RANGES);
    if (bed) memcpy(w->range + nr, bc->range, (size_t)(b->n - nr) * sizeof(*w->range));
    if (sd_grow((void **)&w->reg0, &w->reg0_cap, b->n + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    {
        const int T = rebuild_threads(w, nr);
#ifdef _OPENMP
        if (T > 1)
            st = sd_grid_fill_par(&w->grid, b->n, (const int32_t(*)[6])w->range, w->reg0, &w->slot, &w->slot_cap,
                                  &w->gflag, &w->gflag_cap, bed ? bc : NULL, T);
        else
#endif
            st = sd_grid_fill(&w->grid, b->n, (const int32_t(*)[6])w->range, NULL, w->reg0, &w->slot, &w->slot_cap,
                              &w->gflag, &w->gflag_cap, bed ? bc : NULL);
    }
    if (st) return st;
    if (bed)
        w->bed.used++;
    else if ((st = sd_bed_cache_make(w, hm)))
        return st;
    /* the prefilter's floats, where bb_scan will read them (AVX2, not AVX-512) */
    w->gq_stride = 0;
#ifdef SD_SCAN512
    if (w->sw[SD_SW_SCAN_PRE] && w->simd == SD_SIMD_AVX2) {
        if ((st = sd_cand_grid_coords(w))) return st;
    }
#endif
    RB_STAGE(SD_RB_FILL);

    /* the candidates: the bodies in K chunks, scanned by T threads, joined in chunk order */
    w->bb.n = 0;
    w->bb.nh = 0;
    w->bt.n = 0;
    w->bt.nh = 0;
    if (sd_grow((void **)&w->csr.bt_start, &w->csr.cap_bt_start, b->n + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    {
        const int T = rebuild_threads(w, b->n);
        /* (32 chunks a thread: the scan's cost per body varies along the flume, a log jam at
         * the dam, and the last chunks taken were waited for) */
        const int K = T > 1 ? 32 * T : 1;
        st = sd_cand_scan(w, hm, K, T);
        RB_STAGE(SD_RB_SCAN);
        if (!st) st = sd_cand_join(w, K, T);
        if (st) return st;
    }
    RB_STAGE(SD_RB_JOIN);

    set_effective_masses(w);
    RB_STAGE(SD_RB_MASSES);
    if ((st = sd_history_restore(w, fresh && w->old_n_bodies == b->n))) return st;
    RB_STAGE(SD_RB_RESTORE);

    if (sd_grow((void **)&w->bt_man, &w->bt_man_cap, w->bt.n + 1, sizeof(sd_manifold))) return SD_ERR_NOMEM;

    /* the references of the moves (a bed taken from its cache was not reordered and has not
     * moved: its references still hold) */
#pragma omp parallel for num_threads(w->nthreads) schedule(static) if (nr > w->def.parallel_min)
    for (int i = 0; i < nr; i++) {
        b->pos_ref[i] = b->pos[i];
        b->axis_ref[i] = b->axis[i];
    }
    w->last_rebuild_time = w->time;
    w->need_rebuild = 0;
    w->ref_drift = 0.0;
    w->timers.rebuilds++;
    w->mov_stamp = w->timers.rebuilds; /* made after the sort above */
    RB_STAGE(SD_RB_REFS);
    return SD_OK;
}
#undef RB_STAGE

sd_status sd_neighbor_moving_update(sd_world *w)
{
    const sd_bodies *b = &w->b;
    if (w->mov_stamp == w->timers.rebuilds && w->mov_bn == b->n && w->mov) return SD_OK;
    if (sd_grow((void **)&w->mov, &w->mov_cap, b->n + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    int m = 0;
    for (int i = 0; i < b->n; i++) {
        w->mov[m] = i;
        m += !b->fixed[i] && !sd_body_is_ghost(w, i); /* (a ghost's owner moves it) */
    }
    w->mov_n = m;
    w->mov_bn = b->n;
    w->mov_stamp = w->timers.rebuilds;
    return SD_OK;
}
