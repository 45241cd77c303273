/* OpenMP identity (issue: speed): the reduced flume with logs, every loop forced parallel,
 * gives the same bits on 1 and 2 threads, through packing, gate removal and flow. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "build.h"
#include "check.h"
#include "run.h"
#include "core/cpu.h"
#include "tuning.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* The switches (world_internal.h sd_switch) and the SIMD level the next worlds of this test
 * get: set before a run, applied to each world it makes (cfg_apply). */
static int cfg[SD_SWITCH_COUNT] = {
#define SD_X_SWITCH(name, def, doc) def,
    SD_SWITCH_TABLE(SD_X_SWITCH)
#undef SD_X_SWITCH
};
static int cfg_simd = SD_SIMD_AUTO;

static int cfg_set(sd_switch k, int v)
{
    const int was = cfg[k];
    cfg[k] = v;
    return was;
}

static void cfg_apply(sd_world *w)
{
    for (int k = 0; k < SD_SWITCH_COUNT; k++)
        sd_world_switch(w, (sd_switch)k, cfg[k]);
    sd_world_set_simd_level(w, cfg_simd);
}

static uint64_t run(int threads, long *contacts)
{
    sd_scenario s;
    /* a coarser step so that the spheres land on the bed and pile at the gate within the test */
    const char *sets[] = {"solver.dt=4e-5"};
    if (sd_scenario_load(&s, "examples/flume_small.yaml", sets, 1, stderr)) return 0;
    s.world.parallel_min = 0; /* parallel even for this small scene */
    s.world.threads = threads;
    sd_world *w;
    if (sd_world_create(&s.world, &w)) return 0;
    cfg_apply(w);
    sd_build_info info;
    if (sd_build_scene(w, &s, &info, stderr)) return 0;
    CHECK(sd_world_run(w, 6000) == SD_OK);
    sd_world_set_group_active(w, SD_GROUP_GATE, 0);
    CHECK(sd_world_run(w, 2000) == SD_OK);
    *contacts = sd_world_contact_count(w);
    uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    sd_scenario_free(&s);
    return h;
}

/* run()'s scene and steps, the thread count changed every `seg` steps (1, 2, 1, ...), and the
 * hash and the spring energy taken after each segment: the sphere pairs' springs move between
 * the serial near list, the owners' lists and their slots (contact.c springs_out) with the same
 * bits as run(). */
static uint64_t run_mixed(long seg, long *contacts)
{
    sd_scenario s;
    const char *sets[] = {"solver.dt=4e-5"};
    if (sd_scenario_load(&s, "examples/flume_small.yaml", sets, 1, stderr)) return 0;
    s.world.parallel_min = 0;
    sd_world *w;
    if (sd_world_create(&s.world, &w)) return 0;
    cfg_apply(w);
    sd_build_info info;
    if (sd_build_scene(w, &s, &info, stderr)) return 0;
    int outs[3] = {0, 0, 0}, lsqs[2] = {0, 0};
    /* (and each pair's sqrt_m_eff in its spring's slot or not, in turn every two segments:
     * switch SD_SW_SLOT_SQM, from the next pass) */
    for (long done = 0, k = 0; done < 8000; done += seg, k++) {
        sd_world_set_threads(w, 1 + (int)(k & 1));
        sd_world_switch(w, SD_SW_SLOT_SQM, (int)(k >> 1 & 1));
        if (done == 6000) sd_world_set_group_active(w, SD_GROUP_GATE, 0);
        CHECK(sd_world_run(w, seg) == SD_OK);
        outs[w->springs_out]++;
        if (w->springs_out) lsqs[w->springs_lsq != 0]++;
        (void)sd_world_state_hash(w);
        CHECK(w->springs_out == 0);
        CHECK(isfinite(sd_world_spring_energy(w)));
    }
#ifdef _OPENMP
    CHECK(outs[1] > 0 && outs[2] > 0); /* both lists held the springs */
#endif
    CHECK(lsqs[0] > 0 && lsqs[1] > 0); /* in both forms of slot */
    *contacts = sd_world_contact_count(w);
    uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    sd_scenario_free(&s);
    return h;
}

/* The whole driver (sd_run_scenario) on the reduced flume with water: packing, flow (fluid
 * forces computed inside the step by the thread that moves each body), capture with the dam;
 * every loop forced parallel. */
