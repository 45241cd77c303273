/* Physics of logs (cylinders) against closed forms. Paper values: log φ10 × 100 mm, SG 0.8,
 * K_n = 1e4 N/m, K_s = 4e3 N/m, h = 0.2, tanφ = 0.404, Δt = 1e-5 s unless stated.
 *  1. log lying on a floor of triangles: support = m g, no drift, no spin;
 *  2. log standing on its end (vertical, centre at hl − mg/K_n); log dropped 30° from vertical
 *     lands on its rim, topples and lies down;
 *  3. log across a 15° slope rolls at (2/3) g sinθ with ω = v/r; log along the slope slides at
 *     g(sinθ − tanφ cosθ);
 *  4. sphere on the centre / near the rim of a log's end face, crossed logs: equilibrium,
 *     contact force = weight, normal along the common perpendicular;
 *  5. torque-free spinning log: L and kinetic energy constant, axis precessing about L at
 *     |L|/I_tr;
 *  6. log hitting a fixed φ18 mm pipe (gravity off): contact time and restitution of the
 *     clipped spring–dashpot for the effective mass at the contact, central and off-centre;
 *  7. the logs' moves in batches of SIMD lanes give the bits of the one-by-one moves: 80 logs
 *     (two full batches and a part) among spheres, tumbling, still (no spin) and all but
 *     still (a turn below the series' 1e-12 rad a step), falling into a heap on a floor.
 * Deterministic; numbers printed for docs/physics.md ("Logs (cylinders)"). */
#include <string.h>

#include "check.h"
#include "sabodem.h"
#include "core/vmath.h"
#include "world_internal.h" /* sd_cyl_batch_set */

static const double G = 9.81;
static const double R_LOG = 0.005, LEN_LOG = 0.1, RHO_LOG = 800.0;
static const double KN = 1.0e4;

static double log_mass(void) { return RHO_LOG * M_PI * R_LOG * R_LOG * LEN_LOG; }
static double log_itr(void) { return log_mass() * (3.0 * R_LOG * R_LOG + LEN_LOG * LEN_LOG) / 12.0; }

static sd_world *make_world(sd_vec3 g, double dt, double tan_phi)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = g;
    def.dt = dt;
    def.contact.tan_phi = tan_phi;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    return w;
}

/* Floor z = 0 over [x0,x1] × [y0,y1]: nx × ny squares, each split along a diagonal, group 0. */
static void add_floor(sd_world *w, double x0, double x1, double y0, double y1, int nx, int ny)
{
    double dx = (x1 - x0) / nx, dy = (y1 - y0) / ny;
    for (int i = 0; i < nx; i++)
        for (int j = 0; j < ny; j++) {
            double a = x0 + i * dx, b = a + dx, c = y0 + j * dy, d = c + dy;
            CHECK(sd_world_add_triangle(w, v3(a, c, 0), v3(b, c, 0), v3(b, d, 0), 0) >= 0);
            CHECK(sd_world_add_triangle(w, v3(a, c, 0), v3(b, d, 0), v3(a, d, 0), 0) >= 0);
        }
}

static int add_log(sd_world *w, sd_vec3 pos, sd_vec3 axis, sd_vec3 vel, sd_vec3 omega, int fixed)
{
    sd_cylinder_def c = sd_cylinder_def_default();
    c.pos = pos;
    c.axis = axis;
    c.vel = vel;
    c.omega = omega;
    c.radius = R_LOG;
    c.length = LEN_LOG;
    c.density = RHO_LOG;
    c.fixed = fixed;
    int id = sd_world_add_cylinder(w, &c);
    CHECK(id >= 0);
    return id;
}

static int add_ball(sd_world *w, sd_vec3 pos, double r, double rho)
{
    sd_sphere_def s = sd_sphere_def_default();
    s.pos = pos;
    s.radius = r;
    s.density = rho;
    int id = sd_world_add_sphere(w, &s);
    CHECK(id >= 0);
    return id;
}

static sd_body_state body(const sd_world *w, int id)
{
    sd_body_state b;
    memset(&b, 0, sizeof(b));
    CHECK(sd_world_body(w, id, &b) == SD_OK);
    return b;
}

