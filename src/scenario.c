/* Scenario loader: YAML tree → sd_scenario through one parameter table. */
#include "scenario.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "build.h"
#include "core/hash.h"
#include "core/nearest.h"
#include "core/roff.h"
#include "core/vmath.h"
#include "io_stl.h"
#include "yaml_tree.h"

/* P_NUM_OR_OFF: a number, or false (its int flag at count_off: 1 for a number, 0 for false);
 * P_MEMBERS: dam.members, a list of {from, to, diameter} (min, max: the diameter's range) */
/* P_MAT: a material's name, stored as its id (int); P_MLIST: a list of them */
typedef enum { P_DOUBLE, P_INT, P_BOOL, P_VEC3, P_DLIST, P_ILIST, P_ENUM, P_NUM_OR_OFF, P_MEMBERS, P_MAT, P_MLIST } ptype;

typedef struct {
    const char *key;
    ptype type;
    size_t off;
    size_t count_off; /* lists: offset of the int count */
    int max_count;
    const char *unit;
    double min, max;
    int strict_min; /* 1: value must be > min */
    const char *doc;
} sd_param;

#define OFF(f) offsetof(sd_scenario, f)
#define INF HUGE_VAL
#define EXT SD_MAX_EXTENT

static const sd_param params[] = {
    {"solver.dt", P_DOUBLE, OFF(world.dt), 0, 0, "s", 0, 1, 1, "time step Δt"},
    {"solver.duration", P_DOUBLE, OFF(duration), 0, 0, "s", 0, INF, 0,
     "simulated time (scenes without a flume; the flume run ends by its phases)"},
    {"solver.margin", P_DOUBLE, OFF(world.margin), 0, 0, "m", 0, 1, 0, "candidate margin r_dam"},
    {"solver.t_reset", P_DOUBLE, OFF(world.t_reset), 0, 0, "s", 0, INF, 1, "candidate list rebuild interval"},
    {"solver.threads", P_INT, OFF(world.threads), 0, 0, "-", 0, 1024, 0, "OpenMP threads (0 = all cores)"},
    {"solver.check_dt", P_BOOL, OFF(world.check_dt), 0, 0, "-", 0, 1, 0,
     "refuse a time step with fewer than 8 steps per contact half-period"},
    {"solver.seed", P_INT, OFF(seed), 0, 0, "-", 0, 2147483647.0, 0, "random seed (packing, roughness, log axes)"},
    {"gravity", P_VEC3, OFF(world.gravity), 0, 0, "m/s^2", -INF, INF, 0,
     "gravity vector (flume: set from flume.slope_deg)"},
    {"contact.k_n", P_DOUBLE, OFF(world.contact.k_n), 0, 0, "N/m", 0, INF, 1, "normal spring K_n"},
    {"contact.k_s", P_DOUBLE, OFF(world.contact.k_s), 0, 0, "N/m", 0, INF, 0, "tangential spring K_s"},
    {"contact.damping", P_DOUBLE, OFF(world.contact.damping), 0, 0, "-", 0, 1, 0,
     "damping ratio h (c = 2h sqrt(m* K))"},
    {"contact.tan_phi", P_DOUBLE, OFF(world.contact.tan_phi), 0, 0, "-", 0, INF, 0, "friction tan φ"},
    {"contact.cohesion", P_DOUBLE, OFF(world.contact.cohesion), 0, 0, "N", 0, INF, 0,
     "cohesion c in the Mohr–Coulomb limit"},
    {"box.on", P_BOOL, OFF(box_on), 0, 0, "-", 0, 1, 0, "add an open-top box of triangles"},
    {"box.min", P_VEC3, OFF(box_min), 0, 0, "m", -EXT, EXT, 0, "box lower corner"},
    {"box.max", P_VEC3, OFF(box_max), 0, 0, "m", -EXT, EXT, 0, "box upper corner"},
    {"box.material", P_MAT, OFF(box_mat), 0, 0, "-", 0, 0, 0, "material of the box's triangles"},
    {"pile.diameters", P_DLIST, OFF(pile_diam), OFF(pile_n_classes), SD_MAX_CLASSES, "m", 0, 1, 1,
     "sphere diameters of the random pile"},
    {"pile.counts", P_ILIST, OFF(pile_count), OFF(pile_n_counts), SD_MAX_CLASSES, "-", 0, 1e7, 0,
     "sphere counts per diameter"},
    {"pile.density", P_DOUBLE, OFF(pile_density), 0, 0, "kg/m^3", 0, INF, 1, "sphere density"},
    {"pile.min", P_VEC3, OFF(pile_min), 0, 0, "m", -EXT, EXT, 0, "placement region lower corner"},
    {"pile.max", P_VEC3, OFF(pile_max), 0, 0, "m", -EXT, EXT, 0, "placement region upper corner"},
    {"pile.material", P_MAT, OFF(pile_mat), 0, 0, "-", 0, 0, 0, "material of the pile's spheres"},
    {"flume.on", P_BOOL, OFF(flume_on), 0, 0, "-", 0, 1, 0, "build the paper's flume (SPEC §8)"},
    {"flume.bed", P_BOOL, OFF(flume_bed), 0, 0, "-", 0, 1, 0,
     "build the flume's flat bed (false: a mesh with role bed stands in for it; needs flume.roughness false; "
     "docs/meshes.md)"},
    {"flume.slope_deg", P_DOUBLE, OFF(slope_deg), 0, 0, "deg", 0, 90, 0, "bed slope θ"},
    {"flume.width", P_DOUBLE, OFF(width), 0, 0, "m", 0, 100, 1, "flume width"},
    {"flume.wall_height", P_DOUBLE, OFF(wall_height), 0, 0, "m", 0, 100, 1, "side wall height"},
    {"flume.x_gate", P_DOUBLE, OFF(x_gate), 0, 0, "m", 0, 1000, 1, "gate position (reconstructed 0.35)"},
    {"flume.x_dam", P_DOUBLE, OFF(x_dam), 0, 0, "m", 0, 1000, 1, "dam upstream face (reconstructed 4.0)"},
    {"flume.x_end", P_DOUBLE, OFF(x_end), 0, 0, "m", 0, 1000, 1, "end of the bed; elements beyond are removed"},
    {"flume.roughness", P_BOOL, OFF(roughness_on), 0, 0, "-", 0, 1, 0, "fixed roughness spheres on the bed"},
    {"flume.roughness_dmin", P_DOUBLE, OFF(rough_dmin), 0, 0, "m", 0, 1, 1, "smallest roughness diameter"},
    {"flume.roughness_dmax", P_DOUBLE, OFF(rough_dmax), 0, 0, "m", 0, 1, 1, "largest roughness diameter"},
    {"flume.roughness_coverage", P_DOUBLE, OFF(rough_coverage), 0, 0, "-", 0, 0.9, 1,
     "bed area fraction covered by roughness spheres (random placement stops there or when jammed)"},
    {"flume.pack_height", P_DOUBLE, OFF(pack_height), 0, 0, "m", 0, 100, 1,
     "top of the packing box above the bed (at most flume.wall_height)"},
    {"flume.bed_material", P_MAT, OFF(bed_mat), 0, 0, "-", 0, 0, 0, "material of the bed's triangles"},
    {"flume.wall_material", P_MAT, OFF(wall_mat), 0, 0, "-", 0, 0, 0,
     "material of the side walls and the upstream end wall"},
    {"flume.roughness_material", P_MAT, OFF(rough_mat), 0, 0, "-", 0, 0, 0, "material of the bed roughness spheres"},
    {"flume.gate_material", P_MAT, OFF(gate_mat), 0, 0, "-", 0, 0, 0, "material of the gate"},
    {"flume.volume_factor", P_DOUBLE, OFF(volume_factor), 0, 0, "-", 0, 100, 1,
     "scales the debris released at the gate: each spheres.counts entry and logs.count (when >= 0) is multiplied by "
     "it and rounded when the scenario is loaded (logs from logs.k_w follow the spheres); the packing box must hold "
     "the result"},
    {"spheres.diameters", P_DLIST, OFF(class_diam), OFF(n_classes), SD_MAX_CLASSES, "m", 0, 1, 1,
     "size classes (SPEC §8: 20, 15, 10, 5 mm)"},
    {"spheres.counts", P_ILIST, OFF(class_count), OFF(n_class_counts), SD_MAX_CLASSES, "-", 0, 1e7, 0,
     "count per class (376, 891, 3010, 342)"},
    {"spheres.density", P_DOUBLE, OFF(sphere_density), 0, 0, "kg/m^3", 0, INF, 1, "sphere density (SG 1.9)"},
    {"spheres.materials", P_MLIST, OFF(sphere_mat), OFF(n_sphere_mats), SD_MAX_CLASSES, "-", 0, 0, 0,
     "material of each size class (one name: every class; empty: default)"},
    {"spheres.volume", P_DOUBLE, OFF(sphere_volume), 0, 0, "m^3", 0, 1e4, 0,
     "solid volume of spheres to release, split by spheres.grading or spheres.distribution (0: spheres.counts "
     "gives the counts; the mass is density × volume)"},
    {"spheres.grading.diameters", P_DLIST, OFF(grading_diam), OFF(n_grading_diam), SD_MAX_CLASSES, "m", 0, 1, 1,
     "size classes of a grading by mass (with spheres.grading.mass_fractions and spheres.volume, instead of "
     "spheres.diameters and spheres.counts)"},
    {"spheres.grading.mass_fractions", P_DLIST, OFF(grading_frac), OFF(n_grading_frac), SD_MAX_CLASSES, "-", 0, 1, 0,
     "each class's share of the mass, summing to 1 (within 1e-6); counts by largest remainder in volume "
     "(docs/scenario.md)"},
    {"spheres.distribution.type", P_ENUM, OFF(curve.type), 0, 0, "-", 0, 0, 0,
     "a continuous grading curve by mass, cut into spheres.distribution.classes classes (with spheres.volume): "
     "lognormal (d50, sigma), rosin_rammler (d50, exponent), uniform (the mass spread evenly over d), fuller "
     "((d/d_max)^exponent)"},
    {"spheres.distribution.d50", P_DOUBLE, OFF(curve.d50), 0, 0, "m", 0, 1, 0,
     "median diameter by mass (lognormal, rosin_rammler)"},
    {"spheres.distribution.sigma", P_DOUBLE, OFF(curve.sigma), 0, 0, "-", 0, 5, 0,
     "standard deviation of ln d (lognormal; the geometric standard deviation is exp(sigma))"},
    {"spheres.distribution.exponent", P_DOUBLE, OFF(curve.exponent), 0, 0, "-", 0, 20, 0,
     "uniformity exponent n (rosin_rammler; fuller: 0.5 is Fuller's curve)"},
    {"spheres.distribution.d_min", P_DOUBLE, OFF(curve.d_min), 0, 0, "m", 0, 1, 0,
     "smallest diameter: the curve is cut to [d_min, d_max]"},
    {"spheres.distribution.d_max", P_DOUBLE, OFF(curve.d_max), 0, 0, "m", 0, 1, 0, "largest diameter"},
    {"spheres.distribution.classes", P_INT, OFF(curve.classes), 0, 0, "-", 1, SD_MAX_CLASSES, 0,
     "classes of equal width in ln d between d_min and d_max; each class's diameter the geometric mean of its edges"},
    {"logs.count", P_INT, OFF(log_count), 0, 0, "-", -1, SD_MAX_LOGS, 0, "number of logs (-1: from logs.k_w)"},
    {"logs.k_w", P_DOUBLE, OFF(log_kw), 0, 0, "-", 0, 0.95, 0, "woody volume ratio K_w (eq 54), used when count = -1"},
    {"logs.k_w_volume", P_DOUBLE, OFF(log_kw_volume), 0, 0, "m^3", 0, INF, 0,
     "eq 54's V for the count from K_w: 0: the spheres' solid volume, each log's π d²L/4; > 0: this V, each log "
     "counted as d²L (the paper: V = 0.006, its four 1.5-l measures, gives its 32, 67, 106, 150 logs)"},
    {"logs.diameter", P_DOUBLE, OFF(log_diam), 0, 0, "m", 0, 1, 1, "log diameter (logs.diameter.type fixed)"},
    {"logs.diameter.type", P_ENUM, OFF(log_diam_dist.type), 0, 0, "-", 0, 0, 0,
     "log diameters drawn per log from the logs' own random stream: fixed (logs.diameter), uniform over [min, max], "
     "normal or lognormal (mean, sd) cut to [min, max]"},
    {"logs.diameter.mean", P_DOUBLE, OFF(log_diam_dist.mean), 0, 0, "m", 0, 1, 0,
     "mean of the normal or lognormal diameter before the cut"},
    {"logs.diameter.sd", P_DOUBLE, OFF(log_diam_dist.sd), 0, 0, "m", 0, 1, 0,
     "standard deviation of the normal or lognormal diameter before the cut"},
    {"logs.diameter.min", P_DOUBLE, OFF(log_diam_dist.min), 0, 0, "m", 0, 1, 0, "smallest log diameter"},
    {"logs.diameter.max", P_DOUBLE, OFF(log_diam_dist.max), 0, 0, "m", 0, 1, 0, "largest log diameter"},
    {"logs.length", P_DOUBLE, OFF(log_length), 0, 0, "m", 0, 10, 1, "log length (logs.length.type fixed)"},
    {"logs.length.type", P_ENUM, OFF(log_length_dist.type), 0, 0, "-", 0, 0, 0,
     "log lengths drawn per log, as logs.diameter.type: fixed (logs.length), uniform, normal or lognormal"},
    {"logs.length.mean", P_DOUBLE, OFF(log_length_dist.mean), 0, 0, "m", 0, 10, 0,
     "mean of the normal or lognormal length before the cut"},
    {"logs.length.sd", P_DOUBLE, OFF(log_length_dist.sd), 0, 0, "m", 0, 10, 0,
     "standard deviation of the normal or lognormal length before the cut"},
    {"logs.length.min", P_DOUBLE, OFF(log_length_dist.min), 0, 0, "m", 0, 10, 0, "shortest log"},
    {"logs.length.max", P_DOUBLE, OFF(log_length_dist.max), 0, 0, "m", 0, 10, 0, "longest log"},
    {"logs.density", P_DOUBLE, OFF(log_density), 0, 0, "kg/m^3", 0, INF, 1, "log density (SG 0.8)"},
    {"logs.material", P_MAT, OFF(log_mat), 0, 0, "-", 0, 0, 0, "material of the logs"},
    {"dam.on", P_BOOL, OFF(dam_on), 0, 0, "-", 0, 1, 0, "build the dam"},
    {"dam.pipe_diameter", P_DOUBLE, OFF(pipe_diam), 0, 0, "m", 0, 1, 1, "diameter of the grid's pipes"},
    {"dam.l_h", P_DOUBLE, OFF(l_h), 0, 0, "m", 0, 1, 1,
     "clear spacing of the columns ℓ_H: as few columns as leave no gap wider, centred (used when neither "
     "dam.n_columns nor dam.columns is given)"},
    {"dam.n_columns", P_INT, OFF(column_count), 0, 0, "-", -1, SD_MAX_PIPES, 0,
     "number of columns, centred with every clear gap the same, the two at the walls too: (width − n d)/(n + 1) "
     "(-1: from dam.l_h; 0: no columns)"},
    {"dam.columns", P_DLIST, OFF(column_y), OFF(n_columns), SD_MAX_PIPES, "m", 0, 100, 0,
     "explicit column axes y (empty: from dam.n_columns or dam.l_h); inside the walls, not overlapping"},
    {"dam.l_v", P_DOUBLE, OFF(l_v), 0, 0, "m", 0, 1, 0,
     "underside of the intermediate beam above the bed ℓ_V (0: none), below the top beam (used when no other beam "
     "key is given)"},
    {"dam.beam_axes", P_DLIST, OFF(beam_axis_z), OFF(n_beam_axes), SD_MAX_PIPES - 1, "m", 0, 100, 1,
     "axis heights above the bed of the beams below the top beam (instead of dam.l_v)"},
    {"dam.beam_gaps", P_DLIST, OFF(beam_gap), OFF(n_beam_gaps), SD_MAX_PIPES - 1, "m", 0, 100, 0,
     "clear gaps of the beams below the top beam, from the bed up: bed to the lowest beam's underside, then each "
     "beam's top to the next one's underside (instead of dam.l_v; a beam's axis is its gap + d/2 above what is "
     "below)"},
    {"dam.top_beam", P_NUM_OR_OFF, OFF(top_beam), OFF(top_beam_on), 0, "m", 0, 1, 1,
     "underside of the top beam above the bed, or false: no top beam (the columns then reach the top of the "
     "highest beam, or the wall top when there is none)"},
    {"dam.beams", P_DLIST, OFF(beam_z), OFF(n_beams), SD_MAX_PIPES, "m", 0, 100, 0,
     "every beam's underside, the top beam's included (instead of all the beam keys above; empty: from them); below "
     "the wall top, not overlapping"},
    {"dam.members", P_MEMBERS, OFF(members), OFF(n_members), SD_MAX_MEMBERS, "m", 0, 1, 1,
     "pipes at any orientation, besides the grid or instead of it (dam.n_columns: 0, dam.l_v: 0, dam.top_beam: "
     "false): "
     "[{from: [x, y, z], to: [x, y, z], diameter: d}, ...], fixed; between flume.x_dam and flume.x_end, inside the "
     "walls, no nearer another pipe's axis than the two radii"},
    {"dam.fixed_ends", P_BOOL, OFF(dam_support), 0, 0, "-", 0, 1, 0,
     "pipe bending moments for spans with fixed ends (default: simply supported; docs/loads.md)"},
    {"dam.material", P_MAT, OFF(pipe_mat), 0, 0, "-", 0, 0, 0, "material of the dam's pipes and members"},
    {"dam.event_threshold", P_DOUBLE, OFF(event_threshold), 0, 0, "N", 0, INF, 0,
     "a pipe's impact event begins when |F| exceeds its baseline by this and ends below half of it (0: four times "
     "the weight of the heaviest moving element; docs/loads.md)"},
    {"dam.event_time", P_DOUBLE, OFF(event_time), 0, 0, "s", 0, INF, 1,
     "time constant of a pipe's baseline (its quasi-static load) and the longest an event lasts"},
    {"water.on", P_BOOL, OFF(water_on), 0, 0, "-", 0, 1, 0, "fluid forces (SPEC §5)"},
    {"water.u", P_DOUBLE, OFF(water_u), 0, 0, "m/s", 0, INF, 0, "reference velocity U"},
    {"water.h", P_DOUBLE, OFF(water_h), 0, 0, "m", 0, INF, 1, "flow depth h"},
    {"water.rho", P_DOUBLE, OFF(water_rho), 0, 0, "kg/m^3", 0, INF, 0, "water density ρ"},
    {"water.c_d", P_DOUBLE, OFF(water_cd), 0, 0, "-", 0, INF, 0, "drag coefficient C_D"},
    {"water.probe", P_DOUBLE, OFF(water_probe), 0, 0, "m", 0, INF, 1, "capture-phase probe length upstream of the dam"},
    {"water.h_d_floating", P_BOOL, OFF(water_hd_floating), 0, 0, "-", 0, 1, 0,
     "let elements lighter than water (logs) set the capture depth h_D (the paper's literal rule: a log buoyed to h_D "
     "lifts h_D with it, without bound; see docs/physics.md)"},
    {"water.buoyancy", P_ENUM, OFF(water_buoyancy), 0, 0, "-", 0, 0, 0,
     "direction of the flow phase's buoyancy ρVg: vertical (the paper) or normal to the bed (the hydrostatics of "
     "uniform flow on a slope, ρVg cosθ); the capture's pond is still water: vertical either way"},
    {"water.capture_length", P_DOUBLE, OFF(water_capture_length), 0, 0, "m", 0, INF, 0,
     "the capture profile applies this far upstream of the dam face, the flow profile further up (0: the whole "
     "flume upstream of the dam)"},
    {"water.capture_end", P_ENUM, OFF(water_capture_end), 0, 0, "-", 0, 0, 0,
     "downstream end of the capture profile: the trap plane x_dam + d/2 (what is held gets the pond's water) or the "
     "dam face x_dam; downstream of it the flow profile"},
    {"water.scene", P_ENUM, OFF(water_scene), 0, 0, "-", 0, 0, 0,
     "water in a scene without a flume (water.on): none, the flow profile (eq 50), a uniform stream U, or still "
     "water; x downstream, surface at z = water.h, buoyancy opposite gravity"},
    {"phases.packing_time", P_DOUBLE, OFF(packing_time), 0, 0, "s", 0, INF, 0,
     "longest packing (drop) time: packing ends here if the elements have not come to rest before"},
    {"phases.packing_rest_speed", P_DOUBLE, OFF(packing_rest_speed), 0, 0, "m/s", 0, INF, 0,
     "packing ends once no moving element is faster (checked every 100 steps; 0: packing lasts packing_time)"},
    {"phases.packing_min_time", P_DOUBLE, OFF(packing_min_time), 0, 0, "s", 0, INF, 0,
     "packing does not end at rest before this time (the elements start at rest, in the air)"},
    {"phases.flow_limit", P_DOUBLE, OFF(flow_limit), 0, 0, "s", 0, INF, 1, "longest flow phase"},
    {"phases.capture_limit", P_DOUBLE, OFF(capture_limit), 0, 0, "s", 0, INF, 1,
     "capture time limit (reconstructed 6 s)"},
    {"phases.quiet_time", P_DOUBLE, OFF(quiet_time), 0, 0, "s", 0, INF, 1,
     "settled when nothing crossed the dam for this long"},
    {"phases.ke_fraction", P_DOUBLE, OFF(ke_fraction), 0, 0, "-", 0, 1, 0,
     "... and upstream kinetic energy below this fraction of its peak"},
    {"output.snapshot_interval", P_DOUBLE, OFF(snapshot_interval), 0, 0, "s", 0, INF, 0,
     "VTK snapshot interval (0: none)"},
    {"output.checkpoint_interval", P_DOUBLE, OFF(checkpoint_interval), 0, 0, "s", 0, INF, 0,
     "periodic checkpoint interval (0: none): DIR/checkpoint_<step>.ckpt, the last two kept, for --restart"},
    {"output.log_interval", P_DOUBLE, OFF(log_interval), 0, 0, "s", 0, INF, 1, "time-series and progress interval"},
    {"output.trajectory_ids", P_ILIST, OFF(traj_ids), OFF(n_traj), SD_MAX_IDS, "-", 0, 1e9, 0,
     "element ids whose trajectories are logged"},
    {"output.trajectory_interval", P_DOUBLE, OFF(traj_interval), 0, 0, "s", 0, INF, 1, "trajectory CSV interval"},
    {"output.vtk", P_BOOL, OFF(vtk_on), 0, 0, "-", 0, 1, 0, "write VTK snapshots"},
    {"output.png", P_BOOL, OFF(png_on), 0, 0, "-", 0, 1, 0, "draw side-view pictures (matplotlib)"},
};
#define N_PARAMS ((int)(sizeof(params) / sizeof(params[0])))

