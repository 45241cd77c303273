/* The decomposition into slabs along x (src/slabs.c, docs/decomposition.md), all the slabs in one
 * process: a pile of spheres and logs sliding down a 15° box along x, stepped in one world with a
 * fixed grid and in 1, 2, 3 and 4 slab worlds from the same state (springs included): the same
 * canonical state hash every 250 steps, while bodies change owner, the boundaries move by
 * the counted work and once by hand, and ghosts come and go. Also the engine's support on its
 * own: a body's record put into another world reads back the same bytes, a ghost is not moved,
 * the springs listed and put back give the same pairs their springs. */
#include <string.h>

#include "check.h"
#include "scenes.h"
#include "core/vmath.h"
#include "sabodem.h"
#include "slabs.h"
#include "slab_scene.h"

/* a record put into a world of its own reads back the same bytes; a ghost keeps its state over a
 * step while the body beside it, a copy not a ghost, moves */
static void test_records(void)
{
    sd_grid_def g;
    sd_world *w = make_scene(&g);
    const size_t sz = sd_body_record_size();
    char *a = malloc(sz), *b = malloc(sz);
    CHECK(sd_world_body_record(w, 7, a) == SD_OK);
    CHECK(sd_body_record_gid(a) == 7);
    sd_world_def def = *sd_world_definition(w);
    sd_world *v = NULL;
    CHECK(sd_world_create(&def, &v) == SD_OK);
    CHECK(sd_world_body_put(v, a, 1) == SD_OK);
    CHECK(sd_world_body_count(v) == 1);
    CHECK(sd_world_body_is_ghost(v, 7) == 1);
    CHECK(sd_world_body_record(v, 7, b) == SD_OK);
    CHECK(memcmp(a, b, sz) == 0);
    CHECK(sd_world_body_record(v, 6, b) == SD_ERR_NOTFOUND);
    /* gid 8 as an ordinary body, far from 7 */
    CHECK(sd_world_body_record(w, 8, b) == SD_OK);
    CHECK(sd_world_body_put(v, b, 0) == SD_OK);
    CHECK(sd_world_run(v, 10) == SD_OK);
    sd_body_state s7, s8, w8;
    CHECK(sd_world_body(v, 7, &s7) == SD_OK);
    CHECK(sd_world_body(v, 8, &s8) == SD_OK);
    CHECK(sd_world_body(w, 8, &w8) == SD_OK);
    char *c = malloc(sz);
    CHECK(sd_world_body_record(v, 7, c) == SD_OK);
    {
        sd_body_state was;
        CHECK(sd_world_body(w, 7, &was) == SD_OK);
        CHECK(s7.pos.x == was.pos.x && s7.pos.z == was.pos.z); /* the ghost did not move */
    }
    CHECK(s8.pos.x != w8.pos.x); /* the ordinary body did */
    /* back to an ordinary body: it moves */
    CHECK(sd_world_body_put(v, c, 0) == SD_OK);
    CHECK(sd_world_body_is_ghost(v, 7) == 0);
    CHECK(sd_world_run(v, 10) == SD_OK);
    CHECK(sd_world_body(v, 7, &s8) == SD_OK);
    CHECK(s8.pos.z != s7.pos.z);
    /* a shape that does not match is refused */
    CHECK(sd_world_body_record(w, sd_world_body_count(w) - 1, c) == SD_OK); /* (a log) */
    memcpy(c, a, sizeof(int32_t));                                          /* (as gid 7, a sphere) */
    CHECK(sd_world_body_put(v, c, 0) == SD_ERR_ARG);
    sd_world_destroy(v);
    free(a);
    free(b);
    free(c);
    sd_world_destroy(w);
}

/* The springs a world lists, put back into it after they were taken out by a rebuild's request:
 * the same state (the put ones of the same key are dropped for its own) */
