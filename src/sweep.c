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

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
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
#include "sweep_file.h"
#include "sweep_identity.h"
#include "core/status.h"

/* invalid cases told before the sweep stops checking the others */
#define SWEEP_MAX_BAD_CASES 3

/* What every run of the sweep shares: the file, how the engine runs, the callback. */
typedef struct {
    const sd_sweep_file *f;
    int n_classes; /* size classes: the most of any case (results.csv's p_v_class columns) */
    sd_tuning tuning; /* the caller's (sd_sweep_opts), for every run */
    void (*run_done)(const sd_run_result *res, FILE *log);
} sweep_def;

/* ST_OTHER: another shard's run */
enum { ST_PENDING = 0, ST_RUNNING, ST_DONE, ST_FAILED, ST_SKIPPED, ST_READY, ST_UNNEEDED, ST_OTHER };

typedef struct {
    int case_id, seed, seed_idx;
    int idx[SD_SWEEP_MAX_AXES];
    char name[64];
    char dir[1200];
    int group; /* branch group, -1: a straight run */
    int unit;  /* work unit (its group's, or its own) */
    int state;
    pid_t pid;
} run_item;

typedef struct {
    char key[256];
    char dir[1200];
    char ckpt[1300];
    char ident[1300]; /* the checkpoint's identity (sweep_identity.h) */
    int first; /* a member run (its overrides build the shared flow) */
    int n_runs, n_todo;
    int state; /* ST_PENDING (to compute), ST_RUNNING, ST_READY, ST_FAILED, ST_UNNEEDED */
    int reused;
    char *stale; /* why its checkpoint on disk is not reused (NULL: none, or reused) */
    double flow_ms; /* estimate of its packing and flow */
    pid_t pid;
    double t_start;
} branch_item;

/* Per case: what validating it found. */
typedef struct {
    uint64_t branch_hash; /* sd_scenario_branch_hash at the first seed */
    int flume;
    double ms, flow_ms; /* estimates: the whole run, its packing and flow (sd_scenario_ms) */
} case_info;

static int load_run_scenario(const sweep_def *d, const run_item *r, sd_scenario *s, FILE *err)
{
    if (sd_sweep_file_scenario(d->f, r->idx, r->seed, s, err)) return 1;
    s->world.tuning = d->tuning;
    return 0;
}

