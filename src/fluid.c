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

int sd_fluid_speed_flow(double U, double h, double z, double *u)
{
    if (z < 0.0) z = 0.0;
    if (!(h > 0.0) || !(z <= h)) { /* above the surface (or NaN / no depth): no fluid */
        *u = 0.0;
        return 0;
    }
    /* eq 50: 0.8 U at the bed, U at the surface */
    *u = (z / h / 5.0 + 4.0 / 5.0) * U;
    return 1;
}

void sd_fluid_capture_coeffs(double h, double h_D, double *alpha, double *beta)
{
    if (!(h_D >= h)) h_D = h; /* never below h */
    double r = 1.8 * h / h_D;
    double a = r - 1.0, b = 1.0; /* eq 52 */
    if (a <= 0.1) {               /* eq 53 */
        a = 0.1;
        b = r - a;
    }
    *alpha = a;
    *beta = b;
}

int sd_fluid_speed_capture(double U, double h, double h_D, double z, double *u)
{
    if (!(h_D >= h)) h_D = h;
    if (z < 0.0) z = 0.0;
    if (!(h_D > 0.0) || !(z <= h_D)) {
        *u = 0.0;
        return 0;
    }
    double a, b;
    sd_fluid_capture_coeffs(h, h_D, &a, &b);
    *u = ((b - a) * z / h_D + a) * U; /* eq 51 */
    return 1;
}

int sd_fluid_speed(const sd_fluid_params *p, sd_fluid_phase phase, double h_D, double z, double *u)
{
    switch (phase) {
    case SD_FLUID_FLOW: return sd_fluid_speed_flow(p->U, p->h, z, u);
    case SD_FLUID_CAPTURE: return sd_fluid_speed_capture(p->U, p->h, h_D, z, u);
    case SD_FLUID_NONE:
    default: *u = 0.0; return 0;
    }
}

double sd_fluid_discharge(double U, double h, sd_fluid_phase phase, double h_D, int n)
{
    double top;
    if (phase == SD_FLUID_FLOW) top = h;
    else if (phase == SD_FLUID_CAPTURE) top = h_D >= h ? h_D : h;
    else return 0.0;
    if (n < 2) n = 2;
    if (n % 2) n++;
    double dz = top / n, sum = 0.0;
    for (int k = 0; k <= n; k++) {
        double z = k == n ? top : k * dz; /* the last node exactly at the surface */
        double u = 0.0;
        if (phase == SD_FLUID_FLOW) sd_fluid_speed_flow(U, h, z, &u);
        else sd_fluid_speed_capture(U, h, h_D, z, &u);
        double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
        sum += w * u;
    }
    return sum * dz / 3.0;
}

double sd_fluid_area_sphere(double r) { return M_PI * r * r; }

double sd_fluid_area_cylinder(double r, double L, sd_vec3 axis, sd_vec3 u)
{
    double c = fabs(v3_dot(axis, u));
    if (c > 1.0) c = 1.0;
    return 2.0 * r * L * sqrt(1.0 - c * c) + M_PI * r * r * c;
}

double sd_fluid_volume_sphere(double r) { return 4.0 / 3.0 * M_PI * r * r * r; }

double sd_fluid_volume_cylinder(double r, double L) { return M_PI * r * r * L; }

double sd_fluid_height(const sd_fluid_params *p, sd_vec3 pos)
{
    return v3_dot(pos, p->bed_normal) - p->z_bed;
}

int sd_fluid_force(const sd_fluid_params *p, sd_fluid_phase phase, double h_D,
                   const sd_fluid_element *e, sd_fluid_force_result *out)
{
    sd_fluid_force_result r;
    memset(&r, 0, sizeof r);
    double z = sd_fluid_height(p, e->pos);
    r.z = z < 0.0 ? 0.0 : z;
    int shape_ok = e->shape == SD_SHAPE_SPHERE || e->shape == SD_SHAPE_CYLINDER;
    double u;
    if (!shape_ok || !sd_fluid_speed(p, phase, h_D, z, &u)) {
        if (out) *out = r;
        return 0;
    }
    r.u_local = u;
    sd_vec3 rel = v3_sub(v3_scale(p->flow_dir, u), e->vel); /* U_i − v */
    double speed = v3_norm(rel);
    if (e->shape == SD_SHAPE_SPHERE) {
        r.area = sd_fluid_area_sphere(e->radius);
        r.volume = sd_fluid_volume_sphere(e->radius);
    } else {
        sd_vec3 dir = speed > 0.0 ? v3_scale(rel, 1.0 / speed) : p->flow_dir;
        r.area = sd_fluid_area_cylinder(e->radius, e->length, e->axis, dir);
        r.volume = sd_fluid_volume_cylinder(e->radius, e->length);
    }
    r.drag = v3_scale(rel, 0.5 * p->C_D * p->rho * r.area * speed);
    r.buoyancy = v3_scale(p->gravity, -p->rho * r.volume);
    r.total = v3_add(r.drag, r.buoyancy);
    if (out) *out = r;
    return 1;
}

sd_vec3 sd_fluid_force_total(const sd_fluid_params *p, sd_fluid_phase phase, double h_D,
                             const sd_fluid_element *e)
{
    sd_fluid_force_result r;
    sd_fluid_force(p, phase, h_D, e, &r);
    return r.total;
}

double sd_fluid_dam_depth(double h, size_t n, const double *x, const double *z,
                          const unsigned char *mask, double x_dam, double probe)
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
