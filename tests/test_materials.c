/* Materials and springs per pair of materials (docs/physics.md, "Materials"), against closed
 * forms and against the one-material engine:
 *   - spheres of one material sliding down beds of two others, and a log sliding down one,
 *     accelerate at g (sin θ - μ cos θ) with each pair's μ (1e-6: a constant force, integrated
 *     exactly by the leapfrog);
 *   - spheres of two materials hitting a fixed pipe normally rebound with the restitution and
 *     contact time that each pair's damping gives for the clipped spring-dashpot (1 %);
 *   - two spheres of different materials touch for π/ω, ω² = K_n(pair)/m* (0.5 %);
 *   - a scene whose pairs all have def.contact's springs gives the one-material bits, through
 *     the several-materials path too, at every SIMD level and on 1 and 2 threads;
 *   - a checkpoint keeps the pairs and the ids, and the run goes on with the same bits;
 *   - the time step is checked against the stiffest pair that can meet, the spring energy
 *     uses each pair's springs, bad ids and springs are refused. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "scenes.h"
#include "core/vmath.h"
#include "sabodem.h"

static const double G = 9.81;
enum { ROCK = 1, WOOD = 2, STEEL = 3, BED_A = 4, BED_B = 5, UNUSED_A = 14, UNUSED_B = 15 };

static sd_contact_def with_friction(sd_contact_def c, double tan_phi)
{
    c.tan_phi = tan_phi;
    return c;
}

static sd_contact_def with_springs(sd_contact_def c, double k_n, double damping)
{
    c.k_n = k_n;
    c.damping = damping;
    return c;
}

/* least-squares curvature of x(t) = c0 + c1 t + c2 t², returned as the acceleration 2 c2 */
static double fit_accel(const double *t, const double *x, int n)
{
    double S[5] = {0}, R[3] = {0};
    for (int i = 0; i < n; i++) {
        double p = 1.0;
        for (int k = 0; k < 5; k++) {
            S[k] += p;
            if (k < 3) R[k] += p * x[i];
            p *= t[i];
        }
    }
    double A[3][4] = {{S[0], S[1], S[2], R[0]}, {S[1], S[2], S[3], R[1]}, {S[2], S[3], S[4], R[2]}};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) {
            const double f = A[j][i] / A[i][i];
            for (int k = i; k < 4; k++)
                A[j][k] -= f * A[i][k];
        }
    double c[3];
    for (int i = 2; i >= 0; i--) {
        double s = A[i][3];
        for (int k = i + 1; k < 3; k++)
            s -= A[i][k] * c[k];
        c[i] = s / A[i][i];
    }
    return 2.0 * c[2];
}

/* A strip of squares along x, each split along a diagonal (the bodies cross shared edges), of
 * one material, y from y0 to y1. */
static void bed_strip(sd_world *w, double y0, double y1, int material)
{
    const double seg = 0.05;
    for (int k = 0; k < 10; k++) {
        const double x0 = -0.05 + k * seg, x1 = x0 + seg;
        const int t0 = sd_world_add_triangle(w, v3(x0, y0, 0), v3(x1, y0, 0), v3(x1, y1, 0), 0);
        const int t1 = sd_world_add_triangle(w, v3(x0, y0, 0), v3(x1, y1, 0), v3(x0, y1, 0), 0);
        CHECK(t0 >= 0 && t1 >= 0);
        CHECK(sd_world_set_triangle_material(w, t0, material) == SD_OK);
        CHECK(sd_world_set_triangle_material(w, t1, material) == SD_OK);
    }
}

/* Two rock spheres, one on a bed of material A (μ 0.05), one on B (μ 0.12), and a wooden log
 * lying along the slope on A (μ 0.08), all sliding (μ < (2/7) tan θ = 0.165 for the spheres; a
 * log along the slope cannot roll down it); the world's own tan φ, 0.404, would hold the log and
 * roll the spheres. */
