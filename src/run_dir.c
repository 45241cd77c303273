/* A run's output directory: made the run's own (a directory holding another run's files is
 * refused unless told to overwrite), cleared of the old run's files, and, on a restart into the
 * checkpoint's own directory, cleared of what a kill left behind (temporary files, the stale
 * summary). */
#include <dirent.h>
#include <errno.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/status.h"
#include "run_ctx.h"

/* The names of the files a run (or a sweep, for its run: result.csv) writes. */
static int is_run_file(const char *name, size_t n)
{
    static const char *const exact[] = {"summary.json", "series.csv", "series.pvd", "trajectories.csv", "walls.vtp",
                                        "result.csv",   "flow_end.ckpt", "pipes.csv", "events.csv"};
    static const struct {
        const char *pre, *suf;
    } pattern[] = {{"spheres_", ".vtp"}, {"cylinders_", ".vtp"}, {"side_", ".png"}, {"checkpoint_", ".ckpt"}};
    for (size_t k = 0; k < sizeof exact / sizeof exact[0]; k++)
        if (n == strlen(exact[k]) && !strncmp(name, exact[k], n)) return 1;
    for (size_t k = 0; k < sizeof pattern / sizeof pattern[0]; k++) {
        size_t lp = strlen(pattern[k].pre), ls = strlen(pattern[k].suf);
        if (n > lp + ls && !strncmp(name, pattern[k].pre, lp) && !strncmp(name + n - ls, pattern[k].suf, ls)) return 1;
    }
    return 0;
}

/* An atomic writer's temporary file of a run file: NAME.tmp (summary, copies, result.csv),
 * NAME.tmp.XXXXXX (checkpoints), NAME.XXXXXX (VTK files; mkstemp's six characters). */
static int is_temp_file(const char *name)
{
    size_t n = strlen(name);
    if (n > 4 && !strcmp(name + n - 4, ".tmp")) return is_run_file(name, n - 4);
    if (n > 7 && name[n - 7] == '.') {
        if (n > 11 && !strncmp(name + n - 11, ".tmp", 4)) return is_run_file(name, n - 11);
        return is_run_file(name, n - 7);
    }
    return 0;
}

int sd_run_dir_claim(const char *dir, int overwrite, int resume, char *msg, size_t msglen)
{
    if (sd_mkdir_p(dir)) {
        snprintf(msg, msglen, "%s: cannot create the output directory: %s", dir, strerror(errno));
        return -1;
    }
    DIR *d = opendir(dir);
    if (!d) {
        snprintf(msg, msglen, "%s: cannot read the output directory: %s", dir, strerror(errno));
        return -1;
    }
    char path[1400], first[3][256];
    int n_other = 0, n_run = 0, bad = 0;
    for (struct dirent *e; (e = readdir(d));) {
        const char *name = e->d_name;
        if (!strcmp(name, ".") || !strcmp(name, "..")) continue;
        const int temp = is_temp_file(name), run = temp || is_run_file(name, strlen(name));
        int drop = resume ? temp || !strcmp(name, "summary.json") : overwrite && run;
        if (drop) {
            snprintf(path, sizeof path, "%s/%s", dir, name);
            if (unlink(path) && errno != ENOENT) {
                snprintf(msg, msglen, "%s: cannot delete the old run's file: %s", path, strerror(errno));
                bad = 1;
                break;
            }
            continue;
        }
        if (resume || (overwrite && !run)) continue; /* the run's own files; a stranger's, kept */
        if (n_run + n_other < 3) snprintf(first[n_run + n_other], sizeof first[0], "%s", name);
        if (run)
            n_run++;
        else
            n_other++;
    }
    closedir(d);
    if (bad) return -1;
    if (n_run + n_other > 0) {
        const int shown = n_run + n_other < 3 ? n_run + n_other : 3;
        int len = snprintf(msg, msglen, "%s: the output directory is not empty (it holds %s", dir,
                           n_run ? "another run's files:" : "other files:");
        for (int k = 0; k < shown && len > 0 && (size_t)len < msglen; k++)
            len += snprintf(msg + len, msglen - (size_t)len, " %s", first[k]);
        if (len > 0 && (size_t)len < msglen)
            snprintf(msg + len, msglen - (size_t)len, "%s); give --overwrite to replace %s, or another -o",
                     n_run + n_other > shown ? " ..." : "", n_run ? "that run's files" : "it (other files are kept)");
        return -1;
    }
    return 0;
}

int sd_run_dir_holds(const char *dir, const char *path)
{
    char d[1200];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(d, sizeof d, ".");
    else if (slash == path)
        snprintf(d, sizeof d, "/");
    else
        snprintf(d, sizeof d, "%.*s", (int)(slash - path), path);
    struct stat sa, sb;
    return stat(dir, &sa) == 0 && stat(d, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}
