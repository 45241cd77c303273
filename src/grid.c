/* The candidate search's uniform cell grids (neighbor.c drives them): a grid's layout over a
 * box, its fill from each item's cell range (one thread or several, the same grid entry for
 * entry), the entries' flag bytes, and the triangle grid. */
#include <stdlib.h>
#include <string.h>

#include "neighbor_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

void sd_grid_free(sd_grid *g)
{
    free(g->cell_start);
    free(g->items);
    memset(g, 0, sizeof(*g));
}

static void tri_box(const sd_tri *t, double half_margin, sd_vec3 *lo, sd_vec3 *hi)
{
    sd_vec3 l = t->v[0], h = t->v[0];
    for (int k = 1; k < 3; k++) {
        l = v3(fmin(l.x, t->v[k].x), fmin(l.y, t->v[k].y), fmin(l.z, t->v[k].z));
        h = v3(fmax(h.x, t->v[k].x), fmax(h.y, t->v[k].y), fmax(h.z, t->v[k].z));
    }
    *lo = v3_sub(l, v3(half_margin, half_margin, half_margin));
    *hi = v3_add(h, v3(half_margin, half_margin, half_margin));
}

/* The grid's origin on one axis: the anchor less whole cells, as few as cover lo. */
static double snap_origin(double lo, double anchor, double cell)
{
    return lo >= anchor ? anchor : anchor - ceil((anchor - lo) / cell) * cell;
}

/* Size the grid over [lo, hi] with cells of at least `cell`, enlarged if the count would
 * exceed max_cells (an element flung far away must not make the grid explode).
 * With an anchor (the low corner of the bed's boxes, which never move), the origin is the
 * anchor less whole cells: bodies moving about near the low faces of the box (the flow along
 * the side walls) no longer shift every cell of the grid by micrometres at each rebuild, and
 * the bed keeps its cells (the bed cache). */