static sd_run_result run_driver(int threads)
{
    sd_run_result r;
    memset(&r, 0, sizeof r);
    sd_scenario s;
    const char *sets[] = {"output.vtk=false", "output.png=false", "phases.capture_limit=0.1"};
    if (sd_scenario_load(&s, "examples/flume_small.yaml", sets, 3, stderr)) return r;
    s.world.parallel_min = 0;
    s.world.threads = threads;
    s.world.tuning.simd = cfg_simd;
    char dir[] = "/tmp/sabodem_threads_XXXXXX";
    if (!mkdtemp(dir)) return r;
    sd_run_opts o = {.outdir = dir, .err = stderr};
    CHECK(sd_run_scenario(&s, &o, &r) == 0);
    sd_scenario_free(&s);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    CHECK(system(cmd) == 0);
    return r;
}

static int bed_verdict;  /* the front prefetch's trial on the last bed run (-1 none) */
static double bed_ratio; /* and its ratio, on / off */

/* A bed of 3150 spheres (10 and 5 mm, jittered lattice) collapsing in a box for `steps` steps:
 * over ten thousand candidate pairs, so the parallel body-body pass splits the bodies into
 * owned ranges with cross pairs between them. */
static uint64_t run_bed(int threads, long steps, long *contacts, int *pairs, int *cross)
{
    sd_world_def d = sd_world_def_default();
    d.gravity = v3(0, 0, -9.81);
    d.parallel_min = 0;
    d.threads = threads;
    sd_world *w;
    if (sd_world_create(&d, &w)) return 0;
    cfg_apply(w);
    const double pitch = 0.0100, L = 15 * pitch + 0.002;
    uint64_t st = 7;
    for (int k = 0; k < 14; k++)
        for (int j = 0; j < 15; j++)
            for (int i = 0; i < 15; i++) {
                st = st * 6364136223846793005ULL + 1442695040888963407ULL;
                sd_sphere_def s = sd_sphere_def_default();
                s.radius = (st >> 60) < 4 ? 0.0025 : 0.005;
                s.pos = v3((i + 0.5) * pitch + 1e-4 * (double)((st >> 40) & 7), (j + 0.5) * pitch + 1e-3,
                           (k + 0.5) * pitch);
                sd_world_add_sphere(w, &s);
            }
    sd_vec3 c[8] = {v3(0, 0, 0),   v3(L, 0, 0),   v3(L, L, 0),   v3(0, L, 0),
                    v3(0, 0, 0.3), v3(L, 0, 0.3), v3(L, L, 0.3), v3(0, L, 0.3)};
    const int q[5][4] = {{0, 1, 2, 3}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    for (int f = 0; f < 5; f++) {
        sd_world_add_triangle(w, c[q[f][0]], c[q[f][1]], c[q[f][2]], 0);
        sd_world_add_triangle(w, c[q[f][0]], c[q[f][2]], c[q[f][3]], 0);
    }
    CHECK(sd_world_run(w, steps) == SD_OK);
    bed_verdict = sd_front_prefetch_verdict(w, &bed_ratio);
    *contacts = sd_world_contact_count(w);
    *pairs = w->bb.n;
    *cross = 0;
    for (int t = 0; w->owned && t < w->owned->T; t++) /* each owner's block of cross pairs */
        *cross += w->owned->xb[t] - w->owned->K[t];
    uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    return h;
}

/* One log (r 5 mm, 100 mm long, along x) and one sphere (r 5 mm) per case, the cases far
 * apart, no gravity, spinning and sliding so that the law has work: the sphere on the log's
 * side, on each end face, beyond each end rim, near a rim without touching, inside the log, on
 * its axis, and 0.2 mm clear of an end face and of the side (near pairs that the apart test,
 * done in lanes there, turns away). Runs `steps` steps; returns the state hash and, in seen, a bit per sphere-log
 * contact feature held at the end (1 << feature). */
static uint64_t run_sc_cases(int steps, int *seen)
{
    static const double at[10][3] = {
        {0.0, 0.0, 0.0095},      /* side (feature 0) */
        {-0.0545, 0.001, 0.0},   /* end face at -hl (1) */
        {0.0545, 0.0, 0.002},    /* end face at +hl (2) */
        {-0.053, 0.007, 0.0},    /* beyond the rim at -hl (3) */
        {0.053, 0.0, -0.007},    /* beyond the rim at +hl (4) */
        {0.054, 0.0, 0.009},     /* near the +hl rim, 5.66 mm from it: no contact */
        {0.02, 0.0, 0.003},      /* centre inside the log */
        {0.01, 0.0, 0.0},        /* centre on the axis */
        {0.0552, 0.0, 0.0},      /* 0.2 mm beyond the +hl end face: a near pair, apart */
        {0.0, 0.0102, 0.0},      /* 0.2 mm off the side: a near pair, apart */
    };
    sd_world_def d = sd_world_def_default();
    d.gravity = v3(0, 0, 0);
    d.threads = 1;
    sd_world *w;
    if (sd_world_create(&d, &w)) return 0;
    cfg_apply(w);
    for (int c = 0; c < 10; c++) {
        const double y0 = 0.3 * c;
        sd_cylinder_def cy = sd_cylinder_def_default();
        cy.pos = v3(0.0, y0, 0.0);
        cy.axis = v3(1.0, 0.0, 0.0);
        cy.radius = 0.005;
        cy.length = 0.1;
        cy.density = 800.0;
        cy.omega = v3(0.5, 0.2 * c, -0.3);
        sd_world_add_cylinder(w, &cy);
        sd_sphere_def sp = sd_sphere_def_default();
        sp.pos = v3(at[c][0], y0 + at[c][1], at[c][2]);
        sp.radius = 0.005;
        sp.density = 1900.0;
        sp.vel = v3(0.01 * (c + 1), -0.004, 0.002);
        sp.omega = v3(1.0, -2.0, 0.5 * c);
        sd_world_add_sphere(w, &sp);
    }
    CHECK(sd_world_run(w, steps) == SD_OK);
    *seen = 0;
    for (int k = 0; k < w->bb.n; k++)
        if (w->bb.p[k].kind == SD_PAIR_SC && w->bb.hist[w->bb.p[k].off].feature >= 0)
            *seen |= 1 << w->bb.hist[w->bb.p[k].off].feature;
    const uint64_t h = sd_world_state_hash(w);
    sd_world_destroy(w);
    return h;
}

/* The front prefetch's trial (sd_pf_trial) driven by hand with made-up pass times (off t_off a
 * step; on t_on times 0.8, 0.9, ... 1.5 in the trial's groups 0 .. 7, so that the ratio's median
 * over the groups is that of the middle two, 1.15 t_on / t_off): its blocks run off on on off,
 * each the blocks' steps long; the verdict is on exactly when that median is below 1; no new
 * trial before SD_PF_RETRY steps, one at once when the body count moves by more than a quarter. */
static void check_pf_trial(double t_on, double t_off)
{
    static const int order[4] = {0, 1, 1, 0};
    sd_world_def d = sd_world_def_default();
    sd_world *w;
    CHECK(sd_world_create(&d, &w) == SD_OK);
    if (!w) return;
    const int n = SD_PF_MIN_BODIES + 100;
    for (int i = 0; i < n; i++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = 0.004;
        s.pos = v3(0.01 * (i % 50), 0.01 * (i / 50), 0.0);
        sd_world_add_sphere(w, &s);
    }
    CHECK(w->sw[SD_SW_PREFETCH] == SD_PREFETCH_AUTO); /* (a new world's) */
    CHECK(sd_front_prefetch_verdict(w, NULL) == -1);
    int steps = 0, bad = 0;
    while (sd_front_prefetch_verdict(w, NULL) < 0 && steps < 10000) {
        sd_front_prefetch_trial_before(w);
        CHECK(w->pf.blk >= 0);
        const int on = sd_front_prefetch_on(w);
        bad += on != order[w->pf.blk & 3];
        sd_front_prefetch_trial_after(w, on ? t_on * (0.8 + 0.1 * (w->pf.blk / 4)) : t_off);
        w->step++;
        steps++;
    }
    double r = 0.0;
    const int v = sd_front_prefetch_verdict(w, &r);
    printf("prefetch trial, pass %.2f s on and %.2f s off: verdict %d, ratio %.4f after %d steps (%d a block)\n", t_on,
           t_off, v, r, steps, w->pf.blk_steps);
    CHECK(bad == 0);
    CHECK(steps == 4 * SD_PF_GROUPS * w->pf.blk_steps);
    CHECK(w->pf.blk_steps == 100); /* (2e6 particle-steps a block, at most 100 steps) */
    const double want = 1.15 * t_on / t_off;
    CHECK(v == (want < 1.0));
    CHECK(fabs(r - want) < 1e-12);
    CHECK(sd_front_prefetch_on(w) == v);
    /* no new trial until SD_PF_RETRY steps on */
    CHECK(w->pf.next == w->step - 1 + SD_PF_RETRY);
    w->step = w->pf.next - 1;
    sd_front_prefetch_trial_before(w);
    CHECK(w->pf.blk == -1);
    w->step++;
    sd_front_prefetch_trial_before(w);
    CHECK(w->pf.blk == 0);
    w->pf.blk = -1;
    /* ... or the body count moved by more than a quarter */
    w->pf.next = w->step + 1000;
    w->pf.n = n - n / 3;
    sd_front_prefetch_trial_before(w);
    CHECK(w->pf.blk == 0);
    /* a setting other than auto runs no trial, and ends one that was running */
    CHECK(w->pf.blk == 0);
    sd_world_switch(w, SD_SW_PREFETCH, SD_PREFETCH_OFF);
    sd_front_prefetch_trial_before(w);
    CHECK(w->pf.blk == -1);
    w->pf.n = 1;
    sd_front_prefetch_trial_before(w);
    CHECK(w->pf.blk == -1);
    CHECK(sd_front_prefetch_on(w) == 0);
    sd_world_destroy(w);
}

int main(void)
{
    CHECK(SD_PF_GROUPS == 8); /* (check_pf_trial's made-up times) */
    check_pf_trial(0.8, 1.0);
    check_pf_trial(0.9, 1.0);
    {
        long c[3] = {0, 0, 0};
        int np = 0, nc[3] = {0, 0, 0};
        uint64_t h[3];
        for (int t = 0; t < 3; t++)
            h[t] = run_bed(t + 1, 1500, &c[t], &np, &nc[t]);
        printf("dense bed of 3150 spheres, %d candidate pairs: hash %016llx (1 thread), %016llx (2), %016llx (3); "
               "%ld contacts; %d and %d cross pairs on 2 and 3 threads\n",
               np, (unsigned long long)h[0], (unsigned long long)h[1], (unsigned long long)h[2], c[0], nc[1], nc[2]);
        CHECK(np > 10000);
        CHECK(c[0] > 300);
#ifdef _OPENMP
        /* the owned ranges really were split (about 100-130 cross pairs on 2 threads, by where
         * the measured times put the split) */
        CHECK(nc[0] == 0 && nc[1] > 50 && nc[2] > nc[1]);
#endif
        CHECK(h[0] == h[1] && h[0] == h[2]);
        CHECK(c[0] == c[1] && c[0] == c[2]);
    }
    long c1 = 0, c2 = 0;
    uint64_t h1 = run(1, &c1);
    uint64_t h2 = run(2, &c2);
    printf("1 thread: hash %016llx, %ld contacts; 2 threads: hash %016llx, %ld contacts\n", (unsigned long long)h1, c1,
           (unsigned long long)h2, c2);
    CHECK(h1 != 0);
    CHECK(c1 > 100);
    CHECK(h1 == h2);
    CHECK(c1 == c2);
    {
        long cm = 0;
        const uint64_t hm = run_mixed(500, &cm);
        printf("1 and 2 threads in turn every 500 steps, hashed between: hash %016llx, %ld contacts\n",
               (unsigned long long)hm, cm);
        CHECK(hm == h1 && cm == c1);
        /* and with the springs left in their slots (switch SD_SW_SPRINGS_LIST) */
        const int was = cfg_set(SD_SW_SPRINGS_LIST, 0);
        long cs = 0;
        const uint64_t hs = run(2, &cs);
        cfg_set(SD_SW_SPRINGS_LIST, was);
        printf("springs in their slots: hash %016llx, %ld contacts\n", (unsigned long long)hs, cs);
        CHECK(hs == h1 && cs == c1);
        /* and in the list's order without the pairs' sqrt_m_eff in their slots (switch
         * SD_SW_SLOT_SQM), on 1 and 2 threads */
        const int sq = cfg_set(SD_SW_SLOT_SQM, 0);
        long cq1 = 0, cq2 = 0;
        const uint64_t hq1 = run(1, &cq1), hq2 = run(2, &cq2);
        cfg_set(SD_SW_SLOT_SQM, sq);
        printf("sqrt_m_eff with the records only: hash %016llx / %016llx, %ld contacts\n", (unsigned long long)hq1,
               (unsigned long long)hq2, cq1);
        CHECK(hq1 == h1 && hq2 == h1 && cq1 == c1 && cq2 == c1);
    }
    {
        /* every level of the hand-written SIMD kernels the CPU has (scalar; AVX2 filter, gather
         * and sums; AVX-512 filter, gather, sums and cell scan), on the same scene: log pairs sit
         * among the sphere pairs of a chunk, where the SIMD filters hand them to the scalar
         * path and the sums take the lanes between them */
        for (int level = SD_SIMD_SCALAR; level <= SD_SIMD_AVX512; level++) {
            if (level > sd_cpu_simd_level()) continue; /* not on this CPU */
            cfg_simd = level;
            long cl = 0;
            const uint64_t hl = run(1, &cl);
            printf("SIMD kernels at level %d (1 scalar, 2 AVX2, 3 AVX-512): hash %016llx, %ld contacts\n", level,
                   (unsigned long long)hl, cl);
            CHECK(hl == h1);
            CHECK(cl == c1);
        }
        cfg_simd = SD_SIMD_AUTO;
    }
    {
        /* the body-body pass's prefetch of the bodies' front forced on, forced off, and auto
         * (tried on and off in blocks during the run, sd_pf_trial): a hint, the same bits on 1 and
         * 2 threads, on the log flume and on the dense bed */
        const int was = cfg_set(SD_SW_PREFETCH, SD_PREFETCH_ON);
        long cp1 = 0, cp2 = 0, cb = 0;
        int npb = 0, ncb = 0;
        const uint64_t hp1 = run(1, &cp1), hp2 = run(2, &cp2), hb = run_bed(2, 3400, &cb, &npb, &ncb);
        const int v_on = bed_verdict;
        cfg_set(SD_SW_PREFETCH, SD_PREFETCH_OFF);
        long cbf = 0;
        const uint64_t hbf = run_bed(2, 3400, &cbf, &npb, &ncb);
        const int v_off = bed_verdict;
        cfg_set(SD_SW_PREFETCH, SD_PREFETCH_AUTO);
        long cb0 = 0;
        int npb0 = 0, ncb0 = 0;
        const uint64_t hb0 = run_bed(2, 3400, &cb0, &npb0, &ncb0);
        cfg_set(SD_SW_PREFETCH, was);
        /* auto: the 3150 spheres are tried off and on in their first 3,200 steps (32 blocks of 100) */
        printf("front prefetch forced off: bed hash %016llx; auto: trial verdict %d, on / off %.3f\n",
               (unsigned long long)hbf, bed_verdict, bed_ratio);
        CHECK(v_on == -1 && v_off == -1);
        CHECK(bed_verdict == 0 || bed_verdict == 1);
        CHECK(bed_ratio > 0.0 && bed_ratio < 100.0 && bed_verdict == (bed_ratio < 1.0));
        CHECK(hbf == hb0 && cbf == cb0);
        printf("front prefetch on: log flume hash %016llx (1 thread), %016llx (2); bed hash %016llx (off: %016llx)\n",
               (unsigned long long)hp1, (unsigned long long)hp2, (unsigned long long)hb, (unsigned long long)hb0);
        CHECK(hp1 == h1 && hp2 == h1 && cp1 == c1 && cp2 == c1);
        CHECK(hb == hb0 && cb == cb0);
    }
    {
        /* the sphere-log pairs touching at one point through the law in lanes and through
         * apply_manifold: the log flume above, the same bits */
        long redo0 = 0, redo1 = 0;
        const long lanes0 = sd_contact_sc_lanes_count(&redo0);
        const int was = cfg_set(SD_SW_SC_LANES, 0);
        long cg = 0;
        const uint64_t hg = run(1, &cg);
        const long lanes1 = sd_contact_sc_lanes_count(&redo1);
        cfg_set(SD_SW_SC_LANES, was);
        printf("sphere-log lanes: %ld run (%ld sent back to the scalar law) in the runs above; all through "
               "apply_manifold: hash %016llx\n",
               lanes0, redo0, (unsigned long long)hg);
        CHECK(lanes0 > 1000);    /* the lanes really ran above */
        CHECK(lanes1 == lanes0); /* and not with them off */
        CHECK(hg == h1 && cg == c1);
    }
    {
        /* the sphere-log contacts' geometry in AVX2 lanes (contact.c sc_geom256: side, end face
         * and rim in lanes, the rest pair by pair) against sd_geom_sphere_cyl pair by pair: every
         * case, and the log flume above, the same bits */
        const long g0 = sd_contact_sc_geom_count();
        int seen_on = 0, seen_off = 0;
        const uint64_t hc_on = run_sc_cases(40, &seen_on);
        const long g1 = sd_contact_sc_geom_count();
        const int was = cfg_set(SD_SW_SC_GEOM, 0);
        const uint64_t hc_off = run_sc_cases(40, &seen_off);
        long cg = 0;
        const uint64_t hg = run(1, &cg);
        const long g2 = sd_contact_sc_geom_count();
        cfg_set(SD_SW_SC_GEOM, was);
        printf("sphere-log geometry in lanes: %ld lanes in the runs above, %ld on the cases (features held "
               "0x%x); pair by pair: cases hash %016llx against %016llx, log flume %016llx\n",
               g0, g1 - g0, seen_on, (unsigned long long)hc_off, (unsigned long long)hc_on, (unsigned long long)hg);
        CHECK(hc_on != 0 && hc_on == hc_off);
        CHECK(seen_on == 0x1f && seen_off == 0x1f); /* side, both end faces, both rims */
        CHECK(hg == h1 && cg == c1);
        CHECK(g2 == g1); /* none with the lanes' geometry off */
        if (sd_tuning_simd_level(SD_SIMD_AUTO, sd_cpu_simd_level(), sd_cpu_is_amd()) >= SD_SIMD_AVX2) {
            CHECK(g0 > 1000);          /* the lanes' geometry ran on the log flume */
            CHECK(g1 - g0 >= 5 * 40); /* and on the five touching cases, every step */
        }
    }
    {
        /* the sphere law's spring loop in AVX2 lanes (contact.c ss_law_spring256: a group where
         * no lane slides or passes the limit without the limit's root and division) against the
         * compiler's loop: the log flume above, the same bits */
        long sk = 0;
        const long g = sd_avx2_ss_law_count(&sk);
        const int was = cfg_set(SD_SW_SS_LAW256, 0);
        long cg = 0;
        const uint64_t hg = run(1, &cg);
        const long g2 = sd_avx2_ss_law_count(NULL);
        cfg_set(SD_SW_SS_LAW256, was);
        printf("sphere law's spring loop in lanes: %ld groups on this thread above, %ld without the limit; "
               "the compiler's loop: log flume %016llx\n",
               g, sk, (unsigned long long)hg);
        CHECK(hg == h1 && cg == c1);
        CHECK(g2 == g); /* none with it off */
        if (sd_tuning_simd_level(SD_SIMD_AUTO, sd_cpu_simd_level(), sd_cpu_is_amd()) == SD_SIMD_AVX2) {
            CHECK(g > 1000);         /* it ran */
            CHECK(sk > 0 && sk < g); /* both kinds of group */
        }
    }
    {
        sd_run_result a = run_driver(1), b = run_driver(2);
        printf("driver with water: 1 thread hash %016llx P_V %.6f, 2 threads hash %016llx P_V %.6f; flow ended at "
               "%.4f s, %ld steps\n",
               (unsigned long long)a.state_hash, a.p_v, (unsigned long long)b.state_hash, b.p_v, a.phase_end[1],
               a.steps);
        CHECK(a.state_hash != 0);
        CHECK(a.phase_end[1] > a.phase_end[0] && a.phase_end[2] > a.phase_end[1]); /* flow and capture ran */
        CHECK(a.state_hash == b.state_hash);
        CHECK(a.p_v == b.p_v && a.steps == b.steps);
        /* the fluid forces' AVX-512 form (run.c) against the batch's scalar one, with the
         * other kernels (those the CPU has), on the whole driver: flow and capture profiles, wet and dry */
        cfg_simd = SD_SIMD_SCALAR;
        sd_run_result c = run_driver(2);
        cfg_simd = SD_SIMD_AUTO;
        printf("driver with the SIMD kernels off: hash %016llx P_V %.6f\n", (unsigned long long)c.state_hash, c.p_v);
        CHECK(c.state_hash == a.state_hash);
        CHECK(c.p_v == a.p_v && c.steps == a.steps);
    }
    return check_report("test_threads");
}
