/* Fluid forces on elements (SPEC §5, eqs 47–53): velocity profiles of the flow and capture
 * phases, drag on the area projected normal to the relative velocity, buoyancy.
 * Pure functions: no globals, no I/O, no dependency on the world internals.
 *
 * Frame: the flume frame of SPEC §8 (x downstream along the bed, z normal to the bed); the
 * parameters carry the bed normal, the downstream direction and the gravity vector, so the
 * functions work in any frame. Height of an element: z = (pos · bed_normal) − z_bed, measured
 * normal to the bed, at the element centre. A centre below the bed (z < 0) is treated as z = 0
 * (it gets the bed velocity 0.8 U in the flow phase, α U in the capture phase). */
#ifndef SD_FLUID_H
#define SD_FLUID_H

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "core/vmath.h"
#include "sabodem.h" /* sd_vec3, SD_SHAPE_* */

typedef struct {
    double U;           /* reference (surface) speed, m/s, along flow_dir */
    double h;           /* flow depth, m (> 0) */
    double rho;         /* fluid density, kg/m^3 */
    double C_D;         /* drag coefficient */
    sd_vec3 flow_dir;   /* unit downstream direction, parallel to the bed; flume frame (1,0,0) */
    sd_vec3 bed_normal; /* unit bed normal; flume frame (0,0,1) */
    double z_bed;       /* bed offset along bed_normal, m (0 in the flume frame) */
    sd_vec3 gravity;    /* the gravity the buoyancy opposes, m/s^2: f_B = −ρ V gravity. The world's
                           gravity (vertical, the paper; flume frame 9.81 (sinθ, 0, −cosθ)), or
                           its part normal to the bed (water.buoyancy: bed_normal) */
} sd_fluid_params;

/* Phase of the velocity profile applied to an element. */
typedef enum {
    SD_FLUID_NONE = 0,   /* no fluid force (packing) */
    SD_FLUID_FLOW = 1,   /* eq 50, surface at h */
    SD_FLUID_CAPTURE = 2, /* eqs 51–53, surface at h_D (>= h) */
    SD_FLUID_UNIFORM = 3  /* U at every depth, surface at h (U = 0: still water) */
} sd_fluid_phase;

/* An element as the fluid sees it. */
typedef struct {
    int shape;     /* SD_SHAPE_SPHERE or SD_SHAPE_CYLINDER */
    sd_vec3 pos;   /* centre, m */
    sd_vec3 vel;   /* centre velocity, m/s */
    sd_vec3 axis;  /* unit axis (cylinders only) */
    double radius; /* m */
    double length; /* full length L = 2l, m (cylinders only) */
} sd_fluid_element;

/* Result of one force evaluation (all zero when the element is dry). */
typedef struct {
    sd_vec3 drag;     /* ½ C_D ρ A |U_i − v| (U_i − v), N */
    sd_vec3 buoyancy; /* −ρ V g, N */
    sd_vec3 total;    /* drag + buoyancy, N */
    double u_local;   /* U_i (speed of the profile at the centre), m/s */
    double area;      /* projected area A used for the drag, m^2 */
    double volume;    /* element volume V, m^3 */
    double z;         /* centre height above the bed (clamped at 0), m */
} sd_fluid_force_result;

/* The paper's water (SPEC §8): U = 1.2 m/s, h = 0.03 m, ρ = 1000, C_D = 0.49, flume frame,
 * gravity 9.81 (sinθ, 0, −cosθ) for the bed slope theta (radians). */
sd_fluid_params sd_fluid_params_default(double slope_rad);

/* Flow phase, eq 50: U_i = (z/h/5 + 4/5) U for 0 <= z <= h (z < 0 read as 0).
 * Returns 1 and sets *u when the point is under the surface, 0 (and *u = 0) above it. */
static inline int sd_fluid_speed_flow(double U, double h, double z, double *u)
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

/* Capture phase, eqs 51–53: α = 1.8 h/h_D − 1, β = 1; if α <= 0.1 then α = 0.1,
 * β = 1.8 h/h_D − α. h_D below h is raised to h. */
static inline void sd_fluid_capture_coeffs(double h, double h_D, double *alpha, double *beta)
{
    if (!(h_D >= h)) h_D = h; /* never below h */
    double r = 1.8 * h / h_D;
    double a = r - 1.0, b = 1.0; /* eq 51 */
    if (a <= 0.1) {              /* eq 52 */
        a = 0.1;
        b = r - a;
    }
    *alpha = a;
    *beta = b;
}

/* Capture phase: U_i = ((β − α) z/h_D + α) U for 0 <= z <= h_D (z < 0 read as 0).
 * Returns 1 and sets *u when under the surface h_D (raised to h), 0 (and *u = 0) above it. */
