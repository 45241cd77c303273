/* Builders: box, random pile, flume, gate, bed roughness, grid dam, packing (SPEC §6, §8). */
#ifndef SD_BUILD_H
#define SD_BUILD_H

#include "core/rng.h"
#include "scenario.h"

/* The builders' wall groups. A mesh (scenario meshes:) joins the group of its role: bed, walls,
 * or SD_GROUP_DAM, the dam body whose load the run reports (series.csv, summary.json). */
enum { SD_GROUP_BED = 0, SD_GROUP_WALLS = 1, SD_GROUP_END = 2, SD_GROUP_GATE = 3, SD_GROUP_BOX = 4, SD_GROUP_DAM = 5 };
/* The placement grid's smallest cell (the pile and the flume's packing box), m. */
#define SD_PLACER_CELL 0.025
/* The most logs a scene holds (logs.count's range; logs.k_w may not ask for more). */
#define SD_MAX_LOGS 1000000

enum { SD_TAG_ROUGH = 100, SD_TAG_LOG = 200, SD_TAG_PIPE = 300 };

typedef struct {
    int n_pipes;
    int pipe_gid[2 * SD_MAX_PIPES];
    int pipe_is_column[2 * SD_MAX_PIPES];
    double pipe_coord[2 * SD_MAX_PIPES]; /* y of a column, z of a beam's axis */
    int n_rough, n_spheres, n_logs;
    int first_moving_gid;
} sd_build_info;

/* Open-top box of triangles between lo and hi. */
sd_status sd_build_box(sd_world *w, sd_vec3 lo, sd_vec3 hi, int group);
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

/* The scene of a scenario: explicit elements, box, pile, flume with everything in it. */
sd_status sd_build_scene(sd_world *w, const sd_scenario *s, sd_build_info *info, FILE *err);
/* The same; with_dam = 0 leaves the grid dam's pipes out (the run driver builds the scene so
 * and adds them with sd_build_dam at the start of the capture phase, so that packing and flow
 * do not depend on the dam layout and a sweep can branch into layouts from one flow). The bed
 * roughness keeps the dam foot clear either way. */
sd_status sd_build_scene_ex(sd_world *w, const sd_scenario *s, sd_build_info *info, FILE *err, int with_dam);
/* The grid dam of fixed cylinders, upstream face at flume.x_dam (nothing when dam.on is
 * false); appends the pipes to info's pipe lists. */
sd_status sd_build_dam(sd_world *w, const sd_scenario *s, sd_build_info *info);
/* Grid dam layout from l_h / l_v / top_beam or the explicit lists (SPEC §8). Returns 0, or -1
 * when l_h across the width needs more than SD_MAX_PIPES columns (the first SD_MAX_PIPES are
 * given). */
int sd_build_dam_layout(const sd_scenario *s, double *col_y, int *n_col, double *beam_z, int *n_beam);
/* The placement grid's cell for the flume's packing box (pile = 0) or the pile (pile = 1):
 * SD_PLACER_CELL, or the largest diameter placed there when larger (at field scale, cells of
 * 25 mm would number 1e8 in the reservoir and a 1 m boulder would cover 64,000 of them). The
 * cell changes no placement: it only sorts the candidates of the exact overlap test. */
double sd_build_placer_cell(const sd_scenario *s, int pile);
/* Number of logs from logs.count or logs.k_w and the sphere volume (eq 54). */
int sd_build_log_count(const sd_scenario *s);

#endif
