/* Checkpoint and restart: a restarted run continues bit for bit; damaged files are refused;
 * a failed write leaves the previous checkpoint intact and no temporary file behind.
 * Scene: spheres and logs (with a fixed sphere pair and a fixed pipe) falling into a box of
 * triangles on the default 15° slope, held by a gate (triangle group) that is later opened;
 * friction on, so tangential springs are carried in the history. */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "core/hash.h"
#include "core/rng.h"
#include "io_checkpoint.h"
#include "world_internal.h"

enum { G_FLOOR = 0, G_WALLS = 1, G_GATE = 2 };

static char dir[64];

static void quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d, int group)
{
    CHECK(sd_world_add_triangle(w, a, b, c, group) >= 0);
    CHECK(sd_world_add_triangle(w, a, c, d, group) >= 0);
}

static sd_world *make_scene(void)
{
    sd_world_def def = sd_world_def_default(); /* 15° slope, friction 0.404, damping 0.2 */
    def.dt = 4e-5;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    const double X = 0.12, Y = 0.08, H = 0.1, s = 0.04;
    /* floor: 3 x 2 quads sharing edges (mesh seams) */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 2; j++)
            quad(w, v3(i * s, j * s, 0), v3((i + 1) * s, j * s, 0), v3((i + 1) * s, (j + 1) * s, 0),
                 v3(i * s, (j + 1) * s, 0), G_FLOOR);
    quad(w, v3(0, 0, 0), v3(0, Y, 0), v3(0, Y, H), v3(0, 0, H), G_WALLS);
    quad(w, v3(X, 0, 0), v3(X, 0, H), v3(X, Y, H), v3(X, Y, 0), G_WALLS);
    quad(w, v3(0, 0, 0), v3(0, 0, H), v3(X, 0, H), v3(X, 0, 0), G_WALLS);
    quad(w, v3(0, Y, 0), v3(X, Y, 0), v3(X, Y, H), v3(0, Y, H), G_WALLS);
    quad(w, v3(0.075, 0, 0), v3(0.075, 0, 0.03), v3(0.075, Y, 0.03), v3(0.075, Y, 0), G_GATE);

    sd_rng rng = {12345};
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++) {
                sd_sphere_def d = sd_sphere_def_default();
                d.radius = sd_rng_range(&rng, 0.004, 0.006);
                d.pos = v3(0.012 + 0.016 * i, 0.012 + 0.016 * j, 0.008 + 0.016 * k);
                d.vel = v3(sd_rng_range(&rng, -0.1, 0.1), sd_rng_range(&rng, -0.1, 0.1), -0.2);
                d.omega = v3(0, sd_rng_range(&rng, -5, 5), 0);
                d.tag = k;
                CHECK(sd_world_add_sphere(w, &d) >= 0);
            }
    for (int k = 0; k < 8; k++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.radius = 0.003;
        c.length = 0.03;
        double u = 0.015 + 0.015 * (k % 4);
        if (k < 4) {
            c.pos = v3(u, 0.04, 0.045);
            c.axis = v3(0.05, 1, 0.02 * k);
        } else {
            c.pos = v3(0.04, u, 0.058);
            c.axis = v3(1, -0.03, 0.01 * k);
        }
        c.vel = v3(0, 0, -0.3);
        c.omega = v3(sd_rng_range(&rng, -3, 3), sd_rng_range(&rng, -3, 3), sd_rng_range(&rng, -3, 3));
        c.tag = 7;
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    /* bed roughness and a dam pipe beyond the gate */
    for (int k = 0; k < 2; k++) {
        sd_sphere_def d = sd_sphere_def_default();
        d.radius = 0.005;
        d.fixed = 1;
        d.pos = v3(0.09, 0.025 + 0.03 * k, 0.0);
        CHECK(sd_world_add_sphere(w, &d) >= 0);
    }
    sd_cylinder_def p = sd_cylinder_def_default();
    p.radius = 0.004;
    p.length = 0.07;
    p.axis = v3(0, 1, 0);
    p.pos = v3(0.105, 0.04, 0.01);
    p.fixed = 1;
    CHECK(sd_world_add_cylinder(w, &p) >= 0);
    return w;
}

