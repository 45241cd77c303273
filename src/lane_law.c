/* The contact law of contact_law.h in lanes over a batch: the sphere pairs (two loops), the
 * one-point sphere-log contacts and the sphere-wall face contacts, each built for the CPU
 * levels by SD_SIMD_CLONES. The arithmetic is sd_contact_law's, operation for operation. */
#include <math.h>

#include "contact_kernels.h"
#include "core/simd.h"

/* sd_contact_law for one lane, operation for operation, with both sides of every branch
 * computed and one kept (so that the loops that call it vectorize): unit normal n, overlap ov,
 * relative velocity v at the contact, sqrt of the effective mass sqm, the stored spring s (in,
 * then out), the force f on A. Returns nonzero when the spring tilted past the small-angle
 * rule and the lane must be redone by the scalar law (rare: a normal turning fast). */
static inline __attribute__((always_inline)) double law_lane(const sd_lane_law *L, double nx, double ny, double nz,
                                                             double ov, double vx, double vy, double vz, double sqm,
                                                             double *sx, double *sy, double *sz, double *fx, double *fy,
                                                             double *fz)
{
    const double vn = vx * nx + vy * ny + vz * nz;
    double pn = L->k_n * ov - L->c_n * sqm * vn;
    pn = pn < 0.0 ? 0.0 : pn;
    const double tx = vx + -vn * nx, ty = vy + -vn * ny, tz = vz + -vn * nz;
    const double s0x = *sx, s0y = *sy, s0z = *sz;
    const double s2 = s0x * s0x + s0y * s0y + s0z * s0z;
    const double sn = s0x * nx + s0y * ny + s0z * nz;
    const double px = s0x + -sn * nx, py = s0y + -sn * ny, pz = s0z + -sn * nz;
    const double r2 = s2 - sn * sn;
    const double x = sn * sn / r2;
    const double poly = 1.0 + 0.5 * x - 0.375 * x * x;
    const int has = s2 > 0.0;
    const double redo = sn * sn < 1e-4 * s2 ? 0.0 : (has ? 1.0 : 0.0);
    double ux = has ? px * poly : s0x, uy = has ? py * poly : s0y, uz = has ? pz * poly : s0z;
    ux = ux + L->mks_dt * tx;
    uy = uy + L->mks_dt * ty;
    uz = uz + L->mks_dt * tz;
    const double limit = L->coh + pn * L->tan_phi, lim2 = limit * limit;
    const double smag2 = ux * ux + uy * uy + uz * uz;
    const int slide = smag2 > lim2;
    const double mcs = -L->c_s * sqm;
    double gx = ux + mcs * tx, gy = uy + mcs * ty, gz = uz + mcs * tz;
    const double fmag2 = gx * gx + gy * gy + gz * gz;
    const int over = fmag2 > lim2;
    /* one square root and one division for whichever of the two limits applies */
    const double cut = limit / sqrt(slide ? smag2 : fmag2);
    gx = over ? gx * cut : gx;
    gy = over ? gy * cut : gy;
    gz = over ? gz * cut : gz;
    ux = slide ? ux * cut : ux;
    uy = slide ? uy * cut : uy;
    uz = slide ? uz * cut : uz;
    gx = slide ? ux : gx;
    gy = slide ? uy : gy;
    gz = slide ? uz : gz;
    *sx = ux;
    *sy = uy;
    *sz = uz;
    *fx = gx + pn * nx;
    *fy = gy + pn * ny;
    *fz = gz + pn * nz;
    return redo;
}

/* Step 4 of sd_bb_chunk, the law in lanes, in two loops, each a shorter chain of dependent
 * operations (the square root and division of the normal, then the law's): more lanes in
 * flight at once. The first (sd_lane_law_ss_normal) leaves the unit normal in dx, dy, dz, the overlap
 * in ra and the velocity at the contact point in vx, vy, vz; the second (sd_lane_law_ss_spring, from
 * lane j0 on) runs law_lane. Where the CPU has AVX2 (not AVX-512), sd_avx2_ss_law_spring takes the
 * second loop's groups of four first. */
