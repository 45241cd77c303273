/* Energy conservation of the leapfrog with elastic, frictionless contacts (h = 0, tanφ = 0):
 * (1) a 20 mm sphere bouncing 100 times on a floor of triangles under gravity;
 * (2) 27 spheres of mixed sizes in a closed box of triangles, gravity on, 0.5 s.
 * Total energy = sd_world_kinetic_energy + sd_world_potential_energy + sd_world_spring_energy. */
#include <string.h>

#include "check.h"
#include "sabodem.h"
#include "core/vmath.h"

static double total_energy(const sd_world *w)
{
    return sd_world_kinetic_energy(w) + sd_world_potential_energy(w) + sd_world_spring_energy(w);
}

static sd_world *elastic_world(void)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(0, 0, -9.81);
    def.dt = 1e-5;
    def.contact.damping = 0.0;
    def.contact.tan_phi = 0.0;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    return w;
}

static void add_quad(sd_world *w, sd_vec3 a, sd_vec3 b, sd_vec3 c, sd_vec3 d, int group)
{
    CHECK(sd_world_add_triangle(w, a, b, c, group) >= 0);
    CHECK(sd_world_add_triangle(w, a, c, d, group) >= 0);
}

static void test_bounces(void)
{
    sd_world *w = elastic_world();
    const double L = 0.03;
    /* floor of 8 triangles sharing edges; the sphere lands on a shared vertex region */
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            double x0 = -L + i * L, y0 = -L + j * L;
            add_quad(w, v3(x0, y0, 0), v3(x0 + L, y0, 0), v3(x0 + L, y0 + L, 0), v3(x0, y0 + L, 0), 0);
        }
    const double r = 0.01, drop = 1.0e-3, g = 9.81;
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = r;
    s.density = 1900.0;
    s.pos = v3(0.004, 0.003, r + drop);
    s.omega = v3(3.0, -2.0, 5.0); /* spin: must stay constant without friction */
    int id = sd_world_add_sphere(w, &s);
    sd_body_state b;
    sd_world_body(w, id, &b);
    double m = b.mass;
    const double e_bounce = m * g * drop; /* energy above resting on the floor */
    double e0 = total_energy(w);
    /* apex energies (v_z changes sign upward->downward): no lag error from the staggered v */
    double apex_e[128];
    int napex = 0, bounces = 0, in_contact = 0;
    double vz_prev = 0.0, max_raw = 0.0, max_sync = 0.0;
    sd_vec3 prev_vel = b.vel, prev_pos = b.pos;
    double prev_ke_rot = 0.0;
    long steps = 0;
    while (bounces < 100 && steps < 5000000) {
        CHECK(sd_world_step(w) == SD_OK);
        steps++;
        sd_world_body(w, id, &b);
        int c = b.force.z != 0.0;
        if (c && !in_contact) bounces++;
        in_contact = c;
        double e = total_energy(w);
        if (fabs(e - e0) > max_raw) max_raw = fabs(e - e0);
        /* synchronised energy at the previous position: v(t) = mean of the two half-step
         * velocities around it, spring ½ k δ² of the face contact */
        sd_vec3 vs = v3_scale(v3_add(prev_vel, b.vel), 0.5);
        double ov = r - prev_pos.z;
        double es = 0.5 * m * v3_norm2(vs) + prev_ke_rot + m * g * prev_pos.z + (ov > 0 ? 0.5 * 1e4 * ov * ov : 0.0);
        if (steps > 1 && fabs(es - e0) > max_sync) max_sync = fabs(es - e0);
        if (vz_prev > 0.0 && b.vel.z <= 0.0 && napex < 128) apex_e[napex++] = e;
        vz_prev = b.vel.z;
        prev_vel = b.vel;
        prev_pos = b.pos;
        prev_ke_rot = 0.5 * 0.4 * m * r * r * v3_norm2(b.omega);
    }
    double drift = (apex_e[napex - 1] - e0) / e_bounce;
    printf("100 bounces: %ld steps (%.3f s), %d apexes, apex energy drift %.2e of m g H, max raw |E-E0| %.2e, "
           "max synchronised |E-E0| %.2e (of m g H = %.3e J)\n",
           steps, steps * 1e-5, napex, drift, max_raw / e_bounce, max_sync / e_bounce, e_bounce);
    CHECK(bounces == 100);
    CHECK(napex >= 99);
    CHECK(fabs(drift) < 1e-3);
    for (int k = 0; k < napex; k++) CHECK(fabs(apex_e[k] - e0) < 1e-3 * e_bounce);
    CHECK(max_sync < 1e-3 * e_bounce);
    CHECK(max_raw < 2e-2 * e_bounce); /* staggered v: O(ω0 Δt) inside a contact */
    CHECK_VEC_NEAR(b.omega, s.omega, 1e-12);
    sd_world_destroy(w);
}