/* ---- comparison of two worlds, field by field ---- */

typedef struct {
    void *p[64];
    size_t elem[64];
    const char *name[64];
    int n;
} field_list;

static void collect_field(void *array, size_t elem, const char *name, void *ctx)
{
    field_list *l = ctx;
    if (l->n >= 64) return;
    l->p[l->n] = *(void **)array;
    l->elem[l->n] = elem;
    l->name[l->n] = name;
    l->n++;
}

static int pairs_equal(const sd_pairlist *a, const sd_pairlist *b)
{
    if (a->n != b->n || a->nh != b->nh) return 0;
    for (int k = 0; k < a->n; k++) {
        const sd_pair *p = &a->p[k], *q = &b->p[k];
        if (p->a != q->a || p->b != q->b || p->off != q->off || p->cap != q->cap || p->kind != q->kind ||
            memcmp(&p->sqrt_m_eff, &q->sqrt_m_eff, sizeof(double)) != 0)
            return 0;
    }
    /* the shear of an empty slot (feature < 0) is never read as a spring; a slot that keeps a
     * separating axis (SD_HIST_SEP_AXIS, a hint that changes no answer) is empty, and is written
     * to the file as one */
    for (int k = 0; k < a->nh; k++)
        if ((a->hist[k].feature < 0 ? -1 : a->hist[k].feature) != (b->hist[k].feature < 0 ? -1 : b->hist[k].feature) ||
            (a->hist[k].feature >= 0 && memcmp(&a->hist[k].shear, &b->hist[k].shear, sizeof(sd_vec3)) != 0))
            return 0;
    return 1;
}

static void check_identical(sd_world *a, sd_world *b, const char *what)
{
    int before = check_failures;
    CHECK(a->step == b->step);
    CHECK(memcmp(&a->time, &b->time, sizeof(double)) == 0);
    CHECK(memcmp(&a->last_rebuild_time, &b->last_rebuild_time, sizeof(double)) == 0);
    CHECK(a->need_rebuild == b->need_rebuild);
    CHECK(a->timers.rebuilds == b->timers.rebuilds);
    CHECK(a->contacts == b->contacts);
    CHECK(sd_world_state_hash(a) == sd_world_state_hash(b));
    CHECK(a->b.n == b->b.n);
    CHECK(a->next_gid == b->next_gid);
    if (a->next_gid == b->next_gid) CHECK(memcmp(a->gid_map, b->gid_map, (size_t)a->next_gid * sizeof(int32_t)) == 0);
    field_list fa = {0}, fb = {0};
    sd_bodies_for_each_field(&a->b, collect_field, &fa);
    sd_bodies_for_each_field(&b->b, collect_field, &fb);
    CHECK(fa.n == fb.n && fa.n > 0);
    if (a->b.n == b->b.n)
        for (int k = 0; k < fa.n && k < fb.n; k++) {
            int same = a->b.n == 0 || memcmp(fa.p[k], fb.p[k], (size_t)a->b.n * fa.elem[k]) == 0;
            if (!same) fprintf(stderr, "%s: body field %s differs\n", what, fa.name[k]);
            CHECK(same);
        }
    CHECK(pairs_equal(&a->bb, &b->bb));
    CHECK(pairs_equal(&a->bt, &b->bt));
    CHECK(a->w.n == b->w.n);
    if (a->w.n == b->w.n && a->w.n > 0) CHECK(memcmp(a->w.force, b->w.force, (size_t)a->w.n * sizeof(sd_vec3)) == 0);
    if (check_failures != before)
        fprintf(stderr, "%s: restarted run differs\n", what);
    else
        printf("%s: bit-identical (step %ld, %d bodies, %d+%d pairs, %ld rebuilds)\n", what, a->step, a->b.n, a->bb.n,
               a->bt.n, a->timers.rebuilds);
}

static long steps_since_rebuild(const sd_world *w) { return lround((w->time - w->last_rebuild_time) / w->def.dt); }

static void run(sd_world *w, long steps)
{
    sd_status st = sd_world_run(w, steps);
    if (st) fprintf(stderr, "run: %s\n", sd_status_message(st));
    CHECK(st == SD_OK);
}

