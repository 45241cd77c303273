/* Independent reference for the cylinder kernels by dense point sampling.
 *
 * For random overlapping (or nearly overlapping) pairs — log-log (phi 10 x 100 mm), log-sphere
 * (r 2.5-10 mm), log-triangle — the reference overlap is the deepest penetration of a sampled
 * surface point of either solid into the other: max over points x of A of depth_B(x) and over
 * points y of B of depth_A(y), with depth = minus the exact signed distance (closed forms
 * written here, independent of the kernels). A triangle is a thin plate: it touches the
 * cylinder iff one of its points lies inside the cylinder; a cylinder point penetrates it when
 * it projects inside the triangle and lies on the far side of the plane from the cylinder
 * centre, as deep as the shorter way back (through the plane or around the nearest edge). Coarse surface grids are refined locally around the deepest
 * sample. Reported and asserted per pair type, at the levels docs/geometry.md prints (LEVELS):
 * missed contacts (kernel: no contact, reference: overlap > 0.01 mm), false contacts (kernel:
 * contact, reference: gap > 0.01 mm), and the error of the kernel's deepest overlap against the
 * reference, for the shallow pairs (reference <= 0.5 mm, the DEM regime) and for all. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "core/rng.h"
#include "geom/geom.h"
#include "geom_ref.h"

#define SD_PI 3.14159265358979323846

static sd_rng rng = {0x243f6a8885a308d3ULL}; /* the engine's splitmix64 (core/rng.h) */
static double urand(void) { return sd_rng_uniform(&rng); }
static double urange(double lo, double hi) { return sd_rng_range(&rng, lo, hi); }
static sd_vec3 rand_unit(void)
{
    for (;;) {
        sd_vec3 v = v3(urange(-1, 1), urange(-1, 1), urange(-1, 1));
        double n = v3_norm(v);
        if (n > 0.1 && n <= 1.0) return v3_scale(v, 1.0 / n);
    }
}

/* exact signed distances: sdf_cyl (geom_ref.h, written independently of the kernels) */
/* ---- parametrised surface samples of a cylinder: part 0 side (u = t, v = angle),
 * part 1/2 end disk -/+ (u = radius, v = angle) ---- */
typedef struct {
    sd_vec3 u, v; /* frame perpendicular to the axis */
} frame;
static frame cyl_frame(const sd_cyl *c)
{
    frame f;
    f.u = v3_any_perp(c->a);
    f.v = v3_cross(c->a, f.u);
    return f;
}
static sd_vec3 cyl_point(const sd_cyl *c, const frame *f, int part, double pu, double pv)
{
    sd_vec3 dir = v3_add(v3_scale(f->u, cos(pv)), v3_scale(f->v, sin(pv)));
    if (part == 0) return v3_add(v3_madd(c->c, c->a, pu), v3_scale(dir, c->r));
    double e = part == 1 ? -1.0 : 1.0;
    return v3_add(v3_madd(c->c, c->a, e * c->hl), v3_scale(dir, pu));
}

/* depth function of the "other" solid */
typedef struct {
    int kind; /* 0 cylinder, 1 sphere, 2 triangle plate seen from cylinder centre cc */
    sd_cyl cyl;
    sd_vec3 sc;
    double sr;
    sd_tri tri;
    sd_vec3 cc;
} other;

static int in_triangle(const sd_tri *t, sd_vec3 p)
{
    for (int k = 0; k < 3; k++) {
        sd_vec3 e = v3_sub(t->v[(k + 1) % 3], t->v[k]);
        if (v3_dot(v3_cross(e, v3_sub(p, t->v[k])), t->n) < 0.0) return 0;
    }
    return 1;
}

static double seg_dist(sd_vec3 p, sd_vec3 a, sd_vec3 b)
{
    sd_vec3 ab = v3_sub(b, a);
    double s = v3_dot(v3_sub(p, a), ab) / v3_norm2(ab);
    s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    return v3_dist(p, v3_madd(a, ab, s));
}