static void test_springs(void)
{
    sd_grid_def g;
    sd_world *w = make_scene(&g), *u = make_scene(&g);
    CHECK(sd_world_run(w, 200) == SD_OK);
    CHECK(sd_world_run(u, 200) == SD_OK);
    const int n = sd_world_springs(w, NULL, 0);
    CHECK(n > 100);
    sd_spring *s = malloc((size_t)n * sizeof(sd_spring));
    CHECK(sd_world_springs(w, s, n) == n);
    int walls = 0;
    for (int k = 0; k < n; k++)
        walls += s[k].kind >= 3;
    CHECK(walls > 10 && walls < n);
    CHECK(sd_world_springs_put(w, s, n) == SD_OK); /* takes them out, puts them back */
    CHECK(sd_world_springs(w, NULL, 0) == n);
    sd_world_request_rebuild(u);
    CHECK(sd_world_needs_rebuild(w) && sd_world_needs_rebuild(u));
    CHECK(sd_world_run(w, 100) == SD_OK);
    CHECK(sd_world_run(u, 100) == SD_OK);
    CHECK(sd_world_state_hash(w) == sd_world_state_hash(u));
    CHECK(sd_world_state_hash_canonical(w) == sd_world_state_hash_canonical(u));
    free(s);
    sd_world_destroy(w);
    sd_world_destroy(u);
}

static void test_slabs(void)
{
    sd_grid_def g;
    sd_world *w = make_scene(&g);
    give_speed(w, 0.6);
    CHECK(sd_world_run(w, 300) == SD_OK);
    CHECK(sd_world_springs(w, NULL, 0) > 100);
    enum { NS = 4 };
    sd_slabs *s[NS];
    for (int k = 0; k < NS; k++) {
        sd_slabs_opts o = {.n = k + 1, .rebalance = 2};
        CHECK(sd_slabs_create(w, &g, &o, &s[k]) == SD_OK);
    }
    sd_world_request_rebuild(w); /* (the slab worlds make their pairs afresh at their first step) */
    const double G = sd_slabs_ghost_width(s[3]);
    CHECK(G > 2 * 0.0202 && G < 2 * 0.0205 + 0.0051);
    double b0[NS + 1];
    sd_slabs_bounds(s[3], b0);
    for (int q = 1; q <= 6; q++) {
        CHECK(sd_world_run(w, 250) == SD_OK);
        const uint64_t h = sd_world_state_hash_canonical(w);
        for (int k = 0; k < NS; k++) {
            const sd_status rs = sd_slabs_run(s[k], 250);
            if (rs) fprintf(stderr, "%d slabs: %s\n", k + 1, sd_status_message(rs));
            CHECK(rs == SD_OK);
            const uint64_t hk = sd_slabs_state_hash(s[k]);
            if (hk != h) fprintf(stderr, "step %d, %d slabs: %016llx, one world %016llx\n", 250 * q, k + 1,
                                 (unsigned long long)hk, (unsigned long long)h);
            CHECK(hk == h);
        }
        if (q == 3) { /* the boundaries moved by hand too: the middle one by a slab's width */
            double x[NS];
            sd_slabs_bounds(s[2], x);
            const double m[4] = {0, x[1] + 0.08, x[2] + 0.08};
            CHECK(sd_slabs_set_bounds(s[2], m) == SD_OK);
        }
    }
    for (int k = 1; k < NS; k++) {
        const sd_slabs_stats t = sd_slabs_get_stats(s[k]);
        printf("%d slabs: %ld steps, %ld redistributions, %ld migrations, %ld boundary moves, %ld ghost records, "
               "%ld springs sent, %.0f kB\n",
               k + 1, t.steps, t.rebuilds, t.migrations, t.boundary_moves, t.ghost_records, t.springs_sent,
               t.bytes / 1e3);
        CHECK(t.steps == 1500);
        CHECK(t.rebuilds >= 15);
        CHECK(t.migrations > 10);
        CHECK(t.boundary_moves >= k);
        int owned = 0;
        for (int j = 0; j <= k; j++)
            owned += sd_slabs_owned(s[k], j);
        CHECK(owned == sd_world_body_count(w));
    }
    double b1[NS + 1];
    sd_slabs_bounds(s[3], b1);
    printf("4 slabs: boundaries %.4f %.4f %.4f -> %.4f %.4f %.4f (ghost width %.4f m)\n", b0[1], b0[2], b0[3], b1[1],
           b1[2], b1[3], G);
    for (int k = 0; k < NS; k++)
        sd_slabs_destroy(s[k]);
    sd_world_destroy(w);
}

int main(void)
{
    test_records();
    test_springs();
    test_slabs();
    return check_report("test_slabs");
}
