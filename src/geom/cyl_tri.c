/* Case 8 (eqs 40-43), extended: solid cylinder (A) against a two-sided triangle (B).
 *
 * Face contacts: n' = triangle normal turned towards the cylinder centre. The deepest line of
 * the side surface along -n' (through the deepest rim point of each end disk, eqs 40-42,
 * S = (n x a) x a) is clipped to the triangle's prism; each end of the clipped part that lies
 * below the plane is a contact (normal n', overlap = depth below the plane). A log lying on a
 * triangle thus gets one contact under each end rim; on a floor of several triangles each
 * triangle supports the part of the line above it. When the end disk is parallel to the plane
 * (S = 0) the contact is the point of the triangle nearest the disk centre (if within r).
 * Edge/vertex contacts: for each edge, the point of the segment deepest inside the cylinder
 * (distance to the nearest of side and end faces, maximised exactly over the segment);
 * normal = minus the cylinder's outward normal there. An edge contact replaces the face
 * contacts when it is a better separating direction (the separating-axis overlap of the two
 * whole bodies along its normal equals its depth and is smaller than along n'), or when there
 * is no face contact. An edge parallel to the axis gives two contacts at the ends of its
 * part alongside the cylinder.
 * feature = (cyl << SD_TRI_FEATURE_BITS) | triangle code, cyl: 0 side, 1/2 end -/+ (rim or
 * disk), 3/4 low/high end of a clipped line part. */
#include "cyl_common.h"

#define CT_FEAT(cf, tf) (((cf) << SD_TRI_FEATURE_BITS) | (tf))

static void ct_push(sd_manifold *m, sd_vec3 n, sd_vec3 p, double ov, int f)
{
    if (m->n >= SD_MANIFOLD_MAX) return;
    m->normal[m->n] = n;
    m->point[m->n] = p;
    m->overlap[m->n] = ov;
    m->feature[m->n] = f;
    m->share[m->n] = ov;
    m->n++;
}

/* Separating-axis overlap for pushing the cylinder along n away from the triangle. */
static double ct_sat_overlap(const sd_cyl *c, const sd_tri *t, sd_vec3 n)
{
    double tmax = v3_dot(t->v[0], n);
    for (int k = 1; k < 3; k++) {
        double x = v3_dot(t->v[k], n);
        if (x > tmax) tmax = x;
    }
    return tmax - (v3_dot(c->c, n) - sd_cyl_extent(c, n));
}

/* Depth of x inside the cylinder (distance to the nearest of side and end faces; negative
 * outside, then only a lower bound of the distance, which is all the search needs). */
static double ct_depth(const sd_cyl *c, sd_vec3 x)
{
    sd_vec3 d = v3_sub(x, c->c);
    double t = v3_dot(d, c->a);
    double rho = v3_norm(v3_madd(d, c->a, -t));
    double ds = c->r - rho, de = c->hl - fabs(t);
    return ds < de ? ds : de;
}

/* Deepest point of segment p + s (q - p), s in [0,1], inside the cylinder. The depth is a
 * concave function of s (min of r - rho(s) and hl -+ t(s)), so its maximum is at an end, at
 * the stationary point of r - rho, at t = 0, or where the side and an end face are equally
 * near (a quadratic). All candidates are evaluated. */
