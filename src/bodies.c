/* The body store: one array per field, driven by a field table. */
#include <stdlib.h>
#include <string.h>

#include "world_internal.h"

#define SD_BODY_FIELDS(X)                                                                                              \
    X(gid, int32_t)                                                                                                    \
    X(shape, uint8_t)                                                                                                  \
    X(fixed, uint8_t)                                                                                                  \
    X(tag, int32_t)                                                                                                    \
    X(pos, sd_vec3)                                                                                                    \
    X(vel, sd_vec3)                                                                                                    \
    X(omega, sd_vec3)                                                                                                  \
    X(angmom, sd_vec3)                                                                                                 \
    X(quat, sd_quat)                                                                                                   \
    X(axis, sd_vec3)                                                                                                   \
    X(force, sd_vec3)                                                                                                  \
    X(torque, sd_vec3)                                                                                                 \
    X(ext_force, sd_vec3)                                                                                              \
    X(pos_ref, sd_vec3)                                                                                                \
    X(axis_ref, sd_vec3)                                                                                               \
    X(radius, double)                                                                                                  \
    X(hl, double)                                                                                                      \
    X(mass, double)                                                                                                    \
    X(inv_mass, double)                                                                                                \
    X(inv_i_ax, double)                                                                                                \
    X(inv_i_tr, double)                                                                                                \
    X(bound_r, double)

void sd_bodies_for_each_field(sd_bodies *b, sd_field_fn fn, void *ctx)
{
#define SD_X_FIELD(name, type) fn((void *)&b->name, sizeof(type), #name, ctx);
    SD_BODY_FIELDS(SD_X_FIELD)
#undef SD_X_FIELD
}

typedef struct {
    int cap;
    int failed;
} grow_ctx;

static void grow_field(void *array, size_t elem, const char *name, void *ctx)
{
    (void)name;
    grow_ctx *g = ctx;
    void **p = array;
    if (g->failed) return;
    void *q = realloc(*p, (size_t)g->cap * elem);
    if (!q) {
        g->failed = 1;
        return;
    }
    *p = q;
}

sd_status sd_bodies_reserve(sd_bodies *b, int cap)
{
    if (cap <= b->cap) return SD_OK;
    int nc = b->cap > 0 ? b->cap : 64;
    while (nc < cap)
        nc *= 2;
    grow_ctx g = {nc, 0};
    sd_bodies_for_each_field(b, grow_field, &g);
    if (g.failed) return SD_ERR_NOMEM;
    b->cap = nc;
    return SD_OK;
}

static void free_field(void *array, size_t elem, const char *name, void *ctx)
{
    (void)elem;
    (void)name;
    (void)ctx;
    void **p = array;
    free(*p);
    *p = NULL;
}

void sd_bodies_free(sd_bodies *b)
{
    sd_bodies_for_each_field(b, free_field, NULL);
    b->n = b->cap = 0;
}

typedef struct {
    int dst, src;
} move_ctx;

static void move_field(void *array, size_t elem, const char *name, void *ctx)
{
    (void)name;
    move_ctx *m = ctx;
    char *p = *(char **)array;
    memcpy(p + (size_t)m->dst * elem, p + (size_t)m->src * elem, elem);
}

void sd_bodies_swap_remove(sd_bodies *b, int i)
{
    int last = b->n - 1;
    if (i != last) {
        move_ctx m = {i, last};
        sd_bodies_for_each_field(b, move_field, &m);
    }
    b->n--;
}

typedef struct {
    const int32_t *perm; /* new index -> old index */
    int n;
    void *scratch;
} permute_ctx;

typedef struct {
    uint64_t w[3];
} blob24;
typedef struct {
    uint64_t w[4];
} blob32;

static void permute_field(void *array, size_t elem, const char *name, void *ctx)
{
    (void)name;
    permute_ctx *pc = ctx;
    char *p = *(char **)array, *t = pc->scratch;
    const int32_t *perm = pc->perm;
    const int n = pc->n;
    /* typed copies for the sizes the store has (a memcpy call per element was most of the
     * permutation at every rebuild) */
    switch (elem) {
    case 1:
        for (int i = 0; i < n; i++)
            ((uint8_t *)t)[i] = ((const uint8_t *)p)[perm[i]];
        break;
    case 4:
        for (int i = 0; i < n; i++)
            ((int32_t *)t)[i] = ((const int32_t *)p)[perm[i]];
        break;
    case 8:
        for (int i = 0; i < n; i++)
            ((uint64_t *)t)[i] = ((const uint64_t *)p)[perm[i]];
        break;
    case 24:
        for (int i = 0; i < n; i++)
            ((blob24 *)t)[i] = ((const blob24 *)p)[perm[i]];
        break;
    case 32:
        for (int i = 0; i < n; i++)
            ((blob32 *)t)[i] = ((const blob32 *)p)[perm[i]];
        break;
    default:
        for (int i = 0; i < n; i++)
            memcpy(t + (size_t)i * elem, p + (size_t)perm[i] * elem, elem);
    }
    memcpy(p, t, (size_t)n * elem);
}

sd_status sd_bodies_permute(sd_bodies *b, const int32_t *perm)
{
    /* the widest field is a quaternion */
    void *scratch = malloc((size_t)(b->n + 1) * sizeof(sd_quat));
    if (!scratch) return SD_ERR_NOMEM;
    permute_ctx pc = {perm, b->n, scratch};
    sd_bodies_for_each_field(b, permute_field, &pc);
    free(scratch);
    return SD_OK;
}