static void test_box(void)
{
    sd_world *w = elastic_world();
    const double L = 0.06, Hh = 0.06;
    /* closed box, 12 triangles, normals irrelevant (two-sided) */
    add_quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, L, 0), v3(0, L, 0), 0);
    add_quad(w, v3(0, 0, Hh), v3(L, 0, Hh), v3(L, L, Hh), v3(0, L, Hh), 1);
    add_quad(w, v3(0, 0, 0), v3(L, 0, 0), v3(L, 0, Hh), v3(0, 0, Hh), 1);
    add_quad(w, v3(0, L, 0), v3(L, L, 0), v3(L, L, Hh), v3(0, L, Hh), 1);
    add_quad(w, v3(0, 0, 0), v3(0, L, 0), v3(0, L, Hh), v3(0, 0, Hh), 1);
    add_quad(w, v3(L, 0, 0), v3(L, L, 0), v3(L, L, Hh), v3(L, 0, Hh), 1);
    const double radii[3] = {0.005, 0.0075, 0.01};
    uint32_t seed = 12345;
    int n = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = radii[(i + j + k) % 3];
                s.density = 1900.0;
                s.pos = v3(0.01 + 0.02 * i, 0.01 + 0.02 * j, 0.01 + 0.02 * k);
                double v[3];
                for (int q = 0; q < 3; q++) {
                    seed = seed * 1664525u + 1013904223u;
                    v[q] = ((seed >> 8) / 16777216.0 - 0.5) * 0.6;
                }
                s.vel = v3(v[0], v[1], v[2]);
                CHECK(sd_world_add_sphere(w, &s) >= 0);
                n++;
            }
    double e0 = total_energy(w);
    double ke0 = sd_world_kinetic_energy(w);
    /* window means of the raw energy smooth the O(ω0 Δt) staggering inside contacts */
    const long steps = 50000, win = 2500;
    double first = 0, last = 0, max_dev = 0;
    long contacts = 0;
    for (long k = 0; k < steps; k++) {
        CHECK(sd_world_step(w) == SD_OK);
        double e = total_energy(w);
        if (k < win) first += e;
        if (k >= steps - win) last += e;
        if (fabs(e - e0) > max_dev) max_dev = fabs(e - e0);
        contacts += sd_world_contact_count(w);
    }
    first /= win;
    last /= win;
    double drift = (last - first) / ke0;
    printf("box of %d spheres, 0.5 s: mean contacts %.2f, KE0 %.3e J, window-mean drift %.2e of KE0, max raw "
           "|E-E0| %.2e of KE0\n",
           n, (double)contacts / steps, ke0, drift, max_dev / ke0);
    CHECK(contacts > 0);
    CHECK(fabs(drift) < 1e-3);
    CHECK(max_dev < 2e-2 * ke0);
    sd_world_destroy(w);
}

int main(void)
{
    test_bounces();
    test_box();
    return check_report("test_energy");
}
