/* Stored reference data (GUIDE.md, tests layer 3): three scenes stepped a fixed number of steps
 * must give the state hash and, one step later, the per-body forces and torques stored in
 * tests/data/ref_<scene>.txt, bit for bit, on 1, 2 and 3 threads and at every SIMD level the
 * CPU has. The references pin the engine's arithmetic: a change that moves a bit fails here
 * first. They change only as a reviewed diff, written by `test_reference --write` (run from the
 * repository root), with the reason in the commit message.
 *
 *   bed      1008 spheres dropped on a jittered lattice into a box of triangles, settled
 *   flume    the reduced flume with logs (examples/flume_small.yaml): packing behind the gate,
 *            the gate removed, the flow down the roughness bed
 *   capture  spheres and logs thrown at 1.2 m/s against a grid of fixed pipes (three columns,
 *            one beam) standing on an inclined floor
 */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "build.h"
#include "check.h"
#include "scenes.h"
#include "core/vmath.h"
#include "sabodem.h"
#include "scenario.h"


typedef struct {
    int gid;
    sd_vec3 f, t;
} body_load;

typedef struct {
    long steps;     /* the hash is taken after these steps ... */
    uint64_t hash;  /* ... */
    long contacts;  /* contacts of the last of them */
    int n;          /* the loads of the next step, every body but the bed roughness, by gid */
    body_load *load;
    double ke;      /* kinetic energy after the hash's step, J (not part of the reference) */
} result;

/* the threads and the SIMD level of the scenes' worlds (run_scene) */
static int scene_threads = 1, scene_simd = SD_SIMD_AUTO;

static sd_world *world_new(sd_world_def *def)
{
    def->parallel_min = 0; /* every loop parallel, even in these small scenes */
    def->threads = scene_threads;
    def->tuning.simd = scene_simd;
    sd_world *w = NULL;
    CHECK(sd_world_create(def, &w) == SD_OK);
    return w;
}

/* 14 x 8 x 9 spheres of 11.2-12.2 mm on a jittered 12.5 mm lattice (no overlap) with random velocities and
 * spins, in an open box; gravity 15 degrees off the floor's normal, as in the flume. */
static sd_world *scene_bed(void)
{
    scene_rng = 0x9E3779B97F4A7C15ULL;
    sd_world_def def = sd_world_def_default();
    def.dt = 5.0e-5;
    sd_world *w = world_new(&def);
    const int nx = 14, ny = 8, nz = 9;
    const double sp = 0.0125;
    scene_open_box(w, nx * sp, ny * sp, 0.2);
    scene_lattice(w, nx, ny, nz, sp);
    return w;
}

/* The reduced flume through packing (n_pack steps behind the gate), the gate then removed for
 * the flow. A coarser step (4e-5 s) so that the spheres land and pile at the gate within the
 * test. */
static sd_world *scene_flume(sd_scenario *s, long n_pack)
{
    const char *sets[] = {"solver.dt=4e-5"};
    CHECK(sd_scenario_load(s, "examples/flume_small.yaml", sets, 1, stderr) == 0);
    sd_world *w = world_new(&s->world);
    sd_build_info info;
    CHECK(sd_build_scene(w, s, &info, stderr) == SD_OK);
    CHECK(sd_world_run(w, n_pack) == SD_OK);
    CHECK(sd_world_set_group_active(w, SD_GROUP_GATE, 0) == SD_OK);
    return w;
}

/* A floor 0.5 x 0.2 m, gravity 15 degrees downstream; pipes of 18 mm: three columns at y =
 * 0.05, 0.1, 0.15 (clear spacing 32 mm) from the floor to 0.14 m at x = 0.3, and a beam across
 * at z = 0.06 just upstream of them. 300 spheres of 8-20 mm and 12 logs of 10 x 100 mm in a
 * block upstream, thrown downstream at 1.2 m/s. */
