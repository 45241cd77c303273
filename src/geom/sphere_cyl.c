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
    sd_vec3 n;
    int f;
    /* hint for a centre exactly on the axis: any fixed perpendicular */
    double sd = sd_cyl_signed_dist(b, c, v3_any_perp(b->a), &n, &f);
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