static inline int sd_fluid_speed_capture(double U, double h, double h_D, double z, double *u)
{
    if (!(h_D >= h)) h_D = h;
    if (z < 0.0) z = 0.0;
    if (!(h_D > 0.0) || !(z <= h_D)) {
        *u = 0.0;
        return 0;
    }
    double a, b;
    sd_fluid_capture_coeffs(h, h_D, &a, &b);
    *u = ((b - a) * z / h_D + a) * U; /* eq 53 */
    return 1;
}

/* Speed of the profile of the given phase at height z; returns 1 wet, 0 dry or phase NONE. */
static inline int sd_fluid_speed(const sd_fluid_params *p, sd_fluid_phase phase, double h_D, double z, double *u)
{
    switch (phase) {
    case SD_FLUID_FLOW:
        return sd_fluid_speed_flow(p->U, p->h, z, u);
    case SD_FLUID_CAPTURE:
        return sd_fluid_speed_capture(p->U, p->h, h_D, z, u);
    case SD_FLUID_UNIFORM:
        if (!(p->h > 0.0) || !(z <= p->h)) { /* above the surface */
            *u = 0.0;
            return 0;
        }
        *u = p->U;
        return 1;
    case SD_FLUID_NONE:
    default:
        *u = 0.0;
        return 0;
    }
}

/* Discharge per unit width ∫ U_i dz over the wet depth (h, or h_D raised to h), by composite
 * Simpson's rule on n intervals (n raised to an even number >= 2) of the profile functions
 * above; exact to rounding since the profiles are linear. Should equal 0.9 U h in both phases. */
double sd_fluid_discharge(double U, double h, sd_fluid_phase phase, double h_D, int n);

/* Projected areas normal to the unit direction u. Sphere: π r². Cylinder (radius r, full length
 * L, unit axis a): 2 r L sqrt(1 − (a·u)²) + π r² |a·u|. */
static inline double sd_fluid_area_sphere(double r) { return M_PI * r * r; }
static inline double sd_fluid_area_cylinder(double r, double L, sd_vec3 axis, sd_vec3 u)
{
    double c = fabs(v3_dot(axis, u));
    if (c > 1.0) c = 1.0;
    return 2.0 * r * L * sqrt(1.0 - c * c) + M_PI * r * r * c;
}
/* Volumes: sphere 4/3 π r³, cylinder π r² L. */
static inline double sd_fluid_volume_sphere(double r) { return 4.0 / 3.0 * M_PI * r * r * r; }
static inline double sd_fluid_volume_cylinder(double r, double L) { return M_PI * r * r * L; }

/* Height of a point above the bed, normal to it, not clamped. */
static inline double sd_fluid_height(const sd_fluid_params *p, sd_vec3 pos)
{
    return v3_dot(pos, p->bed_normal) - p->z_bed;
}

/* Fluid force on one element (eq 47): f = ½ C_D ρ A |U_i − v| (U_i − v) + f_B, with
 * U_i = u_i flow_dir, f_B = −ρ V gravity; no torque. The whole volume counts for buoyancy
 * once the centre is wet. Returns 1 when the centre is under the surface of the phase (force
 * set), 0 when dry, phase NONE or a bad shape (out zeroed). With zero relative velocity the
 * drag is zero (and the area is evaluated for the flow direction). out may be NULL. */
static inline int sd_fluid_force(const sd_fluid_params *p, sd_fluid_phase phase, double h_D, const sd_fluid_element *e,
                                 sd_fluid_force_result *out)
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
/* Same, returning the total force only (zero when dry). */
static inline sd_vec3 sd_fluid_force_total(const sd_fluid_params *p, sd_fluid_phase phase, double h_D,
                                           const sd_fluid_element *e)
{
    sd_fluid_force_result r;
    sd_fluid_force(p, phase, h_D, e, &r);
    return r.total;
}

/* sd_fluid_force_total for n spheres at once, bit for bit (the same operations, no branch on
 * the lanes, vectorized): centres (px, py, pz), velocities (vx, vy, vz), radii r; capture[j]
 * nonzero for the capture profile, else the flow one; forces out in (fx, fy, fz). */
void sd_fluid_sphere_batch(const sd_fluid_params *p, double h_D, int n, const double *restrict px,
                           const double *restrict py, const double *restrict pz, const double *restrict vx,
                           const double *restrict vy, const double *restrict vz, const double *restrict r,
                           const double *restrict capture, double *restrict fx, double *restrict fy,
                           double *restrict fz);

/* Capture-phase depth h_D (SPEC §5): max(h, max z_i over the n elements with
 * x_dam − probe <= x_i <= x_dam). x and z are centre coordinates (z = height above the bed);
 * mask (may be NULL) skips element i when mask[i] == 0; non-finite entries are skipped. */
double sd_fluid_dam_depth(double h, size_t n, const double *x, const double *z, const unsigned char *mask, double x_dam,
                          double probe);

#endif
