/* Cases 2, 3-1, 3-2 (eqs 14-24): sphere (A) against a solid cylinder with flat ends (B).
 * The exact closest point of the solid cylinder to the sphere centre decides the case: side
 * (eqs 14-16), end face (eqs 17-22, with the typo of (20) corrected), end rim (eqs 23-24);
 * a centre inside the cylinder is pushed out through the nearest surface.
 * feature: 0 side, 1 end face -, 2 end face +, 3 rim -, 4 rim + (- / + = end at -hl / +hl
 * along the axis). */
#include "cyl_common.h"

int sd_geom_sphere_cyl(sd_vec3 c, double r, const sd_cyl *b, sd_manifold *m)
{
    m->n = 0;
    double rho2;
    if (sd_sphere_cyl_apart(c, r, b, &rho2)) return 0;
    sd_vec3 n;
    int f;
    /* hint for a centre exactly on the axis (only read there): any fixed perpendicular */
    sd_vec3 hint = rho2 > 1e-280 ? b->a : v3_any_perp(b->a);
    double sd = sd_cyl_signed_dist(b, c, hint, &n, &f);
    if (sd >= r) return 0;
    double ov = r - sd;
    sd_vec3 q = v3_madd(c, n, -sd); /* surface point of B nearest to the centre */
    m->normal[0] = n;
    m->overlap[0] = ov;
    m->point[0] = v3_madd(q, n, -0.5 * ov);
    m->feature[0] = f;
    m->n = 1;
    return 1;
}
