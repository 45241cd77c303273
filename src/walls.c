/* Static triangle walls and the welding that gives shared edges and vertices one id, so that
 * a sphere touching a mesh at a shared edge gets one contact, not two (see contact.c). */
#include <stdlib.h>
#include <string.h>

#include "world_internal.h"

sd_status sd_walls_reserve(sd_walls *w, int cap)
{
    if (cap <= w->cap) return SD_OK;
    int nc = w->cap > 0 ? w->cap : 64;
    while (nc < cap)
        nc *= 2;
    void *p;
#define SD_GROW(field)                                                                                                 \
    p = realloc(w->field, (size_t)nc * sizeof(*w->field));                                                             \
    if (!p) return SD_ERR_NOMEM;                                                                                       \
    w->field = p;
    SD_GROW(tri)
    SD_GROW(group)
    SD_GROW(active)
    SD_GROW(mat)
    SD_GROW(edge_id)
    SD_GROW(vert_id)
    SD_GROW(force)
    SD_GROW(edges)
#undef SD_GROW
    p = realloc(w->edge_vert, (size_t)nc * 3 * sizeof(*w->edge_vert));
    if (!p) return SD_ERR_NOMEM;
    w->edge_vert = p;
    w->cap = nc;
    return SD_OK;
}

void sd_walls_free(sd_walls *w)
{
    free(w->tri);
    free(w->group);
    free(w->active);
    free(w->mat);
    free(w->edge_id);
    free(w->vert_id);
    free(w->edge_vert);
    free(w->edge_flat);
    free(w->force);
    free(w->edges);
    memset(w, 0, sizeof(*w));
}

typedef struct {
    int64_t k[3];
    int idx;
} vkey;

static int cmp_vkey(const void *pa, const void *pb)
{
    const vkey *a = pa, *b = pb;
    for (int d = 0; d < 3; d++) {
        if (a->k[d] != b->k[d]) return a->k[d] < b->k[d] ? -1 : 1;
    }
    return a->idx - b->idx;
}

typedef struct {
    int32_t lo, hi;
    int idx;
} ekey;

static int cmp_ekey(const void *pa, const void *pb)
{
    const ekey *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return a->idx - b->idx;
}

/* Vertices closer than 1 µm (rounded to a 1 µm lattice) are the same vertex. */
sd_status sd_walls_weld(sd_walls *w)
{
    int nv = 3 * w->n;
    vkey *vk = malloc((size_t)(nv > 0 ? nv : 1) * sizeof(*vk));
    ekey *ek = malloc((size_t)(nv > 0 ? nv : 1) * sizeof(*ek));
    if (!vk || !ek) {
        free(vk);
        free(ek);
        return SD_ERR_NOMEM;
    }
    const double q = 1e6;
    for (int t = 0; t < w->n; t++)
        sd_tri_edges_init(&w->edges[t], &w->tri[t]);
    for (int t = 0; t < w->n; t++)
        for (int k = 0; k < 3; k++) {
            sd_vec3 v = w->tri[t].v[k];
            vk[3 * t + k].k[0] = llround(v.x * q);
            vk[3 * t + k].k[1] = llround(v.y * q);
            vk[3 * t + k].k[2] = llround(v.z * q);
            vk[3 * t + k].idx = 3 * t + k;
        }
    qsort(vk, (size_t)nv, sizeof(*vk), cmp_vkey);
    int id = -1;
    for (int i = 0; i < nv; i++) {
        if (i == 0 || cmp_vkey(&(vkey){{vk[i].k[0], vk[i].k[1], vk[i].k[2]}, 0},
                               &(vkey){{vk[i - 1].k[0], vk[i - 1].k[1], vk[i - 1].k[2]}, 0}) != 0)
            id++;
        w->vert_id[vk[i].idx / 3][vk[i].idx % 3] = id;
    }
    w->n_verts = id + 1;
    for (int t = 0; t < w->n; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = w->vert_id[t][k], b = w->vert_id[t][(k + 1) % 3];
            ek[3 * t + k].lo = a < b ? a : b;
            ek[3 * t + k].hi = a < b ? b : a;
            ek[3 * t + k].idx = 3 * t + k;
        }
    qsort(ek, (size_t)nv, sizeof(*ek), cmp_ekey);
    id = -1;
    for (int i = 0; i < nv; i++) {
        if (i == 0 || ek[i].lo != ek[i - 1].lo || ek[i].hi != ek[i - 1].hi) {
            id++;
            w->edge_vert[id][0] = ek[i].lo;
            w->edge_vert[id][1] = ek[i].hi;
        }
        w->edge_id[ek[i].idx / 3][ek[i].idx % 3] = id;
    }
    w->n_edges = id + 1;
    /* seams: an edge with exactly two triangles whose planes coincide */
    uint8_t *flat = realloc(w->edge_flat, (size_t)(w->n_edges + 1));
    int32_t *first = malloc((size_t)(w->n_edges + 1) * sizeof(int32_t));
    int8_t *cnt = calloc((size_t)(w->n_edges + 1), 1);
    if (!flat || !first || !cnt) {
        if (flat) w->edge_flat = flat;
        free(first);
        free(cnt);
        free(vk);
        free(ek);
        return SD_ERR_NOMEM;
    }
    w->edge_flat = flat;
    for (int e = 0; e < w->n_edges; e++)
        flat[e] = 0;
    for (int t = 0; t < w->n; t++)
        for (int k = 0; k < 3; k++) {
            int e = w->edge_id[t][k];
            if (cnt[e] == 0)
                first[e] = t;
            else if (cnt[e] == 1)
                flat[e] = fabs(v3_dot(w->tri[first[e]].n, w->tri[t].n)) > 1.0 - 1e-9;
            else
                flat[e] = 0;
            if (cnt[e] < 3) cnt[e]++;
        }
    free(first);
    free(cnt);
    free(vk);
    free(ek);
    return SD_OK;
}
