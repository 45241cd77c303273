/* Branching (issue 5): a run that continues from a flow-end checkpoint with another dam layout
 * (and other capture-phase settings) gives exactly the straight run of that layout: the same
 * state hash, trap ratio, pipe loads, time series, trajectories and VTK files, bit for bit.
 * Also: a flow-only run (the sweep's shared flow) stops at the checkpoint; a restart into the
 * checkpoint's own directory trims its series there; a scenario that differs in a key acting
 * before the capture, a damaged checkpoint and a missing one are refused, naming the file.
 * Reduced flume (examples/flume_small.yaml), shortened: dam at 0.5 m, 0.25 s packing and
 * capture. */
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "run.h"

static char root[] = "/tmp/sabodem_branch_XXXXXX";

static const char *common[] = {"output.png=false",      "output.vtk=true",         "flume.x_dam=0.5",
                               "flume.x_end=0.6",       "phases.packing_time=0.25", "phases.capture_limit=0.25",
                               "output.trajectory_ids=[0, 7, 100]", "output.trajectory_interval=0.005"};
#define N_COMMON ((int)(sizeof common / sizeof common[0]))

/* layout A: the intermediate beam at 30 mm; layout B: no intermediate beam, columns 25 mm
 * apart (more pipes), a longer capture and a shorter probe */
static const char *layout_a[] = {"dam.l_v=0.030"};
static const char *layout_b[] = {"dam.l_v=0", "dam.l_h=0.025", "phases.capture_limit=0.3", "water.probe=0.08"};

static int load(sd_scenario *s, const char *const *extra, int n_extra)
{
    const char *sets[32];
    int n = 0;
    for (int k = 0; k < N_COMMON; k++) sets[n++] = common[k];
    for (int k = 0; k < n_extra; k++) sets[n++] = extra[k];
    return sd_scenario_load(s, "examples/flume_small.yaml", sets, n, stderr);
}

typedef struct {
    int code;
    sd_run_result r;
    char dir[256];
    char err[4096];
} outcome;

static void run(const char *const *extra, int n_extra, const char *name, const char *ckpt_out, int stop_at_flow_end,
                const char *restart, outcome *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->dir, sizeof out->dir, "%s/%s", root, name);
    sd_scenario s;
    CHECK(load(&s, extra, n_extra) == 0);
    FILE *err = tmpfile();
    sd_run_opts o = {.outdir = out->dir, .err = err ? err : stderr};
    o.checkpoint_flow_end = ckpt_out;
    o.stop_at_flow_end = stop_at_flow_end;
    o.restart = restart;
    out->code = sd_run_scenario(&s, &o, &out->r);
    if (err) {
        rewind(err);
        size_t n = fread(out->err, 1, sizeof out->err - 1, err);
        out->err[n] = '\0';
        fclose(err);
        if (n) fprintf(stderr, "[%s] %s", name, out->err);
    }
    sd_scenario_free(&s);
}

static int same_file(const char *a, const char *b)
{
    FILE *f = fopen(a, "rb"), *g = fopen(b, "rb");
    int same = f && g;
    while (same) {
        int x = fgetc(f), y = fgetc(g);
        if (x != y) same = 0;
        if (x == EOF || y == EOF) break;
    }
    if (f) fclose(f);
    if (g) fclose(g);
    if (!same) fprintf(stderr, "files differ: %s %s\n", a, b);
    return same;
}

static void check_same_run(const outcome *a, const outcome *b)
{
    CHECK(a->code == 0 && b->code == 0);
    CHECK(a->r.state_hash == b->r.state_hash);
    CHECK(memcmp(&a->r.p_v, &b->r.p_v, sizeof(double)) == 0);
    CHECK(memcmp(a->r.p_v_class, b->r.p_v_class, sizeof a->r.p_v_class) == 0);
    CHECK(memcmp(&a->r.p_v_logs, &b->r.p_v_logs, sizeof(double)) == 0);
    CHECK(memcmp(&a->r.peak_dam_force, &b->r.peak_dam_force, sizeof(double)) == 0);
    CHECK(memcmp(a->r.phase_end, b->r.phase_end, sizeof a->r.phase_end) == 0);
    CHECK(a->r.steps == b->r.steps);
    CHECK(a->r.n_passed == b->r.n_passed && a->r.n_upstream == b->r.n_upstream);
    const char *files[] = {"series.csv", "trajectories.csv", "series.pvd", "walls.vtp", "spheres_packed.vtp",
                           "spheres_arrival.vtp", "cylinders_arrival.vtp", "spheres_final.vtp", "cylinders_final.vtp"};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        char p[600], q[600];
        snprintf(p, sizeof p, "%s/%s", a->dir, files[k]);
        snprintf(q, sizeof q, "%s/%s", b->dir, files[k]);
        CHECK(same_file(p, q));
    }
    printf("  %s = %s: P_V = %.6f, hash %016llx, %ld steps, peak pipe force %.4f N\n", a->dir, b->dir, a->r.p_v,
           (unsigned long long)a->r.state_hash, a->r.steps, a->r.peak_dam_force);
}

