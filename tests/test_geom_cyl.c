/* Exact tests of the cylinder kernels: sphere-cylinder (cases 2, 3-1, 3-2), cylinder-cylinder
 * (cases 5-7 and rim contacts), cylinder-triangle (case 8, edges, vertices, lines on a floor).
 * Each hand-built configuration is checked as built, after random rigid motions of the whole
 * configuration, and (cylinder-cylinder) with the pair swapped. Units: metres. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "core/rng.h"
#include "geom/cyl_common.h"
#include "geom/geom.h"
#include "geom_ref.h"

/* ---- deterministic RNG (splitmix64) and rigid motions ---- */
static sd_rng rng = {0x5eed5eed1234ULL}; /* the engine's splitmix64 (core/rng.h) */
static double urange(double lo, double hi) { return sd_rng_range(&rng, lo, hi); }

typedef struct {
    sd_quat q;
    sd_vec3 t;
} xform;

static xform rand_xform(void)
{
    xform x;
    x.q = quat_from_rotvec(v3(urange(-3.0, 3.0), urange(-3.0, 3.0), urange(-3.0, 3.0)));
    x.t = v3(urange(-1.0, 1.0), urange(-1.0, 1.0), urange(-1.0, 1.0));
    return x;
}
static sd_vec3 xp(xform x, sd_vec3 p) { return v3_add(quat_rotate(x.q, p), x.t); }
static sd_vec3 xv(xform x, sd_vec3 v) { return quat_rotate(x.q, v); }
static sd_cyl xcyl(xform x, sd_cyl c)
{
    sd_cyl r = c;
    r.c = xp(x, c.c);
    r.a = v3_normalize(xv(x, c.a));
    return r;
}
static sd_tri xtri(xform x, const sd_tri *t)
{
    sd_tri r;
    sd_tri_init(&r, xp(x, t->v[0]), xp(x, t->v[1]), xp(x, t->v[2]));
    return r;
}

static int manifold_finite(const sd_manifold *m)
{
    if (m->n < 0 || m->n > SD_MANIFOLD_MAX) return 0;
    for (int i = 0; i < m->n; i++) {
        const double v[] = {m->normal[i].x, m->normal[i].y, m->normal[i].z, m->point[i].x,
                            m->point[i].y,  m->point[i].z,  m->overlap[i]};
        for (int k = 0; k < 7; k++)
            if (!isfinite(v[k])) return 0;
        if (fabs(v3_norm(m->normal[i]) - 1.0) > 1e-12) return 0;
        if (!(m->overlap[i] > 0.0)) return 0;
        if (m->feature[i] < 0) return 0;
        for (int j = 0; j < i; j++)
            if (m->feature[j] == m->feature[i]) return 0;
    }
    return 1;
}

static int find_feature(const sd_manifold *m, int f)
{
    for (int i = 0; i < m->n; i++)
        if (m->feature[i] == f) return i;
    return -1;
}

/* expected contacts of one configuration */
typedef struct {
    int n;
    int feature[SD_MANIFOLD_MAX];
    sd_vec3 normal[SD_MANIFOLD_MAX];
    sd_vec3 point[SD_MANIFOLD_MAX];
    double overlap[SD_MANIFOLD_MAX];
} expect;

#define TOL 1e-12

static int find_point(const sd_manifold *m, sd_vec3 p)
{
    int best = -1;
    double bd = INFINITY;
    for (int i = 0; i < m->n; i++) {
        double dd = v3_dist(m->point[i], p);
        if (dd < bd) {
            bd = dd;
            best = i;
        }
    }
    return best;
}

/* m must equal e mapped through x (normals times sgn). Contacts are matched by feature id,
 * or, with by_point (the swapped pair, whose ids differ), by the nearest point. */
static void check_expect(const char *what, const sd_manifold *m, const expect *e, xform x, double sgn, int by_point)
{
    int failures_before = check_failures;
    CHECK(manifold_finite(m));
    CHECK(m->n == e->n);
    for (int i = 0; i < e->n; i++) {
        int k = by_point ? find_point(m, xp(x, e->point[i])) : find_feature(m, e->feature[i]);
        CHECK(k >= 0);
        if (k < 0) continue;
        CHECK_VEC_NEAR(m->normal[k], v3_scale(xv(x, e->normal[i]), sgn), TOL);
        CHECK_NEAR(m->overlap[k], e->overlap[i], TOL);
        CHECK_VEC_NEAR(m->point[k], xp(x, e->point[i]), TOL);
    }
    if (check_failures != failures_before) {
        fprintf(stderr, "  in %s: got %d contacts:\n", what, m->n);
        for (int i = 0; i < m->n; i++)
            fprintf(stderr, "   f=%d n=(%.6g %.6g %.6g) ov=%.9g p=(%.9g %.9g %.9g)\n", m->feature[i], m->normal[i].x,
                    m->normal[i].y, m->normal[i].z, m->overlap[i], m->point[i].x, m->point[i].y, m->point[i].z);
    }
}

static xform identity_xform(void)
{
    xform x;
    x.q = quat_identity();
    x.t = v3(0.0, 0.0, 0.0);
    return x;
}

/* ---------------------------------------------------------------- sphere-cylinder ---- */
static void sc_case(const char *what, sd_vec3 c, double r, sd_cyl b, const expect *e)
{
    sd_manifold m;
    sd_geom_sphere_cyl(c, r, &b, &m);
    check_expect(what, &m, e, identity_xform(), 1.0, 0);
    for (int k = 0; k < 4; k++) {
        xform x = rand_xform();
        sd_cyl bx = xcyl(x, b);
        sd_geom_sphere_cyl(xp(x, c), r, &bx, &m);
        check_expect(what, &m, e, x, 1.0, 0);
    }
}

static expect one(int f, sd_vec3 n, double ov, sd_vec3 p)
{
    expect e;
    e.n = 1;
    e.feature[0] = f;
    e.normal[0] = n;
    e.overlap[0] = ov;
    e.point[0] = p;
    return e;
}
static expect none(void)
{
    expect e;
    e.n = 0;
    return e;
}