static void test_slopes(void)
{
    const double th = 30.0 * M_PI / 180.0, r = 0.005;
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(G * sin(th), 0.0, -G * cos(th));
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    const double mu[3] = {0.05, 0.12, 0.08};
    sd_contact_def c = with_friction(def.contact, mu[0]);
    CHECK(sd_world_set_pair_contact(w, ROCK, BED_A, &c) == SD_OK);
    c = with_friction(def.contact, mu[1]);
    CHECK(sd_world_set_pair_contact(w, BED_B, ROCK, &c) == SD_OK); /* (either order) */
    c = with_friction(def.contact, mu[2]);
    CHECK(sd_world_set_pair_contact(w, WOOD, BED_A, &c) == SD_OK);
    bed_strip(w, -0.05, 0.0, BED_A);
    bed_strip(w, 0.0, 0.05, BED_B);
    bed_strip(w, -0.10, -0.05, BED_A);
    int id[3];
    for (int k = 0; k < 2; k++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = r;
        s.material = ROCK;
        const double m = s.density * 4.0 / 3.0 * M_PI * r * r * r;
        s.pos = v3(0.0, k ? 0.025 : -0.025, r - m * G * cos(th) / def.contact.k_n);
        id[k] = sd_world_add_sphere(w, &s);
        CHECK(id[k] >= 0);
    }
    sd_cylinder_def lg = sd_cylinder_def_default();
    lg.radius = r;
    lg.length = 0.1;
    lg.axis = v3(1, 0, 0);
    lg.pos = v3(0.05, -0.075, r - 0.5 * lg.density * M_PI * r * r * lg.length * G * cos(th) / def.contact.k_n);
    lg.material = WOOD;
    id[2] = sd_world_add_cylinder(w, &lg);
    CHECK(id[2] >= 0);
    sd_body_state b;
    CHECK(sd_world_body(w, id[2], &b) == SD_OK && b.material == WOOD);
    enum { NS = 2048 };
    static double ts[NS], xs[3][NS];
    int ns = 0;
    double fn_dev = 0.0;
    const long n_end = lround(0.3 / def.dt);
    for (long k = 1; k <= n_end; k++) {
        CHECK(sd_world_step(w) == SD_OK);
        const double t = sd_world_time(w);
        if (t < 0.05 || k % 50) continue;
        ts[ns] = t;
        for (int q = 0; q < 3; q++) {
            CHECK(sd_world_body(w, id[q], &b) == SD_OK);
            xs[q][ns] = b.pos.x;
            const double fn = b.mass * G * cos(th);
            if (fabs(b.force.z - fn) / fn > fn_dev) fn_dev = fabs(b.force.z - fn) / fn;
        }
        ns++;
    }
    static const char *const what[3] = {"rock sphere on bed A", "rock sphere on bed B", "wood log on bed A"};
    for (int q = 0; q < 3; q++) {
        const double a = fit_accel(ts, xs[q], ns), a_th = G * (sin(th) - mu[q] * cos(th));
        printf("%-22s mu %.2f: a = %.5f m/s^2, g (sin - mu cos) = %.5f, rel. error %.1e\n", what[q], mu[q], a, a_th,
               fabs(a - a_th) / a_th);
        CHECK_REL(a, a_th, 1e-6);
    }
    printf("largest |F_z / (m g cos) - 1| while sliding: %.1e\n", fn_dev);
    CHECK(fn_dev < 0.02);
    sd_world_destroy(w);
}

/* The clipped linear spring-dashpot's restitution and contact time (test_bounce.c's closed
 * form, Schwager & Pöschel 2007): the contact ends when k x + c x' = 0. */
static void clipped(double k_n, double h, double m_eff, double *e, double *tc)
{
    const double w0 = sqrt(k_n / m_eff), g = h * w0, w = sqrt(w0 * w0 - g * g);
    const double t = (M_PI - atan(2.0 * g * w / (w * w - g * g))) / w;
    *tc = t;
    *e = exp(-g * t) * fabs(cos(w * t) - g / w * sin(w * t));
}

/* A rock sphere and a wooden one fall at 0.2 m/s on a fixed steel pipe (along y, gravity off),
 * each at its own place; the pairs (rock, steel) and (wood, steel) have their own K_n and h. */
