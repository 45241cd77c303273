/* Pipe loads in design terms (src/pipe_loads.c, docs/loads.md), against closed forms:
 * - the resultant's position along a pipe from its force and torque: a force at a known point
 *   (with a radial offset, as a contact on the pipe's surface has) gives that point;
 * - the bending moment of a point load: simple supports P a b / L, fixed ends P a b^2 / L^2
 *   (the larger end moment), symmetric in a <-> b, zero at the supports;
 * - through the engine: a sphere settled on a fixed horizontal pipe 30 mm off its centre
 *   loads it with its weight, and the position read back from the pipe's force and torque is
 *   the sphere's, so the engine's torque is about the pipe's centre as the formula assumes;
 * - impact events (docs/loads.md "Impact events"), gravity off, K_n = 1e4 N/m, h = 0.2: a 20 mm
 *   sphere (SG 1.9) striking a fixed φ18 mm pipe head-on at 0.5 m/s makes one event whose
 *   impulse is m (1 + e) v and duration the contact time t_c of the clipped spring–dashpot
 *   (test_bounce's closed form), whose peak is the closed-form peak of K δ + c δ' and whose
 *   energy, the work of the pipe's force on the sphere while it presses in, is ½ m v² (and so
 *   for a log falling across the pipe at its middle); two
 *   spheres striking 18 ms apart make two such events; under gravity (h = 0.7, the threshold
 *   four times the weight) a sphere dropped 2 mm onto the pipe makes one event and then rests
 *   with its weight on the pipe, below the threshold, making no other. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* the clipped linear spring–dashpot against a fixed wall (Schwager & Pöschel 2007, as
 * test_bounce): contact time and restitution; its force K δ + c δ' at its peak */
static const double KN = 1.0e4, H = 0.2;

static void clipped(double m, double *tc, double *e, double *peak)
{
    const double w0 = sqrt(KN / m), g = H * w0, w = sqrt(w0 * w0 - g * g);
    *tc = (M_PI - atan(2.0 * g * w / (w * w - g * g))) / w;
    *e = exp(-g * *tc) * fabs(cos(w * *tc) - g / w * sin(w * *tc));
    /* δ = (v/w) e^(-g t) sin(w t), F = K δ + 2 g m δ' = (m v / w) e^(-g t) ((w0² - 2g²) sin + 2 g w cos):
     * dF/dt = 0 at tan(w t) = w (w0² - 4 g²) / (g (3 w0² - 4 g²)); peak per unit speed */
    const double ts = atan(w * (w0 * w0 - 4 * g * g) / (g * (3 * w0 * w0 - 4 * g * g))) / w;
    *peak = m / w * exp(-g * ts) * ((w0 * w0 - 2 * g * g) * sin(w * ts) + 2 * g * w * cos(w * ts));
}

/* a fixed horizontal pipe along x at the origin, R = 9 mm, 0.12 m long, and the run's loads */
static sd_world *pipe_world(sd_vec3 g, double h, int *pipe)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = g;
    def.dt = 1e-5;
    def.contact.k_n = KN;
    def.contact.damping = h;
    sd_world *w;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    sd_cylinder_def c = sd_cylinder_def_default();
    c.pos = v3(0, 0, 0);
    c.axis = v3(1, 0, 0);
    c.radius = 0.009;
    c.length = 0.12;
    c.density = 7850;
    c.fixed = 1;
    *pipe = sd_world_add_cylinder(w, &c);
    return w;
}

static int add_ball(sd_world *w, double x, double gap, double v)
{
    sd_sphere_def sp = sd_sphere_def_default();
    sp.pos = v3(x, 0, 0.009 + 0.01 + gap);
    sp.vel = v3(0, 0, -v);
    sp.radius = 0.01;
    sp.density = 1900;
    return sd_world_add_sphere(w, &sp);
}

static void start_loads(sd_pipe_loads *L, sd_world *w, int pipe, double threshold, const char *events)
{
    sd_scenario s;
    sd_scenario_default(&s);
    s.event_threshold = threshold;
    sd_build_info info;
    memset(&info, 0, sizeof info);
    info.n_pipes = 1;
    info.pipe_gid[0] = pipe;
    CHECK(sd_pipe_loads_start(L, &s, &info, w, NULL, events) == 0);
}