static void test_sphere_cyl(void)
{
    const double r = 0.005, hl = 0.05, rs = 0.004, d = 0.0003;
    sd_cyl b = mkcyl(v3(0, 0, 0), v3(1, 0, 0), r, hl); /* axis x, ends at x = -hl (-) and +hl (+) */
    expect e;
    /* case 2, side: centre above the axis */
    e = one(0, v3(0, 0, 1), d, v3(0.01, 0, r - 0.5 * d));
    sc_case("sphere side", v3(0.01, 0, r + rs - d), rs, b, &e);
    e = none();
    sc_case("sphere side separated", v3(0.01, 0, r + rs + 1e-6), rs, b, &e);
    {
        sd_manifold m;
        sd_geom_sphere_cyl(v3(0.01, 0, r + rs), rs, &b, &m); /* exactly touching: no contact */
        CHECK(m.n == 0);
    }
    /* case 3-1, end face +: centre beyond x = hl, inside the radius */
    e = one(2, v3(1, 0, 0), d, v3(hl - 0.5 * d, 0.002, 0.001));
    sc_case("sphere end face +", v3(hl + rs - d, 0.002, 0.001), rs, b, &e);
    e = one(1, v3(-1, 0, 0), d, v3(-hl + 0.5 * d, 0.0, 0.0));
    sc_case("sphere end face - on axis", v3(-hl - rs + d, 0, 0), rs, b, &e);
    /* case 3-2, rim +: centre beyond the end and outside the radius, at 45 deg */
    {
        double s = (rs - d) / sqrt(2.0);
        sd_vec3 n = v3(1.0 / sqrt(2.0), 0, 1.0 / sqrt(2.0));
        sd_vec3 q = v3(hl, 0, r);
        e = one(4, n, d, v3_madd(q, n, -0.5 * d));
        sc_case("sphere rim +", v3(hl + s, 0, r + s), rs, b, &e);
        e = none();
        sc_case("sphere rim separated", v3(hl + s + 0.001, 0, r + s), rs, b, &e);
    }
    /* centre inside, nearest surface the side */
    e = one(0, v3(0, 1, 0), rs + 0.001, v3(0.0, r - 0.5 * (rs + 0.001), 0));
    sc_case("sphere inside near side", v3(0.0, r - 0.001, 0), rs, b, &e);
    /* centre inside, nearest surface end face - */
    e = one(1, v3(-1, 0, 0), rs + 0.001, v3(-hl + 0.5 * (rs + 0.001), 0.001, 0));
    sc_case("sphere inside near end", v3(-hl + 0.001, 0.001, 0), rs, b, &e);
    /* degenerate: centre exactly at the cylinder centre, on the axis */
    {
        sd_manifold m;
        sd_geom_sphere_cyl(v3(0, 0, 0), rs, &b, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n == 1);
        CHECK_NEAR(m.overlap[0], rs + r, TOL);
        CHECK_NEAR(v3_dot(m.normal[0], b.a), 0.0, TOL);
    }
}

/* ---------------------------------------------------------------- cylinder-cylinder ---- */

static void cc_case(const char *what, sd_cyl a, sd_cyl b, const expect *e)
{
    sd_manifold m;
    sd_geom_cyl_cyl(&a, &b, &m);
    check_expect(what, &m, e, identity_xform(), 1.0, 0);
    sd_geom_cyl_cyl(&b, &a, &m);
    check_expect(what, &m, e, identity_xform(), -1.0, 1);
    for (int k = 0; k < 4; k++) {
        xform x = rand_xform();
        sd_cyl ax = xcyl(x, a), bx = xcyl(x, b);
        sd_geom_cyl_cyl(&ax, &bx, &m);
        check_expect(what, &m, e, x, 1.0, 0);
        sd_geom_cyl_cyl(&bx, &ax, &m);
        check_expect(what, &m, e, x, -1.0, 1);
    }
}

