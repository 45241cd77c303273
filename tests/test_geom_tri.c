/* Sphere–triangle contact with the triangle's edge lines precomputed (sd_geom_sphere_tri_e,
 * what the contact pass calls) against closed-form cases and against the closest-point
 * search of sd_geom_sphere_tri on random spheres around random triangles: the same contacts,
 * features, normals, overlaps and points. */
#include <stdint.h>

#include "check.h"
#include "core/rng.h"
#include "geom/geom.h"

static sd_rng rng = {0x7a1e7a1e5eedULL}; /* the engine's splitmix64 (core/rng.h) */
static double urange(double lo, double hi) { return sd_rng_range(&rng, lo, hi); }

static sd_tri mk(sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_tri_edges *e)
{
    sd_tri t;
    sd_tri_init(&t, a, b, c);
    sd_tri_edges_init(e, &t);
    return t;
}

static void closed_form(void)
{
    sd_tri_edges e;
    const sd_tri t = mk(v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), &e);
    sd_manifold m;
    /* the edge lines: inward unit normals, the hypotenuse at distance 1/sqrt(2) from v0 */
    CHECK_VEC_NEAR(e.m[0], v3(0, 1, 0), 1e-15);
    CHECK_VEC_NEAR(e.m[1], v3(-sqrt(0.5), -sqrt(0.5), 0), 1e-15);
    CHECK_VEC_NEAR(e.m[2], v3(1, 0, 0), 1e-15);
    CHECK_NEAR(e.h[1], -sqrt(0.5), 1e-15);
    /* face, above: overlap r - s, normal +z, point midway into the overlap */
    CHECK(sd_geom_sphere_tri_e(v3(0.3, 0.3, 0.05), 0.1, &t, &e, &m) == 1);
    CHECK(m.n == 1 && m.feature[0] == SD_TRI_FACE);
    CHECK_NEAR(m.overlap[0], 0.05, 1e-15);
    CHECK_VEC_NEAR(m.normal[0], v3(0, 0, 1), 0.0);
    CHECK_VEC_NEAR(m.point[0], v3(0.3, 0.3, -0.025), 1e-15);
    /* face, below (two-sided): normal -z */
    CHECK(sd_geom_sphere_tri_e(v3(0.2, 0.1, -0.04), 0.1, &t, &e, &m) == 1);
    CHECK_VEC_NEAR(m.normal[0], v3(0, 0, -1), 0.0);
    CHECK_NEAR(m.overlap[0], 0.06, 1e-15);
    CHECK_VEC_NEAR(m.point[0], v3(0.2, 0.1, 0.03), 1e-15);
    /* beyond the hypotenuse by 0.2/sqrt(2) = 0.141 in the plane: none, though within r of the plane */
    CHECK(sd_geom_sphere_tri_e(v3(0.6, 0.6, 0.0), 0.1, &t, &e, &m) == 0 && m.n == 0);
    /* beyond it by 0.1/sqrt(2) in the plane and 0.02 above: an edge contact at distance
     * sqrt(0.005 + 0.0004) */
    CHECK(sd_geom_sphere_tri_e(v3(0.55, 0.55, 0.02), 0.1, &t, &e, &m) == 1);
    CHECK(m.feature[0] == SD_TRI_EDGE0 + 1);
    CHECK_NEAR(m.overlap[0], 0.1 - sqrt(0.0054), 1e-15);
    CHECK_VEC_NEAR(m.normal[0], v3_scale(v3(0.05, 0.05, 0.02), 1.0 / sqrt(0.0054)), 1e-15);
    /* off a vertex: (-0.03, -0.04) in the plane, 0 above: distance 0.05 */
    CHECK(sd_geom_sphere_tri_e(v3(-0.03, -0.04, 0.0), 0.1, &t, &e, &m) == 1);
    CHECK(m.feature[0] == SD_TRI_VERT0 + 0);
    CHECK_NEAR(m.overlap[0], 0.05, 1e-15);
    /* just inside an edge (1e-10 m, under the face clearance): the closest-point search decides */
    CHECK(sd_geom_sphere_tri_e(v3(0.4, 1e-10, 0.03), 0.1, &t, &e, &m) == 1);
    CHECK(m.feature[0] == SD_TRI_FACE);
    CHECK_NEAR(m.overlap[0], 0.07, 1e-15);
    /* clear of the plane by r: none */
    CHECK(sd_geom_sphere_tri_e(v3(0.3, 0.3, 0.1), 0.1, &t, &e, &m) == 0);
}

