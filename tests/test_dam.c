/* The dam's keys and members (docs/scenario.md "The dam", docs/loads.md), against closed forms:
 * - the paper's scenario builds the same pipes as before these keys existed, bit for bit (the
 *   values below were printed by the code of commit fa6741e);
 * - dam.n_columns: n columns centred, every clear gap (W - n d)/(n + 1), the walls' too;
 * - dam.beam_axes, dam.beam_gaps (an axis is its gap + d/2 above the top of what is below),
 *   the top beam kept unless dam.top_beam is false, dam.beams in any order; the columns reach
 *   the top of the highest beam, the wall top without one;
 * - a key given with --set overrides the file's key of the same group, two in one place are
 *   refused (the messages themselves: tests/input_test.sh);
 * - the least distance of two segments (the members' overlap check);
 * - a member at any orientation is a fixed cylinder in the contacts: a sphere pressed into an
 *   inclined or skew member by a known overlap gets k_n δ along the normal from the axis, at
 *   the foot of its centre; one dropped onto a 30° member first touches it where the closed
 *   form says, then rolls down it at (5/7) g sin θ (tan φ ≥ (2/7) tan θ) or slides at
 *   g (sin θ - tan φ cos θ);
 * - its loads: span = its length, the resultant's position from its first end, the moment of
 *   a sphere resting on it P a b / L. */
#include <string.h>

#include <cjson/cJSON.h>

#include "build.h"
#include "check.h"
#include "core/vmath.h"
#include "pipe_loads.h"
#include "scenario.h"

/* A flume with nothing in it but the dam (dam keys follow). */
#define FLUME                                                                                                       \
    "flume: {on: true, width: 0.3, wall_height: 0.5, x_gate: 0.35, x_dam: 1.0, x_end: 1.5, pack_height: 0.3}\n"      \
    "spheres: {diameters: [0.02], counts: [0]}\nlogs: {count: 0}\nwater: {on: false}\n"

/* the scenario from text and --set overrides; 0, or -1 with the loader's messages in err */
static int load(sd_scenario *s, const char *yaml, const char *const *sets, int n_sets, char *err, size_t n_err)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f) return -1;
    const int rc = sd_scenario_load_string(s, yaml, "t.yaml", sets, n_sets, f);
    fclose(f);
    snprintf(err, n_err, "%s", buf ? buf : "");
    free(buf);
    if (rc) printf("loader: %s", err);
    return rc;
}

