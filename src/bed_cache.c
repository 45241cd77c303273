/* The bed roughness's cache: the fixed bed's boxes, cell ranges and grid entries as the last
 * full rebuild made them, taken again while no body came or went and the body grid keeps its
 * layout (the same bits, without the bed's half of the work). */
#include <stdlib.h>
#include <string.h>

#include "neighbor_internal.h"

void sd_bed_cache_free(sd_bed_cache *c)
{
    free(c->range);
    free(c->cells);
    free(c->off);
    free(c->items);
    free(c->flags);
    memset(c, 0, sizeof(*c));
}

/* The bed's cache still holds for the grid just laid out: the same origin, cells and columns
 * (its ranges and its centres' cells come out the same), the bed below the top layer (nz may
 * change: the bed's ranges do not reach it). */
int sd_bed_cache_fits(const sd_bed_cache *c, const sd_grid *g)
{
    return g->cell == c->cell && g->nx == c->nx && g->ny == c->ny && g->lo.x == c->lo.x && g->lo.y == c->lo.y &&
           g->lo.z == c->lo.z && c->ztop < g->nz - 1;
}

/* The bed cache from the grid just laid out and filled (w->range current): the trailing bed
 * nb0 .. n-1, if every body before it is not bed (what the sort leaves: otherwise no cache). */
sd_status sd_bed_cache_make(sd_world *w, double hm)
{
    const sd_bodies *b = &w->b;
    const sd_grid *g = &w->grid;
    sd_bed_cache *c = &w->bed;
    c->made = 0;
    const int nb0 = sd_bed_start(b);
    if (nb0 == b->n) return SD_OK;
    for (int i = 0; i < nb0; i++)
        if (sd_body_is_bed(b, i)) return SD_OK;
    const int nbed = b->n - nb0;
    sd_vec3 blo = v3(1e300, 1e300, 1e300), bhi = v3(-1e300, -1e300, -1e300);
    int zmax = 0;
    long nitems = 0;
    for (int i = nb0; i < b->n; i++) {
        sd_vec3 l, h;
        body_box(b, i, hm, &l, &h);
        blo = v3(fmin(blo.x, l.x), fmin(blo.y, l.y), fmin(blo.z, l.z));
        bhi = v3(fmax(bhi.x, h.x), fmax(bhi.y, h.y), fmax(bhi.z, h.z));
        const int32_t *r = w->range[i];
        zmax = r[5] > zmax ? r[5] : zmax; /* (the centre's layer, its place in the sort, is within) */
        nitems += (long)(r[3] - r[0] + 1) * (r[4] - r[1] + 1) * (r[5] - r[2] + 1);
    }
    /* the bed's cells: counted over the layers it reaches, then listed ascending */
    if (zmax >= g->nz - 1) return SD_OK; /* the bed reaches the top layer: its ranges depend on nz */
    const int nc = g->nx * g->ny * (zmax + 1);
    int32_t *cnt = calloc((size_t)nc + 1, sizeof(int32_t));
    void *range = realloc(c->range, (size_t)nbed * sizeof(*c->range));
    if (range) c->range = range;
    if (!cnt || !range) {
        free(cnt);
        return SD_ERR_NOMEM;
    }
    memcpy(c->range, w->range + nb0, (size_t)nbed * sizeof(*c->range));
    for (int i = nb0; i < b->n; i++) {
        const int32_t *r = w->range[i];
        for (int z = r[2]; z <= r[5]; z++)
            for (int y = r[1]; y <= r[4]; y++)
                for (int x = r[0]; x <= r[3]; x++)
                    cnt[(z * g->ny + y) * g->nx + x]++;
    }
    int ncells = 0;
    for (int q = 0; q < nc; q++)
        ncells += cnt[q] > 0;
    void *cells = realloc(c->cells, (size_t)(ncells + 1) * sizeof(int32_t));
    if (cells) c->cells = cells;
    void *off = realloc(c->off, (size_t)(ncells + 2) * sizeof(int32_t));
    if (off) c->off = off;
    void *items = realloc(c->items, (size_t)(nitems + 1) * sizeof(int32_t));
    if (items) c->items = items;
    void *flags = realloc(c->flags, (size_t)(nitems + 1));
    if (flags) c->flags = flags;
    if (!cells || !off || !items || !flags) {
        free(cnt);
        return SD_ERR_NOMEM;
    }
    /* cnt becomes each cell's cursor into items */
    int k = 0, at = 0;
    for (int q = 0; q < nc; q++) {
        if (!cnt[q]) continue;
        c->cells[k] = q;
        c->off[k] = at;
        at += cnt[q];
        cnt[q] = c->off[k++];
    }
    c->off[k] = at;
    for (int i = nb0; i < b->n; i++) {
        const int32_t *r = w->range[i];
        for (int z = r[2]; z <= r[5]; z++)
            for (int y = r[1]; y <= r[4]; y++)
                for (int x = r[0]; x <= r[3]; x++) {
                    const int e = cnt[(z * g->ny + y) * g->nx + x]++;
                    c->items[e] = i;
                    c->flags[e] = range_begins(r, x, y, z);
                }
    }
    free(cnt);
    c->ncells = ncells;
    c->nitems = (int)nitems;
    c->blo = blo;
    c->bhi = bhi;
    c->lo = g->lo;
    c->ztop = zmax;
    c->cell = g->cell;
    c->nx = g->nx;
    c->ny = g->ny;
    c->n = b->n;
    c->nb0 = nb0;
    c->version = w->body_version;
    c->made = 1;
    return SD_OK;
}
