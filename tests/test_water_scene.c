/* Water in a scene without a flume (water.scene), through the whole driver, against closed
 * forms: a sphere settling in still water reaches the terminal speed of the drag law on the
 * tanh curve; a neutrally buoyant sphere is carried up to a uniform stream's speed on the
 * quadratic-drag curve; on a slope, bed-normal buoyancy leaves the downslope weight and
 * vertical buoyancy none; a log lighter than water floats with its centre at the surface, wet
 * for the fraction of the time its specific gravity says. And the capture's water region
 * (water.capture_end, water.capture_length) in the force hook itself, at every SIMD level. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "fluid.h"
#include "run.h"
#include "scenario.h"
#include "water.h"

enum { MAX_ROWS = 40000 };
typedef struct {
    int n;
    double t[MAX_ROWS], x[MAX_ROWS], z[MAX_ROWS], vx[MAX_ROWS], vz[MAX_ROWS];
} traj;

/* Run the scene text (trajectory of element 0 logged) and read its trajectory back. */
static int run_scene(const char *yaml, traj *tr)
{
    char dir[] = "/tmp/sabodem_water_XXXXXX";
    if (!mkdtemp(dir)) return -1;
    char path[320], out[64];
    snprintf(path, sizeof path, "%s/scene.yaml", dir);
    snprintf(out, sizeof out, "%s/out", dir);
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fputs(yaml, f);
    fclose(f);
    sd_scenario s;
    int rc = -1;
    if (sd_scenario_load(&s, path, NULL, 0, stderr) == 0) {
        sd_run_opts o = {.outdir = out, .err = stderr};
        sd_run_result r;
        rc = sd_run_scenario(&s, &o, &r);
        sd_scenario_free(&s);
    }
    snprintf(path, sizeof path, "%s/trajectories.csv", out);
    tr->n = 0;
    f = rc == 0 ? fopen(path, "r") : NULL;
    char line[1024];
    if (f && fgets(line, sizeof line, f))
        while (tr->n < MAX_ROWS && fgets(line, sizeof line, f)) {
            double v[17];
            int id;
            if (sscanf(line, "%lf,%d,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &id, &v[2], &v[3], &v[4], &v[5], &v[6], &v[7]) != 8)
                continue;
            tr->t[tr->n] = v[0], tr->x[tr->n] = v[2], tr->z[tr->n] = v[4], tr->vx[tr->n] = v[5], tr->vz[tr->n] = v[7];
            tr->n++;
        }
    if (f) fclose(f);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) rc = -1;
    return rc;
}

static traj tr;

/* A 20 mm sphere of SG 1.9 in still water: m dv/dt = (m − ρV) g − ½ C_D ρ A v², so
 * v(t) = v_t tanh(g' t / v_t), g' = g (1 − ρ/ρ_s), v_t = sqrt(8 r g (ρ_s − ρ) / (3 C_D ρ)). */
static void test_settling_sphere(void)
{
    CHECK(run_scene("solver: {dt: 2.0e-5, duration: 1.0}\n"
                    "water: {on: true, scene: still, h: 10.0, rho: 1000, c_d: 0.49}\n"
                    "elements:\n  - {type: sphere, radius: 0.01, density: 1900, position: [0, 0, 5]}\n"
                    "output: {trajectory_ids: [0], trajectory_interval: 0.01, log_interval: 0.1, vtk: false, png: false}\n",
                    &tr) == 0);
    const double r = 0.01, rs = 1900, rho = 1000, cd = 0.49, g = 9.81;
    const double vt = sqrt(8.0 * r * g * (rs - rho) / (3.0 * cd * rho)), gp = g * (1.0 - rho / rs);
    double worst = 0.0, vx_max = 0.0;
    for (int k = 1; k < tr.n; k++) {
        /* (the logged velocity is the half step behind the time) */
        double want = -vt * tanh(gp * (tr.t[k] - 1e-5) / vt);
        worst = fmax(worst, fabs(tr.vz[k] - want) / vt);
        vx_max = fmax(vx_max, fabs(tr.vx[k]));
    }
    printf("settling sphere: v_t = %.6f m/s, measured %.6f m/s at t = %.2f s; worst |v - v_t tanh| / v_t = %.2e over %d "
           "rows\n",
           vt, -tr.vz[tr.n - 1], tr.t[tr.n - 1], worst, tr.n);
    CHECK(tr.n == 101);
    CHECK_REL(-tr.vz[tr.n - 1], vt, 1e-4);
    CHECK(worst < 1e-4);
    CHECK(vx_max == 0.0);
}

/* A sphere as dense as the water in a uniform stream U, from rest: the weight and the
 * (vertical) buoyancy cancel, and dv/dt = k (U − v)², k = 3 C_D / (8 r), so
 * v(t) = U − U / (1 + k U t). */
static void test_uniform_stream(void)
{
    CHECK(run_scene("solver: {dt: 2.0e-5, duration: 0.5}\n"
                    "water: {on: true, scene: uniform, u: 1.2, h: 10.0, rho: 1000, c_d: 0.49}\n"
                    "elements:\n  - {type: sphere, radius: 0.01, density: 1000, position: [0, 0, 5]}\n"
                    "output: {trajectory_ids: [0], trajectory_interval: 0.01, log_interval: 0.1, vtk: false, png: false}\n",
                    &tr) == 0);
    const double U = 1.2, k = 3.0 * 0.49 / (8.0 * 0.01);
    double worst = 0.0, vz_max = 0.0;
    for (int k2 = 1; k2 < tr.n; k2++) {
        double t = tr.t[k2] - 1e-5, want = U - U / (1.0 + k * U * t);
        worst = fmax(worst, fabs(tr.vx[k2] - want) / U);
        vz_max = fmax(vz_max, fabs(tr.vz[k2]));
    }
    printf("uniform stream: v(0.5 s) = %.6f m/s (closed form %.6f); worst error %.2e U; |v_z| <= %.1e m/s\n",
           tr.vx[tr.n - 1], U - U / (1.0 + k * U * (tr.t[tr.n - 1] - 1e-5)), worst, vz_max);
    CHECK(tr.n == 51);
    CHECK(worst < 3e-4); /* (the drag from the half step before: first order in Δt) */
    CHECK(vz_max < 1e-9);
}

/* On a 15° slope (gravity 9.81 (sin θ, 0, −cos θ)), a sphere as dense as still water: with the
 * buoyancy normal to the bed it keeps the downslope weight m g sin θ and runs to the terminal
 * speed sqrt(8 r g sin θ / (3 C_D)); with the vertical buoyancy of the paper nothing is left. */
static void test_buoyancy_direction(void)
{
    const char *fmt = "solver: {dt: 2.0e-5, duration: 1.5}\n"
                      "gravity: [2.539014832, 0, -9.475732356]\n"
                      "water: {on: true, scene: still, h: 10.0, rho: 1000, c_d: 0.49, buoyancy: %s}\n"
                      "elements:\n  - {type: sphere, radius: 0.01, density: 1000, position: [0, 0, 5]}\n"
                      "output: {trajectory_ids: [0], trajectory_interval: 0.01, log_interval: 0.1, vtk: false, "
                      "png: false}\n";
    char yaml[1024];
    snprintf(yaml, sizeof yaml, fmt, "bed_normal");
    CHECK(run_scene(yaml, &tr) == 0);
    const double gx = 2.539014832, vt = sqrt(8.0 * 0.01 * gx / (3.0 * 0.49));
    double vx_n = tr.vx[tr.n - 1], vz_n = tr.vz[tr.n - 1];
    snprintf(yaml, sizeof yaml, fmt, "vertical");
    CHECK(run_scene(yaml, &tr) == 0);
    double v_v = hypot(tr.vx[tr.n - 1], tr.vz[tr.n - 1]);
    printf("buoyancy normal to the bed: v_x = %.6f m/s (terminal %.6f), v_z = %.1e; vertical: |v| = %.1e m/s\n", vx_n,
           vt, vz_n, v_v);
    CHECK_REL(vx_n, vt, 1e-4);
    CHECK(fabs(vz_n) < 1e-9);
    CHECK(v_v < 1e-9);
}

/* A log of SG 0.8 in still water: the model's buoyancy is the whole ρVg while the centre is
 * under the surface and none above, so the log floats with its centre at the surface (the
 * model's draft: one radius), and over whole bobs its weight equals the buoyancy's time mean:
 * the centre is wet for the fraction ρ_log/ρ = 0.8 of the time. */
static void test_floating_log(void)
{
    CHECK(run_scene("solver: {dt: 1.0e-5, duration: 3.0}\n"
                    "water: {on: true, scene: still, h: 0.2, rho: 1000, c_d: 0.49}\n"
                    "elements:\n  - {type: cylinder, radius: 0.005, length: 0.1, density: 800, axis: [1, 0, 0], "
                    "position: [0, 0, 0.17]}\n"
                    "output: {trajectory_ids: [0], trajectory_interval: 1.0e-4, log_interval: 0.1, vtk: false, png: false}\n",
                    &tr) == 0);
    /* the last second, from the first surfacing on after 2 s to the last one: whole bobs */
    int k0 = -1, k1 = -1;
    for (int k = 1; k < tr.n; k++)
        if (tr.z[k - 1] <= 0.2 && tr.z[k] > 0.2 && tr.t[k] >= 2.0) {
            if (k0 < 0) k0 = k;
            k1 = k;
        }
    CHECK(k0 > 0 && k1 > k0);
    int wet = 0, n = 0;
    double zmin = 1, zmax = -1, zsum = 0;
    for (int k = k0; k < k1; k++, n++) {
        wet += tr.z[k] <= 0.2;
        zmin = fmin(zmin, tr.z[k]);
        zmax = fmax(zmax, tr.z[k]);
        zsum += tr.z[k];
    }
    double frac = n ? (double)wet / n : 0.0;
    printf("floating log: centre in [%.5f, %.5f] m, mean %.5f m (surface 0.2 m) over %.3f s; wet %.4f of the time "
           "(SG 0.8)\n",
           zmin, zmax, n ? zsum / n : 0.0, n * 1e-4, frac);
    CHECK(n > 3000);
    CHECK_NEAR(frac, 0.8, 0.02);
    CHECK(zmin > 0.2 - 0.005 && zmax < 0.2 + 0.005);
}

/* The capture's water region in the hook: the capture profile for x_from <= x < xd, the flow
 * profile elsewhere, bit for bit as sd_fluid_force_total gives them, at every SIMD level, for
 * spheres and logs on both sides of each bound. */
static void test_capture_region(void)
{
    const double xd = 4.009, x_from = 3.5;
    const double xs[] = {3.2, 3.49, 3.5, 3.8, 4.0, 4.005, 4.009, 4.02, 4.2};
    const int nx = (int)(sizeof xs / sizeof xs[0]);
    const int levels[] = {SD_SIMD_SCALAR, SD_SIMD_AVX2, SD_SIMD_AVX512};
    for (int li = 0; li < 3; li++) {
        sd_world_def d = sd_world_def_default();
        d.tuning.simd = levels[li];
        sd_world *w;
        CHECK(sd_world_create(&d, &w) == SD_OK);
        for (int rep = 0; rep < 3; rep++)
            for (int k = 0; k < nx; k++) {
                if ((k + rep) % 4 == 3) {
                    sd_cylinder_def c = sd_cylinder_def_default();
                    c.pos = v3(xs[k], 0.05 * rep, 0.004 + 0.003 * k);
                    c.vel = v3(0.3, 0.0, -0.05);
                    c.axis = v3(0.6, 0.8, 0.0);
                    CHECK(sd_world_add_cylinder(w, &c) >= 0);
                } else {
                    sd_sphere_def s = sd_sphere_def_default();
                    s.radius = 0.005 + 0.001 * rep;
                    s.pos = v3(xs[k], 0.05 * rep, 0.002 + 0.004 * k);
                    s.vel = v3(0.2 * rep, 0.01, 0.0);
                    CHECK(sd_world_add_sphere(w, &s) >= 0);
                }
            }
        sd_water fc;
        memset(&fc, 0, sizeof fc);
        fc.fp = sd_fluid_params_default(15.0 * M_PI / 180.0);
        fc.h_d = 0.05;
        fc.xd = xd;
        fc.x_from = x_from;
        fc.capture = 1;
        const sd_body_view bv = sd_world_bodies(w), *b = &bv;
        int32_t idx[64];
        sd_vec3 out[64];
        for (int i = 0; i < b->n; i++)
            idx[i] = i;
        sd_water_forces(&fc, w, idx, 0, b->n, out);
        int same = 0, cap = 0;
        for (int i = 0; i < b->n; i++) {
            sd_fluid_element e = {b->shape[i], b->pos[i], b->vel[i], b->axis[i], b->radius[i], 2.0 * b->half_length[i]};
            const int in = b->pos[i].x < xd && b->pos[i].x >= x_from;
            cap += in;
            sd_vec3 want = sd_fluid_force_total(&fc.fp, in ? SD_FLUID_CAPTURE : SD_FLUID_FLOW, fc.h_d, &e);
            same += memcmp(&want, &out[i], sizeof want) == 0;
        }
        printf("capture region, SIMD level %d: %d of %d bodies as the closed form, %d in the pond's region\n",
               sd_world_simd_level(w), same, b->n, cap);
        CHECK(same == b->n);
        CHECK(cap == 3 * 4);
        sd_world_destroy(w);
    }
}

int main(void)
{
    test_capture_region();
    test_settling_sphere();
    test_uniform_stream();
    test_buoyancy_direction();
    test_floating_log();
    return check_report("test_water_scene");
}
