/* Normal impact against the closed form of the linear spring-dashpot with the no-tension clip
 * (Schwager & Pöschel 2007): sphere on a floor of two triangles and two equal spheres head-on,
 * gravity off, paper values K_n = 1e4 N/m, h = 0.2, SG 1.9, d = 5, 10, 15, 20 mm.
 * Also: two overlapping spheres released at rest never attract each other. */
#include <string.h>

#include "check.h"
#include "sabodem.h"
#include "core/vmath.h"

static const double KN = 1.0e4, H = 0.2, RHO = 1900.0, V0 = 0.2;

/* Closed form for the clipped linear spring-dashpot: contact ends when k x + c ẋ = 0. */
static void closed_form(double m_eff, double *e, double *tc)
{
    double w0 = sqrt(KN / m_eff), g = H * w0, w = sqrt(w0 * w0 - g * g);
    double t = (M_PI - atan(2.0 * g * w / (w * w - g * g))) / w;
    *tc = t;
    *e = exp(-g * t) * fabs(cos(w * t) - g / w * sin(w * t));
}

static sd_world *make_world(double dt)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = (sd_vec3){0, 0, 0};
    def.dt = dt;
    def.contact.k_n = KN;
    def.contact.damping = H;
    def.contact.tan_phi = 0.404;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    return w;
}

/* Sphere of diameter d falling at V0 on a floor of two triangles. */
static void floor_bounce(double d, double dt, double *e, double *tc)
{
    sd_world *w = make_world(dt);
    const double L = 0.05;
    sd_world_add_triangle(w, (sd_vec3){-L, -L, 0}, (sd_vec3){L, -L, 0}, (sd_vec3){L, L, 0}, 0);
    sd_world_add_triangle(w, (sd_vec3){-L, -L, 0}, (sd_vec3){L, L, 0}, (sd_vec3){-L, L, 0}, 0);
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = 0.5 * d;
    s.density = RHO;
    s.pos = (sd_vec3){0.011, -0.004, s.radius + 1e-4};
    s.vel = (sd_vec3){0, 0, -V0};
    int id = sd_world_add_sphere(w, &s);
    CHECK(id >= 0);
    long nonzero = 0;
    int touched = 0;
    sd_body_state b;
    for (long k = 0; k < 2000000; k++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_world_body(w, id, &b);
        if (b.force.x != 0.0 || b.force.y != 0.0 || b.force.z != 0.0) {
            nonzero++;
            touched = 1;
        }
        if (touched && b.pos.z > s.radius + 1e-5) break;
    }
    *e = b.vel.z / V0;
    *tc = (double)nonzero * dt;
    sd_world_destroy(w);
}

/* Two equal spheres, head-on along x, closing speed V0. */
static void pair_bounce(double d, double dt, double *e, double *tc)
{
    sd_world *w = make_world(dt);
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = 0.5 * d;
    s.density = RHO;
    s.pos = (sd_vec3){-(s.radius + 5e-5), 0.001, 0.002};
    s.vel = (sd_vec3){0.5 * V0, 0, 0};
    int a = sd_world_add_sphere(w, &s);
    s.pos.x = -s.pos.x;
    s.vel.x = -s.vel.x;
    int bid = sd_world_add_sphere(w, &s);
    long nonzero = 0;
    int touched = 0;
    sd_body_state A, B;
    for (long k = 0; k < 2000000; k++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_world_body(w, a, &A);
        sd_world_body(w, bid, &B);
        if (A.force.x != 0.0) {
            nonzero++;
            touched = 1;
            /* Newton's third law, bitwise */
            if (A.force.x != -B.force.x) CHECK(A.force.x == -B.force.x);
        }
        if (touched && B.pos.x - A.pos.x > 2.0 * s.radius + 1e-5) break;
    }
    *e = (B.vel.x - A.vel.x) / V0;
    *tc = (double)nonzero * dt;
    sd_world_destroy(w);
}

