/* Fuzz target: bytes → an STL file → sd_stl_read (the size and count checks, the binary reader
 * or the ASCII grammar) → what a read mesh promises checked (at least one triangle, every
 * corner finite, none of zero area, each where in order) → for small meshes of moderate extent,
 * the triangles as walls of a world with a sphere dropped on the first, two steps (the welding
 * and the triangle grid on odd geometry). A broken promise aborts. */
#include <math.h>

#include "core/vmath.h"
#include "fuzz_io.h"
#include "io_stl.h"

#define SMALL_TRIANGLES 64
#define SMALL_EXTENT 10.0 /* m */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("input.stl", data, size);
    sd_stl_mesh m;
    char msg[1024];
    if (sd_stl_read(path, SD_STL_MAX_TRIANGLES, &m, msg, sizeof msg)) {
        if (m.n || m.tri || m.where || !msg[0]) abort(); /* a refusal leaves nothing, says why */
        return 0;
    }
    if (m.n < 1 || m.n > SD_STL_MAX_TRIANGLES || m.dropped < 0) abort();
    double extent = 0.0;
    for (int t = 0; t < m.n; t++) {
        for (int k = 0; k < 3; k++) {
            const sd_vec3 v = m.tri[t][k];
            if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z)) abort();
            extent = fmax(extent, fmax(fmax(fabs(v.x), fabs(v.y)), fabs(v.z)));
        }
        const sd_vec3 cr = v3_cross(v3_sub(m.tri[t][1], m.tri[t][0]), v3_sub(m.tri[t][2], m.tri[t][0]));
        if (!(v3_norm(cr) > 0.0)) abort();
        /* binary: indices, increasing from 0; ASCII: lines from 1, never decreasing (a file on
         * one line has them all on line 1) */
        if (t > 0 && (m.binary ? m.where[t] <= m.where[t - 1] : m.where[t] < m.where[t - 1])) abort();
        if (m.where[t] < (m.binary ? 0 : 1)) abort();
    }
    if (m.n <= SMALL_TRIANGLES && extent <= SMALL_EXTENT) {
        sd_world_def def = sd_world_def_default();
        def.threads = 1;
        sd_world *w;
        if (sd_world_create(&def, &w) == SD_OK) {
            int ok = 1;
            for (int t = 0; t < m.n && ok; t++)
                ok = sd_world_add_triangle(w, m.tri[t][0], m.tri[t][1], m.tri[t][2], 0) >= 0;
            /* (the world refuses only what the reader drops: exact zero area) */
            if (!ok) abort();
            /* a sphere on the first triangle, half its radius deep, of a size that keeps the
             * grids to some thousands of cells (they grow with the extent over the sphere) */
            sd_sphere_def sp = sd_sphere_def_default();
            sp.radius = fmax(0.01, extent / 20.0);
            const sd_vec3 c = v3_scale(v3_add(v3_add(m.tri[0][0], m.tri[0][1]), m.tri[0][2]), 1.0 / 3.0);
            const sd_vec3 n = v3_cross(v3_sub(m.tri[0][1], m.tri[0][0]), v3_sub(m.tri[0][2], m.tri[0][0]));
            sp.pos = v3_madd(c, n, 0.5 * sp.radius / v3_norm(n));
            if (sd_world_add_sphere(w, &sp) >= 0 && sd_world_check(w) == SD_OK)
                for (int k = 0; k < 2 && sd_world_step(w) == SD_OK; k++) {
                }
            sd_world_destroy(w);
        }
    }
    sd_stl_free(&m);
    return 0;
}
