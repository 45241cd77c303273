/* Case 1 (eq 13): sphere–sphere, normal along the centre line. */
#include "geom.h"

int sd_geom_sphere_sphere(sd_vec3 ca, double ra, sd_vec3 cb, double rb, sd_manifold *m)
{
    sd_vec3 d = v3_sub(ca, cb);
    double dist2 = v3_norm2(d);
    double rs = ra + rb;
    m->n = 0;
    if (dist2 >= rs * rs) return 0;
    double dist = sqrt(dist2);
    /* coincident centres: any direction is as good as another; pick +z so it stays finite */
    sd_vec3 n = dist > 1e-300 ? v3_scale(d, 1.0 / dist) : v3(0.0, 0.0, 1.0);
    double ov = rs - dist;
    m->normal[0] = n;
    m->overlap[0] = ov;
    /* midway between the surface points cb + rb n and ca - ra n */
    m->point[0] = v3_madd(cb, n, rb - 0.5 * ov);
    m->feature[0] = 0;
    m->n = 1;
    return 1;
}
