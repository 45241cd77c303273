/* Narrow-phase contact kernels (SPEC §4, Table 1).
 *
 * Every kernel is a pure function of two shapes. It fills a small manifold and returns the
 * number of contacts (0 when the solids do not overlap). Conventions shared by all kernels:
 *  - the pair is (A, B) in the order of the function name;
 *  - normal[k] is a unit vector pointing from B towards A: the normal force on A is
 *    +F_n normal[k], on B it is -F_n normal[k];
 *  - overlap[k] > 0 is the penetration depth along normal[k] (deepest point);
 *  - point[k] is the contact point, midway between the two surfaces along the normal;
 *  - feature[k] is a small non-negative integer naming the pair of features in contact
 *    (e.g. which end rim touches), stable while the configuration changes continuously,
 *    so that tangential spring history can be matched from one step to the next.
 *    Features of one manifold are distinct.
 *  - share[k] (cylinder kernels only) is the point's raw share of the pair's damping: its
 *    overlap, plus the overlaps of near-duplicate points merged into it. The engine divides
 *    the shares of the points whose normals agree by their sum (sd_manifold_shares) and
 *    scales their springs to sum to K_n times the deepest overlap, so that a flat or line
 *    contact has the stiffness and damping of one point in total, continuous as the points
 *    come and go (docs/physics.md §16).
 * No kernel may return NaN or Inf for finite input; degenerate configurations (parallel or
 * coincident axes, a sphere centre on an axis, a disk flat on a plane) give finite answers.
 */
#ifndef SD_GEOM_H
#define SD_GEOM_H

#include "../core/vmath.h"

#define SD_MANIFOLD_MAX 4

typedef struct {
    int n;
    sd_vec3 normal[SD_MANIFOLD_MAX];
    sd_vec3 point[SD_MANIFOLD_MAX];
    double overlap[SD_MANIFOLD_MAX];
    int feature[SD_MANIFOLD_MAX];
    double share[SD_MANIFOLD_MAX];
} sd_manifold;

/* Cylinder with flat end faces: centre c, unit axis a, radius r, half length hl. */
typedef struct {
    sd_vec3 c;
    sd_vec3 a;
    double r;
    double hl;
} sd_cyl;

/* Triangle: vertices v[0..2] and unit normal n = normalize((v1-v0) x (v2-v0)).
 * Triangles are two-sided: the normal of a face contact points to the side of A. */
typedef struct {
    sd_vec3 v[3];
    sd_vec3 n;
} sd_tri;

/* Triangle feature codes returned by kernels against a triangle (low 3 bits of feature):
 * 0 face, 1..3 edge k-1 (from v[k-1] to v[k % 3]), 4..6 vertex k-4. */
enum { SD_TRI_FACE = 0, SD_TRI_EDGE0 = 1, SD_TRI_VERT0 = 4 };
#define SD_TRI_FEATURE_BITS 3

