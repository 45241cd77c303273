/* Cases 5, 6, 7 (eqs 28-39) and the gaps between them: two solid cylinders with flat ends.
 *
 * Candidate feature pairs, each with its own exact local depth, normal and point:
 *   S     side-side: common perpendicular of the two axes (eqs 28-31), feet inside both axes;
 *   E(P)  end disk of P against the side of Q (case 6, eqs 32-35, done exactly): the point of
 *         the disk nearest the axis of Q, depth r_Q - rho, normal radial from Q's axis;
 *   F(P)  end disk of P against an end face of Q (case 7, eqs 36-39): the rim point of the
 *         disk deepest past Q's end plane (the disk centre region when the disks are
 *         parallel), depth below the plane, normal = Q's end-face normal; the point must lie
 *         inside Q (within its radius and its length);
 * for P, Q = A, B and B, A. Rim against side, rim against rim and rim against end face are the
 * E and F candidates with the rim point as the deepest point of the disk. A candidate is kept
 * when it is a true penetration and describes how the two bodies actually separate: S always;
 * E when the side is the nearest surface of Q to the point, or when the separating-axis
 * overlap of the two whole bodies along its normal equals its depth; F only in the latter
 * case. Of the E and F candidates of one disk the shallower is kept (least penetration
 * direction); near-duplicates (close points, similar normals) are merged, keeping the deepest.
 * feature: 0 side-side; A's disk -/+: 1/2 against B's side, 3/4 against an end face of B;
 * B's disk -/+: 5/6 against A's side, 7/8 against an end face of A; 9 last resort (rims crossing, deep irregular
 * overlaps). */
#include <stddef.h>

#include "cyl_common.h"

typedef struct {
    sd_vec3 n; /* from Q towards P */
    sd_vec3 p;
    double ov;
    int kind; /* 0 side (E), 1 end face (F) */
} sd_cc_cand;

/* Separating-axis overlap of the projections of P and Q on n, for pushing P along +n. */
static double cc_sat_overlap(const sd_cyl *P, const sd_cyl *Q, sd_vec3 n)
{
    return sd_cyl_extent(P, n) + sd_cyl_extent(Q, n) - v3_dot(v3_sub(P->c, Q->c), n);
}