sd_status sd_grid_layout(sd_grid *g, sd_vec3 lo, sd_vec3 hi, double cell, long max_cells, const sd_vec3 *anchor)
{
    sd_vec3 ext = v3_sub(hi, lo);
    /* a body flung to infinity (or NaN) would make the grid unbounded: report the blow-up */
    if (!(isfinite(ext.x) && isfinite(ext.y) && isfinite(ext.z)) || !(cell > 0.0) || !isfinite(cell))
        return SD_ERR_NONFINITE;
    const sd_vec3 lo0 = lo;
    for (;;) {
        if (anchor) {
            lo = v3(snap_origin(lo0.x, anchor->x, cell), snap_origin(lo0.y, anchor->y, cell),
                    snap_origin(lo0.z, anchor->z, cell));
            ext = v3_sub(hi, lo);
        }
        double nx = floor(ext.x / cell) + 1, ny = floor(ext.y / cell) + 1, nz = floor(ext.z / cell) + 1;
        if (nx * ny * nz <= (double)max_cells) {
            g->nx = (int)nx;
            g->ny = (int)ny;
            g->nz = (int)nz;
            break;
        }
        cell *= 1.5;
    }
    g->cell = cell;
    g->lo = lo;
    int ncell = g->nx * g->ny * g->nz;
    if (sd_grow((void **)&g->cell_start, &g->cap_cells, ncell + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    memset(g->cell_start, 0, (size_t)(ncell + 1) * sizeof(int32_t));
    return SD_OK;
}

/* A grid laid out as given (a fixed grid, decomp.c): origin lo, cells of `cell`, nx x ny x nz. */
sd_status sd_grid_layout_fixed(sd_grid *g, sd_vec3 lo, double cell, int nx, int ny, int nz)
{
    g->cell = cell;
    g->lo = lo;
    g->nx = nx, g->ny = ny, g->nz = nz;
    const int ncell = nx * ny * nz;
    if (sd_grow((void **)&g->cell_start, &g->cap_cells, ncell + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    memset(g->cell_start, 0, (size_t)(ncell + 1) * sizeof(int32_t));
    return SD_OK;
}

/* Counting sort of items into cells given each item's range. With reg0 and slot: item i's
 * entries are reg0[i] .. reg0[i+1]-1 in the order z, y, x of its range, and slot[r] is where
 * entry r went in items (so the items after it in that cell are exactly those above i). */
sd_status sd_grid_fill(sd_grid *g, int n, const int32_t (*range)[6], const uint8_t *skip, int32_t *reg0, int32_t **slot,
                       int *slot_cap, uint8_t **flag, int *flag_cap, const sd_bed_cache *bed)
{
    int ncell = g->nx * g->ny * g->nz;
    long total = 0;
    /* with the bed's cache, bodies nd .. n-1 (the bed) go in from its lists, after the others
     * in each cell as their higher indices put them (no entry of theirs in reg0 / slot: the
     * scans never start from the bed) */
    const int nd = bed ? bed->nb0 : n;
    for (int i = 0; i < nd; i++) {
        if (reg0) reg0[i] = (int32_t)total;
        if (skip && skip[i]) continue;
        const int32_t *r = range[i];
        for (int z = r[2]; z <= r[5]; z++)
            for (int y = r[1]; y <= r[4]; y++)
                for (int x = r[0]; x <= r[3]; x++)
                    g->cell_start[(z * g->ny + y) * g->nx + x + 1]++;
        total += (long)(r[3] - r[0] + 1) * (r[4] - r[1] + 1) * (r[5] - r[2] + 1);
    }
    if (reg0)
        for (int i = nd; i <= n; i++)
            reg0[i] = (int32_t)total;
    if (bed)
        for (int q = 0; q < bed->ncells; q++)
            g->cell_start[bed->cells[q] + 1] += bed->off[q + 1] - bed->off[q];
    for (int c = 0; c < ncell; c++)
        g->cell_start[c + 1] += g->cell_start[c];
    const long all = total + (bed ? bed->nitems : 0);
    if (sd_grow((void **)&g->items, &g->cap_items, (int)all + SD_GRID_PAD, sizeof(int32_t))) return SD_ERR_NOMEM;
    if (slot && sd_grow((void **)slot, slot_cap, (int)total + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    if (flag && sd_grow((void **)flag, flag_cap, (int)all + SD_GRID_PAD, sizeof(uint8_t))) return SD_ERR_NOMEM;
    uint8_t *fl = flag ? *flag : NULL;
    /* fill using cell_start as a cursor, then shift back */
    int32_t *sl = slot ? *slot : NULL;
    long e = 0;
    for (int i = 0; i < nd; i++) {
        if (skip && skip[i]) continue;
        const int32_t *r = range[i];
        for (int z = r[2]; z <= r[5]; z++)
            for (int y = r[1]; y <= r[4]; y++)
                for (int x = r[0]; x <= r[3]; x++) {
                    const int at = g->cell_start[(z * g->ny + y) * g->nx + x]++;
                    g->items[at] = i;
                    if (sl) sl[e++] = at;
                    if (fl) fl[at] = range_begins(r, x, y, z);
                }
    }
    if (bed)
        for (int q = 0; q < bed->ncells; q++) {
            const int c = bed->cells[q], m = bed->off[q + 1] - bed->off[q];
            memcpy(g->items + g->cell_start[c], bed->items + bed->off[q], (size_t)m * sizeof(int32_t));
            if (fl) memcpy(fl + g->cell_start[c], bed->flags + bed->off[q], (size_t)m);
            g->cell_start[c] += m;
        }
    for (int c = ncell; c > 0; c--)
        g->cell_start[c] = g->cell_start[c - 1];
    g->cell_start[0] = 0;
    return SD_OK;
}

#ifdef _OPENMP
/* sd_grid_fill of the body grid (reg0, slot and flags made) by T threads: the same grid, entry
 * for entry. The bodies before the bed are cut into T runs; each thread counts its run's
 * entries per cell, the cells' starts and each run's place in each cell follow (serial, over
 * the cells), then each thread places its run (a cell lists its bodies ascending: lower runs
 * first) and the bed's cached lists go in after them. */
sd_status sd_grid_fill_par(sd_grid *g, int n, const int32_t (*range)[6], int32_t *reg0, int32_t **slot, int *slot_cap,
                           uint8_t **flag, int *flag_cap, const sd_bed_cache *bed, int T)
{
    const int ncell = g->nx * g->ny * g->nz;
    const int nd = bed ? bed->nb0 : n;
    /* cur[t * (ncell + 1) + c]: run t's entries in cell c, then its cursor there; cur[T * ..]
     * the bed's count per cell */
    int32_t *cur = malloc(((size_t)T + 1) * ((size_t)ncell + 1) * sizeof(int32_t));
    long tot[SD_MAX_OWNERS + 1];
    if (!cur) return SD_ERR_NOMEM;
    int32_t *bedc = cur + (size_t)T * (ncell + 1);
    memset(bedc, 0, ((size_t)ncell + 1) * sizeof(int32_t));
    if (bed)
        for (int q = 0; q < bed->ncells; q++)
            bedc[bed->cells[q]] = bed->off[q + 1] - bed->off[q];
#pragma omp parallel num_threads(T)
    {
        const int nthr = omp_get_num_threads();
        for (int t = omp_get_thread_num(); t < T; t += nthr) {
            int32_t *cnt = cur + (size_t)t * (ncell + 1);
            memset(cnt, 0, ((size_t)ncell + 1) * sizeof(int32_t));
            const int i0 = (int)((long)nd * t / T), i1 = (int)((long)nd * (t + 1) / T);
            long e = 0;
            for (int i = i0; i < i1; i++) {
                const int32_t *r = range[i];
                for (int z = r[2]; z <= r[5]; z++)
                    for (int y = r[1]; y <= r[4]; y++)
                        for (int x = r[0]; x <= r[3]; x++)
                            cnt[(z * g->ny + y) * g->nx + x]++;
                e += (long)(r[3] - r[0] + 1) * (r[4] - r[1] + 1) * (r[5] - r[2] + 1);
            }
            tot[t] = e;
        }
    }
    long total = 0;
    for (int t = 0; t < T; t++) {
        const long e = tot[t];
        tot[t] = total;
        total += e;
    }
    /* the cells' starts; each run's cursor in each cell; the bed's place (in bedc) */
    int32_t at = 0;
    for (int c = 0; c < ncell; c++) {
        g->cell_start[c] = at;
        for (int t = 0; t < T; t++) {
            int32_t *q = cur + (size_t)t * (ncell + 1) + c;
            const int32_t m = *q;
            *q = at;
            at += m;
        }
        const int32_t m = bedc[c];
        bedc[c] = at;
        at += m;
    }
    g->cell_start[ncell] = at;
    const long all = at;
    if (sd_grow((void **)&g->items, &g->cap_items, (int)all + SD_GRID_PAD, sizeof(int32_t)) ||
        sd_grow((void **)slot, slot_cap, (int)total + 1, sizeof(int32_t)) ||
        sd_grow((void **)flag, flag_cap, (int)all + SD_GRID_PAD, sizeof(uint8_t))) {
        free(cur);
        return SD_ERR_NOMEM;
    }
    uint8_t *fl = *flag;
    int32_t *sl = *slot;
#pragma omp parallel num_threads(T)
    {
        const int nthr = omp_get_num_threads();
        for (int t = omp_get_thread_num(); t < T; t += nthr) {
            int32_t *cnt = cur + (size_t)t * (ncell + 1);
            const int i0 = (int)((long)nd * t / T), i1 = (int)((long)nd * (t + 1) / T);
            long e = tot[t];
            for (int i = i0; i < i1; i++) {
                reg0[i] = (int32_t)e;
                const int32_t *r = range[i];
                for (int z = r[2]; z <= r[5]; z++)
                    for (int y = r[1]; y <= r[4]; y++)
                        for (int x = r[0]; x <= r[3]; x++) {
                            const int a = cnt[(z * g->ny + y) * g->nx + x]++;
                            g->items[a] = i;
                            sl[e++] = a;
                            fl[a] = range_begins(r, x, y, z);
                        }
            }
        }
        /* the bed's lists, cell by cell */
        if (bed) {
#pragma omp for schedule(static)
            for (int q = 0; q < bed->ncells; q++) {
                const int c = bed->cells[q], m = bed->off[q + 1] - bed->off[q];
                memcpy(g->items + bedc[c], bed->items + bed->off[q], (size_t)m * sizeof(int32_t));
                memcpy(fl + bedc[c], bed->flags + bed->off[q], (size_t)m);
            }
        }
    }
    for (int i = nd; i <= n; i++)
        reg0[i] = (int32_t)total;
    free(cur);
    return SD_OK;
}
#endif

/* Each entry's flag byte (range_begins) from the grid's lists and the items' ranges: what the
 * fill writes along with the entries, for a grid whose flags were not kept (a checkpoint keeps
 * the triangle grid, not its flags). flag has room for the grid's entries. */
void sd_grid_flags(const sd_grid *g, const int32_t (*range)[6], uint8_t *flag)
{
    for (int z = 0; z < g->nz; z++)
        for (int y = 0; y < g->ny; y++)
            for (int x = 0; x < g->nx; x++) {
                const int c = (z * g->ny + y) * g->nx + x;
                for (int k = g->cell_start[c]; k < g->cell_start[c + 1]; k++)
                    flag[k] = range_begins(range[g->items[k]], x, y, z);
            }
}

/* The triangle grid remade (the walls changed: a gate opened), with cells of `cell`, its
 * entries' flags and the walls' welding. */
sd_status sd_grid_tri_rebuild(sd_world *w, double cell)
{
    sd_walls *wl = &w->w;
    double hm = 0.5 * w->def.margin;
    sd_vec3 lo = v3(1e300, 1e300, 1e300), hi = v3(-1e300, -1e300, -1e300);
    int any = 0;
    for (int t = 0; t < wl->n; t++) {
        if (!wl->active[t]) continue;
        sd_vec3 l, h;
        tri_box(&wl->tri[t], hm, &l, &h);
        lo = v3(fmin(lo.x, l.x), fmin(lo.y, l.y), fmin(lo.z, l.z));
        hi = v3(fmax(hi.x, h.x), fmax(hi.y, h.y), fmax(hi.z, h.z));
        any = 1;
    }
    if (!any) lo = hi = v3(0, 0, 0);
    sd_status st = sd_grid_layout(&w->tgrid, lo, hi, cell, 2000000, NULL);
    if (st) return st;
    if (sd_grow((void **)&w->trange, &w->trange_cap, wl->n + 1, sizeof(*w->trange))) return SD_ERR_NOMEM;
    for (int t = 0; t < wl->n; t++) {
        sd_vec3 l, h;
        tri_box(&wl->tri[t], hm, &l, &h);
        cell_range(&w->tgrid, l, h, w->trange[t], w->simd);
    }
    uint8_t *skip = malloc((size_t)(wl->n + 1));
    if (!skip) return SD_ERR_NOMEM;
    for (int t = 0; t < wl->n; t++)
        skip[t] = !wl->active[t];
    st = sd_grid_fill(&w->tgrid, wl->n, (const int32_t(*)[6])w->trange, skip, NULL, NULL, NULL, &w->tflag,
                      &w->tflag_cap, NULL);
    free(skip);
    if (st) return st;
    st = sd_walls_weld(wl);
    wl->dirty = 0;
    return st;
}
