/* Candidate search (SPEC §4): against an all-pairs O(N²) check, every overlapping pair is a
 * candidate, every candidate has its gap within the margin (and every pair within the margin is
 * a candidate); after moves smaller than margin/2 without rebuild, every contact is still a
 * candidate; a move beyond margin/2 asks for a rebuild; tangential history survives rebuilds. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

static uint64_t rng_state = 0x2545F4914F6CDD1DULL;
static double urand(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) / 9007199254740992.0;
}

/* the SIMD level of every world here: the CPU's default, or the scalar loops with the argument
 * "scalar" (ctest's test_neighbor_scalar), so that the scalar and the SIMD cell scans both meet
 * the all-pairs truth */
static int g_simd = SD_SIMD_AUTO;

static sd_world *new_world(void)
{
    sd_world_def def = sd_world_def_default();
    def.tuning.simd = g_simd;
    def.check_dt = 0;
    def.parallel_min = 64; /* these scenes are small: the threads' paths too (the owners' near lists) */
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    return w;
}

static double tri_dist(const sd_tri *t, sd_vec3 p)
{
    int f;
    return v3_dist(sd_geom_closest_on_tri(t, p, &f), p);
}

/* Compare the candidate lists with the all-pairs truth. strict: also require every candidate to
 * be within the margin and every pair within the margin to be a candidate (true right after a
 * rebuild). Returns the number of overlapping pairs. */
static long check_candidates(const sd_world *w, int strict, const char *label)
{
    const sd_bodies *b = &w->b;
    const sd_walls *wl = &w->w;
    int n = b->n, nt = wl->n;
    double margin = w->def.margin;
    unsigned char *bbm = calloc((size_t)n * n, 1);
    unsigned char *btm = calloc((size_t)n * (nt > 0 ? nt : 1), 1);
    long dup = 0, far = 0, missing = 0, within = 0, overl = 0;
    for (int k = 0; k < w->bb.n; k++) {
        const sd_pair *p = &w->bb.p[k];
        int i = p->a < p->b ? p->a : p->b, j = p->a < p->b ? p->b : p->a;
        if (bbm[(size_t)i * n + j]++) dup++;
        double gap = v3_dist(b->pos[i], b->pos[j]) - b->radius[i] - b->radius[j];
        if (gap > margin) far++;
        if (b->fixed[i] && b->fixed[j]) far++;
    }
    for (int k = 0; k < w->bt.n; k++) {
        const sd_pair *p = &w->bt.p[k];
        if (btm[(size_t)p->a * nt + p->b]++) dup++;
        if (tri_dist(&wl->tri[p->b], b->pos[p->a]) - b->radius[p->a] > margin) far++;
    }
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            if (b->fixed[i] && b->fixed[j]) continue;
            double gap = v3_dist(b->pos[i], b->pos[j]) - b->radius[i] - b->radius[j];
            if (gap < 0.0) {
                overl++;
                if (!bbm[(size_t)i * n + j]) missing++;
            }
            if (gap <= margin) {
                within++;
                if (strict && !bbm[(size_t)i * n + j]) missing++;
            }
        }
    for (int i = 0; i < n; i++) {
        if (b->fixed[i]) continue;
        for (int t = 0; t < nt; t++) {
            if (!wl->active[t]) continue;
            double gap = tri_dist(&wl->tri[t], b->pos[i]) - b->radius[i];
            if (gap < 0.0) {
                overl++;
                if (!btm[(size_t)i * nt + t]) missing++;
            }
            if (gap <= margin) {
                within++;
                if (strict && !btm[(size_t)i * nt + t]) missing++;
            }
        }
    }
    printf("%-28s bodies %4d tris %3d: candidates %6d + %5d, overlapping %6ld, within margin %6ld, missing %ld, "
           "beyond margin %ld, duplicates %ld\n",
           label, n, nt, w->bb.n, w->bt.n, overl, within, missing, far, dup);
    CHECK(missing == 0);
    CHECK(dup == 0);
    if (strict) {
        CHECK(far == 0);
        CHECK(within == w->bb.n + w->bt.n);
    }
    free(bbm);
    free(btm);
    return overl;
}

static void add_tris(sd_world *w, double L, int random_tris)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double x0 = L * i / 4, x1 = L * (i + 1) / 4, y0 = L * j / 4, y1 = L * (j + 1) / 4;
            sd_world_add_triangle(w, v3(x0, y0, 0), v3(x1, y0, 0), v3(x1, y1, 0), 0);
            sd_world_add_triangle(w, v3(x0, y0, 0), v3(x1, y1, 0), v3(x0, y1, 0), 0);
        }
    for (int k = 0; k < random_tris; k++) {
        sd_vec3 c = v3(L * urand(), L * urand(), L * urand());
        sd_vec3 v[3];
        for (int q = 0; q < 3; q++)
            v[q] = v3_add(c, v3(0.04 * (urand() - 0.5), 0.04 * (urand() - 0.5), 0.04 * (urand() - 0.5)));
        CHECK(sd_world_add_triangle(w, v[0], v[1], v[2], 1 + k % 2) >= 0);
    }
}

/* A world under gravity in the box of add_tris (side L), its candidates rebuilt only on
 * displacement (t_reset 1 s): the near lists' tests. */
static sd_world *drift_box(double L)
{
    sd_world *w = new_world();
    w->def.gravity = v3(0, 0, -9.81);
    w->def.t_reset = 1.0;
    add_tris(w, L, 0);
    return w;
}

/* dense: jittered lattice with spacing below the mean diameter (many overlaps); loose: random */
static void test_static(int dense)
{
    sd_world *w = new_world();
    const int side = 9;
    const double L = dense ? 0.0105 * side : 0.25;
    add_tris(w, L, 12);
    for (int i = 0; i < side; i++)
        for (int j = 0; j < side; j++)
            for (int k = 0; k < side; k++) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = dense ? 0.0045 + 0.002 * urand() : 0.0025 + 0.0035 * urand();
                if (dense)
                    s.pos = v3(0.0105 * (i + 0.5 + 0.2 * (urand() - 0.5)), 0.0105 * (j + 0.5 + 0.2 * (urand() - 0.5)),
                               0.0105 * (k + 0.5 + 0.2 * (urand() - 0.5)));
                else
                    s.pos = v3(L * urand(), L * urand(), L * urand());
                s.fixed = urand() < 0.1;
                CHECK(sd_world_add_sphere(w, &s) >= 0);
            }
    /* one body flung far away must neither be lost nor blow up the grid */
    sd_sphere_def s = sd_sphere_def_default();
    s.pos = v3(50.0, -30.0, 20.0);
    CHECK(sd_world_add_sphere(w, &s) >= 0);
    sd_world_set_group_active(w, 2, 0); /* inactive triangles are never candidates */
    CHECK(sd_neighbor_rebuild(w) == SD_OK);
    long ov = check_candidates(w, 1, dense ? "dense, after rebuild" : "loose, after rebuild");
    if (dense) CHECK(ov > 500);
    for (int k = 0; k < w->bt.n; k++)
        CHECK(w->w.active[w->bt.p[k].b]);
    /* move every moving body by less than margin/2 in a random direction, no rebuild */
    double step = 0.49 * w->def.margin;
    for (int i = 0; i < w->b.n; i++) {
        if (w->b.fixed[i]) continue;
        sd_vec3 d = v3(urand() - 0.5, urand() - 0.5, urand() - 0.5);
        w->b.pos[i] = v3_madd(w->b.pos[i], v3_normalize(d), step * urand());
    }
    check_candidates(w, 0, dense ? "dense, moved < margin/2" : "loose, moved < margin/2");
    sd_world_destroy(w);
}

