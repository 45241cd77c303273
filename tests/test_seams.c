/* Friction across seams (issue 51 item 2, docs/geometry.md "springs carried"): a contact that
 * moves from one triangle to a coplanar neighbour keeps its tangential spring, so a flat bed
 * made of many triangles behaves as one plane. Each case runs twice, on a mesh whose seams lie
 * under the path (a strip of squares, each split along a diagonal that crosses the path) and
 * on one large triangle, and the two must agree:
 * - rolling down a 20° incline (tanφ = 0.404 ≥ (2/7) tanθ): the same position, velocity and
 *   spin at every sample, and the friction force never drops at a seam;
 * - a disc at rest on its face on a 10° incline, across seams: static friction holds it (no
 *   creep), as on the plane;
 * - an oblique impact with back-spin landing exactly on a seam: the same rebound (velocity and
 *   spin) as on one triangle.
 * The bound 1e-9 (relative) is far below what a reset spring costs. Measured with the engine
 * before the springs were carried (the same test): the friction force fell to zero at seams
 * (relative difference 1.0), the rolling sphere's x, v, w differed by up to 2.9e-3, the disc
 * crept 1.1 mm in 0.5 s, and the rebound's x velocity differed by 2.3e-3 and its spin by 1.3e-5;
 * now all agree to the last bits (0 and 1e-15). */
#include <string.h>

#include "check.h"
#include "core/vmath.h"
#include "sabodem.h"

static const double G = 9.81;

enum { MESH = 0, PLANE = 1 };

/* The bed: a strip along x (y in [-hw, hw]) from x = -0.05 to 0.35, as 8 squares of 0.05 m each
 * split along a diagonal (MESH), or as one triangle far larger than the strip (PLANE). */
static void add_bed(sd_world *w, int kind)
{
    if (kind == PLANE) {
        CHECK(sd_world_add_triangle(w, v3(-1, -1, 0), v3(3, -1, 0), v3(-1, 3, 0), 0) >= 0);
        return;
    }
    const double seg = 0.05, hw = 0.02;
    for (int k = 0; k < 8; k++) {
        const double x0 = -0.05 + k * seg, x1 = x0 + seg;
        CHECK(sd_world_add_triangle(w, v3(x0, -hw, 0), v3(x1, -hw, 0), v3(x1, hw, 0), 0) >= 0);
        CHECK(sd_world_add_triangle(w, v3(x0, -hw, 0), v3(x1, hw, 0), v3(x0, hw, 0), 0) >= 0);
    }
}

static sd_world *incline(double theta_deg, int kind)
{
    const double th = theta_deg * M_PI / 180.0;
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(G * sin(th), 0.0, -G * cos(th));
    def.contact.tan_phi = 0.404;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    add_bed(w, kind);
    return w;
}

static int sphere(sd_world *w, sd_vec3 pos, sd_vec3 vel, sd_vec3 omega)
{
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = 0.01;
    s.density = 1900.0;
    s.pos = pos;
    s.vel = vel;
    s.omega = omega;
    const int id = sd_world_add_sphere(w, &s);
    CHECK(id >= 0);
    return id;
}

static double rel(double a, double b) { return fabs(a - b) / fmax(fabs(b), 1e-12); }

/* Rolling down 20°: 0.5 s, 0.3 m of travel (a = (5/7) g sinθ) over 12 seams. */
static void rolling(void)
{
    sd_world *w[2];
    int id[2];
    for (int k = 0; k < 2; k++) {
        w[k] = incline(20.0, k);
        id[k] = sphere(w[k], v3(0.0, 0.0, 0.00995), v3(0, 0, 0), v3(0, 0, 0));
    }
    double worst = 0.0, ft_worst = 0.0;
    sd_status st = SD_OK;
    for (long n = 1; n <= 50000 && st == SD_OK; n++) {
        sd_body_state b[2];
        for (int k = 0; k < 2 && st == SD_OK; k++) {
            st = sd_world_step(w[k]);
            sd_world_body(w[k], id[k], &b[k]);
        }
        if (n % 100 == 0) {
            worst = fmax(worst, rel(b[MESH].pos.x, b[PLANE].pos.x));
            worst = fmax(worst, rel(b[MESH].vel.x, b[PLANE].vel.x));
            worst = fmax(worst, rel(b[MESH].omega.y, b[PLANE].omega.y));
        }
        /* the friction force (along x) at every step, seams or not */
        ft_worst = fmax(ft_worst, fabs(b[MESH].force.x - b[PLANE].force.x) / fmax(fabs(b[PLANE].force.x), 1e-6));
    }
    CHECK(st == SD_OK);
    sd_body_state e;
    sd_world_body(w[MESH], id[MESH], &e);
    const double a = 5.0 / 7.0 * G * sin(20.0 * M_PI / 180.0);
    printf("rolling over 12 seams: %.4f m in 0.5 s (a t^2/2 = %.4f m), mesh against plane: worst relative "
           "difference of x, v, w %.2e, of the friction force %.2e\n",
           e.pos.x, 0.5 * a * 0.25, worst, ft_worst);
    CHECK_REL(e.pos.x, 0.5 * a * 0.25, 0.01);
    CHECK(worst < 1e-9);
    CHECK(ft_worst < 1e-9);
    sd_world_destroy(w[0]);
    sd_world_destroy(w[1]);
}