/* run for t seconds at Δt = 1e-5 s */
static int run_for(sd_world *w, double t) { return sd_world_run(w, lround(t / 1e-5)) == SD_OK; }

/* least-squares fit of y = c0 + c1 t + c2 t² */
static void fit_quadratic(const double *t, const double *y, int n, double c[3])
{
    double S[5] = {0}, R[3] = {0};
    for (int i = 0; i < n; i++) {
        double p = 1.0;
        for (int k = 0; k < 5; k++) {
            S[k] += p;
            if (k < 3) R[k] += p * y[i];
            p *= t[i];
        }
    }
    double A[3][4] = {{S[0], S[1], S[2], R[0]}, {S[1], S[2], S[3], R[1]}, {S[2], S[3], S[4], R[2]}};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) {
            double f = A[j][i] / A[i][i];
            for (int k = i; k < 4; k++) A[j][k] -= f * A[i][k];
        }
    for (int i = 2; i >= 0; i--) {
        double s = A[i][3];
        for (int k = i + 1; k < 3; k++) s -= A[i][k] * c[k];
        c[i] = s / A[i][i];
    }
}

/* ---- 1. log lying on a floor ------------------------------------------------------------ */
static void test_lying(void)
{
    sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
    add_floor(w, -0.1, 0.1, -0.1, 0.1, 2, 2); /* seams and diagonals under the log */
    double m = log_mass();
    double ph = 20.0 * M_PI / 180.0;
    /* dropped from 0.2 mm, axis horizontal at 20° to x, centre off the seams */
    int id = add_log(w, v3(0.003, -0.002, R_LOG + 2e-4), v3(cos(ph), sin(ph), 0), v3(0, 0, 0), v3(0, 0, 0), 0);
    CHECK(run_for(w, 0.3));
    sd_body_state b0 = body(w, id);
    double fmax_dev = 0.0, wmax = 0.0;
    for (int k = 0; k < 50; k++) {
        CHECK(run_for(w, 0.01));
        sd_vec3 f = sd_world_group_force(w, 0); /* force on the floor: -support */
        double dev = fabs(-f.z - m * G) / (m * G);
        if (dev > fmax_dev) fmax_dev = dev;
        sd_body_state b = body(w, id);
        double wn = v3_norm(b.omega);
        if (wn > wmax) wmax = wn;
    }
    sd_body_state b1 = body(w, id);
    double drift = hypot(b1.pos.x - b0.pos.x, b1.pos.y - b0.pos.y);
    double zeq = R_LOG - m * G / KN; /* the two rim contacts share K_n */
    long nc = sd_world_contact_count(w);
    printf("1 lying: support/mg-1 max %.2e, drift %.2e m over 0.5 s, max |w| %.2e rad/s, z-zeq %.2e m, contacts %ld, "
           "axis.z %.1e\n",
           fmax_dev, drift, wmax, b1.pos.z - zeq, nc, b1.axis.z);
    CHECK(fmax_dev < 0.005);
    CHECK(drift < 1e-6);
    CHECK(wmax < 1e-4);
    CHECK_NEAR(b1.pos.z, zeq, 1e-7);
    CHECK(fabs(b1.axis.z) < 1e-6);
    CHECK(nc == 2);
    sd_world_destroy(w);
}

