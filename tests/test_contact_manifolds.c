/* Contact manifolds against closed forms (docs/geometry.md "Shares", docs/model.md §4):
 *  1. flat faces carry moments: a disc (a short log) lying on its face on an incline of many
 *     triangles stays at rest without turning below the friction angle and slides at
 *     g(sinθ − tanφ cosθ) without spinning above it; a sphere resting off the axis of a
 *     standing log's top face turns nothing; a log released tilted on its end settles upright
 *     below the tipping angle atan(d/L) and topples above it;
 *  2. log jams without stiffness jumps: a log (φ10 × 100 mm) across a fixed pipe (φ18) and a
 *     fixed log of its size, the crossing angle swept 0–90° (by 0.001° where the points of the
 *     line contact come and go): the total normal stiffness, the total normal damping and the
 *     force at the depth m g / K_n are those of one contact, continuous in the angle; after
 *     0.15 s at rest the normal force is the weight and the overlap m g / K_n at every angle
 *     but 0-0.0031 deg on the log, where the one crossing point rocks (test_crossing_sweep).
 * Paper values (K_n = 1e4 N/m, K_s = 4e3 N/m, h = 0.2, Δt = 1e-5 s). Deterministic. */
#include <string.h>

#include "check.h"
#include "sabodem.h"
#include "core/vmath.h"

static const double G = 9.81;
static const double KN = 1.0e4;

static sd_world *make_world(sd_vec3 g, double tan_phi)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = g;
    def.dt = 1e-5;
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

static int add_log(sd_world *w, sd_vec3 pos, sd_vec3 axis, double r, double len, double rho, int fixed)
{
    sd_cylinder_def c = sd_cylinder_def_default();
    c.pos = pos;
    c.axis = axis;
    c.radius = r;
    c.length = len;
    c.density = rho;
    c.fixed = fixed;
    int id = sd_world_add_cylinder(w, &c);
    CHECK(id >= 0);
    return id;
}

static int add_ball(sd_world *w, sd_vec3 pos, sd_vec3 vel, sd_vec3 omega, double r, double rho)
{
    sd_sphere_def s = sd_sphere_def_default();
    s.pos = pos;
    s.vel = vel;
    s.omega = omega;
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

static int run_for(sd_world *w, double t) { return sd_world_run(w, lround(t / 1e-5)) == SD_OK; }

/* ---- 1. flat faces ------------------------------------------------------------------------ */

/* A disc r 20 mm, 10 mm thick (wood, 800 kg/m^3) on its face on a θ incline (gravity tilted:
 * the floor stays z = 0, downslope is +x), floor of 12 × 4 squares of 25 mm. */
static void disc_on_incline(double theta_deg, double tan_phi)
{
    const double r = 0.02, len = 0.01, rho = 800.0, th = theta_deg * M_PI / 180.0;
    const double m = rho * M_PI * r * r * len;
    sd_world *w = make_world(v3(G * sin(th), 0, -G * cos(th)), tan_phi);
    add_floor(w, -0.05, 0.25, -0.05, 0.05, 12, 4);
    /* resting (centre at len/2 - m g cosθ / K_n), off the seams and vertices */
    const double z0 = 0.5 * len - m * G * cos(th) / KN;
    const int id = add_log(w, v3(0.0031, 0.0043, z0), v3(0, 0, 1), r, len, rho, 0);
    const int sliding = tan_phi < tan(th);
    double wmax = 0.0, tilt_max = 0.0;
    double t_s[64], x_s[64];
    int ns = 0;
    for (int k = 0; k < 40; k++) {
        CHECK(run_for(w, 0.005));
        sd_body_state b = body(w, id);
        if (k >= 4) {
            if (v3_norm(b.omega) > wmax) wmax = v3_norm(b.omega);
            if (hypot(b.axis.x, b.axis.y) > tilt_max) tilt_max = hypot(b.axis.x, b.axis.y);
            t_s[ns] = sd_world_time(w);
            x_s[ns++] = b.pos.x;
        }
    }
    sd_body_state b = body(w, id);
    /* a from a least-squares parabola x = c0 + c1 t + a/2 t^2 */
    double S[5] = {0}, R[3] = {0};
    for (int i = 0; i < ns; i++) {
        double p = 1.0;
        for (int k = 0; k < 5; k++) {
            S[k] += p;
            if (k < 3) R[k] += p * x_s[i];
            p *= t_s[i];
        }
    }
    double A[3][4] = {{S[0], S[1], S[2], R[0]}, {S[1], S[2], S[3], R[1]}, {S[2], S[3], S[4], R[2]}}, c[3];
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) {
            double f = A[j][i] / A[i][i];
            for (int k = i; k < 4; k++)
                A[j][k] -= f * A[i][k];
        }
    for (int i = 2; i >= 0; i--) {
        double s = A[i][3];
        for (int k = i + 1; k < 3; k++)
            s -= A[i][k] * c[k];
        c[i] = s / A[i][i];
    }
    const double a = 2.0 * c[2], a_th = sliding ? G * (sin(th) - tan_phi * cos(th)) : 0.0;
    printf("1 disc on a %.0f deg incline (tan_phi %.3f): a = %.5f m/s^2 (closed form %.5f), |v| %.2e m/s, "
           "max |w| %.2e rad/s, max tilt %.2e, contacts %ld\n",
           theta_deg, tan_phi, a, a_th, v3_norm(b.vel), wmax, tilt_max, sd_world_contact_count(w));
    if (sliding) {
        CHECK_REL(a, a_th, 0.005);
        CHECK(wmax < 1e-3); /* (1 mm/s at the rim) */
    } else {
        CHECK(v3_norm(b.vel) < 1e-5);
        CHECK(fabs(b.pos.x - 0.0031) < 1e-5);
        CHECK(wmax < 1e-3);
    }
    CHECK(tilt_max < 1e-3);
    sd_world_destroy(w);
}

