/* The sweep driver. Each run is a child process (fork) running one scenario with one thread,
 * so the runs share nothing and a crash of one does not take the others down. A run is done
 * when its directory holds result.csv; resuming skips those, and a run or flow killed on the way
 * continues from its newest periodic checkpoint (output.checkpoint_interval) when it has one.
 *
 * Branching (docs/sweep.md): runs that differ only in capture-phase keys (the dam layout and
 * the capture settings, sd_scenario_is_capture_key) have the same packing and flow, bit for
 * bit. The sweep groups them by everything else and the seed, runs packing + flow once per
 * group (a child that stops at the flow end and leaves DIR/branch/<key>/flow_end.ckpt), then
 * each run of the group continues from that checkpoint with its own layout. A checkpoint,
 * written atomically, marks its flow done; resuming reuses it, after reading it whole: a
 * damaged or foreign one is refused (the sweep stops before running anything and names it). */
#include "sweep.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <unistd.h>

#include "run.h"
#include "scenario.h"
#include "scene_report.h"
#include "core/status.h"
#include "yaml_tree.h"

#define MAX_VARY 8
#define MAX_VALUES 32
#define MAX_SETS 64
#define MAX_RUNS 10000 /* runs in one sweep (the paper's matrix: 60) */

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
    sd_tuning tuning; /* the caller's (sd_sweep_opts), for every run */
    void (*run_done)(const sd_run_result *res, FILE *log);
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
            int n;
            if (v->value[0] != '/' && slash)
                n = snprintf(d->base, sizeof d->base, "%.*s/%s", (int)(slash - path), path, v->value);
            else
                n = snprintf(d->base, sizeof d->base, "%s", v->value);
            if (n < 0 || (size_t)n >= sizeof d->base || !v->value[0]) {
                fprintf(err, "%s:%d:%d: base: expected a scenario file's path (at most %zu characters)\n", path,
                        v->line, v->col, sizeof d->base - 1);
                bad = 1;
            }
        } else if ((!strcmp(k, "runs") || !strcmp(k, "seed_base") || !strcmp(k, "parallel")) &&
                   v->kind == SD_Y_SCALAR) {
            char *end;
            errno = 0;
            long x = strtol(v->value, &end, 10);
            const int runs = !strcmp(k, "runs"), seed = !strcmp(k, "seed_base");
            const long hi = runs ? MAX_RUNS : seed ? 2147483647L - MAX_RUNS : 4096;
            if (errno || end == v->value || *end || x < runs || x > hi) {
                fprintf(err, "%s:%d:%d: %s: expected an integer from %d to %ld\n", path, v->line, v->col, k, runs, hi);
                bad = 1;
            } else if (!strcmp(k, "runs"))
                d->runs = (int)x;
            else if (!strcmp(k, "seed_base"))
                d->seed_base = x;
            else
                d->parallel = (int)x;
        } else if (!strcmp(k, "vary") && v->kind == SD_Y_MAP) {
            for (int j = 0; j < v->n && !bad; j++) {
                const sd_ynode *vals = v->items[j];
                if (d->n_vary == MAX_VARY || vals->kind != SD_Y_SEQ || vals->n < 1 || vals->n > MAX_VALUES) {
                    fprintf(err, "%s:%d:%d: vary.%s: expected a list of 1..%d values\n", path, vals->line, vals->col,
                            v->keys[j], MAX_VALUES);
                    bad = 1;
                    break;
                }
                if (strlen(v->keys[j]) >= sizeof d->vary_key[0]) {
                    fprintf(err, "%s:%d:%d: vary: a key of %zu characters (at most %zu)\n", path, v->key_line[j],
                            v->key_col[j], strlen(v->keys[j]), sizeof d->vary_key[0] - 1);
                    bad = 1;
                    break;
                }
                snprintf(d->vary_key[d->n_vary], sizeof d->vary_key[0], "%s", v->keys[j]);
                for (int q = 0; q < vals->n; q++) {
                    if (vals->items[q]->kind != SD_Y_SCALAR ||
                        strlen(vals->items[q]->value) >= sizeof d->vary_val[0][0]) {
                        fprintf(err, "%s:%d:%d: vary.%s: values must be scalars of at most %zu characters\n", path,
                                vals->items[q]->line, vals->items[q]->col, v->keys[j], sizeof d->vary_val[0][0] - 1);
                        bad = 1;
                        break;
                    }
                    snprintf(d->vary_val[d->n_vary][q], sizeof d->vary_val[0][0], "%s", vals->items[q]->value);
                }
                d->n_val[d->n_vary++] = vals->n;
            }
        } else if (!strcmp(k, "set") && v->kind == SD_Y_MAP) {
            for (int j = 0; j < v->n && !bad; j++) {
                if (d->n_set == MAX_SETS) {
                    fprintf(err, "%s:%d:%d: set: more than %d keys\n", path, v->key_line[j], v->key_col[j], MAX_SETS);
                    bad = 1;
                    break;
                }
                if (v->items[j]->kind != SD_Y_SCALAR ||
                    strlen(v->keys[j]) + strlen(v->items[j]->value) + 2 > sizeof d->set[0]) {
                    fprintf(err, "%s:%d:%d: set.%s: expected a scalar value (key and value within %zu characters)\n",
                            path, v->items[j]->line, v->items[j]->col, v->keys[j], sizeof d->set[0] - 2);
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
    /* the number of runs, in doubles: 8 keys of 32 values each are 32^8 cases, past any int */
    double total = d->runs;
    for (int v = 0; v < d->n_vary; v++)
        total *= d->n_val[v];
    if (!bad && total > MAX_RUNS) {
        const sd_ynode *vn = sd_yaml_get(root, "vary");
        fprintf(err, "%s:%d:%d: vary: %.4g runs (cases x runs), more than %d: split the sweep\n", path,
                vn ? vn->line : 1, vn ? vn->col : 1, total, MAX_RUNS);
        bad = 1;
    }
    if (!bad && !d->base[0]) {
        fprintf(err, "%s:1:1: missing 'base' (the scenario file to vary)\n", path);
        bad = 1;
    }
    sd_yaml_free(root);
    return bad ? -1 : 0;
}

/* ST_OTHER: another shard's run */
enum { ST_PENDING = 0, ST_RUNNING, ST_DONE, ST_FAILED, ST_SKIPPED, ST_READY, ST_UNNEEDED, ST_OTHER };

typedef struct {
    int case_id, seed, seed_idx;
    int idx[MAX_VARY];
    char name[64];
    char dir[1200];
    int group; /* branch group, -1: a straight run */
    int state;
    pid_t pid;
} run_item;

typedef struct {
    char key[256];
    char dir[1200];
    char ckpt[1300];
    int first; /* a member run (its overrides build the shared flow) */
    int n_runs, n_todo;
    int state; /* ST_PENDING (to compute), ST_RUNNING, ST_READY, ST_FAILED, ST_UNNEEDED */
    int reused;
    pid_t pid;
    double t_start;
} branch_item;

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

static int load_run_scenario(const sweep_def *d, const run_item *r, sd_scenario *s, FILE *err)
{
    char buf[MAX_SETS + MAX_VARY + 4][256];
    const char *ptr[MAX_SETS + MAX_VARY + 4];
    int n = run_overrides(d, r, buf, ptr);
    if (sd_scenario_load(s, d->base, ptr, n, err)) return 1;
    s->world.tuning = d->tuning;
    return 0;
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

static void child_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
}

/* The child holds DIR.lock (a POSIX record lock, which the kernel drops when the process ends,
 * however it ends) while it works in DIR: a child left by a sweep killed outright, still
 * stopping, and the resumed sweep's child for the same directory never write there at once.
 * 0 once held; -1 when it cannot be taken or the sweep is stopping. */
static int lock_dir(const char *dir)
{
    char p[1300];
    snprintf(p, sizeof p, "%s.lock", dir);
    int fd = open(p, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) return -1;
    struct flock l;
    memset(&l, 0, sizeof l);
    l.l_type = F_WRLCK;
    l.l_whence = SEEK_SET;
    while (fcntl(fd, F_SETLKW, &l))
        if (errno != EINTR || child_stop) return -1;
    return 0; /* (fd stays open: the lock lives as long as the process) */
}

/* The newest periodic checkpoint in dir (output.checkpoint_interval: what a killed child left)
 * that this run can continue from, into path; 0 if there is one. A damaged one is passed over
 * for the one before it. */
static int resume_point(const sd_scenario *s, const char *dir, char *path, size_t n)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    char best[2][64] = {"", ""}; /* the newest two (the run keeps two) */
    for (struct dirent *e; (e = readdir(d));) {
        const char *name = e->d_name;
        if (strlen(name) != 26 || strncmp(name, "checkpoint_", 11) || strcmp(name + 21, ".ckpt")) continue;
        if (strcmp(name, best[0]) > 0) {
            memcpy(best[1], best[0], sizeof best[0]);
            snprintf(best[0], sizeof best[0], "%s", name);
        } else if (strcmp(name, best[1]) > 0)
            snprintf(best[1], sizeof best[1], "%s", name);
    }
    closedir(d);
    for (int k = 0; k < 2 && best[k][0]; k++) {
        char msg[2048];
        snprintf(path, n, "%s/%s", dir, best[k]);
        if (sd_run_check_restart(s, path, msg, sizeof msg) == 0) return 0;
    }
    return -1;
}

/* Packing and flow of one branch group, up to the flow-end checkpoint. */
static int child_flow(const sweep_def *d, const run_item *r, const branch_item *g)
{
    child_signals();
    if (lock_dir(g->dir)) return child_stop ? 130 : 1;
    char logp[1300];
    snprintf(logp, sizeof logp, "%s.log", g->dir);
    FILE *log = fopen(logp, "w");
    if (!log) return 1;
    sd_scenario s;
    if (load_run_scenario(d, r, &s, log)) {
        fclose(log);
        return 2;
    }
    /* (the directory is the sweep's: what a killed flow left there goes) */
    sd_run_opts o = {.outdir = g->dir, .stop = &child_stop, .log = log, .err = log, .overwrite = 1};
    o.checkpoint_flow_end = g->ckpt;
    o.stop_at_flow_end = 1;
    char resume[1400];
    if (resume_point(&s, g->dir, resume, sizeof resume) == 0) o.restart = resume;
    sd_run_result res;
    int code = sd_run_scenario(&s, &o, &res);
    if (code == 0 && !res.stopped_at_flow_end) code = 1;
    sd_scenario_free(&s);
    fclose(log);
    return code;
}

/* One run: straight, or the capture of a branch from its group's checkpoint. */
static int child_run(const sweep_def *d, const run_item *r, const char *restart)
{
    child_signals();
    if (lock_dir(r->dir)) return child_stop ? 130 : 1;
    sd_scenario s;
    char logp[1300];
    snprintf(logp, sizeof logp, "%s.log", r->dir);
    FILE *log = fopen(logp, "w");
    if (!log) return 1;
    if (load_run_scenario(d, r, &s, log)) {
        fclose(log);
        return 2;
    }
    /* (the directory is the sweep's: what a killed run left there goes) */
    sd_run_opts o = {.outdir = r->dir, .stop = &child_stop, .log = log, .err = log, .overwrite = 1};
    o.restart = restart;
    char resume[1400];
    if (resume_point(&s, r->dir, resume, sizeof resume) == 0) o.restart = resume;
    sd_run_result res;
    double t0 = sd_now();
    int code = sd_run_scenario(&s, &o, &res);
    if (code == 0 && d->run_done) d->run_done(&res, log);
    double wall = sd_now() - t0;
    if (code == 0) {
        /* result.csv marks the run done: written last, atomically */
        char path[1300], tmp[1400];
        snprintf(path, sizeof path, "%s/result.csv", r->dir);
        snprintf(tmp, sizeof tmp, "%s.tmp", path);
        FILE *f = fopen(tmp, "w");
        if (!f)
            code = 1;
        else {
            fprintf(f, "%d,%d", r->case_id, r->seed);
            for (int v = 0; v < d->n_vary; v++)
                fprintf(f, ",%s", d->vary_val[v][r->idx[v]]);
            fprintf(f, ",%.6f", res.p_v);
            for (int k = 0; k < SD_MAX_CLASSES && k < s.n_classes; k++)
                fprintf(f, ",%.6f", res.p_v_class[k]);
            /* the run's own K_w and l_V/d_max (docs/sweep.md), for the figures */
            sd_dam_report dr;
            sd_dam_report_make(&s, &dr);
            const double lvd = dr.n_beam > 0 && dr.d_max > 0 ? dr.gap_z[0] / dr.d_max : 0.0;
            fprintf(f, ",%.6f,%.6f,%.4f", res.p_v_logs, sd_scene_k_w(&s), lvd);
            fprintf(f, ",%.6e,%.6e,%.6e,%s,%.6e,%d,%.2f,%.4f,%.2f,%d,%016llx\n", res.v_held,
                    res.v_channel, res.v_passed, res.capture_cut ? "limit" : "settled", res.peak_dam_force,
                    res.n_passed, wall, s.capture_limit, res.flow_wall, restart != NULL,
                    (unsigned long long)res.state_hash);
            if (fclose(f) || rename(tmp, path)) code = 1;
        }
    }
    sd_scenario_free(&s);
    fclose(log);
    return code;
}

/* A directory name from the group's values: key=value pairs of the non-capture keys and the
 * seed, with anything but [A-Za-z0-9._=+-] replaced. */
static void branch_key(const sweep_def *d, const run_item *r, int gi, char *out, size_t n)
{
    char k[1024] = "";
    size_t len = 0;
    for (int v = 0; v < d->n_vary; v++) {
        if (sd_scenario_is_capture_key(d->vary_key[v])) continue;
        int w = snprintf(k + len, sizeof k - len, "%s=%s_", d->vary_key[v], d->vary_val[v][r->idx[v]]);
        if (w < 0 || (size_t)w >= sizeof k - len) {
            len = sizeof k;
            break;
        }
        len += (size_t)w;
    }
    if (len < sizeof k) snprintf(k + len, sizeof k - len, "seed%d", r->seed);
    if (len >= sizeof k || strlen(k) > 160) snprintf(k, sizeof k, "b%03d_seed%d", gi, r->seed);
    for (char *q = k; *q; q++)
        if (!((*q >= 'a' && *q <= 'z') || (*q >= 'A' && *q <= 'Z') || (*q >= '0' && *q <= '9') || strchr("._=+-", *q)))
            *q = '_';
    snprintf(out, n, "%s", k);
}

static void kill_children(run_item *items, int total, branch_item *groups, int ng)
{
    for (int i = 0; i < total; i++)
        if (items[i].state == ST_RUNNING && items[i].pid > 0) kill(items[i].pid, SIGTERM);
    for (int g = 0; g < ng; g++)
        if (groups[g].state == ST_RUNNING && groups[g].pid > 0) kill(groups[g].pid, SIGTERM);
}

/* Fields of a result.csv line (split on commas, in place); returns the count. */
static int split_csv(char *line, char **f, int max)
{
    int n = 0;
    char *p = line;
    while (n < max) {
        f[n++] = p;
        char *c = strchr(p, ',');
        if (!c) break;
        *c = '\0';
        p = c + 1;
    }
    char *nl = strchr(f[n - 1], '\n');
    if (nl) *nl = '\0';
    return n;
}

/* a string as one word of a POSIX shell script: in single quotes, each ' as '\'' */
static void put_shell_word(FILE *f, const char *s)
{
    fputc('\'', f);
    for (; *s; s++)
        if (*s == '\'') fputs("'\\''", f);
        else fputc(*s, f);
    fputc('\'', f);
}

/* p as an absolute path (the working directory before a relative one); 0, or -1 */
static int absolute_path(const char *p, char *out, size_t n)
{
    char cwd[2048];
    if (p[0] == '/') return snprintf(out, n, "%s", p) < (int)n ? 0 : -1;
    if (!getcwd(cwd, sizeof cwd)) return -1;
    return snprintf(out, n, "%s/%s", cwd, p) < (int)n ? 0 : -1;
}

/* DIR/slurm/: a job array with one task per work unit (`--shard U/N`), a job that collects
 * results.csv when the array is over, a script that submits both, and the list of units.
 * Paths are absolute and quoted (no string of the user's is ever run as shell code). */
static int emit_slurm(const sweep_def *d, const char *sweep_file, const char *outdir, const sd_sweep_opts *so,
                      int n_units, const run_item *items, int total, const branch_item *groups, int ng, FILE *err)
{
    (void)d;
    if (strcmp(so->emit, "slurm")) {
        fprintf(err, "sweep: --emit %s: unknown (the one known is slurm)\n", so->emit);
        return 2;
    }
    char dir[1200], abs_file[4096], abs_out[4096], prog[4096];
    snprintf(dir, sizeof dir, "%s/slurm", outdir);
    if (sd_mkdir_p(dir)) {
        fprintf(err, "%s: cannot create: %s\n", dir, strerror(errno));
        return 1;
    }
    if (absolute_path(sweep_file, abs_file, sizeof abs_file) || absolute_path(outdir, abs_out, sizeof abs_out)) {
        fprintf(err, "sweep: cannot make %s and %s absolute paths: %s\n", sweep_file, outdir, strerror(errno));
        return 1;
    }
    snprintf(prog, sizeof prog, "%s", so->program ? so->program : "sabodem");
    static const char *names[] = {"units.txt", "array.sh", "collect.sh", "submit.sh", "README"};
    int bad = 0;
    for (int k = 0; k < 5 && !bad; k++) {
        char path[1400], tmp[1500];
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        snprintf(tmp, sizeof tmp, "%s.tmp", path);
        FILE *f = fopen(tmp, "w");
        if (!f) {
            fprintf(err, "%s: cannot write: %s\n", tmp, strerror(errno));
            return 1;
        }
        switch (k) {
        case 0: /* unit, what it computes, its runs */
            fprintf(f, "# work units of %s: unit<TAB>what<TAB>runs (task U of the array runs unit U)\n", abs_file);
            for (int u = 0; u < n_units; u++) {
                if (ng > 0) fprintf(f, "%d\tflow %s\t", u, groups[u].key);
                else fprintf(f, "%d\trun\t", u);
                int first = 1;
                for (int i = 0; i < total; i++)
                    if ((ng > 0 ? items[i].group : i) == u) {
                        fprintf(f, "%s%s", first ? "" : " ", items[i].name);
                        first = 0;
                    }
                fputc('\n', f);
            }
            break;
        case 1:
            fprintf(f, "#!/bin/bash\n#SBATCH --job-name=sabodem-sweep\n#SBATCH --array=0-%d\n", n_units - 1);
            fprintf(f, "#SBATCH --cpus-per-task=1\n#SBATCH --output=%s/slurm/unit_%%a.log\n", abs_out);
            fprintf(f, "# one work unit of the sweep per task (units.txt); a task run again skips the runs done\n");
            fprintf(f, "exec ");
            put_shell_word(f, prog);
            fprintf(f, " sweep ");
            put_shell_word(f, abs_file);
            fprintf(f, " -o ");
            put_shell_word(f, abs_out);
            fprintf(f, " --shard \"$SLURM_ARRAY_TASK_ID/%d\" --parallel 1%s\n", n_units, so->no_branch ? " --no-branch" : "");
            break;
        case 2:
            fprintf(f, "#!/bin/bash\n#SBATCH --job-name=sabodem-collect\n#SBATCH --cpus-per-task=1\n");
            fprintf(f, "#SBATCH --output=%s/slurm/collect.log\n", abs_out);
            fprintf(f, "# results.csv, cases.csv and the figures from the finished runs\nexec ");
            put_shell_word(f, prog);
            fprintf(f, " sweep ");
            put_shell_word(f, abs_file);
            fprintf(f, " -o ");
            put_shell_word(f, abs_out);
            fprintf(f, " --collect%s\n", so->no_branch ? " --no-branch" : "");
            break;
        case 3:
            fprintf(f, "#!/bin/sh\n# submit the job array, then the collect job once the array is over\nset -e\ncd ");
            put_shell_word(f, dir);
            fprintf(f, "\njid=$(sbatch --parsable array.sh)\nsbatch --dependency=afterany:\"${jid%%%%;*}\" collect.sh\n");
            break;
        default:
            fprintf(f,
                    "Sweep %s as a Slurm job array: %d tasks, one per work unit (units.txt: a shared flow\n"
                    "and the runs that branch from it, or one run), then a job that collects results.csv.\n"
                    "Submit with: sh %s/submit.sh\n"
                    "Each task runs `sabodem sweep --shard U/%d`; a task run again skips the runs already done,\n"
                    "so a failed or cancelled task is resubmitted with: sbatch --array=U array.sh\n",
                    abs_file, n_units, dir, n_units);
        }
        if (ferror(f) | fclose(f)) bad = 1;
        if (bad || rename(tmp, path)) {
            fprintf(err, "%s: cannot write: %s\n", path, strerror(errno));
            remove(tmp);
            return 1;
        }
        if (k == 1 || k == 2 || k == 3) chmod(path, 0755);
    }
    return 0;
}

int sd_sweep_run(const char *sweep_file, const char *outdir, const sd_sweep_opts *so, volatile sig_atomic_t *stop,
                 FILE *log, FILE *err)
{
    sweep_def d;
    if (load_sweep(sweep_file, &d, err)) return 2;
    d.tuning = so->tuning;
    d.run_done = so->run_done;
    int ncase = 1;
    for (int v = 0; v < d.n_vary; v++)
        ncase *= d.n_val[v];
    int total = ncase * d.runs;
    run_item *items = calloc((size_t)total, sizeof(*items));
    if (!items) return 1;
    /* validate every case before running anything */
    int bad = 0, flume = 0, n_classes = 0;
    for (int c = 0; c < ncase; c++)
        for (int s = 0; s < d.runs; s++) {
            run_item *r = &items[c * d.runs + s];
            r->case_id = c;
            r->seed_idx = s;
            r->seed = (int)(d.seed_base + s);
            r->group = -1;
            int rem = c;
            for (int v = d.n_vary - 1; v >= 0; v--) {
                r->idx[v] = rem % d.n_val[v];
                rem /= d.n_val[v];
            }
            snprintf(r->name, sizeof r->name, "case%03d_seed%d", c, r->seed);
            snprintf(r->dir, sizeof r->dir, "%s/runs/%s", outdir, r->name);
            if (s == 0) {
                sd_scenario sc;
                sd_scenario_cost cost;
                sd_scenario_limits lim = sd_scenario_limits_default();
                if (so->limits.max_bytes > 0) lim.max_bytes = so->limits.max_bytes;
                if (so->limits.max_steps > 0) lim.max_steps = so->limits.max_steps;
                if (load_run_scenario(&d, r, &sc, err)) {
                    fprintf(err, "%s: case %d is invalid (see above)\n", sweep_file, c);
                    bad = 1;
                } else if (sd_scenario_estimate(&sc, &cost), sd_scenario_check_cost(&sc, &cost, &lim, err)) {
                    fprintf(err, "%s: case %d is too large (see above)\n", sweep_file, c);
                    sd_scenario_free(&sc);
                    bad = 1;
                } else {
                    if (c == 0) {
                        flume = sc.flume_on;
                        n_classes = sc.n_classes;
                    }
                    sd_scenario_free(&sc);
                }
            }
        }
    if (bad) {
        free(items);
        return 2;
    }
    /* branch groups: the non-capture case values and the seed */
    int layouts = 1;
    char branch_keys[512] = "";
    for (int v = 0; v < d.n_vary; v++)
        if (sd_scenario_is_capture_key(d.vary_key[v])) {
            layouts *= d.n_val[v];
            size_t l = strlen(branch_keys);
            snprintf(branch_keys + l, sizeof branch_keys - l, "%s%s", l ? ", " : "", d.vary_key[v]);
        }
    int branching = flume && layouts > 1 && !so->no_branch;
    int ng = branching ? total / layouts : 0;
    branch_item *groups = calloc((size_t)ng + 1, sizeof(*groups));
    if (!groups) {
        free(items);
        return 1;
    }
    if (branching) {
        for (int i = 0; i < total; i++) {
            run_item *r = &items[i];
            int gi = 0;
            for (int v = 0; v < d.n_vary; v++)
                if (!sd_scenario_is_capture_key(d.vary_key[v])) gi = gi * d.n_val[v] + r->idx[v];
            gi = gi * d.runs + r->seed_idx;
            r->group = gi;
            branch_item *g = &groups[gi];
            if (g->n_runs++ == 0) {
                g->first = i;
                branch_key(&d, r, gi, g->key, sizeof g->key);
                snprintf(g->dir, sizeof g->dir, "%s/branch/%s", outdir, g->key);
                snprintf(g->ckpt, sizeof g->ckpt, "%s/flow_end.ckpt", g->dir);
            }
        }
    }
    /* work units: a branch group (its flow and its runs) or one unbranched run */
    const int n_units = branching ? ng : total;
    const int shards = so->shards > 1 ? so->shards : 1;
    if (so->shards > 1 && (so->shard < 0 || so->shard >= so->shards)) {
        fprintf(err, "sweep: shard %d of %d does not exist (shards are 0 to %d)\n", so->shard, so->shards,
                so->shards - 1);
        free(groups);
        free(items);
        return 2;
    }
    int skipped = 0, others = 0;
    for (int i = 0; i < total; i++) {
        char p[1300];
        const int unit = items[i].group >= 0 ? items[i].group : i;
        snprintf(p, sizeof p, "%s/result.csv", items[i].dir);
        if (file_exists(p)) {
            items[i].state = ST_SKIPPED;
            skipped++;
        } else if (so->collect || unit % shards != so->shard % shards) {
            items[i].state = ST_OTHER;
            others++;
        } else if (items[i].group >= 0)
            groups[items[i].group].n_todo++;
    }
    if (so->emit) {
        int code = emit_slurm(&d, sweep_file, outdir, so, n_units, items, total, groups, ng, err);
        if (!code)
            fprintf(log,
                    "sweep %s: %d runs in %d work units (%s); job array and collect job written to %s/slurm/ "
                    "(see %s/slurm/README)\n",
                    sweep_file, total, n_units, branching ? "one per shared flow" : "one per run", outdir, outdir);
        free(groups);
        free(items);
        return code;
    }
    int reused = 0, to_compute = 0;
    for (int g = 0; g < ng; g++) {
        if (groups[g].n_todo == 0)
            groups[g].state = ST_UNNEEDED;
        else if (file_exists(groups[g].ckpt)) {
            groups[g].state = ST_READY;
            groups[g].reused = 1;
            reused++;
        } else {
            groups[g].state = ST_PENDING;
            to_compute++;
        }
    }
    if (so->dry_run) {
        fprintf(log, "sweep %s (dry run, outputs would go to %s): %d cases x %d seeds = %d runs, %d already done\n",
                sweep_file, outdir, ncase, d.runs, total, skipped);
        if (branching)
            fprintf(log,
                    "branching on %s: %d shared flows (packing + flow, once each), %d layouts each; %d to compute, %d "
                    "checkpoints to reuse\n",
                    branch_keys, ng, layouts, to_compute, reused);
        else
            fprintf(log, "no branching (%s): every run packs and flows on its own\n",
                    so->no_branch ? "--no-branch"
                    : !flume      ? "not a flume scenario"
                                  : "no capture-phase key varies");
        for (int g = 0; g < ng; g++) {
            fprintf(log, "branch %s: %s ->", groups[g].key,
                    groups[g].state == ST_UNNEEDED ? "not needed"
                    : groups[g].reused             ? "reuse checkpoint"
                                                   : "pack + flow");
            for (int i = 0; i < total; i++)
                if (items[i].group == g) fprintf(log, " %s", items[i].name);
            fputc('\n', log);
        }
        for (int i = 0; i < total; i++) {
            const run_item *r = &items[i];
            fprintf(log, "run %s:", r->name);
            for (int v = 0; v < d.n_vary; v++)
                fprintf(log, " %s=%s", d.vary_key[v], d.vary_val[v][r->idx[v]]);
            fprintf(log, " solver.seed=%d", r->seed);
            if (r->group >= 0) fprintf(log, " (branch %s)", groups[r->group].key);
            fprintf(log, "%s\n", r->state == ST_SKIPPED ? " [done]" : "");
        }
        free(groups);
        free(items);
        return 0;
    }
    /* a checkpoint to reuse must be whole and made for this group: refuse before running */
    for (int g = 0; g < ng; g++) {
        if (!groups[g].reused) continue;
        sd_scenario sc;
        char msg[2048];
        if (load_run_scenario(&d, &items[groups[g].first], &sc, err)) {
            bad = 1;
            continue;
        }
        if (sd_run_check_restart(&sc, groups[g].ckpt, msg, sizeof msg)) {
            fprintf(err, "sweep: refusing the flow checkpoint %s\n  %s\n  delete it to compute that flow again\n",
                    groups[g].ckpt, msg);
            bad = 1;
        }
        sd_scenario_free(&sc);
    }
    if (bad) {
        free(groups);
        free(items);
        return 2;
    }
    char runs_dir[1200];
    snprintf(runs_dir, sizeof runs_dir, "%s/runs", outdir);
    if (sd_mkdir_p(runs_dir)) {
        fprintf(err, "%s: cannot create: %s\n", outdir, strerror(errno));
        free(groups);
        free(items);
        return 1;
    }
    if (branching) {
        snprintf(runs_dir, sizeof runs_dir, "%s/branch", outdir);
        if (sd_mkdir_p(runs_dir)) {
            fprintf(err, "%s: cannot create: %s\n", runs_dir, strerror(errno));
            free(groups);
            free(items);
            return 1;
        }
    }
    int parallel = so->parallel;
    if (parallel <= 0) parallel = d.parallel;
    if (parallel <= 0) parallel = (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (parallel < 1) parallel = 1;
    int done = 0, failed = 0, running = 0, flows_run = 0, runs_run = 0, flows_failed = 0;
    double t0 = sd_now();
    fprintf(log, "sweep %s: %d cases x %d runs = %d runs, %d already done, %d in parallel\n", sweep_file, ncase, d.runs,
            total, skipped, parallel);
    if (shards > 1)
        fprintf(log, "sweep: shard %d of %d: work units %d, %d + %d, ... of %d; %d runs left to other shards\n",
                so->shard, shards, so->shard, so->shard, shards, n_units, others);
    if (branching)
        fprintf(log,
                "sweep: branching on %s: %d groups of %d layouts share their packing and flow (%d to compute, %d "
                "checkpoints reused)\n",
                branch_keys, ng, layouts, to_compute, reused);
    int interrupted = 0;
    if (so->collect) goto collect;
    while (1) {
        while (!interrupted && running < parallel) {
            /* shared flows first: each unlocks several runs */
            int gi = -1, ri = -1;
            for (int g = 0; g < ng && gi < 0; g++)
                if (groups[g].state == ST_PENDING) gi = g;
            if (gi < 0)
                for (int i = 0; i < total && ri < 0; i++)
                    if (items[i].state == ST_PENDING &&
                        (items[i].group < 0 || groups[items[i].group].state == ST_READY))
                        ri = i;
            if (gi < 0 && ri < 0) break;
            fflush(NULL);
            const pid_t parent = getpid();
            pid_t pid = fork();
            if (pid == 0) {
                signal(SIGINT, SIG_IGN); /* the parent stops the children */
#ifdef __linux__
                /* and a parent killed outright (SIGKILL) takes them with it, as SIGTERM would */
                prctl(PR_SET_PDEATHSIG, SIGTERM);
                if (getppid() != parent) _exit(130); /* (it died before the line above) */
#else
                (void)parent;
#endif
                if (gi >= 0) _exit(child_flow(&d, &items[groups[gi].first], &groups[gi]));
                _exit(child_run(&d, &items[ri], items[ri].group >= 0 ? groups[items[ri].group].ckpt : NULL));
            }
            if (pid < 0) {
                fprintf(err, "sweep: fork failed: %s\n", strerror(errno));
                break;
            }
            running++;
            if (gi >= 0) {
                groups[gi].state = ST_RUNNING;
                groups[gi].pid = pid;
                groups[gi].t_start = sd_now();
                flows_run++;
                fprintf(log, "sweep: flow %s started (packing + flow for %d runs)\n", groups[gi].key,
                        groups[gi].n_todo);
            } else {
                items[ri].state = ST_RUNNING;
                items[ri].pid = pid;
                runs_run++;
                if (items[ri].group >= 0)
                    fprintf(log, "sweep: run %s started (capture from branch %s)\n", items[ri].name,
                            groups[items[ri].group].key);
                else
                    fprintf(log, "sweep: run %s started\n", items[ri].name);
            }
            fflush(log);
        }
        if (running == 0) break;
        int status;
        pid_t pid = waitpid(-1, &status, 0);
        if (pid < 0) {
            if (errno == EINTR) {
                if (stop && *stop && !interrupted) {
                    interrupted = 1;
                    kill_children(items, total, groups, ng);
                }
                continue;
            }
            break;
        }
        int ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
        char why[96]; /* how a child that failed ended: its exit code or the signal that killed it */
        if (WIFSIGNALED(status))
            snprintf(why, sizeof why, "killed by signal %d, %s", WTERMSIG(status), strsignal(WTERMSIG(status)));
        else
            snprintf(why, sizeof why, "exit code %d", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
        int found = 0;
        for (int g = 0; g < ng && !found; g++)
            if (groups[g].state == ST_RUNNING && groups[g].pid == pid) {
                found = 1;
                running--;
                groups[g].pid = 0;
                if (ok && file_exists(groups[g].ckpt)) {
                    groups[g].state = ST_READY;
                    fprintf(log, "sweep: flow %s done in %.1f s\n", groups[g].key, sd_now() - groups[g].t_start);
                } else {
                    groups[g].state = ST_FAILED;
                    if (!interrupted) {
                        flows_failed++;
                        fprintf(err, "sweep: flow %s failed (%s; see %s.log); its runs are not run\n", groups[g].key,
                                why, groups[g].dir);
                        for (int i = 0; i < total; i++)
                            if (items[i].group == g && items[i].state == ST_PENDING) {
                                items[i].state = ST_FAILED;
                                failed++;
                            }
                    }
                }
            }
        for (int i = 0; i < total && !found; i++)
            if (items[i].state == ST_RUNNING && items[i].pid == pid) {
                found = 1;
                running--;
                items[i].pid = 0;
                if (ok) {
                    items[i].state = ST_DONE;
                    done++;
                } else {
                    items[i].state = ST_FAILED;
                    if (!interrupted) {
                        failed++;
                        fprintf(err, "sweep: run %s failed (%s; see %s.log)\n", items[i].dir, why, items[i].dir);
                    }
                }
            }
        if (!found) continue;
        double el = sd_now() - t0;
        int remaining = total - skipped - done - failed;
        fprintf(log, "sweep: %d/%d done (%d skipped, %d failed), %d running, elapsed %.0f s, ETA %.0f s\n",
                done + skipped, total, skipped, failed, running, el, done > 0 ? el / done * remaining : 0.0);
        fflush(log);
        if (stop && *stop && !interrupted) {
            interrupted = 1;
            kill_children(items, total, groups, ng);
        }
    }
collect:
    if (shards > 1) { /* the collecting process writes results.csv */
        fprintf(log, "sweep: shard %d of %d: %d flow(s) and %d run(s) in %.1f s, %d failed\n", so->shard, shards,
                flows_run, runs_run, sd_now() - t0, failed + flows_failed);
        free(groups);
        free(items);
        if (interrupted) return 130;
        return failed || flows_failed ? 1 : 0;
    }
    /* results.csv from every finished run, in run order; and what branching saved */
    double cost_straight = 0.0, saved = 0.0;
    int n_branched = 0;
    double *gflow = calloc((size_t)ng + 1, sizeof(double));
    int *gdone = calloc((size_t)ng + 1, sizeof(int));
    char path[1300], tmp[1400];
    snprintf(path, sizeof path, "%s/results.csv", outdir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (f) {
        fprintf(f, "case,seed");
        for (int v = 0; v < d.n_vary; v++)
            fprintf(f, ",%s", d.vary_key[v]);
        fprintf(f, ",p_v");
        for (int k = 0; k < n_classes; k++)
            fprintf(f, ",p_v_class%d", k);
        fprintf(f, ",p_v_logs,k_w,l_v_d_max,v_held_m3,v_channel_m3,v_passed_m3,capture_end,peak_dam_force_N,passed,wall_s,"
                   "capture_limit_s,flow_wall_s,branched,state_hash\n");
        for (int i = 0; i < total; i++) {
            char rp[1300], line[2048], copy[2048];
            snprintf(rp, sizeof rp, "%s/result.csv", items[i].dir);
            FILE *r = fopen(rp, "r");
            if (!r) continue;
            if (fgets(line, sizeof line, r)) {
                fputs(line, f);
                memcpy(copy, line, sizeof copy);
                char *fl[64];
                int nf = split_csv(copy, fl, 64);
                int want = 2 + d.n_vary + 1 + n_classes + 14;
                if (nf == want && gflow && gdone) {
                    double wall = atof(fl[nf - 5]), fw = atof(fl[nf - 3]);
                    int br = atoi(fl[nf - 2]);
                    cost_straight += wall + (br ? fw : 0.0);
                    if (br && items[i].group >= 0) {
                        n_branched++;
                        gflow[items[i].group] = fw;
                        gdone[items[i].group]++;
                    }
                }
            }
            fclose(r);
        }
        fclose(f);
        rename(tmp, path);
    }
    int shared = 0;
    for (int g = 0; g < ng && gflow && gdone; g++)
        if (gdone[g] > 0) {
            saved += (gdone[g] - 1) * gflow[g];
            shared++;
        }
    free(gflow);
    free(gdone);
    if (so->collect) {
        fprintf(log, "sweep: collected %d of %d runs into %s\n", skipped, total, path);
        free(groups);
        free(items);
        if (skipped < total) {
            fprintf(err, "sweep: %d of %d runs have not finished (no result.csv); results.csv lists the others\n",
                    total - skipped, total);
            return 1;
        }
        return 0;
    }
    fprintf(log,
            "sweep: this invocation started %d flow(s) and %d run(s) in %.1f s; %d run(s) were already done, %d flow "
            "checkpoint(s) reused\n",
            flows_run, runs_run, sd_now() - t0, skipped, reused);
    if (branching && cost_straight > 0)
        fprintf(log,
                "sweep: branching saved %.1f s of %.1f s of run time (%.0f %%): %d runs continued from %d shared flows"
                " (process seconds, summed over the finished runs; a straight run packs and flows itself)\n",
                saved, cost_straight, cost_straight > 0 ? 100.0 * saved / cost_straight : 0.0, n_branched, shared);
    if (failed || flows_failed) { /* the failures again, at the end, where they are seen */
        fprintf(err, "sweep: %d run(s) failed (no row in results.csv; run the sweep again to retry them):\n", failed);
        for (int i = 0; i < total; i++)
            if (items[i].state == ST_FAILED)
                fprintf(err, "  %s: see %s.log%s\n", items[i].name,
                        items[i].group >= 0 && groups[items[i].group].state == ST_FAILED ? groups[items[i].group].dir
                                                                                         : items[i].dir,
                        items[i].group >= 0 && groups[items[i].group].state == ST_FAILED ? " (its shared flow)" : "");
    }
    free(groups);
    free(items);
    if (interrupted) return 130;
    return failed || flows_failed ? 1 : 0;
}