SD_SIMD_CLONES
void sd_lane_law_ss_normal(ss_batch *restrict q, int m)
{
    for (int j = 0; j < m; j++) {
        const double dx = q->dx[j], dy = q->dy[j], dz = q->dz[j];
        const double d2 = dx * dx + dy * dy + dz * dz;
        const double dist = sqrt(d2);
        const double inv = 1.0 / dist;
        const int far = dist > 1e-300;
        const double nx = far ? dx * inv : 0.0, ny = far ? dy * inv : 0.0, nz = far ? dz * inv : 1.0;
        const double ov = (q->ra[j] + q->rb[j]) - dist;
        const double la = q->ra[j] - 0.5 * ov, lb = q->rb[j] - 0.5 * ov;
        const double wx = q->wax[j] * la + lb * q->wbx[j], wy = q->way[j] * la + lb * q->wby[j],
                     wz = q->waz[j] * la + lb * q->wbz[j];
        q->vx[j] = q->vx[j] - (wy * nz - wz * ny);
        q->vy[j] = q->vy[j] - (wz * nx - wx * nz);
        q->vz[j] = q->vz[j] - (wx * ny - wy * nx);
        q->dx[j] = nx;
        q->dy[j] = ny;
        q->dz[j] = nz;
        q->ra[j] = ov;
        q->la[j] = la;
        q->lb[j] = lb;
    }
}

/* The loops' lane j takes its law from table[lw[j]] when multi (several materials), else table[0]
 * for every lane: multi is a constant where these inline, so the one-law loops read no table. */
static inline __attribute__((always_inline)) void ss_spring(const sd_lane_law *table, const int32_t *lw,
                                                           ss_batch *restrict q, int j0, int m, const int multi)
{
    const sd_lane_law L = *table;
    for (int j = j0; j < m; j++) {
        const double nx = q->dx[j], ny = q->dy[j], nz = q->dz[j];
        double sx = q->sx[j], sy = q->sy[j], sz = q->sz[j], fx, fy, fz;
        q->redo[j] = law_lane(multi ? &table[lw[j]] : &L, nx, ny, nz, q->ra[j], q->vx[j], q->vy[j], q->vz[j], q->sqm[j],
                              &sx, &sy, &sz, &fx, &fy, &fz);
        q->sx[j] = sx;
        q->sy[j] = sy;
        q->sz[j] = sz;
        q->fx[j] = fx;
        q->fy[j] = fy;
        q->fz[j] = fz;
        q->nfx[j] = ny * fz - nz * fy;
        q->nfy[j] = nz * fx - nx * fz;
        q->nfz[j] = nx * fy - ny * fx;
    }
}

SD_SIMD_CLONES
void sd_lane_law_ss_spring(const sd_lane_law *lanes, ss_batch *restrict q, int j0, int m)
{
    ss_spring(lanes, NULL, q, j0, m, 0);
}

SD_SIMD_CLONES
void sd_lane_law_ss_spring_mat(const sd_lane_law *table, const int32_t *lw, ss_batch *restrict q, int m)
{
    ss_spring(table, lw, q, 0, m, 1);
}

