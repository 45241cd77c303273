/* STL meshes (docs/meshes.md): the reader and the scenario's meshes: list.
 *  1. ASCII and binary STL of the same mesh give the same triangles, bit for bit (the ASCII
 *     written with the binary's float values in full), from memory and from tests/data/; the
 *     ASCII grammar read in any case, any white space, CRLF, on one line, several solids.
 *  2. A binary file whose header begins with "solid" is read as binary (by its size); zero-area
 *     triangles are dropped and counted; NaN, truncation and a bad keyword are refused.
 *  3. The transform: corner' = Rz Ry Rx (scale corner) + translate, exactly as stated.
 *  4. A plane of two STL triangles tilted by rotate_deg under vertical gravity, tan φ = 0.404
 *     (φ = 22.0°): a puck (a short cylinder on its end face, which cannot roll) stays at 20° and
 *     slides at 35° with a = g (sin θ − tan φ cos θ); a sphere rolls at 20° with a = (5/7) g sin θ
 *     (a sphere on a slope rolls whatever the friction angle, tests/test_slope.c).
 *  5. A sphere thrown at a dam mesh (role dam) without gravity: the dam's impulse in summary.json
 *     equals the sphere's loss of momentum, m (v_in − v_out), and its peak force is that of the
 *     largest overlap.
 *  6. A flume whose flat bed is replaced by a bed mesh (flume.bed: false) carries its debris on
 *     it as on its own bed. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "build.h"
#include "check.h"
#include "core/vmath.h"
#include "io_stl.h"
#include "sabodem_run.h"
#include "scenario.h"

static const double G = 9.81;

/* ------------------------------------------------------------- the reader ---- */

/* a mesh of n triangles with float corners: a plane's two and some of random shape */
#define NT 6
static void make_mesh(float v[NT][3][3])
{
    static const float plane[2][3][3] = {{{-1, -0.5f, 0}, {1, -0.5f, 0}, {1, 0.5f, 0}},
                                         {{-1, -0.5f, 0}, {1, 0.5f, 0}, {-1, 0.5f, 0}}};
    memcpy(v, plane, sizeof plane);
    unsigned x = 12345u;
    for (int t = 2; t < NT; t++)
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++) {
                x = x * 1664525u + 1013904223u;
                v[t][k][d] = (float)((double)(x >> 8) / (1 << 24) * 20.0 - 10.0) * 0.1f;
            }
}

static size_t binary_stl(float v[NT][3][3], const char *header, unsigned char *out)
{
    memset(out, ' ', 80);
    memcpy(out, header, strlen(header));
    const unsigned n = NT;
    for (int k = 0; k < 4; k++)
        out[80 + k] = (unsigned char)(n >> 8 * k);
    size_t o = 84;
    for (int t = 0; t < NT; t++) {
        float rec[12] = {0, 0, 1};
        memcpy(rec + 3, v[t], 9 * sizeof(float));
        for (int k = 0; k < 12; k++) {
            unsigned u;
            memcpy(&u, &rec[k], 4);
            for (int b = 0; b < 4; b++)
                out[o++] = (unsigned char)(u >> 8 * b);
        }
        out[o++] = 0;
        out[o++] = 0;
    }
    return o;
}

/* the same mesh as ASCII text; style 0: plain, 1: upper case, tabs, CRLF, blank lines, two
 * solids; 2: all on one line */