/* ---- 2. log standing; log dropped tilted topples ------------------------------------------ */
static void test_standing(void)
{
    double m = log_mass(), hl = 0.5 * LEN_LOG;
    for (int tilted = 0; tilted < 2; tilted++) {
        sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
        add_floor(w, -0.1, 0.1, -0.1, 0.1, 2, 2);
        /* standing on its end, centre off the seams, released 0.1 mm above the floor. The second
         * one is released 2 deg from vertical (below the tipping angle atan(r/hl) = 5.7 deg): it
         * rocks from rim to rim and must not fall over; a slender block rocks long (Housner: 3 %
         * of the energy lost per impact), so only the bound on the tilt is checked (settling:
         * test_contact_manifolds) */
        double ps = tilted ? 2.0 * M_PI / 180.0 : 0.0;
        int id = add_log(w, v3(0.02, 0.03, hl + 1e-4 + R_LOG * sin(ps)), v3(sin(ps), 0, cos(ps)), v3(0, 0, 0),
                         v3(0, 0, 0), 0);
        double tilt_max = 0.0;
        for (int k = 0; k < 100; k++) {
            CHECK(run_for(w, 0.005));
            sd_body_state b = body(w, id);
            double tl = hypot(b.axis.x, b.axis.y);
            if (k >= 20 && tl > tilt_max) tilt_max = tl;
        }
        sd_body_state b = body(w, id);
        sd_vec3 f = sd_world_group_force(w, 0);
        double tilt = hypot(b.axis.x, b.axis.y);
        printf("2 standing (released %.0f deg from vertical): tilt %.2e (max over 0.1-0.5 s %.2e), z - (hl - mg/kn) "
               "%.2e m, support/mg-1 %.2e, |v| %.2e, contacts %ld\n",
               ps * 180.0 / M_PI, tilt, tilt_max, b.pos.z - (hl - m * G / KN), -f.z / (m * G) - 1.0, v3_norm(b.vel),
               sd_world_contact_count(w));
        if (!tilted) {
            CHECK(tilt_max < 1e-3);
            CHECK_NEAR(b.pos.z, hl - m * G / KN, 1e-7);
            CHECK_REL(-f.z, m * G, 0.005);
            CHECK(v3_norm(b.vel) < 1e-5);
        } else {
            CHECK(tilt_max < atan(R_LOG / hl));
            CHECK(b.pos.z > hl * cos(tilt_max) - 1e-4);
        }
        /* the end face's four rim points (docs/geometry.md) */
        if (!tilted) CHECK(sd_world_contact_count(w) == 4);
        sd_world_destroy(w);
    }
    {
        sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
        add_floor(w, -0.2, 0.2, -0.2, 0.2, 4, 4);
        double th = 30.0 * M_PI / 180.0;
        sd_vec3 a = v3(sin(th) * cos(0.3), sin(th) * sin(0.3), cos(th));
        /* lowest rim point 1 mm above the floor */
        double zlow = hl * cos(th) + R_LOG * sin(th);
        int id = add_log(w, v3(0.01, -0.015, zlow + 1e-3), a, v3(0, 0, 0), v3(0, 0, 0), 0);
        int landed_on_rim = 0, first = 1;
        double tilt_at_first = 0.0;
        for (int k = 0; k < 150000; k++) {
            CHECK(sd_world_step(w) == SD_OK);
            if (first && sd_world_contact_count(w) > 0) {
                sd_body_state b = body(w, id);
                first = 0;
                tilt_at_first = acos(fabs(b.axis.z));
                landed_on_rim = sd_world_contact_count(w) == 1;
            }
        }
        sd_body_state b = body(w, id);
        double axis_deg = asin(fabs(b.axis.z)) * 180.0 / M_PI;
        printf("2 toppling: first contact at tilt %.1f deg (%s), final axis %.2f deg from horizontal, z - r %.2e m, "
               "|v| %.2e, |w| %.2e, travel %.3f m\n",
               tilt_at_first * 180.0 / M_PI, landed_on_rim ? "one rim contact" : "several", axis_deg, b.pos.z - R_LOG,
               v3_norm(b.vel), v3_norm(b.omega), hypot(b.pos.x - 0.01, b.pos.y + 0.015));
        CHECK(landed_on_rim);
        CHECK(axis_deg < 2.0);
        CHECK(fabs(b.pos.z - R_LOG) < 2e-5);
        CHECK(v3_norm(b.vel) < 1e-3);
        sd_world_destroy(w);
    }
}

