/* Fluid forces (SPEC §5, eqs 47–53) against hand-computed values.
 * Water of the paper unless stated: U = 1.2 m/s, h = 0.03 m, ρ = 1000 kg/m³, C_D = 0.49,
 * so ½ C_D ρ = 245 kg/m³. Flume frame, θ = 15°. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "core/vmath.h"
#include "fluid.h"

static const double TH = 15.0 * M_PI / 180.0;

static sd_fluid_element sphere_at(double x, double z, double r, sd_vec3 v)
{
    sd_fluid_element e;
    e.shape = SD_SHAPE_SPHERE;
    e.pos = v3(x, 0.15, z);
    e.vel = v;
    e.axis = v3(1.0, 0.0, 0.0);
    e.radius = r;
    e.length = 0.0;
    return e;
}

static sd_fluid_element log_at(double z, sd_vec3 axis, sd_vec3 v)
{
    sd_fluid_element e;
    e.shape = SD_SHAPE_CYLINDER;
    e.pos = v3(2.0, 0.15, z);
    e.vel = v;
    e.axis = axis;
    e.radius = 0.005; /* φ10 × 100 mm */
    e.length = 0.1;
    return e;
}

static void test_flow_profile(void)
{
    double u;
    /* eq 50: U_i = (z/h/5 + 4/5) U, U = 1.2, h = 0.03 */
    CHECK(sd_fluid_speed_flow(1.2, 0.03, 0.0, &u) == 1);
    CHECK_NEAR(u, 0.96, 1e-15); /* 0.8 × 1.2 */
    CHECK(sd_fluid_speed_flow(1.2, 0.03, 0.015, &u) == 1);
    CHECK_NEAR(u, 1.08, 1e-15); /* (0.5/5 + 0.8) = 0.9; 0.9 × 1.2 */
    CHECK(sd_fluid_speed_flow(1.2, 0.03, 0.012, &u) == 1);
    CHECK_NEAR(u, 1.056, 1e-15); /* 0.4/5 = 0.08; 0.88 × 1.2 */
    CHECK(sd_fluid_speed_flow(1.2, 0.03, 0.03, &u) == 1);
    CHECK_NEAR(u, 1.2, 1e-15); /* surface: U */
    CHECK(sd_fluid_speed_flow(1.2, 0.03, -0.004, &u) == 1);
    CHECK_NEAR(u, 0.96, 1e-15); /* below the bed read as z = 0 */
    u = 99.0;
    CHECK(sd_fluid_speed_flow(1.2, 0.03, 0.0301, &u) == 0);
    CHECK(u == 0.0); /* above the surface: none */
    CHECK(sd_fluid_speed_flow(1.2, 0.03, NAN, &u) == 0);
}