static int same_bits(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* The pipes of examples/shibuya2009.yaml for dam.l_v = 0.04, 0 and 0.03: kind (1 column, 0
 * beam), centre, axis, radius, length, mass, printed with %a by the code before this change. */
typedef struct {
    int kind;
    double c[3], a[3], r, len, mass;
} pin;
static const pin pins_lv40[] = {
    {1, {0x1.009374bc6a7fp+2, 0x1.89374bc6a7ef8p-5, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.db22d0e560418p-4, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.78d4fdf3b645ap-3, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.020c49ba5e354p-2, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {0, {0x1.009374bc6a7fp+2, 0x1.3333333333333p-3, 0x1.916872b020c4ap-5}, {0x0p+0, 0x1.ffffffffffffep-1, 0x1p-52},
     0x1.26e978d4fdf3bp-7, 0x1.3333333333333p-2, 0x1.32d41baea6f63p-1},
    {0, {0x1.009374bc6a7fp+2, 0x1.3333333333333p-3, 0x1.04189374bc6a8p-3}, {0x0p+0, 0x1.ffffffffffffep-1, 0x1p-52},
     0x1.26e978d4fdf3bp-7, 0x1.3333333333333p-2, 0x1.32d41baea6f63p-1},
};
static const pin pins_lv0[] = {
    {1, {0x1.009374bc6a7fp+2, 0x1.89374bc6a7ef8p-5, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.db22d0e560418p-4, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.78d4fdf3b645ap-3, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.020c49ba5e354p-2, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {0, {0x1.009374bc6a7fp+2, 0x1.3333333333333p-3, 0x1.04189374bc6a8p-3}, {0x0p+0, 0x1.ffffffffffffep-1, 0x1p-52},
     0x1.26e978d4fdf3bp-7, 0x1.3333333333333p-2, 0x1.32d41baea6f63p-1},
};
static const pin pins_lv30[] = {
    {1, {0x1.009374bc6a7fp+2, 0x1.89374bc6a7ef8p-5, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.db22d0e560418p-4, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.78d4fdf3b645ap-3, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {1, {0x1.009374bc6a7fp+2, 0x1.020c49ba5e354p-2, 0x1.16872b020c49cp-4}, {0x0p+0, 0x0p+0, 0x1p+0},
     0x1.26e978d4fdf3bp-7, 0x1.16872b020c49cp-3, 0x1.1630f38d48df4p-2},
    {0, {0x1.009374bc6a7fp+2, 0x1.3333333333333p-3, 0x1.3f7ced916872bp-5}, {0x0p+0, 0x1.ffffffffffffep-1, 0x1p-52},
     0x1.26e978d4fdf3bp-7, 0x1.3333333333333p-2, 0x1.32d41baea6f63p-1},
    {0, {0x1.009374bc6a7fp+2, 0x1.3333333333333p-3, 0x1.04189374bc6a8p-3}, {0x0p+0, 0x1.ffffffffffffep-1, 0x1p-52},
     0x1.26e978d4fdf3bp-7, 0x1.3333333333333p-2, 0x1.32d41baea6f63p-1},
};

static void paper_dam_unchanged(void)
{
    static const char *const lv[3] = {"dam.l_v=0.04", "dam.l_v=0", "dam.l_v=0.03"};
    const pin *const want[3] = {pins_lv40, pins_lv0, pins_lv30};
    const int n_want[3] = {6, 5, 6};
    for (int c = 0; c < 3; c++) {
        sd_scenario s;
        const char *set[1] = {lv[c]};
        CHECK(sd_scenario_load(&s, "examples/shibuya2009.yaml", set, 1, stderr) == 0);
        sd_world *w;
        CHECK(sd_world_create(&s.world, &w) == SD_OK);
        sd_build_info info;
        memset(&info, 0, sizeof info);
        CHECK(sd_build_dam(w, &s, &info) == SD_OK);
        CHECK(info.n_pipes == n_want[c]);
        for (int k = 0; k < info.n_pipes && k < n_want[c]; k++) {
            const pin *p = &want[c][k];
            sd_body_state b = {0};
            CHECK(sd_world_body(w, info.pipe_gid[k], &b) == SD_OK);
            CHECK(info.pipe_kind[k] == p->kind && b.fixed);
            CHECK(same_bits(b.pos.x, p->c[0]) && same_bits(b.pos.y, p->c[1]) && same_bits(b.pos.z, p->c[2]));
            CHECK(same_bits(b.axis.x, p->a[0]) && same_bits(b.axis.y, p->a[1]) && same_bits(b.axis.z, p->a[2]));
            CHECK(same_bits(b.radius, p->r) && same_bits(b.length, p->len) && same_bits(b.mass, p->mass));
        }
        sd_world_destroy(w);
        sd_scenario_free(&s);
    }
}

static void column_keys(void)
{
    char err[2048];
    sd_scenario s;
    sd_dam_grid g;
    /* 5 columns of 18 mm across 300 mm: gaps (0.3 - 0.09)/6 = 35 mm, axes 44 + 53 k mm */
    CHECK(load(&s, FLUME "dam: {n_columns: 5}\n", NULL, 0, err, sizeof err) == 0);
    CHECK(sd_build_dam_grid(&s, &g) == 0);
    CHECK(g.n_col == 5);
    const double d = 0.018, W = 0.3, gap = (W - 5 * d) / 6;
    CHECK_NEAR(gap, 0.035, 1e-15);
    for (int k = 0; k < g.n_col; k++)
        CHECK_NEAR(g.col_y[k], gap + 0.5 * d + k * (gap + d), 1e-15);
    CHECK_NEAR(g.col_y[2], 0.15, 0.0); /* the middle one on the centre line, exactly */
    CHECK_NEAR(g.col_y[0] - 0.5 * d, gap, 1e-15);
    CHECK_NEAR(W - g.col_y[4] - 0.5 * d, gap, 1e-15);
    sd_scenario_free(&s);
    /* one column: on the centre line; none: a dam of beams */
    CHECK(load(&s, FLUME "dam: {n_columns: 1}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_col == 1 && g.col_y[0] == 0.15);
    sd_scenario_free(&s);
    CHECK(load(&s, FLUME "dam: {n_columns: 0}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_col == 0 && g.n_beam == 2);
    sd_scenario_free(&s);
    /* explicit positions in any order: ascending */
    CHECK(load(&s, FLUME "dam: {columns: [0.2, 0.1]}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_col == 2 && g.col_y[0] == 0.1 && g.col_y[1] == 0.2);
    sd_scenario_free(&s);
    /* --set dam.n_columns overrides the file's dam.l_h (the paper's scenario), and the file's
     * dam.columns; in the same place they are refused */
    const char *set5[1] = {"dam.n_columns=5"};
    CHECK(load(&s, FLUME "dam: {l_h: 0.03}\n", set5, 1, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_col == 5);
    sd_scenario_free(&s);
    CHECK(load(&s, FLUME "dam: {columns: [0.1, 0.2]}\n", set5, 1, err, sizeof err) == 0);
    CHECK(s.n_columns == 0 && s.column_count == 5);
    sd_scenario_free(&s);
    const char *seth[1] = {"dam.l_h=0.03"};
    CHECK(load(&s, FLUME "dam: {n_columns: 3}\n", seth, 1, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_col == 6); /* ceil((0.3 - 0.03)/0.048) */
    sd_scenario_free(&s);
    CHECK(load(&s, FLUME "dam: {n_columns: 3, l_h: 0.03}\n", NULL, 0, err, sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:5:26: dam.n_columns and dam.l_h both give the columns") != NULL);
}

static void beam_keys(void)
{
    char err[2048];
    sd_scenario s;
    sd_dam_grid g;
    const double r = 0.009;
    /* axes as given, then the top beam (underside 0.118): columns to its top */
    CHECK(load(&s, FLUME "dam: {beam_axes: [0.09, 0.05]}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 3 && g.top_beam);
    CHECK(g.beam_z[0] == 0.05 && g.beam_z[1] == 0.09);
    CHECK_NEAR(g.beam_z[2], 0.118 + r, 1e-15);
    CHECK_NEAR(g.col_top, 0.118 + 2 * r, 1e-15);
    sd_scenario_free(&s);
    /* gaps: bed to the first underside 30 mm, then 40 mm to the next: axes 30 + 9 and
     * 30 + 18 + 40 + 9 mm, each gap read back from the axes */
    CHECK(load(&s, FLUME "dam: {beam_gaps: [0.03, 0.04]}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 3 && g.top_beam);
    CHECK_NEAR(g.beam_z[0], 0.03 + r, 1e-15);
    CHECK_NEAR(g.beam_z[1], 0.03 + 2 * r + 0.04 + r, 1e-15);
    CHECK_NEAR(g.beam_z[0] - r, 0.03, 1e-15);
    CHECK_NEAR((g.beam_z[1] - r) - (g.beam_z[0] + r), 0.04, 1e-15);
    CHECK_NEAR(g.beam_z[2], 0.118 + r, 1e-15);
    sd_scenario_free(&s);
    /* without the top beam: the columns reach the top of the highest beam */
    CHECK(load(&s, FLUME "dam: {beam_gaps: [0.03, 0.04], top_beam: false}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 2 && !g.top_beam);
    CHECK_NEAR(g.col_top, 0.03 + 2 * r + 0.04 + 2 * r, 1e-15);
    sd_scenario_free(&s);
    /* no beam at all: columns to the wall top (a slit dam) */
    CHECK(load(&s, FLUME "dam: {l_v: 0, top_beam: false}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 0 && g.n_col == 4 && g.col_top == 0.5);
    sd_scenario_free(&s);
    /* dam.beams: every beam by its underside, in any order, no top beam added */
    CHECK(load(&s, FLUME "dam: {beams: [0.118, 0.04]}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 2 && !g.top_beam);
    CHECK_NEAR(g.beam_z[0], 0.04 + r, 1e-15);
    CHECK_NEAR(g.beam_z[1], 0.118 + r, 1e-15);
    CHECK_NEAR(g.col_top, 0.118 + 2 * r, 1e-15);
    sd_scenario_free(&s);
    /* l_v with the top beam, as the paper's scenarios (test_flume) */
    CHECK(load(&s, FLUME "dam: {l_v: 0.03, top_beam: 0.1}\n", NULL, 0, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 2 && g.beam_z[0] == 0.03 + r && g.beam_z[1] == 0.1 + r);
    sd_scenario_free(&s);
    /* --set of one beam key overrides the file's, of any other beam key */
    const char *setv[1] = {"dam.l_v=0.03"};
    CHECK(load(&s, FLUME "dam: {beam_axes: [0.05, 0.09]}\n", setv, 1, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(s.n_beam_axes == 0 && g.n_beam == 2 && g.beam_z[0] == 0.03 + r);
    sd_scenario_free(&s);
    const char *setb[1] = {"dam.beams=[0.05]"};
    CHECK(load(&s, FLUME "dam: {l_v: 0.04, top_beam: 0.1}\n", setb, 1, err, sizeof err) == 0);
    sd_build_dam_grid(&s, &g);
    CHECK(g.n_beam == 1 && g.beam_z[0] == 0.05 + r);
    sd_scenario_free(&s);
    /* the value false, and its echo */
    const char *setf[1] = {"dam.top_beam=false"};
    CHECK(load(&s, FLUME, setf, 1, err, sizeof err) == 0);
    CHECK(!s.top_beam_on);
    sd_scenario_free(&s);
}

/* The new keys are capture keys: two layouts share a flow (the branch hash) and differ as runs
 * (the run hash), a member's diameter included; the summary echoes them. */
static void capture_keys(void)
{
    char err[2048];
    sd_scenario a, b, c;
    CHECK(sd_scenario_is_capture_key("dam.n_columns") && sd_scenario_is_capture_key("dam.beam_axes") &&
          sd_scenario_is_capture_key("dam.beam_gaps") && sd_scenario_is_capture_key("dam.members"));
    CHECK(load(&a, FLUME "dam: {l_h: 0.05}\n", NULL, 0, err, sizeof err) == 0);
    CHECK(load(&b, FLUME "dam: {n_columns: 5, beam_gaps: [0.03], top_beam: false, members: [{from: [1.1, 0.1, 0], to: "
                   "[1.1, 0.1, 0.2], diameter: 0.01}]}\n",
               NULL, 0, err, sizeof err) == 0);
    CHECK(load(&c, FLUME "dam: {n_columns: 5, beam_gaps: [0.03], top_beam: false, members: [{from: [1.1, 0.1, 0], to: "
                   "[1.1, 0.1, 0.2], diameter: 0.012}]}\n",
               NULL, 0, err, sizeof err) == 0);
    CHECK(sd_scenario_branch_hash(&a) == sd_scenario_branch_hash(&b));
    CHECK(sd_scenario_branch_hash(&b) == sd_scenario_branch_hash(&c));
    CHECK(sd_scenario_run_hash(&a) != sd_scenario_run_hash(&b));
    CHECK(sd_scenario_run_hash(&b) != sd_scenario_run_hash(&c));
    cJSON *j = sd_scenario_params_json(&b);
    char *txt = j ? cJSON_PrintUnformatted(j) : NULL;
    CHECK(txt && strstr(txt, "\"dam.top_beam\":false") && strstr(txt, "\"dam.n_columns\":5") &&
          strstr(txt, "\"dam.beam_gaps\":[0.03]") &&
          strstr(txt, "\"dam.members\":[{\"from\":[1.1,0.1,0],\"to\":[1.1,0.1,0.2],\"diameter\":0.01}]"));
    if (txt && !strstr(txt, "dam.members\":[{")) printf("%s\n", txt);
    cJSON_free(txt);
    cJSON_Delete(j);
    sd_scenario_free(&a);
    sd_scenario_free(&b);
    sd_scenario_free(&c);
}

static void segment_distance(void)
{
    /* skew, crossing above each other: the common normal's length */
    CHECK_NEAR(sd_build_segment_distance(v3(-1, 0, 0), v3(1, 0, 0), v3(0, -1, 0.3), v3(0, 1, 0.3)), 0.3, 1e-15);
    /* the same lines, the second segment beside the first's end: from the end (1, 0, 0) to the
     * point (2, 0, 0.3) of the other's line... which is its end (2, 0, 0.3) */
    CHECK_NEAR(sd_build_segment_distance(v3(-1, 0, 0), v3(1, 0, 0), v3(2, -1, 0.3), v3(2, 1, 0.3)),
               sqrt(1.0 + 0.09), 1e-15);
    /* parallel, overlapping along their length: the lines' distance; and end to end */
    CHECK_NEAR(sd_build_segment_distance(v3(0, 0, 0), v3(1, 0, 0), v3(0.5, 0.2, 0), v3(1.5, 0.2, 0)), 0.2, 1e-15);
    CHECK_NEAR(sd_build_segment_distance(v3(0, 0, 0), v3(1, 0, 0), v3(2, 0, 0), v3(3, 0, 0)), 1.0, 1e-15);
    /* a point and a segment; two points */
    CHECK_NEAR(sd_build_segment_distance(v3(0.5, 1, 1), v3(0.5, 1, 1), v3(0, 0, 0), v3(1, 0, 0)), sqrt(2.0), 1e-15);
    CHECK_NEAR(sd_build_segment_distance(v3(0, 0, 0), v3(0, 0, 0), v3(3, 4, 0), v3(3, 4, 0)), 5.0, 1e-15);
    /* crossing: 0; swapping the two segments changes nothing */
    CHECK_NEAR(sd_build_segment_distance(v3(-1, -1, 0), v3(1, 1, 0), v3(-1, 1, 0), v3(1, -1, 0)), 0.0, 1e-15);
    const sd_vec3 p0 = v3(0.1, 0.2, 0.3), p1 = v3(0.7, -0.1, 0.5), q0 = v3(-0.2, 0.4, 0.9), q1 = v3(0.5, 0.5, 0.1);
    CHECK_NEAR(sd_build_segment_distance(p0, p1, q0, q1), sd_build_segment_distance(q1, q0, p1, p0), 1e-15);
}

/* A world holding the dam of a scenario with the given members (and no grid). */
static sd_world *member_world(const char *members, double tan_phi, double damping, sd_vec3 gravity,
                              sd_scenario *s, sd_build_info *info)
{
    char yaml[2048], err[2048];
    snprintf(yaml, sizeof yaml, FLUME "dam: {n_columns: 0, l_v: 0, top_beam: false, members: %s}\n", members);
    if (load(s, yaml, NULL, 0, err, sizeof err)) return NULL;
    s->world.gravity = gravity;
    s->world.contact.tan_phi = tan_phi;
    s->world.contact.damping = damping;
    sd_world *w;
    if (sd_world_create(&s->world, &w)) return NULL;
    memset(info, 0, sizeof *info);
    if (sd_build_dam(w, s, info)) {
        sd_world_destroy(w);
        return NULL;
    }
    return w;
}

static int add_ball(sd_world *w, sd_vec3 pos, double r)
{
    sd_sphere_def sp = sd_sphere_def_default();
    sp.pos = pos;
    sp.radius = r;
    sp.density = 1900.0;
    return sd_world_add_sphere(w, &sp);
}

/* a unit vector across the unit axis a, at angle psi around it */
static sd_vec3 across(sd_vec3 a, double psi)
{
    const sd_vec3 e1 = v3_normalize(v3_cross(a, fabs(a.z) < 0.9 ? v3(0, 0, 1) : v3(1, 0, 0)));
    const sd_vec3 e2 = v3_cross(a, e1);
    return v3_add(v3_scale(e1, cos(psi)), v3_scale(e2, sin(psi)));
}

/* A sphere pressed into a member by a known overlap, no gravity, at rest: the first step's
 * force is k_n δ along the normal from the axis, on the pipe the opposite, at the foot of the
 * sphere's centre on the axis. */
static void member_contact_exact(void)
{
    static const char *const members[3] = {
        "[{from: [1.1, 0.15, 0.05], to: [1.3598076211353316, 0.15, 0.2], diameter: 0.018}]", /* 30° up along x */
        "[{from: [1.05, 0.02, 0.03], to: [1.4, 0.27, 0.4], diameter: 0.024}]",              /* skew */
        "[{from: [1.2, 0.28, 0.1], to: [1.2, 0.02, 0.1], diameter: 0.018}]"};               /* a beam, backwards */
    const double r = 0.01, delta = 1e-4;
    for (int c = 0; c < 3; c++)
        for (int q = 0; q < 4; q++) {
            sd_scenario s;
            sd_build_info info;
            sd_world *w = member_world(members[c], 0.404, 0.2, v3(0, 0, 0), &s, &info);
            CHECK(w != NULL);
            if (!w) return;
            CHECK(info.n_pipes == 1 && info.pipe_kind[0] == SD_PIPE_MEMBER && info.pipe_coord[0] == 0.0);
            sd_body_state p = {0};
            sd_world_body(w, info.pipe_gid[0], &p);
            const sd_dam_member *m = &s.members[0];
            CHECK_NEAR(p.length, v3_norm(v3_sub(m->to, m->from)), 1e-15);
            CHECK_NEAR(p.radius, 0.5 * m->diameter, 0.0);
            CHECK(v3_dot(p.axis, v3_sub(m->to, m->from)) > 0.0); /* from the first end to the second */
            const double sa = (-0.35 + 0.2 * q) * p.length; /* along the axis from the centre */
            const sd_vec3 n = across(p.axis, 0.7 + 1.3 * q);
            const sd_vec3 foot = v3_madd(p.pos, p.axis, sa);
            const int ball = add_ball(w, v3_madd(foot, n, p.radius + r - delta), r);
            CHECK(sd_world_step(w) == SD_OK);
            sd_body_state b = {0};
            sd_world_body(w, ball, &b);
            sd_world_body(w, info.pipe_gid[0], &p);
            const double fn = s.world.contact.k_n * delta;
            CHECK_NEAR(b.force.x, fn * n.x, 1e-9 * fn);
            CHECK_NEAR(b.force.y, fn * n.y, 1e-9 * fn);
            CHECK_NEAR(b.force.z, fn * n.z, 1e-9 * fn);
            CHECK_NEAR(p.force.x, -b.force.x, 1e-15);
            CHECK_NEAR(p.force.y, -b.force.y, 1e-15);
            CHECK_NEAR(p.force.z, -b.force.z, 1e-15);
            double f_across;
            CHECK_NEAR(sd_pipe_resultant_position(p.axis, p.force, p.torque, &f_across), sa, 1e-12);
            CHECK_NEAR(f_across, fn, 1e-9 * fn);
            sd_world_destroy(w);
            sd_scenario_free(&s);
        }
}

/* Dropped from rest 5 mm above where it would touch, over the axis point at s0 of a member
 * rising 30° along x: the centre comes down the vertical through that point, whose distance
 * from the axis is h cos θ, so it touches at h = (R + r)/cos θ, the foot of its centre then
 * (R + r) tan θ uphill of s0. Then it moves down the member like a sphere on a 30° incline. */
static void member_incline(double tan_phi)
{
    const double th = M_PI / 6, R = 0.009, r = 0.01, g = 9.81;
    sd_scenario s;
    sd_build_info info;
    sd_world *w = member_world("[{from: [1.1, 0.15, 0.05], to: [1.3598076211353316, 0.15, 0.2], diameter: 0.018}]",
                               tan_phi, 0.2, v3(0, 0, -g), &s, &info);
    CHECK(w != NULL);
    if (!w) return;
    sd_body_state p = {0}, b = {0};
    sd_world_body(w, info.pipe_gid[0], &p);
    const double s0 = 0.06, h0 = (R + r) / cos(th) + 0.005;
    const sd_vec3 above = v3_madd(p.pos, p.axis, s0);
    const int ball = add_ball(w, v3(above.x, above.y, above.z + h0), r);
    /* to the first touch */
    int touched = 0;
    sd_status st = SD_OK;
    for (int k = 0; k < 10000 && !touched && st == SD_OK; k++) {
        st = sd_world_step(w);
        sd_world_body(w, ball, &b);
        touched = v3_norm(b.force) > 0.0;
    }
    CHECK(touched && st == SD_OK);
    const sd_vec3 rel = v3_sub(b.pos, p.pos);
    const double sc = v3_dot(rel, p.axis), dist = v3_norm(v3_sub(rel, v3_scale(p.axis, sc)));
    const double v = sqrt(2 * g * 0.005), step = v * s.world.dt; /* how far it moves in a step */
    CHECK(dist <= R + r && dist > R + r - 2 * step);
    CHECK_NEAR(sc, s0 + (R + r) * tan(th), 2 * step);
    /* (the step has moved it once under that first force: nanometres) */
    CHECK_NEAR(b.pos.x, above.x, 1e-8);
    CHECK_NEAR(b.pos.y, 0.15, 1e-12);
    /* down the member: the velocity along the axis from 0.1 s to 0.25 s after the touch */
    const double t0 = sd_world_time(w);
    double u1 = 0.0, t1 = 0.0;
    while (st == SD_OK && sd_world_time(w) < t0 + 0.25) {
        st = sd_world_step(w);
        if (t1 == 0.0 && sd_world_time(w) >= t0 + 0.1) {
            sd_world_body(w, ball, &b);
            u1 = v3_dot(b.vel, p.axis);
            t1 = sd_world_time(w);
        }
    }
    CHECK(st == SD_OK);
    sd_world_body(w, ball, &b);
    const double a = -(v3_dot(b.vel, p.axis) - u1) / (sd_world_time(w) - t1);
    const int rolls = tan_phi >= 2.0 / 7.0 * tan(th);
    const double a_th = rolls ? 5.0 / 7.0 * g * sin(th) : g * (sin(th) - tan_phi * cos(th));
    printf("sphere on a 30 deg member, tan phi %.3f (%s): a = %.5f m/s^2 (closed form %.5f, error %.2e), still on "
           "the member at %.4f m from its centre, %.2e m off its plane\n",
           tan_phi, rolls ? "rolls" : "slides", a, a_th, fabs(a - a_th) / a_th, v3_dot(v3_sub(b.pos, p.pos), p.axis),
           fabs(b.pos.y - 0.15));
    CHECK_REL(a, a_th, 0.01);
    CHECK(fabs(v3_dot(v3_sub(b.pos, p.pos), p.axis)) < 0.5 * p.length && v3_norm(b.force) > 0.0);
    CHECK(fabs(b.pos.y - 0.15) < 1e-9);
    sd_world_destroy(w);
    sd_scenario_free(&s);
}

/* A sphere at rest on a level member skew across the flume, given from its far end back:
 * the load is the sphere's weight across the member, at the sphere's foot counted from the
 * member's first end, the moment P a b / L on the member's length. */
static void member_loads(void)
{
    const double R = 0.009, r = 0.01, g = 9.81;
    sd_scenario s;
    sd_build_info info;
    sd_world *w = member_world("[{from: [1.4, 0.25, 0.1], to: [1.1, 0.05, 0.1], diameter: 0.018}]", 0.404, 0.7,
                               v3(0, 0, -g), &s, &info);
    CHECK(w != NULL);
    if (!w) return;
    sd_body_state p = {0}, b = {0};
    sd_world_body(w, info.pipe_gid[0], &p);
    const double L = sqrt(0.3 * 0.3 + 0.2 * 0.2), s0 = 0.04; /* the foot, from the centre toward the second end */
    CHECK_NEAR(p.length, L, 1e-15);
    const int ball = add_ball(w, v3_add(v3_madd(p.pos, p.axis, s0), v3(0, 0, R + r + 1e-4)), r);
    sd_status st = SD_OK;
    for (int k = 0; k < 50000 && st == SD_OK; k++)
        st = sd_world_step(w);
    CHECK(st == SD_OK);
    sd_world_body(w, ball, &b);
    sd_pipe_loads L_;
    CHECK(sd_pipe_loads_start(&L_, &s, &info, w, NULL, NULL) == 0);
    CHECK(L_.n == 1 && L_.p[0].kind == SD_PIPE_MEMBER);
    CHECK_NEAR(L_.p[0].span, L, 1e-15);
    sd_pipe_loads_step(&L_, w, sd_world_time(w), s.world.dt);
    const double weight = b.mass * g, a = 0.5 * L + s0, bb = 0.5 * L - s0;
    const double foot = v3_dot(v3_sub(b.pos, p.pos), p.axis); /* where the sphere rests, from the centre */
    printf("sphere at rest on a skew member: |F| = %.9f N (weight %.9f), at %.9f m from the first end (%.9f), "
           "M = %.9f N m (P a b / L = %.9f)\n",
           L_.p[0].peak, weight, L_.p[0].s_at_m_peak, 0.5 * L + foot, L_.p[0].m_peak, weight * a * bb / L);
    CHECK_NEAR(foot, s0, 1e-6);
    CHECK_REL(L_.p[0].peak, weight, 1e-6);
    CHECK_NEAR(L_.p[0].s_at_m_peak, 0.5 * L + foot, 1e-9);
    CHECK_REL(L_.p[0].m_peak, weight * (0.5 * L + foot) * (0.5 * L - foot) / L, 1e-6);
    CHECK_REL(L_.p[0].m_peak, weight * a * bb / L, 1e-4);
    sd_pipe_loads_free(&L_);
    sd_world_destroy(w);
    sd_scenario_free(&s);
}

int main(void)
{
    paper_dam_unchanged();
    column_keys();
    beam_keys();
    capture_keys();
    segment_distance();
    member_contact_exact();
    member_incline(0.404); /* (2/7) tan 30° = 0.165: rolls */
    member_incline(0.1);   /* slides */
    member_loads();
    return check_report("test_dam");
}