static double depth_in(const other *o, sd_vec3 x)
{
    if (o->kind == 0) return -sdf_cyl(&o->cyl, x);
    if (o->kind == 1) return o->sr - v3_dist(x, o->sc);
    /* thin plate seen from the cylinder centre: a point beyond the plane over the triangle is
     * as deep as the shorter way back, through the plane or around the nearest edge */
    double sx = v3_dot(v3_sub(x, o->tri.v[0]), o->tri.n);
    double scc = v3_dot(v3_sub(o->cc, o->tri.v[0]), o->tri.n);
    if (sx * scc > 0.0 || !in_triangle(&o->tri, v3_madd(x, o->tri.n, -sx))) return -1.0;
    double dd = fabs(sx);
    for (int k = 0; k < 3; k++) dd = fmin(dd, seg_dist(x, o->tri.v[k], o->tri.v[(k + 1) % 3]));
    return dd;
}

/* deepest sampled point of cylinder c's surface in o: coarse grid, then two local refinements */
/* sampling resolution: fine for the reference, coarse for placing pairs near contact */
static int coarse = 0;

static double cyl_deepest(const sd_cyl *c, const other *o)
{
    frame f = cyl_frame(c);
    const int nt = coarse ? 41 : 201, na = coarse ? 24 : 96, nr = coarse ? 4 : 12;
    double best = -INFINITY, bu = 0, bv = 0;
    int bp = 0;
    for (int part = 0; part < 3; part++) {
        int nu = part == 0 ? nt : nr;
        for (int i = 0; i < nu; i++) {
            double pu = part == 0 ? -c->hl + 2.0 * c->hl * i / (nt - 1) : c->r * i / (nr - 1);
            for (int j = 0; j < na; j++) {
                double pv = 2.0 * SD_PI * j / na;
                double dd = depth_in(o, cyl_point(c, &f, part, pu, pv));
                if (dd > best) {
                    best = dd;
                    bu = pu;
                    bv = pv;
                    bp = part;
                }
            }
        }
    }
    double du = bp == 0 ? 2.0 * c->hl / (nt - 1) : c->r / (nr - 1), dv = 2.0 * SD_PI / na;
    for (int lev = 0; lev < (coarse ? 2 : 3); lev++) {
        double cu = bu, cv = bv;
        for (int i = -10; i <= 10; i++) {
            double pu = cu + du * i / 10.0;
            if (bp == 0 ? fabs(pu) > c->hl : (pu < 0.0 || pu > c->r)) continue;
            for (int j = -10; j <= 10; j++) {
                double pv = cv + dv * j / 10.0;
                double dd = depth_in(o, cyl_point(c, &f, bp, pu, pv));
                if (dd > best) {
                    best = dd;
                    bu = pu;
                    bv = pv;
                }
            }
        }
        du /= 10.0;
        dv /= 10.0;
    }
    return best;
}

static double sphere_deepest(sd_vec3 sc, double sr, const sd_cyl *c)
{
    /* latitude-longitude grid, then refinement */
    const int nth = 120, nph = 240;
    double best = -INFINITY, bt = 0, bph = 0;
    for (int i = 0; i <= nth; i++) {
        double th = SD_PI * i / nth;
        for (int j = 0; j < nph; j++) {
            double ph = 2.0 * SD_PI * j / nph;
            sd_vec3 x = v3_add(sc, v3(sr * sin(th) * cos(ph), sr * sin(th) * sin(ph), sr * cos(th)));
            double dd = -sdf_cyl(c, x);
            if (dd > best) {
                best = dd;
                bt = th;
                bph = ph;
            }
        }
    }
    double dt = SD_PI / nth, dp = 2.0 * SD_PI / nph;
    for (int lev = 0; lev < 3; lev++) {
        double ct = bt, cp = bph;
        for (int i = -10; i <= 10; i++)
            for (int j = -10; j <= 10; j++) {
                double th = ct + dt * i / 10.0, ph = cp + dp * j / 10.0;
                sd_vec3 x = v3_add(sc, v3(sr * sin(th) * cos(ph), sr * sin(th) * sin(ph), sr * cos(th)));
                double dd = -sdf_cyl(c, x);
                if (dd > best) {
                    best = dd;
                    bt = th;
                    bph = ph;
                }
            }
        dt /= 10.0;
        dp /= 10.0;
    }
    return best;
}