/* The near list (contact.c), when the next step will use it as it is: every touching sphere
 * pair of the candidate list must be in it. Counts the steps checked, those where the list was
 * shorter than the candidates, and the touching pairs missing. */
static long near_logs_out;  /* log pairs left out of the near list, summed over the checks */
static long near_by_owners; /* checks of the owners' segments (two threads) */

static long flags_wrong, flags_checked; /* near_check: spring flags against their slots */
static long rs2_wrong; /* near_check: the entries' (r_a + r_b)^2 (a float) against the radii, and -1 for the others */
/* near_check: the pairs holding a spring, each marked near (near_mark) as the spring
 * collection at the next rebuild takes for granted (it reads no other pair's slots) */
static long marks_checked, marks_wrong;

static double rs2_of(const sd_world *w, const sd_pair *p)
{
    const double rs = w->b.radius[p->a] + w->b.radius[p->b];
    return rs * rs;
}

/* an entry's rs2 not what contact.c's entry_rs2 makes of its pair: a sphere pair's (r_a + r_b)^2
 * rounded to a float (NaN outside [2^-100, 2^100]), -1 for any other kind */
static int rs2_bad(float got, const sd_world *w, const sd_pair *p)
{
    if (p->kind != SD_PAIR_SS) return got != -1.0f;
    const double r = rs2_of(w, p);
    if (!(r >= 0x1p-100 && r <= 0x1p100)) return !isnan(got);
    /* (and within 2^-24 of the double, which the AVX2 filter's band takes for granted) */
    return got != (float)r || fabs((double)got - r) > 0x1p-24 * r;
}

static void near_check(const sd_world *w, long *checked, long *shorter, long *missing)
{
    if (sd_neighbor_needs_rebuild(w) || w->near_stamp != w->timers.rebuilds ||
        !(2.0 * w->near_drift < 0.999 * w->near_skin))
        return;
    /* the current near pairs: the serial pass's list, or the owners' segments in owner order
     * (each ascending, the owners' candidates in turn) */
    static int32_t near[1 << 20];
    int nn = 0;
    if (w->bb.n > (int)(sizeof near / sizeof near[0])) {
        CHECK(!"scene too large for near_check");
        return;
    }
    /* each near sphere pair's flag (sd_pair_soa.act) says whether its slot holds a spring,
     * as the slot does: the touch filter reads the flag instead */
    sd_near_springs_home((sd_world *)w); /* (the list's springs into their slots) */
    const sd_hist *hist = w->bb.hist;
    if (w->near_soa_version == w->near_version + 1) {
        for (int j = 0; j < w->near_n; j++) {
            near[nn++] = w->near[j];
            const sd_pair *p = &w->bb.p[w->near[j]];
            if (p->kind == SD_PAIR_SS) flags_wrong += w->near_soa.act[j] != (hist[p->off].feature >= 0);
            rs2_wrong += rs2_bad(w->near_soa.rs2[j], w, p);
            flags_checked += p->kind == SD_PAIR_SS;
        }
    } else if (w->owned && w->owned->stamp == w->near_version) {
        const sd_owned *o = w->owned;
        near_by_owners++;
        for (int t = 0; t < o->T; t++)
            for (int j = o->K[t]; j < o->seg1[t]; j++) {
                const int own = o->list[j] >= 0;
                near[nn++] = own ? o->list[j] : o->cross[~o->list[j]];
                const sd_pair *p = &w->bb.p[near[nn - 1]];
                const uint8_t act = own ? o->soa.act[j] : o->xsoa.act[~o->list[j]];
                if (p->kind == SD_PAIR_SS) flags_wrong += act != (hist[p->off].feature >= 0);
                /* (a cross entry: its record in xsoa, and -1 in the owner's list) */
                rs2_wrong += own ? rs2_bad(o->soa.rs2[j], w, p)
                                 : rs2_bad(o->xsoa.rs2[~o->list[j]], w, p) + (o->soa.rs2[j] != -1.0f);
                flags_checked += p->kind == SD_PAIR_SS;
            }
    } else {
        CHECK(!"no current near list");
        return;
    }
    if (w->near_mark_rb == w->timers.rebuilds)
        for (int k = 0; k < w->bb.n; k++) {
            const sd_pair *p = &w->bb.p[k];
            int held = 0;
            for (int s = 0; s < p->cap; s++)
                held |= hist[p->off + s].feature >= 0;
            marks_checked += held;
            marks_wrong += held && !w->near_mark[k];
        }
    int unordered = 0;
    for (int j = 1; j < nn; j++)
        unordered += near[j] <= near[j - 1];
    CHECK(unordered == 0);
    (*checked)++;
    *shorter += nn < w->bb.n;
    int j = 0;
    for (int k = 0; k < w->bb.n; k++) {
        while (j < nn && near[j] < k)
            j++;
        if (j < nn && near[j] == k) continue;
        const sd_pair *p = &w->bb.p[k];
        if (p->kind == SD_PAIR_SS) {
            if (v3_dist(w->b.pos[p->a], w->b.pos[p->b]) < w->b.radius[p->a] + w->b.radius[p->b]) (*missing)++;
            continue;
        }
        near_logs_out++;
        sd_manifold m;
        const sd_cyl cb = sd_body_cyl(&w->b, p->b);
        if (p->kind == SD_PAIR_SC) {
            sd_geom_sphere_cyl(w->b.pos[p->a], w->b.radius[p->a], &cb, &m);
        } else {
            const sd_cyl ca = sd_body_cyl(&w->b, p->a);
            sd_geom_cyl_cyl(&ca, &cb, &m);
        }
        *missing += m.n > 0;
    }
}

/* Spheres on a lattice settling gently onto a floor, and six logs thrown down on them,
 * tumbling. */
static sd_world *settling_world(void)
{
    const double L = 0.08;
    sd_world *w = drift_box(L);
    for (int i = 0; i < 8; i++)
        for (int j = 0; j < 8; j++)
            for (int k = 0; k < 3; k++) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = 0.0025 + 0.0015 * urand();
                s.pos = v3(0.005 + 0.0082 * i, 0.005 + 0.0082 * j, 0.0042 + 0.0082 * k);
                s.vel = v3(0.05 * (urand() - 0.5), 0.05 * (urand() - 0.5), 0.05 * (urand() - 0.5));
                CHECK(sd_world_add_sphere(w, &s) >= 0);
            }
    /* and logs dropped onto them, tumbling */
    for (int k = 0; k < 6; k++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.radius = 0.003;
        c.length = 0.03;
        /* 4 cm apart (longer than a log): no log starts touching another */
        c.pos = v3(0.02 + 0.04 * (k & 1), 0.02 + 0.04 * ((k >> 1) & 1), 0.045 + 0.04 * (k >> 2));
        c.axis = v3_normalize(v3(urand() - 0.5, urand() - 0.5, urand() - 0.5));
        c.omega = v3(20.0 * (urand() - 0.5), 20.0 * (urand() - 0.5), 20.0 * (urand() - 0.5));
        c.vel = v3(0.0, 0.0, -1.5); /* thrown down: faster than any sphere until they meet */
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    return w;
}

/* The settling lattice and logs (below 2.5 m/s): the near list is remade on drift, leaves
 * pairs out (logs' too), and never a touching one. */