/* A sphere (r 5 mm, 2650 kg/m^3) resting 15 mm off the axis of a standing log's top face (the
 * log r 20 mm, 100 mm long, free on a floor of triangles): nothing turns. */
static void sphere_off_axis(void)
{
    const double r = 0.02, len = 0.1, rho = 800.0, rs = 0.005, rhos = 2650.0, off = 0.015;
    const double m = rho * M_PI * r * r * len, ms = rhos * 4.0 / 3.0 * M_PI * rs * rs * rs;
    sd_world *w = make_world(v3(0, 0, -G), 0.404);
    add_floor(w, -0.1, 0.1, -0.1, 0.1, 4, 4);
    const double zl = 0.5 * len - (m + ms) * G / KN;
    const int il = add_log(w, v3(0.011, 0.007, zl), v3(0, 0, 1), r, len, rho, 0);
    const int is = add_ball(w, v3(0.011 + off, 0.007, zl + 0.5 * len + rs - ms * G / KN + 1e-6), v3(0, 0, 0),
                            v3(0, 0, 0), rs, rhos);
    double wmax = 0.0;
    for (int k = 0; k < 150; k++) {
        CHECK(run_for(w, 0.01));
        if (k >= 140) {
            const double wl = v3_norm(body(w, il).omega);
            if (wl > wmax) wmax = wl;
        }
    }
    sd_body_state l = body(w, il), s = body(w, is);
    /* the floor's moment m_s g off balances through the face's rim points: tilt ~ m_s g off /
     * (K_n r^2 / 2) (four points of K_n / 4 each, two of them r off the tilt axis) */
    const double tilt_th = ms * G * off / (0.5 * KN * r * r);
    printf("1 sphere %.0f mm off the axis of a standing log: log tilt %.2e (rigid face estimate %.2e), max |w_log| over "
           "1.4-1.5 s %.2e rad/s, |v_s| %.2e, F_s,z/m_s g - 1 = %.2e\n",
           off * 1e3, hypot(l.axis.x, l.axis.y), tilt_th, wmax, v3_norm(s.vel), s.force.z / (ms * G) - 1.0);
    CHECK(wmax < 1e-4);
    /* the face tilted by the load is an incline of that slope, down which the sphere rolls
     * at (5/7) g tilt (no rolling resistance in the law), never faster */
    const double tilt = hypot(l.axis.x, l.axis.y);
    CHECK(v3_norm(s.vel) < 1.2 * 5.0 / 7.0 * G * tilt * sd_world_time(w));
    CHECK(tilt < 3.0 * tilt_th);
    CHECK_REL(s.force.z, ms * G, 0.005);
    sd_world_destroy(w);
}

/* A log d 40 mm × L 80 mm (tipping angle atan(d/L) = 26.57 deg) released from rest standing on
 * its end, tilted by tilt_deg about y, the lower rim point on the floor. Returns the final
 * angle of its axis from the vertical, deg. */