static double tri_deepest(const sd_tri *t, const sd_cyl *c)
{
    /* barycentric grid with about 0.5 mm spacing, restricted to the cylinder's bounding sphere */
    double len = fmax(v3_dist(t->v[0], t->v[1]), fmax(v3_dist(t->v[1], t->v[2]), v3_dist(t->v[2], t->v[0])));
    int n = (int)(len / (coarse ? 0.002 : 0.0005)) + 2;
    double R = sqrt(c->r * c->r + c->hl * c->hl);
    double best = -INFINITY, bu = 0, bv = 0;
    sd_vec3 e1 = v3_sub(t->v[1], t->v[0]), e2 = v3_sub(t->v[2], t->v[0]);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n - i; j++) {
            double u = (double)i / n, v = (double)j / n;
            sd_vec3 x = v3_add(t->v[0], v3_add(v3_scale(e1, u), v3_scale(e2, v)));
            if (v3_dist(x, c->c) > R) continue;
            double dd = -sdf_cyl(c, x);
            if (dd > best) {
                best = dd;
                bu = u;
                bv = v;
            }
        }
    if (best == -INFINITY) return best;
    double du = 1.0 / n;
    for (int lev = 0; lev < 3; lev++) {
        double cu = bu, cv = bv;
        for (int i = -10; i <= 10; i++)
            for (int j = -10; j <= 10; j++) {
                double u = cu + du * i / 10.0, v = cv + du * j / 10.0;
                if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
                double dd = -sdf_cyl(c, v3_add(t->v[0], v3_add(v3_scale(e1, u), v3_scale(e2, v))));
                if (dd > best) {
                    best = dd;
                    bu = u;
                    bv = v;
                }
            }
        du /= 10.0;
    }
    return best;
}

/* ---- statistics ---- */
typedef struct {
    const char *name;
    int pairs, ref_touch, kern_touch, missed, missed_deep, false_pos, both;
    double err_sum, err2_sum, err_max, err_min, rel_max;
    double worst_miss;
    int within_1um, within_10um;
    /* the same for shallow overlaps (reference <= 0.5 mm), the DEM regime */
    int sh_n, sh_1um, sh_10um;
    double sh_sum, sh2_sum, sh_min, sh_max;
} stats;

static void stats_add(stats *s, double ref, const sd_manifold *m)
{
    const double tol = 1e-5; /* 0.01 mm */
    s->pairs++;
    double kov = 0.0;
    for (int i = 0; i < m->n; i++) kov = fmax(kov, m->overlap[i]);
    if (ref > tol) s->ref_touch++;
    if (m->n > 0) s->kern_touch++;
    if (m->n == 0 && ref > tol) {
        s->missed++;
        if (ref > s->worst_miss) s->worst_miss = ref;
        if (ref > 5e-4) s->missed_deep++;
    }
    if (m->n > 0 && ref < -tol) s->false_pos++;
    if (m->n > 0 && ref > tol) {
        double err = kov - ref;
        s->both++;
        s->err_sum += err;
        s->err2_sum += err * err;
        if (err > s->err_max) s->err_max = err;
        if (err < s->err_min) s->err_min = err;
        if (fabs(err) / ref > s->rel_max) s->rel_max = fabs(err) / ref;
        if (fabs(err) <= 1e-6) s->within_1um++;
        if (fabs(err) <= 1e-5) s->within_10um++;
        if (ref <= 5e-4) {
            s->sh_n++;
            s->sh_sum += err;
            s->sh2_sum += err * err;
            if (err < s->sh_min) s->sh_min = err;
            if (err > s->sh_max) s->sh_max = err;
            if (fabs(err) <= 1e-6) s->sh_1um++;
            if (fabs(err) <= 1e-5) s->sh_10um++;
        }
    }
}