static void ascii_stl(float v[NT][3][3], int style, char *out, size_t cap)
{
    size_t o = 0;
    const char *nl = style == 1 ? "\r\n\r\n" : style == 2 ? " " : "\n";
    const char *in = style == 1 ? "\t \t" : "  ";
#define PUT(...) o += (size_t)snprintf(out + o, cap - o, __VA_ARGS__)
    PUT("%s%s", style == 1 ? "SOLID Part 1" : "solid test", nl);
    for (int t = 0; t < NT; t++) {
        if (style == 1 && t == 3) PUT("ENDSOLID Part 1%sSolid part_2%s", nl, nl);
        PUT("%s%s 0 0 1%s", in, style == 1 ? "FACET Normal" : "facet normal", nl);
        PUT("%s%s%s", in, style == 1 ? "Outer LOOP" : "outer loop", nl);
        for (int k = 0; k < 3; k++) /* %.17g of the float's double: the float's exact value */
            PUT("%s%s%s %.17g %.17g\t%.17g%s", in, in, style == 1 ? "VERTEX" : "vertex", (double)v[t][k][0],
                (double)v[t][k][1], (double)v[t][k][2], nl);
        PUT("%s%s%s%s%s", in, style == 1 ? "EndLoop" : "endloop", nl, style == 1 ? "endFacet" : "endfacet", nl);
    }
    PUT("%s", style == 1 ? "endsolid part_2\r\n" : style == 2 ? "endsolid test" : "endsolid test\n");
#undef PUT
}

static int same_triangles(const sd_stl_mesh *a, float v[NT][3][3])
{
    if (a->n != NT) return 0;
    for (int t = 0; t < NT; t++)
        for (int k = 0; k < 3; k++)
            if (a->tri[t][k].x != (double)v[t][k][0] || a->tri[t][k].y != (double)v[t][k][1] ||
                a->tri[t][k].z != (double)v[t][k][2])
                return 0;
    return 1;
}

