/* sabodem: the only main(). Subcommands: run, check, params. Exit codes: 0 ok, 1 run failed,
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
#include "plot.h"
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

/* The subcommands' help, one table: usage lines, then what each does and its options. */
static const struct {
    const char *name, *usage, *help;
} commands[] = {
    {"run", "sabodem run FILE [-o DIR] [--set key=value]... [--threads N] [--seed S]\n"
            "                 [--checkpoint-at flow_end] [--restart CHECKPOINT] [--max-memory BYTES] [--max-steps N]",
     "simulate the scenario; outputs go to DIR (default out/<scenario name>)\n"
     "  -o, --output DIR          the output directory\n"
     "  --set key=value           override a scenario key (sabodem params lists them)\n"
     "  --threads N               threads (solver.threads; 0: all cores)\n"
     "  --seed S                  the random seed (solver.seed)\n"
     "  --checkpoint-at flow_end  also write DIR/flow_end.ckpt when the flow reaches the dam\n"
     "  --restart CHECKPOINT      continue from such a checkpoint (the capture phase only); FILE may\n"
     "                            differ from the writer's scenario only in the dam layout and\n"
     "                            capture-phase keys (docs/sweep.md)\n"
     "  --max-memory BYTES        refuse a scene estimated to need more memory (default 8G;\n"
     "                            suffixes K, M, G, T)\n"
     "  --max-steps N             refuse a run of more time steps (default 1e8)"},
    {"check", "sabodem check FILE [--set key=value]... [--max-memory BYTES] [--max-steps N]",
     "validate the scenario, estimate its memory and steps, and build its scene without running"},
    {"sweep", "sabodem sweep FILE [-o DIR] [--parallel N] [--dry-run] [--no-branch] [--max-memory BYTES]\n"
              "                 [--max-steps N]",
     "run a matrix of cases x seeds in parallel (resumable), with CSV and figures; runs that\n"
     "differ only in the dam layout share one packing + flow (docs/sweep.md)\n"
     "  --parallel N  processes at once (default: the sweep file's, else the cores)\n"
     "  --dry-run     list the runs and shared flows, and what is already done\n"
     "  --no-branch   every run packs and flows on its own\n"
     "  --max-memory BYTES, --max-steps N   the limits each run's estimate must keep to (as run)"},
    {"params", "sabodem params [--markdown]", "list every scenario key with its type, unit, default and range"},
};
enum { N_COMMANDS = sizeof commands / sizeof commands[0] };

static void usage(FILE *f)
{
    for (int k = 0; k < N_COMMANDS; k++)
        fprintf(f, "%s %s\n", k ? "      " : "usage:", commands[k].usage);
    fprintf(f, "       sabodem --version\n\n");
    for (int k = 0; k < N_COMMANDS; k++) {
        const char *h = commands[k].help;
        fprintf(f, "%-7s ", commands[k].name);
        for (; *h; h++) { /* (the help's lines indented under the name) */
            fputc(*h, f);
            if (*h == '\n') fputs("        ", f);
        }
        fputc('\n', f);
    }
    fprintf(f, "\n"
               "sabodem COMMAND --help shows one command.\n"
               "environment (how the engine runs; the results are the same bits whatever they say):\n"
               "  SD_SIMD=scalar|avx2|avx512|auto   the hand-written kernels' width (auto: the CPU's best,\n"
               "                                    AVX2 on AMD CPUs)\n"
               "  SD_PREFETCH=on|off|auto           the contact pass's prefetch (auto: tried during the run)\n"
               "  OMP_NUM_THREADS                   threads when --threads is not given\n"
               "  SABODEM_SCRIPTS                   where the plotting scripts are, if not beside the program\n");
}

