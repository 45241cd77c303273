/* Private helpers shared by the cylinder kernels (sphere_cyl.c, cyl_cyl.c, cyl_tri.c).
 * Everything here is static inline: pure, no globals, no allocation. See docs/geometry.md. */
#ifndef SD_CYL_COMMON_H
#define SD_CYL_COMMON_H

#include "geom.h"

/* Half extent of cylinder c along the unit direction u (support function minus c.u):
 * hl |a.u| + r |a x u|. The cross product form keeps full relative accuracy for u nearly
 * parallel to the axis (sqrt(1 - s^2) would lose half the digits there). */
static inline double sd_cyl_extent(const sd_cyl *c, sd_vec3 u)
{
    return c->hl * fabs(v3_dot(c->a, u)) + c->r * v3_norm(v3_cross(c->a, u));
}

/* Centre of end e (e = -1 or +1) of cylinder c. */
static inline sd_vec3 sd_cyl_end(const sd_cyl *c, double e)
{
    return v3_madd(c->c, c->a, e * c->hl);
}

/* Unit vector perpendicular to unit axis a along the part of v perpendicular to a; when that
 * part is too small to give a reliable direction, along the part of `hint` perpendicular to a,
 * then any perpendicular (deterministic). Two Gram-Schmidt passes keep it perpendicular to a
 * to rounding even when the perpendicular part is small. */
static inline sd_vec3 sd_perp_dir(sd_vec3 a, sd_vec3 v, sd_vec3 hint)
{
    for (int k = 0; k < 2; k++) {
        sd_vec3 x = k ? hint : v;
        double nx = v3_norm(x);
        sd_vec3 w = v3_madd(x, a, -v3_dot(x, a));
        double n = v3_norm(w);
        if (n > 1e-8 * nx && n > 1e-300) {
            w = v3_scale(w, 1.0 / n);
            w = v3_normalize(v3_madd(w, a, -v3_dot(w, a)));
            return w;
        }
    }
    return v3_any_perp(a);
}

/* Signed distance from point x to the solid cylinder c (negative inside) and the outward unit
 * normal of the nearest boundary point, so that the nearest boundary point is x - sd * normal.
 * *feature: 0 side, 1 end face -, 2 end face +, 3 rim -, 4 rim +. For an inside point the
 * nearest of side and end faces wins (ties go to the side). `hint` fixes the radial direction
 * when x is on the axis. */
static inline double sd_cyl_signed_dist(const sd_cyl *c, sd_vec3 x, sd_vec3 hint, sd_vec3 *normal,
                                        int *feature)
{
    sd_vec3 d = v3_sub(x, c->c);
    double t = v3_dot(d, c->a);
    sd_vec3 w = v3_madd(d, c->a, -t);
    double rho = v3_norm(w);
    double e = t >= 0.0 ? 1.0 : -1.0;
    double ax = fabs(t) - c->hl; /* > 0 beyond the end plane */
    double rd = rho - c->r;      /* > 0 outside the side surface */
    sd_vec3 radial = rho > 1e-300 ? v3_scale(w, 1.0 / rho) : sd_perp_dir(c->a, hint, hint);
    if (ax <= 0.0 && rd <= 0.0) {
        if (rd >= ax) {
            *normal = radial;
            *feature = 0;
            return rd;
        }
        *normal = v3_scale(c->a, e);
        *feature = e < 0.0 ? 1 : 2;
        return ax;
    }
    if (rd <= 0.0) {
        *normal = v3_scale(c->a, e);
        *feature = e < 0.0 ? 1 : 2;
        return ax;
    }
    if (ax <= 0.0) {
        *normal = radial;
        *feature = 0;
        return rd;
    }
    /* beyond the rim: distance to the rim circle, in the (radial, axial) half plane */
    double dist = sqrt(rd * rd + ax * ax);
    *normal = v3_add(v3_scale(radial, rd / dist), v3_scale(c->a, e * ax / dist));
    *feature = e < 0.0 ? 3 : 4;
    return dist;
}

/* Point of the disk (centre ce, unit normal ax, radius R) closest to the line through p0 with
 * unit direction b (a 2x2 trust-region problem). In the disk frame (u along the projection of
 * b on the disk plane, v = ax x u) the squared distance is c2 al^2 + 2 g1 al + be^2 + 2 g2 be
 * + const with c2 = (b.ax)^2. Interior minimum if it lies in the disk, otherwise on the rim,
 * with al = -g1/(c2+lam), be = -g2/(1+lam); lam >= 0 is found by Newton on the secular
 * equation 1/|x(lam)| = 1/R, which is concave and increasing so that Newton from lam = 0
 * converges monotonically. When b lies in the disk plane (c2 ~ 0) the minimisers form a
 * chord of the disk; its midpoint (al = 0) is returned. */
static inline sd_vec3 sd_disk_closest_to_line(sd_vec3 ce, sd_vec3 ax, double R, sd_vec3 p0, sd_vec3 b)
{
    sd_vec3 w0 = v3_sub(ce, p0);
    sd_vec3 u = sd_perp_dir(ax, b, w0);
    sd_vec3 v = v3_cross(ax, u);
    double bax = v3_dot(b, ax);
    double c2 = bax * bax;
    sd_vec3 pu = v3_madd(u, b, -v3_dot(u, b));
    double g1 = v3_dot(pu, w0);
    double g2 = v3_dot(v, w0) - v3_dot(v, b) * v3_dot(b, w0);
    double al, be = -g2;
    int degenerate = c2 < 1e-14;
    al = degenerate ? 0.0 : -g1 / c2;
    if (al * al + be * be > R * R) {
        if (degenerate) {
            al = 0.0;
            be = be > R ? R : (be < -R ? -R : be);
        } else {
            double lam = 0.0;
            for (int it = 0; it < 60; it++) {
                double d1 = c2 + lam, d2 = 1.0 + lam;
                double a1 = -g1 / d1, b1 = -g2 / d2;
                double nx = sqrt(a1 * a1 + b1 * b1);
                double psi = 1.0 / nx - 1.0 / R;
                double dpsi = (a1 * a1 / d1 + b1 * b1 / d2) / (nx * nx * nx);
                if (!(dpsi > 0.0)) break;
                double step = -psi / dpsi;
                lam += step;
                if (lam < 0.0) lam = 0.0;
                if (fabs(step) <= 1e-15 * (lam + c2)) break;
            }
            al = -g1 / (c2 + lam);
            be = -g2 / (1.0 + lam);
            /* put it exactly on the rim */
            double nx = sqrt(al * al + be * be);
            if (nx > 0.0) {
                al *= R / nx;
                be *= R / nx;
            }
        }
    }
    return v3_add(ce, v3_add(v3_scale(u, al), v3_scale(v, be)));
}

/* Closest points of two lines p + s da, q + t db (unit directions); returns 0 when they are
 * parallel to rounding (|da x db|^2 < 1e-20), else 1 with the parameters. */
static inline int sd_line_line(sd_vec3 p, sd_vec3 da, sd_vec3 q, sd_vec3 db, double *s, double *t)
{
    sd_vec3 d = v3_sub(p, q);
    double b = v3_dot(da, db);
    double den = v3_norm2(v3_cross(da, db));
    if (den < 1e-20) return 0;
    double dp = v3_dot(d, da), dq = v3_dot(d, db);
    *s = (b * dq - dp) / den;
    *t = (dq - b * dp) / den;
    return 1;
}

#endif
