/* The driver's state in a checkpoint's blob (the flow-end one, periodic ones), and a restart
 * from it: the state read back, the outputs so far carried into the new run's directory. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/status.h"
#include "core/vmath.h"
#include "run_ctx.h"

/* The driver's state in the checkpoint's extra blob: a tagged, versioned byte string with
 * everything of run_ctx that is state (not how it runs): the phase and its flags, the build's
 * element counts and pipes, the volumes, the pipe accumulators, the phase times, the flow
 * length, the time series' lengths and the VTK series so far; the materials' names by id (the
 * world keeps the ids and the pairs' springs), which a restart's scenario must declare alike. The output timers are the world's
 * step count (saved with the world). The build's random numbers are spent before the first
 * step; the driver draws none later, so there is no rng state to carry. */
#define BLOB_MAGIC "SDRUNv6"

const char *sd_run_state_version(void) { return BLOB_MAGIC; }

static long file_len(FILE *f)
{
    if (!f || fflush(f)) return -1;
    return ftell(f);
}

static void state_pack(const run_ctx *c, sd_bin_writer *b, int kind, long series_len, long traj_len, long pipes_len,
                       long events_len)
{
    const double now = sd_now();
    sd_bin_put(b, BLOB_MAGIC, 8);
    sd_bin_put_u64(b, sd_scenario_branch_hash(c->s));
    sd_bin_put_u64(b, sd_scenario_run_hash(c->s));
    sd_bin_put_i32(b, kind);
    sd_bin_put_i32(b, c->s->n_materials);
    for (int m = 0; m < c->s->n_materials; m++) {
        const int32_t len = (int32_t)strlen(c->s->material_name[m]);
        sd_bin_put_i32(b, len);
        sd_bin_put(b, c->s->material_name[m], (size_t)len);
    }
    sd_bin_put_i32(b, c->phase);
    sd_bin_put_i32(b, c->flow_ended);
    sd_bin_put_i32(b, c->dam_built);
    sd_bin_put_i32(b, c->flow_ckpt_written);
    sd_bin_put_i32(b, c->n_passed);
    sd_bin_put_i32(b, c->flow_len_done);
    sd_bin_put_i32(b, c->n_snap);
    sd_bin_put_i32(b, c->info.n_rough);
    sd_bin_put_i32(b, c->info.n_spheres);
    sd_bin_put_i32(b, c->info.n_logs);
    sd_bin_put_i32(b, c->info.first_moving_gid);
    sd_bin_put_i32(b, c->info.n_pipes);
    for (int k = 0; k < c->info.n_pipes; k++) {
        sd_bin_put_i32(b, c->info.pipe_gid[k]);
        sd_bin_put_i32(b, c->info.pipe_kind[k]);
        sd_bin_put_f64(b, c->info.pipe_coord[k]);
    }
    sd_pipe_loads_pack(&c->loads, b);
    sd_bin_put_i32(b, c->capture_cut);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        sd_bin_put_f64(b, c->vol_total_class[k]);
    sd_bin_put_f64(b, c->vol_total_logs);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        sd_bin_put_f64(b, c->vol_passed_class[k]);
    sd_bin_put_f64(b, c->vol_passed_logs);
    sd_bin_put_f64(b, c->h_d);
    sd_bin_put_f64(b, c->last_cross_time);
    sd_bin_put_f64(b, c->ke_peak);
    sd_bin_put_f64(b, c->dam_force_now);
    sd_bin_put_f64(b, c->mesh_dam_peak);
    sd_bin_put_f64(b, c->mesh_dam_t_peak);
    sd_bin_put_f64(b, c->mesh_dam_impulse);
    sd_bin_put_f64(b, c->mesh_dam_impulse_vec.x);
    sd_bin_put_f64(b, c->mesh_dam_impulse_vec.y);
    sd_bin_put_f64(b, c->mesh_dam_impulse_vec.z);
    for (int k = 0; k < 4; k++)
        sd_bin_put_f64(b, c->phase_end[k]);
    for (int k = 0; k < 4; k++)
        sd_bin_put_f64(b, c->phase_wall[k]);
    sd_bin_put_f64(b, c->flow_len);
    sd_bin_put_f64(b, c->flow_q05);
    sd_bin_put_f64(b, c->flow_q95);
    sd_bin_put_f64(b, c->flow_front);
    sd_bin_put_f64(b, c->flow_len_time);
    sd_bin_put_i32(b, c->pack_at_rest);
    for (int k = 0; k < 3; k++)
        sd_bin_put_f64(b, c->pack_speed[k]);
    sd_bin_put_f64(b, c->phase_t0);
    sd_bin_put_f64(b, c->flow_wall);
    sd_bin_put_f64(b, now - c->wall0);
    sd_bin_put_f64(b, now - c->phase_w0);
    sd_bin_put_i64(b, pipes_len);
    sd_bin_put_i64(b, events_len);
    sd_bin_put_i64(b, series_len);
    sd_bin_put_i64(b, traj_len);
    /* the VTK series so far (file names relative to the output directory) */
    int np = c->pvd_on ? (int)c->pvd.n : 0;
    sd_bin_put_i32(b, np);
    for (int k = 0; k < np; k++) {
        int32_t len = (int32_t)strlen(c->pvd.file[k]);
        sd_bin_put_f64(b, c->pvd.time[k]);
        sd_bin_put_i32(b, c->pvd.part[k]);
        sd_bin_put_i32(b, len);
        sd_bin_put(b, c->pvd.file[k], (size_t)len);
    }
}