static sd_world *scene_capture(void)
{
    scene_rng = 0xD1B54A32D192ED03ULL;
    sd_world_def def = sd_world_def_default();
    def.dt = 2.0e-5;
    sd_world *w = world_new(&def);
    const double lx = 0.5, ly = 0.2, h = 0.16;
    scene_quad(w, v3(0, 0, 0), v3(lx, 0, 0), v3(lx, ly, 0), v3(0, ly, 0), 0);
    scene_quad(w, v3(0, 0, 0), v3(lx, 0, 0), v3(lx, 0, h), v3(0, 0, h), 1);
    scene_quad(w, v3(0, ly, 0), v3(lx, ly, 0), v3(lx, ly, h), v3(0, ly, h), 1);
    const double rp = 0.009, xp = 0.3;
    for (int c = 0; c < 3; c++) {
        sd_cylinder_def p = sd_cylinder_def_default();
        p.radius = rp;
        p.length = 0.14;
        p.pos = v3(xp, 0.05 * (c + 1), 0.07);
        p.axis = v3(0, 0, 1);
        p.fixed = 1;
        p.tag = 300 + c;
        CHECK(sd_world_add_cylinder(w, &p) >= 0);
    }
    sd_cylinder_def beam = sd_cylinder_def_default();
    beam.radius = rp;
    beam.length = ly;
    beam.pos = v3(xp - 2.0 * rp, 0.5 * ly, 0.06);
    beam.axis = v3(0, 1, 0);
    beam.fixed = 1;
    beam.tag = 303;
    CHECK(sd_world_add_cylinder(w, &beam) >= 0);
    /* the block: 10 x 6 x 5 cells of 22 mm from x = 0.02, one sphere each, jittered */
    const double cell = 0.022;
    for (int k = 0; k < 5; k++)
        for (int j = 0; j < 6; j++)
            for (int i = 0; i < 10; i++) {
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = 0.004 + 0.006 * scene_urand();
                const double room = cell - 2.0 * s.radius;
                s.pos = v3(0.02 + cell * (i + 0.5) + room * (scene_urand() - 0.5),
                           0.034 + cell * (j + 0.5) + room * (scene_urand() - 0.5),
                           0.012 + cell * (k + 0.5) + room * (scene_urand() - 0.5));
                s.vel = v3(1.2, 0.1 * (scene_urand() - 0.5), 0.1 * (scene_urand() - 0.5));
                s.tag = 1 + (int)(s.radius > 0.007);
                CHECK(sd_world_add_sphere(w, &s) >= 0);
            }
    /* the logs above the block, along x and across it in turn, tilted a little */
    for (int q = 0; q < 12; q++) {
        sd_cylinder_def c = sd_cylinder_def_default();
        c.pos = v3(0.08 + 0.03 * (q % 4), 0.05 + 0.05 * (q / 4), 0.135 + 0.012 * (q % 2));
        c.axis = q % 2 ? v3(0.1 * scene_urand(), 1, 0.1 * scene_urand()) : v3(1, 0.2 * (scene_urand() - 0.5), 0.1 * scene_urand());
        c.vel = v3(1.2, 0, 0);
        c.omega = v3(0, 0, 2.0 * (scene_urand() - 0.5));
        c.tag = 200;
        CHECK(sd_world_add_cylinder(w, &c) >= 0);
    }
    return w;
}

/* Steps w to `steps` (counted from its first step), takes the hash, steps once more and takes
 * every body's force and torque but the bed roughness's (fixed spheres carry none). */
static result finish(sd_world *w, long steps)
{
    result r;
    memset(&r, 0, sizeof r);
    CHECK(sd_world_run(w, steps - sd_world_step_count(w)) == SD_OK);
    r.steps = sd_world_step_count(w);
    r.hash = sd_world_state_hash(w);
    r.contacts = sd_world_contact_count(w);
    r.ke = sd_world_kinetic_energy(w);
    CHECK(sd_world_step(w) == SD_OK);
    const int n = sd_world_body_count(w);
    r.load = calloc((size_t)n, sizeof *r.load);
    for (int i = 0; i < n; i++) {
        sd_body_state b;
        CHECK(sd_world_body_at(w, i, &b) == SD_OK);
        if (b.fixed && b.shape == SD_SHAPE_SPHERE) continue;
        r.load[r.n++] = (body_load){b.gid, b.force, b.torque};
    }
    for (int i = 1; i < r.n; i++) /* by gid: the store's order is the engine's business */
        for (int j = i; j > 0 && r.load[j - 1].gid > r.load[j].gid; j--) {
            const body_load t = r.load[j];
            r.load[j] = r.load[j - 1];
            r.load[j - 1] = t;
        }
    sd_world_destroy(w);
    return r;
}

