/* The driver's public face (sabodem_run.h): scenarios loaded with their errors returned as
 * text, and runs taken a stretch at a time through run.c's three parts. */
#include <stdlib.h>
#include <string.h>

#include "core/status.h"
#include "run_ctx.h"
#include "sabodem_run.h"
#include "sd_build_id.h" /* (generated at each build: scripts/build_id.cmake) */

#ifndef SD_VERSION
#error "SD_VERSION (the project's version) comes from CMakeLists.txt"
#endif

const char *sd_version(void) { return SD_VERSION; }

const char *sd_build_id(void) { return SD_BUILD_ID; }

void sd_free(void *p) { free(p); }

/* text (NULL: "") into err, cut to fit */
static void copy_message(char *err, size_t err_len, const char *text)
{
    if (err && err_len) snprintf(err, err_len, "%s", text ? text : "");
}

/* load a scenario from a file (text NULL) or from text, its messages caught into err */
static int load(const char *path, const char *text, const char *const *overrides, int n_overrides, sd_scenario **out,
                char *err, size_t err_len)
{
    *out = NULL;
    char *msg = NULL;
    size_t msg_len = 0;
    sd_scenario *s = malloc(sizeof *s);
    FILE *m = open_memstream(&msg, &msg_len);
    if (!s || !m) {
        if (m) fclose(m);
        free(msg);
        free(s);
        copy_message(err, err_len, "out of memory");
        return 1;
    }
    const int bad = text ? sd_scenario_load_string(s, text, path, overrides, n_overrides, m)
                         : sd_scenario_load(s, path, overrides, n_overrides, m);
    fclose(m);
    copy_message(err, err_len, msg);
    free(msg);
    if (bad) {
        free(s);
        return 2;
    }
    *out = s;
    return 0;
}

int sd_scenario_load_file(const char *path, const char *const *overrides, int n_overrides, sd_scenario **out, char *err,
                          size_t err_len)
{
    return load(path, NULL, overrides, n_overrides, out, err, err_len);
}

int sd_scenario_load_text(const char *yaml, const char *name, const char *const *overrides, int n_overrides,
                          sd_scenario **out, char *err, size_t err_len)
{
    return load(name ? name : "<text>", yaml ? yaml : "", overrides, n_overrides, out, err, err_len);
}

void sd_scenario_destroy(sd_scenario *s)
{
    if (!s) return;
    sd_scenario_free(s);
    free(s);
}

int sd_run_create(const sd_scenario *s, const char *outdir, int threads, sd_run **out, char *err, size_t err_len)
{
    *out = NULL;
    sd_run *r = calloc(1, sizeof *r);
    if (r) r->err_stream = open_memstream(&r->err_text, &r->err_len);
    if (!r || !r->err_stream) {
        free(r);
        copy_message(err, err_len, "out of memory");
        return 1;
    }
    r->o.outdir = outdir;
    r->o.err = r->err_stream; /* no progress lines: the caller asks what it wants to know */
    r->c.s = s;
    r->c.o = &r->o;
    r->c.wall0 = sd_now();
    const int code = sd_run_begin(r);
    fflush(r->err_stream);
    copy_message(err, err_len, r->err_text);
    if (code) {
        fclose(r->err_stream);
        free(r->err_text);
        free(r);
        return code;
    }
    if (threads > 0) sd_world_set_threads(r->c.w, threads);
    *out = r;
    return 0;
}

/* step while keep(r) says so and the run goes on; 1 while it goes on */
static int advance_while(sd_run *r, int (*keep)(const sd_run *r, const void *arg), const void *arg)
{
    while (!r->ended && !r->finished && keep(r, arg))
        if (sd_run_step_once(r)) r->ended = 1;
    return !r->ended && !r->finished;
}

static int before_time(const sd_run *r, const void *arg)
{
    return sd_world_time(r->c.w) < *(const double *)arg - 0.5 * r->c.s->world.dt;
}

int sd_run_advance(sd_run *r, double t) { return advance_while(r, before_time, &t); }

/* The phase as the caller sees it: once the flow has reached the dam, the capture (the pipes
 * go in at the next step). */
static int phase_now(const sd_run *r) { return r->c.phase == PH_FLOW && r->c.flow_ended ? PH_CAPTURE : r->c.phase; }

static int same_phase(const sd_run *r, const void *arg) { return phase_now(r) == *(const int *)arg; }

int sd_run_advance_phase(sd_run *r)
{
    const int phase = phase_now(r);
    return advance_while(r, same_phase, &phase);
}

const char *sd_run_phase(const sd_run *r) { return sd_run_phase_name(phase_now(r)); }

const sd_world *sd_run_world(const sd_run *r) { return r->c.w; }

int sd_run_finish(sd_run *r)
{
    if (!r->finished) {
        if (!r->ended && !r->code) r->msg = "stopped before the end";
        sd_run_end(r);
    }
    return r->code;
}

int sd_run_status(const sd_run *r, const char **message)
{
    if (message) *message = r->msg;
    return r->code;
}

const char *sd_run_messages(sd_run *r)
{
    fflush(r->err_stream);
    return r->err_text ? r->err_text : "";
}

char *sd_run_summary_json(sd_run *r)
{
    char *text = sd_output_summary_text(&r->c, &r->res, r->code, r->msg);
    char *copy = text ? strdup(text) : NULL;
    sd_output_summary_free(text);
    return copy;
}

void sd_run_destroy(sd_run *r)
{
    if (!r) return;
    if (!r->finished) sd_output_close(&r->c);
    sd_pipe_loads_free(&r->c.loads);
    sd_world_destroy(r->c.w);
    fclose(r->err_stream);
    free(r->err_text);
    free(r);
}