static void test_restitution(void)
{
    const double ds[4] = {0.005, 0.010, 0.015, 0.020};
    const double dts[2] = {1e-6, 1e-5}, tols[2] = {0.01, 0.05};
    const double e_unclipped = exp(-M_PI * H / sqrt(1.0 - H * H));
    CHECK_NEAR(e_unclipped, 0.5266, 1e-4);
    printf("%-6s %-7s %-8s %-9s %-9s %-11s %-11s\n", "case", "d[mm]", "dt[s]", "e", "e_theory", "t_c[s]",
           "t_c_theory");
    for (int t = 0; t < 2; t++)
        for (int i = 0; i < 4; i++)
            for (int pair = 0; pair < 2; pair++) {
                double r = 0.5 * ds[i], m = RHO * 4.0 / 3.0 * M_PI * r * r * r;
                double e_th, tc_th, e, tc;
                closed_form(pair ? 0.5 * m : m, &e_th, &tc_th);
                if (pair) pair_bounce(ds[i], dts[t], &e, &tc);
                else floor_bounce(ds[i], dts[t], &e, &tc);
                printf("%-6s %-7.0f %-8.0e %-9.5f %-9.5f %-11.4e %-11.4e\n", pair ? "pair" : "floor", ds[i] * 1e3,
                       dts[t], e, e_th, tc, tc_th);
                CHECK_REL(e, e_th, tols[t]);
                CHECK_REL(tc, tc_th, tols[t]);
                /* the clip matters: the unclipped value is 8 % lower, outside both tolerances */
                CHECK(fabs(e - e_unclipped) > fabs(e - e_th));
                if (t == 0) CHECK(fabs(e - e_unclipped) > 0.04);
            }
    double e_th, tc_th;
    closed_form(1.0, &e_th, &tc_th);
    CHECK_NEAR(e_th, 0.5717, 1e-4); /* size independent */
}

/* Two spheres overlapping by 10 % of a radius, released at rest: they must push apart and
 * never pull on each other. */
static void test_no_tension(void)
{
    for (int pass = 0; pass < 2; pass++) {
        sd_world *w = make_world(1e-6);
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = pass ? 0.0025 : 0.01;
        s.density = RHO;
        double ov = 0.1 * s.radius;
        sd_vec3 dir = {0.6, 0.0, 0.8};
        double half = s.radius - 0.5 * ov;
        s.pos = (sd_vec3){-half * dir.x, 0, -half * dir.z};
        int a = sd_world_add_sphere(w, &s);
        s.radius *= 1.0; /* equal */
        s.pos = (sd_vec3){half * dir.x, 0, half * dir.z};
        int bid = sd_world_add_sphere(w, &s);
        int attract = 0, pushed = 0;
        sd_body_state A, B;
        for (int k = 0; k < 20000; k++) {
            CHECK(sd_world_step(w) == SD_OK);
            sd_world_body(w, a, &A);
            sd_world_body(w, bid, &B);
            sd_vec3 ab = {B.pos.x - A.pos.x, B.pos.y - A.pos.y, B.pos.z - A.pos.z};
            /* force on A must point away from B (or vanish), and on B away from A */
            double fa = A.force.x * ab.x + A.force.y * ab.y + A.force.z * ab.z;
            double fb = B.force.x * ab.x + B.force.y * ab.y + B.force.z * ab.z;
            if (fa > 0.0 || fb < 0.0) attract++;
            if (fa < 0.0) pushed++;
        }
        sd_vec3 dv = {B.vel.x - A.vel.x, B.vel.y - A.vel.y, B.vel.z - A.vel.z};
        sd_vec3 ab = {B.pos.x - A.pos.x, B.pos.y - A.pos.y, B.pos.z - A.pos.z};
        double vsep = (dv.x * ab.x + dv.y * ab.y + dv.z * ab.z) / sqrt(ab.x * ab.x + ab.y * ab.y + ab.z * ab.z);
        printf("no tension r=%g: steps pushing %d, attracting %d, final separation speed %.4g m/s, gap %.3g m\n",
               s.radius, pushed, attract, vsep, sqrt(ab.x * ab.x + ab.y * ab.y + ab.z * ab.z) - 2 * s.radius);
        CHECK(attract == 0);
        CHECK(pushed > 0);
        CHECK(vsep > 0.0);
        CHECK(sqrt(ab.x * ab.x + ab.y * ab.y + ab.z * ab.z) > 2 * s.radius);
        CHECK(sd_world_contact_count(w) == 0);
        sd_world_destroy(w);
    }
}

int main(void)
{
    test_restitution();
    test_no_tension();
    return check_report("test_bounce");
}
