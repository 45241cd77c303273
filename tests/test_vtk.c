/* VTK XML writers (src/io_vtk.c): write small known sets into a temp dir, read them back with
 * the independent Python checker (scripts/check_vtk.py, xml.etree only) and parse numbers
 * back in C. Runs with the repository root as working directory (ctest WORKING_DIRECTORY). */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "io_vtk.h"

static char dir[64];
static const char *python = "python3";
static char script[1024] = "scripts/check_vtk.py";

/* The interpreter: $SD_PYTHON, else Debian's /usr/bin/python3 (a pyenv shim on PATH costs
 * half a second a call), else python3 from PATH. */
static void pick_python(void)
{
    const char *env = getenv("SD_PYTHON");
    if (env && *env) python = env;
    else if (access("/usr/bin/python3", X_OK) == 0) python = "/usr/bin/python3";
    /* ctest runs in the repository root; elsewhere, find the script beside this source */
    const char *src = __FILE__, *cut = strstr(src, "tests/test_vtk.c");
    if (access(script, R_OK) != 0 && cut && cut - src < 900)
        snprintf(script, sizeof script, "%.*sscripts/check_vtk.py", (int)(cut - src), src);
}

static void path_of(char *out, size_t cap, const char *name)
{
    snprintf(out, cap, "%s/%s", dir, name);
}

/* Run the checker on dir/name with extra args; returns its exit status (-1 if it did not run). */
static int run_checker(const char *name, const char *args)
{
    char cmd[2560];
    snprintf(cmd, sizeof cmd, "%s '%s' '%s/%s' --quiet %s", python, script, dir, name, args);
    int st = system(cmd);
    if (st == -1 || !WIFEXITED(st)) return -1;
    return WEXITSTATUS(st);
}

static char *slurp(const char *name)
{
    char p[256];
    path_of(p, sizeof p, name);
    FILE *f = fopen(p, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    if (buf) buf[n] = '\0';
    fclose(f);
    return buf;
}

/* Parse up to cap numbers of the DataArray named name; returns how many were read. */
static int parse_array(const char *xml, const char *name, double *out, int cap)
{
    char key[128];
    snprintf(key, sizeof key, "Name=\"%s\"", name);
    const char *s = strstr(xml, key);
    if (!s) return -1;
    s = strchr(s, '>');
    if (!s) return -1;
    s++;
    int k = 0;
    for (;;) {
        char *end;
        double v = strtod(s, &end);
        if (end == s) break; /* reached '<' */
        if (k < cap) out[k] = v;
        k++;
        s = end;
    }
    return k;
}

static int count_dir(int *leftover_tmp)
{
    DIR *d = opendir(dir);
    int n = 0;
    *leftover_tmp = 0;
    if (!d) return -1;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        n++;
        /* temp files are "<name>.XXXXXX" */
        const char *dot = strrchr(e->d_name, '.');
        if (dot && strlen(dot) == 7) (*leftover_tmp)++;
    }
    closedir(d);
    return n;
}

static void cleanup(void)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char p[512];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        unlink(p);
    }
    closedir(d);
    rmdir(dir);
}

