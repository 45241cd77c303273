/* Sphere–sphere friction, rolling and the tangential–rotational mode, through the engine's
 * sphere-pair path (the lanes of the contact pass), against closed forms. The partner is a
 * fixed sphere of radius R = 10 m: locally a floor, so the closed forms of a sphere on a plane
 * hold to O(x/R).
 *
 * 1. Spin without speed (the billiard stroke): a 20 mm sphere set down spinning at ω0 slides,
 *    friction tanφ m g accelerates it at tanφ g and slows the spin at (5/2) tanφ g / r, until it
 *    rolls at t* = 2 r ω0 / (7 tanφ g), with v = (2/7) r ω0 from then on.
 * 2. The tangential spring against translation and rotation together: a sphere held by
 *    friction, pushed sideways, swings at ω_t = sqrt((7/2) K_s / m*) (docs/physics.md §1),
 *    1.18 ω_n at the paper's K_s/K_n = 0.4; sd_stable_dt_max takes that mode into account. */
#include <string.h>

#include "check.h"
#include "core/vmath.h"
#include "sabodem.h"

static const double R = 10.0, r = 0.01, rho = 1900.0, g = 9.81;

/* A world with gravity −g z, the big fixed sphere under z = 0 and a sphere of radius r on it at
 * its equilibrium overlap m g / K_n; returns the small sphere's gid. */
static sd_world *make(sd_world_def *d, sd_vec3 vel, sd_vec3 omega, int *gid)
{
    d->gravity = v3(0, 0, -g);
    sd_world *w = NULL;
    CHECK(sd_world_create(d, &w) == SD_OK);
    sd_sphere_def big = sd_sphere_def_default();
    big.radius = R;
    big.pos = v3(0, 0, -R);
    big.fixed = 1;
    CHECK(sd_world_add_sphere(w, &big) >= 0);
    const double m = rho * 4.0 / 3.0 * M_PI * r * r * r;
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = r;
    s.density = rho;
    s.pos = v3(0, 0, r - m * g / d->contact.k_n);
    s.vel = vel;
    s.omega = omega;
    *gid = sd_world_add_sphere(w, &s);
    CHECK(*gid >= 0);
    return w;
}

static void test_billiard(void)
{
    sd_world_def d = sd_world_def_default(); /* K_n 1e4, K_s 4e3, h 0.2, tanφ 0.404 */
    d.dt = 1e-5;
    const double mu = d.contact.tan_phi, w0 = 50.0;
    int id;
    sd_world *w = make(&d, v3(0, 0, 0), v3(0, w0, 0), &id);
    const double t_star = 2.0 * r * w0 / (7.0 * mu * g), v_roll = 2.0 / 7.0 * r * w0;
    sd_body_state b;
    double v1 = 0, v2 = 0, w1 = 0, w2 = 0, slip_max = 0;
    const long n1 = 500, n2 = 2500, n_end = 8000; /* 5 ms, 25 ms (sliding), 80 ms (rolling) */
    for (long k = 1; k <= n_end; k++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_world_body(w, id, &b);
        if (k == n1) v1 = b.vel.x, w1 = b.omega.y;
        if (k == n2) v2 = b.vel.x, w2 = b.omega.y;
        if (k * d.dt > 1.5 * t_star) slip_max = fmax(slip_max, fabs(b.vel.x - b.omega.y * r) / v_roll);
    }
    const double a = (v2 - v1) / ((n2 - n1) * d.dt), alpha = (w2 - w1) / ((n2 - n1) * d.dt);
    printf("billiard stroke on a sphere: sliding a = %.6f m/s^2 (tanφ g = %.6f), spin-down %.4f rad/s^2 ((5/2) tanφ g / r "
           "= %.4f); rolling v = %.6f m/s ((2/7) r ω0 = %.6f), slip <= %.2e v after 1.5 t* (t* = %.4f s)\n",
           a, mu * g, -alpha, 2.5 * mu * g / r, b.vel.x, v_roll, slip_max, t_star);
    CHECK_REL(a, mu * g, 2e-3);
    CHECK_REL(-alpha, 2.5 * mu * g / r, 2e-3); /* (the lever arm is r − δ/2: 4e-4 short) */
    CHECK_REL(b.vel.x, v_roll, 2e-3);
    CHECK(slip_max < 2e-3);
    CHECK(fabs(b.vel.y) < 1e-12 && fabs(b.omega.x) < 1e-9 && fabs(b.omega.z) < 1e-9);
    sd_world_destroy(w);
}

static void test_tangential_mode(void)
{
    sd_world_def d = sd_world_def_default();
    d.dt = 1e-6;
    d.contact.damping = 0.0;
    d.contact.tan_phi = 10.0; /* held: no sliding */
    const double m = rho * 4.0 / 3.0 * M_PI * r * r * r;
    const double ks_list[2] = {4.0e3, 1.0e4};
    for (int c = 0; c < 2; c++) {
        d.contact.k_s = ks_list[c];
        int id;
        sd_world *w = make(&d, v3(1e-3, 0, 0), v3(0, 0, 0), &id);
        sd_body_state b;
        double prev = 0, first = -1, last = -1;
        int crossings = 0;
        for (long k = 1; k <= 40000; k++) {
            CHECK(sd_world_step(w) == SD_OK);
            sd_world_body(w, id, &b);
            const double f = b.force.x, t = k * d.dt;
            if (k > 1 && (f > 0) != (prev > 0) && f != 0.0) {
                const double tc = t - d.dt * f / (f - prev); /* (linear between the steps) */
                if (first < 0) first = tc;
                last = tc;
                crossings++;
            }
            prev = f;
        }
        const double half = (last - first) / (crossings - 1), w_t = sqrt(3.5 * d.contact.k_s / m),
                     w_n = sqrt(d.contact.k_n / m);
        printf("tangential-rotational mode, K_s/K_n = %.1f: half period %.6e s over %d crossings (π/ω_t = %.6e s, "
               "ω_t/ω_n = %.4f)\n",
               d.contact.k_s / d.contact.k_n, half, crossings, M_PI / w_t, w_t / w_n);
        CHECK(crossings > 10);
        CHECK_REL(half, M_PI / w_t, 1e-3);
        sd_world_destroy(w);
    }
    /* the time-step check: 8 steps per half period of the faster mode, m* = m/2 */
    const double ms = 0.5 * m;
    CHECK_REL(sd_stable_dt_max(1e4, 4e3, m), M_PI / 8.0 / sqrt(1.4e4 / ms), 1e-15); /* ω_t = 1.18 ω_n */
    CHECK_REL(sd_stable_dt_max(1e4, 1e4, m), M_PI / 8.0 / sqrt(3.5e4 / ms), 1e-15); /* 1.87 ω_n */
    CHECK_REL(sd_stable_dt_max(1e4, 2e3, m), M_PI / 8.0 / sqrt(1e4 / ms), 1e-15);   /* the normal mode */
    CHECK_REL(sqrt(3.5 * 4e3 / 1e4), 1.1832, 1e-4);
}

int main(void)
{
    test_billiard();
    test_tangential_mode();
    return check_report("test_ss_friction");
}
