/* A program of someone else's, built against the installed library (tests/install_test.sh):
 * a scenario from text, stepped to its end, the bodies read, the summary printed. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sabodem.h>
#include <sabodem_run.h>

int main(int argc, char **argv)
{
    const char *yaml = "solver: {dt: 1.0e-5, duration: 0.01}\n"
                       "gravity: [0, 0, -9.81]\n"
                       "elements:\n"
                       "  - {type: sphere, radius: 0.005, density: 1900, position: [0, 0, 0.1]}\n";
    char err[4096];
    sd_scenario *s;
    if (sd_scenario_load_text(yaml, "drop", NULL, 0, &s, err, sizeof err)) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    sd_run *r;
    if (sd_run_create(s, argc > 1 ? argv[1] : "out-drop", 1, &r, err, sizeof err)) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    sd_run_advance(r, HUGE_VAL);
    const int code = sd_run_finish(r);
    const sd_body_view b = sd_world_bodies(sd_run_world(r));
    /* a free fall for 0.01 s from rest: z = 0.1 - g t^2 / 2 */
    printf("sabodem %s: %d body, z = %.6f m, t = %.4f s, exit %d\n", sd_version(), b.n, b.pos[0].z,
           sd_world_time(sd_run_world(r)), code);
    char *json = sd_run_summary_json(r);
    const int ok = json && strstr(json, "\"status\":\t\"finished\"") != NULL;
    sd_free(json);
    sd_run_destroy(r);
    sd_scenario_destroy(s);
    return code || !ok;
}