/* The choices of the P_ENUM keys, in the order of their values (scenario.h's enums). */
static const struct {
    const char *key;
    const char *const names[8];
} enum_choices[] = {
    {"spheres.distribution.type", {"none", "lognormal", "rosin_rammler", "uniform", "fuller", NULL}},
    {"logs.diameter.type", {"fixed", "uniform", "normal", "lognormal", NULL}},
    {"logs.length.type", {"fixed", "uniform", "normal", "lognormal", NULL}},
    {"water.buoyancy", {"vertical", "bed_normal", NULL}},
    {"water.capture_end", {"trap_plane", "dam_face", NULL}},
    {"water.scene", {"none", "flow", "uniform", "still", NULL}},
};

static const char *const *choices(const sd_param *p)
{
    for (size_t k = 0; k < sizeof enum_choices / sizeof enum_choices[0]; k++)
        if (!strcmp(enum_choices[k].key, p->key)) return enum_choices[k].names;
    return NULL;
}

/* "a, b, c": the choices of an enumerated key */
static void choices_text(const sd_param *p, char *buf, size_t len)
{
    const char *const *c = choices(p);
    buf[0] = 0;
    for (int k = 0; c && c[k]; k++) {
        size_t n = strlen(buf);
        snprintf(buf + n, len - n, "%s%s", k ? ", " : "", c[k]);
    }
}

void sd_scenario_default(sd_scenario *s)
{
    memset(s, 0, sizeof(*s));
    s->world = sd_world_def_default();
    s->world.gravity = v3(0.0, 0.0, -9.81);
    s->n_materials = 1;
    snprintf(s->material_name[0], SD_MATERIAL_NAME_MAX, "default");
    s->duration = 1.0;
    s->seed = 1;
    s->pile_density = 1900.0;
    s->flume_bed = 1;
    s->slope_deg = 15.0;
    s->width = 0.3;
    s->wall_height = 0.5;
    s->x_gate = 0.35;
    s->x_dam = 4.0;
    s->x_end = 4.35;
    s->roughness_on = 1;
    s->rough_dmin = 0.007;
    s->rough_dmax = 0.020;
    s->rough_coverage = 0.5;
    s->pack_height = 0.45;
    s->volume_factor = 1.0;
    s->n_classes = 4;
    s->n_class_counts = 4;
    double d[4] = {0.020, 0.015, 0.010, 0.005};
    int c[4] = {376, 891, 3010, 342};
    for (int i = 0; i < 4; i++) {
        s->class_diam[i] = d[i];
        s->class_count[i] = c[i];
    }
    s->sphere_density = 1900.0;
    s->curve.classes = 8;
    s->log_count = -1;
    s->log_kw = 0.0;
    s->log_diam = 0.010;
    s->log_length = 0.100;
    s->log_density = 800.0;
    s->dam_on = 1;
    s->event_time = 0.1;
    s->pipe_diam = 0.018;
    s->l_h = 0.050;
    s->l_v = 0.040;
    s->top_beam = 0.118;
    s->top_beam_on = 1;
    s->column_count = -1;
    s->water_on = 1;
    s->water_u = 1.2;
    s->water_h = 0.03;
    s->water_rho = 1000.0;
    s->water_cd = 0.49;
    s->water_probe = 0.10;
    s->packing_time = 2.0;
    s->packing_rest_speed = 1e-3;
    s->packing_min_time = 0.5;
    s->flow_limit = 10.0;
    s->capture_limit = 6.0;
    s->quiet_time = 0.5;
    s->ke_fraction = 0.01;
    s->snapshot_interval = 0.0;
    s->log_interval = 0.01;
    s->traj_interval = 1e-3;
    s->vtk_on = 1;
    s->png_on = 1;
}

void sd_scenario_free(sd_scenario *s)
{
    free(s->elems);
    s->elems = NULL;
    s->n_elems = 0;
    for (int k = 0; k < s->n_meshes; k++)
        free(s->meshes[k].tri);
    free(s->meshes);
    s->meshes = NULL;
    s->n_meshes = 0;
}

/* Where a parameter was last set: the file (or "--set") and the value's line and column; file
 * NULL while it holds its default. */
typedef struct {
    const char *file;
    int line, col;
} origin;

typedef struct {
    FILE *err;
    const char *file;
    int errors;
    origin *at; /* per parameter (params[] order) */
} ectx;