/* ---- 3. slope: rolling across, sliding along ------------------------------------------------ */
#define NSAMP 4096
static void run_slope(int across, double tan_phi)
{
    double th = 15.0 * M_PI / 180.0;
    sd_world *w = make_world(v3(G * sin(th), 0, -G * cos(th)), 1e-5, tan_phi);
    add_floor(w, -0.05, 0.35, -0.08, 0.08, 8, 2);
    double m = log_mass();
    double fn = m * G * cos(th);
    sd_vec3 axis = across ? v3(0, 1, 0) : v3(1, 0, 0);
    int id = add_log(w, v3(0.0, 0.003, R_LOG - 0.5 * fn / KN), axis, v3(0, 0, 0), v3(0, 0, 0), 0);
    static double ts[NSAMP], xs[NSAMP];
    int ns = 0;
    double slip_max = 0.0, fn_dev = 0.0, wperp = 0.0;
    const double t0 = 0.05, t1 = 0.35;
    sd_body_state b = body(w, id);
    for (long k = 1; k <= lround(t1 / 1e-5); k++) {
        CHECK(sd_world_step(w) == SD_OK);
        double t = sd_world_time(w);
        if (t < t0) continue;
        b = body(w, id);
        if (k % 50 == 0 && ns < NSAMP) {
            ts[ns] = t;
            xs[ns] = b.pos.x;
            ns++;
            double dev = -sd_world_group_force(w, 0).z / fn - 1.0;
            if (fabs(dev) > fn_dev) fn_dev = fabs(dev);
        }
        if (across) {
            double slip = fabs(b.vel.x - b.omega.y * R_LOG);
            if (b.vel.x > 0.02 && slip / b.vel.x > slip_max) slip_max = slip / b.vel.x;
            double wp = hypot(b.omega.x, b.omega.z);
            if (wp > wperp) wperp = wp;
        } else {
            double wn = v3_norm(b.omega);
            if (wn > wperp) wperp = wn;
        }
    }
    double c[3];
    fit_quadratic(ts, xs, ns, c);
    double a = 2.0 * c[2];
    double a_th = across ? 2.0 / 3.0 * G * sin(th) : G * (sin(th) - tan_phi * cos(th));
    printf("3 slope %s (tan_phi %.3f): a = %.5f m/s^2 (theory %.5f, err %.2e), max |Fn/(mg cos)-1| %.2e, max slip/v "
           "%.2e, max |w| off-axis %.2e, |y| %.1e, travel %.3f m\n",
           across ? "across, rolling" : "along, sliding", tan_phi, a, a_th, fabs(a - a_th) / a_th, fn_dev, slip_max,
           wperp, fabs(b.pos.y - 0.003), b.pos.x);
    CHECK_REL(a, a_th, 0.01);
    CHECK(fn_dev < 0.02);
    if (across) {
        CHECK(slip_max < 0.01);
        CHECK(wperp < 1e-4 * b.omega.y); /* no yaw or pitch beside the rolling */
        CHECK_NEAR(b.axis.y, 1.0, 1e-6);
    } else {
        CHECK(wperp < 1e-2);
        CHECK_NEAR(b.axis.x, 1.0, 1e-6);
    }
    sd_world_destroy(w);
}

