/* Pipe loads in design terms (src/pipe_loads.c, docs/loads.md), against closed forms:
 * - the resultant's position along a pipe from its force and torque: a force at a known point
 *   (with a radial offset, as a contact on the pipe's surface has) gives that point;
 * - the bending moment of a point load: simple supports P a b / L, fixed ends P a b^2 / L^2
 *   (the larger end moment), symmetric in a <-> b, zero at the supports;
 * - through the engine: a sphere settled on a fixed horizontal pipe 30 mm off its centre
 *   loads it with its weight, and the position read back from the pipe's force and torque is
 *   the sphere's, so the engine's torque is about the pipe's centre as the formula assumes. */
#include <math.h>

#include "check.h"
#include "core/vmath.h"
#include "pipe_loads.h"
#include "sabodem.h"

static void resultant_position(void)
{
    const double R = 0.009;
    const sd_vec3 axes[3] = {v3(0, 0, 1), v3(0, 1, 0), v3_normalize(v3(1, 2, 3))};
    for (int k = 0; k < 3; k++) {
        const sd_vec3 a = axes[k];
        /* a unit vector across the axis, and a force across it with an axial part too */
        const sd_vec3 n = v3_normalize(v3_cross(a, v3(0.3, -0.7, 0.2)));
        const sd_vec3 f = v3_add(v3_scale(n, -2.5), v3_scale(v3_cross(a, n), 0.4));
        for (double s = -0.05; s <= 0.05; s += 0.025) {
            /* the contact point on the surface: s along the axis, R out along n (normal force
             * through the axis) */
            const sd_vec3 r = v3_add(v3_scale(a, s), v3_scale(n, R));
            /* torque of the normal part through the axis, plus the tangential part's own */
            const sd_vec3 t = v3_cross(r, f);
            double fa;
            const double got = sd_pipe_resultant_position(a, f, t, &fa);
            /* the tangential force 0.4 (across the axis, at radius R) shifts nothing along it */
            CHECK_NEAR(got, s, 1e-12);
            CHECK_NEAR(fa, sqrt(2.5 * 2.5 + 0.4 * 0.4), 1e-12);
        }
    }
    /* a force along the axis only: nothing across, position 0 */
    double fa;
    CHECK_NEAR(sd_pipe_resultant_position(v3(0, 0, 1), v3(0, 0, 3), v3(0, 0, 0), &fa), 0.0, 0.0);
    CHECK_NEAR(fa, 0.0, 0.0);
}

static void bending_moments(void)
{
    const double L = 0.136, P = 4.0;
    for (double x = 0.0; x <= L + 1e-12; x += L / 8) {
        const double a = x, b = L - x;
        CHECK_NEAR(sd_pipe_bending_moment(SD_SUPPORT_SIMPLE, L, x, P), P * a * b / L, 1e-15);
        CHECK_NEAR(sd_pipe_bending_moment(SD_SUPPORT_FIXED, L, x, P), P * fmax(a * b * b, a * a * b) / (L * L), 1e-15);
        CHECK_NEAR(sd_pipe_bending_moment(SD_SUPPORT_SIMPLE, L, x, P), sd_pipe_bending_moment(SD_SUPPORT_SIMPLE, L, L - x, P),
                   1e-15);
    }
    /* mid-span: P L / 4 simple; fixed ends P L / 8 */
    CHECK_NEAR(sd_pipe_bending_moment(SD_SUPPORT_SIMPLE, L, L / 2, P), P * L / 4, 1e-15);
    CHECK_NEAR(sd_pipe_bending_moment(SD_SUPPORT_FIXED, L, L / 2, P), P * L / 8, 1e-15);
    /* a position outside the span is clamped to the support: no moment */
    CHECK_NEAR(sd_pipe_bending_moment(SD_SUPPORT_SIMPLE, L, -0.01, P), 0.0, 0.0);
}

static void sphere_on_pipe(void)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(0, 0, -9.81);
    def.dt = 1e-5;
    def.contact.k_n = 1e4;
    def.contact.damping = 0.7;
    sd_world *w;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    const double R = 0.009, r = 0.01, s0 = 0.03;
    sd_cylinder_def c = sd_cylinder_def_default();
    c.pos = v3(0, 0, 0);
    c.axis = v3(1, 0, 0);
    c.radius = R;
    c.length = 0.12;
    c.density = 7850;
    c.fixed = 1;
    const int pipe = sd_world_add_cylinder(w, &c);
    sd_sphere_def sp = sd_sphere_def_default();
    sp.pos = v3(s0, 0, R + r + 1e-4);
    sp.radius = r;
    sp.density = 1900;
    const int ball = sd_world_add_sphere(w, &sp);
    CHECK(pipe >= 0 && ball >= 0);
    sd_status st = SD_OK;
    for (int i = 0; i < 50000 && st == SD_OK; i++)
        st = sd_world_step(w);
    CHECK(st == SD_OK);
    sd_body_state bp, bs;
    sd_world_body(w, pipe, &bp);
    sd_world_body(w, ball, &bs);
    const double weight = bs.mass * 9.81;
    CHECK_REL(bp.force.z, -weight, 1e-6);
    double fa;
    const double s = sd_pipe_resultant_position(bp.axis, bp.force, bp.torque, &fa);
    CHECK_NEAR(s, bs.pos.x, 1e-9);
    CHECK_NEAR(s, s0, 1e-6);
    CHECK_REL(fa, weight, 1e-6);
    /* on a simple span of the pipe's length: P (L/2 + s)(L/2 - s) / L */
    const double a = 0.06 + s, b = 0.06 - s;
    CHECK_REL(sd_pipe_bending_moment(SD_SUPPORT_SIMPLE, 0.12, a, fa), weight * a * b / 0.12, 1e-6);
    sd_world_destroy(w);
}

int main(void)
{
    resultant_position();
    bending_moments();
    sphere_on_pipe();
    return check_report("test_pipe_loads");
}