static void test_cyl_cyl(void)
{
    const double r = 0.005, hl = 0.05, rp = 0.009, hp = 0.2, d = 0.0004;
    expect e;
    /* case 5: crossed logs, A along x above B along y */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(0, 1, 0), r, hl);
        sd_cyl a = mkcyl(v3(0.01, 0.02, 2 * r - d), v3(1, 0, 0), r, hl);
        e = one(0, v3(0, 0, 1), d, v3(0, 0.02, r - 0.5 * d));
        cc_case("crossed logs", a, b, &e);
        a.c.z = 2 * r + 1e-7;
        e = none();
        cc_case("crossed logs separated", a, b, &e);
        /* crossed at 30 degrees, different radii */
        sd_cyl a2 = mkcyl(v3(0.003, -0.004, r + rp - d), v3(cos(0.5), sin(0.5), 0), r, hl);
        sd_cyl b2 = mkcyl(v3(0, 0, 0), v3(1, 0, 0), rp, hp);
        /* axes cross above (x, 0): point on A's axis where y = 0 */
        double s = 0.004 / sin(0.5);
        sd_vec3 pa = v3(0.003 + s * cos(0.5), 0, 0);
        e = one(0, v3(0, 0, 1), d, v3(pa.x, 0, rp - 0.5 * d));
        cc_case("crossed log on pipe 30 deg", a2, b2, &e);
    }
    /* case 5 parallel: log resting along a pipe: two contacts under the log's end rims */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(1, 0, 0), rp, hp);
        sd_cyl a = mkcyl(v3(0.03, 0, r + rp - d), v3(1, 0, 0), r, hl);
        e.n = 2;
        e.feature[0] = 1;
        e.normal[0] = v3(0, 0, 1);
        e.overlap[0] = d;
        e.point[0] = v3(0.03 - hl, 0, rp - 0.5 * d);
        e.feature[1] = 2;
        e.normal[1] = v3(0, 0, 1);
        e.overlap[1] = d;
        e.point[1] = v3(0.03 + hl, 0, rp - 0.5 * d);
        cc_case("log along pipe", a, b, &e);
        a.c.z = r + rp + 1e-7;
        e = none();
        cc_case("log along pipe separated", a, b, &e);
    }
    /* parallel equal logs side by side, offset along the axis: ends of the overlapping part */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(1, 0, 0), r, hl);
        sd_cyl a = mkcyl(v3(0.03, 2 * r - d, 0), v3(1, 0, 0), r, hl);
        e.n = 2;
        e.feature[0] = 1; /* A's end - against B's side */
        e.normal[0] = v3(0, 1, 0);
        e.overlap[0] = d;
        e.point[0] = v3(0.03 - hl, r - 0.5 * d, 0);
        e.feature[1] = 6; /* B's end + against A's side */
        e.normal[1] = v3(0, 1, 0);
        e.overlap[1] = d;
        e.point[1] = v3(hl, r - 0.5 * d, 0);
        cc_case("parallel logs offset", a, b, &e);
    }
    /* case 6: log end face against the side of a pipe (log axis through the pipe axis) */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(0, 0, 1), rp, hp);
        sd_cyl a = mkcyl(v3(rp - d + hl, 0, 0.01), v3(1, 0, 0), r, hl);
        e = one(1, v3(1, 0, 0), d, v3(rp - 0.5 * d, 0, 0.01));
        cc_case("log end against pipe side", a, b, &e);
        /* tilted log: its lowest rim point touches the pipe side */
        double th = 0.4;
        sd_vec3 ax = v3(cos(th), 0, sin(th));
        sd_vec3 u = v3(-sin(th), 0, cos(th)); /* perpendicular to ax in the xz plane */
        /* rim points of end - : ce + r (cos phi u + sin phi y); the one nearest the z axis has
         * the smallest x: phi = 0 when u.x < 0 */
        sd_vec3 rim = v3(rp - d, 0, 0.02);
        sd_vec3 ce = v3_madd(rim, u, -r);
        sd_cyl a2 = mkcyl(v3_madd(ce, ax, hl), ax, r, hl);
        e = one(1, v3(1, 0, 0), d, v3(rp - 0.5 * d, 0, 0.02));
        cc_case("tilted log rim against pipe side", a2, b, &e);
    }
    /* case 7: end to end, coaxial; and parallel axes offset sideways (lens of two disks) */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(0, 0, 1), r, hl);
        sd_cyl a = mkcyl(v3(0, 0, 2 * hl - d), v3(0, 0, 1), r, hl);
        e = one(3, v3(0, 0, 1), d, v3(0, 0, hl - 0.5 * d));
        cc_case("end to end coaxial", a, b, &e);
        sd_cyl a2 = mkcyl(v3(0.003, 0, 2 * hl - d), v3(0, 0, 1), r, hl);
        e = one(3, v3(0, 0, 1), d, v3(0.0015, 0, hl - 0.5 * d));
        cc_case("end to end offset", a2, b, &e);
        a2.c.z = 2 * hl + 1e-7;
        e = none();
        cc_case("end to end separated", a2, b, &e);
    }
    /* rim against end face: a tilted log's lowest rim point into a pipe's end face */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(0, 0, 1), rp, hp);
        double th = 0.3;
        sd_vec3 ax = v3(sin(th), 0, cos(th));
        sd_vec3 u = v3(-cos(th), 0, sin(th)); /* in-plane direction of steepest descent is -u */
        sd_vec3 rim = v3(0.001, 0, hp - d);
        sd_vec3 ce = v3_madd(rim, u, r); /* rim = ce - r u */
        sd_cyl a = mkcyl(v3_madd(ce, ax, hl), ax, r, hl);
        e = one(3, v3(0, 0, 1), d, v3(0.001, 0, hp - 0.5 * d));
        cc_case("rim against end face", a, b, &e);
    }
    /* rim against side of a parallel log at the corner (ends flush): still two contacts */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(1, 0, 0), r, hl);
        sd_cyl a = mkcyl(v3(0, 0, 2 * r - d), v3(1, 0, 0), r, hl);
        sd_manifold m;
        sd_geom_cyl_cyl(&a, &b, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n == 2);
        for (int i = 0; i < m.n; i++) {
            CHECK_NEAR(m.overlap[i], d, TOL);
            CHECK_VEC_NEAR(m.normal[i], v3(0, 0, 1), TOL);
            CHECK_NEAR(fabs(m.point[i].x), hl, TOL);
        }
    }
    /* degenerate: coincident cylinders, axes crossing through each other */
    {
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(1, 0, 0), r, hl);
        sd_manifold m;
        sd_geom_cyl_cyl(&b, &b, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n >= 1);
        sd_cyl a = mkcyl(v3(0, 0, 0), v3(0, 1, 0), r, hl);
        sd_geom_cyl_cyl(&a, &b, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n >= 1);
        sd_cyl c = mkcyl(v3(0, 0, 0.001), v3(0, 0, 1), r, hl);
        sd_geom_cyl_cyl(&c, &b, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n >= 1);
    }
}

/* ---------------------------------------------------------------- cylinder-triangle ---- */
static void ct_case(const char *what, sd_cyl a, const sd_tri *t, const expect *e)
{
    sd_manifold m;
    sd_geom_cyl_tri(&a, t, &m);
    check_expect(what, &m, e, identity_xform(), 1.0, 0);
    /* reversed winding: two-sided, same result */
    sd_tri tr;
    sd_tri_init(&tr, t->v[0], t->v[2], t->v[1]);
    sd_manifold m2;
    sd_geom_cyl_tri(&a, &tr, &m2);
    CHECK(m2.n == m.n);
    for (int k = 0; k < 4; k++) {
        xform x = rand_xform();
        sd_cyl ax = xcyl(x, a);
        sd_tri tx = xtri(x, t);
        sd_geom_cyl_tri(&ax, &tx, &m);
        check_expect(what, &m, e, x, 1.0, 0);
    }
}

#define CTF(c, t) (((c) << SD_TRI_FEATURE_BITS) | (t))

/* An end disk flat on a plane: its rim points at centre pc + r (u, v, -u, -v) (pc at the
 * contact points' level), ids first, then 5, 6, 7 of the same triangle code. */
static expect disk4(int first, sd_vec3 pc, sd_vec3 u, sd_vec3 v, double r, sd_vec3 n, double d)
{
    expect e;
    e.n = 4;
    const sd_vec3 dir[4] = {u, v, v3_neg(u), v3_neg(v)};
    for (int i = 0; i < 4; i++) {
        e.feature[i] = i == 0 ? first : (((5 + i - 1) << SD_TRI_FEATURE_BITS) | (first & 7));
        e.normal[i] = n;
        e.overlap[i] = d;
        e.point[i] = v3_madd(pc, dir[i], r);
    }
    return e;
}

