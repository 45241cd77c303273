/* Checkpoint and restart (layout and guarantees in io_checkpoint.h). */
#include "io_checkpoint.h"

#include <errno.h>
#include <float.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/binio.h"
#include "core/hash.h"
#include "world_internal.h"

/* The file stores these structures field by field or as arrays of doubles; a new field in any
 * of them must be added to the checkpoint (and SD_CHECKPOINT_VERSION bumped): these
 * assertions fail the build until then. Only checked on the LP64 targets the sizes were taken
 * on. */
#if defined(__x86_64__) || defined(__aarch64__)
/* the world's state: the fields before its first field of scratch (world_internal.h) */
_Static_assert(offsetof(struct sd_world, nthreads) == 11296, "the world's state changed: update io_checkpoint.c");
_Static_assert(sizeof(sd_world_def) == 120, "sd_world_def changed: update io_checkpoint.c (its tuning is not saved)");
/* sd_walls: its edge ids, seams and edge lines are derived (sd_walls_weld, again on load) */
_Static_assert(sizeof(sd_walls) == 104, "sd_walls changed: update io_checkpoint.c");
_Static_assert(sizeof(sd_pairlist) == 56, "sd_pairlist changed: update io_checkpoint.c");
_Static_assert(sizeof(sd_pair) == 24, "sd_pair changed: update io_checkpoint.c");
_Static_assert(sizeof(sd_hist) == 32, "sd_hist changed: update io_checkpoint.c");
_Static_assert(sizeof(sd_grid) == 72, "sd_grid changed: update io_checkpoint.c");
_Static_assert(sizeof(sd_world_timers) == 40, "sd_world_timers changed: update io_checkpoint.c");
#endif
_Static_assert(sizeof(double) == 8, "double must be IEEE-754 binary64");
_Static_assert(sizeof(sd_vec3) == 3 * sizeof(double), "sd_vec3 must be three packed doubles");
_Static_assert(sizeof(sd_quat) == 4 * sizeof(double), "sd_quat must be four packed doubles");
_Static_assert(sizeof(sd_tri) == 4 * sizeof(sd_vec3), "sd_tri must be four packed vectors");

#define HEADER_SIZE 64
static const char magic[8] = {'S', 'A', 'B', 'O', 'D', 'E', 'M', 'C'};
static const uint32_t endian_tag = 0x01020304u;
static const double probe = -1.5;
static const uint8_t type_sizes[8] = {
    sizeof(double), sizeof(sd_vec3), sizeof(sd_quat), sizeof(int32_t), sizeof(int64_t), sizeof(sd_tri), 0, 0};


/* ---------------------------------------------------------------- writing ---- */

/* The payload goes through an sd_bin writer whose sink writes to the file and keeps the running
 * checksum; the sections are streamed, not assembled in memory, so a checkpoint costs no
 * second copy of the state. */
typedef struct {
    FILE *f;
    uint64_t hash;        /* of the payload so far */
    uint64_t len;         /* payload bytes so far */
    long long fail_after; /* the tests' full disk (sd_checkpoint_write_capped), -1 none */
} file_sink;

static int to_file(void *ctx, const void *p, size_t n)
{
    file_sink *fs = ctx;
    if (fs->fail_after >= 0 && (unsigned long long)HEADER_SIZE + fs->len + n > (unsigned long long)fs->fail_after) {
        /* injected failure: write what fits, then fail as a full disk does */
        long long room = fs->fail_after - HEADER_SIZE - (long long)fs->len;
        if (room > 0) (void)fwrite(p, 1, (size_t)room, fs->f);
        return ENOSPC;
    }
    if (fwrite(p, 1, n, fs->f) != n) return errno ? errno : EIO;
    fs->hash = sd_hash_bytes(fs->hash, p, n);
    fs->len += n;
    return 0;
}

/* sizing a section: its bytes are only counted */
static int to_nothing(void *ctx, const void *p, size_t n)
{
    (void)ctx;
    (void)p;
    (void)n;
    return 0;
}

typedef void (*section_fn)(sd_bin_writer *wr, const sd_world *w, const void *ctx);

/* A section: tag, zero, content length (found by a counting pass), content. */
static void section(sd_bin_writer *wr, const char tag[4], section_fn fn, const sd_world *w, const void *ctx)
{
    sd_bin_writer cnt;
    sd_bin_writer_init_sink(&cnt, to_nothing, NULL);
    fn(&cnt, w, ctx);
    sd_bin_put(wr, tag, 4);
    sd_bin_put_i32(wr, 0);
    sd_bin_put_u64(wr, (uint64_t)cnt.n);
    size_t before = wr->n;
    fn(wr, w, ctx);
    if (!wr->err && wr->n - before != cnt.n) wr->err = EIO; /* cannot happen: same function */
}

/* the pairs of materials with springs of their own: a <= b, each with its five constants */
static void sec_matl(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    int n = 0;
    for (int a = 0; a < SD_MATERIALS_MAX; a++)
        for (int b = a; b < SD_MATERIALS_MAX; b++)
            n += w->mat_set[sd_mat_pair(a, b)];
    sd_bin_put_i32(wr, n);
    for (int a = 0; a < SD_MATERIALS_MAX; a++)
        for (int b = a; b < SD_MATERIALS_MAX; b++) {
            const int k = sd_mat_pair(a, b);
            if (!w->mat_set[k]) continue;
            const sd_contact_def *c = &w->mat_pair[k];
            sd_bin_put_i32(wr, a);
            sd_bin_put_i32(wr, b);
            sd_bin_put_f64(wr, c->k_n);
            sd_bin_put_f64(wr, c->k_s);
            sd_bin_put_f64(wr, c->damping);
            sd_bin_put_f64(wr, c->tan_phi);
            sd_bin_put_f64(wr, c->cohesion);
        }
}