/* a CSV field, quoted when it must be (RFC 4180: a comma, a quote or a line break inside) */
static void put_csv(FILE *f, const char *s)
{
    if (!strpbrk(s, ",\"\r\n")) {
        fputs(s, f);
        return;
    }
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '"') fputc('"', f);
        fputc(*s, f);
    }
    fputc('"', f);
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
            snprintf(best[0], sizeof best[0], "%.26s", name);
        } else if (strcmp(name, best[1]) > 0)
            snprintf(best[1], sizeof best[1], "%.26s", name);
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
    /* the identity goes first and comes back last: a checkpoint without one is never reused */
    if (remove(g->ident) && errno != ENOENT) {
        fprintf(log, "%s: cannot delete: %s\n", g->ident, strerror(errno));
        sd_scenario_free(&s);
        fclose(log);
        return 1;
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
    if (code == 0 && sd_sweep_identity_write(g->ident, &s)) {
        fprintf(log, "%s: cannot write: %s\n", g->ident, strerror(errno));
        code = 1;
    }
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
            for (int a = 0; a < d->f->n_axes; a++) {
                fputc(',', f);
                put_csv(f, d->f->axis[a].val[r->idx[a]].label);
            }
            fprintf(f, ",%.6f", res.p_v);
            /* (as many class columns as the sweep's case with the most; this run's own filled) */
            for (int k = 0; k < d->n_classes; k++)
                if (k < s.n_classes)
                    fprintf(f, ",%.6f", res.p_v_class[k]);
                else
                    fputc(',', f);
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

static void kill_children(run_item *items, int total, branch_item *groups, int ng)
{
    for (int i = 0; i < total; i++)
        if (items[i].state == ST_RUNNING && items[i].pid > 0) kill(items[i].pid, SIGTERM);
    for (int g = 0; g < ng; g++)
        if (groups[g].state == ST_RUNNING && groups[g].pid > 0) kill(groups[g].pid, SIGTERM);
}

/* Fields of a CSV line, split in place (a quoted field unquoted); returns the count. */
static int split_csv(char *line, char **f, int max)
{
    line[strcspn(line, "\r\n")] = '\0';
    int n = 0;
    char *p = line;
    while (n < max) {
        f[n++] = p;
        if (*p == '"') { /* "...": "" is one quote; ends at the quote before a comma or the end */
            char *out = p, *q = p + 1;
            while (*q && !(q[0] == '"' && q[1] != '"')) {
                if (q[0] == '"') q++;
                *out++ = *q++;
            }
            if (*q == '"') q++;
            *out = '\0';
            if (*q != ',') break;
            p = q + 1;
            continue;
        }
        char *c = strchr(p, ',');
        if (!c) break;
        *c = '\0';
        p = c + 1;
    }
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
static int emit_slurm(const char *sweep_file, const char *outdir, const sd_sweep_opts *so, int n_units,
                      const int *unit_first, const double *unit_ms, const run_item *items, int total,
                      const branch_item *groups, FILE *err)
{
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
        case 0: /* unit, what it computes, its runs, its estimate */
            fprintf(f,
                    "# work units of %s: unit<TAB>what<TAB>runs<TAB>time estimate on one core (sabodem check's "
                    "model; task U of the array runs unit U)\n",
                    abs_file);
            for (int u = 0; u < n_units; u++) {
                const run_item *r0 = &items[unit_first[u]];
                if (r0->group >= 0) fprintf(f, "%d\tflow %s\t", u, groups[r0->group].key);
                else fprintf(f, "%d\trun\t", u);
                int first = 1;
                for (int i = 0; i < total; i++)
                    if (items[i].unit == u) {
                        fprintf(f, "%s%s", first ? "" : " ", items[i].name);
                        first = 0;
                    }
                char est[48];
                sd_scenario_ms_text(unit_ms[u], est, sizeof est);
                fprintf(f, "\t%s\n", est);
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
        default: {
            double all = 0.0, longest = 0.0;
            for (int u = 0; u < n_units; u++) {
                all += unit_ms[u];
                longest = unit_ms[u] > longest ? unit_ms[u] : longest;
            }
            char est_all[48], est_longest[48];
            sd_scenario_ms_text(all, est_all, sizeof est_all);
            sd_scenario_ms_text(longest, est_longest, sizeof est_longest);
            fprintf(f,
                    "Sweep %s as a Slurm job array: %d tasks, one per work unit (units.txt: a shared flow\n"
                    "and the runs that branch from it, or one run), then a job that collects results.csv.\n"
                    "Submit with: sh %s/submit.sh\n"
                    "Each task runs `sabodem sweep --shard U/%d`; a task run again skips the runs already done,\n"
                    "so a failed or cancelled task is resubmitted with: sbatch --array=U array.sh\n"
                    "Time estimate on one core (sabodem check's cost model): %s in all, the longest task %s.\n",
                    abs_file, n_units, dir, n_units, est_all, est_longest);
        }
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

/* A run's case values, "key=value key=value", into buf. */
static void case_values(const sd_sweep_file *f, const int *idx, char *buf, size_t n)
{
    size_t len = 0;
    buf[0] = '\0';
    for (int a = 0; a < f->n_axes && len < n; a++) {
        const int w = snprintf(buf + len, n - len, "%s%s=%s", a ? " " : "", f->axis[a].name, f->axis[a].val[idx[a]].label);
        if (w < 0) break;
        len += (size_t)w;
    }
}

/* Branch groups. Two runs share a flow when their cases are flumes whose scenarios agree in
 * every key that acts before the flow ends (sd_scenario_branch_hash: all but the capture keys,
 * the seed included) and they have the same seed: then their packings and flows are the same
 * bits. Grouping by the hash, not by which vary keys are capture keys, keeps a named variant
 * that sets a key of each kind (a layout and a grading) on a flow of its own, and lets two
 * values that differ only after the flow end share one, whatever key (of any type, from any
 * part of the scenario) they set. A group of one is a straight run. */
typedef struct {
    uint64_t hash;
    int seed_idx, run;
} group_key;

static int cmp_group_key(const void *a, const void *b)
{
    const group_key *x = a, *y = b;
    if (x->hash != y->hash) return x->hash < y->hash ? -1 : 1;
    if (x->seed_idx != y->seed_idx) return x->seed_idx < y->seed_idx ? -1 : 1;
    return (x->run > y->run) - (x->run < y->run);
}

/* Sets each run's group (-1: straight), numbered in the order of the groups' first runs;
 * returns the number of groups, or -1 when out of memory. */
static int form_groups(run_item *items, int total, const case_info *cases, int no_branch)
{
    for (int i = 0; i < total; i++)
        items[i].group = -1;
    if (no_branch) return 0;
    group_key *k = malloc((size_t)total * sizeof *k);
    int *id = malloc((size_t)total * sizeof *id);
    if (!k || !id) {
        free(k);
        free(id);
        return -1;
    }
    int nk = 0;
    for (int i = 0; i < total; i++)
        if (cases[items[i].case_id].flume)
            k[nk++] = (group_key){cases[items[i].case_id].branch_hash, items[i].seed_idx, i};
    qsort(k, (size_t)nk, sizeof *k, cmp_group_key);
    for (int a = 0, b; a < nk; a = b) { /* (a group's runs, marked by its first run) */
        for (b = a + 1; b < nk && k[b].hash == k[a].hash && k[b].seed_idx == k[a].seed_idx; b++) {
        }
        if (b - a > 1)
            for (int j = a; j < b; j++)
                items[k[j].run].group = k[a].run;
    }
    int ng = 0;
    for (int i = 0; i < total; i++)
        id[i] = -1;
    for (int i = 0; i < total; i++)
        if (items[i].group >= 0) {
            const int first = items[i].group;
            if (id[first] < 0) id[first] = ng++;
            items[i].group = id[first];
        }
    free(k);
    free(id);
    return ng;
}

/* label into out as part of a directory name: brackets, braces, quotes and spaces dropped,
 * commas as '-', anything else but [A-Za-z0-9._+-] as '_' ("[20, 40, 120]": "20-40-120") */
static size_t put_dir_label(char *out, size_t n, const char *label)
{
    size_t len = 0;
    for (const char *c = label; *c && len + 1 < n; c++) {
        if (strchr(" []{}\"", *c)) continue;
        out[len++] = *c == ',' ? '-' : (isalnum((unsigned char)*c) || strchr("._+-", *c)) ? *c : '_';
    }
    out[len] = '\0';
    return len;
}

static int cmp_group_name(const void *a, const void *b)
{
    const branch_item *const *x = a, *const *y = b;
    return strcmp((*x)->key, (*y)->key);
}

/* Each group's directory name: name=value_ for every axis that sets a key acting before the
 * flow end (its values in the group joined by '+'), then seed<S>; "b<N>_seed<S>" when that is
 * long or not unique. within[a]: 1 when axis a varies within some group (what it branches on). */
static int name_groups(const sd_sweep_file *f, const run_item *items, int total, branch_item *groups, int ng,
                       int *within)
{
    unsigned long *seen = calloc((size_t)ng * SD_SWEEP_MAX_AXES + 1, sizeof *seen); /* (32 values: bits) */
    const branch_item **order = malloc(((size_t)ng + 1) * sizeof *order);
    if (!seen || !order) {
        free(seen);
        free((void *)order);
        return -1;
    }
    for (int i = 0; i < total; i++)
        if (items[i].group >= 0)
            for (int a = 0; a < f->n_axes; a++)
                seen[(size_t)items[i].group * SD_SWEEP_MAX_AXES + (size_t)a] |= 1ul << items[i].idx[a];
    for (int a = 0; a < f->n_axes; a++) {
        within[a] = 0;
        for (int g = 0; g < ng; g++) {
            const unsigned long m = seen[(size_t)g * SD_SWEEP_MAX_AXES + (size_t)a];
            if (m & (m - 1)) within[a] = 1;
        }
    }
    for (int g = 0; g < ng; g++) {
        char k[1024];
        size_t len = 0;
        for (int a = 0; a < f->n_axes && len + 1 < sizeof k; a++) {
            if (f->axis[a].capture) continue;
            len += (size_t)snprintf(k + len, sizeof k - len, "%s=", f->axis[a].name);
            for (int v = 0, first = 1; v < f->axis[a].n_val && len + 1 < sizeof k; v++)
                if (seen[(size_t)g * SD_SWEEP_MAX_AXES + (size_t)a] >> v & 1ul) {
                    if (!first) k[len++] = '+';
                    len += put_dir_label(k + len, sizeof k - len, f->axis[a].val[v].label);
                    first = 0;
                }
            if (len + 1 < sizeof k) k[len++] = '_';
            k[len < sizeof k ? len : sizeof k - 1] = '\0';
        }
        const int seed = items[groups[g].first].seed;
        if (len + 16 < sizeof k) snprintf(k + len, sizeof k - len, "seed%d", seed);
        if (len + 16 >= sizeof k || strlen(k) > 160) snprintf(k, sizeof k, "b%03d_seed%d", g, seed);
        snprintf(groups[g].key, sizeof groups[g].key, "%.200s", k); /* (at most 160: above) */
        order[g] = &groups[g];
    }
    qsort((void *)order, (size_t)ng, sizeof *order, cmp_group_name);
    for (int j = 1; j < ng; j++)
        if (!strcmp(order[j - 1]->key, order[j]->key)) {
            for (int g = 0; g < ng; g++)
                snprintf(groups[g].key, sizeof groups[g].key, "b%03d_seed%d", g, items[groups[g].first].seed);
            break;
        }
    free(seen);
    free((void *)order);
    return 0;
}

/* checkpoint_<step>.ckpt in dir (what a killed run or flow left to continue from) deleted */
static void remove_periodic(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    for (struct dirent *e; (e = readdir(d));) {
        const size_t n = strlen(e->d_name);
        if (n > 16 && !strncmp(e->d_name, "checkpoint_", 11) && !strcmp(e->d_name + n - 5, ".ckpt")) {
            char p[1600];
            snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
            remove(p);
        }
    }
    closedir(d);
}

/* Which flows there are to compute and which checkpoints to reuse. A group's checkpoint is
 * reused when its identity (sweep_identity.h) matches this program and the group's scenario
 * up to the flow end, and it reads back whole; one of another engine or scenario, or without
 * an identity, is stale: its flow is computed again (and, unless dry, the stale checkpoint is
 * deleted with the periodic checkpoints of the flow and of its runs not done, which continue
 * from it). A damaged checkpoint that would be reused is refused: 2 (nothing run, nothing
 * deleted); else 0. */
static int review_flows(const sweep_def *d, run_item *items, int total, branch_item *groups, int ng, int dry, FILE *log,
                        FILE *err, int *reused, int *to_compute)
{
    int bad = 0;
    *reused = *to_compute = 0;
    for (int g = 0; g < ng; g++) {
        branch_item *b = &groups[g];
        if (b->n_todo == 0) {
            b->state = ST_UNNEEDED;
            continue;
        }
        b->state = ST_PENDING;
        if (!file_exists(b->ckpt)) {
            ++*to_compute;
            continue;
        }
        sd_scenario sc;
        char msg[2048], why[2300];
        if (load_run_scenario(d, &items[b->first], &sc, err)) {
            bad = 1;
            continue;
        }
        const int id = sd_sweep_identity_check(b->ident, &sc, msg, sizeof msg);
        if (id == SD_IDENTITY_SAME) {
            if (!dry && sd_run_check_restart(&sc, b->ckpt, msg, sizeof msg)) {
                fprintf(err, "sweep: refusing the flow checkpoint %s\n  %s\n  delete it to compute that flow again\n",
                        b->ckpt, msg);
                bad = 1;
            } else {
                b->state = ST_READY;
                b->reused = 1;
                ++*reused;
            }
        } else {
            if (id == SD_IDENTITY_NONE)
                snprintf(why, sizeof why,
                         "no identity (%s: made before sweeps recorded one, or stopped before it was written)", msg);
            else
                snprintf(why, sizeof why, "%s", msg);
            b->stale = strdup(why);
            ++*to_compute;
        }
        sd_scenario_free(&sc);
    }
    if (bad) return 2;
    for (int g = 0; g < ng && !dry; g++) {
        branch_item *b = &groups[g];
        if (b->state != ST_PENDING || !b->stale) continue;
        fprintf(log, "sweep: not branching from %s: %s; computing that flow again\n", b->ckpt, b->stale);
        remove(b->ckpt);
        remove(b->ident);
        remove_periodic(b->dir);
        for (int i = 0; i < total; i++)
            if (items[i].group == g && items[i].state == ST_PENDING) remove_periodic(items[i].dir);
    }
    return 0;
}

/* A run's estimate when it runs (ms): the whole run, or a branched run's capture. */
static double run_ms(const run_item *r, const case_info *cases)
{
    const case_info *c = &cases[r->case_id];
    return r->group >= 0 ? c->ms - c->flow_ms : c->ms;
}

/* The elapsed time (ms) of the work left when `parallel` processes take it as the loop in
 * sd_sweep_run does, each task lasting its estimate: a flow to compute first, else the first
 * run that can start (a straight run, or one whose flow is ready). */
static double estimate_elapsed(const run_item *items, int total, const branch_item *groups, int ng,
                               const case_info *cases, int parallel)
{
    char *left = malloc((size_t)total + 1), *flow = malloc((size_t)ng + 1); /* flow: 0 to do, 1 running, 2 ready */
    double *end = malloc((size_t)parallel * sizeof *end);
    int *task = malloc((size_t)parallel * sizeof *task); /* run i, flow -(g + 1), or 0 with end < 0: free */
    if (!left || !flow || !end || !task) {
        free(left);
        free(flow);
        free(end);
        free(task);
        return NAN;
    }
    for (int i = 0; i < total; i++)
        left[i] = items[i].state == ST_PENDING;
    for (int g = 0; g < ng; g++)
        flow[g] = groups[g].state == ST_PENDING ? 0 : 2;
    for (int k = 0; k < parallel; k++)
        end[k] = -1.0;
    double now = 0.0;
    int busy = 0;
    for (;;) {
        for (int k = 0; k < parallel; k++) {
            if (end[k] >= 0.0) continue;
            int g = 0, i = 0;
            while (g < ng && flow[g] != 0)
                g++;
            if (g < ng) {
                flow[g] = 1;
                task[k] = -(g + 1);
                end[k] = now + groups[g].flow_ms;
            } else {
                while (i < total && !(left[i] && (items[i].group < 0 || flow[items[i].group] == 2)))
                    i++;
                if (i == total) break;
                left[i] = 0;
                task[k] = i;
                end[k] = now + run_ms(&items[i], cases);
            }
            busy++;
        }
        if (!busy) break;
        int next = -1;
        for (int k = 0; k < parallel; k++)
            if (end[k] >= 0.0 && (next < 0 || end[k] < end[next])) next = k;
        if (next < 0) { /* (an estimate that is not a number: none to give) */
            now = NAN;
            break;
        }
        now = end[next];
        if (task[next] < 0) flow[-task[next] - 1] = 2;
        end[next] = -1.0;
        busy--;
    }
    free(left);
    free(flow);
    free(end);
    free(task);
    return now;
}

/* "117228.600 s (32.6 h)": whole ms, and in words from two minutes on */
static void time_text(double ms, char *buf, size_t n)
{
    char exact[40], words[40];
    sd_scenario_ms_text(ms, exact, sizeof exact);
    sd_scenario_human_time(ms / 1000.0, words, sizeof words);
    if (ms >= 120000.0)
        snprintf(buf, n, "%s (%s)", exact, words);
    else
        snprintf(buf, n, "%s", exact);
}

int sd_sweep_run(const char *sweep_file, const char *outdir, const sd_sweep_opts *so, volatile sig_atomic_t *stop,
                 FILE *log, FILE *err)
{
    sd_sweep_file *file = calloc(1, sizeof *file);
    if (!file) return 1;
    if (sd_sweep_file_load(file, sweep_file, err)) {
        sd_sweep_file_free(file);
        free(file);
        return 2;
    }
    sweep_def d = {.f = file, .n_classes = 0, .tuning = so->tuning, .run_done = so->run_done};
    const int ncase = (int)sd_sweep_file_cases(file);
    const int total = ncase * file->runs;
    run_item *items = calloc((size_t)total, sizeof(*items));
    case_info *cases = calloc((size_t)ncase, sizeof(*cases));
    branch_item *groups = NULL;
    int *unit_first = NULL;
    double *unit_ms = NULL;
    int code = 0, ng = 0;
    if (!items || !cases) {
        code = 1;
        goto out;
    }
    /* validate every case before running anything, and estimate it */
    sd_scenario_limits lim = sd_scenario_limits_default();
    if (so->limits.max_bytes > 0) lim.max_bytes = so->limits.max_bytes;
    if (so->limits.max_steps > 0) lim.max_steps = so->limits.max_steps;
    int n_bad = 0; /* invalid or too large cases: after SWEEP_MAX_BAD_CASES the rest are not checked (the same
                    * mistake would be told once a case) */
    for (int c = 0; c < ncase && n_bad < SWEEP_MAX_BAD_CASES; c++)
        for (int s = 0; s < file->runs; s++) {
            run_item *r = &items[c * file->runs + s];
            r->case_id = c;
            r->seed_idx = s;
            r->seed = (int)(file->seed_base + s);
            r->group = -1;
            int rem = c;
            for (int a = file->n_axes - 1; a >= 0; a--) {
                r->idx[a] = rem % file->axis[a].n_val;
                rem /= file->axis[a].n_val;
            }
            snprintf(r->name, sizeof r->name, "case%03d_seed%d", c, r->seed);
            snprintf(r->dir, sizeof r->dir, "%s/runs/%s", outdir, r->name);
            if (s > 0) continue;
            sd_scenario sc;
            sd_scenario_cost cost;
            char values[512], which[600];
            case_values(file, r->idx, values, sizeof values);
            snprintf(which, sizeof which, "case %d%s%s%s", c, values[0] ? " (" : "", values, values[0] ? ")" : "");
            if (load_run_scenario(&d, r, &sc, err)) {
                fprintf(err, "%s: %s is invalid (see above)\n", sweep_file, which);
                code = 2;
                if (++n_bad == SWEEP_MAX_BAD_CASES && c + 1 < ncase)
                    fprintf(err, "%s: cases %d to %d not checked after %d invalid ones\n", sweep_file, c + 1,
                            ncase - 1, n_bad);
                break;
            }
            sd_scenario_estimate(&sc, &cost);
            if (sd_scenario_check_cost(&sc, &cost, &lim, err)) {
                fprintf(err, "%s: %s is too large (see above)\n", sweep_file, which);
                code = 2;
                if (++n_bad == SWEEP_MAX_BAD_CASES && c + 1 < ncase)
                    fprintf(err, "%s: cases %d to %d not checked after %d invalid ones\n", sweep_file, c + 1,
                            ncase - 1, n_bad);
            }
            cases[c] = (case_info){sd_scenario_branch_hash(&sc), sc.flume_on, sd_scenario_ms(cost.seconds),
                                   sd_scenario_ms(cost.flow_seconds)};
            if (sc.n_classes > d.n_classes) d.n_classes = sc.n_classes < SD_MAX_CLASSES ? sc.n_classes : SD_MAX_CLASSES;
            sd_scenario_free(&sc);
        }
    if (code) goto out;
    ng = form_groups(items, total, cases, so->no_branch);
    groups = calloc((size_t)(ng > 0 ? ng : 0) + 1, sizeof(*groups));
    unit_first = malloc((size_t)total * sizeof *unit_first);
    unit_ms = calloc((size_t)total, sizeof *unit_ms);
    int within[SD_SWEEP_MAX_AXES] = {0};
    if (ng < 0 || !groups || !unit_first || !unit_ms) {
        code = 1;
        goto out;
    }
    const int branching = ng > 0;
    /* work units: a branch group (its flow and its runs) or one straight run, in run order */
    int n_units = 0;
    for (int i = 0; i < total; i++) {
        run_item *r = &items[i];
        if (r->group < 0) {
            unit_first[n_units] = i;
            r->unit = n_units++;
            continue;
        }
        branch_item *g = &groups[r->group];
        if (g->n_runs++ == 0) {
            g->first = i;
            unit_first[n_units] = i;
            g->flow_ms = cases[r->case_id].flow_ms;
            r->unit = n_units++;
        } else
            r->unit = items[g->first].unit;
    }
    if (name_groups(file, items, total, groups, ng, within)) {
        code = 1;
        goto out;
    }
    char branch_axes[512] = "";
    for (int a = 0; a < file->n_axes; a++)
        if (within[a]) {
            const size_t l = strlen(branch_axes);
            snprintf(branch_axes + l, sizeof branch_axes - l, "%s%s", l ? ", " : "", file->axis[a].name);
        }
    for (int g = 0; g < ng; g++) {
        snprintf(groups[g].dir, sizeof groups[g].dir, "%s/branch/%s", outdir, groups[g].key);
        snprintf(groups[g].ckpt, sizeof groups[g].ckpt, "%s/flow_end.ckpt", groups[g].dir);
        snprintf(groups[g].ident, sizeof groups[g].ident, "%s/identity.json", groups[g].dir);
    }
    const int shards = so->shards > 1 ? so->shards : 1;
    if (so->shards > 1 && (so->shard < 0 || so->shard >= so->shards)) {
        fprintf(err, "sweep: shard %d of %d does not exist (shards are 0 to %d)\n", so->shard, so->shards,
                so->shards - 1);
        code = 2;
        goto out;
    }
    int skipped = 0, others = 0;
    for (int i = 0; i < total; i++) {
        char p[1300];
        snprintf(p, sizeof p, "%s/result.csv", items[i].dir);
        unit_ms[items[i].unit] += run_ms(&items[i], cases);
        if (file_exists(p)) {
            items[i].state = ST_SKIPPED;
            skipped++;
        } else if (so->collect || items[i].unit % shards != so->shard % shards) {
            items[i].state = ST_OTHER;
            others++;
        } else if (items[i].group >= 0)
            groups[items[i].group].n_todo++;
    }
    for (int g = 0; g < ng; g++)
        unit_ms[items[groups[g].first].unit] += groups[g].flow_ms;
    if (so->emit) {
        code = emit_slurm(sweep_file, outdir, so, n_units, unit_first, unit_ms, items, total, groups, err);
        if (!code)
            fprintf(log,
                    "sweep %s: %d runs in %d work units (%s); job array and collect job written to %s/slurm/ "
                    "(see %s/slurm/README)\n",
                    sweep_file, total, n_units, branching ? "a shared flow with its runs, or a run" : "one per run",
                    outdir, outdir);
        goto out;
    }
    int reused = 0, to_compute = 0;
    code = review_flows(&d, items, total, groups, ng, so->dry_run, log, err, &reused, &to_compute);
    if (code) goto out;
    int parallel = so->parallel;
    if (parallel <= 0) parallel = file->parallel;
    if (parallel <= 0) parallel = (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (parallel < 1) parallel = 1;
    /* the time estimate, in whole ms: straight, branched, left to do, elapsed */
    double est_straight = 0.0, est_shared = 0.0, est_left = 0.0;
    for (int i = 0; i < total; i++) {
        est_straight += cases[items[i].case_id].ms;
        if (items[i].state == ST_PENDING) est_left += run_ms(&items[i], cases);
    }
    for (int g = 0; g < ng; g++) {
        est_shared += (groups[g].n_runs - 1) * groups[g].flow_ms;
        if (groups[g].state == ST_PENDING) est_left += groups[g].flow_ms;
    }
    const double est_elapsed = estimate_elapsed(items, total, groups, ng, cases, parallel);
    char t_straight[96], t_branched[96], t_shared[96], t_left[96], t_elapsed[96];
    time_text(est_straight, t_straight, sizeof t_straight);
    time_text(est_straight - est_shared, t_branched, sizeof t_branched);
    time_text(est_shared, t_shared, sizeof t_shared);
    time_text(est_left, t_left, sizeof t_left);
    time_text(est_elapsed, t_elapsed, sizeof t_elapsed);
    if (so->dry_run) {
        fprintf(log, "sweep %s (dry run, outputs would go to %s): %d cases x %d seeds = %d runs, %d already done\n",
                sweep_file, outdir, ncase, file->runs, total, skipped);
        int n_branched = 0, any_flume = 0;
        for (int g = 0; g < ng; g++)
            n_branched += groups[g].n_runs;
        for (int c = 0; c < ncase; c++)
            any_flume |= cases[c].flume;
        if (branching)
            fprintf(log,
                    "branching on %s: %d shared flows (packing + flow, once each) for %d runs; %d to compute, %d "
                    "checkpoints to reuse\n",
                    branch_axes[0] ? branch_axes : "nothing (equal cases)", ng, n_branched, to_compute, reused);
        else
            fprintf(log, "no branching (%s): every run packs and flows on its own\n",
                    so->no_branch ? "--no-branch"
                    : !any_flume  ? "not a flume scenario"
                                  : "no two runs have the same packing and flow");
        for (int g = 0; g < ng; g++) {
            char est[48];
            sd_scenario_ms_text(groups[g].flow_ms, est, sizeof est);
            fprintf(log, "branch %s: %s, est %s%s%s ->", groups[g].key,
                    groups[g].state == ST_UNNEEDED ? "not needed"
                    : groups[g].reused             ? "reuse checkpoint"
                    : groups[g].stale              ? "pack + flow again"
                                                   : "pack + flow",
                    est, groups[g].stale ? " (its checkpoint is not reused: " : "",
                    groups[g].stale ? groups[g].stale : "");
            if (groups[g].stale) fputc(')', log);
            for (int i = 0; i < total; i++)
                if (items[i].group == g) fprintf(log, " %s", items[i].name);
            fputc('\n', log);
        }
        for (int i = 0; i < total; i++) {
            const run_item *r = &items[i];
            char values[4096], est[48], own[48];
            case_values(file, r->idx, values, sizeof values);
            sd_scenario_ms_text(cases[r->case_id].ms, est, sizeof est);
            sd_scenario_ms_text(run_ms(r, cases), own, sizeof own);
            fprintf(log, "run %s: %s%ssolver.seed=%d", r->name, values, values[0] ? " " : "", r->seed);
            if (r->group >= 0) fprintf(log, " (branch %s)", groups[r->group].key);
            fprintf(log, " est %s", est);
            if (r->group >= 0) fprintf(log, " (capture %s)", own);
            fprintf(log, "%s\n", r->state == ST_SKIPPED ? " [done]" : "");
        }
        char what[96];
        fprintf(log, "time estimate (sabodem check's cost model, one core per run):\n");
        snprintf(what, sizeof what, "straight (%d runs, each packing and flowing):", total);
        fprintf(log, "  %-48s %s\n", what, t_straight);
        if (branching) {
            snprintf(what, sizeof what, "branched (%d shared flows):", ng);
            fprintf(log, "  %-48s %s, %s less\n", what, t_branched, t_shared);
        }
        fprintf(log, "  %-48s %s\n", "left to do:", t_left);
        snprintf(what, sizeof what, "elapsed, %d processes at once:", parallel);
        fprintf(log, "  %-48s %s\n", what, t_elapsed);
        goto out;
    }
    char runs_dir[1200];
    snprintf(runs_dir, sizeof runs_dir, "%s/runs", outdir);
    if (sd_mkdir_p(runs_dir)) {
        fprintf(err, "%s: cannot create: %s\n", outdir, strerror(errno));
        code = 1;
        goto out;
    }
    if (branching) {
        snprintf(runs_dir, sizeof runs_dir, "%s/branch", outdir);
        if (sd_mkdir_p(runs_dir)) {
            fprintf(err, "%s: cannot create: %s\n", runs_dir, strerror(errno));
            code = 1;
            goto out;
        }
    }
    int done = 0, failed = 0, running = 0, flows_run = 0, runs_run = 0, flows_failed = 0;
    double t0 = sd_now();
    fprintf(log, "sweep %s: %d cases x %d runs = %d runs, %d already done, %d in parallel\n", sweep_file, ncase,
            file->runs, total, skipped, parallel);
    if (shards > 1)
        fprintf(log, "sweep: shard %d of %d: work units %d, %d + %d, ... of %d; %d runs left to other shards\n",
                so->shard, shards, so->shard, so->shard, shards, n_units, others);
    if (branching)
        fprintf(log,
                "sweep: branching on %s: %d groups share their packing and flow (%d to compute, %d checkpoints "
                "reused)\n",
                branch_axes[0] ? branch_axes : "nothing (equal cases)", ng, to_compute, reused);
    if (!so->collect)
        fprintf(log, "sweep: time estimate (sabodem check's cost model): %s to do, about %s elapsed\n", t_left,
                t_elapsed);
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
                if (ok && file_exists(groups[g].ckpt) && file_exists(groups[g].ident)) {
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
        code = interrupted ? 130 : failed || flows_failed ? 1 : 0;
        goto out;
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
        for (int a = 0; a < file->n_axes; a++) {
            fputc(',', f);
            put_csv(f, file->axis[a].name);
        }
        fprintf(f, ",p_v");
        for (int k = 0; k < d.n_classes; k++)
            fprintf(f, ",p_v_class%d", k);
        fprintf(f, ",p_v_logs,k_w,l_v_d_max,v_held_m3,v_channel_m3,v_passed_m3,capture_end,peak_dam_force_N,passed,wall_s,"
                   "capture_limit_s,flow_wall_s,branched,state_hash\n");
        char *line = NULL, *fl[64];
        size_t cap = 0;
        for (int i = 0; i < total; i++) {
            char rp[1300];
            snprintf(rp, sizeof rp, "%s/result.csv", items[i].dir);
            FILE *r = fopen(rp, "r");
            if (!r) continue;
            if (getline(&line, &cap, r) > 0) {
                fputs(line, f);
                if (line[strlen(line) - 1] != '\n') fputc('\n', f);
                const int nf = split_csv(line, fl, 64), want = 2 + file->n_axes + 1 + d.n_classes + 14;
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
        free(line);
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
        if (skipped < total) {
            fprintf(err, "sweep: %d of %d runs have not finished (no result.csv); results.csv lists the others\n",
                    total - skipped, total);
            code = 1;
        }
        goto out;
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
    code = interrupted ? 130 : failed || flows_failed ? 1 : 0;
out:
    for (int g = 0; groups && g < ng; g++)
        free(groups[g].stale);
    free(unit_first);
    free(unit_ms);
    free(groups);
    free(cases);
    free(items);
    sd_sweep_file_free(file);
    free(file);
    return code;
}
