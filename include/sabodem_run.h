/* sabodem's driver, public: scenarios (YAML files or text) and runs of them, stepped or whole,
 * with the world to read between steps and the summary as JSON. The command line and the
 * Python package (python/sabodem) use it; the engine's own API is sabodem.h. Units: SI.
 *
 *   sd_scenario *s; char err[4096];
 *   if (sd_scenario_load_file("flume.yaml", NULL, 0, &s, err, sizeof err)) { puts(err); ... }
 *   sd_run *r;
 *   if (sd_run_create(s, "out/flume", &r, err, sizeof err)) { ... }
 *   sd_run_advance(r, 0.5);              // to t = 0.5 s, or the run's end if sooner
 *   const sd_world *w = sd_run_world(r); // sd_world_bodies(w): the bodies' arrays
 *   sd_run_advance(r, HUGE_VAL);         // to the end of the phases
 *   sd_run_finish(r);                    // final outputs and summary.json
 *   char *json = sd_run_summary_json(r); ... sd_free(json);
 *   sd_run_destroy(r); sd_scenario_destroy(s);
 */
#ifndef SABODEM_RUN_H
#define SABODEM_RUN_H

#include <stddef.h>

#include "sabodem.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sd_scenario sd_scenario;
typedef struct sd_run sd_run;

/* The library's version, "MAJOR.MINOR.PATCH". */
const char *sd_version(void);
/* The source it was built from: "git <commit>", with "+<hash>" of the uncommitted changes to
 * src/, include/ and CMakeLists.txt when there are any, or "unknown" (not built from a git
 * checkout). */
const char *sd_build_id(void);

/* A scenario from a YAML file, or from YAML text (name: what its messages call it), with
 * "key=value" overrides (as `--set`). 0 on success; else 2 with every error in err, each as
 * file:line:col: message, and *out NULL. */
int sd_scenario_load_file(const char *path, const char *const *overrides, int n_overrides, sd_scenario **out, char *err,
                          size_t err_len);
int sd_scenario_load_text(const char *yaml, const char *name, const char *const *overrides, int n_overrides,
                          sd_scenario **out, char *err, size_t err_len);
void sd_scenario_destroy(sd_scenario *s);

/* A run of s (which must outlive it) writing its outputs into outdir (created): the world
 * built, the first outputs written, no step taken. threads: 0 for the scenario's. 0 on
 * success; else the exit code (2 bad input, 1 failure) with the message in err. */
int sd_run_create(const sd_scenario *s, const char *outdir, int threads, sd_run **out, char *err, size_t err_len);
/* Step until the simulated time reaches t (s) or the run ends (its phases done, or a failure):
 * 1 while the run goes on, 0 when it has ended (sd_run_status says how). */
int sd_run_advance(sd_run *r, double t);
/* Step to the end of the current phase (the flow phase ends when the front reaches the dam):
 * as sd_run_advance. */
int sd_run_advance_phase(sd_run *r);
/* The phase now: "packing", "flow", "capture", "done", or "run" (a scene without a flume). */
const char *sd_run_phase(const sd_run *r);
/* The world, to read between steps (sd_world_bodies, sd_world_time, ...); the run's own. */
const sd_world *sd_run_world(const sd_run *r);
/* End the run where it is: the final outputs and summary.json written (once). Returns the exit
 * code: 0 done, 1 failed. */
int sd_run_finish(sd_run *r);
/* The exit code so far (0 while well) and the summary's status ("finished", a failure, ...). */
int sd_run_status(const sd_run *r, const char **message);
/* The messages the run has written (failures), "" when none; valid until the next call. */
const char *sd_run_messages(sd_run *r);
/* The summary as summary.json has it, as JSON text (sd_free it); NULL when out of memory. */
char *sd_run_summary_json(sd_run *r);
void sd_run_destroy(sd_run *r);
/* Free what the library handed out. */
void sd_free(void *p);

#ifdef __cplusplus
}
#endif

#endif