static void test_pipe_restitution(void)
{
    const double v0 = 0.2, dt = 1e-6, rp = 0.009;
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(0, 0, 0);
    def.dt = dt;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    const double kn[2] = {2.0e4, 6.0e3}, h[2] = {0.5, 0.1};
    const int mat[2] = {ROCK, WOOD};
    for (int q = 0; q < 2; q++) {
        const sd_contact_def c = with_springs(def.contact, kn[q], h[q]);
        CHECK(sd_world_set_pair_contact(w, mat[q], STEEL, &c) == SD_OK);
    }
    sd_cylinder_def p = sd_cylinder_def_default();
    p.radius = rp;
    p.length = 0.2;
    p.axis = v3(0, 1, 0);
    p.fixed = 1;
    p.density = 7850.0;
    p.material = STEEL;
    CHECK(sd_world_add_cylinder(w, &p) >= 0);
    int id[2];
    double m[2];
    const double rs[2] = {0.006, 0.0045}, rho[2] = {1900.0, 800.0};
    for (int q = 0; q < 2; q++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = rs[q];
        s.density = rho[q];
        s.material = mat[q];
        s.pos = v3(0.0, q ? 0.05 : -0.05, rp + rs[q] + 2e-5);
        s.vel = v3(0, 0, -v0);
        m[q] = rho[q] * 4.0 / 3.0 * M_PI * pow(rs[q], 3);
        id[q] = sd_world_add_sphere(w, &s);
        CHECK(id[q] >= 0);
    }
    long touching[2] = {0, 0};
    int done[2] = {0, 0};
    double e[2] = {0, 0};
    for (long k = 0; k < 200000 && !(done[0] && done[1]); k++) {
        CHECK(sd_world_step(w) == SD_OK);
        for (int q = 0; q < 2; q++) {
            sd_body_state b;
            CHECK(sd_world_body(w, id[q], &b) == SD_OK);
            if (b.force.z != 0.0) touching[q]++;
            if (touching[q] && !done[q] && b.pos.z > rp + rs[q] + 1e-5) {
                done[q] = 1;
                e[q] = b.vel.z / v0;
            }
        }
    }
    for (int q = 0; q < 2; q++) {
        double e_th, tc_th, e_world, tc_world;
        clipped(kn[q], h[q], m[q], &e_th, &tc_th);
        clipped(def.contact.k_n, def.contact.damping, m[q], &e_world, &tc_world);
        const double tc = touching[q] * dt;
        printf("%s sphere on the steel pipe, K_n %.0f N/m, h %.2f: e = %.5f (closed form %.5f; the world's springs "
               "would give %.5f), contact %.4e s (closed form %.4e)\n",
               q ? "wood" : "rock", kn[q], h[q], e[q], e_th, e_world, tc, tc_th);
        CHECK(done[q]);
        CHECK_REL(e[q], e_th, 0.01);
        CHECK_REL(tc, tc_th, 0.01);
        CHECK(fabs(e[q] - e_world) > 0.05); /* the pair's springs, not the world's */
    }
    sd_world_destroy(w);
}

/* Two spheres of different materials head-on, undamped pair: contact time π/ω, ω² = K_n/m*. */
static void test_pair_duration(void)
{
    const double dt = 1e-6, kn = 3.0e4, v0 = 0.2;
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(0, 0, 0);
    def.dt = dt;
    for (int order = 0; order < 2; order++) {
        sd_world *w = NULL;
        CHECK(sd_world_create(&def, &w) == SD_OK);
        const sd_contact_def c = with_springs(def.contact, kn, 0.0);
        CHECK(sd_world_set_pair_contact(w, WOOD, ROCK, &c) == SD_OK);
        const double r[2] = {0.010, 0.006}, rho[2] = {1900.0, 800.0};
        const int mat[2] = {ROCK, WOOD};
        double m[2];
        int id[2];
        for (int k = 0; k < 2; k++) {
            const int q = order ? 1 - k : k; /* (the pair's A is the one added first) */
            sd_sphere_def s = sd_sphere_def_default();
            s.radius = r[q];
            s.density = rho[q];
            s.material = mat[q];
            s.pos = v3(q ? r[q] + 1e-5 : -(r[q] + 1e-5), 0.0005, -0.0003);
            s.vel = v3(q ? -0.5 * v0 : 0.5 * v0, 0, 0);
            m[q] = rho[q] * 4.0 / 3.0 * M_PI * pow(r[q], 3);
            id[q] = sd_world_add_sphere(w, &s);
            CHECK(id[q] >= 0);
        }
        long touching = 0;
        sd_body_state A, B;
        for (long k = 0; k < 100000; k++) {
            CHECK(sd_world_step(w) == SD_OK);
            CHECK(sd_world_body(w, id[0], &A) == SD_OK && sd_world_body(w, id[1], &B) == SD_OK);
            if (A.force.x != 0.0) touching++;
            if (touching && B.pos.x - A.pos.x > r[0] + r[1] + 5e-6) break;
        }
        const double m_eff = m[0] * m[1] / (m[0] + m[1]), tc_th = M_PI / sqrt(kn / m_eff);
        const double tc = touching * dt, e = (B.vel.x - A.vel.x) / v0;
        printf("rock-wood spheres (%s first), K_n %.0f N/m, m* %.4e kg: contact %.5e s, pi/omega %.5e s (rel. "
               "%.1e); e = %.5f (undamped: 1)\n",
               order ? "wood" : "rock", kn, m_eff, tc, tc_th, fabs(tc - tc_th) / tc_th, e);
        CHECK_REL(tc, tc_th, 0.005);
        CHECK_NEAR(e, 1.0, 0.005);
        sd_world_destroy(w);
    }
}

