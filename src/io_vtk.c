/* VTK XML PolyData / PVD writers; see io_vtk.h. */
#include "io_vtk.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- atomic file: temp in the same directory, rename on success ---- */

typedef struct {
    FILE *f;
    char *tmp;
    const char *path;
    int err; /* first errno seen, 0 if none */
} sd_afile;

static int afile_open(sd_afile *a, const char *path)
{
    memset(a, 0, sizeof *a);
    a->path = path;
    size_t len = strlen(path);
    a->tmp = malloc(len + 8);
    if (!a->tmp) {
        errno = ENOMEM;
        return -1;
    }
    memcpy(a->tmp, path, len);
    memcpy(a->tmp + len, ".XXXXXX", 8);
    int fd = mkstemp(a->tmp);
    if (fd < 0) {
        int e = errno;
        free(a->tmp);
        a->tmp = NULL;
        errno = e;
        return -1;
    }
    (void)fchmod(fd, 0644); /* mkstemp gives 0600; snapshots are meant to be shared */
    a->f = fdopen(fd, "w");
    if (!a->f) {
        int e = errno;
        close(fd);
        unlink(a->tmp);
        free(a->tmp);
        a->tmp = NULL;
        errno = e;
        return -1;
    }
    return 0;
}

/* Record the first error of a stdio call. */
static void afile_check(sd_afile *a, int failed)
{
    if (failed && !a->err) a->err = errno ? errno : EIO;
}

static int afile_close(sd_afile *a)
{
    int e = a->err;
    if (!e && ferror(a->f)) e = errno ? errno : EIO;
    if (fclose(a->f) != 0 && !e) e = errno ? errno : EIO;
    a->f = NULL;
    if (!e && rename(a->tmp, a->path) != 0) e = errno;
    if (e) unlink(a->tmp);
    free(a->tmp);
    a->tmp = NULL;
    if (e) {
        errno = e;
        return -1;
    }
    return 0;
}

static void wr(sd_afile *a, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void wr(sd_afile *a, const char *fmt, ...)
{
    if (a->err) return;
    va_list ap;
    va_start(ap, fmt);
    errno = 0;
    int r = vfprintf(a->f, fmt, ap);
    va_end(ap);
    afile_check(a, r < 0);
}

/* ---- PolyData pieces ---- */

static void wr_header(sd_afile *a, const char *type)
{
    wr(a,
       "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"%s\" version=\"0.1\" byte_order=\"LittleEndian\">\n",
       type);
}

static void wr_double(sd_afile *a, double v)
{
    if (!isfinite(v)) v = isnan(v) ? 0.0 : (v > 0 ? 1e300 : -1e300); /* keep the XML numeric */
    wr(a, "%.12g", v);
}

static void wr_array_begin(sd_afile *a, const char *type, const char *name, int ncomp)
{
    wr(a, "        <DataArray type=\"%s\"", type);
    if (name) wr(a, " Name=\"%s\"", name);
    if (ncomp > 1) wr(a, " NumberOfComponents=\"%d\"", ncomp);
    wr(a, " format=\"ascii\">\n");
}

static void wr_array_end(sd_afile *a) { wr(a, "        </DataArray>\n"); }

static void wr_scalars(sd_afile *a, const char *name, size_t n, const double *v, double fill)
{
    wr_array_begin(a, "Float64", name, 1);
    for (size_t i = 0; i < n; i++) {
        wr_double(a, v ? v[i] : fill);
        wr(a, (i % 8 == 7 || i + 1 == n) ? "\n" : " ");
    }
    wr_array_end(a);
}

static void wr_vec(sd_afile *a, sd_vec3 v)
{
    wr_double(a, v.x);
    wr(a, " ");
    wr_double(a, v.y);
    wr(a, " ");
    wr_double(a, v.z);
    wr(a, "\n");
}

static void wr_vectors(sd_afile *a, const char *name, size_t n, const sd_vec3 *v)
{
    wr_array_begin(a, "Float64", name, 3);
    sd_vec3 zero = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < n; i++)
        wr_vec(a, v ? v[i] : zero);
    wr_array_end(a);
}

/* ints; v NULL → index (iota) if iota, else 0 */
static void wr_ints(sd_afile *a, const char *name, size_t n, const int *v, int iota)
{
    wr_array_begin(a, "Int32", name, 1);
    for (size_t i = 0; i < n; i++) {
        long x = v ? (long)v[i] : (iota ? (long)i : 0L);
        wr(a, "%ld", x);
        wr(a, (i % 16 == 15 || i + 1 == n) ? "\n" : " ");
    }
    wr_array_end(a);
}