static void test_reader(void)
{
    float v[NT][3][3];
    make_mesh(v);
    static unsigned char bin[84 + 50 * NT];
    static char txt[8192];
    char msg[512];
    sd_stl_mesh m;
    /* binary, with a header that begins with "solid": binary by its size */
    const size_t nb = binary_stl(v, "solid exported by a CAD program", bin);
    CHECK(nb == sizeof bin);
    CHECK(sd_stl_parse(bin, nb, "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == 0);
    CHECK(m.binary == 1 && m.dropped == 0);
    CHECK(same_triangles(&m, v));
    sd_stl_free(&m);
    for (int style = 0; style < 3; style++) {
        ascii_stl(v, style, txt, sizeof txt);
        const int rc = sd_stl_parse(txt, strlen(txt), "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg);
        if (rc) fprintf(stderr, "style %d: %s\n", style, msg);
        CHECK(rc == 0 && m.binary == 0);
        CHECK(same_triangles(&m, v));
        sd_stl_free(&m);
    }
    /* the fixtures: the same plane in ASCII and in binary (header "solid plane ...") */
    sd_stl_mesh a, b;
    CHECK(sd_stl_read("tests/data/plane.stl", SD_STL_MAX_TRIANGLES, &a, msg, sizeof msg) == 0);
    CHECK(sd_stl_read("tests/data/plane_bin.stl", SD_STL_MAX_TRIANGLES, &b, msg, sizeof msg) == 0);
    CHECK(a.binary == 0 && b.binary == 1 && a.n == 2 && b.n == 2);
    CHECK(a.n == b.n && memcmp(a.tri, b.tri, (size_t)a.n * sizeof a.tri[0]) == 0);
    CHECK(a.where[0] == 2 && a.where[1] == 9 && b.where[1] == 1); /* facet lines; indices */
    sd_stl_free(&a);
    sd_stl_free(&b);

    /* zero-area triangles dropped and counted: the third corner on the first two's line, and
     * a repeated corner */
    float d[NT][3][3];
    memcpy(d, v, sizeof d);
    for (int k = 0; k < 3; k++) {
        for (int c = 0; c < 3; c++)
            d[3][c][k] = (float)c * (k + 1.0f); /* (0,0,0), (1,2,3), (2,4,6) */
        d[5][1][k] = d[5][0][k];
    }
    binary_stl(d, "", bin);
    CHECK(sd_stl_parse(bin, nb, "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == 0);
    CHECK(m.n == NT - 2 && m.dropped == 2 && m.first_dropped == 3);
    CHECK(m.where[3] == 4); /* triangle index 4 is the fourth kept */
    sd_stl_free(&m);
    /* refused: NaN (binary and ASCII), truncation, a bad keyword, trailing bytes, too many */
    v[4][1][2] = NAN;
    binary_stl(v, "", bin);
    CHECK(sd_stl_parse(bin, nb, "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == -1);
    CHECK(strstr(msg, "mem.stl: triangle index 4 (byte offset 284): vertex 2's z is not finite") != NULL);
    CHECK(m.n == 0 && m.tri == NULL);
    ascii_stl(v, 0, txt, sizeof txt);
    CHECK(sd_stl_parse(txt, strlen(txt), "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == -1);
    CHECK(strstr(msg, "mem.stl:33: vertex 2's z is not finite") != NULL);
    make_mesh(v);
    binary_stl(v, "", bin);
    CHECK(sd_stl_parse(bin, nb - 7, "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == -1);
    CHECK(strstr(msg, "truncated binary STL: it declares 6 triangles (84 + 50 x 6 = 384 bytes) but has 377 bytes; "
                      "triangle index 5 is cut at byte offset 377") != NULL);
    CHECK(sd_stl_parse(bin, nb, "mem.stl", 5, &m, msg, sizeof msg) == -1);
    CHECK(strstr(msg, "binary STL of 6 triangles, more than the limit of 5") != NULL);
    ascii_stl(v, 0, txt, sizeof txt);
    char *p = strstr(txt, "endloop");
    memcpy(p, "endlop ", 7);
    CHECK(sd_stl_parse(txt, strlen(txt), "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == -1);
    CHECK(strstr(msg, "mem.stl:7: expected 'endloop', found 'endlop'") != NULL);
    CHECK(sd_stl_parse("solid x\n", 8, "mem.stl", SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg) == -1);
    CHECK(strstr(msg, "mem.stl:2: expected 'facet' or 'endsolid', found the end of the file") != NULL);
}

/* ---------------------------------------------------------- the scenario ---- */

static void test_transform(void)
{
    const char *yaml = "meshes:\n"
                       "  - {file: plane.stl, role: wall, scale: 2, rotate_deg: [90, 0, 90], translate: [1, 2, 3]}\n";
    sd_scenario s;
    CHECK(sd_scenario_load_string(&s, yaml, "tests/data/transform.yaml", NULL, 0, stderr) == 0);
    CHECK(s.n_meshes == 1 && s.meshes[0].n_tri == 2 && s.meshes[0].role == SD_MESH_WALL);
    CHECK(!strcmp(s.meshes[0].file, "tests/data/plane.stl"));
    /* (1, -0.5, 0) x2 = (2, -1, 0); Rx 90: (2, 0, -1); Rz 90: (0, 2, -1); + (1, 2, 3) */
    CHECK_VEC_NEAR(s.meshes[0].tri[0][1], v3(1, 4, 2), 1e-14);
    /* (1, 0.5, 0) x2 = (2, 1, 0); Rx: (2, 0, 1); Rz: (0, 2, 1); + */
    CHECK_VEC_NEAR(s.meshes[0].tri[0][2], v3(1, 4, 4), 1e-14);
    sd_world *w;
    CHECK(sd_world_create(&s.world, &w) == SD_OK);
    sd_build_info info;
    CHECK(sd_build_scene(w, &s, &info, stderr) == SD_OK);
    CHECK(sd_world_triangle_count(w) == 2);
    sd_vec3 c[3];
    int group = -1, active = 0;
    CHECK(sd_world_triangle(w, 1, c, &group, &active) == SD_OK && group == SD_GROUP_WALLS && active);
    sd_world_destroy(w);
    sd_scenario_free(&s);
}

/* A body on the plane of tests/data/plane.stl (or its binary twin) tilted by theta about y:
 * the distance it travels down the slope at each sample time. shape 0: a puck of radius 0.02 m
 * and length 0.01 m on its end face; 1: a sphere of radius 0.01 m. */
#define NS 41
static void on_incline(double theta_deg, int shape, const char *file, double t[NS], double s_down[NS])
{
    const double th = theta_deg * M_PI / 180.0;
    const sd_vec3 n = v3(sin(th), 0.0, cos(th)), down = v3(cos(th), 0.0, -sin(th));
    const double lift = shape == 0 ? 0.005 : 0.01; /* the centre above the plane: touching */
    const sd_vec3 p = v3_scale(n, lift);
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "solver: {dt: 1.0e-5}\n"
             "gravity: [0, 0, -9.81]\n"
             "contact: {k_n: 1.0e4, k_s: 4.0e3, damping: 0.2, tan_phi: 0.404}\n"
             "meshes:\n"
             "  - {file: %s, role: bed, rotate_deg: [0, %.17g, 0]}\n"
             "elements:\n"
             "  - %s, position: [%.17g, 0, %.17g], axis: [%.17g, 0, %.17g]}\n",
             file, theta_deg,
             shape == 0 ? "{type: cylinder, radius: 0.02, length: 0.01, density: 2000"
                        : "{type: sphere, radius: 0.01, density: 2000",
             p.x, p.z, n.x, n.z);
    sd_scenario s;
    CHECK(sd_scenario_load_string(&s, yaml, "tests/data/incline.yaml", NULL, 0, stderr) == 0);
    sd_world *w;
    CHECK(sd_world_create(&s.world, &w) == SD_OK);
    sd_build_info info;
    CHECK(sd_build_scene(w, &s, &info, stderr) == SD_OK);
    const long every = 1000; /* 0.01 s */
    for (int k = 0; k < NS; k++) {
        if (k)
            for (long i = 0; i < every; i++)
                CHECK(sd_world_step(w) == SD_OK);
        sd_body_state st;
        CHECK(sd_world_body(w, 0, &st) == SD_OK);
        t[k] = sd_world_time(w);
        s_down[k] = v3_dot(v3_sub(st.pos, p), down);
    }
    sd_world_destroy(w);
    sd_scenario_free(&s);
}

/* least-squares y = c0 + c1 t + c2 t^2 over samples from k0 on; returns the acceleration 2 c2 */
static double fit_acceleration(const double *t, const double *y, int k0, int n)
{
    double S[5] = {0}, R[3] = {0};
    for (int i = k0; i < n; i++) {
        double q = 1.0;
        for (int k = 0; k < 5; k++) {
            S[k] += q;
            if (k < 3) R[k] += q * y[i];
            q *= t[i];
        }
    }
    double A[3][4] = {{S[0], S[1], S[2], R[0]}, {S[1], S[2], S[3], R[1]}, {S[2], S[3], S[4], R[2]}};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) {
            const double f = A[j][i] / A[i][i];
            for (int k = i; k < 4; k++)
                A[j][k] -= f * A[i][k];
        }
    double c[3] = {0};
    for (int i = 2; i >= 0; i--) {
        double v = A[i][3];
        for (int k = i + 1; k < 3; k++)
            v -= A[i][k] * c[k];
        c[i] = v / A[i][i];
    }
    return 2.0 * c[2];
}

static void test_incline(void)
{
    const double tan_phi = 0.404;
    double t[NS], s[NS];
    /* 20° < φ = 22.0°: the puck stays. It slips some 70 µm while its springs load from zero
     * (the friction limit grows with the normal force), then moves less than a micrometre over
     * 0.35 s (sliding, it would travel 0.2 m in that time at 35°) */
    on_incline(20.0, 0, "plane_bin.stl", t, s);
    double drift = 0.0;
    for (int k = 5; k < NS; k++)
        drift = fmax(drift, fabs(s[k] - s[5]));
    printf("puck at 20 deg: moved %.3g m in all, %.3g m after 0.05 s\n", s[NS - 1], drift);
    CHECK(fabs(s[NS - 1]) < 1e-4);
    CHECK(drift < 1e-6);
    /* 35°: it slides at g (sin θ − tan φ cos θ) = 2.381 m/s² (to 0.5 %, fitted over 0.1-0.4 s) */
    on_incline(35.0, 0, "plane.stl", t, s);
    const double th = 35.0 * M_PI / 180.0, a_slide = G * (sin(th) - tan_phi * cos(th));
    const double a = fit_acceleration(t, s, 10, NS);
    printf("puck at 35 deg: a = %.5f m/s^2, g (sin - tan phi cos) = %.5f\n", a, a_slide);
    CHECK_REL(a, a_slide, 5e-3);
    /* a sphere at 20°: rolls, a = (5/7) g sin θ = 2.396 m/s² (to 0.5 %) */
    on_incline(20.0, 1, "plane.stl", t, s);
    const double a_roll = 5.0 / 7.0 * G * sin(20.0 * M_PI / 180.0), ar = fit_acceleration(t, s, 10, NS);
    printf("sphere at 20 deg: a = %.5f m/s^2, (5/7) g sin = %.5f\n", ar, a_roll);
    CHECK_REL(ar, a_roll, 5e-3);
}

/* A sphere of 0.01 m at 1 m/s along x into a dam mesh (the binary plane stood up across x at
 * x = 0.1), no gravity: the run's summary against the sphere's momentum. */
static void test_dam_mesh(void)
{
    const char *yaml = "solver: {dt: 1.0e-5, duration: 0.1}\n"
                       "gravity: [0, 0, 0]\n"
                       "meshes:\n"
                       "  - {file: plane_bin.stl, role: dam, rotate_deg: [0, 90, 0], translate: [0.1, 0, 0]}\n"
                       "elements:\n"
                       "  - {type: sphere, radius: 0.01, density: 2000, position: [0.05, 0, 0], velocity: [1, 0, 0]}\n"
                       "output: {vtk: false, png: false}\n";
    sd_scenario *s = NULL;
    char err[2048];
    CHECK(sd_scenario_load_text(yaml, "tests/data/dam.yaml", NULL, 0, &s, err, sizeof err) == 0);
    char dir[] = "/tmp/sd_test_meshes.XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char out[64];
    snprintf(out, sizeof out, "%s/run", dir);
    sd_run *r = NULL;
    CHECK(sd_run_create(s, out, 1, &r, err, sizeof err) == 0);
    while (sd_run_advance(r, HUGE_VAL)) {
    }
    sd_body_state st;
    CHECK(sd_world_body(sd_run_world(r), 0, &st) == SD_OK);
    CHECK(sd_run_finish(r) == 0);
    char *json = sd_run_summary_json(r);
    cJSON *o = cJSON_Parse(json);
    const cJSON *d = cJSON_GetObjectItem(o, "dam_mesh");
    CHECK(d != NULL);
    const double m = 2000.0 * 4.0 / 3.0 * M_PI * 1e-6;
    const double ix = cJSON_GetNumberValue(cJSON_GetObjectItem(d, "impulse_x_Ns"));
    const double imp = cJSON_GetNumberValue(cJSON_GetObjectItem(d, "impulse_Ns"));
    const double peak = cJSON_GetNumberValue(cJSON_GetObjectItem(d, "peak_force_N"));
    printf("dam mesh: impulse %.9g N s (x %.9g), m (v_in - v_out) = %.9g; peak %.4g N; v_out %.4f m/s\n", imp, ix,
           m * (1.0 - st.vel.x), peak, st.vel.x);
    CHECK(st.vel.x < -0.3); /* bounced */
    CHECK_REL(ix, m * (1.0 - st.vel.x), 1e-9);
    CHECK_REL(imp, ix, 1e-9); /* a head-on impact: the force is along x throughout */
    /* the peak: K_n times the largest overlap of an undamped impact, v sqrt(m / K_n), less the
     * damping's share (h = 0.2 lowers it by ~20 %): between 0.7 and 1 of that */
    const double f_undamped = 1.0e4 * sqrt(m / 1.0e4);
    CHECK(peak > 0.7 * f_undamped && peak <= f_undamped);
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(d, "triangles")) == 2);
    cJSON_Delete(o);
    sd_free(json);
    sd_run_destroy(r);
    sd_scenario_destroy(s);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    CHECK(system(cmd) == 0);
}

/* The flume with flume.bed: false and the plane of tests/data/plane.stl as its bed (role bed,
 * group 0), against the same flume on its own flat bed (no roughness either way): 40 spheres
 * dropped behind the gate come to rest on the mesh as on the flat bed (kinetic energy below
 * 1e-6 J after 1 s), none below it, and the bed group carries their weight across the bed,
 * Σ m g cos θ, in both to 3 % (the walls and the gate take a little by friction; the flat bed
 * is 8 triangles, the mesh 2, so the bits differ). */
static double flume_bed_load(int mesh, double *lowest)
{
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "solver: {dt: 1.0e-5}\n"
             "flume: {on: true, bed: %s, roughness: false, slope_deg: 15, width: 0.12, wall_height: 0.2,\n"
             "        x_gate: 0.15, x_dam: 0.8, x_end: 0.9, pack_height: 0.16}\n"
             "spheres: {diameters: [0.02, 0.01], counts: [10, 30], density: 1900}\n"
             "logs: {count: 0}\n"
             "dam: {on: false}\n"
             "water: {on: false}\n"
             "%s",
             mesh ? "false" : "true", mesh ? "meshes:\n  - {file: plane.stl, role: bed, translate: [0.5, 0.25, 0]}\n" : "");
    sd_scenario s;
    CHECK(sd_scenario_load_string(&s, yaml, "tests/data/flume_bed.yaml", NULL, 0, stderr) == 0);
    sd_world *w;
    CHECK(sd_world_create(&s.world, &w) == SD_OK);
    sd_build_info info;
    CHECK(sd_build_scene(w, &s, &info, stderr) == SD_OK);
    /* the bed (2 or 8 triangles), the side walls (4 quads each), the end wall, the gate */
    CHECK(sd_world_triangle_count(w) == (mesh ? 2 : 8) + 16 + 2 + 2);
    for (int k = 0; k < 100000; k++)
        if (sd_world_step(w) != SD_OK) {
            CHECK(0);
            break;
        }
    CHECK(sd_world_kinetic_energy(w) < 1e-6);
    const sd_body_view b = sd_world_bodies(w);
    double weight = 0.0;
    *lowest = 1.0;
    for (int i = 0; i < b.n; i++) {
        weight += b.mass[i] * G * cos(15.0 * M_PI / 180.0);
        *lowest = fmin(*lowest, b.pos[i].z - b.radius[i]);
    }
    CHECK(b.n == 40);
    const double f = -sd_world_group_force(w, SD_GROUP_BED).z;
    printf("flume on %s: lowest point %.3g m, bed force z %.5g N, weight across the bed %.5g N\n",
           mesh ? "a bed mesh" : "its flat bed", *lowest, f, weight);
    CHECK_REL(f, weight, 0.03);
    sd_world_destroy(w);
    sd_scenario_free(&s);
    return f;
}

static void test_flume_bed(void)
{
    double low_flat, low_mesh;
    const double flat = flume_bed_load(0, &low_flat), mesh = flume_bed_load(1, &low_mesh);
    CHECK(low_mesh > -1e-3 && low_flat > -1e-3); /* resting on the bed (µm in), not fallen through */
    CHECK_REL(mesh, flat, 0.03);
}

int main(void)
{
    test_reader();
    test_transform();
    test_incline();
    test_dam_mesh();
    test_flume_bed();
    return check_report("test_meshes");
}