enum { SCENE_BED, SCENE_FLUME, SCENE_CAPTURE, SCENES };
static const char *const scene_name[SCENES] = {"bed", "flume", "capture"};
static const long scene_steps[SCENES] = {10000, 8000, 5000};

static result run_scene(int scene, int threads, int simd)
{
    scene_threads = threads;
    scene_simd = simd;
    result r;
    if (scene == SCENE_FLUME) {
        sd_scenario s;
        r = finish(scene_flume(&s, 6000), scene_steps[scene]);
        sd_scenario_free(&s);
    } else {
        r = finish(scene == SCENE_BED ? scene_bed() : scene_capture(), scene_steps[scene]);
    }
    return r;
}

static void ref_path(int scene, char *path, size_t len) { snprintf(path, len, "tests/data/ref_%s.txt", scene_name[scene]); }

static int write_ref(int scene, const result *r)
{
    char path[128], tmp[160];
    ref_path(scene, path, sizeof path);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) return -1;
    fprintf(f, "# sabodem stored reference, scene '%s' (tests/test_reference.c): the state hash after\n", scene_name[scene]);
    fprintf(f, "# `steps` steps, then each body's force (N) and torque (N m) of the step after, hex floats.\n");
    fprintf(f, "# Written by `test_reference --write`; changed only as a reviewed diff.\n");
    fprintf(f, "steps %ld\nhash %016" PRIx64 "\ncontacts %ld\nbodies %d\n", r->steps, r->hash, r->contacts, r->n);
    for (int k = 0; k < r->n; k++) {
        const body_load *l = &r->load[k];
        fprintf(f, "%d %a %a %a %a %a %a\n", l->gid, l->f.x, l->f.y, l->f.z, l->t.x, l->t.y, l->t.z);
    }
    if (fclose(f) != 0 || rename(tmp, path) != 0) return -1;
    printf("wrote %s: %d bodies, hash %016" PRIx64 "\n", path, r->n, r->hash);
    return 0;
}

static int read_ref(int scene, result *r)
{
    char path[128], line[512];
    ref_path(scene, path, sizeof path);
    memset(r, 0, sizeof *r);
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "%s: cannot open (run from the repository root)\n", path);
        return -1;
    }
    int ok = 1, k = 0, lineno = 0;
    while (ok && fgets(line, sizeof line, f)) {
        lineno++;
        if (line[0] == '#') continue;
        if (!strncmp(line, "steps ", 6))
            ok = sscanf(line + 6, "%ld", &r->steps) == 1;
        else if (!strncmp(line, "hash ", 5))
            ok = sscanf(line + 5, "%" SCNx64, &r->hash) == 1;
        else if (!strncmp(line, "contacts ", 9))
            ok = sscanf(line + 9, "%ld", &r->contacts) == 1;
        else if (!strncmp(line, "bodies ", 7)) {
            ok = sscanf(line + 7, "%d", &r->n) == 1 && r->n > 0 && r->n < 1000000;
            if (ok) ok = (r->load = calloc((size_t)r->n, sizeof *r->load)) != NULL;
        } else {
            body_load *l = k < r->n ? &r->load[k++] : NULL;
            ok = l && sscanf(line, "%d %la %la %la %la %la %la", &l->gid, &l->f.x, &l->f.y, &l->f.z, &l->t.x, &l->t.y,
                             &l->t.z) == 7;
        }
    }
    fclose(f);
    if (!ok || k != r->n || r->steps <= 0) {
        fprintf(stderr, "%s:%d: malformed reference\n", path, lineno);
        return -1;
    }
    return 0;
}