/* The contact of end disk e of P with Q, if any (normal from Q towards P). */
static int cc_disk_into(const sd_cyl *P, double e, const sd_cyl *Q, double tol, sd_cc_cand *out)
{
    sd_vec3 ce = sd_cyl_end(P, e);
    /* exact rejection: every point the tests below can accept lies in the disk (within P->r of
     * its centre) and within Q->r + tol of Q's axis segment, so a centre farther than
     * P->r + Q->r + 2 tol from that segment has no contact (the common case: two logs side by
     * side, their ends clear of each other) */
    {
        sd_vec3 dq = v3_sub(ce, Q->c);
        double t = v3_dot(dq, Q->a);
        t = t > Q->hl ? Q->hl : (t < -Q->hl ? -Q->hl : t);
        double reach = P->r + Q->r + 2.0 * tol;
        if (v3_norm2(v3_madd(dq, Q->a, -t)) > reach * reach) return 0;
    }
    int found = 0;
    /* E: disk against Q's side */
    {
        sd_vec3 x = sd_disk_closest_to_line(ce, P->a, P->r, Q->c, Q->a);
        sd_vec3 d = v3_sub(x, Q->c);
        double tq = v3_dot(d, Q->a);
        sd_vec3 w = v3_madd(d, Q->a, -tq);
        double rho = v3_norm(w);
        if (fabs(tq) <= Q->hl + tol && rho < Q->r) {
            sd_vec3 n = rho > 1e-300 ? v3_scale(w, 1.0 / rho) : sd_perp_dir(Q->a, v3_sub(P->c, Q->c), P->a);
            double ov = Q->r - rho;
            int side_nearest = ov <= Q->hl - fabs(tq);
            if (side_nearest || cc_sat_overlap(P, Q, n) <= ov + tol) {
                out->n = n;
                out->ov = ov;
                out->p = v3_madd(x, n, 0.5 * ov);
                out->kind = 0;
                found = 1;
            }
        }
    }
    /* F: disk against an end face of Q */
    for (int k = 0; k < 2; k++) {
        double f = k ? 1.0 : -1.0;
        sd_vec3 nf = v3_scale(Q->a, f);
        sd_vec3 cf = sd_cyl_end(Q, f);
        sd_vec3 dp = v3_madd(v3_neg(nf), P->a, v3_dot(nf, P->a)); /* -nf projected on the disk plane */
        double ndp = v3_norm(dp);
        sd_vec3 x;
        if (ndp > 1e-12) {
            x = v3_madd(ce, dp, P->r / ndp);
        } else {
            /* parallel disks: middle of the lens of the two disks along their centre line */
            sd_vec3 dv = v3_sub(ce, cf);
            dv = v3_madd(dv, Q->a, -v3_dot(dv, Q->a));
            double dd = v3_norm(dv);
            if (dd > 1e-300) {
                sd_vec3 dir = v3_scale(dv, 1.0 / dd);
                double lo = dd - P->r > -Q->r ? dd - P->r : -Q->r;
                double hi = dd + P->r < Q->r ? dd + P->r : Q->r;
                x = v3_madd(ce, dir, 0.5 * (lo + hi) - dd);
            } else {
                x = ce;
            }
        }
        sd_vec3 d = v3_sub(x, cf);
        double ov = -v3_dot(d, nf);
        if (!(ov > 0.0) || ov > 2.0 * Q->hl) continue;
        double rho = v3_norm(v3_madd(d, Q->a, -v3_dot(d, Q->a)));
        if (rho > Q->r + tol) continue;
        /* the end face must be Q's nearest surface to x (as the side must be for E): a disk
         * that pokes out past Q's end near the side would otherwise get the depth through the
         * whole face, up to 2 hl (test_geom_continuity) */
        if (ov > Q->r - rho + tol) continue;
        if (cc_sat_overlap(P, Q, nf) > ov + tol) continue;
        if (!found || ov < out->ov) {
            out->n = nf;
            out->ov = ov;
            out->p = v3_madd(x, nf, 0.5 * ov);
            out->kind = 1;
            found = 1;
        }
    }
    return found;
}

/* Closest points of the two axis segments (Ericson, Real-Time Collision Detection, 5.1.9). */
static void cc_seg_seg(const sd_cyl *a, const sd_cyl *b, sd_vec3 *pa, sd_vec3 *pb)
{
    sd_vec3 r = v3_sub(sd_cyl_end(a, -1.0), sd_cyl_end(b, -1.0));
    double la = 2.0 * a->hl, lb = 2.0 * b->hl;
    double ab = v3_dot(a->a, b->a), c = v3_dot(a->a, r) * la, f = v3_dot(b->a, r) * lb;
    double A = la * la, E = lb * lb, B = ab * la * lb;
    double den = A * E - B * B, s = 0.0, t;
    if (den > 1e-20 * A * E) {
        s = (B * f - c * E) / den;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    }
    t = (B * s + f) / E;
    if (t < 0.0) {
        t = 0.0;
        s = -c / A;
    } else if (t > 1.0) {
        t = 1.0;
        s = (B - c) / A;
    }
    s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    *pa = v3_madd(sd_cyl_end(a, -1.0), a->a, s * la);
    *pb = v3_madd(sd_cyl_end(b, -1.0), b->a, t * lb);
}

static int cc_inside(const sd_cyl *c, sd_vec3 x)
{
    sd_vec3 d = v3_sub(x, c->c);
    double t = v3_dot(d, c->a);
    return fabs(t) <= c->hl && v3_norm2(v3_madd(d, c->a, -t)) <= c->r * c->r;
}

