/* Case 4 (eqs 25–27), extended: the closest point on the triangle decides face, edge or
 * vertex contact, so that a mesh behaves like the surface it approximates. */
#include "geom.h"

/* Closest point on a triangle by Voronoi regions (Ericson, Real-Time Collision Detection,
 * sec. 5.1.5, the textbook algorithm). */
sd_vec3 sd_geom_closest_on_tri(const sd_tri *t, sd_vec3 p, int *feature)
{
    sd_vec3 a = t->v[0], b = t->v[1], c = t->v[2];
    sd_vec3 ab = v3_sub(b, a), ac = v3_sub(c, a), ap = v3_sub(p, a);
    double d1 = v3_dot(ab, ap), d2 = v3_dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) { *feature = SD_TRI_VERT0 + 0; return a; }
    sd_vec3 bp = v3_sub(p, b);
    double d3 = v3_dot(ab, bp), d4 = v3_dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) { *feature = SD_TRI_VERT0 + 1; return b; }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        double v = d1 / (d1 - d3);
        *feature = SD_TRI_EDGE0 + 0;
        return v3_madd(a, ab, v);
    }
    sd_vec3 cp = v3_sub(p, c);
    double d5 = v3_dot(ab, cp), d6 = v3_dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) { *feature = SD_TRI_VERT0 + 2; return c; }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        double w = d2 / (d2 - d6);
        *feature = SD_TRI_EDGE0 + 2;
        return v3_madd(a, ac, w);
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        *feature = SD_TRI_EDGE0 + 1;
        return v3_madd(b, v3_sub(c, b), w);
    }
    double denom = 1.0 / (va + vb + vc);
    double v = vb * denom, w = vc * denom;
    *feature = SD_TRI_FACE;
    return v3_add(a, v3_add(v3_scale(ab, v), v3_scale(ac, w)));
}

int sd_geom_sphere_tri(sd_vec3 c, double r, const sd_tri *t, sd_manifold *m)
{
    m->n = 0;
    /* cheap plane test first (eq 25–27) */
    double s = v3_dot(v3_sub(c, t->v[0]), t->n);
    if (fabs(s) >= r) return 0;
    int f;
    sd_vec3 q = sd_geom_closest_on_tri(t, c, &f);
    sd_vec3 d = v3_sub(c, q);
    double dist2 = v3_norm2(d);
    if (dist2 >= r * r) return 0;
    sd_vec3 n;
    double dist;
    if (f == SD_TRI_FACE) {
        /* exact plane normal: no round-off wobble for a sphere rolling on a face */
        n = s >= 0.0 ? t->n : v3_neg(t->n);
        dist = fabs(s);
    } else {
        dist = sqrt(dist2);
        n = dist > 1e-300 ? v3_scale(d, 1.0 / dist) : t->n;
    }
    double ov = r - dist;
    m->normal[0] = n;
    m->overlap[0] = ov;
    m->point[0] = v3_madd(q, n, -0.5 * ov);
    m->feature[0] = f;
    m->n = 1;
    return 1;
}

void sd_tri_edges_init(sd_tri_edges *e, const sd_tri *t)
{
    for (int k = 0; k < 3; k++) {
        const sd_vec3 a = t->v[k], b = t->v[(k + 1) % 3];
        e->m[k] = v3_normalize(v3_cross(t->n, v3_sub(b, a)));
        e->h[k] = v3_dot(e->m[k], a);
    }
}

int sd_geom_sphere_tri_e(sd_vec3 c, double r, const sd_tri *t, const sd_tri_edges *e, sd_manifold *m)
{
    m->n = 0;
    double s;
    const int kind = sd_sphere_tri_class(c, r, t, e, &s);
    if (kind == 0) return 0;
    if (kind == 2) return sd_geom_sphere_tri(c, r, t, m);
    sd_sphere_tri_face(c, r, t, s, &m->normal[0], &m->overlap[0], &m->point[0]);
    m->feature[0] = SD_TRI_FACE;
    m->n = 1;
    return 1;
}