static void test_spheres(void)
{
    const sd_vec3 pos[3] = {{0.1, 0.2, 0.3}, {1.5, -0.25, 0.0125}, {4.0, 0.3, 1e-3}};
    const double rad[3] = {0.01, 0.0075, 0.0025};
    const sd_vec3 vel[3] = {{1.2, 0.0, -0.5}, {0.0, 0.0, 0.0}, {-3.25e-3, 7.0, 1.0 / 3.0}};
    const int id[3] = {10, 11, 12}, tag[3] = {0, 1, 2};
    char p[256];
    path_of(p, sizeof p, "spheres_0001.vtp");
    CHECK(sd_vtk_write_spheres(p, 3, pos, rad, vel, id, tag) == 0);
    CHECK(run_checker("spheres_0001.vtp", "--points 3 --verts 3 --fields radius:1,diameter:1,velocity:3,id:1,tag:1") == 0);
    /* the checker must catch a wrong count and a missing field */
    CHECK(run_checker("spheres_0001.vtp", "--points 4 2>/dev/null") == 1);
    CHECK(run_checker("spheres_0001.vtp", "--fields axis 2>/dev/null") == 1);
    CHECK(run_checker("spheres_0001.vtp", "--fields velocity:1 2>/dev/null") == 1);

    /* numbers back in C */
    char *xml = slurp("spheres_0001.vtp");
    CHECK(xml != NULL);
    if (xml) {
        double v[16];
        CHECK(parse_array(xml, "radius", v, 16) == 3);
        for (int i = 0; i < 3; i++) CHECK_REL(v[i], rad[i], 1e-11);
        CHECK(parse_array(xml, "diameter", v, 16) == 3);
        for (int i = 0; i < 3; i++) CHECK_REL(v[i], 2.0 * rad[i], 1e-11);
        CHECK(parse_array(xml, "velocity", v, 16) == 9);
        for (int i = 0; i < 3; i++) {
            CHECK_NEAR(v[3 * i + 0], vel[i].x, 1e-11 * fabs(vel[i].x));
            CHECK_NEAR(v[3 * i + 1], vel[i].y, 1e-11 * fabs(vel[i].y));
            CHECK_NEAR(v[3 * i + 2], vel[i].z, 1e-11 * fabs(vel[i].z));
        }
        CHECK(parse_array(xml, "Points", v, 16) == 9);
        for (int i = 0; i < 3; i++) {
            CHECK_REL(v[3 * i + 0], pos[i].x, 1e-11);
            CHECK_REL(v[3 * i + 2], pos[i].z, 1e-11);
        }
        CHECK(parse_array(xml, "id", v, 16) == 3);
        for (int i = 0; i < 3; i++) CHECK(v[i] == id[i]);
        CHECK(parse_array(xml, "tag", v, 16) == 3);
        CHECK(v[2] == 2.0);
        free(xml);
    }

    /* the independent reader's numbers agree too (--dump prints one tuple a line) */
    char cmd[2560];
    snprintf(cmd, sizeof cmd, "%s '%s' '%s/spheres_0001.vtp' --quiet --dump radius", python, script, dir);
    FILE *pp = popen(cmd, "r");
    CHECK(pp != NULL);
    if (pp) {
        double r;
        int k = 0;
        while (k < 5 && fscanf(pp, "%lf", &r) == 1) {
            if (k < 3) CHECK_REL(r, rad[k], 1e-11);
            k++;
        }
        CHECK(k == 3);
        CHECK(pclose(pp) == 0);
    }

    /* defaults for the optional arrays; overwrite in place (atomic rename) with fewer */
    CHECK(sd_vtk_write_spheres(p, 1, pos + 1, rad + 1, NULL, NULL, NULL) == 0);
    CHECK(run_checker("spheres_0001.vtp", "--points 1 --fields radius,velocity:3,id,tag") == 0);
    xml = slurp("spheres_0001.vtp");
    if (xml) {
        double v[4];
        CHECK(parse_array(xml, "id", v, 4) == 1 && v[0] == 0.0);
        CHECK(parse_array(xml, "velocity", v, 4) == 3 && v[0] == 0.0 && v[2] == 0.0);
        free(xml);
    }
    CHECK(sd_vtk_write_spheres(p, 3, pos, rad, vel, id, tag) == 0);

    /* empty set is a valid file */
    path_of(p, sizeof p, "a&b.vtp");
    CHECK(sd_vtk_write_spheres(p, 0, NULL, NULL, NULL, NULL, NULL) == 0);
    CHECK(run_checker("a&b.vtp", "--points 0 --fields radius,velocity") == 0);
}

static void test_logs(void)
{
    const sd_vec3 pos[2] = {{2.0, 0.15, 0.02}, {2.1, 0.1, 0.05}};
    const sd_vec3 axis[2] = {{1.0, 0.0, 0.0}, {0.0, 3.0, 4.0}}; /* second not unit: → (0, .6, .8) */
    const double len[2] = {0.1, 0.1}, rad[2] = {0.005, 0.005};
    const sd_vec3 vel[2] = {{0.5, 0.0, 0.0}, {0.25, 0.1, -0.2}};
    const int id[2] = {100, 101};
    char p[256];
    path_of(p, sizeof p, "logs_0001.vtp");
    CHECK(sd_vtk_write_cylinders(p, 2, pos, axis, len, rad, vel, id, NULL) == 0);
    CHECK(run_checker("logs_0001.vtp", "--points 2 --fields axis:3,length:1,radius:1,velocity:3,id,tag,glyph_scale:3") == 0);
    char *xml = slurp("logs_0001.vtp");
    CHECK(xml != NULL);
    if (xml) {
        double v[8];
        CHECK(parse_array(xml, "axis", v, 8) == 6);
        CHECK_NEAR(v[0], 1.0, 1e-12);
        CHECK_NEAR(v[3], 0.0, 1e-12);
        CHECK_NEAR(v[4], 0.6, 1e-12);
        CHECK_NEAR(v[5], 0.8, 1e-12);
        CHECK(parse_array(xml, "glyph_scale", v, 8) == 6);
        CHECK_REL(v[0], 0.1, 1e-12);
        CHECK_REL(v[1], 0.01, 1e-12);
        CHECK_REL(v[2], 0.01, 1e-12);
        CHECK(parse_array(xml, "length", v, 8) == 2);
        CHECK_REL(v[1], 0.1, 1e-12);
        free(xml);
    }
}

