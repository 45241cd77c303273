/* A scenario's cost (elements, memory, steps, wall time) estimated from its parameters alone,
 * before anything is allocated, and checked against the limits the user can raise. All in
 * doubles: counts times sizes cannot overflow, and an absurd scene gives an absurd, finite or
 * infinite, estimate that the check refuses. */
#include <math.h>

#include "build.h"
#include "core/vmath.h"
#include "scenario.h"

/* Cells of a placement grid over [lo, hi] (build.c's sd_placer), each a pointer and two ints. */
static double placer_bytes(sd_vec3 lo, sd_vec3 hi, double cell)
{
    const double n = (floor((hi.x - lo.x) / cell) + 1) * (floor((hi.y - lo.y) / cell) + 1) *
                     (floor((hi.z - lo.z) / cell) + 1);
    return n * (double)(sizeof(int *) + 2 * sizeof(int));
}

void sd_scenario_estimate(const sd_scenario *s, sd_scenario_cost *c)
{
    double bodies = s->n_elems, fixed = 0.0, bytes = 0.0;
    for (int k = 0; k < s->n_elems; k++)
        fixed += s->elems[k].fixed || s->elems[k].type == 2;
    if (s->pile_n_classes > 0) {
        for (int k = 0; k < s->pile_n_classes && k < s->pile_n_counts; k++)
            bodies += s->pile_count[k];
        bytes += placer_bytes(s->pile_min, s->pile_max, sd_build_placer_cell(s, 1));
    }
    double duration = s->duration, flow_duration = 0.0, expected = s->duration;
    if (s->flume_on) {
        double vs = 0.0;
        for (int k = 0; k < s->n_classes && k < s->n_class_counts; k++) {
            bodies += s->class_count[k];
            vs += s->class_count[k] * M_PI / 6.0 * pow(s->class_diam[k], 3);
        }
        if (s->log_count >= 0)
            bodies += s->log_count;
        else if (s->log_kw > 0.0)
            bodies += s->log_kw * vs / (1.0 - s->log_kw) / sd_build_log_mean_volume(s, 0);
        const double L = s->x_end, W = s->width;
        if (s->roughness_on) {
            const double r = 0.5 * s->rough_dmin;
            const double n_rough = ceil(s->rough_coverage * L * W / (M_PI * r * r));
            bodies += n_rough;
            fixed += n_rough;
            const double dm = s->rough_dmax;
            bytes += placer_bytes(v3(0, 0, -dm), v3(L, W, dm), dm);
        }
        if (s->dam_on) {
            bodies += 2 * SD_MAX_PIPES + s->n_members;
            fixed += 2 * SD_MAX_PIPES + s->n_members;
        }
        bytes += placer_bytes(v3(0, 0, 0), v3(s->x_gate, W, s->pack_height), sd_build_placer_cell(s, 0));
        bytes += 4.0 * (ceil(L / 0.25) + 2) * 512.0; /* the walls' triangles */
        duration = s->packing_time + s->flow_limit + s->capture_limit; /* (at most) */
        /* expected: the front at SD_COST_FRONT_SPEED_OF_U of the water's speed from the gate to
         * the dam, within the flow's limit */
        double t_flow = s->flow_limit;
        if (s->water_on && s->water_u > 0.0)
            t_flow = fmin(t_flow, fmax(s->x_dam - s->x_gate, 0.0) / (SD_COST_FRONT_SPEED_OF_U * s->water_u));
        flow_duration = s->packing_time + t_flow;
        expected = flow_duration + s->capture_limit;
    }
    for (int k = 0; k < s->n_meshes; k++) /* the meshes' triangles, as the flume's walls' */
        bytes += s->meshes[k].n_tri * 512.0;
    bytes += bodies * SD_BYTES_PER_ELEMENT;
    c->bodies = bodies;
    c->bytes = bytes;
    c->moving = fmax(bodies - fixed, 0.0);
    const double per_step = fmax(c->moving, 1.0) * SD_COST_S_PER_MOVING_STEP + fixed * SD_COST_S_PER_FIXED_STEP;
    c->steps = ceil(duration / s->world.dt);
    c->expected_steps = fmin(ceil(expected / s->world.dt), c->steps);
    c->seconds = c->expected_steps * per_step;
    c->flow_steps = fmin(ceil(flow_duration / s->world.dt), c->expected_steps);
    c->flow_seconds = c->flow_steps * per_step;
}