/* ---- 4. equilibria: sphere on an end face, crossed logs -------------------------------------- */
static void test_sphere_on_end(void)
{
    double hl = 0.5 * LEN_LOG, rs = 0.005, rhos = 1900.0;
    double ms = rhos * 4.0 / 3.0 * M_PI * rs * rs * rs, m = log_mass();
    {
        /* free log standing on the floor, sphere on the centre of its top face */
        sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
        add_floor(w, -0.1, 0.1, -0.1, 0.1, 2, 2);
        double zl = hl - (m + ms) * G / KN;
        int il = add_log(w, v3(0.02, 0.03, zl), v3(0, 0, 1), v3(0, 0, 0), v3(0, 0, 0), 0);
        int is = add_ball(w, v3(0.02, 0.03, zl + hl + rs - ms * G / KN + 1e-5), rs, rhos);
        CHECK(run_for(w, 0.4));
        sd_body_state s = body(w, is), l = body(w, il);
        sd_vec3 f = sd_world_group_force(w, 0);
        printf("4 sphere on end-face centre (log on floor): F_s/m_s g - 1 = %.2e, |F_s,xy| %.1e N, |v_s| %.2e, floor/((m+m_s)g) "
               "- 1 = %.2e, log tilt %.1e\n",
               s.force.z / (ms * G) - 1.0, hypot(s.force.x, s.force.y), v3_norm(s.vel), -f.z / ((m + ms) * G) - 1.0,
               hypot(l.axis.x, l.axis.y));
        CHECK_REL(s.force.z, ms * G, 0.005);
        CHECK(hypot(s.force.x, s.force.y) < 1e-3 * ms * G);
        CHECK(v3_norm(s.vel) < 1e-5);
        CHECK_REL(-f.z, (m + ms) * G, 0.005);
        CHECK(hypot(l.axis.x, l.axis.y) < 1e-3);
        sd_world_destroy(w);
    }
    {
        /* fixed standing log, sphere near the rim: its lowest point 0.5 mm inside the rim */
        sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
        int il = add_log(w, v3(0, 0, 0), v3(0, 0, 1), v3(0, 0, 0), v3(0, 0, 0), 1);
        double off = 0.9 * R_LOG;
        int is = add_ball(w, v3(off * cos(1.0), off * sin(1.0), hl + rs - ms * G / KN + 1e-5), rs, rhos);
        CHECK(run_for(w, 0.3));
        sd_body_state s = body(w, is), l = body(w, il);
        printf("4 sphere near the rim (fixed log): F_s/m_s g - 1 = %.2e, |F_s,xy| %.1e N, |v_s| %.2e, F_log.z/m_s g + 1 = "
               "%.2e, torque on log %.3e N m (expected %.3e)\n",
               s.force.z / (ms * G) - 1.0, hypot(s.force.x, s.force.y), v3_norm(s.vel), l.force.z / (ms * G) + 1.0,
               hypot(l.torque.x, l.torque.y), ms * G * off);
        CHECK_REL(s.force.z, ms * G, 0.005);
        CHECK(hypot(s.force.x, s.force.y) < 1e-3 * ms * G);
        CHECK(v3_norm(s.vel) < 1e-5);
        CHECK_REL(l.force.z, -ms * G, 0.005);
        /* the load acts at the contact point, off the axis: torque m_s g × off on the log */
        CHECK_REL(hypot(l.torque.x, l.torque.y), ms * G * off, 0.01);
        sd_world_destroy(w);
    }
}

static void test_crossed(double cross_deg)
{
    double m = log_mass();
    sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
    int il = add_log(w, v3(0, 0, 0), v3(1, 0, 0), v3(0, 0, 0), v3(0, 0, 0), 1);
    double c = cross_deg * M_PI / 180.0;
    double z0 = 2.0 * R_LOG - m * G / KN;
    int iu = add_log(w, v3(0, 0, z0 + 1e-5), v3(cos(c), sin(c), 0), v3(0, 0, 0), v3(0, 0, 0), 0);
    CHECK(run_for(w, 0.3));
    sd_body_state u = body(w, iu), l = body(w, il);
    printf("4 crossed logs at %.0f deg: F_u/mg - 1 = %.2e, |F_u,xy|/mg %.1e, |T_u| %.1e N m, |v_u| %.2e, z - z_eq "
           "%.2e m, contacts %ld\n",
           cross_deg, u.force.z / (m * G) - 1.0, hypot(u.force.x, u.force.y) / (m * G), v3_norm(u.torque),
           v3_norm(u.vel), u.pos.z - z0, sd_world_contact_count(w));
    CHECK_REL(u.force.z, m * G, 0.005);
    /* the normal is the common perpendicular of the two horizontal axes: vertical */
    CHECK(hypot(u.force.x, u.force.y) < 1e-4 * m * G);
    CHECK(v3_norm(u.vel) < 1e-5);
    CHECK_NEAR(u.pos.z, z0, 1e-7);
    CHECK_REL(l.force.z, -m * G, 0.005);
    CHECK(sd_world_contact_count(w) == 1);
    sd_world_destroy(w);
}

/* ---- 5. torque-free spinning log ------------------------------------------------------------- */
static sd_vec3 rotate(sd_vec3 v, sd_vec3 k, double ang) /* Rodrigues, k unit */
{
    double c = cos(ang), s = sin(ang);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(k, v), s)), v3_scale(k, v3_dot(k, v) * (1.0 - c)));
}