static void test_cyl_tri(void)
{
    const double r = 0.005, hl = 0.05, d = 0.0002;
    sd_tri floor;
    sd_tri_init(&floor, v3(-1, -1, 0), v3(1, -1, 0), v3(0, 1, 0));
    expect e;
    /* log lying flat on a floor triangle: exactly two contacts, one under each end rim */
    {
        sd_cyl a = mkcyl(v3(0.01, 0.02, r - d), v3(cos(0.7), sin(0.7), 0), r, hl);
        e.n = 2;
        for (int i = 0; i < 2; i++) {
            double s = i ? hl : -hl;
            e.feature[i] = CTF(1 + i, SD_TRI_FACE);
            e.normal[i] = v3(0, 0, 1);
            e.overlap[i] = d;
            e.point[i] = v3(0.01 + s * cos(0.7), 0.02 + s * sin(0.7), -0.5 * d);
        }
        ct_case("log flat on floor", a, &floor, &e);
        /* below the floor (cylinder centre on the other side): mirrored normal */
        sd_cyl ab = a;
        ab.c.z = -(r - d);
        for (int i = 0; i < 2; i++) {
            e.normal[i] = v3(0, 0, -1);
            e.point[i].z = 0.5 * d;
        }
        ct_case("log flat under floor", ab, &floor, &e);
        a.c.z = r + 1e-7;
        e = none();
        ct_case("log above floor", a, &floor, &e);
    }
    /* case 8: tilted log, the lower end's deepest rim point only */
    {
        double th = 0.25;
        sd_vec3 ax = v3(cos(th), 0, sin(th));
        sd_vec3 u = v3(sin(th), 0, -cos(th)); /* deepest direction in the end disk */
        sd_vec3 rim = v3(0.02, 0.03, -d);
        sd_vec3 ce = v3_madd(rim, u, -r);
        sd_cyl a = mkcyl(v3_madd(ce, ax, hl), ax, r, hl);
        e = one(CTF(1, SD_TRI_FACE), v3(0, 0, 1), d, v3(0.02, 0.03, -0.5 * d));
        ct_case("tilted log rim on floor", a, &floor, &e);
    }
    /* standing log: end disk flat on the floor (S = 0): four rim points a quarter turn apart,
     * the first along the triangle's first edge (x), then a x u (y), -x, -y */
    {
        sd_cyl a = mkcyl(v3(0.1, 0.2, hl - d), v3(0, 0, 1), r, hl);
        e = disk4(CTF(1, SD_TRI_FACE), v3(0.1, 0.2, -0.5 * d), v3(1, 0, 0), v3(0, 1, 0), r, v3(0, 0, 1), d);
        ct_case("standing log", a, &floor, &e);
        sd_cyl b = mkcyl(v3(0.1, 0.2, -(hl - d)), v3(0, 0, 1), r, hl); /* under: end + */
        e = disk4(CTF(2, SD_TRI_FACE), v3(0.1, 0.2, 0.5 * d), v3(1, 0, 0), v3(0, 1, 0), r, v3(0, 0, -1), d);
        ct_case("standing log under", b, &floor, &e);
        /* tilted by 0.6 d / r about y, the disk centre at depth d/2: the rim points' depths
         * d/2 + r sin(tilt) (deepest, +x), d/2 on the tilt axis (ids 5, 7), and the top one
         * above the floor (no contact) */
        const double tl = 0.6 * d / r;
        const sd_vec3 ax = v3(sin(tl), 0, cos(tl));
        const sd_vec3 uu = v3(cos(tl), 0, -sin(tl)); /* from the axis towards the floor, in the disk */
        const sd_vec3 ce = v3(0.1, 0.2, -0.5 * d);
        sd_cyl c = mkcyl(v3_madd(ce, ax, hl), ax, r, hl);
        e.n = 3;
        const sd_vec3 pts[3] = {v3_madd(ce, uu, r), v3_madd(ce, v3(0, 1, 0), r), v3_madd(ce, v3(0, -1, 0), r)};
        const int ids[3] = {CTF(1, SD_TRI_FACE), CTF(5, SD_TRI_FACE), CTF(7, SD_TRI_FACE)};
        for (int i = 0; i < 3; i++) {
            e.feature[i] = ids[i];
            e.normal[i] = v3(0, 0, 1);
            e.overlap[i] = -pts[i].z;
            e.point[i] = v3(pts[i].x, pts[i].y, 0.5 * pts[i].z);
        }
        ct_case("standing log tilted", c, &floor, &e);
    }
    /* log across a seam of two triangles: each supports its own part of the line */
    {
        sd_tri t1, t2;
        sd_tri_init(&t1, v3(-1, -1, 0), v3(0, -1, 0), v3(0, 1, 0)); /* x <= 0 */
        sd_tri_init(&t2, v3(0, -1, 0), v3(1, -1, 0), v3(0, 1, 0));  /* x >= 0 */
        sd_cyl a = mkcyl(v3(0.02, 0.0, r - d), v3(1, 0, 0), r, hl);
        /* t1: end - rim (face) and the seam (edge 1 of t1 from v1 to v2) */
        e.n = 2;
        e.feature[0] = CTF(1, SD_TRI_FACE);
        e.normal[0] = v3(0, 0, 1);
        e.overlap[0] = d;
        e.point[0] = v3(0.02 - hl, 0, -0.5 * d);
        e.feature[1] = CTF(4, SD_TRI_EDGE0 + 1);
        e.normal[1] = v3(0, 0, 1);
        e.overlap[1] = d;
        e.point[1] = v3(0, 0, -0.5 * d);
        ct_case("log over seam, t1", a, &t1, &e);
        /* t2: the seam (edge 2 of t2 from v2 to v0) and end + rim */
        e.feature[0] = CTF(3, SD_TRI_EDGE0 + 2);
        e.point[0] = v3(0, 0, -0.5 * d);
        e.feature[1] = CTF(2, SD_TRI_FACE);
        e.point[1] = v3(0.02 + hl, 0, -0.5 * d);
        ct_case("log over seam, t2", a, &t2, &e);
    }
    /* log against a vertical wall with its end rim (case 8 with the wall's normal) */
    {
        sd_tri wall;
        sd_tri_init(&wall, v3(0, -1, -1), v3(0, 1, -1), v3(0, 0, 1)); /* plane x = 0 */
        sd_cyl a = mkcyl(v3(hl - d, 0.0, 0.1), v3(1, 0, 0), r, hl);   /* end disk flat on the wall */
        e = disk4(CTF(1, SD_TRI_FACE), v3(-0.5 * d, 0.0, 0.1), v3(0, 1, 0), v3(0, 0, 1), r, v3(1, 0, 0), d);
        ct_case("log end against wall", a, &wall, &e);
    }
    /* log lying across a blade (vertical triangle's top edge), perpendicular: edge contact */
    {
        sd_tri blade;
        sd_tri_init(&blade, v3(-0.1, 0, -0.2), v3(0.1, 0, -0.2), v3(0, 0, 0)); /* apex at origin */
        sd_tri blade2;
        sd_tri_init(&blade2, v3(-0.1, 0, -0.2), v3(0.1, 0, 0), v3(-0.1, 0, 0)); /* top edge z = 0 */
        sd_cyl a = mkcyl(v3(0.01, 0.0, r - d), v3(0, 1, 0), r, hl);
        e = one(CTF(0, SD_TRI_EDGE0 + 1), v3(0, 0, 1), d, v3(0.01, 0, -0.5 * d));
        ct_case("log across blade edge", a, &blade2, &e);
        /* on the apex vertex */
        sd_cyl a2 = mkcyl(v3(0.0, 0.01, r - d), v3(0, 1, 0), r, hl);
        sd_cyl a3 = a2;
        a3.c.y = 0.0;
        e = one(CTF(0, SD_TRI_VERT0 + 2), v3(0, 0, 1), d, v3(0, 0, -0.5 * d));
        ct_case("log on blade apex", a3, &blade, &e);
        /* log lying along the top edge of the blade: two contacts at the log's ends */
        sd_cyl a4 = mkcyl(v3(0.0, 0.0, r - d), v3(1, 0, 0), r, hl);
        e.n = 2;
        e.feature[0] = CTF(3, SD_TRI_EDGE0 + 1);
        e.normal[0] = v3(0, 0, 1);
        e.overlap[0] = d;
        e.point[0] = v3(-hl, 0, -0.5 * d);
        e.feature[1] = CTF(4, SD_TRI_EDGE0 + 1);
        e.normal[1] = v3(0, 0, 1);
        e.overlap[1] = d;
        e.point[1] = v3(hl, 0, -0.5 * d);
        ct_case("log along blade edge", a4, &blade2, &e);
        (void)a2;
    }
    /* log along the boundary edge of a floor, its lowest line just outside the triangle */
    {
        sd_tri t;
        sd_tri_init(&t, v3(-1, 0, 0), v3(1, 0, 0), v3(0, 1, 0)); /* y >= 0 */
        double y0 = -0.003;                                      /* axis beside the edge */
        double z0 = sqrt(r * r - y0 * y0) - d;                   /* edge depth r - dist = d */
        (void)z0;
        double dist = r - d;
        double zc = sqrt(dist * dist - y0 * y0);
        sd_cyl a = mkcyl(v3(0.0, y0, zc), v3(1, 0, 0), r, hl);
        sd_vec3 n = v3_normalize(v3(0, y0, zc)); /* from the edge (y = z = 0) to the axis */
        e.n = 2;
        e.feature[0] = CTF(3, SD_TRI_EDGE0 + 0);
        e.normal[0] = n;
        e.overlap[0] = d;
        e.point[0] = v3_madd(v3(-hl, 0, 0), n, -0.5 * d);
        e.feature[1] = CTF(4, SD_TRI_EDGE0 + 0);
        e.normal[1] = n;
        e.overlap[1] = d;
        e.point[1] = v3_madd(v3(hl, 0, 0), n, -0.5 * d);
        ct_case("log along floor boundary edge", a, &t, &e);
    }
    /* degenerate: cylinder through the triangle, centre on the plane; tiny triangle inside */
    {
        sd_cyl a = mkcyl(v3(0, 0, 0), v3(0, 0, 1), r, hl);
        sd_manifold m;
        sd_geom_cyl_tri(&a, &floor, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n >= 1);
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(1, 0, 0), r, hl);
        sd_geom_cyl_tri(&b, &floor, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n >= 1);
        sd_tri tiny;
        sd_tri_init(&tiny, v3(0, 0, 0), v3(0.001, 0, 0), v3(0, 0.001, 0));
        sd_geom_cyl_tri(&b, &tiny, &m);
        CHECK(manifold_finite(&m));
        CHECK(m.n >= 1);
    }
}