/* Step until the next step is not a rebuild and the last one is well behind. */
static void run_to_mid_interval(sd_world *w)
{
    long per = lround(w->def.t_reset / w->def.dt);
    for (int k = 0; k < 5000; k++) {
        long since = steps_since_rebuild(w);
        if (since >= per / 3 && since <= per - 10 && !sd_neighbor_needs_rebuild(w)) return;
        run(w, 1);
    }
    CHECK(0); /* never settled between rebuilds */
}

static void path_in_dir(char *buf, size_t n, const char *name) { snprintf(buf, n, "%s/%s", dir, name); }

static unsigned char *read_all(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    *n = 0;
    if (!f) return NULL;
    size_t cap = 1024;
    unsigned char *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + *n, 1, cap - *n, f)) > 0) {
        *n += got;
        if (*n == cap) {
            unsigned char *q = realloc(buf, cap * 2);
            if (!q) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = q;
            cap *= 2;
        }
    }
    fclose(f);
    return buf;
}

static void write_all(const char *path, const void *p, size_t n)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (!f) return;
    if (n) CHECK(fwrite(p, 1, n, f) == n);
    fclose(f);
}

/* the payload's checksum (FNV-1a over the bytes from 64 on, at offset 40) remade after an edit */
static void remake_checksum(unsigned char *data, size_t n)
{
    uint64_t h = sd_hash(data + 64, n - 64);
    memcpy(data + 40, &h, 8);
}

/* a moving body that holds a sphere spring removed: its springs and the others' are taken out
 * and wait, keyed, for the next rebuild */
static void remove_body_in_contact(sd_world *w)
{
    int victim = -1;
    sd_near_springs_home(w); /* (a near list's springs into their slots) */
    for (int k = 0; k < w->bb.n && victim < 0; k++)
        if (w->bb.hist[w->bb.p[k].off].feature >= 0 && !w->b.fixed[w->bb.p[k].a]) victim = w->b.gid[w->bb.p[k].a];
    CHECK(victim >= 0);
    CHECK(sd_world_remove_body(w, victim) == SD_OK);
}

static int count_temp_files(void)
{
    DIR *d = opendir(dir);
    int n = 0;
    if (!d) return -1;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp.")) n++;
    closedir(d);
    return n;
}

/* Driver state carried in the extra blob. */
typedef struct {
    int phase;
    double accum;
    sd_rng rng;
} driver_state;

/* Checkpoint w (with a driver blob), continue w, restart from the file, continue the copy,
 * and require identical results. */
static void restart_matches(sd_world *w, long more, const char *what)
{
    char path[128], path2[128];
    path_in_dir(path, sizeof(path), "ck.bin");
    path_in_dir(path2, sizeof(path2), "ck2.bin");
    driver_state ds;
    memset(&ds, 0, sizeof(ds)); /* padding too: the blob is compared bytewise */
    ds.phase = 3;
    ds.accum = 1.25;
    ds.rng.s = 987654321ULL;
    (void)sd_rng_next(&ds.rng);
    CHECK(sd_checkpoint_write(path, w, &ds, sizeof(ds)) == SD_OK);
    CHECK(count_temp_files() == 0);

    sd_world *r = NULL;
    void *extra = NULL;
    size_t extra_len = 0;
    char msg[256];
    sd_status st = sd_checkpoint_read(path, &r, &extra, &extra_len, msg, sizeof(msg));
    if (st) fprintf(stderr, "%s: %s\n", what, msg);
    CHECK(st == SD_OK);
    if (st) return;
    CHECK(extra_len == sizeof(ds));
    CHECK(extra != NULL && memcmp(extra, &ds, sizeof(ds)) == 0);
    if (extra) {
        driver_state back;
        memcpy(&back, extra, sizeof(back));
        sd_rng mine = ds.rng;
        CHECK(back.phase == 3 && sd_rng_next(&back.rng) == sd_rng_next(&mine));
    }
    free(extra);
    /* nothing is lost: the restored world writes the same bytes */
    CHECK(sd_checkpoint_write(path2, r, &ds, sizeof(ds)) == SD_OK);
    size_t n1, n2;
    unsigned char *b1 = read_all(path, &n1), *b2 = read_all(path2, &n2);
    CHECK(b1 && b2 && n1 == n2 && memcmp(b1, b2, n1) == 0);
    free(b1);
    free(b2);
    check_identical(w, r, what); /* right after the restore */

    long rebuilds0 = w->timers.rebuilds;
    run(w, more);
    run(r, more);
    CHECK(w->timers.rebuilds > rebuilds0); /* the continuation crosses candidate rebuilds */
    check_identical(w, r, what);
    sd_world_destroy(r);
}

