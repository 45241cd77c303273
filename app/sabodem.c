/* sabodem: the only main(). Subcommands: run, check, sweep, params, man, completion (their table
 * in commands.c). Exit codes: 0 ok, 1 run failed,
 * 2 bad input or usage, 130 interrupted. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "build.h"
#include "run.h"
#include "scenario.h"
#include "scene_report.h"
#include "commands.h"
#include "completion.h"
#include "manpage.h"
#include "plot.h"
#include "ranks.h"
#include "sweep.h"

static volatile sig_atomic_t stop_flag = 0;

static void on_sigint(int sig)
{
    (void)sig;
    stop_flag = 1;
}

/* Ctrl-C, a kill, a closed terminal or a closed pipe downstream (`sabodem run ... | head`) all
 * stop the run as Ctrl-C does, with every output file closed and valid: none kills it. */
static void stop_on_signals(struct sigaction *sa)
{
    sigaction(SIGINT, sa, NULL);
    sigaction(SIGTERM, sa, NULL);
    sigaction(SIGHUP, sa, NULL);
    sigaction(SIGPIPE, sa, NULL);
}

/* `sabodem COMMAND --help`: 1 when argv asks for it (and it was printed) */
static int command_help(const char *cmd, int argc, char **argv)
{
    const app_command *c = app_command_find(cmd);
    for (int i = 2; c && i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: %s\n\n%s\n", c->usage, c->help);
            return 1;
        }
    return 0;
}

/* an option the command does not know (or one missing its value): the message, with the
 * nearest option the command has; 2 */
static int bad_option(const char *cmd, const char *opt)
{
    char hint[96];
    fprintf(stderr, "sabodem %s: unknown or incomplete option '%s'%s\n", cmd, opt,
            app_did_you_mean(app_command_find(cmd), opt, hint, sizeof hint));
    fprintf(stderr, "usage: %s\n", app_command_find(cmd)->usage);
    return 2;
}

/* A count option's value: 0 and *v set when it is an integer in [lo, hi], else a message naming
 * the option and 2. */
static int int_option(const char *opt, const char *text, long lo, long hi, long *v)
{
    char *end;
    errno = 0;
    const long x = strtol(text, &end, 10);
    if (errno || end == text || *end || x < lo || x > hi) {
        fprintf(stderr, "sabodem: %s: expected an integer from %ld to %ld, got '%s'\n", opt, lo, hi, text);
        return 2;
    }
    *v = x;
    return 0;
}

/* --max-memory (bytes, with an optional K, M, G or T: powers of 1024) or --max-steps (a count,
 * 1e9 allowed): 0 and *v set, else a message naming the option and 2. */
static int limit_option(const char *opt, const char *text, int bytes, double *v)
{
    char *end;
    errno = 0;
    double x = strtod(text, &end);
    if (bytes && *end && !end[1]) {
        const char *u = strchr("KMGT", *end);
        if (u) {
            x *= (double)(1ull << (10 * (u - "KMGT" + 1)));
            end++;
        }
    }
    if (errno || end == text || *end || !(x >= 1) || !(x < 1e30)) {
        fprintf(stderr, "sabodem: %s: expected a positive %s, got '%s'\n", opt,
                bytes ? "size in bytes (suffix K, M, G or T)" : "number of steps", text);
        return 2;
    }
    *v = x;
    return 0;
}

/* The engine's tuning from the environment (SD_SIMD, SD_PREFETCH; sd_tuning_from_env): how it
 * runs, never what it computes, so a value it does not know is a warning, not an error. */
static void tuning_from_env(sd_tuning *t)
{
    char msg[200];
    if (sd_tuning_from_env(t, msg, sizeof msg)) fprintf(stderr, "sabodem: warning: %s: ignored\n", msg);
}

static void draw_run_pictures(const sd_run_result *res, FILE *log) { app_draw_pictures(res, log); }