static double tilted_release(double tilt_deg, double t_end)
{
    const double r = 0.02, len = 0.08, rho = 800.0, hl = 0.5 * len, ps = tilt_deg * M_PI / 180.0;
    sd_world *w = make_world(v3(0, 0, -G), 0.404);
    add_floor(w, -0.2, 0.2, -0.2, 0.2, 4, 4);
    const int id = add_log(w, v3(0.013, 0.021, hl * cos(ps) + r * sin(ps) + 1e-5), v3(sin(ps), 0, cos(ps)), r,
                           len, rho, 0);
    CHECK(run_for(w, t_end));
    sd_body_state b = body(w, id);
    const double ang = acos(fabs(b.axis.z)) * 180.0 / M_PI;
    printf("1 log d/L = 0.5 released %.1f deg from vertical (tipping angle %.2f deg): after %.1f s axis %.3g deg from "
           "vertical, |v| %.2e, |w| %.2e, contacts %ld\n",
           tilt_deg, atan(2.0 * r / len) * 180.0 / M_PI, t_end, ang, v3_norm(b.vel), v3_norm(b.omega),
           sd_world_contact_count(w));
    sd_world_destroy(w);
    return ang;
}

static void test_flat_faces(void)
{
    disc_on_incline(15.0, 0.404); /* below the friction angle (22 deg) */
    disc_on_incline(30.0, 0.404); /* above */
    sphere_off_axis();
    const double crit = atan(0.5) * 180.0 / M_PI;
    CHECK(tilted_release(5.0, 1.0) < 0.05);
    CHECK(tilted_release(crit - 2.0, 1.5) < 0.05);
    CHECK(tilted_release(crit + 2.0, 1.0) > 80.0);
}


/* ---- 2. a log resting across a fixed pipe or log, the crossing angle swept ------------------ */

static const double LOG_R = 0.005, LOG_LEN = 0.1, LOG_RHO = 800.0;

static double log_mass(void) { return LOG_RHO * M_PI * LOG_R * LOG_R * LOG_LEN; }

/* The log released at rest just touching, centred over the fixed cylinder (radius rb, length
 * lb) and crossing it at ang deg; after 0.15 s the depth of its axis below r + rb (the settled
 * overlap of a line contact) over m g / K_n, the vertical contact force on it over m g, and
 * its contact points. */
static void rest_across(double rb, double lb, double ang_deg, double *ov_rel, double *f_rel, long *pts)
{
    const double a = ang_deg * M_PI / 180.0, m = log_mass();
    sd_world *w = make_world(v3(0, 0, -G), 0.404);
    add_log(w, v3(0, 0, 0), v3(1, 0, 0), rb, lb, 7850.0, 1);
    const int id = add_log(w, v3(0, 0, LOG_R + rb - m * G / KN), v3(cos(a), sin(a), 0), LOG_R, LOG_LEN, LOG_RHO, 0);
    CHECK(run_for(w, 0.15));
    sd_body_state b = body(w, id);
    *ov_rel = (LOG_R + rb - b.pos.z) / (m * G / KN);
    *f_rel = b.force.z / (m * G);
    *pts = sd_world_contact_count(w);
    sd_world_destroy(w);
}

/* One step of the log placed centred across the fixed cylinder at ang deg, its axis ov below
 * r + rb, moving down at u: the vertical contact force at those positions (the force of the
 * step, computed before the move), and the contact points. */
static double across_once(double rb, double lb, double ang_deg, double ov, double u, double tan_phi, long *pts)
{
    const double a = ang_deg * M_PI / 180.0;
    sd_world *w = make_world(v3(0, 0, -G), tan_phi);
    add_log(w, v3(0, 0, 0), v3(1, 0, 0), rb, lb, 7850.0, 1);
    sd_cylinder_def c = sd_cylinder_def_default();
    c.pos = v3(0, 0, LOG_R + rb - ov);
    c.axis = v3(cos(a), sin(a), 0);
    c.vel = v3(0, 0, -u);
    c.radius = LOG_R;
    c.length = LOG_LEN;
    c.density = LOG_RHO;
    const int id = sd_world_add_cylinder(w, &c);
    CHECK(id >= 0);
    CHECK(sd_world_step(w) == SD_OK);
    const double fz = body(w, id).force.z;
    if (pts) *pts = sd_world_contact_count(w);
    sd_world_destroy(w);
    return fz;
}

typedef struct {
    double lo, hi, step; /* range; largest change between angles 0.001 deg apart */
    double at_lo, at_hi, at_step;
    double prev_ang, prev;
    int n;
} sweep_stat;

static void sweep_add(sweep_stat *s, double ang, double x)
{
    if (s->n == 0 || x < s->lo) s->lo = x, s->at_lo = ang;
    if (s->n == 0 || x > s->hi) s->hi = x, s->at_hi = ang;
    if (s->n > 0 && ang - s->prev_ang < 0.0015 && fabs(x - s->prev) > s->step)
        s->step = fabs(x - s->prev), s->at_step = ang;
    s->prev_ang = ang;
    s->prev = x;
    s->n++;
}

