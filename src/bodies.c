/* The body store: one array per field, driven by a field table. */
#include <stdlib.h>
#include <string.h>

#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#define SD_BODY_FIELDS(X)                                                                                              \
    X(gid, int32_t)                                                                                                    \
    X(shape, uint8_t)                                                                                                  \
    X(fixed, uint8_t)                                                                                                  \
    X(mat, uint8_t)                                                                                                    \
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
    /* one element past the capacity, zeroed: SIMD code reads a vec3 as a 32-byte row (x, y, z
     * and the next element's first 8 bytes), so the last element must have bytes after it */
    void *q = realloc(*p, (size_t)(g->cap + 1) * elem);
    if (!q) {
        g->failed = 1;
        return;
    }
    memset((char *)q + (size_t)g->cap * elem, 0, elem);
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
    uint64_t w[3];
} blob24;
typedef struct {
    uint64_t w[4];
} blob32;

/* a[i] <- a[perm[i]] for i0 <= i < i1 (a block perm maps onto itself), through the scratch t */
static void permute_array(char *p, size_t elem, const int32_t *perm, int i0, int i1, char *t)
{
    const int n = i1 - i0;
    perm += i0;
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
    memcpy(p + (size_t)i0 * elem, t, (size_t)n * elem);
}

#define SD_MAX_FIELDS 64
typedef struct {
    char *array[SD_MAX_FIELDS];
    size_t elem[SD_MAX_FIELDS];
    int n;
} field_list;

static void list_field(void *array, size_t elem, const char *name, void *ctx)
{
    (void)name;
    field_list *f = ctx;
    if (f->n < SD_MAX_FIELDS) {
        f->array[f->n] = *(char **)array;
        f->elem[f->n] = elem;
    }
    f->n++;
}

/* The end of the block that starts at i0 (perm[i0] != i0): the shortest run from i0 that perm
 * maps onto itself, where the running maximum of perm comes back to the index (bounded by n:
 * perm is one of 0 .. n-1). */
static int block_end(const int32_t *perm, int n, int i0)
{
    int i = i0, hi = perm[i0];
    while (hi != i && i + 1 < n) {
        i++;
        if (perm[i] > hi) hi = perm[i];
    }
    return i + 1;
}

sd_status sd_bodies_permute(sd_bodies *b, const int32_t *perm, int n, int threads)
{
    field_list f = {.n = 0};
    sd_bodies_for_each_field(b, list_field, &f);
    if (f.n > SD_MAX_FIELDS) return SD_ERR_NOMEM;
    /* Only the blocks the permutation moves: a rebuild's sort moves a few bodies a few places
     * each (neighbor.c), so most entries stay, and copying every field whole through an
     * n-long scratch cost 100-280 ms a rebuild at 1e6 bodies, much of it the scratch's fresh
     * pages (performance pass P38, in the git history). */
    int nblk = 0, widest = 0;
    long moved = 0;
    for (int i = 0; i < n;) {
        if (perm[i] == i) {
            i++;
            continue;
        }
        const int i1 = block_end(perm, n, i);
        nblk++;
        moved += i1 - i;
        widest = i1 - i > widest ? i1 - i : widest;
        i = i1;
    }
    if (nblk == 0) return SD_OK;
    int T = 1;
#ifdef _OPENMP
    T = moved > 2000 ? threads : 1;
#else
    (void)threads;
#endif
    /* the blocks (start, end), and one scratch per thread as wide as the widest block and field
     * (a quaternion) */
    int32_t *blk = malloc(2 * (size_t)nblk * sizeof(int32_t));
    char *scratch = malloc((size_t)T * (size_t)(widest + 1) * sizeof(sd_quat));
    if (!blk || !scratch) {
        free(blk);
        free(scratch);
        return SD_ERR_NOMEM;
    }
    for (int i = 0, k = 0; i < n;) {
        if (perm[i] == i) {
            i++;
            continue;
        }
        blk[2 * k] = i;
        blk[2 * k + 1] = i = block_end(perm, n, i);
        k++;
    }
#pragma omp parallel for schedule(dynamic, 1) num_threads(T) if (T > 1)
    for (int q = 0; q < f.n; q++) {
        int tid = 0;
#ifdef _OPENMP
        tid = omp_get_thread_num();
#endif
        char *t = scratch + (size_t)tid * (size_t)(widest + 1) * sizeof(sd_quat);
        for (int j = 0; j < nblk; j++)
            permute_array(f.array[q], f.elem[q], perm, blk[2 * j], blk[2 * j + 1], t);
    }
    free(scratch);
    free(blk);
    return SD_OK;
}

size_t sd_bodies_record_size(void)
{
    size_t n = 0;
#define SD_X_FIELD(name, type) n += sizeof(type);
    SD_BODY_FIELDS(SD_X_FIELD)
#undef SD_X_FIELD
    return n;
}

void sd_bodies_get_record(const sd_bodies *b, int i, void *rec)
{
    char *p = rec;
#define SD_X_FIELD(name, type)                                                                                         \
    memcpy(p, &b->name[i], sizeof(type));                                                                              \
    p += sizeof(type);
    SD_BODY_FIELDS(SD_X_FIELD)
#undef SD_X_FIELD
}

void sd_bodies_set_record(sd_bodies *b, int i, const void *rec)
{
    const char *p = rec;
#define SD_X_FIELD(name, type)                                                                                         \
    memcpy(&b->name[i], p, sizeof(type));                                                                              \
    p += sizeof(type);
    SD_BODY_FIELDS(SD_X_FIELD)
#undef SD_X_FIELD
}

size_t sd_bodies_record_offset(const char *field)
{
    size_t n = 0;
#define SD_X_FIELD(name, type)                                                                                         \
    if (strcmp(field, #name) == 0) return n;                                                                           \
    n += sizeof(type);
    SD_BODY_FIELDS(SD_X_FIELD)
#undef SD_X_FIELD
    return (size_t)-1;
}
