/* Inline 3-vector and quaternion math. Double precision throughout (SPEC §2). */
#ifndef SD_VMATH_H
#define SD_VMATH_H

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The same guarded definitions stand in include/sabodem.h, so either header may come first. */
#ifndef SD_VEC_TYPES_DEFINED
#define SD_VEC_TYPES_DEFINED
typedef struct {
    double x, y, z;
} sd_vec3;

typedef struct {
    double w, x, y, z; /* unit quaternion, w scalar part */
} sd_quat;
#endif

static inline sd_vec3 v3(double x, double y, double z) { sd_vec3 r = {x, y, z}; return r; }
static inline sd_vec3 v3_add(sd_vec3 a, sd_vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline sd_vec3 v3_sub(sd_vec3 a, sd_vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline sd_vec3 v3_scale(sd_vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline sd_vec3 v3_neg(sd_vec3 a) { return v3(-a.x, -a.y, -a.z); }
/* a + s*b */
static inline sd_vec3 v3_madd(sd_vec3 a, sd_vec3 b, double s) { return v3(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z); }
static inline double v3_dot(sd_vec3 a, sd_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline sd_vec3 v3_cross(sd_vec3 a, sd_vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_norm2(sd_vec3 a) { return v3_dot(a, a); }
static inline double v3_norm(sd_vec3 a) { return sqrt(v3_dot(a, a)); }
static inline sd_vec3 v3_normalize(sd_vec3 a)
{
    double n = v3_norm(a);
    return n > 0.0 ? v3_scale(a, 1.0 / n) : v3(0.0, 0.0, 0.0);
}
static inline double v3_dist(sd_vec3 a, sd_vec3 b) { return v3_norm(v3_sub(a, b)); }
static inline double v3_max_abs(sd_vec3 a)
{
    double m = fabs(a.x);
    if (fabs(a.y) > m) m = fabs(a.y);
    if (fabs(a.z) > m) m = fabs(a.z);
    return m;
}
/* Any unit vector perpendicular to unit vector a (deterministic). */
static inline sd_vec3 v3_any_perp(sd_vec3 a)
{
    sd_vec3 t = fabs(a.x) < 0.57735 ? v3(1.0, 0.0, 0.0) : (fabs(a.y) < 0.57735 ? v3(0.0, 1.0, 0.0) : v3(0.0, 0.0, 1.0));
    return v3_normalize(v3_cross(a, t));
}

static inline sd_quat quat_identity(void) { sd_quat q = {1.0, 0.0, 0.0, 0.0}; return q; }
static inline sd_quat quat_mul(sd_quat a, sd_quat b)
{
    sd_quat r;
    r.w = a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z;
    r.x = a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y;
    r.y = a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x;
    r.z = a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w;
    return r;
}
static inline sd_quat quat_normalize(sd_quat q)
{
    double n = sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    sd_quat r = {q.w / n, q.x / n, q.y / n, q.z / n};
    return r;
}
/* Rotation by the rotation vector phi (axis * angle). */
static inline sd_quat quat_from_rotvec(sd_vec3 phi)
{
    double ang = v3_norm(phi);
    sd_quat r;
    if (ang < 1e-12) {
        /* second-order series keeps |q| = 1 to rounding for tiny angles */
        r.w = 1.0 - ang * ang / 8.0;
        r.x = 0.5 * phi.x;
        r.y = 0.5 * phi.y;
        r.z = 0.5 * phi.z;
        return quat_normalize(r);
    }
    double s = sin(0.5 * ang) / ang;
    r.w = cos(0.5 * ang);
    r.x = phi.x * s;
    r.y = phi.y * s;
    r.z = phi.z * s;
    return r;
}
/* Rotate vector v by unit quaternion q (body -> world). */
static inline sd_vec3 quat_rotate(sd_quat q, sd_vec3 v)
{
    sd_vec3 u = v3(q.x, q.y, q.z);
    sd_vec3 t = v3_scale(v3_cross(u, v), 2.0);
    return v3_add(v3_add(v, v3_scale(t, q.w)), v3_cross(u, t));
}
/* Rotate vector v by the inverse of q (world -> body). */
static inline sd_vec3 quat_rotate_inv(sd_quat q, sd_vec3 v)
{
    sd_quat c = {q.w, -q.x, -q.y, -q.z};
    return quat_rotate(c, v);
}
/* Shortest-arc unit quaternion taking unit vector a (body z axis) to unit vector b. */
static inline sd_quat quat_from_z_to(sd_vec3 b)
{
    sd_vec3 a = v3(0.0, 0.0, 1.0);
    double d = v3_dot(a, b);
    sd_quat q;
    if (d < -1.0 + 1e-14) {
        q.w = 0.0; q.x = 1.0; q.y = 0.0; q.z = 0.0; /* 180 deg about x */
        return q;
    }
    sd_vec3 c = v3_cross(a, b);
    q.w = 1.0 + d;
    q.x = c.x;
    q.y = c.y;
    q.z = c.z;
    return quat_normalize(q);
}

#endif