/* Nearest point of the solid cylinder c to x. */
static sd_vec3 cc_project(const sd_cyl *c, sd_vec3 x)
{
    sd_vec3 d = v3_sub(x, c->c);
    double t = v3_dot(d, c->a);
    sd_vec3 w = v3_madd(d, c->a, -t);
    double rho = v3_norm(w);
    if (t > c->hl) t = c->hl;
    if (t < -c->hl) t = -c->hl;
    if (rho > c->r) w = v3_scale(w, c->r / rho);
    return v3_add(v3_madd(c->c, c->a, t), w);
}

/* The separating-axis margin of a unit direction n: how far the projections of a and b on n
 * are apart (negative when they overlap); dc = a.c - b.c. */
static double cc_sep_margin(const sd_cyl *a, const sd_cyl *b, sd_vec3 dc, sd_vec3 n)
{
    return fabs(v3_dot(dc, n)) - (sd_cyl_extent(a, n) + sd_cyl_extent(b, n));
}

/* Farthest point of c along d (d need not be unit). */
static sd_vec3 cc_support(const sd_cyl *c, sd_vec3 d)
{
    const double t = v3_dot(d, c->a);
    const sd_vec3 p = v3_madd(c->c, c->a, t >= 0.0 ? c->hl : -c->hl);
    const sd_vec3 w = v3_madd(d, c->a, -t);
    const double wn = v3_norm(w);
    return wn > 0.0 ? v3_madd(p, w, c->r / wn) : p;
}

/* A vertex of the GJK simplex: w = pa - pb, a point of A - B, with the points of A and B it
 * came from (a common point of A and B is read off them when the origin is enclosed). */
typedef struct {
    sd_vec3 w, pa;
} gjk_vert;

/* Closest point v to the origin of the triangle s[0..2] (Ericson, Real-Time Collision
 * Detection, 5.1.5, with the query point at the origin); s and *n reduced to the vertices that
 * span v. Returns 0 for a degenerate triangle. */
static int gjk_triangle(gjk_vert *s, int *n, sd_vec3 *v)
{
    const sd_vec3 a = s[0].w, b = s[1].w, c = s[2].w;
    const sd_vec3 ab = v3_sub(b, a), ac = v3_sub(c, a);
    const double d1 = -v3_dot(ab, a), d2 = -v3_dot(ac, a);
    if (d1 <= 0.0 && d2 <= 0.0) {
        *n = 1;
        *v = a;
        return 1;
    }
    const double d3 = -v3_dot(ab, b), d4 = -v3_dot(ac, b);
    if (d3 >= 0.0 && d4 <= d3) {
        s[0] = s[1];
        *n = 1;
        *v = b;
        return 1;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        if (!(d1 - d3 > 0.0)) return 0;
        *n = 2;
        *v = v3_madd(a, ab, d1 / (d1 - d3));
        return 1;
    }
    const double d5 = -v3_dot(ab, c), d6 = -v3_dot(ac, c);
    if (d6 >= 0.0 && d5 <= d6) {
        s[0] = s[2];
        *n = 1;
        *v = c;
        return 1;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        if (!(d2 - d6 > 0.0)) return 0;
        s[1] = s[2];
        *n = 2;
        *v = v3_madd(a, ac, d2 / (d2 - d6));
        return 1;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        const double den = (d4 - d3) + (d5 - d6);
        if (!(den > 0.0)) return 0;
        s[0] = s[1];
        s[1] = s[2];
        *n = 2;
        *v = v3_madd(b, v3_sub(c, b), (d4 - d3) / den);
        return 1;
    }
    const double den = va + vb + vc;
    if (!(den > 0.0)) return 0;
    *n = 3;
    *v = v3_add(a, v3_add(v3_scale(ab, vb / den), v3_scale(ac, vc / den)));
    return 1;
}

static double det3(sd_vec3 a, sd_vec3 b, sd_vec3 c) { return v3_dot(a, v3_cross(b, c)); }