/* A chute with a pipe grid: a floor of two materials, two side walls, a steel column and beam,
 * 120 spheres of two materials and 6 logs thrown downstream (mats 0: every material id 0,
 * else rock and wood spheres, wood logs, steel pipes, beds A and B, steel walls). */
static sd_world *chute(int threads, int simd, int mats)
{
    scene_rng = 0x2545F4914F6CDD1DULL;
    sd_world_def def = sd_world_def_default();
    def.dt = 2.0e-5;
    def.threads = threads;
    def.parallel_min = 0;
    def.tuning.simd = simd;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    const double lx = 0.4, ly = 0.12, h = 0.12;
    const int floor_mat[2] = {mats ? BED_A : 0, mats ? BED_B : 0}, wall_mat = mats ? STEEL : 0;
    for (int k = 0; k < 4; k++) { /* the floor in four squares, A and B in turn */
        const double x0 = 0.1 * k, x1 = x0 + 0.1;
        const int t0 = sd_world_add_triangle(w, v3(x0, 0, 0), v3(x1, 0, 0), v3(x1, ly, 0), 0);
        const int t1 = sd_world_add_triangle(w, v3(x0, 0, 0), v3(x1, ly, 0), v3(x0, ly, 0), 0);
        CHECK(sd_world_set_triangle_material(w, t0, floor_mat[k & 1]) == SD_OK);
        CHECK(sd_world_set_triangle_material(w, t1, floor_mat[k & 1]) == SD_OK);
    }
    const int t0 = sd_world_triangle_count(w);
    scene_quad(w, v3(0, 0, 0), v3(lx, 0, 0), v3(lx, 0, h), v3(0, 0, h), 1);
    scene_quad(w, v3(0, ly, 0), v3(lx, ly, 0), v3(lx, ly, h), v3(0, ly, h), 1);
    for (int t = t0; t < sd_world_triangle_count(w); t++)
        CHECK(sd_world_set_triangle_material(w, t, wall_mat) == SD_OK);
    sd_cylinder_def p = sd_cylinder_def_default();
    p.radius = 0.009;
    p.length = 0.1;
    p.pos = v3(0.25, 0.06, 0.05);
    p.axis = v3(0, 0, 1);
    p.fixed = 1;
    p.material = mats ? STEEL : 0;
    CHECK(sd_world_add_cylinder(w, &p) >= 0);
    p.length = ly;
    p.pos = v3(0.23, 0.5 * ly, 0.035);
    p.axis = v3(0, 1, 0);
    CHECK(sd_world_add_cylinder(w, &p) >= 0);
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 5; j++)
            for (int i = 0; i < 6; i++) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = 0.004 + 0.004 * scene_urand();
                s.pos = v3(0.02 + 0.02 * i + 0.002 * (scene_urand() - 0.5), 0.02 + 0.02 * j,
                           0.009 + 0.02 * k + 0.002 * (scene_urand() - 0.5));
                s.vel = v3(1.0, 0.1 * (scene_urand() - 0.5), 0.1 * (scene_urand() - 0.5));
                s.material = mats ? ((i + j + k) % 2 ? ROCK : WOOD) : 0;
                CHECK(sd_world_add_sphere(w, &s) >= 0);
            }
    for (int q = 0; q < 6; q++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.pos = v3(0.04 + 0.04 * (q % 3), 0.035 + 0.05 * (q / 3), 0.1);
        c.axis = q % 2 ? v3(0.1, 1, 0.05) : v3(1, 0.1, 0.05);
        c.length = 0.06;
        c.vel = v3(1.0, 0, 0);
        c.material = mats ? WOOD : 0;
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    return w;
}

