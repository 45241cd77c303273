#include "plot.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <spawn.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

/* dir/name exists as a file: path filled */
static int script_in(const char *dir, const char *name, char *path, size_t len)
{
    struct stat st;
    if (snprintf(path, len, "%s/%s", dir, name) >= (int)len) return 0;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* The script `name`'s path (see plot.h); 0 when found. */
static int script_path(const char *name, char *path, size_t len)
{
    const char *env = getenv("SABODEM_SCRIPTS");
    if (env && *env && script_in(env, name, path, len)) return 0;
    char exe[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) return -1;
    exe[n] = 0;
    char *slash = strrchr(exe, '/');
    if (!slash) return -1;
    *slash = 0;
    char dir[PATH_MAX + 32];
    snprintf(dir, sizeof dir, "%s/../share/sabodem", exe);
    if (script_in(dir, name, path, len)) return 0;
    snprintf(dir, sizeof dir, "%s/../scripts", exe);
    if (script_in(dir, name, path, len)) return 0;
    return -1;
}

/* python3 with argv (argv[0] is set here), its output to `out` (NULL: /dev/null); the pid, or -1 */
static pid_t spawn_python(char **argv, const char *out)
{
    posix_spawn_file_actions_t fa;
    if (posix_spawn_file_actions_init(&fa)) return -1;
    const char *o = out ? out : "/dev/null";
    posix_spawn_file_actions_addopen(&fa, 1, o, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    /* Debian's python3 (where python3-matplotlib is), else the first on the PATH */
    const int sys = access("/usr/bin/python3", X_OK) == 0;
    argv[0] = sys ? "/usr/bin/python3" : "python3";
    pid_t pid;
    const int rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    return rc ? -1 : pid;
}

static int wait_ok(pid_t pid)
{
    int status = 0;
    if (pid < 0) return 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return 0;
    return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

int app_draw_pictures(const sd_run_result *r, FILE *log)
{
    char script[PATH_MAX + 64];
    const int have = script_path("plot_side.py", script, sizeof script) == 0;
    pid_t pid[SD_RUN_PICTURES];
    for (int k = 0; k < r->n_pictures; k++) {
        const sd_run_picture *p = &r->pictures[k];
        char xd[32], x0[32], x1[32];
        snprintf(xd, sizeof xd, "%.17g", p->x_dam);
        snprintf(x0, sizeof x0, "%.17g", p->x_min);
        snprintf(x1, sizeof x1, "%.17g", p->x_max);
        char *argv[] = {NULL,       script,   "--spheres", (char *)p->spheres, "--logs",          (char *)p->logs,
                        "--xdam",   xd,       "--xmin",    x0,                 "--xmax",          x1,
                        "--out",    (char *)p->png, NULL};
        pid[k] = have ? spawn_python(argv, NULL) : -1;
    }
    int drawn = 0;
    for (int k = 0; k < r->n_pictures; k++) {
        const int ok = wait_ok(pid[k]);
        drawn += ok;
        if (!ok && log)
            fprintf(log, "note: picture %s not drawn (%s)\n", r->pictures[k].png,
                    have ? "python3-matplotlib missing?" : "scripts/plot_side.py not found; set SABODEM_SCRIPTS");
    }
    return drawn;
}

int app_draw_sweep(const char *outdir)
{
    char script[PATH_MAX + 64], out[PATH_MAX + 64];
    if (script_path("plot_sweep.py", script, sizeof script)) return -1;
    if (snprintf(out, sizeof out, "%s/plot.log", outdir) >= (int)sizeof out) return -1;
    char *argv[] = {NULL, script, (char *)outdir, NULL};
    return wait_ok(spawn_python(argv, out)) ? 0 : -1;
}

int app_draw_design(const char *data_dir, const char *png, const char *log_path)
{
    char script[PATH_MAX + 64];
    if (script_path("plot_design.py", script, sizeof script)) return -1;
    char *argv[] = {NULL, script, (char *)data_dir, (char *)png, NULL};
    return wait_ok(spawn_python(argv, log_path)) ? 0 : -1;
}