void sd_run_state_free(sd_run_restored *r)
{
    for (int k = 0; k < r->npvd; k++)
        free(r->pvd_file[k]);
    free(r->pvd_time);
    free(r->pvd_part);
    free(r->pvd_file);
    memset(r, 0, sizeof *r);
}

/* 0 on success; otherwise writes why to msg. */
int sd_run_state_unpack(run_ctx *c, const void *blob, size_t len, sd_run_restored *r, char *msg, size_t msglen)
{
    memset(r, 0, sizeof *r);
    sd_bin_reader b;
    sd_bin_reader_init(&b, blob, len);
    char magic[8];
    sd_bin_get(&b, magic, 8);
    if (b.bad || memcmp(magic, BLOB_MAGIC, 8)) {
        snprintf(msg, msglen, "holds no run-driver state of this version (not written by this 'sabodem run')");
        return -1;
    }
    const uint64_t branch = sd_bin_get_u64(&b), whole = sd_bin_get_u64(&b);
    r->kind = sd_bin_get_i32(&b);
    {
        /* the materials by id: the world's ids mean the scenario's names */
        const int nm = sd_bin_get_i32(&b);
        char names[SD_MATERIALS_MAX * SD_MATERIAL_NAME_MAX + 16] = "";
        int same = !b.bad && nm == c->s->n_materials;
        for (int m = 0; m < nm && m < SD_MATERIALS_MAX && !b.bad; m++) {
            const int nl = sd_bin_get_i32(&b);
            const char *t = nl > 0 && nl < SD_MATERIAL_NAME_MAX ? sd_bin_take(&b, (size_t)nl) : NULL;
            if (!t) {
                b.bad = 1;
                break;
            }
            same &= m < c->s->n_materials && (int)strlen(c->s->material_name[m]) == nl &&
                    !memcmp(t, c->s->material_name[m], (size_t)nl);
            const size_t at = strlen(names);
            snprintf(names + at, sizeof names - at, "%s%.*s", m ? ", " : "", nl, t);
        }
        if (b.bad || nm < 1 || nm > SD_MATERIALS_MAX) {
            snprintf(msg, msglen, "run-driver state is truncated or malformed");
            return -1;
        }
        if (!same) {
            snprintf(msg, msglen, "holds the materials (%s); %s declares others: a restart keeps the materials", names,
                     c->s->path);
            return -1;
        }
    }
    if (r->kind == SD_CKPT_FLOW_END && branch != sd_scenario_branch_hash(c->s)) {
        snprintf(msg, msglen,
                 "was written for other scenario parameters than %s (a restart may change only the capture-phase keys:"
                 " dam.l_h, dam.n_columns, dam.columns, dam.l_v, dam.beam_axes, dam.beam_gaps, dam.top_beam, dam.beams,"
                 " dam.members, dam.fixed_ends, dam.material, phases.capture_limit, phases.quiet_time,"
                 " phases.ke_fraction, water.probe, water.h_d_floating, water.capture_length, water.capture_end,"
                 " dam.event_threshold, dam.event_time)",
                 c->s->path);
        return -1;
    }
    if (r->kind == SD_CKPT_PERIODIC && whole != sd_scenario_run_hash(c->s)) {
        snprintf(msg, msglen,
                 "was written for other scenario parameters than %s (a restart from a periodic checkpoint continues"
                 " the same run: only solver.threads and output.checkpoint_interval may differ)",
                 c->s->path);
        return -1;
    }
    c->phase = sd_bin_get_i32(&b);
    c->flow_ended = sd_bin_get_i32(&b);
    c->dam_built = sd_bin_get_i32(&b);
    c->flow_ckpt_written = sd_bin_get_i32(&b);
    c->n_passed = sd_bin_get_i32(&b);
    c->flow_len_done = sd_bin_get_i32(&b);
    c->n_snap = sd_bin_get_i32(&b);
    c->info.n_rough = sd_bin_get_i32(&b);
    c->info.n_spheres = sd_bin_get_i32(&b);
    c->info.n_logs = sd_bin_get_i32(&b);
    c->info.first_moving_gid = sd_bin_get_i32(&b);
    c->info.n_pipes = sd_bin_get_i32(&b);
    if (b.bad || c->info.n_pipes < 0 || c->info.n_pipes > SD_MAX_DAM_PIPES) {
        snprintf(msg, msglen, "run-driver state is truncated or malformed");
        return -1;
    }
    for (int k = 0; k < c->info.n_pipes; k++) {
        c->info.pipe_gid[k] = sd_bin_get_i32(&b);
        c->info.pipe_kind[k] = sd_bin_get_i32(&b);
        c->info.pipe_coord[k] = sd_bin_get_f64(&b);
        /* a member's coordinate is its index in dam.members (the outputs look it up) */
        const int kind = c->info.pipe_kind[k];
        const double co = c->info.pipe_coord[k];
        if (kind < SD_PIPE_BEAM || kind > SD_PIPE_MEMBER ||
            (kind == SD_PIPE_MEMBER && !(co >= 0 && co < c->s->n_members && co == (int)co))) {
            snprintf(msg, msglen, "run-driver state: pipe %d is of an unknown kind, or names no member of dam.members", k);
            return -1;
        }
    }
    if (sd_pipe_loads_unpack(&c->loads, &b) || (c->loads.n != 0 && c->loads.n != c->info.n_pipes)) {
        snprintf(msg, msglen, "run-driver state: the pipe loads are malformed");
        return -1;
    }
    c->capture_cut = sd_bin_get_i32(&b);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        c->vol_total_class[k] = sd_bin_get_f64(&b);
    c->vol_total_logs = sd_bin_get_f64(&b);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        c->vol_passed_class[k] = sd_bin_get_f64(&b);
    c->vol_passed_logs = sd_bin_get_f64(&b);
    c->h_d = sd_bin_get_f64(&b);
    c->last_cross_time = sd_bin_get_f64(&b);
    c->ke_peak = sd_bin_get_f64(&b);
    c->dam_force_now = sd_bin_get_f64(&b);
    c->mesh_dam_peak = sd_bin_get_f64(&b);
    c->mesh_dam_t_peak = sd_bin_get_f64(&b);
    c->mesh_dam_impulse = sd_bin_get_f64(&b);
    c->mesh_dam_impulse_vec.x = sd_bin_get_f64(&b);
    c->mesh_dam_impulse_vec.y = sd_bin_get_f64(&b);
    c->mesh_dam_impulse_vec.z = sd_bin_get_f64(&b);
    for (int k = 0; k < 4; k++)
        c->phase_end[k] = sd_bin_get_f64(&b);
    for (int k = 0; k < 4; k++)
        c->phase_wall[k] = sd_bin_get_f64(&b);
    c->flow_len = sd_bin_get_f64(&b);
    c->flow_q05 = sd_bin_get_f64(&b);
    c->flow_q95 = sd_bin_get_f64(&b);
    c->flow_front = sd_bin_get_f64(&b);
    c->flow_len_time = sd_bin_get_f64(&b);
    c->pack_at_rest = sd_bin_get_i32(&b);
    for (int k = 0; k < 3; k++)
        c->pack_speed[k] = sd_bin_get_f64(&b);
    c->phase_t0 = sd_bin_get_f64(&b);
    c->flow_wall = sd_bin_get_f64(&b);
    r->wall_before = sd_bin_get_f64(&b);
    r->phase_wall_in = sd_bin_get_f64(&b);
    r->pipes_len = (long)sd_bin_get_i64(&b);
    r->events_len = (long)sd_bin_get_i64(&b);
    r->series_len = (long)sd_bin_get_i64(&b);
    r->traj_len = (long)sd_bin_get_i64(&b);
    int np = sd_bin_get_i32(&b);
    if (b.bad || np < 0 || (size_t)np > sd_bin_left(&b) / 16) {
        snprintf(msg, msglen, "run-driver state is truncated or malformed");
        return -1;
    }
    r->pvd_time = calloc((size_t)np + 1, sizeof(double));
    r->pvd_part = calloc((size_t)np + 1, sizeof(int));
    r->pvd_file = calloc((size_t)np + 1, sizeof(char *));
    if (!r->pvd_time || !r->pvd_part || !r->pvd_file) {
        snprintf(msg, msglen, "out of memory");
        sd_run_state_free(r);
        return -1;
    }
    for (int k = 0; k < np && !b.bad; k++) {
        r->pvd_time[k] = sd_bin_get_f64(&b);
        r->pvd_part[k] = sd_bin_get_i32(&b);
        int32_t l = sd_bin_get_i32(&b);
        if (b.bad || l <= 0 || l > 255 || (size_t)l > sd_bin_left(&b)) {
            b.bad = 1;
            break;
        }
        r->pvd_file[k] = malloc((size_t)l + 1);
        if (!r->pvd_file[k]) {
            b.bad = 1;
            break;
        }
        r->npvd = k + 1;
        sd_bin_get(&b, r->pvd_file[k], (size_t)l);
        r->pvd_file[k][l] = '\0';
        if (strchr(r->pvd_file[k], '/')) b.bad = 1;
    }
    if (b.bad || sd_bin_left(&b)) {
        snprintf(msg, msglen, "run-driver state is truncated or malformed");
        sd_run_state_free(r);
        return -1;
    }
    int ok = c->n_passed >= 0 && c->n_snap >= 0 && r->series_len >= 0 && r->traj_len >= -1 && r->pipes_len >= -1 && r->events_len >= -1 && isfinite(c->phase_t0) &&
             isfinite(c->h_d) && isfinite(r->wall_before) && isfinite(r->phase_wall_in) && isfinite(c->flow_wall);
    if (ok && r->kind == SD_CKPT_FLOW_END)
        ok = c->phase == PH_FLOW && c->flow_ended == 1 && c->dam_built == 0;
    else if (ok)
        ok = r->kind == SD_CKPT_PERIODIC && (c->s->flume_on ? c->phase >= PH_PACK && c->phase <= PH_CAPTURE : c->phase == PH_RUN) &&
             (c->dam_built == 0 || c->phase == PH_CAPTURE) && (c->flow_ended == 0 || c->phase != PH_PACK);
    if (!ok) {
        snprintf(msg, msglen, "is not a checkpoint of a run of this scenario (its driver state is inconsistent)");
        sd_run_state_free(r);
        return -1;
    }
    return 0;
}