/* A disc (a log 30 mm across, 10 mm long, standing on its end face) at rest on 10° with the
 * square boundary at x = 0.05 and a diagonal under its face: held by static friction
 * (tanφ = 0.404 > tan 10°), as on the plane. (A sphere would roll: a face is what rests.) */
static void resting_on_seam(void)
{
    double creep[2];
    for (int k = 0; k < 2; k++) {
        sd_world *w = incline(10.0, k);
        sd_cylinder_def c = sd_cylinder_def_default();
        c.radius = 0.015;
        c.length = 0.01;
        c.density = 800.0;
        c.axis = v3(0, 0, 1);
        c.pos = v3(0.05, 0.0, 0.005 - 1e-6);
        const int id = sd_world_add_cylinder(w, &c);
        CHECK(id >= 0);
        sd_status st = SD_OK;
        for (long n = 0; n < 30000 && st == SD_OK; n++) /* 0.3 s to settle */
            st = sd_world_step(w);
        sd_body_state a, b;
        sd_world_body(w, id, &a);
        for (long n = 0; n < 50000 && st == SD_OK; n++) /* then 0.5 s */
            st = sd_world_step(w);
        CHECK(st == SD_OK);
        sd_world_body(w, id, &b);
        creep[k] = b.pos.x - a.pos.x;
        sd_world_destroy(w);
    }
    printf("a disc at rest across seams, 10 deg: creep over 0.5 s %.2e m (mesh), %.2e m (plane)\n", creep[MESH],
           creep[PLANE]);
    CHECK(fabs(creep[MESH]) < 1e-7);
    CHECK(fabs(creep[PLANE]) < 1e-7);
}

/* Oblique impact with back-spin landing on the diagonal seam of the second square, on a flat
 * bed (gravity straight down): the same rebound as on one triangle. */
static void impact_on_seam(void)
{
    sd_body_state out[2];
    for (int k = 0; k < 2; k++) {
        sd_world_def def = sd_world_def_default();
        def.gravity = v3(0, 0, -G);
        def.contact.tan_phi = 0.404;
        sd_world *w = NULL;
        CHECK(sd_world_create(&def, &w) == SD_OK);
        add_bed(w, k);
        /* the diagonal of square 2 runs from (0.05, -0.02) to (0.10, 0.02): it crosses y = 0 at
         * x = 0.075, where the sphere lands after 2 mm of fall and 1.5 ms of travel */
        const int id = sphere(w, v3(0.075 - 0.5 * 0.0021, 0.0, 0.012), v3(0.5, 0.0, -1.0), v3(0.0, -80.0, 0.0));
        sd_status st = SD_OK;
        for (long n = 0; n < 1500 && st == SD_OK; n++) /* 15 ms: fall, contact, rebound */
            st = sd_world_step(w);
        CHECK(st == SD_OK);
        sd_world_body(w, id, &out[k]);
        sd_world_destroy(w);
    }
    printf("impact with spin on a seam: rebound v = (%.6f, %.6f) m/s, w_y = %.4f rad/s (plane: (%.6f, %.6f), %.4f)\n",
           out[MESH].vel.x, out[MESH].vel.z, out[MESH].omega.y, out[PLANE].vel.x, out[PLANE].vel.z, out[PLANE].omega.y);
    CHECK(out[MESH].vel.z > 0.1); /* it did bounce */
    CHECK(rel(out[MESH].vel.x, out[PLANE].vel.x) < 1e-9);
    CHECK(rel(out[MESH].vel.z, out[PLANE].vel.z) < 1e-9);
    CHECK(rel(out[MESH].omega.y, out[PLANE].omega.y) < 1e-9);
}

int main(void)
{
    rolling();
    resting_on_seam();
    impact_on_seam();
    return check_report("test_seams");
}