static void sweep_print(const char *what, const char *on, const sweep_stat *s)
{
    printf("2 log on a %s, %d angles 0-90 deg: %s %.7g (at %.3f deg) to %.7g (at %.3f deg), largest step between "
           "angles 0.001 deg apart %.2e (at %.3f deg)\n",
           on, s->n, what, s->lo, s->at_lo, s->hi, s->at_hi, s->step, s->at_step);
}

/* Stiffness, damping and the static force of the line contact at every angle (0-0.6 deg by
 * 0.001 deg, where the points of the line contacts come and go; to 2 deg by 0.01 deg, then to
 * 90 deg by 0.5 deg), from single steps at the settled depth m g / K_n: one step per
 * configuration, no settling. */
static void test_crossing_springs(void)
{
    static double ang[1024];
    int na = 0;
    for (int i = 0; i <= 600; i++)
        ang[na++] = 0.001 * i;
    for (int i = 1; i <= 140; i++)
        ang[na++] = 0.6 + 0.01 * i;
    for (int i = 1; i <= 176; i++)
        ang[na++] = 2.0 + 0.5 * i;
    const double m = log_mass(), d0 = m * G / KN, h = 1e-8, u = 1e-3;
    const double c_n = 2.0 * sd_world_def_default().contact.damping * sqrt(m * KN);
    for (int pipe = 1; pipe >= 0; pipe--) {
        const double rb = pipe ? 0.009 : 0.005, lb = pipe ? 0.5 : 0.1;
        const char *on = pipe ? "pipe" : "log";
        sweep_stat sk = {0}, sc = {0}, sf = {0};
        long pts_prev = -1;
        for (int i = 0; i < na; i++) {
            long pts;
            const double f = across_once(rb, lb, ang[i], d0, 0.0, 0.404, &pts) / (m * G);
            /* the total normal stiffness: the central difference of the vertical force over the
             * depth, over K_n */
            const double k = (across_once(rb, lb, ang[i], d0 + h, 0.0, 0.404, NULL) -
                              across_once(rb, lb, ang[i], d0 - h, 0.0, 0.404, NULL)) /
                             (2.0 * h * KN);
            /* the total normal damping: the force moving down at u, frictionless (no tangential
             * spring or dashpot), less the force at rest (in the first step of a contact at rest
             * friction adds nothing), over c_n u */
            const double c = (across_once(rb, lb, ang[i], d0, u, 0.0, NULL) - f * m * G) / (c_n * u);
            sweep_add(&sk, ang[i], k);
            sweep_add(&sc, ang[i], c);
            sweep_add(&sf, ang[i], f);
            if (pts != pts_prev)
                printf("2 log on a %s from %.3f deg, its axis m g / K_n deep: %ld contact points (stiffness / K_n "
                       "%.7f, damping / c_n %.7f, F_n / m g %.7f)\n",
                       on, ang[i], pts, k, c, f);
            pts_prev = pts;
        }
        sweep_print("stiffness / K_n", on, &sk);
        sweep_print("damping / c_n", on, &sc);
        sweep_print("F_n / m g at m g / K_n deep", on, &sf);
        /* Each is 1 where the normals are vertical (parallel, one crossing point); the end
         * points of a log on the pipe lean out by up to ~1.4 deg (their lateral offset over
         * r + r_pipe) and push less than straight up: measured down to 0.99977 (stiffness),
         * 0.99976 (damping), 0.99993 (force), each continuous (steps <= 7.3e-6 per 0.001 deg).
         * With the springs weighted by the shares alone, the stiffness fell to -0.95 K_n where
         * the end points leave (0.475 deg: a point joining at zero depth took its share from
         * the deep one) and the force at m g / K_n to 0.73 m g. */
        CHECK(sk.lo > 0.9997 && sk.hi < 1.0 + 1e-6 && sk.step < 2e-5);
        CHECK(sc.lo > 0.9997 && sc.hi < 1.0 + 1e-6 && sc.step < 2e-5);
        CHECK(sf.lo > 0.9999 && sf.hi < 1.0 + 1e-12 && sf.step < 2e-6);
    }
}