static void test_capture_profile(void)
{
    double a, b, u;
    /* h_D = h = 0.03: 1.8 h/h_D = 1.8, α = 0.8, β = 1 → same as eq 50 */
    sd_fluid_capture_coeffs(0.03, 0.03, &a, &b);
    CHECK_NEAR(a, 0.8, 1e-15);
    CHECK(b == 1.0);
    for (int k = 0; k <= 10; k++) {
        double z = 0.003 * k, uf, uc;
        CHECK(sd_fluid_speed_flow(1.2, 0.03, z, &uf) == 1);
        CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.03, z, &uc) == 1);
        CHECK_NEAR(uc, uf, 1e-15);
    }
    /* h_D below h is raised to h */
    sd_fluid_capture_coeffs(0.03, 0.02, &a, &b);
    CHECK_NEAR(a, 0.8, 1e-15);
    CHECK(b == 1.0);
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.02, 0.025, &u) == 1); /* wet up to h */

    /* h_D = 0.04: 1.8 × 0.03/0.04 = 1.35, α = 0.35 > 0.1, β = 1 */
    sd_fluid_capture_coeffs(0.03, 0.04, &a, &b);
    CHECK_NEAR(a, 0.35, 1e-15);
    CHECK(b == 1.0);
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.04, 0.0, &u) == 1);
    CHECK_NEAR(u, 0.42, 1e-15); /* 0.35 × 1.2 */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.04, 0.02, &u) == 1);
    CHECK_NEAR(u, 0.81, 1e-15); /* (0.65 × 0.5 + 0.35) = 0.675; × 1.2 */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.04, 0.04, &u) == 1);
    CHECK_NEAR(u, 1.2, 1e-15);                                      /* β U at the surface h_D */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.04, 0.035, &u) == 1); /* above h, below h_D */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.04, 0.0401, &u) == 0);
    CHECK(u == 0.0);

    /* h_D = 0.05: 1.8 × 0.03/0.05 = 1.08, α = 0.08 <= 0.1 → α = 0.1, β = 1.08 − 0.1 = 0.98 */
    sd_fluid_capture_coeffs(0.03, 0.05, &a, &b);
    CHECK_NEAR(a, 0.1, 1e-15);
    CHECK_NEAR(b, 0.98, 1e-15);
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.05, 0.0, &u) == 1);
    CHECK_NEAR(u, 0.12, 1e-15); /* 0.1 × 1.2 */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.05, 0.025, &u) == 1);
    CHECK_NEAR(u, 0.648, 1e-15); /* (0.88 × 0.5 + 0.1) = 0.54; × 1.2 */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.05, 0.05, &u) == 1);
    CHECK_NEAR(u, 1.176, 1e-15); /* 0.98 × 1.2 */

    /* h_D = 0.09: 1.8 × 0.03/0.09 = 0.6, α = −0.4 → 0.1, β = 0.5 */
    sd_fluid_capture_coeffs(0.03, 0.09, &a, &b);
    CHECK_NEAR(a, 0.1, 1e-15);
    CHECK_NEAR(b, 0.5, 1e-15);
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.09, 0.045, &u) == 1);
    CHECK_NEAR(u, 0.36, 1e-15); /* (0.4 × 0.5 + 0.1) = 0.3; × 1.2 */
    CHECK(sd_fluid_speed_capture(1.2, 0.03, 0.09, 0.09, &u) == 1);
    CHECK_NEAR(u, 0.6, 1e-15); /* 0.5 × 1.2 */

    /* branch boundary h_D = 1.8 h/1.1 = 0.054/1.1: α = 0.1, β = 1 from either side,
     * and the profile is continuous across it */
    double hb = 0.054 / 1.1;
    sd_fluid_capture_coeffs(0.03, hb, &a, &b);
    CHECK_NEAR(a, 0.1, 1e-14);
    CHECK_NEAR(b, 1.0, 1e-14);
    double a1, b1, a2, b2;
    sd_fluid_capture_coeffs(0.03, hb * (1.0 - 1e-9), &a1, &b1);
    sd_fluid_capture_coeffs(0.03, hb * (1.0 + 1e-9), &a2, &b2);
    CHECK(a1 > 0.1 && b1 == 1.0); /* α branch */
    CHECK(a2 == 0.1 && b2 < 1.0); /* clamped branch */
    CHECK_NEAR(a1, a2, 1e-8);
    CHECK_NEAR(b1, b2, 1e-8);
}

static void test_discharge(void)
{
    /* ∫0^h (z/(5h) + 4/5) U dz = (1/10 + 4/5) U h = 0.9 U h;
     * ∫0^hD ((β−α) z/hD + α) U dz = (α+β)/2 U hD = 0.9 U h since α + β = 1.8 h/hD */
    double q = 0.9 * 1.2 * 0.03; /* 0.0324 m²/s */
    CHECK_REL(sd_fluid_discharge(1.2, 0.03, SD_FLUID_FLOW, 0.0, 2), q, 1e-12);
    CHECK_REL(sd_fluid_discharge(1.2, 0.03, SD_FLUID_FLOW, 0.0, 1000), q, 1e-12);
    const double hds[] = {0.01, 0.03, 0.035, 0.04, 0.045, 0.054 / 1.1, 0.05, 0.06, 0.09, 0.2, 1.0};
    for (size_t i = 0; i < sizeof hds / sizeof hds[0]; i++) {
        CHECK_REL(sd_fluid_discharge(1.2, 0.03, SD_FLUID_CAPTURE, hds[i], 64), q, 1e-12);
        CHECK_REL(sd_fluid_discharge(1.2, 0.03, SD_FLUID_CAPTURE, hds[i], 7), q, 1e-12); /* odd n */
    }
    /* other water */
    CHECK_REL(sd_fluid_discharge(2.5, 0.07, SD_FLUID_CAPTURE, 0.3, 10), 0.9 * 2.5 * 0.07, 1e-12);
    CHECK(sd_fluid_discharge(1.2, 0.03, SD_FLUID_NONE, 0.05, 10) == 0.0);
}