static void sec_def(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    const sd_world_def *d = &w->def;
    sd_bin_put_vec3(wr, d->gravity);
    sd_bin_put_f64(wr, d->dt);
    sd_bin_put_f64(wr, d->margin);
    sd_bin_put_f64(wr, d->t_reset);
    sd_bin_put_f64(wr, d->contact.k_n);
    sd_bin_put_f64(wr, d->contact.k_s);
    sd_bin_put_f64(wr, d->contact.damping);
    sd_bin_put_f64(wr, d->contact.tan_phi);
    sd_bin_put_f64(wr, d->contact.cohesion);
    sd_bin_put_i32(wr, d->threads);
    sd_bin_put_i32(wr, d->parallel_min);
    sd_bin_put_i32(wr, d->check_dt);
}

typedef struct {
    sd_bin_writer *wr;
    int n;
    int count;
} field_wctx;

static void count_field(void *array, size_t elem, const char *name, void *ctx)
{
    (void)array;
    (void)elem;
    (void)name;
    ((field_wctx *)ctx)->count++;
}

static void write_field(void *array, size_t elem, const char *name, void *ctx)
{
    field_wctx *fc = ctx;
    size_t len = strlen(name);
    uint8_t l8 = (uint8_t)len;
    sd_bin_put(fc->wr, &l8, 1);
    sd_bin_put(fc->wr, name, len);
    sd_bin_put_i32(fc->wr, (int32_t)elem);
    if (fc->n > 0) sd_bin_put(fc->wr, *(void **)array, (size_t)fc->n * elem);
}

static void sec_body(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    sd_bodies *b = (sd_bodies *)&w->b; /* the field table hands out the arrays; only read here */
    field_wctx fc = {wr, b->n, 0};
    sd_bodies_for_each_field(b, count_field, &fc);
    sd_bin_put_i32(wr, b->n);
    sd_bin_put_i32(wr, fc.count);
    sd_bodies_for_each_field(b, write_field, &fc);
}

static void sec_gids(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    sd_bin_put_i32(wr, w->next_gid);
    if (w->next_gid > 0) sd_bin_put(wr, w->gid_map, (size_t)w->next_gid * sizeof(int32_t));
}

static void sec_wall(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    const sd_walls *wl = &w->w;
    sd_bin_put_i32(wr, wl->n);
    if (wl->n > 0) {
        sd_bin_put(wr, wl->tri, (size_t)wl->n * sizeof(sd_tri));
        sd_bin_put(wr, wl->group, (size_t)wl->n * sizeof(int32_t));
        sd_bin_put(wr, wl->active, (size_t)wl->n);
        sd_bin_put(wr, wl->mat, (size_t)wl->n);
        sd_bin_put(wr, wl->force, (size_t)wl->n * sizeof(sd_vec3));
    }
    sd_bin_put_i32(wr, wl->dirty);
}

/* The triangle grid is current when the walls are not dirty and there are walls; its cell size
 * came from the bodies present when it was built, so it is saved, not recomputed. */
static int tgrid_current(const sd_world *w) { return !w->w.dirty && w->w.n > 0; }

static void sec_tgrid(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    int present = tgrid_current(w);
    sd_bin_put_i32(wr, present);
    if (!present) return;
    const sd_grid *g = &w->tgrid;
    int ncell = g->nx * g->ny * g->nz;
    sd_bin_put_f64(wr, g->cell);
    sd_bin_put_i32(wr, g->nx);
    sd_bin_put_i32(wr, g->ny);
    sd_bin_put_i32(wr, g->nz);
    sd_bin_put_vec3(wr, g->lo);
    sd_bin_put(wr, g->cell_start, (size_t)(ncell + 1) * sizeof(int32_t));
    sd_bin_put_i32(wr, g->cell_start[ncell]);
    sd_bin_put(wr, g->items, (size_t)g->cell_start[ncell] * sizeof(int32_t));
    sd_bin_put(wr, w->trange, (size_t)w->w.n * sizeof(*w->trange));
}

static void sec_pairs(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)w;
    const sd_pairlist *l = ctx;
    sd_bin_put_i32(wr, l->n);
    sd_bin_put_i32(wr, l->nh);
    for (int k = 0; k < l->n; k++) {
        const sd_pair *p = &l->p[k];
        sd_bin_put_i32(wr, p->a);
        sd_bin_put_i32(wr, p->b);
        sd_bin_put_i32(wr, p->off);
        sd_bin_put(wr, &p->cap, sizeof(p->cap));
        sd_bin_put(wr, &p->kind, sizeof(p->kind));
        sd_bin_put_f64(wr, p->sqrt_m_eff);
    }
    for (int k = 0; k < l->nh; k++) {
        /* the shear of an empty slot is never read (and may be uninitialised): write zero */
        /* (a kept separating axis, SD_HIST_SEP_AXIS, is not state: written as an empty slot) */
        int32_t f = l->hist[k].feature;
        sd_bin_put_i32(wr, f >= 0 ? f : -1);
        sd_bin_put_vec3(wr, f >= 0 ? l->hist[k].shear : v3(0.0, 0.0, 0.0));
    }
}

static void sec_oldh(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    sd_bin_put_i32(wr, w->keys_collected);
    sd_bin_put_i32(wr, w->n_old);
    if (w->n_old > 0) sd_bin_put(wr, w->old_keys, (size_t)w->n_old * sizeof(uint64_t));
    for (int k = 0; k < w->n_old; k++) {
        sd_bin_put_i32(wr, w->old_hist[k].feature);
        sd_bin_put_vec3(wr, w->old_hist[k].shear);
    }
}

static void sec_time(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)ctx;
    sd_bin_put_f64(wr, w->time);
    sd_bin_put_i64(wr, w->step);
    sd_bin_put_f64(wr, w->last_rebuild_time);
    sd_bin_put_i32(wr, w->need_rebuild);
    sd_bin_put_i32(wr, w->rebuild_every_step);
    sd_bin_put_i64(wr, w->contacts);
    /* (the format's five timers: moves, rebuild, contacts, a stage since folded into the
     * contact pass, always 0, and checks) */
    sd_bin_put_f64(wr, w->timers.moves);
    sd_bin_put_f64(wr, w->timers.rebuild);
    sd_bin_put_f64(wr, w->timers.contacts);
    sd_bin_put_f64(wr, 0.0);
    sd_bin_put_f64(wr, w->timers.checks);
    sd_bin_put_i64(wr, w->timers.rebuilds);
}