static void test_near_slow(void)
{
    sd_world *w = settling_world();
    near_logs_out = 0;
    long checked = 0, shorter = 0, missing = 0, max_contacts = 0;
    const long near0 = w->near_version;
    double vmax = 0.0;
    long log_touch = 0; /* log pairs in contact, summed over the steps */
    for (int st = 0; st < 9000; st++) {
        CHECK(sd_world_step(w) == SD_OK);
        near_check(w, &checked, &shorter, &missing);
        for (int k = 0; k < w->bb.n; k++)
            if (w->bb.p[k].kind != SD_PAIR_SS)
                for (int q = 0; q < w->bb.p[k].cap; q++)
                    log_touch += w->bb.hist[w->bb.p[k].off + q].feature >= 0;
        if (sd_world_contact_count(w) > max_contacts) max_contacts = sd_world_contact_count(w);
        for (int i = 0; i < w->b.n; i++)
            if (v3_norm(w->b.vel[i]) > vmax) vmax = v3_norm(w->b.vel[i]);
    }
    const long rebuilds = sd_world_get_timers(w).rebuilds;
    printf("near list, settling lattice and logs: top speed %.3f m/s, %ld versions, %ld rebuilds, checked at %ld "
           "steps (%ld shorter than the candidates, %ld log pairs left out), max contacts %ld, touching pairs "
           "missing %ld\n",
           vmax, w->near_version - near0, rebuilds, checked, shorter, near_logs_out, max_contacts, missing);
    printf("log contact points, summed over the steps: %ld\n", log_touch);
    CHECK(near_logs_out > 2000 && log_touch > 1000);
    CHECK(vmax < 2.5);
    CHECK(missing == 0);
    CHECK(checked > 6000 && shorter > 6000 && max_contacts > 80);
    CHECK(w->near_version - near0 > rebuilds + 10); /* remade on drift, not only with the candidates */
    sd_world_destroy(w);
}

/* A heap of spinning logs (log-log pairs near by their axis segments' distance, whatever they
 * turn): no touching pair is ever left out of the near list. */
static void test_near_logs(void)
{
    const double L = 0.08;
    sd_world *w = drift_box(L);
    /* a crib: ten layers of four logs 1 cm apart, crossing the layer below, then set spinning */
    for (int k = 0; k < 40; k++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        const int layer = k / 4, j = k % 4;
        c.radius = 0.002 + 0.001 * urand();
        c.length = 0.03 + 0.01 * urand();
        const double u = 0.025 + 0.01 * j;
        c.pos = layer & 1 ? v3(u, 0.04, 0.0035 + 0.0075 * layer) : v3(0.04, u, 0.0035 + 0.0075 * layer);
        c.axis = layer & 1 ? v3(0.1 * (urand() - 0.5), 1.0, 0.1 * (urand() - 0.5))
                           : v3(1.0, 0.1 * (urand() - 0.5), 0.1 * (urand() - 0.5));
        c.omega = v3(40.0 * (urand() - 0.5), 40.0 * (urand() - 0.5), 40.0 * (urand() - 0.5));
        c.vel = v3(0.2 * (urand() - 0.5), 0.2 * (urand() - 0.5), -0.2 * urand());
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    near_logs_out = 0;
    long checked = 0, shorter = 0, missing = 0, cc_touch = 0;
    for (int st = 0; st < 6000; st++) {
        CHECK(sd_world_step(w) == SD_OK);
        near_check(w, &checked, &shorter, &missing);
        for (int k = 0; k < w->bb.n; k++)
            if (w->bb.p[k].kind == SD_PAIR_CC)
                for (int q = 0; q < w->bb.p[k].cap; q++)
                    cc_touch += w->bb.hist[w->bb.p[k].off + q].feature >= 0;
    }
    printf("near list, a heap of spinning logs: checked at %ld steps (%ld shorter than the candidates, %ld log pairs "
           "left out), log-log contact points summed %ld, touching pairs missing %ld\n",
           checked, shorter, near_logs_out, cc_touch, missing);
    CHECK(missing == 0);
    CHECK(checked > 3000 && shorter > 3000 && near_logs_out > 10000);
    CHECK(cc_touch > 5000);
    sd_world_destroy(w);
}

/* Falling spheres onto a floor, rebuilds by margin and t_reset only: at every step without a
 * pending rebuild, every contact must be a candidate (and every touching pair near). */
static void test_dynamic(void)
{
    const double L = 0.08;
    sd_world *w = drift_box(L);
    for (int k = 0; k < 150; k++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = 0.0025 + 0.0025 * urand();
        s.pos = v3(0.006 + (L - 0.012) * urand(), 0.006 + (L - 0.012) * urand(), 0.006 + 0.04 * urand());
        s.vel = v3(0.5 * (urand() - 0.5), 0.5 * (urand() - 0.5), -0.5 - 1.5 * urand());
        CHECK(sd_world_add_sphere(w, &s) >= 0);
    }
    long missing_steps = 0, checked = 0, max_contacts = 0, near_missing = 0, near_checked = 0, near_short = 0;
    long rebuilds0 = sd_world_get_timers(w).rebuilds, near0 = w->near_version;
    for (int st = 0; st < 3000; st++) {
        CHECK(sd_world_step(w) == SD_OK);
        if (sd_world_contact_count(w) > max_contacts) max_contacts = sd_world_contact_count(w);
        near_check(w, &near_checked, &near_short, &near_missing);
        if (sd_neighbor_needs_rebuild(w) || st % 10) continue;
        checked++;
        const sd_bodies *b = &w->b;
        /* inline quick check (the verbose one prints) */
        for (int i = 0; i < b->n; i++)
            for (int j = i + 1; j < b->n; j++) {
                if (v3_dist(b->pos[i], b->pos[j]) >= b->radius[i] + b->radius[j]) continue;
                int found = 0;
                for (int k = 0; k < w->bb.n && !found; k++)
                    found = (w->bb.p[k].a == i && w->bb.p[k].b == j) || (w->bb.p[k].a == j && w->bb.p[k].b == i);
                if (!found) missing_steps++;
            }
        for (int i = 0; i < b->n; i++)
            for (int t = 0; t < w->w.n; t++) {
                if (tri_dist(&w->w.tri[t], b->pos[i]) >= b->radius[i]) continue;
                int found = 0;
                for (int k = w->csr.bt_start[i]; k < w->csr.bt_start[i + 1] && !found; k++)
                    found = w->bt.p[k].b == t;
                if (!found) missing_steps++;
            }
    }
    long rebuilds = sd_world_get_timers(w).rebuilds - rebuilds0;
    printf("dynamic: 3000 steps, %ld rebuilds (displacement-triggered), %ld checks, missing contacts %ld, "
           "max contacts %ld\n",
           rebuilds, checked, missing_steps, max_contacts);
    printf("near list: %ld versions, checked at %ld steps (%ld of them shorter than the candidate list), touching "
           "pairs missing %ld\n",
           w->near_version - near0, near_checked, near_short, near_missing);
    CHECK(near_missing == 0);
    CHECK(near_checked > 1000);
    CHECK(missing_steps == 0);
    CHECK(rebuilds > 1 && rebuilds < 3000);
    CHECK(max_contacts > 20);
    sd_world_destroy(w);

    /* a single move beyond margin/2 flags a rebuild */
    w = new_world();
    w->def.gravity = v3(0, 0, 0);
    sd_sphere_def s = sd_sphere_def_default();
    s.vel = v3(0.51 * w->def.margin / w->def.dt, 0, 0);
    sd_world_add_sphere(w, &s);
    CHECK(sd_world_step(w) == SD_OK);
    CHECK(w->need_rebuild == 1);
    sd_world_destroy(w);
}

/* first live history slot of the pair (kind, body gid) */
static int find_hist(const sd_world *w, int bt, int gid, sd_vec3 *shear)
{
    sd_near_springs_home((sd_world *)w); /* (a near list's springs into their slots) */
    const sd_pairlist *l = bt ? &w->bt : &w->bb;
    int i = w->gid_map[gid];
    for (int k = 0; k < l->n; k++) {
        const sd_pair *p = &l->p[k];
        if (p->a != i && p->b != i) continue;
        for (int s = 0; s < p->cap; s++)
            if (l->hist[p->off + s].feature >= 0) {
                *shear = l->hist[p->off + s].shear;
                return 1;
            }
    }
    return 0;
}

/* sliding sphere on a floor of 2 triangles (bt history) and a sphere sliding off a fixed
 * sphere (bb history) */
static sd_world *history_world(int rebuild_every_step, int *gid_bt, int *gid_bb)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(0, 0, -9.81);
    def.contact.tan_phi = 0.1;
    def.tuning.simd = g_simd;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    sd_world_set_rebuild_every_step(w, rebuild_every_step);
    sd_world_add_triangle(w, v3(-0.1, -0.1, 0), v3(0.1, -0.1, 0), v3(0.1, 0.1, 0), 0);
    sd_world_add_triangle(w, v3(-0.1, -0.1, 0), v3(0.1, 0.1, 0), v3(-0.1, 0.1, 0), 0);
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = 0.01;
    double m = s.density * 4.0 / 3.0 * M_PI * 1e-6;
    s.pos = v3(-0.05, -0.02, 0.01 - m * 9.81 / def.contact.k_n);
    s.vel = v3(0.8, 0.3, 0);
    *gid_bt = sd_world_add_sphere(w, &s);
    sd_sphere_def f = sd_sphere_def_default();
    f.radius = 0.01;
    f.fixed = 1;
    f.pos = v3(0.05, 0.05, 0.1);
    sd_world_add_sphere(w, &f);
    double d = 0.02 - m * 9.81 / def.contact.k_n; /* about the equilibrium overlap */
    s.pos = v3(0.05 + 0.003, 0.05 + 0.001, 0.1 + sqrt(d * d - 0.003 * 0.003 - 0.001 * 0.001));
    s.vel = v3(0, 0, 0);
    *gid_bb = sd_world_add_sphere(w, &s);
    return w;
}