static void one_impact(void)
{
    int pipe;
    sd_world *w = pipe_world(v3(0, 0, 0), H, &pipe);
    const double v = 0.5, dt = 1e-5;
    const int ball = add_ball(w, 0.02, 1e-4, v);
    sd_pipe_loads L;
    char path[] = "/tmp/sd_events_XXXXXX";
    const int fd = mkstemp(path);
    CHECK(fd >= 0);
    close(fd);
    start_loads(&L, w, pipe, 1e-3, path);
    for (int i = 0; i < 2000; i++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_pipe_loads_step(&L, w, sd_world_time(w), dt);
    }
    sd_pipe_loads_finish(&L, 0);
    CHECK(sd_pipe_loads_close(&L) == 0);
    sd_body_state b;
    sd_world_body(w, ball, &b);
    const double m = b.mass;
    double tc, e, peak;
    clipped(m, &tc, &e, &peak);
    const sd_pipe_load *p = &L.p[0];
    CHECK(p->n_events == 1 && !p->in_event);
    const sd_pipe_event *ev = &p->ev;
    /* the sphere leaves at e v (e = 0.5717; the leapfrog's is 0.3 % low at Δt = 1e-5 s with 250
     * steps a contact, docs/physics.md §3): the pipe took its momentum, m (1 + e) v, and exactly
     * the momentum the sphere lost, m (v_in + v_out) */
    CHECK_REL(b.vel.z, e * v, 5e-3);
    CHECK_REL(ev->impulse, m * (1 + e) * v, 3e-3);
    CHECK_REL(-ev->impulse_vec.z, m * (v + b.vel.z), 1e-12);
    CHECK_REL(ev->impulse, m * (v + b.vel.z), 1e-12);
    CHECK_NEAR(ev->impulse_vec.x, 0.0, 1e-12);
    CHECK_NEAR(ev->impulse_vec.y, 0.0, 1e-12);
    /* the event: the steps with force, t_c = 2.50 ms to within two steps */
    CHECK_NEAR(ev->duration, tc, 2 * dt);
    /* the peak: the closed form's to the same 0.3 % */
    CHECK_REL(ev->peak, peak * v, 3e-3);
    /* what the sphere brought in: ½ m v². With the velocity at the middle of each step the sum
     * F·u Δt is m Δ(v²)/2 step by step, so it telescopes to ½ m v_in² less ½ m v² of the one
     * step where v turns: at most ½ m (F_peak Δt / m)², (F_peak Δt / (m v))² = 8.5e-5 of it */
    CHECK_REL(ev->energy, 0.5 * m * v * v, pow(ev->peak * dt / (m * v), 2));
    CHECK(ev->t0 > 0.0 && ev->t0 < 1e-3 && ev->t_peak > ev->t0 && ev->t_peak < ev->t0 + tc);
    CHECK(p->ev_peak == ev->peak && p->ev_impulse == ev->impulse && p->ev_energy == ev->energy);
    /* events.csv: the header and the one row, ended by the force falling */
    FILE *f = fopen(path, "r");
    char line[512];
    int rows = 0;
    double peak_row = 0.0;
    char end[32] = "";
    CHECK(f && fgets(line, sizeof line, f) && !strncmp(line, "pipe,kind,axis_m,t_start_s,duration_s,peak_N", 44));
    while (f && fgets(line, sizeof line, f)) {
        double t0, dur, tp, imp, ix, iy, iz, en, base, ax;
        int k;
        char kind[16];
        if (sscanf(line, "%d,%15[^,],%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%31s", &k, kind, &ax, &t0, &dur,
                   &peak_row, &tp, &imp, &ix, &iy, &iz, &en, &base, end) == 14)
            rows++;
    }
    if (f) fclose(f);
    unlink(path);
    CHECK(rows == 1 && !strcmp(end, "fell"));
    CHECK_REL(peak_row, ev->peak, 1e-6);
    printf("one impact: m = %.6g kg, t_c %.6g s (event %.6g), e %.6g, impulse %.6g (m(1+e)v %.6g), peak %.6g (closed "
           "form %.6g), energy %.9g (½mv² %.9g)\n",
           m, tc, ev->duration, e, ev->impulse, m * (1 + e) * v, ev->peak, peak * v, ev->energy, 0.5 * m * v * v);
    sd_pipe_loads_free(&L);
    sd_world_destroy(w);
}

/* a log (φ10 × 100 mm, SG 0.8) across the pipe, falling onto it at its middle: the cylinder
 * kernels' contact, through its centre (no spin): impulse m (v_in + v_out), energy ½ m v² */