static void test_free_spin(void)
{
    sd_world *w = make_world(v3(0, 0, 0), 1e-5, 0.404);
    double m = log_mass(), itr = log_itr(), iax = 0.5 * m * R_LOG * R_LOG;
    sd_vec3 a0 = v3_normalize(v3(0.3, -0.5, 0.8));
    sd_vec3 om0 = v3(40.0, 25.0, -10.0);
    om0 = v3_madd(om0, a0, 300.0 - v3_dot(om0, a0)); /* fast spin about the axis plus tumbling */
    int id = add_log(w, v3(0.1, 0.2, 0.3), a0, v3(0.01, 0.0, -0.02), om0, 0);
    sd_vec3 L0 = v3_madd(v3_scale(om0, itr), a0, (iax - itr) * v3_dot(om0, a0));
    double ke0 = sd_world_kinetic_energy(w);
    double ke_th = 0.5 * m * (0.01 * 0.01 + 0.02 * 0.02) + 0.5 * v3_dot(om0, L0);
    const long N = 100000;
    double ldev = 0.0, kdev = 0.0;
    for (int k = 0; k < 10; k++) {
        CHECK(sd_world_run(w, N / 10) == SD_OK);
        sd_body_state b = body(w, id);
        sd_vec3 L = v3_madd(v3_scale(b.omega, itr), b.axis, (iax - itr) * v3_dot(b.omega, b.axis));
        double d = v3_norm(v3_sub(L, L0)) / v3_norm(L0);
        if (d > ldev) ldev = d;
        double dk = fabs(sd_world_kinetic_energy(w) - ke0) / ke0;
        if (dk > kdev) kdev = dk;
    }
    sd_body_state b = body(w, id);
    double t = sd_world_time(w);
    double Ln = v3_norm(L0);
    sd_vec3 a_th = rotate(a0, v3_scale(L0, 1.0 / Ln), Ln / itr * t);
    double aerr = v3_norm(v3_sub(b.axis, a_th));
    /* the spin about the axis is constant: ω·a = (L·a)/I_ax */
    double spin_err = fabs(v3_dot(b.omega, b.axis) - v3_dot(om0, a0)) / fabs(v3_dot(om0, a0));
    double turns = Ln / itr * t / (2.0 * M_PI);
    printf("5 free spin: %ld steps, |dL|/|L| max %.2e, |dKE|/KE max %.2e (KE0 vs closed form %.1e), axis vs "
           "rotation about L (%.1f turns) %.2e, spin rel err %.2e, |x - x0 - v t| %.1e\n",
           N, ldev, kdev, fabs(ke0 - ke_th) / ke_th, turns, aerr, spin_err,
           v3_norm(v3_sub(b.pos, v3(0.1 + 0.01 * t, 0.2, 0.3 - 0.02 * t))));
    CHECK(ldev < 1e-9);
    CHECK(kdev < 1e-11);
    CHECK_REL(ke0, ke_th, 1e-14);
    CHECK(aerr < 1e-9);
    CHECK(spin_err < 1e-11);
    CHECK(turns > 5.0);
    sd_world_destroy(w);
}

/* ---- 6. impact on a fixed pipe --------------------------------------------------------------- */
/* Clipped linear spring–dashpot, mass m_e, stiffness k, dashpot c (contact ends at k x + c ẋ = 0) */
static void closed_form(double m_e, double k, double c, double *e, double *tc)
{
    double w0 = sqrt(k / m_e), g = c / (2.0 * m_e), w = sqrt(w0 * w0 - g * g);
    double t = (M_PI - atan(2.0 * g * w / (w * w - g * g))) / w;
    *tc = t;
    *e = exp(-g * t) * fabs(cos(w * t) - g / w * sin(w * t));
}