/* An end face tilted 25 deg from the plane, its disk centre 4 mm through it: on the floor the
 * four rim points (depths dd + r sin, dd, dd - r sin, dd); a small triangle under the +v rim
 * point alone, clear of the plane's section of the log (the plate point over the rim point is
 * outside the log by sqrt(r^2 + (dd sin)^2) - r = 0.28 mm; every point of the triangle is
 * 0.10 mm or more from it), touches nothing: no contact (the kernel gave the rim point, 4 mm).
 * (Run last: its random motions would shift the random stream of the tests above.) */
static void test_cyl_tri_clear_section(void)
{
    const double r = 0.005, hl = 0.05;
    sd_tri floor;
    sd_tri_init(&floor, v3(-1, -1, 0), v3(1, -1, 0), v3(0, 1, 0));
    expect e;
    const double al = 25.0 * M_PI / 180.0, dd = 0.004, sa = sin(al), ca = cos(al);
    const sd_vec3 ax = v3(sa, 0, ca), ce = v3(0, 0, -dd); /* the lower end's centre */
    const sd_cyl a = mkcyl(v3_madd(ce, ax, hl), ax, r, hl);
    const sd_vec3 dir[4] = {v3(ca, 0, -sa), v3(0, 1, 0), v3(-ca, 0, sa), v3(0, -1, 0)};
    e.n = 4;
    for (int i = 0; i < 4; i++) {
        const sd_vec3 x = v3_madd(ce, dir[i], r);
        e.feature[i] = CTF(i ? 4 + i : 1, SD_TRI_FACE);
        e.normal[i] = v3(0, 0, 1);
        e.overlap[i] = -x.z;
        e.point[i] = v3(x.x, x.y, 0.5 * x.z);
    }
    ct_case("end face tilted 25 deg, 4 mm through a floor", a, &floor, &e);
    sd_tri small;
    sd_tri_init(&small, v3(-0.001, r - 1e-4, 0), v3(0.0003, r - 1e-4, 0), v3(-0.00035, r + 0.003, 0));
    double gap = INFINITY; /* the triangle's nearest point to the log, sampled */
    for (int i = 0; i <= 400; i++)
        for (int j = 0; i + j <= 400; j++) {
            const sd_vec3 p = v3_add(small.v[0], v3_add(v3_scale(v3_sub(small.v[1], small.v[0]), i / 400.0),
                                                        v3_scale(v3_sub(small.v[2], small.v[0]), j / 400.0)));
            gap = fmin(gap, sdf_cyl(&a, p));
        }
    printf("tilted end face beside a small triangle: the triangle's points at least %.4f mm from the log\n",
           gap * 1e3);
    CHECK(gap > 1e-4); /* (0.1012 mm) */
    e = none();
    ct_case("end face tilted 25 deg, 4 mm deep, beside a small triangle", a, &small, &e);
}