static void stats_print(const stats *s)
{
    printf("%-12s pairs %5d  ref-touch %5d  kernel-touch %5d  missed %d (%.2f%%, worst %.4f mm)  "
           "false %d (%.2f%%)\n",
           s->name, s->pairs, s->ref_touch, s->kern_touch, s->missed,
           s->ref_touch ? 100.0 * s->missed / s->ref_touch : 0.0, s->worst_miss * 1e3, s->false_pos,
           s->kern_touch ? 100.0 * s->false_pos / s->kern_touch : 0.0);
    if (s->both)
        printf("%-12s overlap error (kernel - ref) mm: mean %+.6f rms %.5f min %+.6f max %+.6f; "
               "|err| <= 1 um: %d (%.1f%%), <= 10 um: %.1f%%\n",
               "", s->err_sum / s->both * 1e3, sqrt(s->err2_sum / s->both) * 1e3, s->err_min * 1e3,
               s->err_max * 1e3, s->within_1um, 100.0 * s->within_1um / s->both, 100.0 * s->within_10um / s->both);
    if (s->sh_n)
        printf("%-12s  ref <= 0.5 mm (%d pairs): mean %+.6f rms %.5f min %+.6f max %+.6f; "
               "|err| <= 1 um: %d (%.1f%%), <= 10 um: %.1f%%\n",
               "", s->sh_n, s->sh_sum / s->sh_n * 1e3, sqrt(s->sh2_sum / s->sh_n) * 1e3, s->sh_min * 1e3,
               s->sh_max * 1e3, s->sh_1um, 100.0 * s->sh_1um / s->sh_n, 100.0 * s->sh_10um / s->sh_n);
}

/* The levels docs/geometry.md prints, asserted: the counts of the reference (which involve no
 * kernel) exactly, the kernels' errors as bounds a little outside what gcc -O2 measures. Errors
 * in mm, kernel minus reference; "within 1 um" counts |error| <= 1 um. */
typedef struct {
    int ref_touch;                /* pairs touching by the reference (ref > 0.01 mm) */
    int missed, false_pos;        /* at most (-1: not checked) */
    int all_1um;                  /* touching pairs within 1 um: at least */
    double all_mean_lo, all_mean_hi, all_min, all_max;
    int sh_n, sh_1um;             /* of them with ref <= 0.5 mm: pairs (exactly), within 1 um (at least) */
    double sh_mean_lo, sh_mean_hi, sh_min, sh_max;
} levels;

static const levels LV_LOG_LOG = {1556, 0, 0, 1098, +0.82, +0.83, -0.70, +5.0, 598, 597, 0.0, +0.00005, -1e-9, +0.028};
static const levels LV_LOG_SPHERE = {1554, 0, 0, 1288, +0.31, +0.32, -1e-9, +8.16, 578, 577, 0.0, +0.00001, -1e-9, +0.0033};
static const levels LV_LOG_TRI = {590, 0, 0, 330, -2.28, -2.27, -44.2, +0.001, 183, 108, -0.035, -0.034, -0.31, +0.0001};
/* log-triangle split by the kind of the kernel's deepest contact: face-type (normal = plane
 * normal) against the full reference; edge/vertex-type against the depth of the triangle's
 * points inside the cylinder (the plate measure overestimates next to an edge); misses are not
 * counted there (a pair without a contact has no kind) */
static const levels LV_TRI_FACE = {350, -1, 0, 300, -0.047, -0.046, -3.51, +0.001, 109, 80, -0.012, -0.011, -0.30, +0.00001};
static const levels LV_TRI_EDGE = {238, -1, 0, 233, -0.0057, -0.0056, -0.78, +0.0115, 158, 156, +0.0001, +0.00012, -1e-9, +0.0115};