static void log_impact(void)
{
    int pipe;
    sd_world *w = pipe_world(v3(0, 0, 0), H, &pipe);
    const double v = 0.5, dt = 1e-5;
    sd_cylinder_def c = sd_cylinder_def_default();
    c.pos = v3(0.01, 0, 0.009 + 0.005 + 1e-4);
    c.axis = v3(0, 1, 0);
    c.vel = v3(0, 0, -v);
    c.radius = 0.005;
    c.length = 0.1;
    c.density = 800;
    const int log = sd_world_add_cylinder(w, &c);
    sd_pipe_loads L;
    start_loads(&L, w, pipe, 1e-3, NULL);
    for (int i = 0; i < 2000; i++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_pipe_loads_step(&L, w, sd_world_time(w), dt);
    }
    sd_pipe_loads_finish(&L, 0);
    sd_body_state b;
    sd_world_body(w, log, &b);
    CHECK(L.p[0].n_events == 1);
    CHECK_REL(L.p[0].ev.impulse, b.mass * (v + b.vel.z), 1e-12);
    CHECK_NEAR(v3_norm(b.omega), 0.0, 1e-9);
    CHECK_REL(L.p[0].ev.energy, 0.5 * b.mass * v * v, pow(L.p[0].ev.peak * dt / (b.mass * v), 2));
    sd_pipe_loads_free(&L);
    sd_world_destroy(w);
}

static void two_impacts(void)
{
    int pipe;
    sd_world *w = pipe_world(v3(0, 0, 0), H, &pipe);
    const double v = 0.5, dt = 1e-5;
    const int a = add_ball(w, -0.03, 1e-4, v), b = add_ball(w, 0.03, 9.1e-3, v); /* 18 ms apart */
    sd_pipe_loads L;
    start_loads(&L, w, pipe, 1e-3, NULL);
    double first_impulse = 0.0;
    for (int i = 0; i < 4000; i++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_pipe_loads_step(&L, w, sd_world_time(w), dt);
        if (L.p[0].n_events == 1 && first_impulse == 0.0) first_impulse = L.p[0].ev.impulse;
    }
    sd_pipe_loads_finish(&L, 0);
    sd_body_state sa, sb;
    sd_world_body(w, a, &sa);
    sd_world_body(w, b, &sb);
    double tc, e, peak;
    clipped(sa.mass, &tc, &e, &peak);
    CHECK(L.p[0].n_events == 2);
    CHECK_REL(first_impulse, sa.mass * (1 + e) * v, 3e-3);
    CHECK_REL(L.p[0].ev.impulse, sb.mass * (1 + e) * v, 3e-3);
    CHECK_REL(L.p[0].ev.energy, 0.5 * sb.mass * v * v, pow(L.p[0].ev.peak * dt / (sb.mass * v), 2));
    CHECK_NEAR(L.p[0].ev.t0, 0.018 + 1e-4 / v, 2 * dt);
    CHECK_REL(L.p[0].impulse, first_impulse + L.p[0].ev.impulse, 1e-12);
    sd_pipe_loads_free(&L);
    sd_world_destroy(w);
}

static void resting_load(void)
{
    int pipe;
    sd_world *w = pipe_world(v3(0, 0, -9.81), 0.7, &pipe);
    const double dt = 1e-5;
    const int ball = add_ball(w, 0.03, 2e-3, 0.0);
    sd_pipe_loads L;
    start_loads(&L, w, pipe, 0.0, NULL);
    sd_body_state b;
    sd_world_body(w, ball, &b);
    const double weight = b.mass * 9.81;
    CHECK_REL(L.ev_threshold, 4 * weight, 1e-14);
    int max_events = 0;
    for (int i = 0; i < 50000; i++) {
        CHECK(sd_world_step(w) == SD_OK);
        sd_pipe_loads_step(&L, w, sd_world_time(w), dt);
        if (L.p[0].n_events > max_events) max_events = L.p[0].n_events;
    }
    const sd_pipe_load *p = &L.p[0];
    sd_body_state bp;
    sd_world_body(w, pipe, &bp);
    CHECK_REL(-bp.force.z, weight, 1e-6);
    CHECK(max_events == 1 && !p->in_event);
    /* the event: the fall of 2 mm (v = 0.198 m/s) ended when the force fell below 2 m g; the
     * baseline then took the weight */
    CHECK(p->ev.peak > 10 * weight && p->ev.duration < 0.01);
    /* the baseline closes on the weight as 1 - (1 - Δt/τ)^n: after ~0.49 s (τ = 0.1 s) within
     * e^-4.9 = 0.7 % */
    CHECK(p->base < weight && p->base > 0.99 * weight);
    sd_pipe_loads_free(&L);
    sd_world_destroy(w);
}

int main(void)
{
    resultant_position();
    bending_moments();
    sphere_on_pipe();
    one_impact();
    log_impact();
    two_impacts();
    resting_load();
    return check_report("test_pipe_loads");
}