static int has_shear(const sd_pairlist *l)
{
    for (int k = 0; k < l->nh; k++)
        if (l->hist[k].feature >= 0 && v3_norm2(l->hist[k].shear) > 0.0) return 1;
    return 0;
}

static void test_restart(void)
{
    /* at step 0: nothing built yet, walls dirty */
    sd_world *w = make_scene();
    restart_matches(w, 300, "fresh world");
    sd_world_destroy(w);

    w = make_scene();
    run(w, 3500);
    run_to_mid_interval(w);
    CHECK(!sd_neighbor_needs_rebuild(w) && steps_since_rebuild(w) > 0);
    CHECK(sd_world_contact_count(w) > 0);
    CHECK(has_shear(&w->bb));
    CHECK(has_shear(&w->bt)); /* tangential history is live */
    int kinds[SD_PAIR_KINDS] = {0};
    for (int k = 0; k < w->bb.n; k++)
        kinds[w->bb.p[k].kind]++;
    for (int k = 0; k < w->bt.n; k++)
        kinds[w->bt.p[k].kind]++;
    for (int k = 0; k < SD_PAIR_KINDS; k++)
        CHECK(kinds[k] > 0);
    printf("mid-interval checkpoint at step %ld, %ld steps after the last rebuild\n", w->step, steps_since_rebuild(w));
    restart_matches(w, 2000, "mid-interval restart");

    /* sensitivity: a restart that forced an extra candidate rebuild would not match */
    {
        char path[128];
        path_in_dir(path, sizeof(path), "ck.bin");
        sd_world *a = NULL, *b = NULL;
        run_to_mid_interval(w);
        CHECK(sd_checkpoint_write(path, w, NULL, 0) == SD_OK);
        CHECK(sd_checkpoint_read(path, &a, NULL, NULL, NULL, 0) == SD_OK);
        CHECK(sd_checkpoint_read(path, &b, NULL, NULL, NULL, 0) == SD_OK);
        if (a && b) {
            b->need_rebuild = 1;
            run(a, 1000);
            run(b, 1000);
            /* the bodies' state may come out the same (the candidate sets are supersets of the
             * contacts), but the comparison in check_identical sees the extra rebuild */
            printf("control: one extra rebuild at the restart %s the state hash, rebuilds %ld vs %ld\n",
                   sd_world_state_hash(a) != sd_world_state_hash(b) ? "changes" : "does not change", a->timers.rebuilds,
                   b->timers.rebuilds);
            CHECK(a->timers.rebuilds != b->timers.rebuilds ||
                  memcmp(&a->last_rebuild_time, &b->last_rebuild_time, sizeof(double)) != 0);
        }
        sd_world_destroy(a);
        sd_world_destroy(b);
    }

    /* right after removing a body in contact and opening the gate: the history waits, keyed by
     * gid, for the next rebuild, and the walls are dirty */
    run(w, 700);
    remove_body_in_contact(w);
    CHECK(sd_world_set_group_active(w, G_GATE, 0) == SD_OK);
    CHECK(w->keys_collected && w->n_old > 0 && w->w.dirty && w->need_rebuild);
    restart_matches(w, 2000, "restart after remove + gate open");
    sd_world_destroy(w);
}