static void test_history(void)
{
    int gbt, gbb;
    sd_world *w = history_world(0, &gbt, &gbb);
    CHECK(sd_world_run(w, 300) == SD_OK);
    sd_vec3 s_bt = v3(0, 0, 0), s_bb = v3(0, 0, 0), s2 = v3(0, 0, 0);
    CHECK(find_hist(w, 1, gbt, &s_bt));
    CHECK(find_hist(w, 0, gbb, &s_bb));
    printf("history before rebuild: floor shear %.6g N (limit %.6g N), sphere shear %.6g N\n", v3_norm(s_bt),
           0.1 * 0.01 * 0.01 * 0.01 * 4.0 / 3.0 * M_PI * 1900 * 9.81, v3_norm(s_bb));
    CHECK(v3_norm(s_bt) > 0.0);
    CHECK(v3_norm(s_bb) > 0.0);
    CHECK(sd_neighbor_rebuild(w) == SD_OK);
    CHECK(find_hist(w, 1, gbt, &s2));
    CHECK(s2.x == s_bt.x && s2.y == s_bt.y && s2.z == s_bt.z);
    CHECK(find_hist(w, 0, gbb, &s2));
    CHECK(s2.x == s_bb.x && s2.y == s_bb.y && s2.z == s_bb.z);
    /* adding a body elsewhere takes the history out by gid and puts it back */
    sd_sphere_def far = sd_sphere_def_default();
    far.pos = v3(1, 1, 1);
    far.fixed = 1;
    sd_world_add_sphere(w, &far);
    CHECK(sd_neighbor_rebuild(w) == SD_OK);
    CHECK(find_hist(w, 1, gbt, &s2));
    CHECK(s2.x == s_bt.x && s2.y == s_bt.y && s2.z == s_bt.z);
    CHECK(find_hist(w, 0, gbb, &s2));
    CHECK(s2.x == s_bb.x && s2.y == s_bb.y && s2.z == s_bb.z);
    sd_world_destroy(w);

    /* rebuild every step vs by margin: the same trajectory */
    int g1, g2, h1, h2;
    sd_world *a = history_world(1, &g1, &h1), *b = history_world(0, &g2, &h2);
    double dmax = 0.0;
    for (int k = 0; k < 20000; k++) {
        CHECK(sd_world_step(a) == SD_OK);
        CHECK(sd_world_step(b) == SD_OK);
    }
    sd_body_state A, B;
    int ids[2][2] = {{g1, g2}, {h1, h2}};
    for (int q = 0; q < 2; q++) {
        sd_world_body(a, ids[q][0], &A);
        sd_world_body(b, ids[q][1], &B);
        dmax = fmax(dmax, v3_dist(A.pos, B.pos));
        CHECK_VEC_NEAR(A.pos, B.pos, 1e-12);
        CHECK_VEC_NEAR(A.vel, B.vel, 1e-10);
        CHECK_VEC_NEAR(A.omega, B.omega, 1e-8);
    }
    printf("rebuild every step vs by margin over 0.2 s: max position difference %.3g m (rebuilds %ld vs %ld)\n", dmax,
           sd_world_get_timers(a).rebuilds, sd_world_get_timers(b).rebuilds);
    sd_world_destroy(a);
    sd_world_destroy(b);
}

/* The springs carried across a rebuild (neighbor.c collect, old_ranges, restore_history):
 * every spring held before a rebuild is held after it, bit for bit, when its pair is still a
 * candidate, and no other is. The settling lattice and its tumbling logs change cells, so the
 * rebuild's sort moves bodies that hold springs (the lookup through the sort), and every third
 * rebuild the springs are taken out before it (as a removal or a gate does: the lookup by gid). */
typedef struct {
    int32_t ga, kind, idb, feature;
    sd_vec3 shear;
} held_spring;

static int cmp_held(const void *x, const void *y)
{
    const held_spring *a = x, *b = y;
    if (a->ga != b->ga) return a->ga < b->ga ? -1 : 1;
    if (a->kind != b->kind) return a->kind < b->kind ? -1 : 1;
    if (a->idb != b->idb) return a->idb < b->idb ? -1 : 1;
    return (a->feature > b->feature) - (a->feature < b->feature);
}

/* every held spring of both lists (pairs only, feature -2: the pairs themselves) */
static held_spring *held_springs(sd_world *w, int pairs, int *n_out)
{
    sd_near_springs_home(w);
    int n = 0, cap = 1024;
    held_spring *h = malloc((size_t)cap * sizeof *h);
    CHECK(h != NULL);
    const sd_pairlist *lists[2] = {&w->bb, &w->bt};
    for (int q = 0; q < 2; q++)
        for (int k = 0; k < lists[q]->n; k++) {
            const sd_pair *p = &lists[q]->p[k];
            const int tri = p->kind == SD_PAIR_ST || p->kind == SD_PAIR_CT;
            for (int s = 0; s < (pairs ? 1 : p->cap); s++) {
                const sd_hist *e = &lists[q]->hist[p->off + s];
                if (!pairs && e->feature < 0) continue;
                if (n == cap) {
                    cap *= 2;
                    h = realloc(h, (size_t)cap * sizeof *h);
                    CHECK(h != NULL);
                }
                h[n++] = (held_spring){w->b.gid[p->a], p->kind, tri ? p->b : w->b.gid[p->b], pairs ? -2 : e->feature,
                                       pairs ? v3(0, 0, 0) : e->shear};
            }
        }
    qsort(h, (size_t)n, sizeof *h, cmp_held);
    *n_out = n;
    return h;
}