static inline void sd_tri_init(sd_tri *t, sd_vec3 a, sd_vec3 b, sd_vec3 c)
{
    t->v[0] = a;
    t->v[1] = b;
    t->v[2] = c;
    t->n = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

/* A triangle's edge lines in its plane: m[k] is the unit normal of edge k (from v[k] to
 * v[(k+1) % 3]) lying in the plane and pointing into the triangle, h[k] = m[k]·v[k], so that
 * m[k]·p − h[k] is the distance of p's projection on the plane from that line, positive on
 * the triangle's side. Derived from the vertices (sd_tri_edges_init), kept beside them. */
typedef struct {
    sd_vec3 m[3];
    double h[3];
} sd_tri_edges;

void sd_tri_edges_init(sd_tri_edges *e, const sd_tri *t);

/* Closest point on triangle t to p; *feature receives the triangle feature code of the
 * region it lies in (face, edge or vertex). */
sd_vec3 sd_geom_closest_on_tri(const sd_tri *t, sd_vec3 p, int *feature);

/* The first, exact rejections of sd_geom_sphere_cyl and sd_geom_cyl_cyl, inline so that the
 * pair loop can skip a log's non-touching pairs without the manifold round trip. 1: apart. */
static inline int sd_sphere_cyl_apart(sd_vec3 c, double r, const sd_cyl *b, double *rho2_out)
{
    /* beyond an end plane, or outside the side surface, by r or more */
    sd_vec3 d = v3_sub(c, b->c);
    double t = v3_dot(d, b->a);
    if (fabs(t) - b->hl >= r) return 1;
    double rho2 = v3_norm2(v3_madd(d, b->a, -t)), rr = b->r + r;
    *rho2_out = rho2;
    return rho2 >= rr * rr;
}

static inline int sd_cyl_cyl_apart(const sd_cyl *a, const sd_cyl *b)
{
    /* bounding spheres (eq 44) */
    double ra = sqrt(a->r * a->r + a->hl * a->hl), rb = sqrt(b->r * b->r + b->hl * b->hl);
    return v3_norm2(v3_sub(a->c, b->c)) >= (ra + rb) * (ra + rb);
}

int sd_geom_sphere_sphere(sd_vec3 ca, double ra, sd_vec3 cb, double rb, sd_manifold *m);
/* feature = triangle feature code of the closest point. */
int sd_geom_sphere_tri(sd_vec3 c, double r, const sd_tri *t, sd_manifold *m);
/* The same contact with the triangle's edge lines at hand (what the contact pass calls): a
 * sphere whose projection lies inside the triangle, clear of every edge, touches the face and
 * one farther than r from the triangle's half-plane beyond an edge touches nothing, both
 * found from three dot products; the rest go through sd_geom_sphere_tri. */
int sd_geom_sphere_tri_e(sd_vec3 c, double r, const sd_tri *t, const sd_tri_edges *e, sd_manifold *m);

/* A projection this far inside every edge line is in the face region of the closest-point
 * search as well (its barycentric tests carry rounding of ~1e-16 L^2 for a triangle of size
 * L: 1e-13 m for L = 4 m), so the two agree on the feature. */
#define SD_TRI_FACE_CLEAR 1e-9

/* The first part of sd_geom_sphere_tri_e: 0 when the sphere (centre c, radius r) cannot touch
 * the triangle, 1 for a contact with the face, 2 when it is near an edge or a vertex (the
 * closest-point search decides). *s: the centre's signed distance from the plane. */
static inline int sd_sphere_tri_class(sd_vec3 c, double r, const sd_tri *t, const sd_tri_edges *e, double *s_out)
{
    const double s = v3_dot(v3_sub(c, t->v[0]), t->n);
    *s_out = s;
    if (fabs(s) >= r) return 0;
    const double e0 = v3_dot(e->m[0], c) - e->h[0], e1 = v3_dot(e->m[1], c) - e->h[1],
                 e2 = v3_dot(e->m[2], c) - e->h[2];
    const double e01 = e0 < e1 ? e0 : e1, emin = e01 < e2 ? e01 : e2;
    if (emin > SD_TRI_FACE_CLEAR) return 1;
    /* the triangle lies in the half-plane emin >= 0 of its plane: nothing of it is nearer
     * than sqrt(s^2 + emin^2) */
    if (emin < 0.0 && s * s + emin * emin >= r * r) return 0;
    return 2;
}

/* A face contact (class 1 above): the normal is the plane's, towards the centre; the point is
 * the projection of the centre moved half the overlap back along it. */
static inline void sd_sphere_tri_face(sd_vec3 c, double r, const sd_tri *t, double s, sd_vec3 *n, double *ov,
                                      sd_vec3 *point)
{
    *n = s >= 0.0 ? t->n : v3_neg(t->n);
    *ov = r - fabs(s);
    *point = v3_madd(v3_madd(c, t->n, -s), *n, -0.5 * *ov);
}
int sd_geom_sphere_cyl(sd_vec3 c, double r, const sd_cyl *b, sd_manifold *m);
int sd_geom_cyl_cyl(const sd_cyl *a, const sd_cyl *b, sd_manifold *m);
/* The same, with a separating axis carried from one call to the next (sep, a unit vector, or
 * zero for none): tested first, and replaced by the axis that shows the two apart, or zero.
 * The answer is that of sd_geom_cyl_cyl bit for bit: the kept axis must show them apart by
 * more than 4e-9 of their summed sizes, where no feature pair can be accepted. */
int sd_geom_cyl_cyl_sep(const sd_cyl *a, const sd_cyl *b, sd_manifold *m, sd_vec3 *sep);
/* sd_geom_cyl_cyl_sep without GJK before its last resort's older search, for the tests, which
 * compare the two: the same answers wherever the older search finds a contact or an axis, and
 * contacts where it missed two rims crossing. */
int sd_geom_cyl_cyl_sep_nogjk(const sd_cyl *a, const sd_cyl *b, sd_manifold *m, sd_vec3 *sep);
/* feature = (cylinder feature << SD_TRI_FEATURE_BITS) | triangle feature code. */
int sd_geom_cyl_tri(const sd_cyl *a, const sd_tri *t, sd_manifold *m);

#endif