/* every pair of the chute's materials its own springs (dt 2e-5 s keeps 8 steps a half period) */
static void chute_pairs(sd_world *w)
{
    const sd_contact_def d = sd_world_definition(w)->contact;
    const int m[5] = {ROCK, WOOD, STEEL, BED_A, BED_B};
    for (int i = 0; i < 5; i++)
        for (int j = i; j < 5; j++) {
            sd_contact_def c = d;
            c.k_n = d.k_n * (0.6 + 0.1 * i + 0.05 * j);
            c.k_s = 0.4 * c.k_n;
            c.damping = 0.1 + 0.05 * i + 0.02 * j;
            c.tan_phi = 0.2 + 0.08 * j - 0.03 * i;
            c.cohesion = i == j ? 1e-3 : 0.0;
            CHECK(sd_world_set_pair_contact(w, m[i], m[j], &c) == SD_OK);
        }
}

static uint64_t run_hash(sd_world *w, long steps)
{
    CHECK(sd_world_run(w, steps) == SD_OK);
    const uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    return h;
}

static void test_one_material_bits(void)
{
    const long steps = 1500;
    const uint64_t h0 = run_hash(chute(1, SD_SIMD_AUTO, 0), steps);
    /* materials on every body and triangle, no pair set: def.contact everywhere */
    CHECK(run_hash(chute(1, SD_SIMD_AUTO, 1), steps) == h0);
    /* every used pair set to def.contact's very springs: still the one-law path */
    {
        sd_world *w = chute(1, SD_SIMD_AUTO, 1);
        const sd_contact_def d = sd_world_definition(w)->contact;
        for (int a = 0; a < 6; a++)
            for (int b = a; b < 6; b++)
                CHECK(sd_world_set_pair_contact(w, a, b, &d) == SD_OK);
        CHECK(run_hash(w, steps) == h0);
    }
    /* a pair of two materials no element has, of other springs: the pass takes every contact's
     * law from the table (the several-materials path), whose every used entry is def.contact */
    int n = 0;
    for (int level = SD_SIMD_SCALAR; level <= SD_SIMD_AVX512; level++) {
        if (level > sd_cpu_simd_level()) continue;
        for (int threads = 1; threads <= 2; threads++) {
            sd_world *w = chute(threads, level, 1);
            sd_contact_def c = sd_world_definition(w)->contact;
            c.k_n *= 2.0;
            c.tan_phi = 0.7;
            CHECK(sd_world_set_pair_contact(w, UNUSED_A, UNUSED_B, &c) == SD_OK);
            const uint64_t h = run_hash(w, steps);
            CHECK(h == h0);
            n++;
        }
    }
    printf("one material's bits %016llx: materials set, pairs set to def.contact, and the table path at %d SIMD "
           "level x thread variants\n",
           (unsigned long long)h0, n);
    /* the chute with its own springs per pair: the same bits at every level and thread count, and
     * not the one-material bits */
    uint64_t hm = 0;
    n = 0;
    for (int level = SD_SIMD_SCALAR; level <= SD_SIMD_AVX512; level++) {
        if (level > sd_cpu_simd_level()) continue;
        for (int threads = 1; threads <= 2; threads++) {
            sd_world *w = chute(threads, level, 1);
            chute_pairs(w);
            const uint64_t h = run_hash(w, steps);
            if (n++ == 0) hm = h;
            CHECK(h == hm);
        }
    }
    printf("springs per pair: hash %016llx at %d variants\n", (unsigned long long)hm, n);
    CHECK(hm != h0);
}