static void dir_of(const char *path, char *buf, size_t n)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(buf, n, ".");
    else if (slash == path)
        snprintf(buf, n, "/");
    else
        snprintf(buf, n, "%.*s", (int)(slash - path), path);
}

/* dst := the first len bytes of src (len < 0: all of it); src and dst may be the same file. */
static int copy_prefix(const char *src, const char *dst, long len, char *msg, size_t msglen)
{
    FILE *f = fopen(src, "rb");
    if (!f) {
        snprintf(msg, msglen, "%s: cannot open: %s", src, strerror(errno));
        return -1;
    }
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    while (buf) {
        if (n == cap) {
            char *q = realloc(buf, cap * 2);
            if (!q) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = q;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0 || (len >= 0 && n >= (size_t)len)) break;
    }
    fclose(f);
    if (!buf) {
        snprintf(msg, msglen, "%s: out of memory", src);
        return -1;
    }
    if (len >= 0 && n < (size_t)len) {
        snprintf(msg, msglen,
                 "%s: %zu bytes, shorter than the %ld the checkpoint recorded (not the checkpoint's own output?)", src,
                 n, len);
        free(buf);
        return -1;
    }
    if (len >= 0) n = (size_t)len;
    char tmp[1400];
    snprintf(tmp, sizeof tmp, "%s.tmp", dst);
    FILE *g = fopen(tmp, "wb");
    int bad = !g || fwrite(buf, 1, n, g) != n;
    if (g && fclose(g)) bad = 1;
    if (!bad && rename(tmp, dst)) bad = 1;
    free(buf);
    if (bad) {
        snprintf(msg, msglen, "%s: cannot write: %s", dst, strerror(errno));
        unlink(tmp);
        return -1;
    }
    return 0;
}