/* The settled overlap and the normal force after 0.15 s at rest, the angle swept: on the pipe
 * 0.45-0.50 deg by 0.001 deg around the angle where its end points leave (0.477 deg), on the
 * log 0-0.006 deg by 0.0005 deg (its end points leave at once: the crossing point alone
 * carries the log beyond 0 deg).
 *
 * Measured on the log, the crossing point alone: between 0 and theta_c = dt sqrt(m g h / (4
 * I_tr)) = 0.0031 deg (h = r + r_log, the axes' distance) the log does not come to rest. Its
 * one contact point lies where the axes cross, and a pitch phi of the log moves it along the
 * axis by h phi / theta^2: a rocking stiffness m g h / theta^2 whose frequency passes 2 / dt
 * (the leapfrog's limit) below theta_c, so the pitch keeps a period-2 oscillation, the force
 * within 4 % of the weight, the overlap 0.9896-0.9923 (and the yaw grows out of the band, by 1.57
 * in 0.15 s). Parallel (2 points) and from theta_c on, the log rests exactly. */
static void test_crossing_sweep(void)
{
    static const double coarse[] = {0.0,  0.005, 0.01, 0.02, 0.05, 0.1, 0.15, 0.2,  0.25, 0.3, 0.35, 0.4, 0.45,
                                    0.5,  0.6,   0.75, 1.0,  1.25, 1.5, 1.75, 2.0, 2.5,  3.0, 5.0, 10., 20.,
                                    45., 90.};
    const double m = log_mass(), i_tr = m * (3.0 * LOG_R * LOG_R + LOG_LEN * LOG_LEN) / 12.0;
    const double theta_c = 1e-5 * sqrt(m * G * 2.0 * LOG_R / (4.0 * i_tr)) * 180.0 / M_PI;
    for (int pipe = 1; pipe >= 0; pipe--) {
        const char *on = pipe ? "pipe" : "log";
        static double ang[128];
        int na = 0;
        for (int i = 0; i < (int)(sizeof(coarse) / sizeof(coarse[0])); i++) {
            ang[na++] = coarse[i];
            if (pipe && coarse[i] == 0.45)
                for (int k = 1; k < 50; k++)
                    ang[na++] = 0.45 + 0.001 * k;
            if (!pipe && coarse[i] == 0.0)
                for (int k = 1; k <= 12; k++)
                    ang[na++] = 0.0005 * k;
        }
        sweep_stat so = {0}, sf = {0}, bo = {0}, bf = {0};
        long pts_prev = -1;
        for (int i = 0; i < na; i++) {
            double ov, f;
            long pts;
            rest_across(pipe ? 0.009 : 0.005, pipe ? 0.5 : 0.1, ang[i], &ov, &f, &pts);
            if (pts != pts_prev || i % 10 == 0 || (!pipe && ang[i] < 0.01))
                printf("2 log on a %s at %6.4f deg, after 0.15 s: overlap / (m g / K_n) %.7f, F_n / m g - 1 %+.1e, %ld "
                       "contact points\n",
                       on, ang[i], ov, f - 1.0, pts);
            pts_prev = pts;
            /* (on the log, the band 0 < theta <= 1.05 theta_c apart) */
            const int band = !pipe && ang[i] > 0.0 && ang[i] <= 1.05 * theta_c;
            sweep_add(band ? &bo : &so, ang[i], ov);
            sweep_add(band ? &bf : &sf, ang[i], f - 1.0);
        }
        if (!pipe) printf("2 log on a log: theta_c = %.5f deg\n", theta_c);
        sweep_print("settled overlap / (m g / K_n)", on, &so);
        sweep_print("F_n / m g - 1 after 0.15 s", on, &sf);
        /* the weight, and one contact's overlap at every angle: measured 0.99993-1.00000 on the
         * pipe, steps <= 5.9e-7 per 0.001 deg (the springs weighted by the shares alone:
         * 1.00-1.37, a step of 0.33 at 0.477 deg); the end points lean (above), and their
         * friction holds a little of the weight */
        CHECK(sf.lo > -1e-8 && sf.hi < 1e-8);
        CHECK(so.lo > 0.9999 && so.hi < 1.0 + 1e-6 && so.step < 5e-6);
        if (!pipe) {
            sweep_print("in the band, settled overlap / (m g / K_n)", on, &bo);
            sweep_print("in the band, F_n / m g - 1 after 0.15 s", on, &bf);
            CHECK(fabs(theta_c - 0.0031) < 5e-5);
            CHECK(bo.n == 6 && bo.lo > 0.989 && bo.hi < 0.994 && bf.lo > -0.04 && bf.hi < 0.04);
        }
    }
}

int main(void)
{
    test_flat_faces();
    test_crossing_springs();
    test_crossing_sweep();
    return check_report("test_contact_manifolds");
}