typedef struct {
    const void *p;
    size_t n;
} blob;

static void sec_extra(sd_bin_writer *wr, const sd_world *w, const void *ctx)
{
    (void)w;
    const blob *x = ctx;
    sd_bin_put_u64(wr, (uint64_t)x->n);
    sd_bin_put(wr, x->p, x->n);
}

static void make_header(unsigned char h[HEADER_SIZE], uint64_t plen, uint64_t hash)
{
    uint32_t version = SD_CHECKPOINT_VERSION;
    memset(h, 0, HEADER_SIZE);
    memcpy(h, magic, 8);
    memcpy(h + 8, &version, 4);
    memcpy(h + 12, &endian_tag, 4);
    memcpy(h + 16, type_sizes, 8);
    memcpy(h + 24, &probe, 8);
    memcpy(h + 32, &plen, 8);
    memcpy(h + 40, &hash, 8);
}

/* fsync the directory holding path, so that the rename is durable (best effort). */
static void sync_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    char *dir;
    if (!slash)
        dir = strdup(".");
    else if (slash == path)
        dir = strdup("/");
    else {
        dir = malloc((size_t)(slash - path) + 1);
        if (dir) {
            memcpy(dir, path, (size_t)(slash - path));
            dir[slash - path] = '\0';
        }
    }
    if (!dir) return;
    int fd = open(dir, O_RDONLY);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
    free(dir);
}

sd_status sd_checkpoint_write(const char *path, const sd_world *w, const void *extra, size_t extra_len)
{
    return sd_checkpoint_write_capped(path, w, extra, extra_len, -1);
}

sd_status sd_checkpoint_write_capped(const char *path, const sd_world *w, const void *extra, size_t extra_len,
                                     long long fail_after)
{
    if (fail_after < 0) fail_after = -1;
    if (!path || !*path || !w || (extra_len > 0 && !extra)) return SD_ERR_ARG;
    /* the sphere pairs' springs into bb.hist, where the section reads them (where they are
     * kept, not what they are: the world is const to the caller) */
    sd_near_springs_home((sd_world *)w);
    sd_contact_gather((sd_world *)w); /* the wall loads are a cache, summed when asked for */
    size_t plen = strlen(path);
    char *tmp = malloc(plen + sizeof(".tmp.XXXXXX"));
    if (!tmp) return SD_ERR_NOMEM;
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, ".tmp.XXXXXX", sizeof(".tmp.XXXXXX"));
    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        free(tmp);
        errno = e;
        return SD_ERR_IO;
    }
    (void)fchmod(fd, 0644); /* mkstemp gives 0600 */
    FILE *f = fdopen(fd, "wb");
    if (!f) {
        int e = errno;
        close(fd);
        unlink(tmp);
        free(tmp);
        errno = e;
        return SD_ERR_IO;
    }
    file_sink fs = {f, sd_hash_init(), 0, fail_after};
    sd_bin_writer wr;
    sd_bin_writer_init_sink(&wr, to_file, &fs);
    unsigned char hdr[HEADER_SIZE];
    make_header(hdr, 0, 0); /* placeholder: length and checksum filled in at the end */
    if (fail_after >= 0 && fail_after < HEADER_SIZE)
        wr.err = ENOSPC;
    else if (fwrite(hdr, 1, HEADER_SIZE, f) != HEADER_SIZE)
        wr.err = errno ? errno : EIO;

    blob x = {extra, extra_len};
    section(&wr, "DEF ", sec_def, w, NULL);
    section(&wr, "MATL", sec_matl, w, NULL);
    section(&wr, "BODY", sec_body, w, NULL);
    section(&wr, "GIDS", sec_gids, w, NULL);
    section(&wr, "WALL", sec_wall, w, NULL);
    section(&wr, "TGRD", sec_tgrid, w, NULL);
    section(&wr, "PRBB", sec_pairs, w, &w->bb);
    section(&wr, "PRBT", sec_pairs, w, &w->bt);
    section(&wr, "OLDH", sec_oldh, w, NULL);
    section(&wr, "TIME", sec_time, w, NULL);
    section(&wr, "XTRA", sec_extra, w, &x);

    if (!wr.err) {
        make_header(hdr, fs.len, fs.hash);
        if (fseek(f, 0, SEEK_SET) != 0 || fwrite(hdr, 1, HEADER_SIZE, f) != HEADER_SIZE) wr.err = errno ? errno : EIO;
    }
    if (!wr.err && fflush(f) != 0) wr.err = errno ? errno : EIO;
    if (!wr.err && fsync(fileno(f)) != 0) wr.err = errno ? errno : EIO;
    if (fclose(f) != 0 && !wr.err) wr.err = errno ? errno : EIO;
    if (!wr.err && rename(tmp, path) != 0) wr.err = errno ? errno : EIO;
    if (wr.err) {
        unlink(tmp);
        free(tmp);
        errno = wr.err;
        return SD_ERR_IO;
    }
    free(tmp);
    sync_dir(path);
    return SD_OK;
}

/* ---------------------------------------------------------------- reading ---- */