/* `sabodem COMMAND --help`: 1 when argv asks for it (and it was printed) */
static int command_help(const char *cmd, int argc, char **argv)
{
    for (int i = 2; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h"))
            for (int k = 0; k < N_COMMANDS; k++)
                if (!strcmp(cmd, commands[k].name)) {
                    printf("usage: %s\n\n%s\n", commands[k].usage, commands[k].help);
                    return 1;
                }
    return 0;
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

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version") || !strcmp(cmd, "version")) {
        printf("sabodem %s\n", SD_VERSION);
        return 0;
    }
    if (command_help(cmd, argc, argv)) return 0;
    if (!strcmp(cmd, "params")) {
        sd_scenario_print_params(stdout, argc > 2 && !strcmp(argv[2], "--markdown"));
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
            else if (argv[i][0] == '-') {
                fprintf(stderr, "sabodem: unknown or incomplete option '%s'\n", argv[i]);
                return 2;
            } else file = argv[i];
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
        int code = sd_sweep_run(file, outdir, &so, &stop_flag, stdout, stderr);
        if ((code == 0 || code == 1) && !so.dry_run && app_draw_sweep(outdir))
            fprintf(stdout, "note: figures not drawn (see %s/plot.log)\n", outdir);
        if ((code == 0 || code == 1) && !so.dry_run) printf("sweep results in %s/results.csv, %s/cases.csv\n", outdir, outdir);
        return code;
    }
    if (strcmp(cmd, "run") && strcmp(cmd, "check")) {
        fprintf(stderr, "sabodem: unknown command '%s'\n", cmd);
        usage(stderr);
        return 2;
    }
    const char *file = NULL, *outdir = NULL, *restart = NULL;
    int ckpt_flow_end = 0;
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
        else if ((!strcmp(a, "--max-memory") || !strcmp(a, "--max-steps")) && i + 1 < argc) {
            const int bytes = !strcmp(a, "--max-memory");
            if (limit_option(a, argv[++i], bytes, bytes ? &lim.max_bytes : &lim.max_steps)) {
                free(sets);
                return 2;
            }
        }
        else if (a[0] == '-') {
            fprintf(stderr, "sabodem: unknown or incomplete option '%s'\n", a);
            usage(stderr);
            free(sets);
            return 2;
        } else if (!file) file = a;
        else {
            fprintf(stderr, "sabodem: more than one scenario file given ('%s')\n", a);
            free(sets);
            return 2;
        }
    }
    if (!file) {
        fprintf(stderr, "sabodem: no scenario file given\n");
        usage(stderr);
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
        sd_world_destroy(w);
        sd_scenario_free(&s);
        if (st) {
            fprintf(stderr, "%s: %s\n", file, sd_status_message(st));
            return 2;
        }
        printf("%s: ok (%d elements, %d triangles; estimate: %.3g MB, %.4g steps, about %.3g s on one core)\n", file,
               n, t, cost.bytes / 1e6, cost.steps, cost.seconds);
        return 0;
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
    if ((ckpt_flow_end || restart) && !s.flume_on) {
        fprintf(stderr, "%s: --%s needs a flume scenario (flume.on: true)\n", file, restart ? "restart" : "checkpoint-at");
        sd_scenario_free(&s);
        return 2;
    }
    char ckpt_path[600];
    snprintf(ckpt_path, sizeof ckpt_path, "%s/flow_end.ckpt", outdir);
    sd_run_opts o = {.outdir = outdir, .progress_tty = isatty(fileno(stderr)), .stop = &stop_flag, .log = stderr, .err = stderr};
    o.checkpoint_flow_end = ckpt_flow_end ? ckpt_path : NULL;
    o.restart = restart;
    sd_run_result r;
    memset(&r, 0, sizeof r);
    int code = sd_run_scenario(&s, &o, &r);
    app_draw_pictures(&r, stderr);
    if (code == 0 || code == 130) {
        printf("%s: %s, %ld steps, %.1f s wall", file, code ? "interrupted" : "done", r.steps, r.wall_time);
        if (s.flume_on) printf(", trap ratio P_V = %.4f (capture limit %.2f s)", r.p_v, s.capture_limit);
        printf("; outputs in %s\n", outdir);
    }
    sd_scenario_free(&s);
    return code;
}