static inline __attribute__((always_inline)) void sc_law(const sd_lane_law *table, const int32_t *lw,
                                                        struct sc_lanes *restrict q, int m, const int multi)
{
    const sd_lane_law L = *table;
    for (int j = 0; j < m; j++) {
        const double rax = q->rax[j], ray = q->ray[j], raz = q->raz[j], rbx = q->rbx[j], rby = q->rby[j],
                     rbz = q->rbz[j];
        /* v_a + w_a x r_a - (v_b + w_b x r_b) */
        const double vax = q->vax[j] + (q->way[j] * raz - q->waz[j] * ray),
                     vay = q->vay[j] + (q->waz[j] * rax - q->wax[j] * raz),
                     vaz = q->vaz[j] + (q->wax[j] * ray - q->way[j] * rax);
        const double vbx = q->vbx[j] + (q->wby[j] * rbz - q->wbz[j] * rby),
                     vby = q->vby[j] + (q->wbz[j] * rbx - q->wbx[j] * rbz),
                     vbz = q->vbz[j] + (q->wbx[j] * rby - q->wby[j] * rbx);
        double sx = q->sx[j], sy = q->sy[j], sz = q->sz[j], fx, fy, fz;
        q->redo[j] = law_lane(multi ? &table[lw[j]] : &L, q->nx[j], q->ny[j], q->nz[j], q->ov[j], vax - vbx, vay - vby, vaz - vbz, q->sqm[j],
                              &sx, &sy, &sz, &fx, &fy, &fz);
        q->sx[j] = sx;
        q->sy[j] = sy;
        q->sz[j] = sz;
        /* sd_manifold_apply's sums, from zero */
        q->fx[j] = 0.0 + fx;
        q->fy[j] = 0.0 + fy;
        q->fz[j] = 0.0 + fz;
        q->tax[j] = 0.0 + (ray * fz - raz * fy);
        q->tay[j] = 0.0 + (raz * fx - rax * fz);
        q->taz[j] = 0.0 + (rax * fy - ray * fx);
        q->tbx[j] = 0.0 - (rby * fz - rbz * fy);
        q->tby[j] = 0.0 - (rbz * fx - rbx * fz);
        q->tbz[j] = 0.0 - (rbx * fy - rby * fx);
    }
}

SD_SIMD_CLONES
void sd_lane_law_sc(const sd_lane_law *lanes, struct sc_lanes *restrict q, int m)
{
    sc_law(lanes, NULL, q, m, 0);
}

SD_SIMD_CLONES
void sd_lane_law_sc_mat(const sd_lane_law *table, const int32_t *lw, struct sc_lanes *restrict q, int m)
{
    sc_law(table, lw, q, m, 1);
}

static inline __attribute__((always_inline)) void bt_law(const sd_lane_law *table, const int32_t *lw,
                                                        bt_batch *restrict q, int m, const int multi)
{
    const sd_lane_law L = *table;
    for (int j = 0; j < m; j++) {
        const double nx = q->nx[j], ny = q->ny[j], nz = q->nz[j], rx = q->rx[j], ry = q->ry[j], rz = q->rz[j];
        /* v + w x r (the wall is still: v - 0 is v) */
        const double vx = q->vx[j] + (q->wy[j] * rz - q->wz[j] * ry), vy = q->vy[j] + (q->wz[j] * rx - q->wx[j] * rz),
                     vz = q->vz[j] + (q->wx[j] * ry - q->wy[j] * rx);
        double sx = q->sx[j], sy = q->sy[j], sz = q->sz[j], fx, fy, fz;
        q->redo[j] = law_lane(multi ? &table[lw[j]] : &L, nx, ny, nz, q->ov[j], vx, vy, vz, q->sqm[j], &sx, &sy, &sz, &fx, &fy, &fz);
        q->sx[j] = sx;
        q->sy[j] = sy;
        q->sz[j] = sz;
        /* sd_manifold_apply's sums, from zero */
        q->fx[j] = 0.0 + fx;
        q->fy[j] = 0.0 + fy;
        q->fz[j] = 0.0 + fz;
        q->tx[j] = 0.0 + (ry * fz - rz * fy);
        q->ty[j] = 0.0 + (rz * fx - rx * fz);
        q->tz[j] = 0.0 + (rx * fy - ry * fx);
    }
}

SD_SIMD_CLONES
void sd_lane_law_bt(const sd_lane_law *lanes, bt_batch *restrict q, int m)
{
    bt_law(lanes, NULL, q, m, 0);
}

SD_SIMD_CLONES
void sd_lane_law_bt_mat(const sd_lane_law *table, const int32_t *lw, bt_batch *restrict q, int m)
{
    bt_law(table, lw, q, m, 1);
}