/* random configurations: finite, and invariant under rigid motions */
static void test_random_invariance(void)
{
    for (int it = 0; it < 2000; it++) {
        sd_cyl a = mkcyl(v3(urange(-0.06, 0.06), urange(-0.06, 0.06), urange(-0.06, 0.06)),
                         v3(urange(-1, 1), urange(-1, 1), urange(-1, 1)), 0.005, 0.05);
        sd_cyl b = mkcyl(v3(0, 0, 0), v3(urange(-1, 1), urange(-1, 1), urange(-1, 1)), 0.009, 0.1);
        sd_manifold m, mx, ms;
        sd_geom_cyl_cyl(&a, &b, &m);
        CHECK(manifold_finite(&m));
        sd_geom_cyl_cyl(&b, &a, &ms);
        CHECK(manifold_finite(&ms));
        CHECK(ms.n == m.n);
        for (int i = 0; i < m.n && ms.n == m.n; i++) {
            int k = find_point(&ms, m.point[i]);
            CHECK(k >= 0);
            if (k < 0) continue;
            CHECK_NEAR(ms.overlap[k], m.overlap[i], 1e-12);
            CHECK_VEC_NEAR(ms.normal[k], v3_neg(m.normal[i]), 1e-9);
            CHECK_VEC_NEAR(ms.point[k], m.point[i], 1e-12);
        }
        xform x = rand_xform();
        sd_cyl ax = xcyl(x, a), bx = xcyl(x, b);
        sd_geom_cyl_cyl(&ax, &bx, &mx);
        /* away from decision boundaries the contact set is the same */
        if (mx.n == m.n) {
            for (int i = 0; i < m.n; i++) {
                int k = find_feature(&mx, m.feature[i]);
                if (k < 0) continue;
                CHECK_NEAR(mx.overlap[k], m.overlap[i], 1e-11);
            }
        }
        sd_geom_sphere_cyl(a.c, urange(0.0025, 0.01), &b, &m);
        CHECK(manifold_finite(&m));
        sd_tri t;
        sd_tri_init(&t, v3(urange(-0.1, 0.1), urange(-0.1, 0.1), urange(-0.1, 0.1)),
                    v3(urange(-0.1, 0.1), urange(-0.1, 0.1), urange(-0.1, 0.1)),
                    v3(urange(-0.1, 0.1), urange(-0.1, 0.1), urange(-0.1, 0.1)));
        sd_geom_cyl_tri(&a, &t, &m);
        CHECK(manifold_finite(&m));
    }
}

/* ---- log-log: the side-side shortcut and the carried separating axis ---- */

/* how far apart the projections of a and b on the unit direction n are (negative: overlap) */
static double sep_margin(const sd_cyl *a, const sd_cyl *b, sd_vec3 n)
{
    return fabs(v3_dot(v3_sub(a->c, b->c), n)) - (sd_cyl_extent(a, n) + sd_cyl_extent(b, n));
}

static sd_vec3 rand_unit(void)
{
    for (;;) {
        sd_vec3 v = v3(urange(-1, 1), urange(-1, 1), urange(-1, 1));
        double n = v3_norm(v);
        if (n > 0.1 && n < 1.0) return v3_scale(v, 1.0 / n);
    }
}

static int same_manifold(const sd_manifold *x, const sd_manifold *y)
{
    if (x->n != y->n) return 0;
    for (int i = 0; i < x->n; i++)
        if (memcmp(&x->normal[i], &y->normal[i], sizeof(sd_vec3)) ||
            memcmp(&x->point[i], &y->point[i], sizeof(sd_vec3)) ||
            memcmp(&x->overlap[i], &y->overlap[i], sizeof(double)) || x->feature[i] != y->feature[i])
            return 0;
    return 1;
}

/* sd_geom_cyl_cyl skips its separating-axis tests when the side-side contact S is deeper than
 * tol with both feet farther than tol inside their segments: then a ball of radius tol/2 lies
 * in both solids, so no direction can separate them. Checked here on every direction the tests
 * try and on random ones, over random crossings of two logs and of a log and a pipe. */
static void test_cyl_cyl_deep_side(void)
{
    int deep = 0;
    for (int it = 0; it < 20000; it++) {
        const int pipe = it & 1;
        sd_cyl a = mkcyl(v3(urange(-0.02, 0.02), urange(-0.02, 0.02), urange(-0.02, 0.02)), rand_unit(), 0.005, 0.05);
        sd_cyl b = mkcyl(v3(0, 0, 0), rand_unit(), pipe ? 0.009 : 0.005, pipe ? 0.1 : 0.05);
        const double tol = 1e-9 * (a.r + a.hl + b.r + b.hl);
        double s, t;
        if (!sd_line_line(a.c, a.a, b.c, b.a, &s, &t) || !(fabs(s) <= a.hl && fabs(t) <= b.hl)) continue;
        const sd_vec3 pa = v3_madd(a.c, a.a, s), pb = v3_madd(b.c, b.a, t);
        const double ov = a.r + b.r - v3_norm(v3_sub(pa, pb));
        if (!(ov > tol && a.hl - fabs(s) > tol && b.hl - fabs(t) > tol)) continue;
        deep++;
        const sd_vec3 dirs[5] = {v3_sub(pa, pb), v3_cross(a.a, b.a), a.a, b.a, v3_sub(a.c, b.c)};
        for (int k = 0; k < 5 + 16; k++) {
            sd_vec3 n = k < 5 ? dirs[k] : rand_unit();
            const double nn = v3_norm(n);
            if (!(nn > 1e-12)) continue;
            n = v3_scale(n, 1.0 / nn);
            CHECK(sep_margin(&a, &b, n) < -0.5 * tol);
        }
        sd_manifold m;
        sd_geom_cyl_cyl(&a, &b, &m);
        CHECK(find_feature(&m, 0) >= 0);
    }
    CHECK(deep > 2000);
}