/* The outputs so far continue in the new run's directory: the time series up to the checkpoint
 * (the recorded lengths: rows written after it, and a row cut by a kill, are dropped) and, when
 * the checkpoint lives elsewhere, the VTK files listed in the series. */
int sd_run_state_restore_outputs(run_ctx *c, const sd_run_restored *r, char *msg, size_t msglen)
{
    char src[1100], a[1300], b[1300];
    dir_of(c->restarted_from, src, sizeof src);
    snprintf(a, sizeof a, "%s/series.csv", src);
    snprintf(b, sizeof b, "%s/series.csv", c->dir);
    if (copy_prefix(a, b, r->series_len, msg, msglen)) return -1;
    if (r->pipes_len >= 0) {
        snprintf(a, sizeof a, "%s/pipes.csv", src);
        snprintf(b, sizeof b, "%s/pipes.csv", c->dir);
        if (copy_prefix(a, b, r->pipes_len, msg, msglen)) return -1;
    }
    if (r->events_len >= 0) {
        snprintf(a, sizeof a, "%s/events.csv", src);
        snprintf(b, sizeof b, "%s/events.csv", c->dir);
        if (copy_prefix(a, b, r->events_len, msg, msglen)) return -1;
    }
    if (c->s->n_traj > 0 && r->traj_len >= 0) {
        snprintf(a, sizeof a, "%s/trajectories.csv", src);
        snprintf(b, sizeof b, "%s/trajectories.csv", c->dir);
        if (copy_prefix(a, b, r->traj_len, msg, msglen)) return -1;
    }
    if (c->s->vtk_on && !sd_run_dir_holds(c->dir, c->restarted_from)) {
        for (int k = -1; k < r->npvd; k++) {
            const char *name = k < 0 ? "walls.vtp" : r->pvd_file[k];
            snprintf(a, sizeof a, "%s/%s", src, name);
            snprintf(b, sizeof b, "%s/%s", c->dir, name);
            char why[1400];
            if (copy_prefix(a, b, -1, why, sizeof why) && c->o->log)
                fprintf(c->o->log, "note: %s (the VTK series of the new run lacks it)\n", why);
        }
    }
    return 0;
}