static double ct_edge_deepest(const sd_cyl *c, sd_vec3 p, sd_vec3 q, double *s_best)
{
    sd_vec3 e = v3_sub(q, p);
    sd_vec3 d0 = v3_sub(p, c->c);
    double t0 = v3_dot(d0, c->a), t1 = v3_dot(e, c->a);
    sd_vec3 w0 = v3_madd(d0, c->a, -t0), w1 = v3_madd(e, c->a, -t1);
    double A2 = v3_norm2(w1), B2 = 2.0 * v3_dot(w0, w1), C2 = v3_norm2(w0);
    double cand[8];
    int nc = 0;
    cand[nc++] = 0.0;
    cand[nc++] = 1.0;
    if (A2 > 0.0) cand[nc++] = -0.5 * B2 / A2;
    if (t1 != 0.0) cand[nc++] = -t0 / t1;
    for (int k = 0; k < 2; k++) {
        double sg = k ? 1.0 : -1.0; /* side depth = end depth of end sg: rho = r - hl + sg t */
        double k0 = c->r - c->hl + sg * t0, k1 = sg * t1;
        double qa = A2 - k1 * k1, qb = B2 - 2.0 * k0 * k1, qc = C2 - k0 * k0;
        if (fabs(qa) > 1e-14 * (A2 + k1 * k1)) {
            double disc = qb * qb - 4.0 * qa * qc;
            if (disc >= 0.0) {
                double sq = sqrt(disc);
                double qq = -0.5 * (qb + (qb >= 0.0 ? sq : -sq));
                cand[nc++] = qq / qa;
                if (qq != 0.0) cand[nc++] = qc / qq;
            }
        } else if (qb != 0.0) {
            cand[nc++] = -qc / qb;
        }
    }
    double best = -INFINITY;
    *s_best = 0.0;
    for (int i = 0; i < nc; i++) {
        double s = cand[i];
        if (!(s >= 0.0 && s <= 1.0)) continue;
        double dep = ct_depth(c, v3_madd(p, e, s));
        if (dep > best) {
            best = dep;
            *s_best = s;
        }
    }
    return best;
}