static int finite3(sd_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* A count of elements of `elem` bytes that must still fit in what is left to read. */
static int get_count(sd_bin_reader *c, size_t elem)
{
    int32_t v = sd_bin_get_i32(c);
    if (c->bad || v < 0 || v >= INT_MAX / 8 || (elem > 0 && (size_t)v > sd_bin_left(c) / elem)) {
        c->bad = 1;
        return 0;
    }
    return v;
}

typedef struct {
    const char *path;
    char *msg;
    size_t msglen;
} rd_ctx;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static sd_status
fail(const rd_ctx *r, const char *fmt, ...)
{
    if (r->msg && r->msglen > 0) {
        int k = snprintf(r->msg, r->msglen, "%s: ", r->path);
        if (k >= 0 && (size_t)k < r->msglen) {
            va_list ap;
            va_start(ap, fmt);
            vsnprintf(r->msg + k, r->msglen - (size_t)k, fmt, ap);
            va_end(ap);
        }
    }
    return SD_ERR_FORMAT;
}

/* Open the next section, which must carry `tag`; *sec covers its content. */
static sd_status open_section(const rd_ctx *r, sd_bin_reader *c, const char *tag, sd_bin_reader *sec)
{
    size_t at = c->pos;
    const unsigned char *t = sd_bin_take(c, 4);
    int32_t zero = sd_bin_get_i32(c);
    uint64_t len = sd_bin_get_u64(c);
    if (c->bad) return fail(r, "section %s missing at payload offset %zu", tag, at);
    if (memcmp(t, tag, 4) != 0 || zero != 0) return fail(r, "section %s expected at payload offset %zu", tag, at);
    if (len > sd_bin_left(c)) return fail(r, "section %s overruns the payload", tag);
    sd_bin_reader_init(sec, sd_bin_take(c, (size_t)len), (size_t)len);
    return SD_OK;
}

static sd_status close_section(const rd_ctx *r, const sd_bin_reader *sec, const char *tag)
{
    if (sec->bad) return fail(r, "section %s is malformed (short or out-of-range counts)", tag);
    if (sd_bin_left(sec)) return fail(r, "section %s has %zu unexpected trailing bytes", tag, sd_bin_left(sec));
    return SD_OK;
}

typedef struct {
    char name[256];
    uint32_t elem;
    const unsigned char *data;
    int used;
} file_field;

typedef struct {
    file_field *ff;
    int nff, n;
    const rd_ctx *r;
    sd_status st;
} field_rctx;

static void read_field(void *array, size_t elem, const char *name, void *ctx)
{
    field_rctx *fc = ctx;
    if (fc->st) return;
    for (int k = 0; k < fc->nff; k++) {
        file_field *f = &fc->ff[k];
        if (strcmp(f->name, name) != 0) continue;
        if (f->elem != elem) {
            fc->st = fail(fc->r, "body field '%s' has %u-byte elements, this build uses %zu (incompatible build)", name,
                          f->elem, elem);
            return;
        }
        if (fc->n > 0) memcpy(*(void **)array, f->data, (size_t)fc->n * elem);
        f->used = 1;
        return;
    }
    fc->st = fail(fc->r, "body field '%s' is missing (written by an incompatible build)", name);
}

/* The bodies read back are checked value by value: a checksum proves the file is the one
 * written, not that what was written makes sense (a crafted or buggy file with a body at
 * z = 7.3e200 once restarted into a NaN cell index and another P_V). */
#define CK_DOMAIN 1.0e6 /* m: no coordinate of a body lies farther from the origin */
static int finite_vec(sd_vec3 v, double lim) { return fabs(v.x) <= lim && fabs(v.y) <= lim && fabs(v.z) <= lim; }

static sd_status check_bodies(const rd_ctx *r, const sd_bodies *b)
{
    for (int i = 0; i < b->n; i++) {
        const char *bad = NULL;
        const sd_quat q = b->quat[i];
        const double qn = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
        if (b->shape[i] != SD_SHAPE_SPHERE && b->shape[i] != SD_SHAPE_CYLINDER)
            bad = "shape";
        else if (!finite_vec(b->pos[i], CK_DOMAIN))
            bad = "position (not finite, or beyond 1e6 m)";
        else if (!finite_vec(b->vel[i], DBL_MAX) || !finite_vec(b->omega[i], DBL_MAX) ||
                 !finite_vec(b->angmom[i], DBL_MAX))
            bad = "velocity";
        else if (!finite_vec(b->force[i], DBL_MAX) || !finite_vec(b->torque[i], DBL_MAX) ||
                 !finite_vec(b->ext_force[i], DBL_MAX))
            bad = "force";
        else if (!(fabs(qn - 1.0) < 1e-6) || !finite_vec(b->axis[i], 1.0 + 1e-9))
            bad = "attitude (not a unit quaternion)";
        else if (!(b->radius[i] > 0.0 && b->radius[i] <= CK_DOMAIN) || !(b->hl[i] >= 0.0 && b->hl[i] <= CK_DOMAIN) ||
                 !(b->bound_r[i] >= b->radius[i] && b->bound_r[i] <= 2.0 * CK_DOMAIN))
            bad = "size";
        else if (!(b->mass[i] > 0.0 && b->mass[i] < DBL_MAX) || !(b->inv_mass[i] >= 0.0 && b->inv_mass[i] < DBL_MAX) ||
                 !(b->inv_i_ax[i] >= 0.0 && b->inv_i_ax[i] < DBL_MAX) || !(b->inv_i_tr[i] >= 0.0 && b->inv_i_tr[i] < DBL_MAX))
            bad = "mass or inertia";
        else if (b->mat[i] >= SD_MATERIALS_MAX)
            bad = "material";
        if (bad) return fail(r, "body %d (gid %d): impossible %s", i, (int)b->gid[i], bad);
    }
    return SD_OK;
}

static sd_status read_bodies(const rd_ctx *r, sd_bin_reader *c, sd_world *w)
{
    int n = get_count(c, 0);
    int nf = get_count(c, 5);
    if (c->bad) return SD_OK; /* reported by close_section */
    file_field *ff = calloc((size_t)nf + 1, sizeof(*ff));
    if (!ff) return SD_ERR_NOMEM;
    for (int k = 0; k < nf && !c->bad; k++) {
        uint8_t len;
        sd_bin_get(c, &len, 1);
        const char *nm = sd_bin_take(c, len);
        if (!nm) break;
        memcpy(ff[k].name, nm, len);
        ff[k].name[len] = '\0';
        int32_t elem = sd_bin_get_i32(c);
        if (elem <= 0 || elem > 4096) {
            c->bad = 1;
            break;
        }
        ff[k].elem = (uint32_t)elem;
        if ((size_t)n > sd_bin_left(c) / (size_t)elem) {
            c->bad = 1;
            break;
        }
        ff[k].data = sd_bin_take(c, (size_t)n * (size_t)elem);
    }
    if (c->bad) {
        free(ff);
        return SD_OK;
    }
    /* every field of the store is in the file (an unknown one is refused below): so n is
     * bounded by the bytes read, and a short file cannot make the store reserve room for
     * millions of bodies */
    field_wctx store = {0};
    sd_bodies_for_each_field(&w->b, count_field, &store);
    if (nf < store.count) {
        free(ff);
        return fail(r, "section BODY: %d body fields, this build has %d (a damaged or incompatible file)", nf, store.count);
    }
    if (sd_bodies_reserve(&w->b, n)) {
        free(ff);
        return SD_ERR_NOMEM;
    }
    w->b.n = n;
    field_rctx fc = {ff, nf, n, r, SD_OK};
    sd_bodies_for_each_field(&w->b, read_field, &fc);
    for (int k = 0; k < nf && !fc.st; k++)
        if (!ff[k].used) fc.st = fail(r, "unknown body field '%s' (written by an incompatible build)", ff[k].name);
    free(ff);
    return fc.st ? fc.st : check_bodies(r, &w->b);
}

static sd_status read_pairs(const rd_ctx *r, sd_bin_reader *c, sd_world *w, sd_pairlist *l, int bt, const char *tag)
{
    int n = get_count(c, 24);
    int nh = get_count(c, 0);
    if (c->bad) return SD_OK;
    /* the history slots (28 bytes each) follow the n pairs (24 bytes each), at most
     * SD_MANIFOLD_MAX a pair: bounded before anything is reserved for them */
    if ((size_t)nh > (size_t)n * SD_MANIFOLD_MAX || (size_t)nh > (sd_bin_left(c) - (size_t)n * 24) / 28) {
        c->bad = 1;
        return SD_OK;
    }
    if (sd_grow((void **)&l->p, &l->cap, n + 1, sizeof(sd_pair)) ||
        sd_grow((void **)&l->hist, &l->hcap, nh + 1, sizeof(sd_hist)))
        return SD_ERR_NOMEM;
    if (bt) { /* the wall pairs' results, rewritten by the next force pass (as restore_history) */
        if (sd_grow((void **)&l->out, &l->out_cap, n + 1, sizeof(sd_vec3)) ||
            sd_grow((void **)&l->active, &l->active_cap, n + 1, 1))
            return SD_ERR_NOMEM;
        memset(l->active, 0, (size_t)n + 1);
    }
    int nb = w->b.n, nt = w->w.n;
    int next_off = 0; /* the slots of consecutive pairs follow each other (push_pair) */
    for (int k = 0; k < n; k++) {
        sd_pair *p = &l->p[k];
        p->a = sd_bin_get_i32(c);
        p->b = sd_bin_get_i32(c);
        p->off = sd_bin_get_i32(c);
        sd_bin_get(c, &p->cap, sizeof(p->cap));
        sd_bin_get(c, &p->kind, sizeof(p->kind));
        p->sqrt_m_eff = sd_bin_get_f64(c);
        if (c->bad) return SD_OK;
        int ok = p->a >= 0 && p->a < nb && p->cap >= 1 && p->cap <= SD_MANIFOLD_MAX && p->off == next_off &&
                 p->off <= nh - p->cap;
        next_off += p->cap;
        if (bt)
            ok = ok && (p->kind == SD_PAIR_ST || p->kind == SD_PAIR_CT) && p->b >= 0 && p->b < nt &&
                 (k == 0 || l->p[k - 1].a <= p->a);
        else
            ok = ok && (p->kind == SD_PAIR_SS || p->kind == SD_PAIR_SC || p->kind == SD_PAIR_CC) && p->b >= 0 &&
                 p->b < nb && p->b != p->a;
        if (!ok) return fail(r, "section %s: pair %d is out of range", tag, k);
    }
    if (next_off != nh) return fail(r, "section %s: %d history slots for pairs holding %d", tag, nh, next_off);
    if ((size_t)nh > sd_bin_left(c) / 28) {
        c->bad = 1;
        return SD_OK;
    }
    for (int k = 0; k < nh; k++) {
        l->hist[k].feature = sd_bin_get_i32(c);
        l->hist[k].shear = sd_bin_get_vec3(c);
    }
    l->n = n;
    l->nh = nh;
    return SD_OK;
}

static sd_status read_tgrid(const rd_ctx *r, sd_bin_reader *c, sd_world *w)
{
    int present = sd_bin_get_i32(c);
    if (c->bad) return SD_OK;
    if (present != tgrid_current(w))
        return fail(r, "section TGRD: triangle grid %s", present ? "saved for dirty walls" : "missing");
    if (!present) return SD_OK;
    sd_grid *g = &w->tgrid;
    g->cell = sd_bin_get_f64(c);
    g->nx = sd_bin_get_i32(c);
    g->ny = sd_bin_get_i32(c);
    g->nz = sd_bin_get_i32(c);
    g->lo = sd_bin_get_vec3(c);
    if (c->bad) return SD_OK;
    if (!(g->cell > 0.0) || !isfinite(g->cell) || !finite3(g->lo) || g->nx < 1 || g->ny < 1 || g->nz < 1 ||
        (double)g->nx * g->ny * g->nz > (double)(INT_MAX / 8))
        return fail(r, "section TGRD: bad grid dimensions");
    int ncell = g->nx * g->ny * g->nz;
    if ((size_t)ncell + 1 > sd_bin_left(c) / sizeof(int32_t)) {
        c->bad = 1;
        return SD_OK;
    }
    if (sd_grow((void **)&g->cell_start, &g->cap_cells, ncell + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    sd_bin_get(c, g->cell_start, (size_t)(ncell + 1) * sizeof(int32_t));
    int nitems = get_count(c, sizeof(int32_t));
    if (c->bad) return SD_OK;
    if (g->cell_start[0] != 0 || g->cell_start[ncell] != nitems) return fail(r, "section TGRD: bad cell table");
    for (int k = 0; k < ncell; k++)
        if (g->cell_start[k + 1] < g->cell_start[k]) return fail(r, "section TGRD: bad cell table");
    if (sd_grow((void **)&g->items, &g->cap_items, nitems + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    sd_bin_get(c, g->items, (size_t)nitems * sizeof(int32_t));
    int nt = w->w.n;
    for (int k = 0; k < nitems; k++)
        if (g->items[k] < 0 || g->items[k] >= nt) return fail(r, "section TGRD: bad triangle index");
    if (sd_grow((void **)&w->trange, &w->trange_cap, nt + 1, sizeof(*w->trange))) return SD_ERR_NOMEM;
    sd_bin_get(c, w->trange, (size_t)nt * sizeof(*w->trange));
    if (c->bad) return SD_OK;
    const int dims[3] = {g->nx, g->ny, g->nz};
    for (int t = 0; t < nt; t++)
        for (int d = 0; d < 3; d++)
            if (w->trange[t][d] < 0 || w->trange[t][d] > w->trange[t][d + 3] || w->trange[t][d + 3] >= dims[d])
                return fail(r, "section TGRD: bad cell range of triangle %d", t);
    return sd_neighbor_tgrid_flags(w);
}

/* Derived structures, exactly as sd_neighbor_rebuild leaves them for these pair lists. */
static sd_status derive(sd_world *w)
{
    int n = w->b.n;
    if (sd_grow((void **)&w->csr.bt_start, &w->csr.cap_bt_start, n + 1, sizeof(int32_t)) ||
        sd_grow((void **)&w->bt_man, &w->bt_man_cap, w->bt.n + 1, sizeof(sd_manifold)))
        return SD_ERR_NOMEM;
    /* body–triangle pairs are grouped by body in body order */
    int k = 0;
    for (int i = 0; i <= n; i++) {
        while (k < w->bt.n && w->bt.p[k].a < i)
            k++;
        w->csr.bt_start[i] = k;
    }
    /* the weld ids are a pure function of the vertices: the same as the saved run's (when the
     * walls are dirty, the next rebuild welds again anyway) */
    if (w->w.n > 0 && sd_walls_weld(&w->w)) return SD_ERR_NOMEM;
    return SD_OK;
}

/* What add_body guarantees of a body, so that a damaged file cannot hang or blow up the next
 * rebuild (the checksum catches accidents; this catches a file made to pass it). */
static int body_sane(const sd_bodies *b, int i)
{
    const sd_quat q = b->quat[i];
    return finite3(b->pos[i]) && finite3(b->vel[i]) && finite3(b->omega[i]) && finite3(b->angmom[i]) && isfinite(q.w) &&
           isfinite(q.x) && isfinite(q.y) && isfinite(q.z) && finite3(b->axis[i]) && finite3(b->force[i]) &&
           finite3(b->torque[i]) && finite3(b->ext_force[i]) && finite3(b->pos_ref[i]) && finite3(b->axis_ref[i]) &&
           isfinite(b->radius[i]) && b->radius[i] > 0.0 && isfinite(b->hl[i]) && b->hl[i] >= 0.0 &&
           isfinite(b->mass[i]) && b->mass[i] > 0.0 && isfinite(b->inv_mass[i]) && b->inv_mass[i] > 0.0 &&
           isfinite(b->inv_i_ax[i]) && b->inv_i_ax[i] > 0.0 && isfinite(b->inv_i_tr[i]) && b->inv_i_tr[i] > 0.0 &&
           isfinite(b->bound_r[i]) && b->bound_r[i] > 0.0;
}

static sd_status parse(const rd_ctx *r, sd_bin_reader *pl, sd_world **out, void **extra, size_t *extra_len)
{
    sd_status st;
    sd_bin_reader c;
    sd_world *w = NULL;

    /* world definition */
    if ((st = open_section(r, pl, "DEF ", &c))) return st;
    sd_world_def def;
    memset(&def, 0, sizeof(def));
    def.gravity = sd_bin_get_vec3(&c);
    def.dt = sd_bin_get_f64(&c);
    def.margin = sd_bin_get_f64(&c);
    def.t_reset = sd_bin_get_f64(&c);
    def.contact.k_n = sd_bin_get_f64(&c);
    def.contact.k_s = sd_bin_get_f64(&c);
    def.contact.damping = sd_bin_get_f64(&c);
    def.contact.tan_phi = sd_bin_get_f64(&c);
    def.contact.cohesion = sd_bin_get_f64(&c);
    def.threads = sd_bin_get_i32(&c);
    def.parallel_min = sd_bin_get_i32(&c);
    def.check_dt = sd_bin_get_i32(&c);
    if ((st = close_section(r, &c, "DEF "))) return st;
    if (!isfinite(def.dt) || !isfinite(def.margin) || !isfinite(def.t_reset))
        return fail(r, "section DEF : invalid world definition");
    st = sd_world_create(&def, &w);
    if (st == SD_ERR_ARG) return fail(r, "section DEF : invalid world definition");
    if (st) return st;

    /* the pairs of materials with springs of their own */
    if ((st = open_section(r, pl, "MATL", &c))) goto out;
    {
        const int n = get_count(&c, 2 * sizeof(int32_t) + 5 * sizeof(double));
        for (int k = 0; k < n && !c.bad; k++) {
            const int a = sd_bin_get_i32(&c), b = sd_bin_get_i32(&c);
            sd_contact_def cd;
            cd.k_n = sd_bin_get_f64(&c);
            cd.k_s = sd_bin_get_f64(&c);
            cd.damping = sd_bin_get_f64(&c);
            cd.tan_phi = sd_bin_get_f64(&c);
            cd.cohesion = sd_bin_get_f64(&c);
            if (c.bad) break;
            if (a > b || sd_world_pair_contact(w, a, b, NULL) != 0 || sd_world_set_pair_contact(w, a, b, &cd)) {
                st = fail(r, "section MATL: pair %d (materials %d, %d) is out of range, repeated or invalid", k, a, b);
                goto out;
            }
        }
        if ((st = close_section(r, &c, "MATL"))) goto out;
    }

    /* bodies */
    if ((st = open_section(r, pl, "BODY", &c)) || (st = read_bodies(r, &c, w)) || (st = close_section(r, &c, "BODY")))
        goto out;

    /* gid map */
    if ((st = open_section(r, pl, "GIDS", &c))) goto out;
    int ng = get_count(&c, sizeof(int32_t));
    if (!c.bad) {
        if (sd_grow((void **)&w->gid_map, &w->gid_cap, ng + 1, sizeof(int32_t))) {
            st = SD_ERR_NOMEM;
            goto out;
        }
        sd_bin_get(&c, w->gid_map, (size_t)ng * sizeof(int32_t));
        w->next_gid = ng;
    }
    if ((st = close_section(r, &c, "GIDS"))) goto out;
    {
        const sd_bodies *b = &w->b;
        int live = 0;
        for (int g = 0; g < w->next_gid; g++) {
            int i = w->gid_map[g];
            if (i < -1 || i >= b->n || (i >= 0 && b->gid[i] != g)) {
                st = fail(r, "section GIDS: gid %d maps to a wrong index", g);
                goto out;
            }
            live += i >= 0;
        }
        if (live != b->n) {
            st = fail(r, "section GIDS: %d live gids for %d bodies", live, b->n);
            goto out;
        }
        for (int i = 0; i < b->n; i++) {
            if (b->shape[i] > SD_SHAPE_CYLINDER || b->fixed[i] > 1 || !body_sane(b, i)) {
                st = fail(r, "section BODY: body %d (gid %d) has a bad shape, flag or non-finite state", i, b->gid[i]);
                goto out;
            }
            w->ext_any |= sd_ext_set(b->ext_force[i]); /* (world_internal.h ext_any) */
        }
    }

    /* walls */
    if ((st = open_section(r, pl, "WALL", &c))) goto out;
    {
        sd_walls *wl = &w->w;
        int nt = get_count(&c, sizeof(sd_tri) + sizeof(int32_t) + 2 + sizeof(sd_vec3));
        if (!c.bad) {
            if (sd_walls_reserve(wl, nt + 1)) {
                st = SD_ERR_NOMEM;
                goto out;
            }
            wl->n = nt;
            if (nt > 0) {
                sd_bin_get(&c, wl->tri, (size_t)nt * sizeof(sd_tri));
                sd_bin_get(&c, wl->group, (size_t)nt * sizeof(int32_t));
                sd_bin_get(&c, wl->active, (size_t)nt);
                sd_bin_get(&c, wl->mat, (size_t)nt);
                sd_bin_get(&c, wl->force, (size_t)nt * sizeof(sd_vec3));
            }
            wl->dirty = sd_bin_get_i32(&c);
        }
        if ((st = close_section(r, &c, "WALL"))) goto out;
        for (int t = 0; t < nt; t++)
            if (wl->active[t] > 1 || wl->mat[t] >= SD_MATERIALS_MAX || !finite3(wl->tri[t].v[0]) || !finite3(wl->tri[t].v[1]) ||
                !finite3(wl->tri[t].v[2]) || !finite3(wl->tri[t].n) || !finite3(wl->force[t])) {
                st = fail(r, "section WALL: triangle %d has a bad flag or material, or non-finite vertices", t);
                goto out;
            }
        if (wl->dirty != 0 && wl->dirty != 1) {
            st = fail(r, "section WALL: bad dirty flag");
            goto out;
        }
    }

    if ((st = open_section(r, pl, "TGRD", &c)) || (st = read_tgrid(r, &c, w)) || (st = close_section(r, &c, "TGRD")))
        goto out;
    if ((st = open_section(r, pl, "PRBB", &c)) || (st = read_pairs(r, &c, w, &w->bb, 0, "PRBB")) ||
        (st = close_section(r, &c, "PRBB")))
        goto out;
    if ((st = open_section(r, pl, "PRBT", &c)) || (st = read_pairs(r, &c, w, &w->bt, 1, "PRBT")) ||
        (st = close_section(r, &c, "PRBT")))
        goto out;

    /* history carried to the next rebuild */
    if ((st = open_section(r, pl, "OLDH", &c))) goto out;
    w->keys_collected = sd_bin_get_i32(&c);
    {
        int m = get_count(&c, sizeof(uint64_t) + 28);
        if (!c.bad) {
            if (sd_grow((void **)&w->old_keys, &w->old_cap, m + 1, sizeof(uint64_t)) ||
                sd_grow((void **)&w->old_hist, &w->old_hist_cap, m + 1, sizeof(sd_hist))) {
                st = SD_ERR_NOMEM;
                goto out;
            }
            sd_bin_get(&c, w->old_keys, (size_t)m * sizeof(uint64_t));
            for (int k = 0; k < m; k++) {
                w->old_hist[k].feature = sd_bin_get_i32(&c);
                w->old_hist[k].shear = sd_bin_get_vec3(&c);
            }
            w->n_old = m;
        }
        if ((st = close_section(r, &c, "OLDH"))) goto out;
        if (w->keys_collected != 0 && w->keys_collected != 1) {
            st = fail(r, "section OLDH: bad flag");
            goto out;
        }
        /* each first body's entries are one run (neighbor.c old_ranges) */
        uint8_t *seen = m > 0 ? calloc((size_t)w->next_gid + 1, 1) : NULL;
        if (m > 0 && !seen) {
            st = SD_ERR_NOMEM;
            goto out;
        }
        for (int k = 0; k < m && !st; k++) {
            const uint64_t g = w->old_keys[k] >> 32;
            if (k > 0 && g == w->old_keys[k - 1] >> 32) continue;
            if (g >= (uint64_t)w->next_gid || seen[g])
                st = fail(r, "section OLDH: keys not grouped by body");
            else
                seen[g] = 1;
        }
        free(seen);
        if (st) goto out;
    }

    /* clock and flags */
    if ((st = open_section(r, pl, "TIME", &c))) goto out;
    w->time = sd_bin_get_f64(&c);
    w->step = (long)sd_bin_get_i64(&c);
    w->last_rebuild_time = sd_bin_get_f64(&c);
    w->need_rebuild = sd_bin_get_i32(&c);
    w->rebuild_every_step = sd_bin_get_i32(&c);
    w->contacts = (long)sd_bin_get_i64(&c);
    w->timers.moves = sd_bin_get_f64(&c);
    w->timers.rebuild = sd_bin_get_f64(&c);
    w->timers.contacts = sd_bin_get_f64(&c);
    w->timers.moves += sd_bin_get_f64(&c); /* (older files: the gather, 0 now) */
    w->timers.checks = sd_bin_get_f64(&c);
    w->timers.rebuilds = (long)sd_bin_get_i64(&c);
    if ((st = close_section(r, &c, "TIME"))) goto out;
    if (!isfinite(w->time) || !isfinite(w->last_rebuild_time) || w->step < 0) {
        st = fail(r, "section TIME: bad clock");
        goto out;
    }
    w->checked = 0; /* sd_world_check runs again at the next step; it passes as before */
    /* how far the spheres drifted since the last rebuild is not saved: test each of them
     * exactly at every step until the next rebuild (the same outcome as without the stop) */
    w->ref_drift = INFINITY;

    /* the driver's blob */
    if ((st = open_section(r, pl, "XTRA", &c))) goto out;
    {
        uint64_t len = sd_bin_get_u64(&c);
        const void *data = NULL;
        if (!c.bad && len <= sd_bin_left(&c))
            data = sd_bin_take(&c, (size_t)len);
        else
            c.bad = 1;
        if ((st = close_section(r, &c, "XTRA"))) goto out;
        if (sd_bin_left(pl)) {
            st = fail(r, "%zu unexpected bytes after the last section", sd_bin_left(pl));
            goto out;
        }
        if ((st = derive(w))) goto out;
        if (extra) {
            *extra = NULL;
            if (len > 0) {
                *extra = malloc((size_t)len);
                if (!*extra) {
                    st = SD_ERR_NOMEM;
                    goto out;
                }
                memcpy(*extra, data, (size_t)len);
            }
        }
        if (extra_len) *extra_len = (size_t)len;
    }
    *out = w;
    return SD_OK;
out:
    sd_world_destroy(w);
    return st;
}

/* Whole file into memory. */
static sd_status slurp(const rd_ctx *r, unsigned char **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    FILE *f = fopen(r->path, "rb");
    if (!f) {
        int e = errno;
        if (r->msg && r->msglen) snprintf(r->msg, r->msglen, "%s: cannot open: %s", r->path, strerror(e));
        errno = e;
        return SD_ERR_IO;
    }
    /* a regular file, read up to its size and no further: a device or a pipe (/dev/zero) would
     * be read until memory ran out */
    struct stat sb;
    if (fstat(fileno(f), &sb) != 0 || !S_ISREG(sb.st_mode)) {
        fclose(f);
        if (r->msg && r->msglen) snprintf(r->msg, r->msglen, "%s: not a regular file", r->path);
        return SD_ERR_FORMAT;
    }
    size_t cap = (size_t)sb.st_size + 1, n = 0; /* (one more byte: a file that grew is refused below) */
    unsigned char *buf = malloc(cap);
    if (!buf) {
        fclose(f);
        return SD_ERR_NOMEM;
    }
    for (;;) {
        size_t got = n < cap ? fread(buf + n, 1, cap - n, f) : 0;
        n += got;
        if (got == 0) break;
    }
    int err = ferror(f);
    int e = errno;
    fclose(f);
    if (err) {
        free(buf);
        if (r->msg && r->msglen) snprintf(r->msg, r->msglen, "%s: read error: %s", r->path, strerror(e));
        return SD_ERR_IO;
    }
    *data = buf;
    *size = n;
    return SD_OK;
}

uint32_t sd_checkpoint_version(void) { return SD_CHECKPOINT_VERSION; }

sd_status sd_checkpoint_read(const char *path, sd_world **out, void **extra, size_t *extra_len, char *msg,
                             size_t msglen)
{
    if (out) *out = NULL;
    if (extra) *extra = NULL;
    if (extra_len) *extra_len = 0;
    if (msg && msglen) msg[0] = '\0';
    if (!path || !out) return SD_ERR_ARG;
    rd_ctx r = {path, msg, msglen};
    unsigned char *data;
    size_t size;
    sd_status st = slurp(&r, &data, &size);
    if (st) return st;

    if (size == 0)
        st = fail(&r, "empty file (not a checkpoint, or a write that never finished)");
    else if (memcmp(data, magic, size < 8 ? size : 8) != 0)
        st = fail(&r, "not a sabodem checkpoint (bad magic)");
    else if (size < HEADER_SIZE)
        st = fail(&r, "truncated: %zu bytes, shorter than the %d-byte header", size, HEADER_SIZE);
    if (st) goto done;
    {
        uint32_t version, tag;
        double pr;
        uint64_t plen, hash;
        memcpy(&version, data + 8, 4);
        memcpy(&tag, data + 12, 4);
        memcpy(&pr, data + 24, 8);
        memcpy(&plen, data + 32, 8);
        memcpy(&hash, data + 40, 8);
        int reserved_zero = 1;
        for (int k = 48; k < HEADER_SIZE; k++)
            reserved_zero &= data[k] == 0;
        if (tag != endian_tag) {
            st = fail(&r, "written on a machine of the other byte order (or corrupted header)");
        } else if (version != SD_CHECKPOINT_VERSION) {
            st = fail(&r, "format version %u, this build reads version %u", (unsigned)version,
                      (unsigned)SD_CHECKPOINT_VERSION);
        } else if (memcmp(data + 16, type_sizes, 8) != 0 || memcmp(&pr, &probe, 8) != 0) {
            st = fail(&r, "element sizes or floating-point format differ from this build (or corrupted header)");
        } else if (!reserved_zero) {
            st = fail(&r, "corrupted header (reserved bytes not zero)");
        } else if (plen > size - HEADER_SIZE) {
            st = fail(&r, "truncated: %zu bytes, the header announces %llu", size,
                      (unsigned long long)plen + HEADER_SIZE);
        } else if (plen < size - HEADER_SIZE) {
            st = fail(&r, "%zu bytes after the announced end of the checkpoint (corrupted)",
                      size - HEADER_SIZE - (size_t)plen);
        } else if (sd_hash(data + HEADER_SIZE, (size_t)plen) != hash) {
            st = fail(&r, "checksum mismatch (corrupted file)");
        }
        if (st) goto done;
        sd_bin_reader pl;
        sd_bin_reader_init(&pl, data + HEADER_SIZE, (size_t)plen);
        st = parse(&r, &pl, out, extra, extra_len);
    }
done:
    free(data);
    return st;
}