static sd_status write_world(run_ctx *c, const sd_world *w, const char *path, int kind);

static sd_status write_state(run_ctx *c, const char *path, int kind)
{
    /* a decomposed run: the whole system gathered into one world (rank 0 writes it), taken
     * where the pairs are remade at the next step (run.c), as a restart from it remakes them at
     * its first */
    sd_world *whole = NULL;
    if (c->sys) {
        sd_status st = sd_run_slabs_whole(c, &whole);
        if (st || c->rank != 0) {
            sd_world_destroy(whole);
            return st;
        }
    }
    const sd_status st = write_world(c, whole ? whole : c->w, path, kind);
    sd_world_destroy(whole);
    return st;
}

static sd_status write_world(run_ctx *c, const sd_world *w, const char *path, int kind)
{
    long sl = file_len(c->series), tl = c->traj ? file_len(c->traj) : -1, pl = c->loads.csv ? file_len(c->loads.csv) : -1;
    long el = c->loads.ev_csv ? file_len(c->loads.ev_csv) : -1;
    if (sl < 0 || (c->traj && tl < 0) || (c->loads.csv && pl < 0) || (c->loads.ev_csv && el < 0)) return SD_ERR_IO;
    /* the rows the checkpoint counts are on the disk before the checkpoint that counts them */
    if (kind == SD_CKPT_PERIODIC && (fsync(fileno(c->series)) || (c->traj && fsync(fileno(c->traj))) ||
                                     (c->loads.csv && fsync(fileno(c->loads.csv))) ||
                                     (c->loads.ev_csv && fsync(fileno(c->loads.ev_csv)))))
        return SD_ERR_IO;
    sd_bin_writer b;
    sd_bin_writer_init(&b);
    state_pack(c, &b, kind, sl, tl, pl, el);
    sd_status st = b.err ? SD_ERR_NOMEM : sd_checkpoint_write(path, w, b.p, b.n);
    sd_bin_writer_fini(&b);
    return st;
}