int sd_geom_cyl_tri(const sd_cyl *a, const sd_tri *t, sd_manifold *m)
{
    m->n = 0;
    if (!(v3_norm2(t->n) > 0.25)) return 0; /* degenerate triangle */
    double tol = 1e-9 * (a->r + a->hl);
    double sc = v3_dot(v3_sub(a->c, t->v[0]), t->n);
    sd_vec3 np = sc >= 0.0 ? t->n : v3_neg(t->n);
    sc = fabs(sc);
    double pen_face = sd_cyl_extent(a, np) - sc; /* depth of the cylinder below the plane */
    if (!(pen_face > 0.0)) return 0;

    /* ---- face contacts ---- */
    sd_manifold fm;
    fm.n = 0;
    double sg = v3_dot(a->a, np);
    sd_vec3 wv = v3_madd(np, a->a, -sg);
    double wn = v3_norm(wv);
    /* u: from the axis towards the plane, in the end disks' plane (the deepest rim point of
     * each disk is c +- hl a + r u); for a disk flat on the plane (S = 0) any direction, taken
     * from the triangle's first edge: all rim points are then equally deep */
    sd_vec3 u = wn >= 1e-12 ? v3_scale(wv, -1.0 / wn) : sd_perp_dir(a->a, v3_sub(t->v[1], t->v[0]), np);
    /* a face within 30 deg of the plane: the lower end disk's rim points, the deepest one
     * and three more a quarter turn apart (ids 1 or 2, then 5, 6, 7); else the deepest line
     * of the side surface, clipped to the triangle */
    if (fabs(sg) >= 0.86602540378443860) {
        /* Each counts where it is below the plane and its projection lies on the triangle
         * (the next triangle of a floor takes it beyond an edge). With the deepest one they
         * carry a moment when the face lies on the plane, and they leave it one by one, at
         * zero depth, as the face tilts away. A point is a contact where the plate's point
         * over it is in the log, true to first order in the tilt; past 30 deg the three are
         * clear of the plane unless the disk centre is r/2 deep. */
        const double e = sg > 0.0 ? -1.0 : 1.0;
        const sd_vec3 ce = sd_cyl_end(a, e), v = v3_cross(a->a, u);
        const sd_vec3 dirs[4] = {u, v, v3_neg(u), v3_neg(v)};
        for (int k = 0; k < 4; k++) {
            sd_vec3 x = v3_madd(ce, dirs[k], a->r);
            double dep = -v3_dot(v3_sub(x, t->v[0]), np);
            /* (deeper than the rounding: a log standing across a blade's plane has the
             * three in it) */
            if (!(dep > (k ? tol : 0.0))) continue;
            int inside = 1;
            for (int j = 0; j < 3 && inside; j++) {
                sd_vec3 vi = t->v[j], vj = t->v[(j + 1) % 3];
                inside = v3_dot(v3_sub(x, vi), v3_cross(t->n, v3_sub(vj, vi))) >= 0.0;
            }
            const int cf = k ? 4 + k : (e < 0.0 ? 1 : 2);
            if (inside) ct_push(&fm, np, v3_madd(x, np, 0.5 * dep), dep, CT_FEAT(cf, SD_TRI_FACE));
        }
    } else {
        sd_vec3 l0 = v3_madd(a->c, u, a->r); /* deepest line l0 + s a, s in [-hl, hl] */
        double lo = -a->hl, hi = a->hl;
        int elo = -1, ehi = -1, empty = 0;
        for (int k = 0; k < 3 && !empty; k++) {
            sd_vec3 vi = t->v[k], vj = t->v[(k + 1) % 3];
            sd_vec3 mk = v3_cross(t->n, v3_sub(vj, vi)); /* inward edge normal */
            double g0 = v3_dot(v3_sub(l0, vi), mk), g1 = v3_dot(a->a, mk);
            /* inside: g0 + s g1 >= 0 */
            if (g1 > 0.0) {
                double sb = -g0 / g1;
                if (sb > lo) { lo = sb; elo = k; }
            } else if (g1 < 0.0) {
                double sb = -g0 / g1;
                if (sb < hi) { hi = sb; ehi = k; }
            } else if (g0 < 0.0) {
                empty = 1;
            }
        }
        if (!empty && lo <= hi) {
            double s2[2] = {lo, hi};
            int ed[2] = {elo, ehi};
            int npts = hi - lo > 1e-12 * a->hl ? 2 : 1;
            for (int i = 0; i < npts; i++) {
                sd_vec3 x = v3_madd(l0, a->a, s2[i]);
                double dep = -v3_dot(v3_sub(x, t->v[0]), np);
                if (!(dep > 0.0)) continue;
                int cf, tf;
                if (ed[i] < 0) {
                    cf = i == 0 ? 1 : 2;
                    tf = SD_TRI_FACE;
                } else {
                    cf = 3 + i;
                    tf = SD_TRI_EDGE0 + ed[i];
                }
                ct_push(&fm, np, v3_madd(x, np, 0.5 * dep), dep, CT_FEAT(cf, tf));
            }
        }
    }

    /* ---- edge / vertex contacts ---- */
    int best_k = -1;
    double best_s = 0.0, best_dep = 0.0, best_pen = INFINITY;
    sd_vec3 best_n = np;
    int best_cf = 0, best_strict = 0;
    for (int k = 0; k < 3; k++) {
        sd_vec3 p = t->v[k], q = t->v[(k + 1) % 3];
        double s;
        double dep = ct_edge_deepest(a, p, q, &s);
        if (!(dep > 0.0)) continue;
        sd_vec3 x = v3_madd(p, v3_sub(q, p), s);
        sd_vec3 nout;
        int cf;
        sd_cyl_signed_dist(a, x, v3_sub(a->c, x), &nout, &cf);
        sd_vec3 n = v3_neg(nout);
        double pen = ct_sat_overlap(a, t, n);
        if (pen < best_pen - tol || (pen <= best_pen + tol && dep > best_dep)) {
            best_k = k;
            best_s = s;
            best_dep = dep;
            best_pen = pen;
            best_n = n;
            best_cf = cf;
            best_strict = pen <= dep + tol;
        }
    }
    /* No edge reaches into the log: the triangle meets it, if at all, only with its inside, and
     * the plane's section of the log (convex, crossed by no edge) then lies wholly inside the
     * triangle or wholly outside it, so one point of the section decides. The face contacts
     * alone cannot: a rim point below the plane can lie under the triangle while the section
     * beside it misses the triangle (a log deep through the plane next to a small triangle,
     * its end face tilted: the plate point over the rim point is outside the log). The point:
     * where the axis crosses the plane, else the deepest point lifted to the plane (inside the
     * log when the face is tilted); neither inside by more than tol (a face flat on the plane
     * only just below it): no test, the face contacts stand. */
    if (best_k < 0 && fm.n > 0) {
        const double s_ax = fabs(sg) > 1e-12 ? -sc / sg : INFINITY;
        sd_vec3 z = v3_madd(a->c, a->a, s_ax);
        if (!(fabs(s_ax) < a->hl)) {
            z = v3_madd(v3_madd(a->c, a->a, sg > 0.0 ? -a->hl : a->hl), u, a->r);
            z = v3_madd(z, np, pen_face);
        }
        if (ct_depth(a, z) > tol) {
            int inside = 1;
            for (int j = 0; j < 3 && inside; j++) {
                sd_vec3 vi = t->v[j], vj = t->v[(j + 1) % 3];
                inside = v3_dot(v3_sub(z, vi), v3_cross(t->n, v3_sub(vj, vi))) >= 0.0;
            }
            if (!inside) return 0;
        }
    }
    /* Compare with the deepest face contact on this triangle, not with pen_face (the depth of
     * the whole cylinder below the infinite plane, possibly over a neighbouring triangle): on a
     * flat mesh an edge under a log lies in the plane and its separating-axis overlap ties with
     * the face contacts beside it, but a log tilted by ~1e-9 rad reaches lower over the next
     * triangle, and the edge contact would then replace this triangle's rim contact. */
    double face_dep = 0.0;
    for (int i = 0; i < fm.n; i++)
        if (fm.overlap[i] > face_dep) face_dep = fm.overlap[i];
    /* (a face resting on the plane, less than r/10 deep, keeps its rim points: on a floor of
     * triangles an edge under the face is a seam, where a rim point 1 um from it would
     * otherwise go to a sideways edge contact that the flat-mesh rule then drops, losing the
     * point; a triangle cutting deep into a log, as a blade across it, is an edge contact) */
    const int face_on_plane = fabs(sg) >= 0.86602540378443860 && face_dep < 0.1 * a->r;
    int use_edge = best_k >= 0 && (fm.n == 0 || (!face_on_plane && best_strict && best_pen < face_dep - tol));
    if (!use_edge) {
        *m = fm;
        return m->n;
    }
    sd_vec3 p = t->v[best_k], q = t->v[(best_k + 1) % 3];
    sd_vec3 e = v3_sub(q, p);
    double le = v3_norm(e);
    if (best_cf == 0 && le > 0.0 && fabs(v3_dot(e, a->a)) > (1.0 - 1e-9) * le) {
        /* edge along the side: the ends of its part alongside the cylinder */
        double tp = v3_dot(v3_sub(p, a->c), a->a), tq = v3_dot(v3_sub(q, a->c), a->a);
        double s_lo, s_hi;
        {
            double sa = (-a->hl - tp) / (tq - tp), sb = (a->hl - tp) / (tq - tp);
            s_lo = sa < sb ? sa : sb;
            s_hi = sa < sb ? sb : sa;
        }
        if (s_lo < 0.0) s_lo = 0.0;
        if (s_hi > 1.0) s_hi = 1.0;
        if (s_hi - s_lo > 1e-12) {
            /* order by the axial coordinate so that id 3 is the end towards -hl */
            double sv[2] = {tq > tp ? s_lo : s_hi, tq > tp ? s_hi : s_lo};
            for (int i = 0; i < 2; i++) {
                sd_vec3 x = v3_madd(p, e, sv[i]);
                sd_vec3 d = v3_sub(x, a->c);
                sd_vec3 w = v3_madd(d, a->a, -v3_dot(d, a->a));
                double rho = v3_norm(w);
                double dep = a->r - rho;
                if (!(dep > 0.0)) continue;
                sd_vec3 n = rho > 1e-300 ? v3_scale(w, -1.0 / rho) : best_n;
                int tf = sv[i] <= 0.0 ? SD_TRI_VERT0 + best_k
                                      : (sv[i] >= 1.0 ? SD_TRI_VERT0 + (best_k + 1) % 3 : SD_TRI_EDGE0 + best_k);
                ct_push(m, n, v3_madd(x, n, -0.5 * dep), dep, CT_FEAT(3 + i, tf));
            }
            if (m->n > 0) return m->n;
        }
    }
    sd_vec3 x = v3_madd(p, e, best_s);
    int tf = best_s <= 0.0 ? SD_TRI_VERT0 + best_k
                           : (best_s >= 1.0 ? SD_TRI_VERT0 + (best_k + 1) % 3 : SD_TRI_EDGE0 + best_k);
    ct_push(m, best_n, v3_madd(x, best_n, -0.5 * best_dep), best_dep, CT_FEAT(best_cf, tf));
    return m->n;
}