/* cells of size k over points 0..n*k-1 */
static void wr_cells(sd_afile *a, const char *tag, size_t ncell, int k)
{
    wr(a, "      <%s>\n", tag);
    wr_array_begin(a, "Int64", "connectivity", 1);
    size_t np = ncell * (size_t)k;
    for (size_t i = 0; i < np; i++)
        wr(a, "%zu%s", i, (i % 16 == 15 || i + 1 == np) ? "\n" : " ");
    wr_array_end(a);
    wr_array_begin(a, "Int64", "offsets", 1);
    for (size_t i = 0; i < ncell; i++)
        wr(a, "%zu%s", (i + 1) * (size_t)k, (i % 16 == 15 || i + 1 == ncell) ? "\n" : " ");
    wr_array_end(a);
    wr(a, "      </%s>\n", tag);
}

static void wr_piece_begin(sd_afile *a, size_t npts, size_t nverts, size_t npolys)
{
    wr_header(a, "PolyData");
    wr(a,
       "  <PolyData>\n"
       "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"%zu\" NumberOfLines=\"0\""
       " NumberOfStrips=\"0\" NumberOfPolys=\"%zu\">\n",
       npts, nverts, npolys);
}

static void wr_points(sd_afile *a, size_t n, const sd_vec3 *p)
{
    wr(a, "      <Points>\n");
    wr_vectors(a, "Points", n, p);
    wr(a, "      </Points>\n");
}

static void wr_piece_end(sd_afile *a)
{
    wr(a, "    </Piece>\n"
          "  </PolyData>\n"
          "</VTKFile>\n");
}

static int bad_args(void)
{
    errno = EINVAL;
    return -1;
}

int sd_vtk_write_spheres(const char *path, size_t n, const sd_vec3 *pos, const double *radius, const sd_vec3 *vel,
                         const int *id, const int *tag)
{
    if (!path || (n > 0 && (!pos || !radius))) return bad_args();
    sd_afile a;
    if (afile_open(&a, path) != 0) return -1;
    wr_piece_begin(&a, n, n, 0);
    wr(&a, "      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n");
    wr_scalars(&a, "radius", n, radius, 0.0);
    wr_array_begin(&a, "Float64", "diameter", 1);
    for (size_t i = 0; i < n; i++) {
        wr_double(&a, 2.0 * radius[i]);
        wr(&a, (i % 8 == 7 || i + 1 == n) ? "\n" : " ");
    }
    wr_array_end(&a);
    wr_vectors(&a, "velocity", n, vel);
    wr_ints(&a, "id", n, id, 1);
    wr_ints(&a, "tag", n, tag, 0);
    wr(&a, "      </PointData>\n");
    wr_points(&a, n, pos);
    wr_cells(&a, "Verts", n, 1);
    wr_piece_end(&a);
    return afile_close(&a);
}

int sd_vtk_write_cylinders(const char *path, size_t n, const sd_vec3 *pos, const sd_vec3 *axis, const double *length,
                           const double *radius, const sd_vec3 *vel, const int *id, const int *tag)
{
    if (!path || (n > 0 && (!pos || !axis || !length || !radius))) return bad_args();
    sd_afile a;
    if (afile_open(&a, path) != 0) return -1;
    wr_piece_begin(&a, n, n, 0);
    wr(&a, "      <PointData Scalars=\"length\" Vectors=\"axis\">\n");
    wr_array_begin(&a, "Float64", "axis", 3);
    for (size_t i = 0; i < n; i++) {
        sd_vec3 u = axis[i];
        double m = sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
        if (m > 0.0 && isfinite(m)) {
            u.x /= m;
            u.y /= m;
            u.z /= m;
        } else {
            u.x = 0.0;
            u.y = 0.0;
            u.z = 1.0;
        }
        wr_vec(&a, u);
    }
    wr_array_end(&a);
    wr_scalars(&a, "length", n, length, 0.0);
    wr_scalars(&a, "radius", n, radius, 0.0);
    wr_vectors(&a, "velocity", n, vel);
    wr_ints(&a, "id", n, id, 1);
    wr_ints(&a, "tag", n, tag, 0);
    wr_array_begin(&a, "Float64", "glyph_scale", 3);
    for (size_t i = 0; i < n; i++) {
        sd_vec3 s = {length[i], 2.0 * radius[i], 2.0 * radius[i]};
        wr_vec(&a, s);
    }
    wr_array_end(&a);
    wr(&a, "      </PointData>\n");
    wr_points(&a, n, pos);
    wr_cells(&a, "Verts", n, 1);
    wr_piece_end(&a);
    return afile_close(&a);
}