static sd_vec3 rvec(double s) { return v3(urange(-s, s), urange(-s, s), urange(-s, s)); }

/* random triangles from 1 mm to 10 m, slivers among them, random spheres near them */
static void against_closest_point(void)
{
    long n_face = 0, n_reject = 0, n_other = 0, n_contact = 0;
    for (int it = 0; it < 20000; it++) {
        const double L = pow(10.0, urange(-3.0, 1.0));
        const sd_vec3 o = rvec(5.0);
        sd_vec3 a = v3_add(o, rvec(L)), b = v3_add(o, rvec(L)), c = v3_add(o, rvec(L));
        if (it % 5 == 0) c = v3_add(v3_scale(v3_add(a, b), 0.5), rvec(1e-3 * L)); /* a sliver */
        if (!(v3_norm(v3_cross(v3_sub(b, a), v3_sub(c, a))) > 1e-9 * L * L)) continue;
        sd_tri_edges e;
        const sd_tri t = mk(a, b, c, &e);
        const sd_vec3 g = v3_scale(v3_add(v3_add(a, b), c), 1.0 / 3.0);
        for (int j = 0; j < 10; j++) {
            const double r = L * urange(0.01, 0.6);
            const sd_vec3 p = v3_add(g, rvec(0.8 * L));
            sd_manifold mr, me;
            const int kr = sd_geom_sphere_tri(p, r, &t, &mr), ke = sd_geom_sphere_tri_e(p, r, &t, &e, &me);
            const double tol = 1e-12 * (L > 1.0 ? L : 1.0) * 5.0;
            CHECK(kr == ke && mr.n == me.n);
            if (kr != ke || mr.n != me.n) {
                fprintf(stderr, "  it %d: reference %d, edge lines %d (L %.3g, r %.3g)\n", it, kr, ke, L, r);
                continue;
            }
            /* which path it took, from the same tests as sd_geom_sphere_tri_e */
            const double s = v3_dot(v3_sub(p, a), t.n);
            double emin = 1e300;
            for (int k = 0; k < 3; k++) {
                const double ek = v3_dot(e.m[k], p) - e.h[k];
                emin = ek < emin ? ek : emin;
            }
            if (fabs(s) < r) {
                if (emin > 1e-9)
                    n_face++;
                else if (emin < 0.0 && s * s + emin * emin >= r * r)
                    n_reject++;
                else
                    n_other++;
            }
            if (ke == 0) continue;
            n_contact++;
            CHECK(mr.feature[0] == me.feature[0]);
            CHECK_NEAR(me.overlap[0], mr.overlap[0], tol);
            CHECK_VEC_NEAR(me.normal[0], mr.normal[0], 1e-12);
            /* a sliver's barycentric reconstruction in the closest-point search is off by up to
             * ~1e-11 L in the plane (and off the plane); the projection is not */
            CHECK_VEC_NEAR(me.point[0], mr.point[0], it % 5 == 0 ? 1e-10 * (L > 1.0 ? L : 1.0) : tol);
            if (me.feature[0] == SD_TRI_FACE) {
                /* on the face: the contact point lies half the overlap below the plane, right
                 * under the centre */
                const sd_vec3 q = v3_madd(me.point[0], me.normal[0], 0.5 * me.overlap[0]);
                CHECK_NEAR(v3_dot(v3_sub(q, a), t.n), 0.0, 1e-14);
                CHECK_NEAR(v3_norm(v3_cross(v3_sub(p, q), t.n)), 0.0, 1e-14);
            }
        }
    }
    printf("face by the edge lines %ld, rejected by them %ld, closest-point search %ld, contacts %ld\n", n_face,
           n_reject, n_other, n_contact);
    /* all three paths taken, and often */
    CHECK(n_face > 5000);
    CHECK(n_reject > 5000);
    CHECK(n_other > 5000);
}

int main(void)
{
    closed_form();
    against_closest_point();
    return check_report("test_geom_tri");
}