static void check_levels(const stats *s, const levels *lv)
{
    const int before = check_failures;
    CHECK(s->ref_touch == lv->ref_touch);
    if (lv->missed >= 0) CHECK(s->missed <= lv->missed);
    CHECK(s->false_pos <= lv->false_pos);
    CHECK(s->both > 0 && s->within_1um >= lv->all_1um);
    const double mean = s->both ? s->err_sum / s->both * 1e3 : NAN;
    CHECK(mean >= lv->all_mean_lo && mean <= lv->all_mean_hi);
    CHECK(s->err_min * 1e3 >= lv->all_min && s->err_max * 1e3 <= lv->all_max);
    CHECK(s->sh_n == lv->sh_n && s->sh_1um >= lv->sh_1um);
    const double sh_mean = s->sh_n ? s->sh_sum / s->sh_n * 1e3 : NAN;
    CHECK(sh_mean >= lv->sh_mean_lo && sh_mean <= lv->sh_mean_hi);
    CHECK(s->sh_min * 1e3 >= lv->sh_min && s->sh_max * 1e3 <= lv->sh_max);
    if (check_failures != before)
        fprintf(stderr, "  %s: off the levels of docs/geometry.md: ref-touch %d, missed %d, false %d, within 1 um %d; "
                        "all: mean %+.6f min %+.6f max %+.6f mm; ref <= 0.5 mm: %d pairs, within 1 um %d, mean %+.6f "
                        "min %+.6f max %+.6f mm\n",
                s->name, s->ref_touch, s->missed, s->false_pos, s->within_1um, mean, s->err_min * 1e3, s->err_max * 1e3,
                s->sh_n, s->sh_1um, sh_mean, s->sh_min * 1e3, s->sh_max * 1e3);
}

static sd_cyl rand_log(sd_vec3 c)
{
    sd_cyl k;
    k.c = c;
    k.a = rand_unit();
    k.r = 0.005;
    k.hl = 0.05;
    return k;
}
/* random point on the surface of c (area-weighted between side and ends) */
static sd_vec3 rand_surface(const sd_cyl *c)
{
    frame f = cyl_frame(c);
    double side = 4.0 * SD_PI * c->r * c->hl, ends = 2.0 * SD_PI * c->r * c->r;
    double ang = urange(0.0, 2.0 * SD_PI);
    if (urand() * (side + ends) < side) return cyl_point(c, &f, 0, urange(-c->hl, c->hl), ang);
    return cyl_point(c, &f, urand() < 0.5 ? 1 : 2, c->r * sqrt(urand()), ang);
}
static double ext(const sd_cyl *c, sd_vec3 u)
{
    return c->hl * fabs(v3_dot(c->a, u)) + c->r * v3_norm(v3_cross(c->a, u));
}

/* reference overlap of two logs */
static double ref_ll(const sd_cyl *a, const sd_cyl *b)
{
    other oa = {.kind = 0, .cyl = *a}, ob = {.kind = 0, .cyl = *b};
    return fmax(cyl_deepest(a, &ob), cyl_deepest(b, &oa));
}
static double ref_lt2(const sd_cyl *b, const sd_tri *t, double *tri_in_cyl)
{
    /* a thin triangle meets the cylinder iff one of its points is inside the cylinder: that
     * decides touching; the depth is the deeper of the two measures */
    other ot = {.kind = 2, .tri = *t, .cc = b->c};
    double r = tri_deepest(t, b);
    *tri_in_cyl = r;
    if (r > 0.0) r = fmax(r, cyl_deepest(b, &ot));
    return r;
}
static double ref_lt(const sd_cyl *b, const sd_tri *t)
{
    double dummy;
    return ref_lt2(b, t, &dummy);
}
static sd_tri tri_shift(const sd_tri *t, sd_vec3 d)
{
    sd_tri r;
    sd_tri_init(&r, v3_add(t->v[0], d), v3_add(t->v[1], d), v3_add(t->v[2], d));
    return r;
}
/* random penetration target: mostly DEM-like (0-0.5 mm), some deeper, some just apart */
static double rand_target(void)
{
    double x = urand();
    if (x < 0.1) return -urange(0.0, 0.05e-3);
    if (x < 0.8) return urange(0.0, 0.5e-3);
    return urange(0.5e-3, 2e-3);
}

