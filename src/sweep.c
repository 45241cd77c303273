/* The sweep driver. Each run is a child process (fork) running one scenario with one thread,
 * so the runs share nothing and a crash of one does not take the others down. A run is done
 * when its directory holds result.csv; resuming skips those. */
#include "sweep.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "run.h"
#include "scenario.h"
#include "world_internal.h"
#include "yaml_tree.h"

#define MAX_VARY 8
#define MAX_VALUES 32
#define MAX_SETS 64

typedef struct {
    char base[1024];
    int runs;
    long seed_base;
    int n_vary;
    char vary_key[MAX_VARY][128];
    char vary_val[MAX_VARY][MAX_VALUES][64];
    int n_val[MAX_VARY];
    int n_set;
    char set[MAX_SETS][256];
    int parallel;
} sweep_def;

static int load_sweep(const char *path, sweep_def *d, FILE *err)
{
    memset(d, 0, sizeof(*d));
    d->runs = 1;
    d->seed_base = 1;
    char msg[1024];
    sd_ynode *root = sd_yaml_load(path, msg, sizeof msg);
    if (!root) {
        fprintf(err, "%s\n", msg);
        return -1;
    }
    int bad = 0;
    if (root->kind != SD_Y_MAP) {
        fprintf(err, "%s:%d:%d: a sweep file is a mapping (base, runs, vary, set)\n", path, root->line, root->col);
        bad = 1;
    }
    for (int i = 0; !bad && i < root->n; i++) {
        const char *k = root->keys[i];
        const sd_ynode *v = root->items[i];
        if (!strcmp(k, "base") && v->kind == SD_Y_SCALAR) {
            /* relative to the sweep file's directory */
            const char *slash = strrchr(path, '/');
            if (v->value[0] != '/' && slash)
                snprintf(d->base, sizeof d->base, "%.*s/%s", (int)(slash - path), path, v->value);
            else snprintf(d->base, sizeof d->base, "%s", v->value);
        } else if ((!strcmp(k, "runs") || !strcmp(k, "seed_base") || !strcmp(k, "parallel")) && v->kind == SD_Y_SCALAR) {
            char *end;
            long x = strtol(v->value, &end, 10);
            if (*end || x < 0 || (!strcmp(k, "runs") && x < 1)) {
                fprintf(err, "%s:%d:%d: %s: expected a %s integer\n", path, v->line, v->col, k,
                        !strcmp(k, "runs") ? "positive" : "non-negative");
                bad = 1;
            } else if (!strcmp(k, "runs")) d->runs = (int)x;
            else if (!strcmp(k, "seed_base")) d->seed_base = x;
            else d->parallel = (int)x;
        } else if (!strcmp(k, "vary") && v->kind == SD_Y_MAP) {
            for (int j = 0; j < v->n && !bad; j++) {
                const sd_ynode *vals = v->items[j];
                if (d->n_vary == MAX_VARY || vals->kind != SD_Y_SEQ || vals->n < 1 || vals->n > MAX_VALUES) {
                    fprintf(err, "%s:%d:%d: vary.%s: expected a list of 1..%d values\n", path, vals->line, vals->col,
                            v->keys[j], MAX_VALUES);
                    bad = 1;
                    break;
                }
                snprintf(d->vary_key[d->n_vary], sizeof d->vary_key[0], "%s", v->keys[j]);
                for (int q = 0; q < vals->n; q++) {
                    if (vals->items[q]->kind != SD_Y_SCALAR) {
                        fprintf(err, "%s:%d:%d: vary.%s: values must be scalars\n", path, vals->items[q]->line,
                                vals->items[q]->col, v->keys[j]);
                        bad = 1;
                        break;
                    }
                    snprintf(d->vary_val[d->n_vary][q], sizeof d->vary_val[0][0], "%s", vals->items[q]->value);
                }
                d->n_val[d->n_vary++] = vals->n;
            }
        } else if (!strcmp(k, "set") && v->kind == SD_Y_MAP) {
            for (int j = 0; j < v->n && d->n_set < MAX_SETS; j++) {
                if (v->items[j]->kind != SD_Y_SCALAR) {
                    fprintf(err, "%s:%d:%d: set.%s: expected a scalar value\n", path, v->items[j]->line,
                            v->items[j]->col, v->keys[j]);
                    bad = 1;
                    break;
                }
                snprintf(d->set[d->n_set++], sizeof d->set[0], "%s=%s", v->keys[j], v->items[j]->value);
            }
        } else {
            fprintf(err, "%s:%d:%d: unknown or malformed key '%s' (base, runs, seed_base, parallel, vary, set)\n", path,
                    root->key_line[i], root->key_col[i], k);
            bad = 1;
        }
    }
    if (!bad && !d->base[0]) {
        fprintf(err, "%s:1:1: missing 'base' (the scenario file to vary)\n", path);
        bad = 1;
    }
    sd_yaml_free(root);
    return bad ? -1 : 0;
}