int sd_vtk_write_triangles(const char *path, size_t n, const sd_vec3 *verts, const int *group)
{
    if (!path || (n > 0 && !verts)) return bad_args();
    sd_afile a;
    if (afile_open(&a, path) != 0) return -1;
    wr_piece_begin(&a, 3 * n, 0, n);
    wr(&a, "      <CellData Scalars=\"group\" Normals=\"normal\">\n");
    wr_ints(&a, "group", n, group, 0);
    wr_array_begin(&a, "Float64", "normal", 3);
    for (size_t k = 0; k < n; k++) {
        sd_vec3 p = verts[3 * k], q = verts[3 * k + 1], r = verts[3 * k + 2];
        sd_vec3 e1 = {q.x - p.x, q.y - p.y, q.z - p.z}, e2 = {r.x - p.x, r.y - p.y, r.z - p.z};
        sd_vec3 c = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
        double m = sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
        if (m > 0.0 && isfinite(m)) {
            c.x /= m;
            c.y /= m;
            c.z /= m;
        } else {
            c.x = c.y = c.z = 0.0;
        }
        wr_vec(&a, c);
    }
    wr_array_end(&a);
    wr(&a, "      </CellData>\n");
    wr_points(&a, 3 * n, verts);
    wr_cells(&a, "Polys", n, 3);
    wr_piece_end(&a);
    return afile_close(&a);
}

/* ---- PVD ---- */

static void wr_escaped(sd_afile *a, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&':
            wr(a, "&amp;");
            break;
        case '<':
            wr(a, "&lt;");
            break;
        case '>':
            wr(a, "&gt;");
            break;
        case '"':
            wr(a, "&quot;");
            break;
        case '\'':
            wr(a, "&apos;");
            break;
        default:
            wr(a, "%c", *s);
            break;
        }
    }
}

int sd_vtk_write_pvd(const char *path, size_t n, const double *time, const int *part, const char *const *file)
{
    if (!path || (n > 0 && (!time || !file))) return bad_args();
    for (size_t i = 0; i < n; i++)
        if (!file[i]) return bad_args();
    sd_afile a;
    if (afile_open(&a, path) != 0) return -1;
    wr_header(&a, "Collection");
    wr(&a, "  <Collection>\n");
    for (size_t i = 0; i < n; i++) {
        wr(&a, "    <DataSet timestep=\"");
        wr_double(&a, time[i]);
        wr(&a, "\" group=\"\" part=\"%d\" file=\"", part ? part[i] : 0);
        wr_escaped(&a, file[i]);
        wr(&a, "\"/>\n");
    }
    wr(&a, "  </Collection>\n"
           "</VTKFile>\n");
    return afile_close(&a);
}

int sd_vtk_series_init(sd_vtk_series *s, const char *pvd_path)
{
    if (!s) return bad_args();
    memset(s, 0, sizeof *s);
    if (!pvd_path) return bad_args();
    size_t len = strlen(pvd_path) + 1;
    s->path = malloc(len);
    if (!s->path) {
        errno = ENOMEM;
        return -1;
    }
    memcpy(s->path, pvd_path, len);
    return 0;
}

int sd_vtk_series_flush(const sd_vtk_series *s)
{
    if (!s || !s->path) return bad_args();
    return sd_vtk_write_pvd(s->path, s->n, s->time, s->part, (const char *const *)s->file);
}

int sd_vtk_series_add(sd_vtk_series *s, double time, int part, const char *file)
{
    if (!s || !s->path || !file) return bad_args();
    if (s->n == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 16;
        double *t = realloc(s->time, cap * sizeof *t);
        if (!t) goto nomem;
        s->time = t;
        int *p = realloc(s->part, cap * sizeof *p);
        if (!p) goto nomem;
        s->part = p;
        char **f = realloc(s->file, cap * sizeof *f);
        if (!f) goto nomem;
        s->file = f;
        s->cap = cap;
    }
    size_t len = strlen(file) + 1;
    char *copy = malloc(len);
    if (!copy) goto nomem;
    memcpy(copy, file, len);
    s->time[s->n] = time;
    s->part[s->n] = part;
    s->file[s->n] = copy;
    s->n++;
    return sd_vtk_series_flush(s);
nomem:
    errno = ENOMEM;
    return -1;
}

void sd_vtk_series_free(sd_vtk_series *s)
{
    if (!s) return;
    for (size_t i = 0; i < s->n; i++)
        free(s->file[i]);
    free(s->file);
    free(s->time);
    free(s->part);
    free(s->path);
    memset(s, 0, sizeof *s);
}