/* got against the reference: the same hash and contacts, the same bits in every load; on a
 * difference, how far off the loads are, to tell a rounding change from a broken law */
static void compare(int scene, const char *variant, const result *ref, const result *got)
{
    CHECK(got->steps == ref->steps);
    CHECK(got->hash == ref->hash);
    CHECK(got->contacts == ref->contacts);
    CHECK(got->n == ref->n);
    int bad = 0, worst = -1;
    double dmax = 0.0;
    for (int k = 0; k < got->n && k < ref->n; k++) {
        const body_load *a = &got->load[k], *b = &ref->load[k];
        if (a->gid != b->gid || memcmp(&a->f, &b->f, sizeof a->f) || memcmp(&a->t, &b->t, sizeof a->t)) {
            bad++;
            const double d = v3_norm(v3_sub(a->f, b->f)) / fmax(v3_norm(b->f), 1e-300);
            if (d >= dmax) dmax = d, worst = k;
        }
    }
    CHECK(bad == 0);
    printf("%-8s %-16s hash %016" PRIx64 " %s, %ld contacts, %d loads", scene_name[scene], variant, got->hash,
           got->hash == ref->hash ? "= ref" : "!= ref", got->contacts, got->n);
    if (bad)
        printf(": %d differ, the worst gid %d by %.3g of |F|\n", bad, got->load[worst].gid, dmax);
    else
        printf(" bit for bit\n");
}

int main(int argc, char **argv)
{
    const int write = argc > 1 && !strcmp(argv[1], "--write");
    const char *san = getenv("SD_SANITIZED");
    const int sanitized = san && *san && strcmp(san, "0");
    result first[SCENES];
    for (int s = 0; s < SCENES; s++) {
        first[s] = run_scene(s, 1, SD_SIMD_AUTO);
        CHECK(first[s].steps == scene_steps[s]);
        CHECK(first[s].contacts > 0);
    }
    /* what the scenes are, held loosely (the references hold them exactly): the bed has come to
     * rest (1.4 kg of spheres that fell ~5 cm on average, ~0.7 J, keep under 5e-5 J: a few mm/s),
     * the flume and the capture still move */
    printf("kinetic energy at the hash: bed %.3g J, flume %.3g J, capture %.3g J\n", first[0].ke, first[1].ke,
           first[2].ke);
    CHECK(first[SCENE_BED].ke < 5e-5);
    CHECK(first[SCENE_FLUME].ke > 1e-4);
    CHECK(first[SCENE_CAPTURE].ke > 1e-3);
    if (write) {
        for (int s = 0; s < SCENES; s++)
            if (write_ref(s, &first[s])) {
                fprintf(stderr, "cannot write tests/data/ref_%s.txt\n", scene_name[s]);
                return 1;
            }
        return check_report("test_reference --write");
    }
    for (int s = 0; s < SCENES; s++) {
        result ref;
        if (read_ref(s, &ref)) {
            CHECK(0);
            continue;
        }
        compare(s, "1 thread", &ref, &first[s]);
        for (int level = SD_SIMD_SCALAR; level <= SD_SIMD_AVX512; level++) {
            /* under the sanitizers (make asan), which run ~10x slower, 2 threads at the level
             * the CPU runs by default only: the full matrix runs in the plain build */
            if (sanitized && level != SD_SIMD_AUTO) continue;
            if (level > sd_cpu_simd_level()) continue; /* not on this CPU */
            for (int threads = sanitized ? 2 : 1; threads <= (sanitized ? 2 : 3); threads++) {
                char variant[48];
                snprintf(variant, sizeof variant, "%s, %d thr",
                         level == SD_SIMD_SCALAR ? "scalar" : level == SD_SIMD_AVX2 ? "avx2" : "avx512", threads);
                result r = run_scene(s, threads, level);
                compare(s, variant, &ref, &r);
                free(r.load);
            }
        }
        free(ref.load);
    }
    for (int s = 0; s < SCENES; s++)
        free(first[s].load);
    return check_report("test_reference");
}