static void check_refused(const char *path, const char *what, const char *expect)
{
    sd_world *r = (sd_world *)(uintptr_t)1;
    void *extra = (void *)(uintptr_t)1;
    size_t extra_len = 7;
    char msg[256];
    sd_status st = sd_checkpoint_read(path, &r, &extra, &extra_len, msg, sizeof(msg));
    if (st != SD_ERR_FORMAT) fprintf(stderr, "%s: got %s (%s)\n", what, sd_status_message(st), msg);
    CHECK(st == SD_ERR_FORMAT);
    CHECK(r == NULL && extra == NULL && extra_len == 0);
    CHECK(strstr(msg, path) != NULL);
    CHECK(strlen(msg) > strlen(path) + 4);
    if (expect && !strstr(msg, expect)) {
        fprintf(stderr, "%s: message \"%s\" does not mention \"%s\"\n", what, msg, expect);
        CHECK(0);
    }
    sd_world_destroy(r == (sd_world *)(uintptr_t)1 ? NULL : r);
}

/* The carried springs of a checkpoint taken between a removal and the next rebuild: any
 * grouping with one run a first body is read (neighbor.c groups them by store index, earlier
 * versions by gid), a body's keys in two runs are refused. */
static void test_oldh_runs(void)
{
    sd_world *w = make_scene();
    run(w, 3500);
    remove_body_in_contact(w);
    const int m = w->n_old;
    int gid_down = 0; /* the keys not in gid order: grouped by store index */
    for (int k = 1; k < m; k++)
        gid_down |= (w->old_keys[k] >> 32) < (w->old_keys[k - 1] >> 32);
    char path[128], bad[128];
    path_in_dir(path, sizeof(path), "oldh.bin");
    path_in_dir(bad, sizeof(bad), "oldh_bad.bin");
    CHECK(sd_checkpoint_write(path, w, NULL, 0) == SD_OK);
    sd_world_destroy(w);
    size_t n;
    unsigned char *data = read_all(path, &n);
    CHECK(data != NULL);
    if (!data) return;
    sd_world *r = NULL;
    CHECK(sd_checkpoint_read(path, &r, NULL, NULL, NULL, 0) == SD_OK);
    sd_world_destroy(r);
    /* the section: tag, 0, length (8), the flag, the count, then the keys */
    size_t at = 64;
    while (at + 24 < n && !(memcmp(data + at, "OLDH", 4) == 0 && data[at + 4] == 0 && data[at + 5] == 0))
        at++;
    CHECK(at + 24 < n);
    int32_t cnt;
    memcpy(&cnt, data + at + 20, 4);
    CHECK(cnt == m && m >= 3);
    uint64_t *keys = malloc((size_t)m * sizeof(uint64_t));
    CHECK(keys != NULL);
    if (keys && at + 24 + (size_t)m * 8 <= n && cnt == m && m >= 3) {
        memcpy(keys, data + at + 24, (size_t)m * 8);
        int j = 1; /* the first key of another body, then the last key made the first's */
        while (j < m - 1 && keys[j] >> 32 == keys[0] >> 32)
            j++;
        CHECK(j < m - 1);
        keys[m - 1] = (keys[0] & 0xffffffff00000000ULL) | (keys[m - 1] & 0xffffffffULL);
        memcpy(data + at + 24, keys, (size_t)m * 8);
        remake_checksum(data, n);
        write_all(bad, data, n);
        check_refused(bad, "one body's keys in two runs", "not grouped by body");
    }
    printf("carried springs of a checkpoint after a removal: %d entries, %s gid order, read back; one body in two "
           "runs refused\n",
           m, gid_down ? "not in" : "in");
    free(keys);
    free(data);
}