/* "3.2 h", "41 days", "2e+09 years" */
void sd_scenario_human_time(double t, char *buf, size_t n)
{
    if (t < 120)
        snprintf(buf, n, "%.0f s", t);
    else if (t < 7200)
        snprintf(buf, n, "%.0f min", t / 60);
    else if (t < 2 * 86400)
        snprintf(buf, n, "%.1f h", t / 3600);
    else if (t < 2 * 365.25 * 86400)
        snprintf(buf, n, "%.0f days", t / 86400);
    else
        snprintf(buf, n, "%.3g years", t / (365.25 * 86400));
}

double sd_scenario_ms(double seconds) { return round(seconds * 1000.0); }

void sd_scenario_ms_text(double ms, char *buf, size_t n)
{
    if (!(ms < 9.0e15)) { /* (past the exact integers of a double, or infinite) */
        snprintf(buf, n, "%.4g s", ms / 1000.0);
        return;
    }
    const double whole = floor(ms / 1000.0);
    snprintf(buf, n, "%.0f.%03.0f s", whole, ms - 1000.0 * whole);
}

void sd_scenario_print_time(FILE *f, const sd_scenario *s, const sd_scenario_cost *c)
{
    char all[48], flow[48], capture[48];
    const double ms = sd_scenario_ms(c->seconds), flow_ms = sd_scenario_ms(c->flow_seconds);
    sd_scenario_ms_text(ms, all, sizeof all);
    if (!s->flume_on) {
        fprintf(f, "time estimate: %s on one core\n", all);
        return;
    }
    sd_scenario_ms_text(flow_ms, flow, sizeof flow);
    sd_scenario_ms_text(ms - flow_ms, capture, sizeof capture);
    fprintf(f, "time estimate: %s on one core (packing and flow %s, capture %s)\n", all, flow, capture);
}

sd_scenario_limits sd_scenario_limits_default(void)
{
    return (sd_scenario_limits){SD_DEFAULT_MAX_MEMORY, SD_DEFAULT_MAX_STEPS};
}

/* "512 KiB", "8 GiB", "76.3 GiB" */
static void human_bytes(double b, char *buf, size_t n)
{
    static const char *const unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int k = 0;
    while (b >= 1024 && k < 6) {
        b /= 1024;
        k++;
    }
    snprintf(buf, n, "%.3g %s", b, unit[k]);
}

int sd_scenario_check_cost(const sd_scenario *s, const sd_scenario_cost *c, const sd_scenario_limits *lim, FILE *err)
{
    int bad = 0;
    if (!(c->bytes <= lim->max_bytes)) {
        char need[32], have[32];
        human_bytes(c->bytes, need, sizeof need);
        human_bytes(lim->max_bytes, have, sizeof have);
        fprintf(err,
                "%s: the scene needs about %s of memory (%.4g elements), more than the limit of %s; make it smaller "
                "(counts, flume size, placement boxes) or raise the limit with --max-memory\n",
                s->path, need, c->bodies, have);
        bad = 1;
    }
    if (!(c->steps <= lim->max_steps)) {
        char t[64];
        sd_scenario_human_time(c->seconds, t, sizeof t);
        fprintf(err,
                "%s: the run takes up to %.4g time steps (solver.dt = %g s over %g s simulated; about %s on one core "
                "expected); "
                "more than the limit of %.3g steps: lengthen solver.dt, shorten the run, or raise the limit with "
                "--max-steps\n",
                s->path, c->steps, s->world.dt, c->steps * s->world.dt, t, lim->max_steps);
        bad = 1;
    }
    return bad ? -1 : 0;
}