static void pipe_impact(double s, double tan_phi, double tol)
{
    const double dt = 1e-6, v0 = 0.2, rp = 0.009;
    sd_world *w = make_world(v3(0, 0, 0), dt, tan_phi);
    double m = log_mass(), itr = log_itr();
    /* the pipe: a fixed cylinder φ18 mm × 0.3 m along y */
    sd_cylinder_def p = sd_cylinder_def_default();
    p.axis = v3(0, 1, 0);
    p.radius = rp;
    p.length = 0.3;
    p.density = 7850.0;
    p.fixed = 1;
    CHECK(sd_world_add_cylinder(w, &p) >= 0);
    /* the log along x, centre at x = -s: the contact (top of the pipe, x = 0) is s from its centre */
    int id = add_log(w, v3(-s, 0, rp + R_LOG + 1e-5), v3(1, 0, 0), v3(0, 0, -v0), v3(0, 0, 0), 0);
    sd_world_set_rebuild_every_step(w, 1);
    long nonzero = 0;
    int touched = 0;
    sd_body_state b = body(w, id);
    for (long k = 0; k < 200000; k++) {
        CHECK(sd_world_step(w) == SD_OK);
        b = body(w, id);
        if (v3_norm2(b.force) > 0.0) {
            nonzero++;
            touched = 1;
        } else if (touched)
            break;
    }
    /* normal velocity of the log's point at the contact (x = 0 on its lower generator) */
    sd_vec3 rc = v3_sub(v3(0, 0, rp), b.pos);
    sd_vec3 vc = v3_add(b.vel, v3_cross(b.omega, rc));
    double e = vc.z / v0, tc = nonzero * dt;
    double m_e = 1.0 / (1.0 / m + s * s / itr);
    double c = 2.0 * 0.2 * sqrt(m * KN); /* the engine's dashpot uses the body mass (SPEC §3) */
    double e_th, tc_th;
    closed_form(m_e, KN, c, &e_th, &tc_th);
    printf("6 pipe impact s = %.0f mm (tan_phi %.3f): m_e/m %.4f, h_eff %.3f, e = %.5f (closed form %.5f, err %.2e), "
           "t_c = %.4e s (closed form %.4e, err %.2e), centre e %.4f, w_y %.3f rad/s, |vc_x| %.1e\n",
           s * 1e3, tan_phi, m_e / m, c / (2.0 * sqrt(m_e * KN)), e, e_th, fabs(e - e_th) / e_th, tc, tc_th,
           fabs(tc - tc_th) / tc_th, b.vel.z / v0, b.omega.y, fabs(vc.x));
    CHECK(touched);
    CHECK_REL(e, e_th, tol);
    CHECK_REL(tc, tc_th, tol);
    sd_world_destroy(w);
}

/* ---- 7. the logs moved in batches --------------------------------------------------------- */
/* what the moves leave: the state, and the bounds the moves report (the near list's drift, the
 * front, the rebuilds their drift asked for), which the state alone may not show */
typedef struct {
    uint64_t hash;
    double near_drift, front;
    long rebuilds;
} heap_end;

static heap_end heap_run(int batch, long steps, int lanes, int logs_only)
{
    sd_world *w = make_world(v3(0, 0, -G), 1e-5, 0.404);
    sd_world_switch(w, SD_SW_CYL_BATCH, batch);
    sd_world_switch(w, SD_SW_MOVE_LANES, lanes);
    add_floor(w, -0.3, 0.3, -0.3, 0.3, 6, 6);
    int n = 0;
    for (int k = 0; k < 90; k++) {
        const double x = -0.2 + 0.1 * (k % 5), y = -0.2 + 0.1 * (k / 5 % 5), z = 0.02 + 0.03 * (k / 25);
        /* a sphere now and then, between the logs in the store; or mostly spheres, in runs of
         * eight between two logs (sizes and densities apart, so that each has its own 1/m and
         * 1/I) */
        if (logs_only ? k % 9 == 4 : k % 9 != 4) {
            if (logs_only) {
                add_ball(w, v3(x, y, z), 0.008, 2650.0);
                continue;
            }
            /* thrown at each other, spinning, so that they touch within the run and each
             * one's force and torque count */
            sd_sphere_def sp = sd_sphere_def_default();
            sp.pos = v3(x, y, z);
            sp.radius = 0.006 + 0.0003 * (k % 7);
            sp.density = 2650.0 - 40.0 * (k % 5);
            sp.vel = v3(3.0 * sin(1.7 * k), 3.0 * cos(1.1 * k), -1.0 + 0.5 * sin(0.9 * k));
            sp.omega = v3(40.0 * sin(0.3 * k), 30.0 * cos(0.7 * k), 20.0 * sin(1.9 * k));
            CHECK(sd_world_add_sphere(w, &sp) >= 0);
            continue;
        }
        const double t = 0.7 * k;
        sd_vec3 om;
        if (k % 7 == 0)
            om = v3(0, 0, 0); /* still: a zero angle, the series */
        else if (k % 7 == 1)
            om = v3(1e-8, -2e-8, 0.5e-8); /* below 1e-12 rad a step: the series too */
        else
            om = v3(20.0 * sin(t), 15.0 * cos(1.3 * t), 30.0 * sin(0.4 * t) + 5.0);
        add_log(w, v3(x, y, z + 0.01 * sin(t)), v3_normalize(v3(cos(t), sin(t), 0.3 * sin(2.1 * t))),
                v3(0.1 * sin(t), 0.0, -0.2), om, 0);
        n++;
    }
    CHECK(n == (logs_only ? 80 : 10));
    CHECK(sd_world_run(w, steps) == SD_OK);
    const heap_end e = {sd_world_state_hash(w), w->near_drift, w->front, w->timers.rebuilds};
    sd_world_destroy(w);
    return e;
}