/* The separating axis carried from call to call (sd_geom_cyl_cyl_sep) changes no answer: a log
 * drifting and turning past another log or a pipe in small steps gets, at every step, the
 * manifold of sd_geom_cyl_cyl bit for bit, with its own axis carried along and with a random
 * axis handed in instead; and the carried axis is used. */
static void test_cyl_cyl_sep_axis(void)
{
    long calls = 0, kept = 0, apart = 0, touching = 0;
    for (int run = 0; run < 400; run++) {
        const int pipe = run & 1;
        sd_cyl b = mkcyl(v3(0, 0, 0), rand_unit(), pipe ? 0.009 : 0.005, pipe ? 0.1 : 0.05);
        sd_cyl a = mkcyl(v3(urange(-0.03, 0.03), urange(-0.03, 0.03), urange(-0.03, 0.03)), rand_unit(), 0.005, 0.05);
        const sd_vec3 v = v3_scale(rand_unit(), urange(0.05, 0.5)), w = v3_scale(rand_unit(), urange(0.0, 20.0));
        const double dt = 2e-4;
        sd_vec3 sep = v3(0, 0, 0);
        for (int step = 0; step < 300; step++) {
            a.c = v3_madd(a.c, v, dt);
            a.a = v3_normalize(v3_madd(a.a, v3_cross(w, a.a), dt));
            sd_manifold m1, m2, m3;
            const int n1 = sd_geom_cyl_cyl(&a, &b, &m1);
            const sd_vec3 in = sep;
            sd_geom_cyl_cyl_sep(&a, &b, &m2, &sep);
            CHECK(same_manifold(&m1, &m2));
            sd_vec3 any = rand_unit();
            sd_geom_cyl_cyl_sep(&a, &b, &m3, &any);
            CHECK(same_manifold(&m1, &m3));
            calls++;
            touching += n1 > 0;
            if (sep.x != 0.0 || sep.y != 0.0 || sep.z != 0.0) {
                apart++;
                CHECK(n1 == 0);
                CHECK_NEAR(v3_norm(sep), 1.0, 1e-12);
                CHECK(sep_margin(&a, &b, sep) >= 0.0); /* it does separate them */
                kept += sep.x == in.x && sep.y == in.y && sep.z == in.z;
            }
        }
    }
    /* a fair share of contacts; of the apart steps, most are the capsules apart (no axis
     * kept), and of those shown apart by an axis, most by the carried one */
    CHECK(touching > calls / 20);
    CHECK(apart > 1000);
    CHECK(kept > apart / 2);
    printf("carried axis: %ld calls, %ld touching, %ld shown apart by an axis, %ld of them by the carried one\n", calls,
           touching, apart, kept);
}

/* Squared distance of the two axis segments, by alternating clamped projections (the
 * distance is convex in the two parameters); for classifying pairs in the test below. */
static double seg_seg_dist2(const sd_cyl *a, const sd_cyl *b)
{
    double s = 0.0, t = 0.0;
    for (int it = 0; it < 2000; it++) {
        const sd_vec3 q = v3_madd(b->c, b->a, t);
        s = v3_dot(v3_sub(q, a->c), a->a);
        s = s > a->hl ? a->hl : (s < -a->hl ? -a->hl : s);
        const sd_vec3 p = v3_madd(a->c, a->a, s);
        t = v3_dot(v3_sub(p, b->c), b->a);
        t = t > b->hl ? b->hl : (t < -b->hl ? -b->hl : t);
    }
    return v3_norm2(v3_sub(v3_madd(a->c, a->a, s), v3_madd(b->c, b->a, t)));
}

/* inside the solid cylinder c, to within e */
static int in_cyl(const sd_cyl *c, sd_vec3 x, double e)
{
    const sd_vec3 d = v3_sub(x, c->c);
    const double t = v3_dot(d, c->a);
    return fabs(t) <= c->hl + e && v3_norm(v3_madd(d, c->a, -t)) <= c->r + e;
}

/* GJK before the last resort: two logs (or a log and a pipe) placed 1 um to 1 mm past first
 * touch along a random direction, and as far inside. Apart: no contact with GJK on or off,
 * and every axis it returns separates the two; of the near misses that reach the last resort
 * (capsules overlapping, no fixed axis apart) it finds an axis for nearly all, where the
 * alternating projections find one for few. Inside: every pair touches with GJK; without it,
 * the pairs it misses are the last resort's (two rims crossing, below), and wherever both
 * touch through a feature pair (not the last resort) the manifolds are the same bits. */