static void report(ectx *e, int line, int col, const char *fmt, const char *a, const char *b)
{
    if (e->errors < 20) {
        fprintf(e->err, "%s:%d:%d: ", e->file, line, col);
        fprintf(e->err, fmt, a, b);
        fputc('\n', e->err);
    }
    e->errors++;
}

static int parse_double(const char *txt, double *out)
{
    if (!txt || !*txt) return -1;
    char *end;
    errno = 0;
    double v = strtod(txt, &end);
    if (errno || *end || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

static int parse_int(const char *txt, long *out)
{
    if (!txt || !*txt) return -1;
    char *end;
    errno = 0;
    long v = strtol(txt, &end, 10);
    if (errno || *end) return -1;
    *out = v;
    return 0;
}

static int parse_bool(const char *txt, int *out)
{
    if (!txt) return -1;
    if (!strcmp(txt, "true") || !strcmp(txt, "yes") || !strcmp(txt, "on") || !strcmp(txt, "1"))
        *out = 1;
    else if (!strcmp(txt, "false") || !strcmp(txt, "no") || !strcmp(txt, "off") || !strcmp(txt, "0"))
        *out = 0;
    else
        return -1;
    return 0;
}

/* 0 when v is in p's range, else -1 with the range in buf */
static int in_range(const sd_param *p, double v, char *buf, size_t n)
{
    int bad = p->strict_min ? !(v > p->min) : !(v >= p->min);
    if (!bad && !(v > p->max)) return 0;
    if (p->strict_min)
        snprintf(buf, n, "must be > %g and <= %g (%s)", p->min, p->max, p->unit);
    else
        snprintf(buf, n, "must be in [%g, %g] (%s)", p->min, p->max, p->unit);
    return -1;
}

static int check_range(ectx *e, const sd_param *p, double v, int line, int col)
{
    char buf[160];
    if (!in_range(p, v, buf, sizeof buf)) return 0;
    report(e, line, col, "%s: %s", p->key, buf);
    return -1;
}

/* A material's name at n into *id; else reported. */
static int material_param(ectx *e, const sd_scenario *s, const char *key, const sd_ynode *n, int line, int col,
                          int *id)
{
    char hint[SD_MATERIALS_MAX * SD_MATERIAL_NAME_MAX + 64], msg[sizeof hint + 96];
    if (n->kind != SD_Y_SCALAR) {
        report(e, line, col, "%s: expected a material's name%s", key, "");
        return -1;
    }
    *id = sd_scenario_material_id(s, n->value, hint, sizeof hint);
    if (*id >= 0) return 0;
    snprintf(msg, sizeof msg, "unknown material '%s'%s", n->value, hint);
    report(e, line, col, "%s: %s", key, msg);
    return -1;
}

static int parse_vec3_node(const sd_ynode *n, sd_vec3 *v)
{
    if (n->kind != SD_Y_SEQ || n->n != 3) return -1;
    double x[3];
    for (int k = 0; k < 3; k++)
        if (n->items[k]->kind != SD_Y_SCALAR || parse_double(n->items[k]->value, &x[k])) return -1;
    *v = v3(x[0], x[1], x[2]);
    return 0;
}

/* One entry of dam.members into m: 0, or -1 after reporting what is wrong with it. line > 0:
 * it came from --set, and every message goes to (line, col). */
static int parse_member(ectx *e, const sd_param *p, const sd_ynode *n, int k, sd_dam_member *m, int line, int col)
{
    static const char *const keys[] = {"from", "to", "diameter"};
    const int errs = e->errors;
    char msg[200];
    memset(m, 0, sizeof *m);
    m->line = line > 0 ? line : n->line;
    m->col = line > 0 ? col : n->col;
    if (n->kind != SD_Y_MAP) {
        report(e, m->line, m->col, "%s: each member is a mapping {from: [x, y, z], to: [x, y, z], diameter: d}%s",
               p->key, "");
        return -1;
    }
    int have[3] = {0, 0, 0};
    for (int i = 0; i < n->n; i++) {
        const sd_ynode *v = n->items[i];
        const int l = line > 0 ? line : v->line, c = line > 0 ? col : v->col;
        int which = -1;
        for (int j = 0; j < 3; j++)
            if (!strcmp(n->keys[i], keys[j])) which = j;
        if (which < 0) {
            const char *near = sd_nearest_word(n->keys[i], keys, 3);
            char hint[80] = " (from, to, diameter)";
            if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
            snprintf(msg, sizeof msg, "unknown key '%s' in member %d%s", n->keys[i], k, hint);
            report(e, line > 0 ? line : n->key_line[i], line > 0 ? col : n->key_col[i], "%s: %s", p->key, msg);
            continue;
        }
        have[which] = 1;
        if (which < 2) {
            sd_vec3 x = v3(0, 0, 0);
            if (parse_vec3_node(v, &x)) {
                snprintf(msg, sizeof msg, "%s of member %d: expected [x, y, z]", keys[which], k);
                report(e, l, c, "%s: %s", p->key, msg);
            } else if (!(fmax(fmax(fabs(x.x), fabs(x.y)), fabs(x.z)) <= SD_MAX_EXTENT)) {
                snprintf(msg, sizeof msg, "%s of member %d: a coordinate beyond the %g m a scene may span", keys[which],
                         k, SD_MAX_EXTENT);
                report(e, l, c, "%s: %s", p->key, msg);
            } else if (which == 0)
                m->from = x;
            else
                m->to = x;
        } else {
            double d = 0.0;
            if (v->kind != SD_Y_SCALAR || parse_double(v->value, &d) || !(d > p->min) || d > p->max) {
                snprintf(msg, sizeof msg, "diameter of member %d: must be > %g and <= %g (m)", k, p->min, p->max);
                report(e, l, c, "%s: %s", p->key, msg);
            } else
                m->diameter = d;
        }
    }
    for (int j = 0; j < 3; j++)
        if (!have[j]) {
            snprintf(msg, sizeof msg, "member %d has no '%s' (give from: [x, y, z], to: [x, y, z], diameter: d)", k,
                     keys[j]);
            report(e, m->line, m->col, "%s: %s", p->key, msg);
        }
    if (e->errors == errs && !(v3_norm(v3_sub(m->to, m->from)) > 0.0)) {
        snprintf(msg, sizeof msg, "member %d has no length: from and to are the same point", k);
        report(e, m->line, m->col, "%s: %s", p->key, msg);
    }
    return e->errors == errs ? 0 : -1;
}

/* Set one parameter from a node (or from override text when node is NULL). */
static void set_param(ectx *e, sd_scenario *s, const sd_param *p, const sd_ynode *n, const char *text, int line,
                      int col)
{
    char *base = (char *)s;
    sd_ynode *tmp = NULL;
    if (!n) {
        /* override text: parse it as YAML so lists and vectors use the same syntax */
        char msg[512];
        tmp = sd_yaml_parse_string(text, "--set", msg, sizeof msg);
        if (!tmp) {
            report(e, line, col, "%s: cannot parse value '%s'", p->key, text);
            return;
        }
        n = tmp;
    }
    if (e->at) e->at[p - params] = (origin){e->file, tmp ? line : n->line, tmp ? col : n->col};
    switch (p->type) {
    case P_DOUBLE: {
        double v;
        if (n->kind != SD_Y_SCALAR || parse_double(n->value, &v)) {
            report(e, n->line > 0 && !tmp ? n->line : line, tmp ? col : n->col, "%s: expected a number%s", p->key, "");
            break;
        }
        if (!check_range(e, p, v, tmp ? line : n->line, tmp ? col : n->col)) *(double *)(base + p->off) = v;
        break;
    }
    case P_INT: {
        long v;
        if (n->kind != SD_Y_SCALAR || parse_int(n->value, &v)) {
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: expected an integer%s", p->key, "");
            break;
        }
        if (!check_range(e, p, (double)v, tmp ? line : n->line, tmp ? col : n->col)) {
            if (p->off == OFF(seed))
                *(long *)(base + p->off) = v;
            else
                *(int *)(base + p->off) = (int)v;
        }
        break;
    }
    case P_BOOL: {
        int v;
        if (n->kind != SD_Y_SCALAR || parse_bool(n->value, &v)) {
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: expected true or false%s", p->key, "");
            break;
        }
        *(int *)(base + p->off) = v;
        break;
    }
    case P_ENUM: {
        const char *const *c = choices(p);
        int v = -1;
        for (int k = 0; c && c[k] && n->kind == SD_Y_SCALAR; k++)
            if (!strcmp(n->value, c[k])) v = k;
        if (v < 0) {
            char list[128];
            choices_text(p, list, sizeof list);
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: expected one of: %s", p->key, list);
            break;
        }
        *(int *)(base + p->off) = v;
        break;
    }
    case P_VEC3: {
        sd_vec3 v;
        if (parse_vec3_node(n, &v)) {
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: expected a list of three numbers [x, y, z]%s",
                   p->key, "");
            break;
        }
        if (check_range(e, p, v.x, tmp ? line : n->line, tmp ? col : n->col) ||
            check_range(e, p, v.y, tmp ? line : n->line, tmp ? col : n->col) ||
            check_range(e, p, v.z, tmp ? line : n->line, tmp ? col : n->col))
            break;
        *(sd_vec3 *)(base + p->off) = v;
        break;
    }
    case P_NUM_OR_OFF: {
        double v = 0.0;
        int on = 1;
        const int l = tmp ? line : n->line, c = tmp ? col : n->col;
        if (n->kind == SD_Y_SCALAR && !parse_bool(n->value, &on) && !on) {
            *(int *)(base + p->count_off) = 0;
            break;
        }
        if (n->kind != SD_Y_SCALAR || parse_double(n->value, &v)) {
            report(e, l, c, "%s: expected a number or false%s", p->key, "");
            break;
        }
        if (!check_range(e, p, v, l, c)) {
            *(double *)(base + p->off) = v;
            *(int *)(base + p->count_off) = 1;
        }
        break;
    }
    case P_MEMBERS: {
        if (n->kind != SD_Y_SEQ || n->n > p->max_count) {
            char m[160];
            snprintf(m, sizeof m, "expected a list of at most %d members [{from: [x, y, z], to: [x, y, z], diameter: d}]",
                     p->max_count);
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: %s", p->key, m);
            break;
        }
        sd_dam_member got[SD_MAX_MEMBERS];
        int ok = 1;
        for (int k = 0; k < n->n; k++)
            ok &= !parse_member(e, p, n->items[k], k, &got[k], tmp ? line : 0, col);
        if (ok) {
            memcpy(base + p->off, got, (size_t)n->n * sizeof got[0]);
            *(int *)(base + p->count_off) = n->n;
        }
        break;
    }
    case P_MAT: {
        int id;
        if (!material_param(e, s, p->key, n, tmp ? line : n->line, tmp ? col : n->col, &id)) *(int *)(base + p->off) = id;
        break;
    }
    case P_MLIST: {
        if (n->kind != SD_Y_SEQ || n->n > p->max_count) {
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: expected a list of material names (at most %s)",
                   p->key, "one per size class");
            break;
        }
        int ok = 1, ids[SD_MAX_CLASSES];
        for (int k = 0; k < n->n; k++) {
            const sd_ynode *it = n->items[k];
            ok &= !material_param(e, s, p->key, it, tmp ? line : it->line, tmp ? col : it->col, &ids[k]);
        }
        if (ok) {
            memcpy(base + p->off, ids, (size_t)n->n * sizeof(int));
            *(int *)(base + p->count_off) = n->n;
        }
        break;
    }
    case P_DLIST:
    case P_ILIST: {
        if (n->kind != SD_Y_SEQ || n->n > p->max_count) {
            report(e, tmp ? line : n->line, tmp ? col : n->col, "%s: expected a list (at most the allowed length)%s",
                   p->key, "");
            break;
        }
        int ok = 1;
        for (int k = 0; k < n->n && ok; k++) {
            const sd_ynode *it = n->items[k];
            int l = tmp ? line : it->line, c = tmp ? col : it->col;
            if (p->type == P_DLIST) {
                double v;
                if (it->kind != SD_Y_SCALAR || parse_double(it->value, &v)) {
                    report(e, l, c, "%s: expected a number in the list%s", p->key, "");
                    ok = 0;
                } else if (check_range(e, p, v, l, c))
                    ok = 0;
                else
                    ((double *)(base + p->off))[k] = v;
            } else {
                long v;
                if (it->kind != SD_Y_SCALAR || parse_int(it->value, &v)) {
                    report(e, l, c, "%s: expected an integer in the list%s", p->key, "");
                    ok = 0;
                } else if (check_range(e, p, (double)v, l, c))
                    ok = 0;
                else
                    ((int *)(base + p->off))[k] = (int)v;
            }
        }
        if (ok) *(int *)(base + p->count_off) = n->n;
        break;
    }
    }
    sd_yaml_free(tmp);
}

static const sd_param *find_param(const char *key)
{
    for (int i = 0; i < N_PARAMS; i++)
        if (!strcmp(params[i].key, key)) return &params[i];
    return NULL;
}

static int is_section(const char *prefix)
{
    size_t n = strlen(prefix);
    for (int i = 0; i < N_PARAMS; i++)
        if (!strncmp(params[i].key, prefix, n) && params[i].key[n] == '.') return 1;
    return 0;
}

/* " (did you mean 'KEY'?)" for an unknown key near a known one (a key, a section or
 * "elements"), else "" */