static void test_areas(void)
{
    CHECK_REL(sd_fluid_area_sphere(0.01), M_PI * 1e-4, 1e-15);
    CHECK_REL(sd_fluid_volume_sphere(0.01), 4.0 / 3.0 * M_PI * 1e-6, 1e-15);
    CHECK_REL(sd_fluid_volume_cylinder(0.005, 0.1), M_PI * 2.5e-5 * 0.1, 1e-15);
    sd_vec3 x = v3(1, 0, 0);
    /* parallel: π r² = π × 2.5e-5 */
    CHECK_REL(sd_fluid_area_cylinder(0.005, 0.1, x, x), M_PI * 2.5e-5, 1e-15);
    CHECK_REL(sd_fluid_area_cylinder(0.005, 0.1, v3(-1, 0, 0), x), M_PI * 2.5e-5, 1e-15);
    /* perpendicular: 2 r L = 2 × 0.005 × 0.1 = 1e-3 */
    CHECK_REL(sd_fluid_area_cylinder(0.005, 0.1, v3(0, 1, 0), x), 1e-3, 1e-15);
    CHECK_REL(sd_fluid_area_cylinder(0.005, 0.1, v3(0, 0, 1), x), 1e-3, 1e-15);
    /* 60° from the flow: a·u = 0.5: 1e-3 × sqrt(0.75) + π 2.5e-5 × 0.5 */
    sd_vec3 a60 = v3(0.5, sqrt(0.75), 0.0);
    CHECK_REL(sd_fluid_area_cylinder(0.005, 0.1, a60, x), 1e-3 * sqrt(0.75) + M_PI * 1.25e-5, 1e-14);
}

static void test_drag_sphere(void)
{
    sd_fluid_params p = sd_fluid_params_default(TH);
    sd_fluid_force_result r;
    const double A = M_PI * 1e-4; /* r = 0.01 */
    /* at rest at z = 0.015: U_i = 1.08; drag = 245 × π 1e-4 × 1.08² along +x */
    sd_fluid_element e = sphere_at(2.0, 0.015, 0.01, v3(0, 0, 0));
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r) == 1);
    CHECK_NEAR(r.u_local, 1.08, 1e-15);
    CHECK_REL(r.area, A, 1e-15);
    CHECK_REL(r.drag.x, 245.0 * A * 1.08 * 1.08, 1e-14);
    CHECK(r.drag.y == 0.0 && r.drag.z == 0.0);
    /* faster than the water by 1 m/s: drag = −245 A × 1 × 1 */
    e.vel = v3(2.08, 0, 0);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK_REL(r.drag.x, -245.0 * A, 1e-12);
    /* relative velocity (1, 0, −0.75): |.| = 1.25, drag = 245 A × 1.25 × (1, 0, −0.75) */
    e.vel = v3(0.08, 0.0, 0.75);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK_REL(r.drag.x, 245.0 * A * 1.25, 1e-12);
    CHECK_REL(r.drag.z, -245.0 * A * 1.25 * 0.75, 1e-12);
    CHECK(r.drag.y == 0.0);
    /* lateral only: v = (1.08, 0.5, 0): rel = (0, −0.5, 0), drag y = −245 A 0.25 */
    e.vel = v3(1.08, 0.5, 0.0);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK_NEAR(r.drag.x, 0.0, 1e-18);
    CHECK_REL(r.drag.y, -245.0 * A * 0.25, 1e-12);
    /* zero relative velocity → zero drag (buoyancy remains) */
    e.vel = v3(1.08, 0.0, 0.0);
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r) == 1);
    CHECK(r.drag.x == 0.0 && r.drag.y == 0.0 && r.drag.z == 0.0);
    CHECK(v3_norm(r.buoyancy) > 0.0);
    /* below the bed: z read as 0, U_i = 0.96 */
    e = sphere_at(2.0, -0.002, 0.01, v3(0, 0, 0));
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK_NEAR(r.u_local, 0.96, 1e-15);
    CHECK(r.z == 0.0);
    CHECK_REL(r.drag.x, 245.0 * A * 0.96 * 0.96, 1e-14);
    /* capture phase h_D = 0.05 at z = 0.025: U_i = 0.648 */
    e = sphere_at(3.95, 0.025, 0.01, v3(0, 0, 0));
    CHECK(sd_fluid_force(&p, SD_FLUID_CAPTURE, 0.05, &e, &r) == 1);
    CHECK_REL(r.drag.x, 245.0 * A * 0.648 * 0.648, 1e-14);
}

