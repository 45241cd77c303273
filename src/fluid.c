/* Fluid forces (SPEC §5, eqs 47–53). Pure functions; see fluid.h for the conventions. */
#include "fluid.h"

#include <math.h>
#include <string.h>

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
    if (phase == SD_FLUID_FLOW)
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
        if (phase == SD_FLUID_FLOW)
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
