/* Builders: box, random pile, flume, gate, bed roughness, grid dam, packing (SPEC §6, §8). */
#ifndef SD_BUILD_H
#define SD_BUILD_H

#include "core/rng.h"
#include "debris.h"
#include "scenario.h"

/* The builders' wall groups. A mesh (scenario meshes:) joins the group of its role: bed, walls,
 * or SD_GROUP_DAM, the dam body whose load the run reports (series.csv, summary.json). */
enum { SD_GROUP_BED = 0, SD_GROUP_WALLS = 1, SD_GROUP_END = 2, SD_GROUP_GATE = 3, SD_GROUP_BOX = 4, SD_GROUP_DAM = 5 };
/* The placement grid's smallest cell (the pile and the flume's packing box), m. */
#define SD_PLACER_CELL 0.025
/* The most logs a scene holds (logs.count's range; logs.k_w may not ask for more). */
#define SD_MAX_LOGS 1000000

enum { SD_TAG_ROUGH = 100, SD_TAG_LOG = 200, SD_TAG_PIPE = 300 };

/* The kinds of a dam's pipes; the grid's two are the values the run-driver state has always
 * held for a column (1) and a beam (0). */
enum { SD_PIPE_BEAM = 0, SD_PIPE_COLUMN = 1, SD_PIPE_MEMBER = 2 };
/* The most pipes a dam holds: the grid's columns and beams, and the members. */
#define SD_MAX_DAM_PIPES (2 * SD_MAX_PIPES + SD_MAX_MEMBERS)

typedef struct {
    int n_pipes;
    int pipe_gid[SD_MAX_DAM_PIPES];
    int pipe_kind[SD_MAX_DAM_PIPES];     /* SD_PIPE_* */
    double pipe_coord[SD_MAX_DAM_PIPES]; /* y of a column, z of a beam's axis, a member's index in dam.members */
    int n_rough, n_spheres, n_logs;
    int first_moving_gid;
} sd_build_info;

/* The grid of a dam: its columns and beams (SPEC §8), from the keys of scenario.h. */
typedef struct {
    int n_col, n_beam;
    double col_y[SD_MAX_PIPES];  /* column axes across the flume, m (the wall at y = 0), ascending */
    double beam_z[SD_MAX_PIPES]; /* beam axes above the bed, m, ascending; the top beam (top_beam) last */
    int top_beam;                /* 1: beam_z[n_beam - 1] is dam.top_beam's */
    double col_top;              /* the columns stand from the bed to here: the top of the highest beam, or
                                    the wall top when there is no beam, m */
} sd_dam_grid;

/* One pipe of a dam as it is built: a fixed cylinder. */
typedef struct {
    int kind;          /* SD_PIPE_* */
    double coord;      /* as sd_build_info.pipe_coord */
    sd_vec3 from, to;  /* the axis's ends: a column's from the bed up, a beam's from the wall at
                          y = 0, a member's as given */
    sd_vec3 centre, axis; /* the cylinder's centre and axis direction (not normalised), m */
    double length, radius; /* m */
} sd_dam_pipe;

/* Open-top box of triangles between lo and hi, of a material. */
sd_status sd_build_box(sd_world *w, sd_vec3 lo, sd_vec3 hi, int group, int material);
/* Put `count` spheres of diameter d at random, without overlap with anything placed so far
 * by this placer, inside [lo, hi]. */
typedef struct sd_placer sd_placer;
/* NULL when out of memory, or when the box is empty, not finite or too many cells. */
sd_placer *sd_placer_create(sd_vec3 lo, sd_vec3 hi, double cell);
void sd_placer_destroy(sd_placer *p);
/* Returns 1 when placed, 0 when no room was found in max_tries. */
int sd_placer_try_sphere(sd_placer *p, sd_rng *rng, double r, double clearance, int max_tries, sd_vec3 *pos);
int sd_placer_try_cylinder(sd_placer *p, sd_rng *rng, double r, double hl, double clearance, int max_tries,
                           sd_vec3 *pos, sd_vec3 *axis);