static void test_refused(void)
{
    char good[128], bad[128];
    path_in_dir(good, sizeof(good), "good.bin");
    path_in_dir(bad, sizeof(bad), "bad.bin");
    sd_world *w = make_scene();
    run(w, 500);
    const char blob[] = "driver";
    CHECK(sd_checkpoint_write(good, w, blob, sizeof(blob)) == SD_OK);
    sd_world_destroy(w);
    size_t n;
    unsigned char *data = read_all(good, &n);
    CHECK(data != NULL && n > 1000);
    if (!data) return;
    printf("checkpoint of the 43-element scene: %zu bytes\n", n);

    write_all(bad, data, 0);
    check_refused(bad, "empty", "empty");
    const size_t cuts[] = {1, 7, 8, 40, 63, 64, 65, 100, n / 3, n / 2, n - 17, n - 1};
    for (size_t k = 0; k < sizeof(cuts) / sizeof(cuts[0]); k++) {
        write_all(bad, data, cuts[k]);
        char what[64];
        snprintf(what, sizeof(what), "cut at %zu", cuts[k]);
        check_refused(bad, what, "truncated");
    }
    /* one flipped byte anywhere */
    const size_t flips[] = {0, 5, 9, 13, 17, 26, 33, 41, 50, 64, 70, 200, n / 2, n - 9, n - 1};
    for (size_t k = 0; k < sizeof(flips) / sizeof(flips[0]); k++) {
        data[flips[k]] ^= 0x10;
        write_all(bad, data, n);
        data[flips[k]] ^= 0x10;
        char what[64];
        snprintf(what, sizeof(what), "flip at %zu", flips[k]);
        check_refused(bad, what, flips[k] >= 64 ? "checksum" : NULL);
    }
    memcpy(data, "SABODEMX", 8);
    write_all(bad, data, n);
    check_refused(bad, "wrong magic", "magic");
    memcpy(data, "SABODEMC", 8);
    uint32_t v = SD_CHECKPOINT_VERSION + 1;
    memcpy(data + 8, &v, 4);
    write_all(bad, data, n);
    check_refused(bad, "newer version", "version");
    v = SD_CHECKPOINT_VERSION - 1; /* (version 1: before the materials) */
    memcpy(data + 8, &v, 4);
    write_all(bad, data, n);
    check_refused(bad, "older version", "version");
    v = SD_CHECKPOINT_VERSION;
    memcpy(data + 8, &v, 4);
    write_all(bad, data, n);
    sd_world *r = NULL;
    CHECK(sd_checkpoint_read(bad, &r, NULL, NULL, NULL, 0) == SD_OK); /* restored bytes read again */
    sd_world_destroy(r);
    /* a foreign file and one with trailing garbage */
    write_all(bad, "solid cube\nfacet normal 0 0 1\n", 30);
    check_refused(bad, "foreign", "magic");
    unsigned char *longer = malloc(n + 1);
    if (longer) {
        memcpy(longer, data, n);
        longer[n] = 0;
        write_all(bad, longer, n + 1);
        check_refused(bad, "trailing byte", NULL);
        free(longer);
    }
    /* a file whose checksum matches but whose content is impossible: the first body 7.3e200 m
     * up, then its attitude not a unit quaternion; each refused, naming the body and the value */
    {
        static const struct {
            const char *name;
            int len, at; /* the field's name, its length, the double changed in body 0's element */
            double value;
            const char *expect;
        } bad_values[] = {{"pos", 3, 2, 7.3e200, "impossible position"},
                          {"quat", 4, 0, 3.0, "impossible attitude"},
                          {"mass", 4, 0, -1.0, "impossible mass"}};
        for (size_t bv = 0; bv < sizeof bad_values / sizeof bad_values[0]; bv++) {
            unsigned char *m = malloc(n);
            if (!m) break;
            memcpy(m, data, n);
            size_t at = 0;
            for (size_t k = 64; k + 1 + (size_t)bad_values[bv].len + 4 < n && !at; k++)
                if (m[k] == bad_values[bv].len && !memcmp(m + k + 1, bad_values[bv].name, (size_t)bad_values[bv].len))
                    at = k + 1 + (size_t)bad_values[bv].len + 4; /* (the name, then its element size) */
            CHECK(at > 0);
            if (at) {
                memcpy(m + at + 8 * (size_t)bad_values[bv].at, &bad_values[bv].value, sizeof(double));
                remake_checksum(m, n);
                write_all(bad, m, n);
                check_refused(bad, bad_values[bv].name, bad_values[bv].expect);
            }
            free(m);
        }
    }
    /* a damaged payload whose checksum was made to match (a bug, or a crafted file): every
     * count and index is range-checked, so the read refuses it or gives a usable world */
    {
        sd_rng rng = {42};
        int refused = 0, accepted = 0;
        for (int k = 0; k < 600; k++) {
            unsigned char *m = malloc(n);
            if (!m) break;
            memcpy(m, data, n);
            int nflip = 1 + (int)(sd_rng_next(&rng) % 3);
            for (int f = 0; f < nflip; f++) {
                size_t at = 64 + (size_t)(sd_rng_next(&rng) % (n - 64));
                m[at] = (k & 1) ? (unsigned char)(m[at] ^ (1u << (sd_rng_next(&rng) % 8)))
                                : (unsigned char)sd_rng_next(&rng);
            }
            remake_checksum(m, n);
            write_all(bad, m, n);
            free(m);
            r = NULL;
            sd_status st = sd_checkpoint_read(bad, &r, NULL, NULL, NULL, 0);
            CHECK(st == SD_OK || st == SD_ERR_FORMAT);
            CHECK((st == SD_OK) == (r != NULL));
            if (st == SD_OK)
                accepted++;
            else
                refused++;
            sd_world_destroy(r);
        }
        printf("payload damaged behind a matching checksum: %d refused, %d read\n", refused, accepted);
    }
    free(data);

    /* a missing file is an I/O error, not a format error */
    char missing[128], msg[256];
    path_in_dir(missing, sizeof(missing), "missing.bin");
    r = NULL;
    CHECK(sd_checkpoint_read(missing, &r, NULL, NULL, msg, sizeof(msg)) == SD_ERR_IO);
    CHECK(r == NULL && strstr(msg, missing) != NULL);
}

