/* ParaView-readable VTK XML output: PolyData (.vtp, ASCII) for spheres, cylinders (logs,
 * pipes) and triangle walls, and .pvd collections for time series.
 * Plain arrays in, no dependency on the world internals. Every file is written atomically:
 * to a temporary file in the same directory (mkstemp, mode 0644), then rename()d over the
 * target, so a reader never sees a half-written file. No fsync (a crash may lose the latest
 * snapshot, never corrupt the previous one on a journalled file system).
 * Every writer returns 0 on success, -1 on failure with errno set (EINVAL for bad arguments,
 * otherwise the errno of the failing call, preserved through the clean-up).
 * Numbers are written with 12 significant digits.
 *
 * ParaView recipes:
 *  - spheres: Glyph filter, Glyph Type Sphere, Scale Array "diameter" (Sphere source radius
 *    is 0.5, so scale by the diameter), Scale Factor 1.
 *  - cylinders (ParaView >= 5.6 Glyph filter, which takes scale and orientation from separate
 *    arrays): Glyph Type Cylinder, Orientation Array "axis", Scale Array "glyph_scale" with
 *    Vector Scale Mode "Scale by Components", Scale Factor 1, Glyph Transform Rotate
 *    (0, 0, -90) (the Cylinder source lies along y; the rotation puts it along x, which the
 *    orientation turns onto the axis). glyph_scale = (L, 2r, 2r) for the unit-height,
 *    radius-0.5 source. Not checked inside ParaView here; plain VTK's vtkGlyph3D cannot use
 *    it (its component scaling reads the orientation vectors): there, or as a fallback, glyph
 *    with Orientation "axis" and uniform Scale Array "length" (right length, but the diameter
 *    comes out equal to L), or draw them with scripts/plot_side.py. */
#ifndef SD_IO_VTK_H
#define SD_IO_VTK_H

#include <stddef.h>

#include "sabodem.h" /* sd_vec3 */

/* Spheres: points = centres; point data radius, diameter, velocity (3), id, tag; one vertex
 * cell per point. pos and radius required (may be NULL only when n == 0); vel NULL → zeros,
 * id NULL → 0..n-1, tag NULL → 0. */
int sd_vtk_write_spheres(const char *path, size_t n, const sd_vec3 *pos, const double *radius, const sd_vec3 *vel,
                         const int *id, const int *tag);

/* Cylinders (logs, dam pipes): points = centres; point data axis (3, unit; re-normalised,
 * a zero axis is written as (0,0,1)), length (full length L), radius, velocity (3), id, tag,
 * glyph_scale (3) = (L, 2r, 2r). pos, axis, length, radius required; vel, id, tag as above. */
int sd_vtk_write_cylinders(const char *path, size_t n, const sd_vec3 *pos, const sd_vec3 *axis, const double *length,
                           const double *radius, const sd_vec3 *vel, const int *id, const int *tag);

/* Triangle walls: n triangles, vertices verts[3k], verts[3k+1], verts[3k+2] (3n points, not
 * merged); one polygon per triangle with cell data group (group NULL → 0) and normal (3,
 * unit, right-hand rule; zero for a degenerate triangle). Write once per run. */
int sd_vtk_write_triangles(const char *path, size_t n, const sd_vec3 *verts, const int *group);

/* .pvd collection: n DataSet entries (timestep time[i], part part[i] (NULL → 0),
 * file file[i]). File names are written as given (XML-escaped): give them relative to the
 * .pvd's directory so the set can be moved. */
int sd_vtk_write_pvd(const char *path, size_t n, const double *time, const int *part, const char *const *file);

/* A growing .pvd: every add appends an entry and rewrites the whole collection atomically,
 * so the .pvd on disk is always valid and lists every snapshot written so far. If the
 * rewrite fails the entry is kept (the next add writes it) and -1 is returned. */
typedef struct {
    char *path;
    size_t n, cap;
    double *time;
    int *part;
    char **file;
} sd_vtk_series;

/* Initialise (no file written until the first add). -1 with errno ENOMEM/EINVAL on failure. */
int sd_vtk_series_init(sd_vtk_series *s, const char *pvd_path);
int sd_vtk_series_add(sd_vtk_series *s, double time, int part, const char *file);
/* Write the collection now (also with no entries: an empty, valid collection). */
int sd_vtk_series_flush(const sd_vtk_series *s);
void sd_vtk_series_free(sd_vtk_series *s);

#endif
