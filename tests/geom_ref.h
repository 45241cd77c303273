/* Helpers shared by the geometry tests: a cylinder from centre, axis, radius, half length, and
 * the exact signed distance to it, written independently of the kernels (the reference side). */
#ifndef SD_TEST_GEOM_REF_H
#define SD_TEST_GEOM_REF_H

#include "geom/geom.h"

static inline sd_cyl mkcyl(sd_vec3 c, sd_vec3 a, double r, double hl)
{
    sd_cyl k;
    k.c = c;
    k.a = v3_normalize(a);
    k.r = r;
    k.hl = hl;
    return k;
}

/* < 0 inside, 0 on the surface, > 0 outside */
static inline double sdf_cyl(const sd_cyl *c, sd_vec3 x)
{
    sd_vec3 d = v3_sub(x, c->c);
    double t = v3_dot(d, c->a);
    double rho = sqrt(fmax(v3_norm2(d) - t * t, 0.0));
    double dx = rho - c->r, dy = fabs(t) - c->hl;
    double out = sqrt(fmax(dx, 0.0) * fmax(dx, 0.0) + fmax(dy, 0.0) * fmax(dy, 0.0));
    return fmin(fmax(dx, dy), 0.0) + out;
}

#endif