static void test_failed_write(void)
{
    char good[128], nodir[128];
    path_in_dir(good, sizeof(good), "keep.bin");
    path_in_dir(nodir, sizeof(nodir), "no/such/dir/ck.bin");
    sd_world *w = make_scene();
    run(w, 400);
    CHECK(sd_checkpoint_write(good, w, NULL, 0) == SD_OK);
    size_t n0;
    unsigned char *before = read_all(good, &n0);
    CHECK(before != NULL);
    run(w, 100); /* a newer state that the failed writes try to save */

    CHECK(sd_checkpoint_write(nodir, w, NULL, 0) == SD_ERR_IO);
    struct stat sb;
    char sub[128];
    path_in_dir(sub, sizeof(sub), "no");
    CHECK(stat(sub, &sb) != 0);

    CHECK(sd_checkpoint_write(good, w, NULL, 100) == SD_ERR_ARG); /* extra_len without extra */
    CHECK(sd_checkpoint_write(NULL, w, NULL, 0) == SD_ERR_ARG);
    CHECK(sd_checkpoint_write(good, NULL, NULL, 0) == SD_ERR_ARG);

    const long long fails[] = {0, 10, 63, 64, 65, 1000, (long long)n0 / 2, (long long)n0 - 1};
    for (size_t k = 0; k < sizeof(fails) / sizeof(fails[0]); k++) {
        errno = 0;
        sd_status st = sd_checkpoint_write_capped(good, w, NULL, 0, fails[k]);
        int e = errno;
        CHECK(st == SD_ERR_IO);
        CHECK(e == ENOSPC);
    }
    size_t n1;
    unsigned char *after = read_all(good, &n1);
    CHECK(after && before && n0 == n1 && memcmp(before, after, n0) == 0); /* previous one intact */
    CHECK(count_temp_files() == 0);
    sd_world *r = NULL;
    CHECK(sd_checkpoint_read(good, &r, NULL, NULL, NULL, 0) == SD_OK);
    CHECK(r && r->step == 400);
    sd_world_destroy(r);
    /* and the next write that can succeed replaces it */
    CHECK(sd_checkpoint_write(good, w, NULL, 0) == SD_OK);
    r = NULL;
    CHECK(sd_checkpoint_read(good, &r, NULL, NULL, NULL, 0) == SD_OK);
    CHECK(r && r->step == 500);
    sd_world_destroy(r);
    CHECK(count_temp_files() == 0);
    free(before);
    free(after);
    sd_world_destroy(w);
}

static void remove_dir(void)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char p[512];
    while ((e = readdir(d)) != NULL) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof(p), "%s/%s", dir, e->d_name);
        unlink(p);
    }
    closedir(d);
    rmdir(dir);
}

int main(void)
{
    snprintf(dir, sizeof(dir), "/tmp/sd_ckpt_XXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_restart();
    test_refused();
    test_oldh_runs();
    test_failed_write();
    remove_dir();
    return check_report("test_checkpoint");
}