/* two runs of heap_run that must end alike: the same state, the same near drift and front to
 * the bit, the same rebuilds (and more than one) */
static void check_same_end(const heap_end *x, const heap_end *y)
{
    CHECK(x->hash == y->hash);
    CHECK(memcmp(&x->near_drift, &y->near_drift, sizeof(double)) == 0);
    CHECK(memcmp(&x->front, &y->front, sizeof(double)) == 0);
    CHECK(x->rebuilds == y->rebuilds);
    CHECK(x->rebuilds > 1);
}

static void test_batched_moves(void)
{
    const heap_end one = heap_run(0, 4000, 1, 1), bat = heap_run(1, 4000, 1, 1);
    printf("7 logs moved in batches: state hash %016llx, near drift %.17g m, front %.17g m, %ld rebuilds; one by "
           "one %016llx, %.17g, %.17g, %ld\n",
           (unsigned long long)bat.hash, bat.near_drift, bat.front, bat.rebuilds, (unsigned long long)one.hash,
           one.near_drift, one.front, one.rebuilds);
    check_same_end(&one, &bat);
}

/* ---- 8. the spheres moved four at a time in lanes (integrate.c move_block256) -------------- */
/* against one by one (move_one): the same state, near drift, front and rebuilds, on a heap of
 * spheres in runs of eight between logs (groups of four, and the remainders around the logs
 * one by one) */
static void test_sphere_lanes(void)
{
    const long g0 = sd_integrate_lanes_count();
    const heap_end on = heap_run(1, 4000, 1, 0);
    const long g1 = sd_integrate_lanes_count();
    const heap_end off = heap_run(1, 4000, 0, 0);
    const long g2 = sd_integrate_lanes_count();
    printf("8 spheres moved in lanes (%ld groups of four): state hash %016llx, near drift %.17g m, front %.17g m, %ld "
           "rebuilds; one by one %016llx, %.17g, %.17g, %ld\n",
           g1 - g0, (unsigned long long)on.hash, on.near_drift, on.front, on.rebuilds, (unsigned long long)off.hash,
           off.near_drift, off.front, off.rebuilds);
    check_same_end(&on, &off);
    CHECK(g2 == g1); /* none with the lanes off */
    if (sd_cpu_simd_level() >= SD_SIMD_AVX2) CHECK(g1 - g0 >= 4000L * 10); /* 80 spheres: at least 10 groups a step */
}

int main(void)
{
    test_lying();
    test_standing();
    run_slope(1, 0.404);
    run_slope(0, 0.2);
    test_sphere_on_end();
    test_crossed(90.0);
    test_crossed(50.0);
    test_free_spin();
    pipe_impact(0.0, 0.404, 0.01);
    pipe_impact(0.03, 0.404, 0.03);
    pipe_impact(0.03, 0.0, 0.01);
    test_batched_moves();
    test_sphere_lanes();
    return check_report("test_logs");
}