sd_status sd_run_state_checkpoint(run_ctx *c, const char *path)
{
    c->flow_ckpt_written = 1; /* (a restart from it does not write it again) */
    if (c->sys) sd_run_slabs_request_rebuild(c); /* (the dam's pipes go in next anyway, if any) */
    return write_state(c, path, SD_CKPT_FLOW_END);
}

/* checkpoint_<step>.ckpt: its step, or -1 for another name */
static long periodic_step(const char *name)
{
    const char *pre = "checkpoint_";
    size_t lp = strlen(pre), n = strlen(name);
    if (n != lp + 10 + 5 || strncmp(name, pre, lp) || strcmp(name + n - 5, ".ckpt")) return -1;
    long v = 0;
    for (size_t k = lp; k < lp + 10; k++) {
        if (name[k] < '0' || name[k] > '9') return -1;
        v = v * 10 + (name[k] - '0');
    }
    return v;
}

sd_status sd_run_state_periodic(run_ctx *c)
{
    const long step = sd_world_step_count(c->w);
    char path[1400];
    snprintf(path, sizeof path, "%s/checkpoint_%010ld.ckpt", c->dir, step);
    sd_status st = write_state(c, path, SD_CKPT_PERIODIC);
    if (st || c->rank != 0) return st;
    /* keep this one and the newest before it */
    DIR *d = opendir(c->dir);
    if (!d) return SD_OK;
    long prev = -1;
    for (struct dirent *e; (e = readdir(d));) {
        long k = periodic_step(e->d_name);
        if (k >= 0 && k < step && k > prev) prev = k;
    }
    rewinddir(d);
    for (struct dirent *e; (e = readdir(d));) {
        long k = periodic_step(e->d_name);
        if (k >= 0 && k < prev) {
            snprintf(path, sizeof path, "%s/%s", c->dir, e->d_name);
            (void)unlink(path);
        }
    }
    closedir(d);
    return SD_OK;
}