/* Register an existing body (sphere when hl = 0) with the placer. */
void sd_placer_add(sd_placer *p, sd_vec3 pos, sd_vec3 axis, double r, double hl);

/* The scene of a scenario: the springs of its pairs of materials, explicit elements, box, pile,
 * flume with everything in it, each of its material. */
sd_status sd_build_scene(sd_world *w, const sd_scenario *s, sd_build_info *info, FILE *err);
/* The same; with_dam = 0 leaves the grid dam's pipes out (the run driver builds the scene so
 * and adds them with sd_build_dam at the start of the capture phase, so that packing and flow
 * do not depend on the dam layout and a sweep can branch into layouts from one flow). The bed
 * roughness keeps the dam foot clear either way. */
sd_status sd_build_scene_ex(sd_world *w, const sd_scenario *s, sd_build_info *info, FILE *err, int with_dam);
/* The dam of fixed cylinders, the grid's upstream face at flume.x_dam, and its members (nothing
 * when dam.on is false); appends the pipes to info's pipe lists. */
sd_status sd_build_dam(sd_world *w, const sd_scenario *s, sd_build_info *info);
/* The grid of columns and beams (docs/scenario.md, "The dam"): the columns from dam.columns,
 * dam.n_columns or dam.l_h, the beams from dam.beams, or from dam.beam_axes, dam.beam_gaps or
 * dam.l_v with the top beam unless dam.top_beam is false. Returns 0, or -1 when l_h across the
 * width needs more than SD_MAX_PIPES columns (the first SD_MAX_PIPES are given). */
int sd_build_dam_grid(const sd_scenario *s, sd_dam_grid *g);
/* Every pipe of the dam, in the order sd_build_dam adds them: the grid's columns, its beams,
 * then dam.members; returns how many (at most SD_MAX_DAM_PIPES). */
int sd_build_dam_pipes(const sd_scenario *s, const sd_dam_grid *g, sd_dam_pipe *out);
/* "column", "beam" or "member" */
const char *sd_build_pipe_kind_name(int kind);
/* The least distance between the segments p0–p1 and q0–q1 (either may be a point), m. */
double sd_build_segment_distance(sd_vec3 p0, sd_vec3 p1, sd_vec3 q0, sd_vec3 q1);
/* The placement grid's cell for the flume's packing box (pile = 0) or the pile (pile = 1):
 * SD_PLACER_CELL, or the largest diameter placed there when larger (at field scale, cells of
 * 25 mm would number 1e8 in the reservoir and a 1 m boulder would cover 64,000 of them). The
 * cell changes no placement: it only sorts the candidates of the exact overlap test. */
double sd_build_placer_cell(const sd_scenario *s, int pile);
/* Number of logs from logs.count or logs.k_w and the sphere volume (eq 54). With sizes drawn
 * (logs.length.type or logs.diameter.type not fixed), the count from K_w takes the logs of the
 * logs' stream (debris.h) in order, as many as bring their volume nearest to eq 54's V_t. */
int sd_build_log_count(const sd_scenario *s);
/* 1 when a log size is drawn per log (logs.length.type or logs.diameter.type not fixed). */
int sd_build_log_sizes_vary(const sd_scenario *s);
/* A log's expected solid volume, π/4 E[d²] E[L] (paper = 1: E[d²] E[L], the paper's count of a
 * log as d² L), m^3. */
double sd_build_log_mean_volume(const sd_scenario *s, int paper);
/* The logs a flume scenario releases, as the builder makes them: count, length and diameter
 * (smallest, mean, standard deviation of the sample, largest; m) and solid volume (m^3). */
typedef struct {
    int n;
    double len_min, len_mean, len_sd, len_max;
    double d_min, d_mean, d_sd, d_max;
    double volume;
} sd_log_stats;
void sd_build_log_stats(const sd_scenario *s, sd_log_stats *st);

#endif