static const char *did_you_mean(const char *key, char *buf, size_t n)
{
    const char *cand[2 * N_PARAMS + 4];
    char sections[N_PARAMS][32];
    size_t nc = 0;
    for (int i = 0; i < N_PARAMS; i++) {
        cand[nc++] = params[i].key;
        const char *dot = strchr(params[i].key, '.');
        if (dot && (size_t)(dot - params[i].key) < sizeof sections[0]) {
            snprintf(sections[i], sizeof sections[0], "%.*s", (int)(dot - params[i].key), params[i].key);
            cand[nc++] = sections[i];
        }
    }
    cand[nc++] = "elements";
    cand[nc++] = "materials";
    cand[nc++] = "contact_pairs";
    cand[nc++] = "meshes";
    const char *best = sd_nearest_word(key, cand, nc);
    if (best)
        snprintf(buf, n, " (did you mean '%s'?)", best);
    else
        buf[0] = 0;
    return buf;
}

/* Element list entry keys. */
static const char *elem_keys[] = {"type", "radius", "diameter", "length",   "density", "position", "velocity", "omega",
                                  "axis", "fixed",  "tag",      "vertices", "group",   "material", NULL};

static void parse_element(ectx *e, sd_scenario *s, const sd_ynode *n)
{
    sd_elem_def d;
    memset(&d, 0, sizeof d);
    d.line = n->line;
    d.axis = v3(1, 0, 0);
    d.density = -1;
    d.radius = -1;
    d.length = -1;
    if (n->kind != SD_Y_MAP) {
        report(e, n->line, n->col, "elements: each element is a mapping with a type%s%s", "", "");
        return;
    }
    const sd_ynode *t = sd_yaml_get(n, "type");
    if (!t || t->kind != SD_Y_SCALAR) {
        report(e, n->line, n->col, "elements: missing 'type' (sphere, cylinder or triangle)%s%s", "", "");
        return;
    }
    if (!strcmp(t->value, "sphere"))
        d.type = 0;
    else if (!strcmp(t->value, "cylinder"))
        d.type = 1;
    else if (!strcmp(t->value, "triangle"))
        d.type = 2;
    else {
        static const char *const types[] = {"sphere", "cylinder", "triangle"};
        const char *near = sd_nearest_word(t->value, types, 3);
        char hint[64] = " (sphere, cylinder or triangle)";
        if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
        report(e, t->line, t->col, "elements.type: unknown element type '%s'%s", t->value, hint);
        return;
    }
    int errs = e->errors;
    for (int i = 0; i < n->n; i++) {
        const char *k = n->keys[i];
        const sd_ynode *v = n->items[i];
        int known = 0;
        for (int j = 0; elem_keys[j]; j++)
            known |= !strcmp(elem_keys[j], k);
        if (!known) {
            const char *near = sd_nearest_word(k, elem_keys, sizeof elem_keys / sizeof elem_keys[0] - 1);
            char hint[80] = "";
            if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
            report(e, n->key_line[i], n->key_col[i], "elements: unknown key '%s'%s", k, hint);
            continue;
        }
        double x;
        if (!strcmp(k, "radius") || !strcmp(k, "diameter") || !strcmp(k, "length") || !strcmp(k, "density")) {
            if (v->kind != SD_Y_SCALAR || parse_double(v->value, &x) || !(x > 0)) {
                report(e, v->line, v->col, "elements.%s: expected a positive number%s", k, "");
                continue;
            }
            if (!strcmp(k, "radius"))
                d.radius = x;
            else if (!strcmp(k, "diameter"))
                d.radius = 0.5 * x;
            else if (!strcmp(k, "length"))
                d.length = x;
            else
                d.density = x;
        } else if (!strcmp(k, "position") || !strcmp(k, "velocity") || !strcmp(k, "omega") || !strcmp(k, "axis")) {
            sd_vec3 vv;
            if (parse_vec3_node(v, &vv)) {
                report(e, v->line, v->col, "elements.%s: expected [x, y, z]%s", k, "");
                continue;
            }
            if (!strcmp(k, "position"))
                d.pos = vv;
            else if (!strcmp(k, "velocity"))
                d.vel = vv;
            else if (!strcmp(k, "omega"))
                d.omega = vv;
            else {
                if (!(v3_norm(vv) > 0)) report(e, v->line, v->col, "elements.axis: must be non-zero%s%s", "", "");
                d.axis = vv;
            }
        } else if (!strcmp(k, "fixed")) {
            if (v->kind != SD_Y_SCALAR || parse_bool(v->value, &d.fixed))
                report(e, v->line, v->col, "elements.fixed: expected true or false%s%s", "", "");
        } else if (!strcmp(k, "tag") || !strcmp(k, "group")) {
            long iv;
            if (v->kind != SD_Y_SCALAR || parse_int(v->value, &iv) || iv < 0)
                report(e, v->line, v->col, "elements.%s: expected a non-negative integer%s", k, "");
            else if (!strcmp(k, "tag"))
                d.tag = (int)iv;
            else
                d.group = (int)iv;
        } else if (!strcmp(k, "material")) {
            if (material_param(e, s, "elements.material", v, v->line, v->col, &d.material)) d.material = 0;
        } else if (!strcmp(k, "vertices")) {
            if (v->kind != SD_Y_SEQ || v->n != 3 || parse_vec3_node(v->items[0], &d.v[0]) ||
                parse_vec3_node(v->items[1], &d.v[1]) || parse_vec3_node(v->items[2], &d.v[2]))
                report(e, v->line, v->col, "elements.vertices: expected three points [[x,y,z],[x,y,z],[x,y,z]]%s%s", "",
                       "");
        }
    }
    if (e->errors != errs) return;
    if (d.type != 2 && d.radius < 0) {
        report(e, n->line, n->col, "elements: %s needs a radius (or diameter)%s", t->value, "");
        return;
    }
    if (d.type == 1 && d.length < 0) {
        report(e, n->line, n->col, "elements: cylinder needs a length%s%s", "", "");
        return;
    }
    if (d.type != 2 && d.density < 0) d.density = d.type == 0 ? 1900.0 : 800.0;
    if (d.type == 2 && !(v3_norm(v3_cross(v3_sub(d.v[1], d.v[0]), v3_sub(d.v[2], d.v[0]))) > 0)) {
        report(e, n->line, n->col, "elements: triangle is degenerate (or has no vertices)%s%s", "", "");
        return;
    }
    sd_elem_def *ne = realloc(s->elems, (size_t)(s->n_elems + 1) * sizeof(*ne));
    if (!ne) {
        report(e, n->line, n->col, "out of memory%s%s", "", "");
        return;
    }
    s->elems = ne;
    s->elems[s->n_elems++] = d;
}

/* meshes: entry keys */
static const char *mesh_keys[] = {"file", "role", "scale", "translate", "rotate_deg", "material", NULL};

/* corner' = R (scale corner) + translate, R = Rz Ry Rx (degrees, about the origin) */
static sd_vec3 mesh_transform(const sd_mesh_def *d, sd_vec3 p)
{
    const double deg = M_PI / 180.0;
    const double cx = cos(d->rotate_deg.x * deg), sx = sin(d->rotate_deg.x * deg);
    const double cy = cos(d->rotate_deg.y * deg), sy = sin(d->rotate_deg.y * deg);
    const double cz = cos(d->rotate_deg.z * deg), sz = sin(d->rotate_deg.z * deg);
    sd_vec3 q = v3_scale(p, d->scale);
    q = v3(q.x, cx * q.y - sx * q.z, sx * q.y + cx * q.z);
    q = v3(cy * q.x + sy * q.z, q.y, -sy * q.x + cy * q.z);
    q = v3(cz * q.x - sz * q.y, sz * q.x + cz * q.y, q.z);
    return v3_add(q, d->translate);
}

/* the scenario's meshes' triangles so far */
static int mesh_triangles(const sd_scenario *s)
{
    int n = 0;
    for (int k = 0; k < s->n_meshes; k++)
        n += s->meshes[k].n_tri;
    return n;
}

static void parse_mesh(ectx *e, sd_scenario *s, const sd_ynode *n)
{
    sd_mesh_def d;
    memset(&d, 0, sizeof d);
    d.line = n->line;
    d.role = -1;
    d.scale = 1.0;
    if (n->kind != SD_Y_MAP) {
        report(e, n->line, n->col, "meshes: each mesh is a mapping with a file and a role%s%s", "", "");
        return;
    }
    if (s->n_meshes >= SD_MAX_MESHES) {
        report(e, n->line, n->col, "meshes: more than %s meshes%s", "64", "");
        return;
    }
    const int errs = e->errors;
    const sd_ynode *file = NULL;
    for (int i = 0; i < n->n; i++) {
        const char *k = n->keys[i];
        const sd_ynode *v = n->items[i];
        int known = 0;
        for (int j = 0; mesh_keys[j]; j++)
            known |= !strcmp(mesh_keys[j], k);
        if (!known) {
            const char *near = sd_nearest_word(k, mesh_keys, sizeof mesh_keys / sizeof mesh_keys[0] - 1);
            char hint[80] = "";
            if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
            report(e, n->key_line[i], n->key_col[i], "meshes: unknown key '%s'%s", k, hint);
        } else if (!strcmp(k, "file")) {
            if (v->kind != SD_Y_SCALAR || !v->value[0])
                report(e, v->line, v->col, "meshes.file: expected a file name%s%s", "", "");
            else
                file = v;
        } else if (!strcmp(k, "role")) {
            static const char *const roles[] = {"bed", "wall", "dam"};
            for (int r = 0; r < 3 && v->kind == SD_Y_SCALAR; r++)
                if (!strcmp(v->value, roles[r])) d.role = r;
            if (d.role < 0) report(e, v->line, v->col, "meshes.role: expected one of: %s%s", "bed, wall, dam", "");
        } else if (!strcmp(k, "material")) {
            if (material_param(e, s, "meshes.material", v, v->line, v->col, &d.material)) d.material = 0;
        } else if (!strcmp(k, "scale")) {
            if (v->kind != SD_Y_SCALAR || parse_double(v->value, &d.scale) || !(d.scale > 0) || d.scale > 1e4)
                report(e, v->line, v->col, "meshes.scale: expected a number > 0 and <= 1e4%s%s", "", "");
        } else {
            sd_vec3 vv = v3(0, 0, 0);
            const double lim = k[0] == 't' ? EXT : 360.0; /* translate, m; rotate_deg */
            if (parse_vec3_node(v, &vv) || !(fmax(fmax(fabs(vv.x), fabs(vv.y)), fabs(vv.z)) <= lim))
                report(e, v->line, v->col, "meshes.%s: expected [x, y, z], each within %s", k,
                       k[0] == 't' ? "1e4 m" : "360 degrees");
            else if (k[0] == 't')
                d.translate = vv;
            else
                d.rotate_deg = vv;
        }
    }
    if (e->errors != errs) return;
    if (!file || d.role < 0) {
        report(e, n->line, n->col, "meshes: each mesh needs %s%s", !file ? "a file" : "a role (bed, wall or dam)", "");
        return;
    }
    /* relative to the scenario file's directory */
    const char *slash = strrchr(s->path, '/');
    int len;
    if (file->value[0] == '/' || !slash)
        len = snprintf(d.file, sizeof d.file, "%s", file->value);
    else
        len = snprintf(d.file, sizeof d.file, "%.*s/%s", (int)(slash - s->path), s->path, file->value);
    if (len < 0 || (size_t)len >= sizeof d.file) {
        report(e, file->line, file->col, "meshes.file: the path is too long%s%s", "", "");
        return;
    }
    char msg[1536];
    sd_stl_mesh m;
    if (sd_stl_read(d.file, SD_STL_MAX_TRIANGLES - mesh_triangles(s), &m, msg, sizeof msg)) {
        report(e, file->line, file->col, "meshes.file: %s%s", msg, "");
        return;
    }
    d.binary = m.binary;
    /* transformed; a corner beyond the scene's extent is an error, a triangle that the scale
     * made too small to weld (an edge under 1 µm, walls.c) is dropped with the file's own */
    int small = 0, first_small = 0;
    for (int k = 0; k < m.n; k++) {
        sd_vec3 t[3];
        for (int v = 0; v < 3; v++) {
            t[v] = mesh_transform(&d, m.tri[k][v]);
            if (!(fmax(fmax(fabs(t[v].x), fabs(t[v].y)), fabs(t[v].z)) <= EXT)) {
                char where[64], a[1400];
                snprintf(a, sizeof a, "%s, %s: a corner at (%g, %g, %g) m, beyond the 1e4 m a scene may span", d.file,
                         sd_stl_where(&m, k, where, sizeof where), t[v].x, t[v].y, t[v].z);
                report(e, file->line, file->col, "meshes: %s%s", a, " (see meshes.scale and translate)");
                sd_stl_free(&m);
                free(d.tri);
                return;
            }
        }
        const double l2 =
            fmin(fmin(v3_norm2(v3_sub(t[1], t[0])), v3_norm2(v3_sub(t[2], t[0]))), v3_norm2(v3_sub(t[2], t[1])));
        if (!(l2 >= 1e-12) || !(v3_norm(v3_cross(v3_sub(t[1], t[0]), v3_sub(t[2], t[0]))) > 0.0)) {
            if (!small++) first_small = k;
            continue;
        }
        if (!d.tri) {
            d.tri = malloc((size_t)m.n * sizeof *d.tri);
            if (!d.tri) {
                report(e, file->line, file->col, "meshes.file: %s: out of memory%s", d.file, "");
                sd_stl_free(&m);
                return;
            }
        }
        memcpy(d.tri[d.n_tri++], t, sizeof t);
    }
    char where[64], a[1400];
    if (m.dropped) {
        snprintf(a, sizeof a, "%s: %d triangles of zero area dropped (the first at %s %d)", d.file, m.dropped,
                 m.binary ? "triangle index" : "line", m.first_dropped);
        fprintf(e->err, "%s:%d:%d: meshes.file: warning: %s\n", e->file, file->line, file->col, a);
    }
    if (small) {
        snprintf(a, sizeof a, "%s: %d triangles with an edge under 1 micrometre after the scale dropped (the first at %s)",
                 d.file, small, sd_stl_where(&m, first_small, where, sizeof where));
        fprintf(e->err, "%s:%d:%d: meshes.file: warning: %s\n", e->file, file->line, file->col, a);
    }
    sd_stl_free(&m);
    if (d.n_tri == 0) {
        report(e, file->line, file->col, "meshes.file: %s: no triangle is left%s", d.file, "");
        free(d.tri);
        return;
    }
    sd_mesh_def *nm = realloc(s->meshes, (size_t)(s->n_meshes + 1) * sizeof *nm);
    if (!nm) {
        report(e, n->line, n->col, "out of memory%s%s", "", "");
        free(d.tri);
        return;
    }
    s->meshes = nm;
    s->meshes[s->n_meshes++] = d;
}