static void test_checkpoint(void)
{
    char path[] = "/tmp/sabodem_test_materials_XXXXXX";
    const int fd = mkstemp(path);
    CHECK(fd >= 0);
    if (fd >= 0) close(fd);
    sd_world *w = chute(1, SD_SIMD_AUTO, 1);
    chute_pairs(w);
    CHECK(sd_world_run(w, 700) == SD_OK);
    CHECK(sd_checkpoint_write(path, w, NULL, 0) == SD_OK);
    CHECK(sd_world_run(w, 700) == SD_OK);
    const uint64_t h_straight = sd_world_state_hash(w);
    sd_world *r = NULL;
    char msg[512];
    CHECK(sd_checkpoint_read(path, &r, NULL, NULL, msg, sizeof msg) == SD_OK);
    if (!r) {
        printf("%s\n", msg);
        sd_world_destroy(w);
        return;
    }
    int pairs = 0, same = 1;
    for (int a = 0; a < SD_MATERIALS_MAX; a++)
        for (int b = 0; b < SD_MATERIALS_MAX; b++) {
            sd_contact_def c1, c2;
            const int s1 = sd_world_pair_contact(w, a, b, &c1), s2 = sd_world_pair_contact(r, a, b, &c2);
            same &= s1 == s2 && !memcmp(&c1, &c2, sizeof c1);
            pairs += s2 == 1;
        }
    CHECK(same);
    CHECK(pairs == 25); /* the 15 pairs of five materials, both orders */
    for (int t = 0; t < sd_world_triangle_count(w); t++)
        CHECK(sd_world_triangle_material(r, t) == sd_world_triangle_material(w, t));
    int mats[SD_MATERIALS_MAX] = {0};
    for (int g = 0; g < sd_world_body_count(w); g++) {
        sd_body_state a, b;
        CHECK(sd_world_body(w, g, &a) == SD_OK && sd_world_body(r, g, &b) == SD_OK);
        CHECK(a.material == b.material);
        mats[b.material]++;
    }
    CHECK(mats[0] == 0 && mats[ROCK] > 0 && mats[WOOD] > 0 && mats[STEEL] == 2);
    CHECK(sd_world_run(r, 700) == SD_OK);
    const uint64_t h_restart = sd_world_state_hash(r);
    printf("checkpoint of the chute with %d ordered pairs set: restart hash %016llx, straight %016llx\n", pairs,
           (unsigned long long)h_restart, (unsigned long long)h_straight);
    CHECK(h_restart == h_straight);
    /* the materials copied to a world of the same triangles (slabs.c's worlds), and refused
     * to one of other triangles */
    sd_world *c = NULL;
    CHECK(sd_world_create(sd_world_definition(w), &c) == SD_OK);
    CHECK(sd_world_copy_materials(c, w) == SD_ERR_ARG);
    for (int t = 0; t < sd_world_triangle_count(w); t++) {
        sd_vec3 q[3];
        int group;
        CHECK(sd_world_triangle(w, t, q, &group, NULL) == SD_OK);
        CHECK(sd_world_add_triangle(c, q[0], q[1], q[2], group) == t);
    }
    CHECK(sd_world_copy_materials(c, w) == SD_OK);
    same = 1;
    for (int a = 0; a < SD_MATERIALS_MAX; a++)
        for (int b = 0; b < SD_MATERIALS_MAX; b++) {
            sd_contact_def c1, c2;
            const int s1 = sd_world_pair_contact(w, a, b, &c1), s2 = sd_world_pair_contact(c, a, b, &c2);
            same &= s1 == s2 && !memcmp(&c1, &c2, sizeof c1);
        }
    for (int t = 0; t < sd_world_triangle_count(w); t++)
        same &= sd_world_triangle_material(c, t) == sd_world_triangle_material(w, t);
    CHECK(same);
    sd_world_destroy(c);
    sd_world_destroy(r);
    sd_world_destroy(w);
    unlink(path);
}

/* The time step against the stiffest pair that can meet, with its material's lightest body. */
static void test_time_step(void)
{
    sd_world_def def = sd_world_def_default();
    def.dt = 1e-5;
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    sd_sphere_def s = sd_sphere_def_default();
    s.radius = 0.005;
    s.material = ROCK;
    CHECK(sd_world_add_sphere(w, &s) >= 0);
    s.radius = 0.01;
    s.pos = v3(0.1, 0, 0);
    CHECK(sd_world_add_sphere(w, &s) >= 0);
    sd_cylinder_def p = sd_cylinder_def_default();
    p.fixed = 1;
    p.pos = v3(0.3, 0, 0);
    p.material = STEEL;
    CHECK(sd_world_add_cylinder(w, &p) >= 0);
    const double m = s.density * 4.0 / 3.0 * M_PI * pow(0.005, 3);
    int a = -1, b = -1;
    CHECK(sd_world_stable_dt(w, &a, &b) == sd_stable_dt_max(def.contact.k_n, def.contact.k_s, m));
    CHECK(sd_world_check(w) == SD_OK);
    /* a stiff pair of two materials no body has changes nothing */
    sd_contact_def c = with_springs(def.contact, 1e7, 0.2);
    CHECK(sd_world_set_pair_contact(w, WOOD, STEEL, &c) == SD_OK);
    CHECK(sd_world_check(w) == SD_OK);
    /* rock on steel that stiff is refused, and named */
    CHECK(sd_world_set_pair_contact(w, ROCK, STEEL, &c) == SD_OK);
    const double dt = sd_world_stable_dt(w, &a, &b);
    printf("rock-steel K_n 1e7 N/m: largest stable dt %.3e s (pair %d-%d); the world's K_n: %.3e s\n", dt, a, b,
           sd_stable_dt_max(def.contact.k_n, def.contact.k_s, m));
    CHECK(dt == sd_stable_dt_max(1e7, def.contact.k_s, m));
    CHECK(a == ROCK && b == STEEL);
    CHECK(sd_world_check(w) == SD_ERR_UNSTABLE);
    CHECK(sd_world_step(w) == SD_ERR_UNSTABLE);
    /* a stiff tangential spring counts (7/2 K_s) */
    c = def.contact;
    c.k_s = 5e5;
    CHECK(sd_world_set_pair_contact(w, ROCK, STEEL, &c) == SD_OK);
    CHECK(sd_world_stable_dt(w, NULL, NULL) == sd_stable_dt_max(def.contact.k_n, 5e5, m));
    CHECK(sd_world_set_pair_contact(w, ROCK, STEEL, NULL) == SD_OK); /* back to def.contact */
    CHECK(sd_world_pair_contact(w, STEEL, ROCK, NULL) == 0);
    CHECK(sd_world_check(w) == SD_OK);
    sd_world_destroy(w);
}