int main(int argc, char **argv)
{
    int n_pairs = argc > 1 ? atoi(argv[1]) : 2400;
    stats sc = {.name = "log-log", .err_min = INFINITY, .err_max = -INFINITY, .sh_min = INFINITY, .sh_max = -INFINITY};
    stats ss = {.name = "log-sphere", .err_min = INFINITY, .err_max = -INFINITY, .sh_min = INFINITY, .sh_max = -INFINITY};
    stats st = {.name = "log-tri", .err_min = INFINITY, .err_max = -INFINITY, .sh_min = INFINITY, .sh_max = -INFINITY};
    stats stf = {.name = " tri face", .err_min = INFINITY, .err_max = -INFINITY, .sh_min = INFINITY, .sh_max = -INFINITY};
    stats ste = {.name = " tri edge", .err_min = INFINITY, .err_max = -INFINITY, .sh_min = INFINITY, .sh_max = -INFINITY};
    sd_manifold m;
    for (int it = 0; it < n_pairs; it++) {
        /* log-log: offset along a random direction, a fraction of the sum of the extents */
        sd_cyl b = rand_log(v3(0, 0, 0));
        sd_cyl a = rand_log(v3(0, 0, 0));
        sd_vec3 u = rand_unit();
        double s;
        if (it % 3 == 1) {
            /* offset along a random direction, a fraction of the sum of the extents */
            s = (ext(&a, u) + ext(&b, u)) * (1.02 - 0.6 * urand() * urand());
            a.c = v3_scale(u, s);
        } else if (it % 3 == 2) {
            /* move in along u from far away: bisection (coarse sampling) to first contact,
             * then a random penetration along u */
            double lo = 0.0, hi = ext(&a, u) + ext(&b, u);
            coarse = 1;
            for (int k = 0; k < 24; k++) {
                double mid = 0.5 * (lo + hi);
                a.c = v3_scale(u, mid);
                if (ref_ll(&a, &b) > 0.0) lo = mid; else hi = mid;
            }
            coarse = 0;
            a.c = v3_scale(u, hi - rand_target());
        } else {
            /* a random surface point of A put within 2 mm of a random surface point of B */
            sd_vec3 pa = rand_surface(&a), pb = rand_surface(&b);
            a.c = v3_add(v3_sub(pb, pa), v3_scale(rand_unit(), urange(0.0, 0.002)));
        }
        sd_geom_cyl_cyl(&a, &b, &m);
        double ref = ref_ll(&a, &b);
        stats_add(&sc, ref, &m);
        CHECK(!(m.n == 0 && ref > 5e-4));
        if (m.n == 0 && ref > 5e-4)
            fprintf(stderr, "missed log-log: ref %.4f mm a.c (%.17g, %.17g, %.17g) a.a (%.17g %.17g %.17g) b.a (%.17g %.17g %.17g)\n",
                    ref * 1e3, a.c.x, a.c.y, a.c.z, a.a.x, a.a.y, a.a.z, b.a.x, b.a.y, b.a.z);

        /* log-sphere */
        double sr = urange(0.0025, 0.01);
        u = rand_unit();
        s = (ext(&b, u) + sr) * (1.02 - 0.6 * urand() * urand());
        sd_vec3 c = v3_scale(u, s);
        if (it % 3 == 0) c = v3_add(rand_surface(&b), v3_scale(rand_unit(), urange(0.0, sr + 0.001)));
        if (it % 3 == 2) {
            /* exact placement is easy for a sphere: distance sr - target from the surface */
            sd_vec3 p = rand_surface(&b);
            other ob1 = {.kind = 0, .cyl = b};
            (void)ob1;
            c = v3_madd(p, rand_unit(), 0.0);
            /* outward direction: away from the axis or along it, whichever the point is on */
            sd_vec3 d = v3_sub(p, b.c);
            double ta = v3_dot(d, b.a);
            sd_vec3 out = fabs(fabs(ta) - b.hl) < 1e-12 ? v3_scale(b.a, ta > 0 ? 1.0 : -1.0)
                                                       : v3_normalize(v3_madd(d, b.a, -ta));
            c = v3_madd(p, out, sr - rand_target());
        }
        sd_geom_sphere_cyl(c, sr, &b, &m);
        other os = {.kind = 1, .sc = c, .sr = sr};
        ref = fmax(cyl_deepest(&b, &os), sphere_deepest(c, sr, &b));
        stats_add(&ss, ref, &m);
        CHECK(!(m.n == 0 && ref > 5e-4));

        /* log-triangle: a random triangle in a plane at a random distance from the log */
        sd_vec3 n = rand_unit();
        double dist = ext(&b, n) * (it & 1 ? urange(0.9, 1.02) : 1.02 - 0.6 * urand() * urand());
        sd_vec3 p0 = v3_scale(n, dist);
        sd_vec3 t1 = v3_any_perp(n), t2 = v3_cross(n, t1);
        sd_vec3 cen = v3_add(p0, v3_add(v3_scale(t1, urange(-0.05, 0.05)), v3_scale(t2, urange(-0.05, 0.05))));
        sd_vec3 vv[3];
        double size = urange(0.02, 0.12);
        for (int k = 0; k < 3; k++) {
            double ang = 2.0 * SD_PI * k / 3.0 + urange(-0.6, 0.6);
            double rr = size * urange(0.3, 1.0);
            vv[k] = v3_add(cen, v3_add(v3_scale(t1, rr * cos(ang)), v3_scale(t2, rr * sin(ang))));
        }
        sd_tri t;
        sd_tri_init(&t, vv[0], vv[1], vv[2]);
        if (it % 3 == 2) {
            /* bring the triangle in along a random direction to first contact, then deeper */
            sd_vec3 dir = rand_unit();
            double lo = 0.0, hi = 0.3;
            coarse = 1;
            for (int k = 0; k < 24; k++) {
                double mid = 0.5 * (lo + hi);
                sd_tri tt = tri_shift(&t, v3_scale(dir, mid));
                if (ref_lt(&b, &tt) > 0.0) lo = mid; else hi = mid;
            }
            coarse = 0;
            if (lo > 0.0) t = tri_shift(&t, v3_scale(dir, hi - rand_target()));
        }
        sd_geom_cyl_tri(&b, &t, &m);
        double tic;
        ref = ref_lt2(&b, &t, &tic);
        stats_add(&st, ref, &m);
        {
            /* split by the kind of the kernel's deepest contact: face-type (normal = plane
             * normal) against the full reference, edge/vertex-type against the depth of the
             * triangle's points inside the cylinder (the plate measure overestimates there) */
            int k = -1;
            for (int i = 0; i < m.n; i++)
                if (k < 0 || m.overlap[i] > m.overlap[k]) k = i;
            if (k >= 0 && fabs(v3_dot(m.normal[k], t.n)) > 1.0 - 1e-9)
                stats_add(&stf, ref, &m);
            else if (k >= 0)
                stats_add(&ste, tic, &m);
        }
        if (getenv("SD_DEBUG_TRI")) {
            double kov = 0.0;
            int kf = -1;
            for (int i = 0; i < m.n; i++)
                if (m.overlap[i] > kov) {
                    kov = m.overlap[i];
                    kf = m.feature[i];
                }
            if (m.n > 0 && ref > 1e-5 && ref < 5e-4 && fabs(kov - ref) > 1e-5) {
                other ot = {.kind = 2, .tri = t, .cc = b.c};
                printf("tri: kern %.5f ref %.5f (tri in cyl %.5f, cyl beyond plate %.5f) feature cyl %d tri %d\n",
                       kov * 1e3, ref * 1e3, tri_deepest(&t, &b) * 1e3, cyl_deepest(&b, &ot) * 1e3,
                       kf >> SD_TRI_FEATURE_BITS, kf & 7);
            }
        }
    }
    stats_print(&sc);
    stats_print(&ss);
    stats_print(&st);
    printf("log-tri split by the kind of the kernel's deepest contact (miss counts not meaningful here):\n");
    stats_print(&stf);
    stats_print(&ste);
    if (n_pairs == 2400) { /* (the levels are those of the default sample) */
        check_levels(&sc, &LV_LOG_LOG);
        check_levels(&ss, &LV_LOG_SPHERE);
        check_levels(&st, &LV_LOG_TRI);
        check_levels(&stf, &LV_TRI_FACE);
        check_levels(&ste, &LV_TRI_EDGE);
    }
    return check_report("test_geom_sampling");
}