static void test_drag_log(void)
{
    sd_fluid_params p = sd_fluid_params_default(TH);
    sd_fluid_force_result r;
    const double q = 245.0 * 1.08 * 1.08; /* ½ C_D ρ |U_i|², at rest at z = 0.015 */
    /* axis parallel to the flow: A = π r² */
    sd_fluid_element e = log_at(0.015, v3(1, 0, 0), v3(0, 0, 0));
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r) == 1);
    CHECK_REL(r.area, M_PI * 2.5e-5, 1e-15);
    CHECK_REL(r.drag.x, q * M_PI * 2.5e-5, 1e-14);
    /* perpendicular (across the flume): A = 2 r L = 1e-3 */
    e.axis = v3(0, 1, 0);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK_REL(r.area, 1e-3, 1e-15);
    CHECK_REL(r.drag.x, q * 1e-3, 1e-14);
    CHECK(r.drag.y == 0.0 && r.drag.z == 0.0);
    /* oblique, 60° from the flow: A = 1e-3 sqrt(0.75) + π 2.5e-5 × 0.5; drag stays along the
     * relative velocity (no lift: "as for a sphere of equal projected area") */
    e.axis = v3(0.5, sqrt(0.75), 0.0);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    double A60 = 1e-3 * sqrt(0.75) + M_PI * 1.25e-5;
    CHECK_REL(r.area, A60, 1e-14);
    CHECK_REL(r.drag.x, q * A60, 1e-14);
    CHECK(r.drag.y == 0.0 && r.drag.z == 0.0);
    /* the area follows the relative velocity, not the flow: log along x moving across the
     * flow at the water's speed: rel = (0, −0.5, 0) ⟂ axis → A = 2 r L */
    e.axis = v3(1, 0, 0);
    e.vel = v3(1.08, 0.5, 0.0);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK_REL(r.area, 1e-3, 1e-12);
    CHECK_REL(r.drag.y, -245.0 * 1e-3 * 0.25, 1e-12);
    /* zero relative velocity → zero drag */
    e.vel = v3(1.08, 0, 0);
    sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r);
    CHECK(r.drag.x == 0.0 && r.drag.y == 0.0 && r.drag.z == 0.0);
}