static void test_walls(void)
{
    /* two quads: bed (z = 0, 0 <= x <= 4, 0 <= y <= 0.3), side wall y = 0 */
    const sd_vec3 v[12] = {
        {0, 0, 0}, {4, 0, 0}, {4, 0.3, 0},   {0, 0, 0}, {4, 0.3, 0}, {0, 0.3, 0},
        {0, 0, 0}, {0, 0, 0.5}, {4, 0, 0.5}, {0, 0, 0}, {4, 0, 0.5}, {4, 0, 0},
    };
    const int group[4] = {0, 0, 1, 1};
    char p[256];
    path_of(p, sizeof p, "walls.vtp");
    CHECK(sd_vtk_write_triangles(p, 4, v, group) == 0);
    CHECK(run_checker("walls.vtp", "--points 12 --polys 4 --cell-fields group:1,normal:3") == 0);
    CHECK(run_checker("walls.vtp", "--polys 3 2>/dev/null") == 1);
    char *xml = slurp("walls.vtp");
    CHECK(xml != NULL);
    if (xml) {
        double a[16];
        CHECK(parse_array(xml, "group", a, 16) == 4);
        CHECK(a[0] == 0.0 && a[1] == 0.0 && a[2] == 1.0 && a[3] == 1.0);
        CHECK(parse_array(xml, "normal", a, 16) == 12);
        CHECK_NEAR(a[2], 1.0, 1e-12);  /* bed: +z */
        CHECK_NEAR(a[7], 1.0, 1e-12);  /* wall (0,0,0),(0,0,.5),(4,0,.5): +y */
        CHECK(parse_array(xml, "offsets", a, 16) == 4);
        CHECK(a[3] == 12.0);
        free(xml);
    }
}

static void test_pvd(void)
{
    char p[256];
    path_of(p, sizeof p, "spheres.pvd");
    sd_vtk_series s;
    CHECK(sd_vtk_series_init(&s, p) == 0);
    CHECK(sd_vtk_series_flush(&s) == 0); /* empty collection */
    CHECK(run_checker("spheres.pvd", "--entries 0") == 0);
    CHECK(sd_vtk_series_add(&s, 0.0, 0, "spheres_0001.vtp") == 0);
    CHECK(run_checker("spheres.pvd", "--entries 1 --recurse") == 0);
    CHECK(sd_vtk_series_add(&s, 0.25, 0, "logs_0001.vtp") == 0);
    CHECK(run_checker("spheres.pvd", "--entries 2 --recurse") == 0);
    CHECK(run_checker("spheres.pvd", "--entries 3 2>/dev/null") == 1);
    char *xml = slurp("spheres.pvd");
    CHECK(xml != NULL);
    if (xml) {
        CHECK(strstr(xml, "timestep=\"0.25\"") != NULL);
        CHECK(strstr(xml, "file=\"logs_0001.vtp\"") != NULL);
        free(xml);
    }
    sd_vtk_series_free(&s);

    /* plain writer, XML escaping of file names, parts */
    const double t[2] = {1.5, 1.5};
    const int part[2] = {0, 1};
    const char *files[2] = {"a&b.vtp", "walls.vtp"};
    path_of(p, sizeof p, "multi.pvd");
    CHECK(sd_vtk_write_pvd(p, 2, t, part, files) == 0);
    CHECK(run_checker("multi.pvd", "--entries 2 --recurse") == 0);
    /* a missing file is caught */
    const char *missing[1] = {"nope.vtp"};
    path_of(p, sizeof p, "bad.pvd");
    CHECK(sd_vtk_write_pvd(p, 1, t, NULL, missing) == 0);
    CHECK(run_checker("bad.pvd", "--entries 1 2>/dev/null") == 1);
    CHECK(run_checker("bad.pvd", "--entries 1 --no-files") == 0);
}

static void test_errors(void)
{
    char p[256];
    const sd_vec3 pos = {0, 0, 0};
    const double r = 0.01;
    path_of(p, sizeof p, "no_such_dir/x.vtp");
    errno = 0;
    CHECK(sd_vtk_write_spheres(p, 1, &pos, &r, NULL, NULL, NULL) == -1);
    CHECK(errno == ENOENT);
    errno = 0;
    CHECK(sd_vtk_write_pvd(p, 0, NULL, NULL, NULL) == -1);
    CHECK(errno == ENOENT);
    path_of(p, sizeof p, "x.vtp");
    errno = 0;
    CHECK(sd_vtk_write_spheres(p, 2, NULL, &r, NULL, NULL, NULL) == -1);
    CHECK(errno == EINVAL);
    errno = 0;
    CHECK(sd_vtk_write_cylinders(p, 1, &pos, NULL, &r, &r, NULL, NULL, NULL) == -1);
    CHECK(errno == EINVAL);
    CHECK(access(p, F_OK) != 0); /* nothing written */
}

int main(void)
{
    pick_python();
    strcpy(dir, "/tmp/sd_vtk_XXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_spheres();
    test_logs();
    test_walls();
    test_pvd();
    test_errors();
    /* spheres_0001, a&b, logs_0001, walls, spheres.pvd, multi.pvd, bad.pvd; no temp files */
    int tmp_left;
    CHECK(count_dir(&tmp_left) == 7);
    CHECK(tmp_left == 0);
    cleanup();
    CHECK(access(dir, F_OK) != 0);
    return check_report("test_vtk");
}