static void test_history_sorted(void)
{
    sd_world *w = settling_world();
    long kept = 0, dropped = 0, moved_rounds = 0;
    int by_gid_rounds = 0;
    CHECK(sd_world_run(w, 1500) == SD_OK); /* (landed: springs held) */
    for (int r = 0; r < 30; r++) {
        CHECK(sd_world_run(w, 60) == SD_OK);
        int nb, na, np;
        held_spring *before = held_springs(w, 0, &nb);
        if (r % 3 == 2) { /* taken out first: the lookup by gid */
            CHECK(sd_history_collect(w) == SD_OK);
            by_gid_rounds += nb > 0;
        }
        CHECK(sd_neighbor_rebuild(w) == SD_OK);
        moved_rounds += w->rb_perm_m > 0 && nb > 0;
        held_spring *after = held_springs(w, 0, &na);
        held_spring *pairs = held_springs(w, 1, &np);
        /* each spring before: held after, the same bits, iff its pair is still there */
        int k = 0;
        for (int i = 0; i < nb; i++) {
            held_spring key = before[i];
            key.feature = -2;
            const int still = bsearch(&key, pairs, (size_t)np, sizeof *pairs, cmp_held) != NULL;
            while (k < na && cmp_held(&after[k], &before[i]) < 0) {
                CHECK(0); /* held after, not before */
                k++;
            }
            if (still) {
                CHECK(k < na && cmp_held(&after[k], &before[i]) == 0);
                if (k < na && cmp_held(&after[k], &before[i]) == 0) {
                    CHECK(memcmp(&after[k].shear, &before[i].shear, sizeof(sd_vec3)) == 0);
                    k++;
                }
                kept++;
            } else {
                CHECK(k >= na || cmp_held(&after[k], &before[i]) != 0);
                dropped++;
            }
        }
        CHECK(k == na);
        free(before);
        free(after);
        free(pairs);
    }
    printf("springs carried across 30 rebuilds: %ld kept bit for bit, %ld with their pair gone; rounds with "
           "held springs and bodies moved by the sort %ld, taken out before the rebuild %d\n",
           kept, dropped, moved_rounds, by_gid_rounds);
    CHECK(kept > 500 && moved_rounds >= 20 && by_gid_rounds >= 8);
    sd_world_destroy(w);
}

/* The bed cache (neighbor.c): a floor of fixed spheres (the bed) under spheres dropped on it,
 * stepped with the cache and without: the same state at every check, the candidates exact
 * right after a rebuild, and the cache used for most rebuilds, also across a body removed, a
 * body added and one flying off past the bed's corner (the grid's origin moved by whole
 * cells, then the columns changed). */
static sd_world *bed_world(void)
{
    sd_world *w = new_world();
    w->def.gravity = v3(0, 0, -9.81);
    const double L = 0.08;
    add_tris(w, L, 0);
    rng_state = 0x9E3779B97F4A7C15ULL;
    for (int i = 0; i < 16; i++)
        for (int j = 0; j < 16; j++) {
            sd_sphere_def s = sd_sphere_def_default();
            s.radius = 0.002 + 0.0005 * urand();
            s.pos = v3(0.0025 + 0.005 * i, 0.0025 + 0.005 * j, 0.002);
            s.fixed = 1;
            CHECK(sd_world_add_sphere(w, &s) >= 0);
        }
    for (int k = 0; k < 120; k++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = 0.0015 + 0.002 * urand();
        s.pos = v3(0.006 + (L - 0.012) * urand(), 0.006 + (L - 0.012) * urand(), 0.008 + 0.03 * urand());
        s.vel = v3(0.2 * (urand() - 0.5), 0.2 * (urand() - 0.5), -0.5 * urand());
        CHECK(sd_world_add_sphere(w, &s) >= 0);
    }
    return w;
}

/* bed_world with 12 logs falling among the spheres */
static sd_world *bed_world_logs(void)
{
    sd_world *w = bed_world();
    for (int k = 0; k < 12; k++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.radius = 0.0015;
        c.length = 0.015 + 0.01 * urand();
        c.pos = v3(0.01 + 0.06 * urand(), 0.01 + 0.06 * urand(), 0.04 + 0.01 * urand());
        c.axis = v3_normalize(v3(urand() - 0.5, urand() - 0.5, urand() - 0.5));
        c.vel = v3(0.0, 0.0, -0.5);
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    return w;
}

static void test_bed_cache(void)
{
    sd_world *w[2];
    for (int c = 0; c < 2; c++) {
        w[c] = bed_world();
        sd_world_switch(w[c], SD_SW_BED_CACHE, c == 0);
    }
    long checks = 0, differ = 0, strict = 0;
    int gone = -1;
    for (int st = 1; st <= 1500; st++) {
        for (int c = 0; c < 2; c++) {
            if (st == 400) CHECK(sd_world_remove_body(w[c], w[c]->b.gid[w[c]->b.n / 3]) == SD_OK);
            if (st == 700) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = 0.003;
                s.pos = v3(0.04, 0.04, 0.03);
                CHECK(sd_world_add_sphere(w[c], &s) >= 0);
                /* one more that leaves past the bed's low corner, then beyond the columns */
                s.radius = 0.002;
                s.pos = v3(0.01, 0.01, 0.02);
                s.vel = v3(-20.0, -10.0, 0.0);
                gone = sd_world_add_sphere(w[c], &s);
                CHECK(gone >= 0);
            }
            CHECK(sd_world_step(w[c]) == SD_OK);
        }
        if (st % 50 == 0) {
            checks++;
            differ += sd_world_state_hash(w[0]) != sd_world_state_hash(w[1]);
        }
        if (st % 300 == 0) { /* a rebuild now, in both worlds, then the exact candidates */
            for (int c = 0; c < 2; c++)
                CHECK(sd_neighbor_rebuild(w[c]) == SD_OK);
            check_candidates(w[0], 1, "bed cache, after a rebuild");
            strict++;
            /* the store in cell order, x slowest, the bed last (the rebuild's sort) */
            const sd_grid *g = &w[0]->grid;
            long prev = -1, unsorted = 0;
            for (int i = 0; i < w[0]->b.n; i++) {
                const sd_vec3 p = w[0]->b.pos[i];
                const long cx = (long)floor((p.x - g->lo.x) / g->cell), cy = (long)floor((p.y - g->lo.y) / g->cell),
                           cz = (long)floor((p.z - g->lo.z) / g->cell);
                const long key = ((cx * g->ny + cy) * g->nz + cz) +
                                 (sd_body_is_bed(&w[0]->b, i) ? (long)g->nx * g->ny * g->nz : 0);
                unsorted += key < prev;
                prev = key;
            }
            CHECK(unsorted == 0);
        }
    }
    sd_body_state bs;
    CHECK(sd_world_body(w[0], gone, &bs) == SD_OK);
    const long rb = sd_world_get_timers(w[0]).rebuilds;
    printf("bed cache: %ld rebuilds, %ld from the cache (%ld in the world without it), %ld of %ld checks differ, "
           "strict candidate checks %ld, the flying sphere at (%.3f, %.3f), grid origin (%.4f, %.4f, %.4f)\n",
           rb, w[0]->bed.used, w[1]->bed.used, differ, checks, strict, bs.pos.x, bs.pos.y, w[0]->grid.lo.x,
           w[0]->grid.lo.y, w[0]->grid.lo.z);
    CHECK(differ == 0);
    CHECK(checks == 30);
    CHECK(w[1]->bed.used == 0);
    CHECK(w[0]->bed.used > rb / 2 && w[0]->bed.used < rb - 3); /* it was made afresh at least 4 times */
    CHECK(bs.pos.x < -0.05 && bs.pos.y < -0.03); /* it got past the bed's corner */
    CHECK(strict == 5);
    for (int c = 0; c < 2; c++)
        sd_world_destroy(w[c]);
}