/* Closest point v to the origin of the simplex s[0..*n-1] (1 to 4 points, s[*n-1] the newest),
 * s reduced to the points that span it. Returns 1, or 2 with a common point x of A and B when
 * the tetrahedron holds the origin, or 0 when the simplex is degenerate. */
static int gjk_closest(gjk_vert *s, int *n, sd_vec3 *v, sd_vec3 *x)
{
    if (*n == 1) {
        *v = s[0].w;
        return 1;
    }
    if (*n == 2) {
        const sd_vec3 ab = v3_sub(s[1].w, s[0].w);
        const double t = -v3_dot(s[0].w, ab), dd = v3_norm2(ab);
        if (t <= 0.0) {
            *n = 1;
            *v = s[0].w;
        } else if (t >= dd) {
            s[0] = s[1];
            *n = 1;
            *v = s[0].w;
        } else {
            *v = v3_madd(s[0].w, ab, t / dd);
        }
        return 1;
    }
    if (*n == 3) return gjk_triangle(s, n, v);
    /* tetrahedron: the origin's barycentric coordinates; all >= 0, it is inside, and the same
     * weights of the points of A (each a point of A, so their mean is in A) give a point that
     * is also the same mean of the points of B: a common point */
    const sd_vec3 e1 = v3_sub(s[1].w, s[0].w), e2 = v3_sub(s[2].w, s[0].w), e3 = v3_sub(s[3].w, s[0].w),
                  o = v3_neg(s[0].w);
    const double vol = det3(e1, e2, e3);
    if (fabs(vol) > 1e-300) {
        const double l1 = det3(o, e2, e3) / vol, l2 = det3(e1, o, e3) / vol, l3 = det3(e1, e2, o) / vol,
                     l0 = 1.0 - l1 - l2 - l3;
        if (l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0) {
            *x = v3_add(v3_add(v3_scale(s[0].pa, l0), v3_scale(s[1].pa, l1)),
                        v3_add(v3_scale(s[2].pa, l2), v3_scale(s[3].pa, l3)));
            return 2;
        }
    }
    /* outside: the new point s[3] came from the origin's side of the old triangle's plane (it
     * is the support along -v), so the old face does not face the origin: the nearest of the
     * three faces through s[3] */
    static const int face[3][3] = {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
    double best = INFINITY;
    gjk_vert bs[3];
    sd_vec3 bv = v3(0.0, 0.0, 0.0);
    int bn = 0;
    for (int f = 0; f < 3; f++) {
        gjk_vert t[3] = {s[face[f][0]], s[face[f][1]], s[face[f][2]]};
        sd_vec3 q;
        int m = 3;
        if (!gjk_triangle(t, &m, &q)) continue;
        const double q2 = v3_norm2(q);
        if (q2 < best) {
            best = q2;
            bv = q;
            bn = m;
            for (int k = 0; k < m; k++)
                bs[k] = t[k];
        }
    }
    if (bn == 0) return 0;
    for (int k = 0; k < bn; k++)
        s[k] = bs[k];
    *n = bn;
    *v = bv;
    return 1;
}

/* GJK on A - B: v, the point of the current simplex nearest the origin, tends to the nearest
 * point of A - B, whose direction separates the two when they are apart. Returns 1 with the
 * unit axis once it shows them apart by more than 4 tol (the test of a carried axis); 2 with a
 * point x of both solids once a tetrahedron of the simplex holds the origin; 0 when neither
 * within 32 steps, or the simplex degenerates. */
static int cc_gjk(const sd_cyl *a, const sd_cyl *b, sd_vec3 dc, double tol, sd_vec3 *axis, sd_vec3 *x)
{
    gjk_vert s[4];
    sd_vec3 v = dc;
    int n = 0;
    for (int it = 0; it < 32; it++) {
        const double v2 = v3_norm2(v);
        if (!(v2 > 1e-300)) return 0;
        const sd_vec3 u = v3_scale(v, 1.0 / sqrt(v2));
        if (it > 0 && cc_sep_margin(a, b, dc, u) > 4.0 * tol) {
            *axis = u;
            return 1;
        }
        /* the point of A - B farthest along -v */
        const sd_vec3 pa = cc_support(a, v3_neg(v)), w = v3_sub(pa, cc_support(b, v));
        /* no progress towards the origin: v is (to rounding) the nearest point already */
        if (n > 0 && v2 - v3_dot(v, w) <= 1e-14 * v2) return 0;
        s[n].w = w;
        s[n].pa = pa;
        n++;
        const int r = gjk_closest(s, &n, &v, x);
        if (r != 1) return r;
    }
    return 0;
}

/* From the unit direction *n (along dc) with separating-axis overlap *ov, a pattern search on
 * the sphere for a nearby direction of smaller overlap: the best of eight steps of h (along two
 * tangents and their diagonals, which follow the creases where an extent has a kink), h halved
 * when none helps, down to 1e-7 rad (the depth then to ~1e-15 m); at most 800 trials. The
 * tangents come from the two axes (a x b, else dc), not from the world's frame, and the best of
 * the eight is taken, not the first: the same search for the pair in either order and in any
 * frame. */
static void cc_min_overlap(const sd_cyl *a, const sd_cyl *b, sd_vec3 dc, sd_vec3 *n, double *ov)
{
    const sd_vec3 ab = v3_cross(a->a, b->a);
    sd_vec3 bn = *n;
    double best = *ov, h = 0.25;
    for (int trial = 0; trial < 800 && h > 1e-7; trial += 8) {
        sd_vec3 t1 = v3_madd(ab, bn, -v3_dot(ab, bn));
        if (!(v3_norm2(t1) > 1e-12)) t1 = v3_madd(dc, bn, -v3_dot(dc, bn));
        t1 = v3_norm2(t1) > 1e-300 ? v3_normalize(t1) : v3_any_perp(bn);
        const sd_vec3 t2 = v3_cross(bn, t1);
        const double c = 0.7071067811865476;
        const sd_vec3 d1 = v3_scale(v3_add(t1, t2), c), d2 = v3_scale(v3_sub(t1, t2), c);
        const sd_vec3 step[8] = {t1, t2, v3_neg(t1), v3_neg(t2), d1, d2, v3_neg(d1), v3_neg(d2)};
        double o4 = best;
        sd_vec3 m4 = bn;
        for (int k = 0; k < 8; k++) {
            sd_vec3 m = v3_normalize(v3_madd(bn, step[k], h));
            if (v3_dot(m, dc) < 0.0) m = v3_neg(m);
            const double o = cc_sat_overlap(a, b, m);
            if (o < o4) {
                o4 = o;
                m4 = m;
            }
        }
        if (o4 < best) {
            best = o4;
            bn = m4;
        } else {
            h *= 0.5;
        }
    }
    *n = bn;
    *ov = best;
}

int sd_geom_cyl_cyl(const sd_cyl *a, const sd_cyl *b, sd_manifold *m) { return sd_geom_cyl_cyl_sep(a, b, m, NULL); }

static int cc_contact(const sd_cyl *a, const sd_cyl *b, sd_manifold *m, sd_vec3 *sep, int use_gjk);

int sd_geom_cyl_cyl_sep(const sd_cyl *a, const sd_cyl *b, sd_manifold *m, sd_vec3 *sep)
{
    return cc_contact(a, b, m, sep, 1);
}

int sd_geom_cyl_cyl_sep_nogjk(const sd_cyl *a, const sd_cyl *b, sd_manifold *m, sd_vec3 *sep)
{
    return cc_contact(a, b, m, sep, 0);
}

static int cc_contact(const sd_cyl *a, const sd_cyl *b, sd_manifold *m, sd_vec3 *sep, int use_gjk)
{
    m->n = 0;
    sd_vec3 dc = v3_sub(a->c, b->c);
    double tol = 1e-9 * (a->r + a->hl + b->r + b->hl);
    /* a separating axis kept from an earlier call: apart by more than 4 tol along it, no
     * feature pair below can be accepted (each needs a point within tol of both solids), so
     * the answer is the one the whole test would give */
    if (sep) {
        if ((sep->x != 0.0 || sep->y != 0.0 || sep->z != 0.0) && cc_sep_margin(a, b, dc, *sep) > 4.0 * tol) return 0;
        *sep = v3(0.0, 0.0, 0.0);
    }
    if (sd_cyl_cyl_apart(a, b)) return 0;
    /* cheap exact rejection first: each cylinder lies inside the capsule around its axis
     * segment, so axis segments farther apart than r_a + r_b cannot touch */
    sd_vec3 qa, qb;
    cc_seg_seg(a, b, &qa, &qb);
    const sd_vec3 gap = v3_sub(qa, qb);
    {
        double g2 = v3_norm2(gap), rr = a->r + b->r;
        if (g2 >= rr * rr) return 0;
    }

    sd_vec3 cn[5], cp[5];
    double cov[5], csh[5];
    int cid[5], nc = 0;

    /* S: side-side, common perpendicular of the axes (eqs 28-31) */
    double s, t;
    int s_deep = 0;
    if (sd_line_line(a->c, a->a, b->c, b->a, &s, &t) && fabs(s) <= a->hl && fabs(t) <= b->hl) {
        sd_vec3 pa = v3_madd(a->c, a->a, s), pb = v3_madd(b->c, b->a, t);
        sd_vec3 d = v3_sub(pa, pb);
        double dist = v3_norm(d);
        double ov = a->r + b->r - dist;
        if (ov > 0.0) {
            sd_vec3 n;
            if (dist > 1e-300) {
                n = v3_scale(d, 1.0 / dist);
            } else {
                n = v3_normalize(v3_cross(a->a, b->a));
                if (v3_dot(n, dc) < 0.0) n = v3_neg(n);
            }
            cn[nc] = n;
            cov[nc] = ov;
            /* midway between B's surface pb + rb n and A's surface pa - ra n */
            cp[nc] = v3_madd(v3_scale(v3_add(pa, pb), 0.5), n, 0.5 * (b->r - a->r));
            cid[nc] = 0;
            csh[nc] = ov;
            nc++;
            /* the point on pa-pb at ra - tol/2 from pa is inside both solids by tol/2 or more:
             * the two overlap, and no axis below can separate them */
            s_deep = ov > tol && a->hl - fabs(s) > tol && b->hl - fabs(t) > tol;
        }
    }
    if (!s_deep) {
        /* a few separating axes (segment gap direction, a x b, a, b, centre line), exact */
        sd_vec3 axes[5] = {gap, v3_cross(a->a, b->a), a->a, b->a, dc};
        for (int k = 0; k < 5; k++) {
            double nn = v3_norm(axes[k]);
            if (!(nn > 1e-12)) continue;
            /* the overlaps along +n and -n (cc_sat_overlap both ways): the extents do not
             * depend on the sign of n, bit for bit */
            const sd_vec3 n = v3_scale(axes[k], 1.0 / nn);
            const double e = sd_cyl_extent(a, n) + sd_cyl_extent(b, n), x = v3_dot(dc, n);
            if (e - x <= 0.0 || e + x <= 0.0) {
                if (sep) *sep = n;
                return 0;
            }
        }
    }

    /* end disks of A into B, then of B into A (normal flipped to point from B to A) */
    for (int k = 0; k < 4; k++) {
        double e = (k & 1) ? 1.0 : -1.0;
        sd_cc_cand c;
        if (k < 2) {
            if (!cc_disk_into(a, e, b, tol, &c)) continue;
            cn[nc] = c.n;
            cid[nc] = 1 + (k & 1) + 2 * c.kind;
        } else {
            if (!cc_disk_into(b, e, a, tol, &c)) continue;
            cn[nc] = v3_neg(c.n);
            cid[nc] = 5 + (k & 1) + 2 * c.kind;
        }
        cp[nc] = c.p;
        cov[nc] = c.ov;
        csh[nc] = c.ov;
        nc++;
    }
    /* Last resort, for overlaps that no feature pair above describes (two end rims crossing;
     * the end of one log deep in the side of another near its end): a witness point inside
     * both solids (from GJK, else the closest points of the axis segments, end centres, then
     * alternating projections onto the two solids). If one is found, one contact at it: the
     * least separating-axis overlap of a few directions, searched down to its nearest minimum
     * (the depth of the overlap) by cc_min_overlap. */
    if (nc == 0) {
        /* GJK first: it shows most pairs that get here apart (a small gap near an end or a
         * rim, where no fixed axis shows it), and finds a common point of the rest, among them
         * two end rims crossing each other, where the alternating projections below creep
         * and find none (docs/physics.md) */
        int g = 0;
        sd_vec3 gx = v3(0.0, 0.0, 0.0);
        if (use_gjk) {
            sd_vec3 u;
            g = cc_gjk(a, b, dc, tol, &u, &gx);
            if (g == 1) {
                if (sep) *sep = u;
                return 0;
            }
        }
        sd_vec3 pa, pb;
        cc_seg_seg(a, b, &pa, &pb);
        sd_vec3 w[7] = {v3_scale(v3_add(pa, pb), 0.5),
                        pa,
                        pb,
                        sd_cyl_end(a, -1.0),
                        sd_cyl_end(a, 1.0),
                        sd_cyl_end(b, -1.0),
                        sd_cyl_end(b, 1.0)};
        int found = -1;
        for (int k = 0; k < 7 && found < 0; k++)
            if (cc_inside(a, w[k]) && cc_inside(b, w[k])) found = k;
        sd_vec3 nxa = a->a, nxb = b->a; /* outward normals at the witness search point */
        if (found < 0 && g == 2) {
            int fa, fb;
            sd_cyl_signed_dist(a, gx, dc, &nxa, &fa);
            sd_cyl_signed_dist(b, gx, v3_neg(dc), &nxb, &fb);
            w[0] = gx;
            found = 0;
        }
        if (found < 0) {
            sd_vec3 x = w[0];
            for (int it = 0; it < 64; it++) {
                const sd_vec3 xa = cc_project(a, x), xb = cc_project(b, xa);
                /* two solids apart (most pairs that get here): the step from A's point to B's
                 * is a separating axis once the iterates settle; exact test, then done */
                const sd_vec3 n = v3_sub(xa, xb);
                const double nn = v3_norm(n);
                if (nn > 1e-12 * (a->r + b->r) && cc_sat_overlap(a, b, v3_scale(n, 1.0 / nn)) <= 0.0) {
                    if (sep) *sep = v3_scale(n, 1.0 / nn);
                    return 0;
                }
                /* a fixed point: the remaining iterations would not move it */
                if (xb.x == x.x && xb.y == x.y && xb.z == x.z) break;
                x = xb;
            }
            /* x is (nearly) in the intersection if there is one; step into both solids along
             * the sum of their inward normals to get a strict witness */
            int fa, fb;
            sd_cyl_signed_dist(a, x, dc, &nxa, &fa);
            sd_cyl_signed_dist(b, x, v3_neg(dc), &nxb, &fb);
            sd_vec3 in = v3_normalize(v3_neg(v3_add(nxa, nxb)));
            double h = a->r < b->r ? a->r : b->r;
            for (int k = 0; k < 40 && found < 0; k++, h *= 0.5) {
                sd_vec3 y = v3_madd(x, in, h);
                if (cc_inside(a, y) && cc_inside(b, y)) {
                    w[0] = y;
                    found = 0;
                }
            }
            /* no witness: apart (no contact either way), though no axis tried showed it; for
             * the next call, the step between the iterates or one of the two outward normals,
             * if it does (a log's end near another's rim, the iterates slow to settle) */
            if (found < 0 && sep) {
                const sd_vec3 xa = cc_project(a, x), xb = cc_project(b, xa);
                const sd_vec3 cand[4] = {v3_sub(xa, xb), nxb, nxa, v3_sub(nxb, nxa)};
                for (int k = 0; k < 4; k++) {
                    const double nn = v3_norm(cand[k]);
                    if (!(nn > 1e-300)) continue;
                    const sd_vec3 n = v3_scale(cand[k], 1.0 / nn);
                    if (cc_sep_margin(a, b, dc, n) > 4.0 * tol) {
                        *sep = n;
                        break;
                    }
                }
            }
        }
        if (found >= 0) {
            /* two end rims crossing: the normal is across both rims' tangents there */
            const sd_vec3 xa = v3_sub(w[found], a->c), xb = v3_sub(w[found], b->c);
            const sd_vec3 ra = v3_madd(xa, a->a, -v3_dot(xa, a->a)), rb = v3_madd(xb, b->a, -v3_dot(xb, b->a));
            sd_vec3 dirs[9] = {v3_sub(pa, pb),
                               dc,
                               a->a,
                               b->a,
                               v3_cross(a->a, b->a),
                               nxb,
                               v3_neg(nxa),
                               v3_sub(nxb, nxa),
                               v3_cross(v3_cross(a->a, ra), v3_cross(b->a, rb))};
            double best = INFINITY;
            sd_vec3 bn = v3(0.0, 0.0, 0.0);
            for (int k = 0; k < 9; k++) {
                double nn = v3_norm(dirs[k]);
                if (!(nn > 1e-300)) continue;
                sd_vec3 n = v3_scale(dirs[k], 1.0 / nn);
                if (v3_dot(n, dc) < 0.0) n = v3_neg(n);
                double ov = cc_sat_overlap(a, b, n);
                if (ov < best) {
                    best = ov;
                    bn = n;
                }
            }
            /* then down the separating-axis overlap to its nearest minimum: the depth of the
             * overlap and the direction that ends it (the fixed directions above bound it from
             * above, by 10-1000x for two rims crossing, docs/physics.md) */
            if (best > 0.0 && best < INFINITY) cc_min_overlap(a, b, dc, &bn, &best);
            if (best > 0.0 && best < INFINITY) {
                cn[nc] = bn;
                cov[nc] = best;
                cp[nc] = w[found];
                cid[nc] = 9;
                csh[nc] = best;
                nc++;
            }
        }
    }
    /* deepest first (ties by feature id), merge near-duplicates, keep at most 4 */
    int order[5];
    for (int i = 0; i < nc; i++)
        order[i] = i;
    for (int i = 1; i < nc; i++) {
        int j = i, x = order[i];
        while (j > 0 && (cov[order[j - 1]] < cov[x] || (cov[order[j - 1]] == cov[x] && cid[order[j - 1]] > cid[x]))) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = x;
    }
    double rmin = a->r < b->r ? a->r : b->r;
    for (int i = 0; i < nc && m->n < SD_MANIFOLD_MAX; i++) {
        int c = order[i], dup = -1;
        for (int j = 0; j < m->n; j++) {
            if (v3_dist(cp[c], m->point[j]) < 0.5 * rmin && v3_dot(cn[c], m->normal[j]) > 0.9) {
                dup = j;
                break;
            }
        }
        if (dup >= 0) {
            /* the deeper point takes the merged one's share: the pair's total is kept */
            m->share[dup] += csh[c];
            continue;
        }
        m->normal[m->n] = cn[c];
        m->point[m->n] = cp[c];
        m->overlap[m->n] = cov[c];
        m->feature[m->n] = cid[c];
        m->share[m->n] = csh[c];
        m->n++;
    }
    return m->n;
}