static void report_cb(void *ctx, int line, int col, const char *msg) { report(ctx, line, col, "%s%s", msg, ""); }

/* a contact_pairs constant: the number in text, in the range of its contact.* key */
static int pair_value(int key, const char *text, double *v, char *why, size_t n)
{
    char k[32];
    snprintf(k, sizeof k, "contact.%s", sd_scenario_pair_key(key));
    const sd_param *p = find_param(k);
    if (!text || parse_double(text, v)) {
        snprintf(why, n, "expected a number");
        return -1;
    }
    return in_range(p, *v, why, n);
}

static void walk(ectx *e, sd_scenario *s, const sd_ynode *map, const char *prefix)
{
    for (int i = 0; i < map->n; i++) {
        char key[256];
        if (*prefix)
            snprintf(key, sizeof key, "%s.%s", prefix, map->keys[i]);
        else
            snprintf(key, sizeof key, "%s", map->keys[i]);
        const sd_ynode *v = map->items[i];
        if (!*prefix && !strcmp(key, "meshes")) {
            if (v->kind != SD_Y_SEQ) {
                report(e, v->line, v->col, "meshes: expected a list%s%s", "", "");
                continue;
            }
            for (int k = 0; k < v->n; k++)
                parse_mesh(e, s, v->items[k]);
            continue;
        }
        if (!*prefix && !strcmp(key, "elements")) {
            if (v->kind != SD_Y_SEQ) {
                report(e, v->line, v->col, "elements: expected a list%s%s", "", "");
                continue;
            }
            for (int k = 0; k < v->n; k++)
                parse_element(e, s, v->items[k]);
            continue;
        }
        if (!*prefix && !strcmp(key, "materials")) continue; /* (read first: load) */
        if (!*prefix && !strcmp(key, "contact_pairs")) {
            sd_scenario_parse_pairs(s, v, pair_value, report_cb, e);
            continue;
        }
        const sd_param *p = find_param(key);
        if (v->kind == SD_Y_MAP && is_section(key)) {
            walk(e, s, v, key); /* logs.length: a number, or a mapping of logs.length.* */
        } else if (p) {
            set_param(e, s, p, v, NULL, v->line, v->col);
        } else if (is_section(key)) {
            if (v->kind != SD_Y_MAP)
                report(e, v->line, v->col, "%s: expected a mapping (section)%s", key, "");
            else
                walk(e, s, v, key);
        } else {
            char hint[128];
            report(e, map->key_line[i], map->key_col[i], "unknown key '%s'%s", key, did_you_mean(key, hint, sizeof hint));
        }
    }
}

/* Cross-field checks: geometry that contradicts itself, an unstable time step. */
/* Report at where the first of the keys that was set was set (the scenario's first line when
 * all hold their defaults). */
static void report_keys(ectx *e, const origin *at, const char *k1, const char *k2, const char *fmt, const char *a,
                        const char *b)
{
    const char *keys[2] = {k1, k2};
    for (int i = 0; i < 2; i++) {
        const sd_param *p = keys[i] ? find_param(keys[i]) : NULL;
        if (p && at[p - params].file) {
            const origin *o = &at[p - params];
            ectx here = {e->err, o->file, e->errors, NULL};
            report(&here, o->line, o->col, fmt, a, b);
            e->errors = here.errors;
            return;
        }
    }
    report(e, 1, 1, fmt, a, b);
}

static const char *num(char *buf, double v) /* buf: 32 bytes */
{
    snprintf(buf, 32, "%g", v);
    return buf;
}

/* The first axis (0, 1, 2) on which the box [lo, hi] is not wider than d, or -1. */
static int narrow_axis(sd_vec3 lo, sd_vec3 hi, double d)
{
    const double ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    for (int k = 0; k < 3; k++)
        if (!(ext[k] > d)) return k;
    return -1;
}