static const char *basename_noext(const char *path, char *buf, size_t n)
{
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    snprintf(buf, n, "%s", b);
    char *dot = strrchr(buf, '.');
    if (dot && dot != buf) *dot = 0;
    return buf;
}

/* `check --png`: the design's data into a fresh temporary directory, drawn by
 * scripts/plot_design.py, then removed. 0 when drawn, else 1 with the script's output. */
static int draw_design(const sd_scenario *s, const sd_world *w, const char *png)
{
    if (!s->flume_on) {
        fprintf(stderr, "sabodem: --png draws a flume and its dam; %s has no flume (flume.on: false)\n", s->path);
        return 2;
    }
    const char *tmpdir = getenv("TMPDIR");
    char dir[1024], logp[1100];
    snprintf(dir, sizeof dir, "%s/sabodem-design-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
    if (!mkdtemp(dir)) {
        fprintf(stderr, "sabodem: cannot create a temporary directory in %s: %s\n", tmpdir ? tmpdir : "/tmp",
                strerror(errno));
        return 1;
    }
    snprintf(logp, sizeof logp, "%s/plot.log", dir);
    int code = sd_scene_write_design(dir, s, w, stderr) ? 1 : 0;
    if (!code && app_draw_design(dir, png, logp)) {
        fprintf(stderr, "sabodem: %s not drawn (python3-matplotlib missing, or scripts/plot_design.py not found):\n", png);
        FILE *l = fopen(logp, "r");
        char line[512];
        while (l && fgets(line, sizeof line, l))
            fputs(line, stderr);
        if (l) fclose(l);
        code = 1;
    } else if (!code)
        printf("design drawn: %s\n", png);
    static const char *files[] = {"design.csv", "members.csv", "bodies.csv", "plot.log"};
    for (int k = 0; k < 4; k++) {
        char p[1200];
        snprintf(p, sizeof p, "%s/%s", dir, files[k]);
        remove(p);
    }
    rmdir(dir);
    return code;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        app_print_usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
        app_print_usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version") || !strcmp(cmd, "version")) {
        printf("sabodem %s\n", SD_VERSION);
        return 0;
    }
    if (command_help(cmd, argc, argv)) return 0;
    if (!strcmp(cmd, "params") || !strcmp(cmd, "man")) {
        int md = 0;
        for (int i = 2; i < argc; i++)
            if (!strcmp(cmd, "params") && !strcmp(argv[i], "--markdown")) md = 1;
            else return bad_option(cmd, argv[i]);
        if (!strcmp(cmd, "man"))
            app_print_man(stdout, SD_VERSION);
        else
            sd_scenario_print_params(stdout, md ? SD_PARAMS_MARKDOWN : SD_PARAMS_TEXT);
        return 0;
    }
    if (!strcmp(cmd, "completion")) {
        if (argc != 3 || strcmp(argv[2], "bash")) {
            fprintf(stderr, "sabodem completion: the one shell is bash (sabodem completion bash)\n");
            return 2;
        }
        app_print_bash_completion(stdout);
        return 0;
    }
    if (!strcmp(cmd, "sweep")) {
        const char *file = NULL, *outdir = NULL;
        sd_sweep_opts so;
        memset(&so, 0, sizeof so);
        so.limits = sd_scenario_limits_default();
        for (int i = 2; i < argc; i++) {
            if ((!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) && i + 1 < argc) outdir = argv[++i];
            else if (!strcmp(argv[i], "--parallel") && i + 1 < argc) {
                char *end;
                long p = strtol(argv[++i], &end, 10);
                if (*end || end == argv[i] || p < 1 || p > 4096) {
                    fprintf(stderr, "sabodem: --parallel: expected a positive integer, got '%s'\n", argv[i]);
                    return 2;
                }
                so.parallel = (int)p;
            } else if (!strcmp(argv[i], "--max-memory") && i + 1 < argc) {
                if (limit_option("--max-memory", argv[++i], 1, &so.limits.max_bytes)) return 2;
            } else if (!strcmp(argv[i], "--max-steps") && i + 1 < argc) {
                if (limit_option("--max-steps", argv[++i], 0, &so.limits.max_steps)) return 2;
            } else if (!strcmp(argv[i], "--dry-run")) so.dry_run = 1;
            else if (!strcmp(argv[i], "--no-branch")) so.no_branch = 1;
            else if (!strcmp(argv[i], "--collect")) so.collect = 1;
            else if (!strcmp(argv[i], "--emit") && i + 1 < argc) so.emit = argv[++i];
            else if (!strcmp(argv[i], "--shard") && i + 1 < argc) {
                int u, n, len = 0;
                if (sscanf(argv[++i], "%d/%d%n", &u, &n, &len) != 2 || argv[i][len] || n < 1 || u < 0 || u >= n) {
                    fprintf(stderr, "sabodem: --shard: expected U/N with 0 <= U < N, got '%s'\n", argv[i]);
                    return 2;
                }
                so.shard = u;
                so.shards = n;
            }
            else if (argv[i][0] == '-') return bad_option(cmd, argv[i]);
            else file = argv[i];
        }
        if (!file) {
            fprintf(stderr, "sabodem: no sweep file given\n");
            return 2;
        }
        char name[256], dirbuf[512];
        if (!outdir) {
            snprintf(dirbuf, sizeof dirbuf, "out/%s", basename_noext(file, name, sizeof name));
            outdir = dirbuf;
        }
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_sigint;
        stop_on_signals(&sa);
        tuning_from_env(&so.tuning);
        so.run_done = draw_run_pictures;
        char self[4096];
        ssize_t nself = readlink("/proc/self/exe", self, sizeof self - 1);
        if (nself > 0) {
            self[nself] = 0;
            so.program = self;
        }
        if ((so.collect != 0) + (so.emit != NULL) + (so.shards > 0) + (so.dry_run != 0) > 1) {
            fprintf(stderr, "sabodem: --shard, --collect, --emit and --dry-run exclude each other\n");
            return 2;
        }
        app_ranks ranks;
        if (app_ranks_start(&ranks, &argc, &argv)) return 2;
        if (ranks.active && ranks.size > 1) {
            if (so.collect || so.emit || so.shards || so.dry_run) {
                if (ranks.rank == 0)
                    fprintf(stderr, "sabodem: under mpirun the ranks are the shards: no --shard, --collect, --emit "
                                    "or --dry-run\n");
                app_ranks_finish(&ranks);
                return 2;
            }
            so.shard = ranks.rank;
            so.shards = ranks.size;
            if (so.parallel == 0) so.parallel = 1;
        }
        int code = sd_sweep_run(file, outdir, &so, &stop_flag, stdout, stderr);
        if (so.shards > 1 && ranks.active) { /* every rank's part done: rank 0 collects */
            code = app_ranks_max(&ranks, code);
            if (ranks.rank == 0 && code != 2 && code != 130) {
                sd_sweep_opts co = so;
                co.shard = co.shards = 0;
                co.collect = 1;
                int c = sd_sweep_run(file, outdir, &co, &stop_flag, stdout, stderr);
                if (c > code) code = c;
            } else if (ranks.rank != 0) {
                app_ranks_finish(&ranks);
                return code;
            }
        }
        app_ranks_finish(&ranks);
        const int summarised = (code == 0 || code == 1) && !so.dry_run && !so.emit && (so.shards <= 1 || ranks.size > 1);
        if (summarised && app_draw_sweep(outdir)) fprintf(stdout, "note: figures not drawn (see %s/plot.log)\n", outdir);
        if (summarised) printf("sweep results in %s/results.csv, %s/cases.csv\n", outdir, outdir);
        return code;
    }
    if (strcmp(cmd, "run") && strcmp(cmd, "check")) {
        char hint[96];
        fprintf(stderr, "sabodem: unknown command '%s'%s\n", cmd, app_did_you_mean(NULL, cmd, hint, sizeof hint));
        app_print_usage(stderr);
        return 2;
    }
    const char *file = NULL, *outdir = NULL, *restart = NULL, *png = NULL;
    int ckpt_flow_end = 0, overwrite = 0, decompose = 0;
    double progress = 5.0; /* s of wall time between progress lines in a log (--progress) */
    sd_scenario_limits lim = sd_scenario_limits_default();
    const char **sets = calloc((size_t)argc + 2, sizeof(char *));
    char seedbuf[64], thrbuf[64];
    int nsets = 0;
    if (!sets) return 1;
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && i + 1 < argc) outdir = argv[++i];
        else if (!strcmp(a, "--set") && i + 1 < argc) sets[nsets++] = argv[++i];
        else if (!strncmp(a, "--set=", 6)) sets[nsets++] = a + 6;
        else if (!strcmp(a, "--threads") && i + 1 < argc) {
            long v;
            if (int_option("--threads", argv[++i], 0, 1024, &v)) {
                free(sets);
                return 2;
            }
            snprintf(thrbuf, sizeof thrbuf, "solver.threads=%ld", v);
            sets[nsets++] = thrbuf;
        } else if (!strcmp(a, "--seed") && i + 1 < argc) {
            long v;
            if (int_option("--seed", argv[++i], 0, 2147483647L, &v)) {
                free(sets);
                return 2;
            }
            snprintf(seedbuf, sizeof seedbuf, "solver.seed=%ld", v);
            sets[nsets++] = seedbuf;
        } else if (!strcmp(a, "--checkpoint-at") && i + 1 < argc && !strcmp(cmd, "run")) {
            if (strcmp(argv[++i], "flow_end")) {
                fprintf(stderr, "sabodem: --checkpoint-at: unknown point '%s' (the one point is flow_end)\n", argv[i]);
                free(sets);
                return 2;
            }
            ckpt_flow_end = 1;
        } else if (!strcmp(a, "--restart") && i + 1 < argc && !strcmp(cmd, "run")) restart = argv[++i];
        else if (!strcmp(a, "--png") && i + 1 < argc && !strcmp(cmd, "check")) png = argv[++i];
        else if (!strcmp(a, "--overwrite") && !strcmp(cmd, "run")) overwrite = 1;
        else if (!strcmp(a, "--decompose") && !strcmp(cmd, "run")) decompose = 1;
        else if (!strcmp(a, "--progress") && i + 1 < argc && !strcmp(cmd, "run")) {
            char *end;
            progress = strtod(argv[++i], &end);
            if (*end || end == argv[i] || !(progress >= 0.0 && progress <= 86400.0)) {
                fprintf(stderr, "sabodem: --progress: expected seconds from 0 to 86400, got '%s'\n", argv[i]);
                free(sets);
                return 2;
            }
        }
        else if ((!strcmp(a, "--max-memory") || !strcmp(a, "--max-steps")) && i + 1 < argc) {
            const int bytes = !strcmp(a, "--max-memory");
            if (limit_option(a, argv[++i], bytes, bytes ? &lim.max_bytes : &lim.max_steps)) {
                free(sets);
                return 2;
            }
        }
        else if (a[0] == '-') {
            free(sets);
            return bad_option(cmd, a);
        } else if (!file) file = a;
        else {
            fprintf(stderr, "sabodem: more than one scenario file given ('%s')\n", a);
            free(sets);
            return 2;
        }
    }
    if (!file) {
        fprintf(stderr, "sabodem: no scenario file given\n");
        app_print_usage(stderr);
        free(sets);
        return 2;
    }
    sd_scenario s;
    if (sd_scenario_load(&s, file, sets, nsets, stderr)) {
        free(sets);
        return 2;
    }
    free(sets);
    tuning_from_env(&s.world.tuning);
    /* the memory and the steps it will take, before anything is allocated */
    sd_scenario_cost cost;
    sd_scenario_estimate(&s, &cost);
    if (sd_scenario_check_cost(&s, &cost, &lim, stderr)) {
        sd_scenario_free(&s);
        return 2;
    }
    if (!strcmp(cmd, "check")) {
        /* build the scene too: placement and stability are part of validity */
        sd_world *w;
        if (sd_world_create(&s.world, &w)) {
            fprintf(stderr, "%s: invalid solver settings\n", file);
            sd_scenario_free(&s);
            return 2;
        }
        sd_build_info info;
        sd_status st = sd_build_scene(w, &s, &info, stderr);
        if (!st) st = sd_world_check(w);
        int n = sd_world_body_count(w), t = sd_world_triangle_count(w);
        if (st) {
            sd_world_destroy(w);
            sd_scenario_free(&s);
            fprintf(stderr, "%s: %s\n", file, sd_status_message(st));
            return 2;
        }
        printf("%s: ok (%d elements, %d triangles; estimate: %.3g MB, %.4g steps expected (at most %.4g), about %.3g s "
               "on one core)\n",
               file, n, t, cost.bytes / 1e6, cost.expected_steps, cost.steps, cost.seconds);
        sd_scenario_print_time(stdout, &s, &cost);
        sd_scene_report(stdout, &s, &info, n, t);
        int code = 0;
        if (png) code = draw_design(&s, w, png);
        sd_world_destroy(w);
        sd_scenario_free(&s);
        return code;
    }
    char name[256], dirbuf[512];
    if (!outdir) {
        snprintf(dirbuf, sizeof dirbuf, "out/%s", basename_noext(file, name, sizeof name));
        outdir = dirbuf;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    stop_on_signals(&sa);
    if (ckpt_flow_end && !s.flume_on) {
        fprintf(stderr, "%s: --checkpoint-at needs a flume scenario (flume.on: true)\n", file);
        sd_scenario_free(&s);
        return 2;
    }
    char ckpt_path[600];
    snprintf(ckpt_path, sizeof ckpt_path, "%s/flow_end.ckpt", outdir);
    sd_run_opts o = {.outdir = outdir, .progress_tty = isatty(fileno(stderr)), .progress_interval = progress,
                     .stop = &stop_flag, .log = stderr, .err = stderr};
    o.checkpoint_flow_end = ckpt_flow_end ? ckpt_path : NULL;
    o.restart = restart;
    o.overwrite = overwrite;
    /* under mpirun -np N (N > 1), or with --decompose: one run over slabs, a rank each (rank 0
     * writes the files and speaks for the run) */
    app_ranks ranks;
    if (app_ranks_start(&ranks, &argc, &argv)) {
        sd_scenario_free(&s);
        return 2;
    }
    sd_run_comm comm;
    FILE *quiet = NULL;
    o.decompose = decompose || (ranks.active && ranks.size > 1);
    if (o.decompose && !app_ranks_comm(&ranks, &comm)) {
        o.comm = &comm;
        if (comm.rank != 0) {
            quiet = fopen("/dev/null", "w");
            o.log = NULL;
            o.err = quiet ? quiet : stderr;
            o.progress_tty = 0;
        }
    }
    sd_run_result r;
    memset(&r, 0, sizeof r);
    int code = sd_run_scenario(&s, &o, &r);
    const int speaker = ranks.rank == 0;
    app_ranks_finish(&ranks);
    if (quiet) fclose(quiet);
    if (speaker) app_draw_pictures(&r, stderr);
    if (speaker && (code == 0 || code == 130)) {
        printf("%s: %s, %ld steps, %.1f s wall", file, code ? "interrupted" : "done", r.steps, r.wall_time);
        if (s.flume_on) printf(", trap ratio P_V = %.4f (capture limit %.2f s)", r.p_v, s.capture_limit);
        printf("; outputs in %s\n", outdir);
    }
    sd_scenario_free(&s);
    return code;
}