/* The wall pass over the bodies near a wall only (contact.c wall_near_range): spheres
 * dropped on a floor with tilted triangles about, stepped with it and without, on one thread
 * (the serial pass) and on all (the owners): the same state at every check, wall contacts
 * made, and bodies with wall pairs skipped. */
static void test_wall_near(void)
{
    int threads[2] = {1, 1};
#ifdef _OPENMP
    threads[1] = omp_get_max_threads();
#endif
    for (int h = 0; h < 2; h++) {
#ifdef _OPENMP
        const int T0 = omp_get_max_threads();
        omp_set_num_threads(threads[h]);
#endif
        sd_world *w[2];
        for (int c = 0; c < 2; c++) {
            w[c] = new_world();
            w[c]->def.gravity = v3(0, 0, -9.81);
            rng_state = 0x3C6EF372FE94F82BULL;
            const double L = 0.08;
            add_tris(w[c], L, 12);
            for (int k = 0; k < 150; k++) {
                sd_sphere_def sd = sd_sphere_def_default();
                sd.radius = 0.0025 + 0.0025 * urand();
                sd.pos = v3(0.006 + (L - 0.012) * urand(), 0.006 + (L - 0.012) * urand(), 0.004 + 0.012 * urand());
                sd.vel = v3(0.5 * (urand() - 0.5), 0.5 * (urand() - 0.5), -0.5 - 1.5 * urand());
                CHECK(sd_world_add_sphere(w[c], &sd) >= 0);
            }
            /* and logs, spinning as they fall: listed by their extent along each wall's
             * normal, which their turning changes */
            for (int k = 0; k < 24; k++) {
                sd_cylinder_def cd = sd_cylinder_def_default();
                cd.radius = 0.0015;
                cd.length = 0.012 + 0.008 * urand();
                cd.pos = v3(0.012 + (L - 0.024) * urand(), 0.012 + (L - 0.024) * urand(), 0.01 + 0.02 * urand());
                cd.axis = v3(urand() - 0.5, urand() - 0.5, 0.6 * (urand() - 0.5));
                cd.vel = v3(0.3 * (urand() - 0.5), 0.3 * (urand() - 0.5), -0.3 - urand());
                cd.omega = v3(60.0 * (urand() - 0.5), 60.0 * (urand() - 0.5), 60.0 * (urand() - 0.5));
                CHECK(sd_world_add_cylinder(w[c], &cd) >= 0);
            }
        }
        long differ = 0, touching = 0, log_touching = 0;
        for (int st = 1; st <= 3000; st++) {
            for (int c = 0; c < 2; c++) {
                sd_world_switch(w[c], SD_SW_WALL_NEAR, c == 0);
                CHECK(sd_world_step(w[c]) == SD_OK);
            }
            for (int k = 0; k < w[0]->bt.n; k++) {
                touching += w[0]->bt.active[k];
                log_touching += w[0]->bt.active[k] && w[0]->b.shape[w[0]->bt.p[k].a] != SD_SHAPE_SPHERE;
            }
            if (st % 100 == 0) differ += sd_world_state_hash(w[0]) != sd_world_state_hash(w[1]);
        }
        printf("wall pass near walls only, %d thread(s): %ld of 30 checks differ, wall contacts summed over the steps %ld "
               "(logs %ld), bodies skipped %ld (%ld without)\n",
               threads[h], differ, touching, log_touching, w[0]->wall_skipped, w[1]->wall_skipped);
        CHECK(differ == 0);
        CHECK(touching > 3000);
        CHECK(log_touching > 500);
        CHECK(w[0]->wall_skipped > 1000);
        CHECK(w[1]->wall_skipped == 0);
        for (int c = 0; c < 2; c++)
            sd_world_destroy(w[c]);
#ifdef _OPENMP
        omp_set_num_threads(T0);
#endif
    }
}

/* The fixed bodies' scan through the moving bodies' lists (a dam of many fixed pipes) against
 * the scan of the grid's own lists: the same state, step for step. */
static void test_moving_index(void)
{
    sd_world *w[2];
    for (int c = 0; c < 2; c++) {
        w[c] = new_world();
        w[c]->def.gravity = v3(0, 0, -9.81);
        rng_state = 0xBB67AE8584CAA73BULL;
        add_tris(w[c], 0.08, 0);
        for (int i = 0; i < 9; i++) /* 81 fixed pipes standing on the floor, a grid dam */
            for (int j = 0; j < 9; j++) {
                sd_cylinder_def cd = sd_cylinder_def_default();
                cd.pos = v3(0.004 + 0.009 * i, 0.004 + 0.009 * j, 0.015);
                cd.axis = v3(0, 0, 1);
                cd.radius = 0.0015;
                cd.length = 0.03;
                cd.fixed = 1;
                CHECK(sd_world_add_cylinder(w[c], &cd) >= 0);
            }
        for (int k = 0; k < 120; k++) {
            sd_sphere_def sd = sd_sphere_def_default();
            sd.radius = 0.0015 + 0.0015 * urand();
            sd.pos = v3(0.004 + 0.072 * urand(), 0.004 + 0.072 * urand(), 0.035 + 0.02 * urand());
            sd.vel = v3(0.3 * (urand() - 0.5), 0.3 * (urand() - 0.5), -1.0 * urand());
            CHECK(sd_world_add_sphere(w[c], &sd) >= 0);
        }
    }
    long differ = 0, contacts = 0;
    for (int st = 1; st <= 2000; st++) {
        for (int c = 0; c < 2; c++) {
            sd_world_switch(w[c], SD_SW_MOVING_INDEX_MIN, c == 0 ? 64 : 1 << 30);
            CHECK(sd_world_step(w[c]) == SD_OK);
        }
        contacts += sd_world_contact_count(w[0]);
        if (st % 100 == 0) differ += sd_world_state_hash(w[0]) != sd_world_state_hash(w[1]);
    }
    printf("fixed pipes through the moving lists: %ld of 20 checks differ, contacts summed %ld, rebuilds %ld\n",
           differ, contacts, sd_world_get_timers(w[0]).rebuilds);
    CHECK(differ == 0);
    CHECK(contacts > 2000);
    for (int c = 0; c < 2; c++)
        sd_world_destroy(w[c]);
}

/* The rebuild on one thread and on three (the grid filled by runs of bodies, the chunks' lists
 * joined at their places): the same grid, entry for entry, and the same lists, pair for pair,
 * for a bed under falling spheres and logs, at several moments. */