static double axis_of(sd_vec3 v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

/* Two lists given per class must be as long as each other. */
static void check_lengths(ectx *e, const origin *at, const char *kd, int nd, const char *kc, int nc)
{
    if (nd == nc) return;
    char a[200];
    snprintf(a, sizeof a, "%s has %d values and %s has %d: give one count per diameter", kc, nc, kd, nd);
    report_keys(e, at, kc, kd, "%s%s", a, "");
}

/* The dam's keys that say one thing in different ways (docs/scenario.md, "The dam"): the
 * columns (dam.columns, dam.n_columns, dam.l_h), the beams below the top beam (dam.beams,
 * dam.beam_axes, dam.beam_gaps, dam.l_v) and the top beam (dam.beams lists it too, so
 * dam.top_beam would go unused). At most one key of a group may be given. One given with --set
 * overrides those of its group that the file gives (a sweep or a --set changes the layout of a
 * scenario written with another key); two given in the same place are refused, rather than one
 * silently ignored. */
enum { K_COLUMNS, K_N_COLUMNS, K_L_H, K_BEAMS, K_BEAM_AXES, K_BEAM_GAPS, K_L_V, K_TOP_BEAM };
static const char *const dam_key[] = {"dam.columns",   "dam.n_columns", "dam.l_h", "dam.beams",
                                      "dam.beam_axes", "dam.beam_gaps", "dam.l_v", "dam.top_beam"};

static origin *key_origin(origin *at, int k) { return &at[find_param(dam_key[k]) - params]; }

/* 1 when key k was given and says something (a list with values, a count of columns) */
static int dam_key_given(const sd_scenario *s, origin *at, int k)
{
    if (!key_origin(at, k)->file) return 0;
    switch (k) {
    case K_COLUMNS:
        return s->n_columns > 0;
    case K_N_COLUMNS:
        return s->column_count >= 0;
    case K_BEAMS:
        return s->n_beams > 0;
    case K_BEAM_AXES:
        return s->n_beam_axes > 0;
    case K_BEAM_GAPS:
        return s->n_beam_gaps > 0;
    default:
        return 1;
    }
}

/* key k as if not given (l_h, l_v and top_beam need nothing: the others take precedence over
 * them, build.c) */
static void dam_key_clear(sd_scenario *s, origin *at, int k)
{
    if (k == K_COLUMNS) s->n_columns = 0;
    if (k == K_N_COLUMNS) s->column_count = -1;
    if (k == K_BEAMS) s->n_beams = 0;
    if (k == K_BEAM_AXES) s->n_beam_axes = 0;
    if (k == K_BEAM_GAPS) s->n_beam_gaps = 0;
    key_origin(at, k)->file = NULL;
}

static void resolve_dam_keys(ectx *e, sd_scenario *s, origin *at)
{
    static const int group[3][5] = {{K_COLUMNS, K_N_COLUMNS, K_L_H, -1},
                                    {K_BEAMS, K_BEAM_AXES, K_BEAM_GAPS, K_L_V, -1},
                                    {K_BEAMS, K_TOP_BEAM, -1}};
    static const char *const what[3] = {"the columns: give one of dam.columns, dam.n_columns, dam.l_h",
                                        "the beams: give one of dam.beams, dam.beam_axes, dam.beam_gaps, dam.l_v",
                                        "the top beam: dam.beams lists every beam, the top one included; give the "
                                        "lower beams with dam.beam_axes or dam.beam_gaps to keep dam.top_beam"};
    for (int g = 0; g < 3; g++) {
        int by_set = 0;
        for (int i = 0; group[g][i] >= 0; i++)
            by_set |= dam_key_given(s, at, group[g][i]) && !strcmp(key_origin(at, group[g][i])->file, "--set");
        for (int i = 0; by_set && group[g][i] >= 0; i++)
            if (dam_key_given(s, at, group[g][i]) && strcmp(key_origin(at, group[g][i])->file, "--set"))
                dam_key_clear(s, at, group[g][i]);
        int first = -1;
        for (int i = 0; group[g][i] >= 0; i++) {
            const int k = group[g][i];
            if (!dam_key_given(s, at, k)) continue;
            if (first < 0) {
                first = k;
                continue;
            }
            /* at the later of the two */
            const origin *o1 = key_origin(at, first), *o2 = key_origin(at, k);
            const int later = o2->line > o1->line || (o2->line == o1->line && o2->col > o1->col);
            const origin *o = later ? o2 : o1;
            char m[320];
            snprintf(m, sizeof m, "%s and %s both give %s", dam_key[first], dam_key[k], what[g]);
            ectx here = {e->err, o->file, e->errors, NULL};
            report(&here, o->line, o->col, "%s%s", m, "");
            e->errors = here.errors;
            break;
        }
    }
}

/* A member's message, at the member (its line and column where dam.members was given). */
static void report_member(ectx *e, const origin *at, const sd_dam_member *m, int k, const char *what)
{
    const origin *o = &at[find_param("dam.members") - params];
    char msg[400];
    snprintf(msg, sizeof msg, "member %d (from [%g, %g, %g] to [%g, %g, %g], diameter %g m) %s", k, m->from.x,
             m->from.y, m->from.z, m->to.x, m->to.y, m->to.z, m->diameter, what);
    ectx here = {e->err, o->file ? o->file : e->file, e->errors, NULL};
    report(&here, o->file ? m->line : 1, o->file ? m->col : 1, "dam.members: %s%s", msg, "");
    e->errors = here.errors;
}

/* The members: between the dam face and the end of the bed, the pipe whole (the pipes join the
 * world when the capture begins, and none may appear inside the flow upstream of the dam:
 * docs/physics.md "Flow end and branching"); the axis inside the walls and between the bed and
 * the wall top, where a pipe's rim may reach into the bed or a wall as into a foundation (a
 * fixed pipe has no contact with them); no nearer another pipe than the two radii. Along x a
 * flat-ended cylinder with unit axis a and radius r reaches r sqrt(1 - a_x^2) beyond its axis. */
static void check_members(ectx *e, const origin *at, const sd_scenario *s, const sd_dam_pipe *pipe, int n_pipe)
{
    char m[240];
    const int n_grid = n_pipe - s->n_members;
    for (int k = 0; k < s->n_members; k++) {
        const sd_dam_pipe *p = &pipe[n_grid + k];
        const double ax = p->axis.x / p->length, wx = p->radius * sqrt(fmax(0.0, 1.0 - ax * ax));
        const double from[3] = {p->from.x, p->from.y, p->from.z}, to[3] = {p->to.x, p->to.y, p->to.z};
        const double lo[3] = {s->x_dam, 0.0, 0.0}, hi[3] = {s->x_end, s->width, s->wall_height};
        static const char *const side[3][2] = {{"upstream of the dam face flume.x_dam = %g m",
                                                "past the end of the bed flume.x_end = %g m"},
                                               {"through the wall at y = %g m", "through the wall at y = %g m"},
                                               {"below the bed at z = %g m", "above the wall top at z = %g m"}};
        int bad = 0;
        for (int i = 0; i < 3 && !bad; i++) {
            const double w = i == 0 ? wx : 0.0; /* the pipe along x, its axis across and up */
            const double l = fmin(from[i], to[i]) - w, h = fmax(from[i], to[i]) + w;
            char where[120];
            if (l < lo[i] || h > hi[i]) {
                snprintf(where, sizeof where, side[i][l < lo[i] ? 0 : 1], l < lo[i] ? lo[i] : hi[i]);
                snprintf(m, sizeof m, "reaches %s (%s %c = %.6g m)", where, i == 0 ? "the pipe to" : "its axis to",
                         "xyz"[i], l < lo[i] ? l : h);
                bad = 1;
            }
        }
        for (int j = 0; j < n_grid + k && !bad; j++) {
            const double dist = sd_build_segment_distance(p->from, p->to, pipe[j].from, pipe[j].to);
            if (dist < p->radius + pipe[j].radius) {
                static const char *const kind[3] = {"beam at z = %g m", "column at y = %g m", "member %g"};
                char other[64];
                snprintf(other, sizeof other, kind[pipe[j].kind], pipe[j].coord);
                snprintf(m, sizeof m, "overlaps the %s: their axes come %.6g m apart, less than the radii's sum %g m",
                         other, dist, p->radius + pipe[j].radius);
                bad = 1;
            }
        }
        if (bad) report_member(e, at, &s->members[k], k, m);
    }
}

static int beam_is_top(const sd_dam_grid *g, int k) { return g->top_beam && k == g->n_beam - 1; }

/* The dam: every pipe inside the flume, below the wall top, none overlapping another. */
static void check_dam(ectx *e, const origin *at, const sd_scenario *s)
{
    char a[32], b[32], m[300];
    sd_dam_grid g;
    const double d = s->pipe_diam, r = 0.5 * d, W = s->width;
    if (sd_build_dam_grid(s, &g)) {
        snprintf(m, sizeof m,
                 "flume.width = %g m with dam.l_h = %g m needs %.0f columns, more than %d: widen dam.l_h or give "
                 "dam.n_columns or dam.columns",
                 W, s->l_h, ceil((W - s->l_h) / (s->l_h + d) - 1e-9), SD_MAX_PIPES);
        report_keys(e, at, "flume.width", "dam.l_h", "%s%s", m, "");
        return;
    }
    const char *ck = s->n_columns > 0 ? "dam.columns" : s->column_count >= 0 ? "dam.n_columns" : "dam.l_h";
    if (s->n_columns == 0 && s->column_count > 0 && s->column_count * d > W) {
        snprintf(m, sizeof m, "%d columns of %g m do not fit across the %g m flume", s->column_count, d, W);
        report_keys(e, at, ck, "flume.width", "%s: %s", ck, m);
        return;
    }
    for (int k = 0; k < g.n_col; k++)
        if (!(g.col_y[k] - r >= 0 && g.col_y[k] + r <= W)) {
            snprintf(m, sizeof m, "%g m wide flume: the column at y = %s m (diameter %g m) reaches outside the walls", W,
                     num(a, g.col_y[k]), d);
            report_keys(e, at, ck, "flume.width", "%s: %s", ck, m);
            return;
        }
    for (int k = 1; k < g.n_col; k++) /* (ascending) */
        if (g.col_y[k] - g.col_y[k - 1] < d) {
            snprintf(m, sizeof m, "the columns at y = %s and %s m overlap (pipe diameter %g m)", num(a, g.col_y[k - 1]),
                     num(b, g.col_y[k]), d);
            report_keys(e, at, ck, "dam.pipe_diameter", "%s: %s", ck, m);
            return;
        }
    /* the beams: bk gives those below the top beam (all of them with dam.beams) */
    const char *bk = s->n_beams > 0         ? "dam.beams"
                     : s->n_beam_axes > 0   ? "dam.beam_axes"
                     : s->n_beam_gaps > 0   ? "dam.beam_gaps"
                     : g.n_beam > g.top_beam ? "dam.l_v"
                                            : "dam.top_beam";
    for (int k = 0; k < g.n_beam; k++) { /* z: the beams' axes */
        const char *key = beam_is_top(&g, k) ? "dam.top_beam" : bk;
        if (g.beam_z[k] + r > s->wall_height) {
            snprintf(m, sizeof m, "the beam with its underside at %s m tops out at %s m, above the %g m walls",
                     num(a, g.beam_z[k] - r), num(b, g.beam_z[k] + r), s->wall_height);
            report_keys(e, at, key, "flume.wall_height", "%s: %s", key, m);
            return;
        }
        if (g.beam_z[k] - r < 0.0) {
            snprintf(m, sizeof m, "the beam with its axis at %s m reaches into the bed (pipe diameter %g m)",
                     num(a, g.beam_z[k]), d);
            report_keys(e, at, key, "dam.pipe_diameter", "%s: %s", key, m);
            return;
        }
        if (g.top_beam && !beam_is_top(&g, k) && g.beam_z[k] > g.beam_z[g.n_beam - 1]) {
            snprintf(m, sizeof m, "the beam with its underside at %s m is above the top beam (underside %s m): lower it, "
                     "raise dam.top_beam, or remove the top beam (dam.top_beam: false)",
                     num(a, g.beam_z[k] - r), num(b, s->top_beam));
            report_keys(e, at, bk, "dam.top_beam", "%s: %s", bk, m);
            return;
        }
    }
    for (int k = 1; k < g.n_beam; k++) /* (ascending, once none is above the top beam) */
        if (g.beam_z[k] - g.beam_z[k - 1] < d) {
            snprintf(m, sizeof m, "the beams with undersides at %s and %s m overlap (pipe diameter %g m)",
                     num(a, g.beam_z[k - 1] - r), num(b, g.beam_z[k] - r), d);
            report_keys(e, at, bk, "dam.pipe_diameter", "%s: %s", bk, m);
            return;
        }
    if (g.n_col + g.n_beam > 0 && s->x_dam + d > s->x_end) {
        snprintf(m, sizeof m, "the dam's pipes (x = %g to %g m) reach past flume.x_end = %g m", s->x_dam, s->x_dam + d,
                 s->x_end);
        report_keys(e, at, "flume.x_end", "dam.pipe_diameter", "%s%s", m, "");
        return;
    }
    if (g.n_col + g.n_beam + s->n_members == 0) {
        report_keys(e, at, "dam.n_columns", "dam.top_beam",
                    "the dam has no pipe (no column, no beam, no member): give it some, or dam.on: false%s%s", "", "");
        return;
    }
    sd_dam_pipe pipe[SD_MAX_DAM_PIPES];
    const int n = sd_build_dam_pipes(s, &g, pipe);
    check_members(e, at, s, pipe, n);
}

/* 1 when the key was set in the scenario or by --set (not holding its default) */
static int given(const origin *at, const char *key)
{
    const sd_param *p = find_param(key);
    return p && at[p - params].file != NULL;
}

/* A size drawn per log (logs.length.*, logs.diameter.*): its keys agree with its type, its range
 * holds the distribution. */
static void check_log_size(ectx *e, const origin *at, const char *name, const sd_size_dist *d)
{
    static const char *const sub[4] = {"mean", "sd", "min", "max"};
    char key[4][48], tkey[48], m[600];
    snprintf(tkey, sizeof tkey, "%s.type", name);
    for (int k = 0; k < 4; k++)
        snprintf(key[k], sizeof key[k], "%s.%s", name, sub[k]);
    if (d->type == SD_SIZE_FIXED) {
        for (int k = 0; k < 4; k++)
            if (given(at, key[k])) {
                snprintf(m, sizeof m, "%s is set but %s is fixed (%s gives the size): set %s to uniform, normal or "
                         "lognormal", key[k], tkey, name, tkey);
                report_keys(e, at, key[k], NULL, "%s%s", m, "");
            }
        return;
    }
    if (given(at, name)) {
        snprintf(m, sizeof m, "%s conflicts with %s: give one size (%s) or a distribution (%s.*), not both", name, tkey,
                 name, name);
        report_keys(e, at, name, tkey, "%s%s", m, "");
    }
    if (!(d->min > 0.0 && d->max > d->min)) {
        snprintf(m, sizeof m, "%s needs 0 < %s < %s (got %g and %g m)", tkey, key[2], key[3], d->min, d->max);
        report_keys(e, at, key[2], key[3], "%s%s", m, "");
    } else if (d->type != SD_SIZE_UNIFORM) {
        if (!(d->sd > 0.0)) {
            snprintf(m, sizeof m, "%s needs %s > 0 (the spread of the sizes)", tkey, key[1]);
            report_keys(e, at, key[1], tkey, "%s%s", m, "");
        }
        if (!(d->mean >= d->min && d->mean <= d->max)) {
            snprintf(m, sizeof m, "%s = %g m must lie in [%s, %s] = [%g, %g] m", key[0], d->mean, key[2], key[3],
                     d->min, d->max);
            report_keys(e, at, key[0], tkey, "%s%s", m, "");
        }
    }
}

/* The sphere classes as designers give them (debris.h): a grading by mass fractions or a
 * continuous curve, with spheres.volume, resolved here into class_diam and class_count. Their
 * keys agree with each other and not with spheres.diameters or spheres.counts. */
static void check_debris(ectx *e, const origin *at, sd_scenario *s)
{
    static const char *const curve_keys[] = {"spheres.distribution.d50",      "spheres.distribution.sigma",
                                             "spheres.distribution.exponent", "spheres.distribution.d_min",
                                             "spheres.distribution.d_max",    "spheres.distribution.classes"};
    char m[300], a[32];
    const int errs = e->errors;
    const int grading = given(at, "spheres.grading.diameters") || given(at, "spheres.grading.mass_fractions");
    const sd_grading_curve *g = &s->curve;
    const int curve = g->type != SD_GRADING_NONE;
    check_log_size(e, at, "logs.length", &s->log_length_dist);
    check_log_size(e, at, "logs.diameter", &s->log_diam_dist);
    s->class_source = SD_CLASSES_COUNTS;
    for (int i = 0; i < SD_MAX_CLASSES; i++)
        s->class_target[i] = 0.0;
    for (size_t k = 0; !curve && k < sizeof curve_keys / sizeof curve_keys[0]; k++)
        if (given(at, curve_keys[k])) {
            snprintf(m, sizeof m, "%s is set but spheres.distribution.type is none", curve_keys[k]);
            report_keys(e, at, curve_keys[k], NULL, "%s%s", m, "");
        }
    if (grading && curve)
        report_keys(e, at, "spheres.distribution.type", "spheres.grading.diameters",
                    "give spheres.grading or spheres.distribution, not both%s%s", "", "");
    const char *src = grading ? "spheres.grading" : "spheres.distribution";
    const char *src_key = grading ? (given(at, "spheres.grading.diameters") ? "spheres.grading.diameters"
                                                                            : "spheres.grading.mass_fractions")
                                  : "spheres.distribution.type";
    if (grading || curve) {
        static const char *const mine[2] = {"spheres.diameters", "spheres.counts"};
        for (int k = 0; k < 2; k++)
            if (given(at, mine[k])) {
                snprintf(m, sizeof m, "%s conflicts with %s: give the classes one way (%s and spheres.volume make "
                         "spheres.diameters and spheres.counts)", mine[k], src, src);
                report_keys(e, at, mine[k], NULL, "%s%s", m, "");
            }
        if (!(s->sphere_volume > 0.0))
            report_keys(e, at, src_key, NULL, "%s needs spheres.volume, the solid volume of spheres to release%s", src,
                        "");
    } else if (s->sphere_volume > 0.0)
        report_keys(e, at, "spheres.volume", NULL,
                    "spheres.volume is used only with spheres.grading or spheres.distribution (spheres.counts gives "
                    "the counts)%s%s", "", "");
    if (e->errors != errs || !(grading || curve)) return;
    double diam[SD_MAX_CLASSES], frac[SD_MAX_CLASSES];
    int n = 0;
    if (grading) {
        n = s->n_grading_diam;
        if (s->n_grading_frac != n) {
            snprintf(m, sizeof m, "spheres.grading.mass_fractions has %d values and spheres.grading.diameters has %d: "
                     "give one fraction per diameter", s->n_grading_frac, n);
            report_keys(e, at, "spheres.grading.mass_fractions", "spheres.grading.diameters", "%s%s", m, "");
            return;
        }
        if (n == 0) {
            report_keys(e, at, "spheres.grading.diameters", "spheres.grading.mass_fractions",
                        "spheres.grading needs at least one class (spheres.grading.diameters is empty)%s%s", "", "");
            return;
        }
        double sum = 0.0;
        for (int k = 0; k < n; k++)
            sum += s->grading_frac[k];
        /* fractions read from a table rarely sum to 1 exactly: within 1e-6 they are taken as
         * given, scaled to sum to 1 */
        if (!(fabs(sum - 1.0) <= 1e-6)) {
            snprintf(m, sizeof m, "spheres.grading.mass_fractions sum to %.9g, not 1 (within 1e-6)", sum);
            report_keys(e, at, "spheres.grading.mass_fractions", NULL, "%s%s", m, "");
            return;
        }
        for (int k = 0; k < n; k++) {
            diam[k] = s->grading_diam[k];
            frac[k] = s->grading_frac[k] / sum;
        }
    } else {
        static const char *const tname[] = {"none", "lognormal", "rosin_rammler", "uniform", "fuller"};
        const char *need = NULL;
        if (!(g->d_min > 0.0))
            need = "spheres.distribution.d_min";
        else if (!(g->d_max > g->d_min))
            need = "spheres.distribution.d_max";
        else if ((g->type == SD_GRADING_LOGNORMAL || g->type == SD_GRADING_ROSIN_RAMMLER) && !(g->d50 > 0.0))
            need = "spheres.distribution.d50";
        else if (g->type == SD_GRADING_LOGNORMAL && !(g->sigma > 0.0))
            need = "spheres.distribution.sigma";
        else if ((g->type == SD_GRADING_ROSIN_RAMMLER || g->type == SD_GRADING_FULLER) && !(g->exponent > 0.0))
            need = "spheres.distribution.exponent";
        if (need) {
            snprintf(m, sizeof m, "spheres.distribution.type = %s needs %s %s", tname[g->type], need,
                     !strcmp(need, "spheres.distribution.d_max") ? "above spheres.distribution.d_min" : "> 0");
            report_keys(e, at, need, "spheres.distribution.type", "%s%s", m, "");
            return;
        }
        n = sd_debris_discretise(g, diam, frac);
        if (n < 0) {
            snprintf(m, sizeof m, "the %s curve holds no mass between d_min = %g m and d_max = %g m", tname[g->type],
                     g->d_min, g->d_max);
            report_keys(e, at, "spheres.distribution.d_min", "spheres.distribution.type", "%s%s", m, "");
            return;
        }
    }
    int count[SD_MAX_CLASSES];
    if (sd_debris_counts(n, diam, frac, s->sphere_volume, count)) {
        report_keys(e, at, "spheres.volume", NULL, "spheres.volume = %s m^3 asks for more than 1e7 spheres in a class%s",
                    num(a, s->sphere_volume), "");
        return;
    }
    s->class_source = grading ? SD_CLASSES_GRADING : SD_CLASSES_CURVE;
    s->n_classes = s->n_class_counts = n;
    for (int k = 0; k < n; k++) {
        s->class_diam[k] = diam[k];
        s->class_count[k] = count[k];
        s->class_target[k] = frac[k];
    }
}

/* Cross-field checks: geometry that contradicts itself, sizes that do not fit, an unstable time
 * step. Everything a builder allocates from is checked here first. */
static void validate(ectx *e, sd_scenario *s, origin *at)
{
    char a[32], b[300];
    resolve_dam_keys(e, s, at);
    check_debris(e, at, s);
    if (e->errors) return;
    check_lengths(e, at, "pile.diameters", s->pile_n_classes, "pile.counts", s->pile_n_counts);
    check_lengths(e, at, "spheres.diameters", s->n_classes, "spheres.counts", s->n_class_counts);
    if (s->n_sphere_mats > 1 && s->n_sphere_mats != s->n_classes) {
        snprintf(b, sizeof b, "spheres.materials has %d names and the spheres %d size classes: give one material, or "
                 "one per class", s->n_sphere_mats, s->n_classes);
        report_keys(e, at, "spheres.materials", NULL, "%s%s", b, "");
    }
    if (e->errors) return;
    if (s->pile_n_classes > 0) {
        double dmax = 0;
        for (int k = 0; k < s->pile_n_classes; k++)
            dmax = fmax(dmax, s->pile_diam[k]);
        const int k = narrow_axis(s->pile_min, s->pile_max, dmax);
        if (k >= 0) {
            const double lo = axis_of(s->pile_min, k), hi = axis_of(s->pile_max, k);
            if (!(hi > lo))
                snprintf(b, sizeof b, "pile.min must be below pile.max on %c (%g is not below %g)", "xyz"[k], lo, hi);
            else
                snprintf(b, sizeof b, "the pile region spans %g m on %c: no room for its spheres of %g m", hi - lo,
                         "xyz"[k], dmax);
            report_keys(e, at, "pile.max", "pile.min", "%s%s", b, "");
        }
    }
    if (s->box_on && (s->box_min.x >= s->box_max.x || s->box_min.y >= s->box_max.y || s->box_min.z >= s->box_max.z))
        report_keys(e, at, "box.min", "box.max", "box.min must be below box.max on every axis%s%s", "", "");
    for (int i = 0; i < s->n_elems; i++) {
        const sd_elem_def *d = &s->elems[i];
        double big = fmax(fmax(fabs(d->pos.x), fabs(d->pos.y)), fabs(d->pos.z));
        for (int k = 0; k < 3 && d->type == 2; k++)
            big = fmax(big, fmax(fmax(fabs(d->v[k].x), fabs(d->v[k].y)), fabs(d->v[k].z)));
        if (d->type != 2) big = fmax(big, fmax(d->radius, d->length));
        if (big > SD_MAX_EXTENT) {
            ectx here = {e->err, e->file, e->errors, NULL};
            report(&here, d->line, 1, "elements: a coordinate or size of %s m, beyond the %s m a scene may span",
                   num(a, big), "1e+04");
            e->errors = here.errors;
        }
    }
    if (s->flume_on) {
        if (s->x_gate >= s->x_dam)
            report_keys(e, at, "flume.x_gate", "flume.x_dam", "flume.x_gate must be upstream of flume.x_dam%s%s", "", "");
        if (s->x_end <= s->x_dam)
            report_keys(e, at, "flume.x_end", "flume.x_dam", "flume.x_end must be downstream of flume.x_dam%s%s", "", "");
        if (s->rough_dmin > s->rough_dmax)
            report_keys(e, at, "flume.roughness_dmin", "flume.roughness_dmax",
                        "flume.roughness_dmin must not exceed roughness_dmax%s%s", "", "");
        if (s->pack_height > s->wall_height)
            report_keys(e, at, "flume.pack_height", "flume.wall_height",
                        "flume.pack_height = %s m is above flume.wall_height = %s m", num(a, s->pack_height),
                        num(b, s->wall_height));
        if (s->roughness_on && !(s->rough_dmax < s->width && s->rough_dmax < s->x_end))
            report_keys(e, at, "flume.roughness_dmax", "flume.width",
                        "flume.roughness_dmax = %s m does not fit on the bed%s", num(a, s->rough_dmax), "");
        /* the packing box (build.c): above the roughness, behind the gate, 2 mm from the walls */
        double dmax = 0;
        for (int k = 0; k < s->n_classes; k++)
            if (s->class_count[k] > 0) dmax = fmax(dmax, s->class_diam[k]);
        const sd_vec3 lo = v3(0.002, 0.002, 0.5 * s->rough_dmax + 0.002),
                      hi = v3(s->x_gate - 0.002, s->width - 0.002, s->pack_height);
        const int ax = e->errors ? -1 : narrow_axis(lo, hi, dmax);
        if (ax >= 0) {
            static const char *const key[3] = {"flume.x_gate", "flume.width", "flume.pack_height"};
            snprintf(b, sizeof b,
                     "the packing box (2 mm inside the walls and the gate, from the roughness top at %g m up to "
                     "flume.pack_height) spans %g m on %c: no room for spheres of %g m",
                     lo.z, axis_of(hi, ax) - axis_of(lo, ax), "xyz"[ax], dmax);
            report_keys(e, at, key[ax], NULL, "%s: %s", key[ax], b);
        }
        if (s->log_count < 0 && s->log_kw > 0) {
            double vs = 0.0;
            for (int k = 0; k < s->n_classes; k++)
                vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
            const double n = s->log_kw * vs / (1.0 - s->log_kw) / sd_build_log_mean_volume(s, 0);
            if (!(n <= SD_MAX_LOGS)) {
                snprintf(b, sizeof b, "%.3g logs, more than %d", n, SD_MAX_LOGS);
                report_keys(e, at, "logs.k_w", "logs.diameter", "logs.k_w = %s asks for %s", num(a, s->log_kw), b);
            }
        }
        if (s->dam_on && e->errors == 0) check_dam(e, at, s);
        if (!s->flume_bed) {
            int bed_mesh = 0;
            for (int k = 0; k < s->n_meshes; k++)
                bed_mesh |= s->meshes[k].role == SD_MESH_BED;
            if (s->roughness_on)
                report_keys(e, at, "flume.bed", NULL,
                            "flume.bed = false leaves the bed roughness without its bed: set flume.roughness: false%s%s",
                            "", "");
            else if (!bed_mesh)
                report_keys(e, at, "flume.bed", NULL,
                            "flume.bed = false needs a mesh with role: bed in its place (meshes:)%s%s", "", "");
        }
    }
    /* the stiffest pair of materials that can meet, with its lightest moving mass → stability of Δt */
    int ma = 0, mb = 0;
    double mmin = INFINITY;
    const double dt_max = sd_scenario_stable_dt(s, &ma, &mb, &mmin);
    if (s->world.check_dt && isfinite(dt_max) && s->world.dt > dt_max) {
        const sd_contact_def c = sd_scenario_pair_contact(s, ma, mb, NULL);
        char pair[2 * SD_MATERIAL_NAME_MAX + 32] = "";
        if (s->n_materials > 1)
            snprintf(pair, sizeof pair, " of the pair %s-%s", s->material_name[ma], s->material_name[mb]);
        snprintf(a, sizeof a, "%g", s->world.dt);
        snprintf(b, sizeof b,
                 "%g s (8 steps per contact half-period for k_n = %g N/m, k_s = %g N/m%s and the smallest mass %g kg)",
                 dt_max, c.k_n, c.k_s, pair, mmin);
        /* at the pair's entry where contact_pairs made it the stiffest, else at solver.dt */
        int entry = -1;
        for (int p = 0; p < s->n_pairs; p++)
            if (s->pairs[p].a == (ma < mb ? ma : mb) && s->pairs[p].b == (ma < mb ? mb : ma)) entry = p;
        if (entry >= 0 && !at[find_param("solver.dt") - params].file)
            report(e, s->pairs[entry].line, s->pairs[entry].col, "solver.dt = %s is unstable: it must be at most %s", a,
                   b);
        else
            report_keys(e, at, "solver.dt", NULL, "solver.dt = %s is unstable: it must be at most %s", a, b);
    }
}

/* flume.volume_factor: the counts of the debris released at the gate scaled, within their range */
static void scale_volume(ectx *e, sd_scenario *s, const origin *at)
{
    const double f = s->volume_factor;
    if (f == 1.0) return;
    char a[32], b[200];
    for (int k = 0; k < s->n_classes; k++) {
        const double n = round(s->class_count[k] * f);
        if (n > 1e7) {
            snprintf(b, sizeof b, "makes spheres.counts[%d] = %.4g, more than 1e7", k, n);
            report_keys(e, at, "flume.volume_factor", NULL, "flume.volume_factor = %s %s", num(a, f), b);
            return;
        }
        s->class_count[k] = (int)n;
    }
    if (s->log_count > 0) {
        const double n = round(s->log_count * f);
        if (n > SD_MAX_LOGS) {
            snprintf(b, sizeof b, "makes logs.count = %.4g, more than %d", n, SD_MAX_LOGS);
            report_keys(e, at, "flume.volume_factor", NULL, "flume.volume_factor = %s %s", num(a, f), b);
            return;
        }
        s->log_count = (int)n;
    }
}

/* the scenario from its YAML text (text != NULL) or file */
static int load(sd_scenario *s, const char *path, const char *text, const char *const *overrides, int n_overrides,
                FILE *err)
{
    sd_scenario_default(s);
    snprintf(s->path, sizeof s->path, "%s", path);
    char msg[1024];
    sd_ynode *root = text ? sd_yaml_parse_string(text, path, msg, sizeof msg) : sd_yaml_load(path, msg, sizeof msg);
    if (!root) {
        fprintf(err, "%s\n", msg);
        return -1;
    }
    origin at[N_PARAMS];
    memset(at, 0, sizeof at);
    ectx e = {err, path, 0, at};
    if (root->kind != SD_Y_MAP)
        report(&e, root->line, root->col, "the scenario must be a mapping of sections%s%s", "", "");
    else {
        /* flume scenes default gravity to the slope unless given */
        const sd_ynode *fl = sd_yaml_get(root, "flume");
        /* the materials first: every other key may name them */
        const sd_ynode *mats = sd_yaml_get(root, "materials");
        if (mats) sd_scenario_parse_materials(s, mats, report_cb, &e);
        walk(&e, s, root, "");
        if (fl && s->flume_on && !sd_yaml_get(root, "gravity")) {
            double th = s->slope_deg * M_PI / 180.0;
            s->world.gravity = v3(9.81 * sin(th), 0.0, -9.81 * cos(th));
        }
    }
    ectx eo = {err, "--set", 0, at};
    for (int i = 0; i < n_overrides; i++) {
        const char *eq = strchr(overrides[i], '=');
        char key[256];
        if (!eq || eq == overrides[i] || (size_t)(eq - overrides[i]) >= sizeof key) {
            report(&eo, i + 1, 1, "expected key=value, got '%s'%s", overrides[i], "");
            continue;
        }
        memcpy(key, overrides[i], (size_t)(eq - overrides[i]));
        key[eq - overrides[i]] = 0;
        const sd_param *p = find_param(key);
        if (!p) {
            char hint[128];
            report(&eo, i + 1, 1, "unknown key '%s'%s", key, did_you_mean(key, hint, sizeof hint));
            continue;
        }
        set_param(&eo, s, p, NULL, eq + 1, i + 1, (int)(eq - overrides[i]) + 2);
        if (!strcmp(key, "flume.slope_deg") && s->flume_on) {
            double th = s->slope_deg * M_PI / 180.0;
            s->world.gravity = v3(9.81 * sin(th), 0.0, -9.81 * cos(th));
        }
    }
    if (!e.errors && !eo.errors) scale_volume(&e, s, at);
    if (!e.errors && !eo.errors) validate(&e, s, at);
    sd_yaml_free(root);
    int total = e.errors + eo.errors;
    if (total) {
        if (total > 20) fprintf(err, "%s: %d errors in all (first 20 shown)\n", path, total);
        sd_scenario_free(s);
        return -1;
    }
    return 0;
}

int sd_scenario_load(sd_scenario *s, const char *path, const char *const *overrides, int n_overrides, FILE *err)
{
    return load(s, path, NULL, overrides, n_overrides, err);
}

int sd_scenario_load_string(sd_scenario *s, const char *text, const char *name, const char *const *overrides,
                            int n_overrides, FILE *err)
{
    return load(s, name, text, overrides, n_overrides, err);
}

static const char *type_name(ptype t)
{
    switch (t) {
    case P_DOUBLE:
        return "number";
    case P_INT:
        return "integer";
    case P_BOOL:
        return "bool";
    case P_VEC3:
        return "[x, y, z]";
    case P_DLIST:
        return "list of numbers";
    case P_ILIST:
        return "list of integers";
    case P_ENUM:
        return "choice";
    case P_MAT:
        return "material";
    case P_MLIST:
        return "list of materials";
    case P_NUM_OR_OFF:
        return "number or false";
    case P_MEMBERS:
        return "list of {from, to, diameter}";
    }
    return "?";
}

static void print_value(FILE *f, const sd_scenario *s, const sd_param *p, int json)
{
    const char *base = (const char *)s;
    switch (p->type) {
    case P_ENUM:
        fprintf(f, json ? "\"%s\"" : "%s", choices(p)[*(const int *)(base + p->off)]);
        break;
    case P_DOUBLE:
        fprintf(f, "%.10g", *(const double *)(base + p->off));
        break;
    case P_INT:
        if (p->off == OFF(seed))
            fprintf(f, "%ld", *(const long *)(base + p->off));
        else
            fprintf(f, "%d", *(const int *)(base + p->off));
        break;
    case P_BOOL:
        fprintf(f, "%s", *(const int *)(base + p->off) ? "true" : "false");
        break;
    case P_VEC3: {
        const sd_vec3 *v = (const sd_vec3 *)(base + p->off);
        fprintf(f, "[%.10g, %.10g, %.10g]", v->x, v->y, v->z);
        break;
    }
    case P_NUM_OR_OFF:
        if (*(const int *)(base + p->count_off))
            fprintf(f, "%.10g", *(const double *)(base + p->off));
        else
            fputs("false", f);
        break;
    case P_MEMBERS: {
        const sd_dam_member *m = (const sd_dam_member *)(base + p->off);
        const int n = *(const int *)(base + p->count_off);
        fputc('[', f);
        for (int k = 0; k < n; k++)
            fprintf(f, "%s{from: [%.10g, %.10g, %.10g], to: [%.10g, %.10g, %.10g], diameter: %.10g}", k ? ", " : "",
                    m[k].from.x, m[k].from.y, m[k].from.z, m[k].to.x, m[k].to.y, m[k].to.z, m[k].diameter);
        fputc(']', f);
        break;
    }
    case P_MAT:
        fprintf(f, json ? "\"%s\"" : "%s", s->material_name[*(const int *)(base + p->off)]);
        break;
    case P_MLIST: {
        const int n = *(const int *)(base + p->count_off);
        fputc('[', f);
        for (int k = 0; k < n; k++)
            fprintf(f, "%s%s", k ? ", " : "", s->material_name[((const int *)(base + p->off))[k]]);
        fputc(']', f);
        break;
    }
    case P_DLIST:
    case P_ILIST: {
        int n = *(const int *)(base + p->count_off);
        fputc('[', f);
        for (int k = 0; k < n; k++) {
            if (p->type == P_DLIST)
                fprintf(f, "%s%.10g", k ? ", " : "", ((const double *)(base + p->off))[k]);
            else
                fprintf(f, "%s%d", k ? ", " : "", ((const int *)(base + p->off))[k]);
        }
        fputc(']', f);
        break;
    }
    }
}

void sd_scenario_print_params(FILE *f, int format)
{
    sd_scenario d;
    sd_scenario_default(&d);
    const int md = format == SD_PARAMS_MARKDOWN, roff = format == SD_PARAMS_ROFF;
    if (md) fprintf(f, "| key | type | unit | default | range | meaning |\n|---|---|---|---|---|---|\n");
    for (int i = 0; i < N_PARAMS; i++) {
        const sd_param *p = &params[i];
        if (roff) {
            /* .TP, the key in bold, then its type, unit, default and range, and its meaning */
            char val[512], range[192] = "";
            FILE *m = fmemopen(val, sizeof val, "w");
            if (m) {
                print_value(m, &d, p, 0);
                fclose(m);
            } else {
                val[0] = 0;
            }
            if (p->type == P_ENUM) {
                char list[128];
                choices_text(p, list, sizeof list);
                snprintf(range, sizeof range, ", one of %s", list);
            } else if (p->type != P_BOOL && p->type != P_VEC3 && p->type != P_MEMBERS && p->type != P_MAT &&
                       p->type != P_MLIST)
                snprintf(range, sizeof range, ", range %s%g, %g]", p->strict_min ? "(" : "[", p->min, p->max);
            fputs(".TP\n.B ", f);
            sd_roff_puts(f, p->key);
            fputs("\n", f);
            sd_roff_puts(f, type_name(p->type));
            fputs(", ", f);
            sd_roff_puts(f, p->unit);
            fputs(", default ", f);
            sd_roff_puts(f, val);
            sd_roff_puts(f, range);
            fputs(": ", f);
            sd_roff_puts(f, p->doc);
            fputs("\n", f);
            continue;
        }
        if (md)
            fprintf(f, "| `%s` | %s | %s | `", p->key, type_name(p->type), p->unit);
        else
            fprintf(f, "%-31s %-16s %-8s ", p->key, type_name(p->type), p->unit);
        print_value(f, &d, p, 0);
        if (p->type == P_ENUM) {
            char list[128];
            choices_text(p, list, sizeof list);
            fprintf(f, md ? "` | %s | %s |\n" : "  [%s]  %s\n", list, p->doc);
        } else if (p->type == P_MAT || p->type == P_MLIST)
            fprintf(f, md ? "` | a name in materials | %s |\n" : "  [a name in materials]  %s\n", p->doc);
        else if (p->type == P_BOOL || p->type == P_VEC3 || p->type == P_MEMBERS)
            fprintf(f, md ? "` | | %s |\n" : "  %s\n", p->doc);
        else
            fprintf(f, md ? "` | %s%g, %g] | %s |\n" : "  %s%g, %g]  %s\n", p->strict_min ? "(" : "[", p->min, p->max,
                    p->doc);
    }
}

int sd_scenario_param_count(void) { return N_PARAMS; }

const char *sd_scenario_param_key(int i) { return i >= 0 && i < N_PARAMS ? params[i].key : NULL; }

/* [x, y, z] into o under key; 0, or -1 out of memory */
static int add_vec3(cJSON *o, const char *key, sd_vec3 v)
{
    const double xyz[3] = {v.x, v.y, v.z};
    cJSON *a = cJSON_CreateDoubleArray(xyz, 3);
    if (a && cJSON_AddItemToObject(o, key, a)) return 0;
    cJSON_Delete(a);
    return -1;
}

/* A parameter's value as JSON: numbers at full precision (cJSON prints a double with the
 * digits that read back to the same double), vectors and lists as arrays. */
static cJSON *param_json(const sd_scenario *s, const sd_param *p)
{
    const char *base = (const char *)s;
    switch (p->type) {
    case P_ENUM:
        return cJSON_CreateString(choices(p)[*(const int *)(base + p->off)]);
    case P_DOUBLE:
        return cJSON_CreateNumber(*(const double *)(base + p->off));
    case P_INT:
        return cJSON_CreateNumber(p->off == OFF(seed) ? (double)*(const long *)(base + p->off)
                                                      : (double)*(const int *)(base + p->off));
    case P_BOOL:
        return cJSON_CreateBool(*(const int *)(base + p->off));
    case P_VEC3: {
        const sd_vec3 *v = (const sd_vec3 *)(base + p->off);
        const double xyz[3] = {v->x, v->y, v->z};
        return cJSON_CreateDoubleArray(xyz, 3);
    }
    case P_NUM_OR_OFF:
        return *(const int *)(base + p->count_off) ? cJSON_CreateNumber(*(const double *)(base + p->off))
                                                   : cJSON_CreateFalse();
    case P_MAT:
        return cJSON_CreateString(s->material_name[*(const int *)(base + p->off)]);
    case P_MLIST: {
        const int n = *(const int *)(base + p->count_off);
        const char *names[SD_MAX_CLASSES];
        for (int k = 0; k < n; k++)
            names[k] = s->material_name[((const int *)(base + p->off))[k]];
        return cJSON_CreateStringArray(names, n);
    }
    case P_MEMBERS: {
        const sd_dam_member *m = (const sd_dam_member *)(base + p->off);
        cJSON *a = cJSON_CreateArray();
        for (int k = 0; a && k < *(const int *)(base + p->count_off); k++) {
            cJSON *o = cJSON_CreateObject();
            if (!o || !cJSON_AddItemToArray(a, o)) {
                cJSON_Delete(o);
                cJSON_Delete(a);
                return NULL;
            }
            if (add_vec3(o, "from", m[k].from) || add_vec3(o, "to", m[k].to) ||
                !cJSON_AddNumberToObject(o, "diameter", m[k].diameter)) {
                cJSON_Delete(a);
                return NULL;
            }
        }
        return a;
    }
    case P_DLIST:
        return cJSON_CreateDoubleArray((const double *)(base + p->off), *(const int *)(base + p->count_off));
    case P_ILIST:
        return cJSON_CreateIntArray((const int *)(base + p->off), *(const int *)(base + p->count_off));
    }
    return cJSON_CreateNull();
}

cJSON *sd_scenario_params_json(const sd_scenario *s)
{
    cJSON *o = cJSON_CreateObject();
    for (int i = 0; o && i < N_PARAMS; i++) {
        cJSON *v = param_json(s, &params[i]);
        if (!cJSON_AddItemToObject(o, params[i].key, v)) {
            cJSON_Delete(v);
            cJSON_Delete(o);
            return NULL;
        }
    }
    return o;
}

/* Keys that act only from the capture phase on (see scenario.h). dam.pipe_diameter and dam.on
 * are not among them: the bed roughness keeps the dam foot clear by the pipe diameter, and the
 * trap plane (x_dam + d/2) enters the time series from the start. */
static const char *const capture_keys[] = {
    "dam.l_h",          "dam.l_v",        "dam.top_beam",       "dam.columns",          "dam.beams",
    "dam.n_columns",    "dam.beam_axes",  "dam.beam_gaps",      "dam.members",          "dam.fixed_ends",
    "dam.event_threshold", "dam.event_time", "dam.material",
    "phases.capture_limit", "phases.quiet_time", "phases.ke_fraction", "water.probe", "water.h_d_floating",
    "water.capture_length", "water.capture_end"};

int sd_scenario_is_capture_key(const char *key)
{
    for (size_t k = 0; k < sizeof capture_keys / sizeof capture_keys[0]; k++)
        if (!strcmp(key, capture_keys[k])) return 1;
    return 0;
}

/* Keys that never change the bits: the thread count (tests/test_threads.c), how often
 * checkpoints are written. */
static int changes_no_bit(const char *key)
{
    return !strcmp(key, "solver.threads") || !strcmp(key, "output.checkpoint_interval");
}

int sd_scenario_in_branch_hash(const char *key) { return !changes_no_bit(key) && !sd_scenario_is_capture_key(key); }

/* The scenario's keys hashed, but for those that change no bit and, unless with_capture, the
 * capture keys. */
static uint64_t scenario_hash(const sd_scenario *s, int with_capture)
{
    uint64_t h = sd_hash_init();
    const char *base = (const char *)s;
    for (int i = 0; i < N_PARAMS; i++) {
        const sd_param *p = &params[i];
        if (changes_no_bit(p->key) || (!with_capture && sd_scenario_is_capture_key(p->key))) continue;
        h = sd_hash_bytes(h, p->key, strlen(p->key) + 1);
        switch (p->type) {
        case P_DOUBLE:
            h = sd_hash_bytes(h, base + p->off, sizeof(double));
            break;
        case P_INT:
            if (p->off == OFF(seed))
                h = sd_hash_bytes(h, base + p->off, sizeof(long));
            else
                h = sd_hash_bytes(h, base + p->off, sizeof(int));
            break;
        case P_BOOL:
        case P_ENUM:
        case P_MAT:
            h = sd_hash_bytes(h, base + p->off, sizeof(int));
            break;
        case P_VEC3:
            h = sd_hash_bytes(h, base + p->off, sizeof(sd_vec3));
            break;
        case P_NUM_OR_OFF:
            h = sd_hash_bytes(h, base + p->off, sizeof(double));
            h = sd_hash_bytes(h, base + p->count_off, sizeof(int));
            break;
        case P_MEMBERS: {
            /* field by field: the line and column are where it was said, not what */
            const sd_dam_member *m = (const sd_dam_member *)(base + p->off);
            const int n = *(const int *)(base + p->count_off);
            h = sd_hash_bytes(h, &n, sizeof n);
            for (int k = 0; k < n; k++) {
                h = sd_hash_bytes(h, &m[k].from, sizeof m[k].from);
                h = sd_hash_bytes(h, &m[k].to, sizeof m[k].to);
                h = sd_hash_bytes(h, &m[k].diameter, sizeof m[k].diameter);
            }
            break;
        }
        case P_DLIST:
        case P_ILIST:
        case P_MLIST: {
            int n = *(const int *)(base + p->count_off);
            h = sd_hash_bytes(h, &n, sizeof n);
            h = sd_hash_bytes(h, base + p->off, (size_t)n * (p->type == P_DLIST ? sizeof(double) : sizeof(int)));
            break;
        }
        }
    }
    /* explicit elements, field by field (the struct has padding) */
    h = sd_hash_bytes(h, &s->n_elems, sizeof s->n_elems);
    for (int i = 0; i < s->n_elems; i++) {
        const sd_elem_def *d = &s->elems[i];
        h = sd_hash_bytes(h, &d->type, sizeof d->type);
        h = sd_hash_bytes(h, &d->pos, sizeof d->pos);
        h = sd_hash_bytes(h, &d->vel, sizeof d->vel);
        h = sd_hash_bytes(h, &d->omega, sizeof d->omega);
        h = sd_hash_bytes(h, &d->axis, sizeof d->axis);
        h = sd_hash_bytes(h, &d->radius, sizeof d->radius);
        h = sd_hash_bytes(h, &d->length, sizeof d->length);
        h = sd_hash_bytes(h, &d->density, sizeof d->density);
        h = sd_hash_bytes(h, &d->fixed, sizeof d->fixed);
        h = sd_hash_bytes(h, &d->tag, sizeof d->tag);
        h = sd_hash_bytes(h, &d->group, sizeof d->group);
        h = sd_hash_bytes(h, &d->material, sizeof d->material);
        h = sd_hash_bytes(h, d->v, sizeof d->v);
    }
    /* the materials' names and the pairs' springs (the keys name materials by id) */
    h = sd_scenario_materials_hash(s, h);
    /* the meshes as read and transformed */
    h = sd_hash_bytes(h, &s->n_meshes, sizeof s->n_meshes);
    for (int k = 0; k < s->n_meshes; k++) {
        const sd_mesh_def *m = &s->meshes[k];
        h = sd_hash_bytes(h, &m->role, sizeof m->role);
        h = sd_hash_bytes(h, &m->material, sizeof m->material);
        h = sd_hash_bytes(h, &m->n_tri, sizeof m->n_tri);
        h = sd_hash_bytes(h, m->tri, (size_t)m->n_tri * sizeof *m->tri);
    }
    /* fields outside the table that the scene uses */
    h = sd_hash_bytes(h, &s->world.parallel_min, sizeof s->world.parallel_min);
    return h;
}

uint64_t sd_scenario_branch_hash(const sd_scenario *s) { return scenario_hash(s, 0); }

uint64_t sd_scenario_run_hash(const sd_scenario *s) { return scenario_hash(s, 1); }