static void test_cyl_cyl_gjk(void)
{
    long near_miss = 0, old_axis = 0, gjk_axis = 0, inside = 0, touching_in = 0, missed_old = 0, same = 0;
    for (int run = 0; run < 20000; run++) {
        const int pipe = run % 3 == 0;
        sd_cyl b = mkcyl(v3(0, 0, 0), rand_unit(), pipe ? 0.009 : 0.005, pipe ? 0.1 : 0.05);
        sd_cyl a = mkcyl(v3(0, 0, 0), rand_unit(), urange(0.003, 0.006), urange(0.01, 0.05));
        const sd_vec3 dir = rand_unit();
        double lo = 0.0, hi = 0.3;
        for (int k = 0; k < 60; k++) {
            sd_manifold m;
            a.c = v3_scale(dir, 0.5 * (lo + hi));
            if (sd_geom_cyl_cyl(&a, &b, &m) > 0)
                lo = 0.5 * (lo + hi);
            else
                hi = 0.5 * (lo + hi);
        }
        const double d = pow(10.0, urange(-6.0, -3.0));
        for (int side = 0; side < 2; side++) {
            a.c = v3_scale(dir, side ? lo - d : hi + d);
            sd_manifold m_on, m_off;
            sd_vec3 s_on = v3(0, 0, 0), s_off = v3(0, 0, 0);
            const int n_off = sd_geom_cyl_cyl_sep_nogjk(&a, &b, &m_off, &s_off);
            const int n_on = sd_geom_cyl_cyl_sep(&a, &b, &m_on, &s_on);
            const int has_on = s_on.x != 0.0 || s_on.y != 0.0 || s_on.z != 0.0;
            const int has_off = s_off.x != 0.0 || s_off.y != 0.0 || s_off.z != 0.0;
            if (has_on) {
                CHECK(n_on == 0);
                CHECK_NEAR(v3_norm(s_on), 1.0, 1e-12);
                CHECK(sep_margin(&a, &b, s_on) > 0.0);
            }
            if (side) {
                inside++;
                touching_in += n_on > 0;
                missed_old += n_on > 0 && n_off == 0;
                if (n_off > 0 && m_off.feature[0] != 9 && m_on.feature[0] != 9) {
                    CHECK(same_manifold(&m_on, &m_off));
                    same++;
                }
                for (int k = 0; k < n_on; k++)
                    if (m_on.feature[k] == 9) { /* the last resort's point is in both */
                        CHECK(in_cyl(&a, m_on.point[k], 1e-12) && in_cyl(&b, m_on.point[k], 1e-12));
                        CHECK(m_on.overlap[k] > 0.0 && m_on.overlap[k] <= d * (1.0 + 1e-6) + 1e-12);
                    }
                continue;
            }
            CHECK(n_on == 0 && n_off == 0);
            const double rr = a.r + b.r;
            if (seg_seg_dist2(&a, &b) < rr * rr * (1.0 - 1e-9)) {
                /* capsules overlapping: past the capsule test */
                CHECK(!(has_off && !has_on)); /* GJK never loses an axis the rest finds */
                near_miss++;
                old_axis += has_off;
                gjk_axis += has_on;
            }
        }
    }
    printf("GJK first: %ld near misses past the capsule test, an axis found for %ld (without GJK %ld); "
           "%ld of %ld placed inside touch (without GJK %ld missed), %ld feature-pair manifolds the same\n",
           near_miss, gjk_axis, old_axis, touching_in, inside, missed_old, same);
    CHECK(near_miss > 5000);
    CHECK(gjk_axis > near_miss - near_miss / 100); /* 99 % */
    CHECK(gjk_axis > old_axis + near_miss / 10);   /* it finds axes the rest does not */
    CHECK(touching_in == inside);
    CHECK(same > inside / 2);
}

/* Two logs' end rims crossing, a pose from the paper's packing (t = 0.02 s, both logs 10 x
 * 100 mm): each rim passes a few micrometres inside the other log near its end, so no feature
 * pair (side-side, disk-side, disk-face) describes the overlap, and the alternating projections
 * of the last resort found no common point: the contact was missed while the rims ran into each
 * other at 0.5 m/s. Reference depth: the least separating-axis overlap over all directions (for
 * two convex solids, the depth of their overlap), found here by a grid over the sphere and a
 * shrinking random search, independent of the kernel's search. */
static void test_cyl_cyl_rim_crossing(void)
{
    sd_cyl a = mkcyl(v3(0.2967132453935783, 0.1268450692757728, 0.038107778573011217),
                     v3(-0.33376536071384388, 0.90005577119749824, 0.28017903690610779), 0.005, 0.05);
    sd_cyl b = mkcyl(v3(0.25471640618107627, 0.15831090740141932, 0.09668873270382114),
                     v3(0.61717037538651254, 0.28381634636851599, -0.73385898460078702), 0.005, 0.05);
    a.a = v3_normalize(a.a);
    b.a = v3_normalize(b.a);
    double ref = -INFINITY;
    sd_vec3 rn = v3(0, 0, 1);
    for (int i = 0; i <= 400; i++)
        for (int j = 0; j < 800; j++) {
            const double th = M_PI * i / 400.0, ph = 2.0 * M_PI * j / 800.0;
            const sd_vec3 n = v3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
            const double mg = sep_margin(&a, &b, n);
            if (mg > ref) {
                ref = mg;
                rn = n;
            }
        }
    for (double h = 0.01; h > 1e-11; h *= 0.7)
        for (int k = 0; k < 200; k++) {
            const sd_vec3 n = v3_normalize(v3_madd(rn, rand_unit(), h));
            const double mg = sep_margin(&a, &b, n);
            if (mg > ref) {
                ref = mg;
                rn = n;
            }
        }
    sd_manifold m;
    const int n = sd_geom_cyl_cyl(&a, &b, &m);
    printf("rims crossing: reference depth %.6e m; kernel: %d contact(s), feature %d, overlap %.6e m\n", -ref, n,
           n ? m.feature[0] : -1, n ? m.overlap[0] : 0.0);
    CHECK(ref < -1e-6); /* they do overlap, by some 5 um */
    CHECK(n == 1 && m.feature[0] == 9);
    CHECK_NEAR(m.overlap[0], -ref, 1e-4 * -ref);
    CHECK(fabs(v3_dot(m.normal[0], rn)) > 1.0 - 1e-6);
    CHECK(in_cyl(&a, m.point[0], 1e-12) && in_cyl(&b, m.point[0], 1e-12));
    /* pushed apart along the normal by the overlap and a little more: apart */
    sd_cyl a2 = a;
    a2.c = v3_madd(a.c, m.normal[0], m.overlap[0] + 1e-8);
    CHECK(sd_geom_cyl_cyl(&a2, &b, &m) == 0);
}

int main(void)
{
    test_sphere_cyl();
    test_cyl_cyl();
    test_cyl_tri();
    test_random_invariance();
    test_cyl_cyl_deep_side();
    test_cyl_cyl_sep_axis();
    test_cyl_cyl_gjk();
    test_cyl_cyl_rim_crossing();
    test_cyl_tri_clear_section();
    return check_report("test_geom_cyl");
}