int main(void)
{
    CHECK(mkdtemp(root) != NULL);
    char ckpt_a[512], ckpt_f[512];
    snprintf(ckpt_a, sizeof ckpt_a, "%s/straight_a/flow_end.ckpt", root);
    snprintf(ckpt_f, sizeof ckpt_f, "%s/flow/flow_end.ckpt", root);

    /* the capture keys are exactly the layout and capture settings */
    CHECK(sd_scenario_is_capture_key("dam.l_v") && sd_scenario_is_capture_key("dam.beams") &&
          sd_scenario_is_capture_key("phases.capture_limit"));
    CHECK(!sd_scenario_is_capture_key("dam.pipe_diameter") && !sd_scenario_is_capture_key("logs.count") &&
          !sd_scenario_is_capture_key("flume.x_dam") && !sd_scenario_is_capture_key("solver.seed"));

    outcome sa, fl, ra, sb, rb, rb2, bad;
    /* straight run of layout A, writing the flow-end checkpoint on the way */
    run(layout_a, 1, "straight_a", ckpt_a, 0, NULL, &sa);
    CHECK(sa.code == 0 && access(ckpt_a, R_OK) == 0);
    CHECK(!sa.r.restarted && !sa.r.stopped_at_flow_end && sa.r.flow_wall > 0.0);
    /* the flow ended when the front reached the dam face: after the packing, before the limit */
    CHECK(sa.r.phase_end[1] > 0.26 && sa.r.phase_end[1] < 2.0);
    CHECK(sa.r.peak_dam_force > 0.0);

    /* a flow-only run, as a sweep makes it, with layout B's scenario (the layout does not matter) */
    run(layout_b, 4, "flow", ckpt_f, 1, NULL, &fl);
    CHECK(fl.code == 0 && fl.r.stopped_at_flow_end && access(ckpt_f, R_OK) == 0);
    CHECK(memcmp(&fl.r.phase_end[1], &sa.r.phase_end[1], sizeof(double)) == 0);

    /* layout A from the flow-only checkpoint = straight A */
    run(layout_a, 1, "restart_a", NULL, 0, ckpt_f, &ra);
    CHECK(ra.r.restarted);
    check_same_run(&sa, &ra);

    /* layout B: straight, and from straight A's checkpoint */
    run(layout_b, 4, "straight_b", NULL, 0, NULL, &sb);
    run(layout_b, 4, "restart_b", NULL, 0, ckpt_a, &rb);
    check_same_run(&sb, &rb);
    CHECK(sb.r.state_hash != sa.r.state_hash);

    /* layout B into the flow run's own directory: its outputs continue in place */
    run(layout_b, 4, "flow", NULL, 0, ckpt_f, &rb2);
    check_same_run(&sb, &rb2);

    /* refusals, each naming the checkpoint: a key that acts before the capture differs ... */
    const char *other[] = {"dam.l_v=0.030", "logs.count=5"};
    run(other, 2, "bad_key", NULL, 0, ckpt_a, &bad);
    CHECK(bad.code == 2 && strstr(bad.err, ckpt_a) && strstr(bad.err, "other scenario parameters"));
    const char *diam[] = {"dam.pipe_diameter=0.02"};
    run(diam, 1, "bad_diam", NULL, 0, ckpt_a, &bad);
    CHECK(bad.code == 2 && strstr(bad.err, ckpt_a));
    /* ... a damaged file (one byte flipped in the middle) ... */
    char damaged[512];
    snprintf(damaged, sizeof damaged, "%s/damaged.ckpt", root);
    {
        FILE *f = fopen(ckpt_a, "rb"), *g = fopen(damaged, "wb");
        CHECK(f && g);
        long n = 0;
        int ch;
        while (f && g && (ch = fgetc(f)) != EOF) fputc(n++ == 5000 ? ch ^ 0x10 : ch, g);
        if (f) fclose(f);
        if (g) fclose(g);
    }
    run(layout_a, 1, "bad_file", NULL, 0, damaged, &bad);
    CHECK(bad.code == 2 && strstr(bad.err, damaged) && strstr(bad.err, "checksum"));
    /* ... and a missing one; none of them leaves an output directory */
    char missing[512];
    snprintf(missing, sizeof missing, "%s/none.ckpt", root);
    run(layout_a, 1, "bad_missing", NULL, 0, missing, &bad);
    CHECK(bad.code == 2 && strstr(bad.err, missing));
    char p[600];
    snprintf(p, sizeof p, "%s/bad_file", root);
    CHECK(access(p, F_OK) != 0);
    snprintf(p, sizeof p, "%s/bad_key", root);
    CHECK(access(p, F_OK) != 0);

    /* the sweep's up-front check agrees */
    sd_scenario s;
    char msg[2048];
    CHECK(load(&s, layout_b, 4) == 0);
    CHECK(sd_run_check_restart(&s, ckpt_a, msg, sizeof msg) == 0);
    CHECK(sd_run_check_restart(&s, damaged, msg, sizeof msg) != 0 && strstr(msg, damaged));
    sd_scenario_free(&s);

    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf %s", root);
    if (!check_failures) CHECK(system(cmd) == 0);
    else fprintf(stderr, "outputs kept in %s\n", root);
    return check_report("test_branch");
}