typedef struct {
    int case_id, seed;
    int idx[MAX_VARY];
    char dir[1200];
} run_item;

/* Overrides for one run: the sweep's fixed sets, the case values, the seed. */
static int run_overrides(const sweep_def *d, const run_item *r, char buf[][256], const char **ptr)
{
    int n = 0;
    for (int k = 0; k < d->n_set; k++) {
        snprintf(buf[n], 256, "%s", d->set[k]);
        ptr[n] = buf[n];
        n++;
    }
    for (int v = 0; v < d->n_vary; v++) {
        snprintf(buf[n], 256, "%s=%s", d->vary_key[v], d->vary_val[v][r->idx[v]]);
        ptr[n] = buf[n];
        n++;
    }
    snprintf(buf[n], 256, "solver.seed=%d", r->seed);
    ptr[n] = buf[n];
    n++;
    snprintf(buf[n], 256, "solver.threads=1");
    ptr[n] = buf[n];
    n++;
    return n;
}

static int file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

static volatile sig_atomic_t child_stop = 0;

static void on_term(int sig)
{
    (void)sig;
    child_stop = 1;
}

static int child_run(const sweep_def *d, const run_item *r)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
    char buf[MAX_SETS + MAX_VARY + 4][256];
    const char *ptr[MAX_SETS + MAX_VARY + 4];
    int n = run_overrides(d, r, buf, ptr);
    sd_scenario s;
    char logp[1300];
    snprintf(logp, sizeof logp, "%s.log", r->dir);
    FILE *log = fopen(logp, "w");
    if (!log) return 1;
    if (sd_scenario_load(&s, d->base, ptr, n, log)) {
        fclose(log);
        return 2;
    }
    sd_run_opts o = {r->dir, 0, &child_stop, log, log};
    sd_run_result res;
    double t0 = sd_now();
    int code = sd_run_scenario(&s, &o, &res);
    double wall = sd_now() - t0;
    if (code == 0) {
        /* result.csv marks the run done: written last, atomically */
        char path[1300], tmp[1400];
        snprintf(path, sizeof path, "%s/result.csv", r->dir);
        snprintf(tmp, sizeof tmp, "%s.tmp", path);
        FILE *f = fopen(tmp, "w");
        if (!f) code = 1;
        else {
            fprintf(f, "%d,%d", r->case_id, r->seed);
            for (int v = 0; v < d->n_vary; v++) fprintf(f, ",%s", d->vary_val[v][r->idx[v]]);
            fprintf(f, ",%.6f", res.p_v);
            for (int k = 0; k < SD_MAX_CLASSES && k < s.n_classes; k++) fprintf(f, ",%.6f", res.p_v_class[k]);
            for (int k = s.n_classes; k < 4; k++) fprintf(f, ",");
            fprintf(f, ",%.6f,%.6e,%d,%.2f,%.4f\n", res.p_v_logs, res.peak_dam_force, res.n_passed, wall,
                    s.capture_limit);
            if (fclose(f) || rename(tmp, path)) code = 1;
        }
    }
    sd_scenario_free(&s);
    fclose(log);
    return code;
}