static void test_rebuild_threads(void)
{
#ifdef _OPENMP
    sd_world *w = bed_world_logs();
    long compared = 0, entries = 0, differ = 0;
    for (int round = 0; round < 6; round++) {
        sd_world_set_threads(w, 2);
        for (int st = 0; st < 150; st++)
            CHECK(sd_world_step(w) == SD_OK);
        /* the same store for both: rebuilt once (sorted), then on 1 thread and on 3 */
        CHECK(sd_neighbor_rebuild(w) == SD_OK);
        const sd_grid *g = &w->grid;
        int32_t *snap[2] = {NULL, NULL};
        size_t len[2] = {0, 0};
        for (int v = 0; v < 2; v++) {
            sd_world_set_threads(w, v == 0 ? 1 : 3);
            CHECK(sd_neighbor_rebuild(w) == SD_OK);
            const int ncell = g->nx * g->ny * g->nz, nitems = g->cell_start[ncell], n = w->b.n;
            const int nslot = w->reg0[n];
            /* cells, items, flags, reg0, slots, then each body-body and body-triangle pair */
            len[v] = (size_t)(ncell + 1) + (size_t)nitems * 2 + (size_t)(n + 1) + (size_t)nslot +
                     (size_t)w->bb.n * 5 + (size_t)w->bt.n * 3 + 4;
            int32_t *q = snap[v] = malloc(len[v] * sizeof(int32_t));
            CHECK(q != NULL);
            if (!q) return;
            *q++ = ncell, *q++ = nitems, *q++ = w->bb.n, *q++ = w->bt.n;
            for (int c = 0; c <= ncell; c++)
                *q++ = g->cell_start[c];
            for (int k = 0; k < nitems; k++)
                *q++ = g->items[k], *q++ = w->gflag[k];
            for (int i = 0; i <= n; i++)
                *q++ = w->reg0[i];
            for (int e = 0; e < nslot; e++)
                *q++ = w->slot[e];
            for (int k = 0; k < w->bb.n; k++) {
                const sd_pair *p = &w->bb.p[k];
                *q++ = p->a, *q++ = p->b, *q++ = p->off, *q++ = p->cap, *q++ = p->kind;
            }
            for (int k = 0; k < w->bt.n; k++) {
                const sd_pair *p = &w->bt.p[k];
                *q++ = p->a, *q++ = p->b, *q++ = p->off;
            }
        }
        compared++;
        entries += (long)len[0];
        differ += len[0] != len[1] || memcmp(snap[0], snap[1], len[0] * sizeof(int32_t)) != 0;
        free(snap[0]);
        free(snap[1]);
    }
    printf("rebuild on 1 and 3 threads: %ld states compared (%ld words), %ld differ; bed cache used %ld times\n",
           compared, entries, differ, w->bed.used);
    CHECK(differ == 0);
    CHECK(compared == 6 && entries > 10000);
    CHECK(w->bed.used > 10);
    sd_world_destroy(w);
#endif
}

/* A bed under falling spheres and logs: pairs with the bed are near within half the skin (the
 * bed does not move), and still no touching pair is ever left out of the near list. */