static void test_buoyancy(void)
{
    sd_fluid_params p = sd_fluid_params_default(TH);
    sd_fluid_force_result r;
    const double g = 9.81;
    sd_vec3 gv = v3(g * sin(TH), 0.0, -g * cos(TH));
    sd_vec3 up = v3(-sin(TH), 0.0, cos(TH)); /* world vertical in the flume frame */
    /* log SG 0.8, fully submerged (z = 0.01 < h), moving with the water (no drag):
     * weight 800 V g + buoyancy −1000 V g = −200 V g: 0.2 ρ V g upward */
    sd_fluid_element e = log_at(0.01, v3(0.6, 0.8, 0.0), v3(0, 0, 0));
    double u;
    sd_fluid_speed_flow(1.2, 0.03, 0.01, &u);
    e.vel = v3(u, 0, 0);
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r) == 1);
    double V = M_PI * 2.5e-5 * 0.1;
    CHECK_REL(r.volume, V, 1e-15);
    sd_vec3 net = v3_add(r.total, v3_scale(gv, 800.0 * V));
    CHECK_REL(v3_dot(net, up), 0.2 * 1000.0 * V * g, 1e-12);
    CHECK_NEAR(v3_norm(v3_madd(net, up, -v3_dot(net, up))), 0.0, 1e-15); /* purely vertical */
    CHECK(v3_dot(net, up) > 0.0);
    /* buoyancy alone = ρ V g up */
    CHECK_REL(v3_dot(r.buoyancy, up), 1000.0 * V * g, 1e-12);
    /* sphere SG 1.9, r = 0.01: net = 0.9 ρ V g downward */
    sd_fluid_element s = sphere_at(2.0, 0.01, 0.01, v3(u, 0, 0));
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &s, &r) == 1);
    double Vs = 4.0 / 3.0 * M_PI * 1e-6;
    net = v3_add(r.total, v3_scale(gv, 1900.0 * Vs));
    CHECK_REL(v3_dot(net, up), -0.9 * 1000.0 * Vs * g, 1e-12);
    /* centre above the surface: nothing at all (not even buoyancy) */
    s = sphere_at(2.0, 0.0301, 0.01, v3(0, 0, 0));
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &s, &r) == 0);
    CHECK(r.total.x == 0.0 && r.total.y == 0.0 && r.total.z == 0.0);
    sd_vec3 t = sd_fluid_force_total(&p, SD_FLUID_FLOW, 0.0, &s);
    CHECK(t.x == 0.0 && t.y == 0.0 && t.z == 0.0);
    /* ... but wet in the capture phase when h_D = 0.05 ... */
    CHECK(sd_fluid_force(&p, SD_FLUID_CAPTURE, 0.05, &s, &r) == 1);
    /* ... and dry above h_D */
    s.pos.z = 0.0501;
    CHECK(sd_fluid_force(&p, SD_FLUID_CAPTURE, 0.05, &s, &r) == 0);
    /* no phase, bad shape */
    s.pos.z = 0.01;
    CHECK(sd_fluid_force(&p, SD_FLUID_NONE, 0.05, &s, &r) == 0);
    s.shape = 7;
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &s, &r) == 0);
    CHECK(r.total.x == 0.0 && r.total.z == 0.0);
}

/* Same physics in a world frame (z vertical, bed tilted): buoyancy along +z, drag along the
 * tilted flow direction, height measured along the tilted bed normal. */
static void test_other_frame(void)
{
    sd_fluid_params p = sd_fluid_params_default(TH);
    p.bed_normal = v3(sin(TH), 0.0, cos(TH));
    p.flow_dir = v3(cos(TH), 0.0, -sin(TH));
    p.gravity = v3(0.0, 0.0, -9.81);
    p.z_bed = 0.1; /* bed plane through 0.1 × bed_normal */
    sd_fluid_element e;
    e.shape = SD_SHAPE_SPHERE;
    e.pos = v3_add(v3_scale(p.bed_normal, 0.1 + 0.015), v3_scale(p.flow_dir, 1.7));
    e.vel = v3(0, 0, 0);
    e.axis = v3(1, 0, 0);
    e.radius = 0.01;
    e.length = 0.0;
    sd_fluid_force_result r;
    CHECK(sd_fluid_force(&p, SD_FLUID_FLOW, 0.0, &e, &r) == 1);
    CHECK_NEAR(r.z, 0.015, 1e-15);
    CHECK_NEAR(r.u_local, 1.08, 1e-14);
    double D = 245.0 * M_PI * 1e-4 * 1.08 * 1.08;
    CHECK_VEC_NEAR(r.drag, v3_scale(p.flow_dir, D), 1e-15);
    CHECK_VEC_NEAR(r.buoyancy, v3(0.0, 0.0, 1000.0 * 9.81 * 4.0 / 3.0 * M_PI * 1e-6), 1e-15);
}

static void test_dam_depth(void)
{
    /* window [3.9, 4.0] (x_dam = 4, probe 0.1): indices 1, 2, 3 → max z = 0.07 */
    const double x[] = {3.85, 3.95, 3.99, 4.0, 4.01, 3.5, 3.97};
    const double z[] = {0.20, 0.04, 0.06, 0.07, 0.50, 0.9, NAN};
    CHECK(sd_fluid_dam_depth(0.03, 7, x, z, NULL, 4.0, 0.1) == 0.07);
    unsigned char mask[] = {1, 1, 1, 0, 1, 1, 1};
    CHECK(sd_fluid_dam_depth(0.03, 7, x, z, mask, 4.0, 0.1) == 0.06);
    /* never below h */
    CHECK(sd_fluid_dam_depth(0.08, 7, x, z, NULL, 4.0, 0.1) == 0.08);
    /* empty window / no elements */
    CHECK(sd_fluid_dam_depth(0.03, 7, x, z, NULL, 3.0, 0.1) == 0.03);
    CHECK(sd_fluid_dam_depth(0.03, 0, NULL, NULL, NULL, 4.0, 0.1) == 0.03);
    /* longer probe reaches x = 3.85 (z = 0.2) */
    CHECK(sd_fluid_dam_depth(0.03, 7, x, z, NULL, 4.0, 0.2) == 0.2);
}