int sd_sweep_run(const char *sweep_file, const char *outdir, int parallel, volatile sig_atomic_t *stop, FILE *log,
                 FILE *err)
{
    sweep_def d;
    if (load_sweep(sweep_file, &d, err)) return 2;
    int ncase = 1;
    for (int v = 0; v < d.n_vary; v++) ncase *= d.n_val[v];
    int total = ncase * d.runs;
    run_item *items = calloc((size_t)total, sizeof(*items));
    if (!items) return 1;
    /* validate every case before running anything */
    int bad = 0;
    for (int c = 0; c < ncase; c++)
        for (int s = 0; s < d.runs; s++) {
            run_item *r = &items[c * d.runs + s];
            r->case_id = c;
            r->seed = (int)(d.seed_base + s);
            int rem = c;
            for (int v = d.n_vary - 1; v >= 0; v--) {
                r->idx[v] = rem % d.n_val[v];
                rem /= d.n_val[v];
            }
            snprintf(r->dir, sizeof r->dir, "%s/runs/case%03d_seed%d", outdir, c, r->seed);
            if (s == 0) {
                char buf[MAX_SETS + MAX_VARY + 4][256];
                const char *ptr[MAX_SETS + MAX_VARY + 4];
                int n = run_overrides(&d, r, buf, ptr);
                sd_scenario sc;
                if (sd_scenario_load(&sc, d.base, ptr, n, err)) {
                    fprintf(err, "%s: case %d is invalid (see above)\n", sweep_file, c);
                    bad = 1;
                } else sd_scenario_free(&sc);
            }
        }
    if (bad) {
        free(items);
        return 2;
    }
    char runs_dir[1200];
    snprintf(runs_dir, sizeof runs_dir, "%s/runs", outdir);
    if (sd_mkdir_p(runs_dir)) {
        fprintf(err, "%s: cannot create: %s\n", outdir, strerror(errno));
        free(items);
        return 1;
    }
    if (parallel <= 0) parallel = d.parallel;
    if (parallel <= 0) parallel = (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (parallel < 1) parallel = 1;
    int done = 0, failed = 0, skipped = 0, next = 0, running = 0;
    pid_t *pids = calloc((size_t)total, sizeof(pid_t));
    double t0 = sd_now();
    for (int i = 0; i < total; i++) {
        char p[1300];
        snprintf(p, sizeof p, "%s/result.csv", items[i].dir);
        if (file_exists(p)) {
            pids[i] = -1;
            skipped++;
        }
    }
    fprintf(log, "sweep %s: %d cases x %d runs = %d runs, %d already done, %d in parallel\n", sweep_file, ncase, d.runs,
            total, skipped, parallel);
    int interrupted = 0;
    while (1) {
        while (!interrupted && running < parallel && next < total) {
            if (pids[next] == -1) {
                next++;
                continue;
            }
            fflush(NULL);
            pid_t pid = fork();
            if (pid == 0) {
                signal(SIGINT, SIG_IGN); /* the parent stops the children */
                _exit(child_run(&d, &items[next]));
            }
            if (pid < 0) {
                fprintf(err, "sweep: fork failed: %s\n", strerror(errno));
                break;
            }
            pids[next++] = pid;
            running++;
        }
        if (running == 0) break;
        int status;
        pid_t pid = waitpid(-1, &status, 0);
        if (pid < 0) {
            if (errno == EINTR) {
                if (stop && *stop && !interrupted) {
                    interrupted = 1;
                    for (int i = 0; i < total; i++)
                        if (pids[i] > 0) kill(pids[i], SIGTERM);
                }
                continue;
            }
            break;
        }
        running--;
        for (int i = 0; i < total; i++)
            if (pids[i] == pid) {
                pids[i] = 0;
                int ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
                if (ok) done++;
                else if (!interrupted) {
                    failed++;
                    fprintf(err, "sweep: run %s failed (see %s.log)\n", items[i].dir, items[i].dir);
                }
                break;
            }
        double el = sd_now() - t0;
        int remaining = total - skipped - done - failed;
        fprintf(log, "sweep: %d/%d done (%d skipped, %d failed), %d running, elapsed %.0f s, ETA %.0f s\n",
                done + skipped, total, skipped, failed, running, el,
                done > 0 ? el / done * remaining / (running > 0 ? 1.0 : 1.0) : 0.0);
        fflush(log);
        if (stop && *stop && !interrupted) {
            interrupted = 1;
            for (int i = 0; i < total; i++)
                if (pids[i] > 0) kill(pids[i], SIGTERM);
        }
    }
    /* results.csv from every finished run, in run order */
    char path[1300], tmp[1400];
    snprintf(path, sizeof path, "%s/results.csv", outdir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (f) {
        fprintf(f, "case,seed");
        for (int v = 0; v < d.n_vary; v++) fprintf(f, ",%s", d.vary_key[v]);
        fprintf(f, ",p_v,p_v_class0,p_v_class1,p_v_class2,p_v_class3,p_v_logs,peak_dam_force_N,passed,wall_s,capture_limit_s\n");
        for (int i = 0; i < total; i++) {
            char rp[1300], line[2048];
            snprintf(rp, sizeof rp, "%s/result.csv", items[i].dir);
            FILE *r = fopen(rp, "r");
            if (!r) continue;
            if (fgets(line, sizeof line, r)) fputs(line, f);
            fclose(r);
        }
        fclose(f);
        rename(tmp, path);
    }
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 \"%s/scripts/plot_sweep.py\" \"%s\" > \"%s/plot.log\" 2>&1", SD_SOURCE_DIR,
             outdir, outdir);
    if (!interrupted && system(cmd) != 0) fprintf(log, "note: figures not drawn (see %s/plot.log)\n", outdir);
    free(pids);
    free(items);
    if (interrupted) return 130;
    return failed ? 1 : 0;
}