static void test_near_bed(void)
{
    sd_world *w = drift_box(0.08);
    for (int i = 0; i < 16; i++) /* the bed roughness */
        for (int j = 0; j < 16; j++) {
            sd_sphere_def s = sd_sphere_def_default();
            s.radius = 0.002 + 0.0005 * urand();
            s.pos = v3(0.0025 + 0.005 * i, 0.0025 + 0.005 * j, 0.002);
            s.fixed = 1;
            CHECK(sd_world_add_sphere(w, &s) >= 0);
        }
    for (int i = 0; i < 10; i++) /* a layer of spheres just above it, jostled */
        for (int j = 0; j < 10; j++) {
            sd_sphere_def s = sd_sphere_def_default();
            s.radius = 0.002 + 0.001 * urand();
            s.pos = v3(0.008 + 0.007 * i, 0.008 + 0.007 * j, 0.0075);
            s.vel = v3(0.2 * (urand() - 0.5), 0.2 * (urand() - 0.5), -0.2 * urand());
            CHECK(sd_world_add_sphere(w, &s) >= 0);
        }
    for (int k = 0; k < 8; k++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.radius = 0.0015;
        c.length = 0.015 + 0.01 * urand();
        /* two rows of four, 17 mm apart across their axes: none touches another to start */
        c.pos = v3(0.015 + 0.017 * (k & 3), 0.025 + 0.03 * (k >> 2), 0.02);
        c.axis = v3_normalize(v3(0.2 * (urand() - 0.5), 1.0, 0.4 * (urand() - 0.5)));
        c.omega = v3(20.0 * (urand() - 0.5), 20.0 * (urand() - 0.5), 20.0 * (urand() - 0.5));
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    long checked = 0, shorter = 0, missing = 0, bed_touch = 0;
    for (int st = 0; st < 6000; st++) {
        CHECK(sd_world_step(w) == SD_OK);
        /* a sphere thrown out of the box by an overlap of the random start would set the near
         * list's drift at every step: gone */
        for (int i = 0; i < w->b.n; i++)
            if (!w->b.fixed[i] && (w->b.pos[i].z < 0.0 || w->b.pos[i].x < 0.0 || w->b.pos[i].x > 0.08 ||
                                   w->b.pos[i].y < 0.0 || w->b.pos[i].y > 0.08))
                CHECK(sd_world_remove_body(w, w->b.gid[i--]) == SD_OK);
        if (st % 3) continue; /* (every third step) */
        near_check(w, &checked, &shorter, &missing);
        for (int k = 0; k < w->bb.n; k++) {
            const sd_pair *p = &w->bb.p[k];
            if (sd_body_is_bed(&w->b, p->a) || sd_body_is_bed(&w->b, p->b))
                bed_touch += w->bb.hist[p->off].feature >= 0;
        }
    }
    printf("near list over a bed: checked at %ld steps (%ld shorter than the candidates), contacts with the bed "
           "summed %ld, touching pairs missing %ld\n",
           checked, shorter, bed_touch, missing);
    CHECK(missing == 0);
    CHECK(checked > 1000 && shorter > 1000 && bed_touch > 5000);
    sd_world_destroy(w);
}

/* The body-body candidates of a rebuild as words (a, b, kind each), into a new array. */
static int32_t *bb_words(const sd_world *w, int *len)
{
    int32_t *q = malloc(((size_t)3 * w->bb.n + 1) * sizeof(int32_t));
    CHECK(q != NULL);
    if (!q) return NULL;
    for (int k = 0; k < w->bb.n; k++)
        q[3 * k] = w->bb.p[k].a, q[3 * k + 1] = w->bb.p[k].b, q[3 * k + 2] = w->bb.p[k].kind;
    *len = 3 * w->bb.n;
    return q;
}

/* The candidates of a rebuild without (snap[0]) and with (snap[1]) the scan's prefilter, as
 * bb_words gives them. */
static void prefilter_snaps(sd_world *w, int32_t *snap[2], int len[2])
{
    for (int v = 0; v < 2; v++) {
        sd_world_switch(w, SD_SW_SCAN_PRE, v);
        CHECK(sd_neighbor_rebuild(w) == SD_OK);
        snap[v] = bb_words(w, &len[v]);
    }
}

/* The scan's float prefilter (switch SD_SW_SCAN_PRE) leaves the candidates as they were, pair for
 * pair and in order: on a bed under falling spheres and logs at several moments, and on pairs
 * of spheres set at their reach (r_a + r_b + margin) less and more 2e-9 of it, 1 m, 100 m and
 * 10 km from the origin, where a float's rounding is far larger than that: each pair just
 * within reach is a candidate, each just beyond is not. (Off a CPU with AVX2 both runs take
 * the exact test alone.) */
static void test_scan_prefilter(void)
{
    sd_world *w = bed_world_logs();
    long compared = 0, pairs = 0, differ = 0;
    for (int round = 0; round < 6; round++) {
        for (int st = 0; st < 150; st++)
            CHECK(sd_world_step(w) == SD_OK);
        CHECK(sd_neighbor_rebuild(w) == SD_OK); /* (sorted once: the same store for both) */
        int32_t *snap[2];
        int len[2] = {0, 0};
        prefilter_snaps(w, snap, len);
        compared++;
        pairs += len[0] / 3;
        differ += len[0] != len[1] || !snap[0] || !snap[1] || memcmp(snap[0], snap[1], (size_t)len[0] * 4) != 0;
        free(snap[0]);
        free(snap[1]);
    }
    printf("scan prefilter on the bed: %ld rebuilds compared (%ld pairs), %ld differ\n", compared, pairs, differ);
    CHECK(differ == 0 && compared == 6 && pairs > 1000);
    sd_world_destroy(w);

    const double far[4] = {1.0, 100.0, 1e4, -1e4};
    for (int f = 0; f < 4; f++) {
        w = new_world();
        const double m = w->def.margin;
        int inside = 0;
        for (int k = 0; k < 40; k++) {
            const double ra = 0.001 + 0.009 * urand(), rb = 0.001 + 0.009 * urand();
            const int in = k % 2 == 0;
            const double d = (ra + rb + m) * (in ? 1.0 - 2e-9 : 1.0 + 2e-9);
            const sd_vec3 u = v3_normalize(v3(urand() - 0.5, urand() - 0.5, urand() - 0.5));
            const sd_vec3 c = v3(far[f] + 0.1 * k, far[f] + 0.01 * urand(), far[f] + 0.01 * urand());
            sd_sphere_def a = sd_sphere_def_default(), b = sd_sphere_def_default();
            a.radius = ra, b.radius = rb;
            a.pos = c, b.pos = v3_madd(c, u, d);
            CHECK(sd_world_add_sphere(w, &a) >= 0);
            CHECK(sd_world_add_sphere(w, &b) >= 0);
            inside += in;
        }
        int32_t *snap[2];
        int len[2] = {0, 0};
        prefilter_snaps(w, snap, len);
        /* each pair's own two bodies, whatever order the store put them in */
        int found = 0;
        for (int k = 0; k < w->bb.n; k++) {
            const int ga = w->b.gid[w->bb.p[k].a], gb = w->b.gid[w->bb.p[k].b];
            const int lo = ga < gb ? ga : gb, hi = ga < gb ? gb : ga; /* (pair q: gids 2q, 2q + 1) */
            found += lo % 2 == 0 && hi == lo + 1 && (lo / 2) % 2 == 0;
        }
        printf("spheres at their reach %g m out: %d candidates with the prefilter, %d without, %d of %d pairs "
               "within reach found\n",
               far[f], len[1] / 3, len[0] / 3, found, inside);
        CHECK(len[0] == len[1] && snap[0] && snap[1] && memcmp(snap[0], snap[1], (size_t)len[0] * 4) == 0);
        CHECK(found == inside && w->bb.n == inside);
        free(snap[0]);
        free(snap[1]);
        sd_world_destroy(w);
    }
}

/* sd_bodies_permute (the rebuild's re-sort, which copies only the blocks the permutation maps onto
 * themselves): after it, body i holds every field of the body that was at perm[i], for
 * permutations with fixed stretches, short swaps, a rotation, a reversal and one whole shuffle,
 * over a store of spheres and logs (fields of 1, 4, 8, 24 and 32 bytes). */
static void test_permute(void)
{
    enum { N = 300 };
    sd_world *w = new_world();
    for (int i = 0; i < N; i++) {
        if (i % 7 == 3) {
            sd_cylinder_def c = sd_cylinder_def_default();
            c.pos = v3(0.1 * i, 0.02 * (i % 5), 0.3);
            c.axis = v3(1.0, 0.1 * (i % 3), 0.2);
            c.vel = v3(0.01 * i, -0.2, 0.0);
            c.radius = 0.01 + 1e-5 * i;
            c.length = 0.1;
            c.tag = i;
            CHECK(sd_world_add_cylinder(w, &c) >= 0);
        } else {
            sd_sphere_def d = sd_sphere_def_default();
            d.pos = v3(0.1 * i, -0.03 * (i % 4), 0.1);
            d.vel = v3(-0.01 * i, 0.3, 0.0);
            d.omega = v3(0.0, 0.0, 0.5 * i);
            d.radius = 0.005 + 1e-5 * i;
            d.tag = i;
            CHECK(sd_world_add_sphere(w, &d) >= 0);
        }
    }
    sd_bodies *b = &w->b;
    CHECK(b->n == N);
    int32_t perm[N];
    int32_t gid0[N], tag0[N];
    sd_vec3 pos0[N], vel0[N];
    sd_quat q0[N];
    double r0[N];
    uint8_t sh0[N];
    for (int form = 0; form < 6; form++) {
        for (int i = 0; i < N; i++)
            perm[i] = i;
        if (form == 0) { /* a few swaps of neighbours, apart */
            for (int i = 10; i + 1 < N; i += 37) {
                perm[i] = i + 1;
                perm[i + 1] = i;
            }
        } else if (form == 1) { /* a body moved 5 places back, the others one on */
            for (int i = 50; i < 55; i++)
                perm[i] = i + 1;
            perm[55] = 50;
        } else if (form == 2) { /* blocks that touch: [0, 3) rotated, then [3, 5) swapped */
            perm[0] = 2, perm[1] = 0, perm[2] = 1, perm[3] = 4, perm[4] = 3;
        } else if (form == 3) { /* the last entries (the block ends at n) */
            perm[N - 3] = N - 1, perm[N - 2] = N - 3, perm[N - 1] = N - 2;
        } else if (form == 4) { /* reversed whole */
            for (int i = 0; i < N; i++)
                perm[i] = N - 1 - i;
        } else { /* shuffled whole (Fisher-Yates, fixed seed) */
            for (int i = N - 1; i > 0; i--) {
                const int j = (int)(urand() * (i + 1)) % (i + 1);
                const int32_t t = perm[i];
                perm[i] = perm[j];
                perm[j] = t;
            }
        }
        for (int i = 0; i < N; i++) {
            gid0[i] = b->gid[i], tag0[i] = b->tag[i], pos0[i] = b->pos[i], vel0[i] = b->vel[i];
            q0[i] = b->quat[i], r0[i] = b->radius[i], sh0[i] = b->shape[i];
        }
        CHECK(sd_bodies_permute(b, perm, N, 2) == SD_OK);
        int wrong = 0;
        for (int i = 0; i < N; i++) {
            const int o = perm[i];
            wrong += b->gid[i] != gid0[o] || b->tag[i] != tag0[o] || b->shape[i] != sh0[o] || b->radius[i] != r0[o] ||
                     memcmp(&b->pos[i], &pos0[o], sizeof(sd_vec3)) || memcmp(&b->vel[i], &vel0[o], sizeof(sd_vec3)) ||
                     memcmp(&b->quat[i], &q0[o], sizeof(sd_quat));
        }
        CHECK(wrong == 0);
    }
    /* the gids scattered: the world's map put back, as the rebuild's sort does */
    for (int i = 0; i < N; i++)
        w->gid_map[b->gid[i]] = i;
    CHECK(sd_world_step(w) == SD_OK);
    sd_world_destroy(w);
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "scalar")) g_simd = SD_SIMD_SCALAR;
    test_static(1);
    test_static(0);
    test_dynamic();
    test_near_slow();
    test_history();
    test_history_sorted();
    test_bed_cache();
    test_wall_near();
    test_near_logs();
    test_near_bed();
    test_rebuild_threads();
    test_moving_index();
    test_scan_prefilter();
    test_permute();
    printf("near-list checks of the owners' segments (two or more threads): %ld\n", near_by_owners);
    printf("near sphere pairs whose spring flag was checked against the slot: %ld, wrong %ld; (r_a + r_b)^2 wrong "
           "%ld\n",
           flags_checked, flags_wrong, rs2_wrong);
    CHECK(flags_checked > 100000 && flags_wrong == 0);
    CHECK(rs2_wrong == 0);
    printf("pairs holding a spring checked for their near mark: %ld, unmarked %ld\n", marks_checked, marks_wrong);
    CHECK(marks_checked > 100000 && marks_wrong == 0);
#ifdef _OPENMP
    if (omp_get_max_threads() > 1) CHECK(near_by_owners > 1000);
#endif
    return check_report("test_neighbor");
}