/* Spring energy ½ K_n δ² with the pair's K_n; bad ids and springs refused. */
static void test_energy_and_errors(void)
{
    sd_world_def def = sd_world_def_default();
    def.gravity = v3(0, 0, 0);
    sd_world *w = NULL;
    CHECK(sd_world_create(&def, &w) == SD_OK);
    const sd_contact_def c = with_springs(def.contact, 2.5e4, 0.2);
    CHECK(sd_world_set_pair_contact(w, ROCK, WOOD, &c) == SD_OK);
    sd_sphere_def s = sd_sphere_def_default();
    s.material = ROCK;
    const int a = sd_world_add_sphere(w, &s);
    s.material = WOOD;
    s.pos = v3(2.0 * s.radius - 1e-4, 0, 0);
    const int b = sd_world_add_sphere(w, &s);
    CHECK(sd_world_step(w) == SD_OK);
    sd_body_state A, B;
    CHECK(sd_world_body(w, a, &A) == SD_OK && sd_world_body(w, b, &B) == SD_OK);
    const double d = 2.0 * s.radius - v3_norm(v3_sub(B.pos, A.pos));
    CHECK_REL(sd_world_spring_energy(w), 0.5 * c.k_n * d * d, 1e-12);
    sd_world_destroy(w);

    CHECK(sd_world_create(&def, &w) == SD_OK);
    sd_contact_def bad = def.contact;
    bad.k_n = -1.0;
    CHECK(sd_world_set_pair_contact(w, ROCK, WOOD, &bad) == SD_ERR_ARG);
    bad = def.contact;
    bad.damping = NAN;
    CHECK(sd_world_set_pair_contact(w, ROCK, WOOD, &bad) == SD_ERR_ARG);
    CHECK(sd_world_set_pair_contact(w, SD_MATERIALS_MAX, 0, &def.contact) == SD_ERR_ARG);
    CHECK(sd_world_set_pair_contact(w, 0, -1, &def.contact) == SD_ERR_ARG);
    CHECK(sd_world_pair_contact(w, 0, SD_MATERIALS_MAX, NULL) == -1);
    s.material = SD_MATERIALS_MAX;
    CHECK(sd_world_add_sphere(w, &s) == -SD_ERR_ARG);
    s.material = -1;
    CHECK(sd_world_add_sphere(w, &s) == -SD_ERR_ARG);
    CHECK(sd_world_add_triangle(w, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), 0) == 0);
    CHECK(sd_world_set_triangle_material(w, 0, SD_MATERIALS_MAX) == SD_ERR_ARG);
    CHECK(sd_world_set_triangle_material(w, 1, 0) == SD_ERR_NOTFOUND);
    CHECK(sd_world_triangle_material(w, 0) == 0 && sd_world_triangle_material(w, 1) == -1);
    sd_world_destroy(w);
}

int main(void)
{
    test_slopes();
    test_pipe_restitution();
    test_pair_duration();
    test_one_material_bits();
    test_checkpoint();
    test_time_step();
    test_energy_and_errors();
    return check_report("test_materials");
}
