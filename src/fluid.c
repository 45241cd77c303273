/* Fluid forces (SPEC §5, eqs 47–53). Pure functions; see fluid.h for the conventions. */
#include "fluid.h"

#include <math.h>
#include <string.h>

#include "core/simd.h"
#include "core/vmath.h"

sd_fluid_params sd_fluid_params_default(double slope_rad)
{
    sd_fluid_params p;
    p.U = 1.2;
    p.h = 0.03;
    p.rho = 1000.0;
    p.C_D = 0.49;
    p.flow_dir = v3(1.0, 0.0, 0.0);
    p.bed_normal = v3(0.0, 0.0, 1.0);
    p.z_bed = 0.0;
    p.gravity = v3(9.81 * sin(slope_rad), 0.0, -9.81 * cos(slope_rad));
    return p;
}

double sd_fluid_discharge(double U, double h, sd_fluid_phase phase, double h_D, int n)
{
    double top;
    if (phase == SD_FLUID_FLOW || phase == SD_FLUID_UNIFORM)
        top = h;
    else if (phase == SD_FLUID_CAPTURE)
        top = h_D >= h ? h_D : h;
    else
        return 0.0;
    if (n < 2) n = 2;
    if (n % 2) n++;
    double dz = top / n, sum = 0.0;
    for (int k = 0; k <= n; k++) {
        double z = k == n ? top : k * dz; /* the last node exactly at the surface */
        double u = 0.0;
        if (phase == SD_FLUID_UNIFORM)
            u = U;
        else if (phase == SD_FLUID_FLOW)
            sd_fluid_speed_flow(U, h, z, &u);
        else
            sd_fluid_speed_capture(U, h, h_D, z, &u);
        double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
        sum += w * u;
    }
    return sum * dz / 3.0;
}

double sd_fluid_dam_depth(double h, size_t n, const double *x, const double *z, const unsigned char *mask, double x_dam,
                          double probe)
{
    double hd = h;
    for (size_t i = 0; i < n; i++) {
        if (mask && !mask[i]) continue;
        double xi = x[i], zi = z[i];
        if (!isfinite(xi) || !isfinite(zi)) continue;
        if (xi >= x_dam - probe && xi <= x_dam && zi > hd) hd = zi;
    }
    return hd;
}

SD_SIMD_CLONES
void sd_fluid_sphere_batch(const sd_fluid_params *p, double h_D, int n, const double *restrict px,
                           const double *restrict py, const double *restrict pz, const double *restrict vx,
                           const double *restrict vy, const double *restrict vz, const double *restrict r,
                           const double *restrict capture, double *restrict fx, double *restrict fy,
                           double *restrict fz)
{
    const double U = p->U, h = p->h, nx = p->bed_normal.x, ny = p->bed_normal.y, nz = p->bed_normal.z, zb = p->z_bed,
                 dx = p->flow_dir.x, dy = p->flow_dir.y, dz = p->flow_dir.z, kd = 0.5 * p->C_D * p->rho, mrho = -p->rho,
                 gx = p->gravity.x, gy = p->gravity.y, gz = p->gravity.z;
    /* the capture profile's constants (sd_fluid_speed_capture) */
    const double hd = h_D >= h ? h_D : h;
    double a, b;
    sd_fluid_capture_coeffs(h, hd, &a, &b);
    const double bma = b - a;
    const int flow_ok = h > 0.0, cap_ok = hd > 0.0;
    for (int j = 0; j < n; j++) {
        const double z = px[j] * nx + py[j] * ny + pz[j] * nz - zb; /* sd_fluid_height */
        const double zc = z < 0.0 ? 0.0 : z;
        const int cap = capture[j] != 0.0;
        const double uf = (zc / h / 5.0 + 4.0 / 5.0) * U; /* eq 50 */
        const double uc = (bma * zc / hd + a) * U;        /* eq 53 */
        const double wet = cap ? (cap_ok && zc <= hd) : (flow_ok && zc <= h);
        const double u = cap ? uc : uf;
        const double rx = dx * u - vx[j], ry = dy * u - vy[j], rz = dz * u - vz[j];
        const double speed = sqrt(rx * rx + ry * ry + rz * rz);
        const double rj = r[j];
        const double area = M_PI * rj * rj, volume = 4.0 / 3.0 * M_PI * rj * rj * rj;
        const double s = kd * area * speed, bs = mrho * volume;
        const double tx = rx * s + gx * bs, ty = ry * s + gy * bs, tz = rz * s + gz * bs;
        fx[j] = wet != 0.0 ? tx : 0.0;
        fy[j] = wet != 0.0 ? ty : 0.0;
        fz[j] = wet != 0.0 ? tz : 0.0;
    }
}