/* The batched sphere force against sd_fluid_force_total, bit for bit, over wet and dry, flow
 * and capture lanes, centres below the bed, both capture regimes (alpha clamped or not) and
 * a tilted frame. */
static void test_sphere_batch(void)
{
    uint64_t st = 0x9E3779B97F4A7C15ULL;
    enum { N = 1000 };
    static double px[N], py[N], pz[N], vx[N], vy[N], vz[N], r[N], cap[N], fx[N], fy[N], fz[N];
    long differ = 0, wet = 0, dry = 0, ncap = 0;
    for (int frame = 0; frame < 2; frame++) {
        sd_fluid_params p = sd_fluid_params_default(15.0 * M_PI / 180.0);
        if (frame) { /* a tilted bed and another flow direction */
            p.bed_normal = v3_normalize(v3(0.1, -0.2, 1.0));
            p.flow_dir = v3_normalize(v3_cross(v3(0.0, 1.0, 0.0), p.bed_normal));
            p.z_bed = 0.01;
        }
        for (int hcase = 0; hcase < 3; hcase++) {
            const double h_D = hcase == 0 ? 0.02 : (hcase == 1 ? 0.04 : 0.12); /* below h, alpha > 0.1, clamped */
            for (int j = 0; j < N; j++) {
                double u[8];
                for (int k = 0; k < 8; k++) {
                    st ^= st << 13, st ^= st >> 7, st ^= st << 17;
                    u[k] = (double)(st >> 11) / 9007199254740992.0;
                }
                px[j] = 4.0 * u[0], py[j] = 0.3 * u[1] - 0.15, pz[j] = 0.16 * u[2] - 0.01;
                vx[j] = 2.0 * u[3] - 0.5, vy[j] = 0.4 * u[4] - 0.2, vz[j] = 0.4 * u[5] - 0.2;
                r[j] = 0.0025 + 0.0075 * u[6];
                cap[j] = u[7] < 0.5 ? 1.0 : 0.0;
                if (j % 97 == 0) vx[j] = vy[j] = vz[j] = 0.0;
            }
            sd_fluid_sphere_batch(&p, h_D, N, px, py, pz, vx, vy, vz, r, cap, fx, fy, fz);
            for (int j = 0; j < N; j++) {
                sd_fluid_element e = {
                    SD_SHAPE_SPHERE, v3(px[j], py[j], pz[j]), v3(vx[j], vy[j], vz[j]), v3(0, 0, 1), r[j], 0.0};
                sd_fluid_force_result res;
                const int w = sd_fluid_force(&p, cap[j] != 0.0 ? SD_FLUID_CAPTURE : SD_FLUID_FLOW, h_D, &e, &res);
                wet += w, dry += !w, ncap += cap[j] != 0.0 && w;
                differ += memcmp(&res.total.x, &fx[j], sizeof(double)) ||
                          memcmp(&res.total.y, &fy[j], sizeof(double)) || memcmp(&res.total.z, &fz[j], sizeof(double));
            }
        }
    }
    printf("sphere batch: %ld wet (%ld capture), %ld dry, %ld differ from the scalar force\n", wet, ncap, dry, differ);
    CHECK(differ == 0);
    CHECK(wet > 1000 && dry > 1000 && ncap > 500);
}

int main(void)
{
    test_sphere_batch();
    test_flow_profile();
    test_capture_profile();
    test_discharge();
    test_areas();
    test_drag_sphere();
    test_drag_log();
    test_buoyancy();
    test_other_frame();
    test_dam_depth();
    return check_report("test_fluid");
}
