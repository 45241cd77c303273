/* The water's forces inside the step (model.md eqs. (47)-(53), fluid.h's pure functions) as the
 * external-force hook of the world: spheres in SIMD lanes where the CPU has them, else in
 * batches, logs one by one; every form gives the same bits. */
#include "water.h"

#include "core/simd.h"
#include "core/vmath.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#include <immintrin.h>
#define SD_FLUID512 1
#endif

/* Spheres gathered for sd_fluid_sphere_batch. */
enum { FLUID_BATCH = 64 };
typedef struct {
    double px[FLUID_BATCH], py[FLUID_BATCH], pz[FLUID_BATCH], vx[FLUID_BATCH], vy[FLUID_BATCH], vz[FLUID_BATCH];
    double r[FLUID_BATCH], cap[FLUID_BATCH], fx[FLUID_BATCH], fy[FLUID_BATCH], fz[FLUID_BATCH];
    int idx[FLUID_BATCH], m; /* idx: the body's place in the block's forces (out[]) */
} fluid_batch;

static void fluid_flush(fluid_batch *q, const sd_fluid_params *fp, double h_d, sd_vec3 *out)
{
    sd_fluid_sphere_batch(fp, h_d, q->m, q->px, q->py, q->pz, q->vx, q->vy, q->vz, q->r, q->cap, q->fx, q->fy, q->fz);
    for (int j = 0; j < q->m; j++)
        out[q->idx[j]] = v3(q->fx[j], q->fy[j], q->fz[j]);
    q->m = 0;
}

#ifdef SD_FLUID512
/* The spheres among mov[k0 .. k1) in AVX-512, 8 bodies at a time, straight from the store
 * (gathers by index, the forces scattered into out[k - k0]): sd_fluid_sphere_batch's
 * operations in its order, so the same bits, without the copy of each body into the batch and
 * out. The logs among them are left to the caller. */
__attribute__((target("avx512f,avx512vl"))) static void fluid_spheres512(const sd_water *fc,
                                                                         const sd_body_view *b, const int32_t *mov,
                                                                         int k0, int k1, int32_t *logs, int *nlogs,
                                                                         sd_vec3 *out)
{
    const sd_fluid_params *p = &fc->fp;
    const double *pos = &b->pos[0].x, *vel = &b->vel[0].x, *rad = b->radius;
    double *ext = &out[0].x;
    const uint8_t *shape = b->shape;
    const double h = p->h, hd = fc->h_d >= h ? fc->h_d : h;
    double al, be;
    sd_fluid_capture_coeffs(h, hd, &al, &be);
    const __m512d U = _mm512_set1_pd(p->U), H = _mm512_set1_pd(h), HD = _mm512_set1_pd(hd),
                  nx = _mm512_set1_pd(p->bed_normal.x), ny = _mm512_set1_pd(p->bed_normal.y),
                  nz = _mm512_set1_pd(p->bed_normal.z), zb = _mm512_set1_pd(p->z_bed),
                  dx = _mm512_set1_pd(p->flow_dir.x), dy = _mm512_set1_pd(p->flow_dir.y),
                  dz = _mm512_set1_pd(p->flow_dir.z), kd = _mm512_set1_pd(0.5 * p->C_D * p->rho),
                  mrho = _mm512_set1_pd(-p->rho), gx = _mm512_set1_pd(p->gravity.x), gy = _mm512_set1_pd(p->gravity.y),
                  gz = _mm512_set1_pd(p->gravity.z), bma = _mm512_set1_pd(be - al), A = _mm512_set1_pd(al),
                  five = _mm512_set1_pd(5.0), c45 = _mm512_set1_pd(4.0 / 5.0), pi = _mm512_set1_pd(M_PI),
                  c43pi = _mm512_set1_pd(4.0 / 3.0 * M_PI), XD = _mm512_set1_pd(fc->xd), X0 = _mm512_set1_pd(fc->x_from),
                  zero = _mm512_setzero_pd();
    const __mmask8 flow_ok = h > 0.0 ? 0xFF : 0, cap_ok = hd > 0.0 ? 0xFF : 0, capture = fc->capture ? 0xFF : 0;
    for (int k = k0; k < k1; k += 8) {
        const int nl = k1 - k < 8 ? k1 - k : 8;
        __mmask8 sph = 0;
        for (int l = 0; l < nl; l++) {
            const int s = shape[mov[k + l]] == SD_SHAPE_SPHERE;
            sph |= (__mmask8)(s << l);
            if (logs && !s) logs[(*nlogs)++] = k + l;
        }
        if (!sph) continue;
        const __m256i i = _mm256_maskz_loadu_epi32(sph, mov + k);
        const __m256i i3 = _mm256_add_epi32(i, _mm256_add_epi32(i, i));
        const __m512d px = _mm512_mask_i32gather_pd(zero, sph, i3, pos, 8),
                      py = _mm512_mask_i32gather_pd(zero, sph, i3, pos + 1, 8),
                      pz = _mm512_mask_i32gather_pd(zero, sph, i3, pos + 2, 8),
                      vx = _mm512_mask_i32gather_pd(zero, sph, i3, vel, 8),
                      vy = _mm512_mask_i32gather_pd(zero, sph, i3, vel + 1, 8),
                      vz = _mm512_mask_i32gather_pd(zero, sph, i3, vel + 2, 8),
                      r = _mm512_mask_i32gather_pd(zero, sph, i, rad, 8);
        /* z = p.n - z_bed (sd_fluid_height), clamped at the bed as z < 0 ? 0 : z */
        const __m512d z = _mm512_sub_pd(
            _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(px, nx), _mm512_mul_pd(py, ny)), _mm512_mul_pd(pz, nz)), zb);
        const __m512d zc = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(z, zero, _CMP_LT_OQ), z, zero);
        /* the capture profile in the pond's region (capture && x_from <= p.x < xd) */
        const __mmask8 cap = (__mmask8)(capture & _mm512_cmp_pd_mask(px, XD, _CMP_LT_OQ) &
                                        _mm512_cmp_pd_mask(px, X0, _CMP_GE_OQ));
        const __mmask8 wet = (__mmask8)((cap & cap_ok & _mm512_cmp_pd_mask(zc, HD, _CMP_LE_OQ)) |
                                        (~cap & flow_ok & _mm512_cmp_pd_mask(zc, H, _CMP_LE_OQ)));
        /* the profile of each lane; a group all of one profile (nearly every group) skips the
         * other's divisions, the costliest part of this loop */
        __m512d u;
        if ((cap & sph) == sph)
            u = _mm512_mul_pd(_mm512_add_pd(_mm512_div_pd(_mm512_mul_pd(bma, zc), HD), A), U); /* eq 53 */
        else if (!(cap & sph))
            u = _mm512_mul_pd(_mm512_add_pd(_mm512_div_pd(_mm512_div_pd(zc, H), five), c45), U); /* eq 50 */
        else
            u = _mm512_mask_blend_pd(cap,
                                     _mm512_mul_pd(_mm512_add_pd(_mm512_div_pd(_mm512_div_pd(zc, H), five), c45), U),
                                     _mm512_mul_pd(_mm512_add_pd(_mm512_div_pd(_mm512_mul_pd(bma, zc), HD), A), U));
        const __m512d rx = _mm512_sub_pd(_mm512_mul_pd(dx, u), vx), ry = _mm512_sub_pd(_mm512_mul_pd(dy, u), vy),
                      rz = _mm512_sub_pd(_mm512_mul_pd(dz, u), vz);
        const __m512d speed = _mm512_sqrt_pd(
            _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(rx, rx), _mm512_mul_pd(ry, ry)), _mm512_mul_pd(rz, rz)));
        const __m512d area = _mm512_mul_pd(_mm512_mul_pd(pi, r), r),
                      volume = _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(c43pi, r), r), r);
        const __m512d sk = _mm512_mul_pd(_mm512_mul_pd(kd, area), speed), bs = _mm512_mul_pd(mrho, volume);
        const __m512d tx = _mm512_add_pd(_mm512_mul_pd(rx, sk), _mm512_mul_pd(gx, bs)),
                      ty = _mm512_add_pd(_mm512_mul_pd(ry, sk), _mm512_mul_pd(gy, bs)),
                      tz = _mm512_add_pd(_mm512_mul_pd(rz, sk), _mm512_mul_pd(gz, bs));
        /* dry spheres get zero; every sphere lane is written, at its place in the block */
        const __m256i o = _mm256_add_epi32(_mm256_set1_epi32(k - k0), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        const __m256i o3 = _mm256_add_epi32(o, _mm256_add_epi32(o, o));
        _mm512_mask_i32scatter_pd(ext, sph, o3, _mm512_maskz_mov_pd(wet, tx), 8);
        _mm512_mask_i32scatter_pd(ext + 1, sph, o3, _mm512_maskz_mov_pd(wet, ty), 8);
        _mm512_mask_i32scatter_pd(ext + 2, sph, o3, _mm512_maskz_mov_pd(wet, tz), 8);
    }
}
/* The spheres among mov[k0 .. k1) in AVX2, 4 bodies at a time while 4 remain (returns where it
 * stopped; the rest go through the batch): fluid_spheres512's operations, so the same bits, with
 * each body's centre and velocity read as a row (SD_XYZ_LOAD) and its force written into
 * out[k - k0] as one. The logs among them are left to the caller. */
__attribute__((target("avx2"))) static int fluid_spheres256(const sd_water *fc, const sd_body_view *b,
                                                            const int32_t *mov, int k0, int k1, int32_t *logs,
                                                            int *nlogs, sd_vec3 *out)
{
    const sd_fluid_params *p = &fc->fp;
    const double *pos = &b->pos[0].x, *vel = &b->vel[0].x, *rad = b->radius;
    const uint8_t *shape = b->shape;
    sd_vec3 *const ext = out; /* (ext[k - k0]: body mov[k]'s) */
    const double h = p->h, hd = fc->h_d >= h ? fc->h_d : h;
    double al, be;
    sd_fluid_capture_coeffs(h, hd, &al, &be);
    const __m256d U = _mm256_set1_pd(p->U), H = _mm256_set1_pd(h), HD = _mm256_set1_pd(hd),
                  nx = _mm256_set1_pd(p->bed_normal.x), ny = _mm256_set1_pd(p->bed_normal.y),
                  nz = _mm256_set1_pd(p->bed_normal.z), zb = _mm256_set1_pd(p->z_bed),
                  dx = _mm256_set1_pd(p->flow_dir.x), dy = _mm256_set1_pd(p->flow_dir.y),
                  dz = _mm256_set1_pd(p->flow_dir.z), kd = _mm256_set1_pd(0.5 * p->C_D * p->rho),
                  mrho = _mm256_set1_pd(-p->rho), gx = _mm256_set1_pd(p->gravity.x), gy = _mm256_set1_pd(p->gravity.y),
                  gz = _mm256_set1_pd(p->gravity.z), bma = _mm256_set1_pd(be - al), A = _mm256_set1_pd(al),
                  five = _mm256_set1_pd(5.0), c45 = _mm256_set1_pd(4.0 / 5.0), pi = _mm256_set1_pd(M_PI),
                  c43pi = _mm256_set1_pd(4.0 / 3.0 * M_PI), XD = _mm256_set1_pd(fc->xd), X0 = _mm256_set1_pd(fc->x_from),
                  zero = _mm256_setzero_pd();
    const __m256d flow_ok = h > 0.0 ? _mm256_castsi256_pd(_mm256_set1_epi64x(-1)) : zero,
                  cap_ok = hd > 0.0 ? _mm256_castsi256_pd(_mm256_set1_epi64x(-1)) : zero,
                  capture = fc->capture ? _mm256_castsi256_pd(_mm256_set1_epi64x(-1)) : zero;
    /* in two loops over up to 32 groups at a time: the first up to the speed (the divisions and
     * the square root, a chain each group waits on), the second the forces and their stores.
     * One loop had room in flight for little more than one group's chain: the instructions
     * right after the square root and the division held a third of its samples */
    enum { FG = 32 };
    int k = k0;
    while (k + 4 <= k1) {
        __m256d RX[FG], RY[FG], RZ[FG], SP[FG], RA[FG], WT[FG];
        int SPH[FG], KK[FG], ng = 0;
        for (; k + 4 <= k1 && ng < FG; k += 4) {
            const int i0 = mov[k], i1 = mov[k + 1], i2 = mov[k + 2], i3 = mov[k + 3];
            const int sph = (shape[i0] == SD_SHAPE_SPHERE) | (shape[i1] == SD_SHAPE_SPHERE) << 1 |
                            (shape[i2] == SD_SHAPE_SPHERE) << 2 | (shape[i3] == SD_SHAPE_SPHERE) << 3;
            if (logs && sph != 15) /* (the logs: a few groups in a hundred) */
                for (int l = 0; l < 4; l++)
                    if (!(sph >> l & 1)) logs[(*nlogs)++] = k + l;
            if (!sph) continue;
            __m256d px, py, pz, vx, vy, vz, r;
            if (i3 == i0 + 3) { /* four bodies next to each other in the store (nearly always) */
                const double *pp = pos + 3 * i0, *vp = vel + 3 * i0;
                sd_rows3_lanes(_mm256_loadu_pd(pp), _mm256_loadu_pd(pp + 4), _mm256_loadu_pd(pp + 8), &px, &py, &pz);
                sd_rows3_lanes(_mm256_loadu_pd(vp), _mm256_loadu_pd(vp + 4), _mm256_loadu_pd(vp + 8), &vx, &vy, &vz);
                r = _mm256_loadu_pd(rad + i0);
            } else {
                __m256d P[4], V[4];
                sd_transpose4(SD_XYZ_LOAD(pos, i0), SD_XYZ_LOAD(pos, i1), SD_XYZ_LOAD(pos, i2), SD_XYZ_LOAD(pos, i3),
                              P);
                sd_transpose4(SD_XYZ_LOAD(vel, i0), SD_XYZ_LOAD(vel, i1), SD_XYZ_LOAD(vel, i2), SD_XYZ_LOAD(vel, i3),
                              V);
                px = P[0], py = P[1], pz = P[2], vx = V[0], vy = V[1], vz = V[2];
                r = _mm256_setr_pd(rad[i0], rad[i1], rad[i2], rad[i3]);
            }
            /* z = p.n - z_bed (sd_fluid_height), clamped at the bed as z < 0 ? 0 : z */
            const __m256d z = _mm256_sub_pd(
                _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(px, nx), _mm256_mul_pd(py, ny)), _mm256_mul_pd(pz, nz)), zb);
            const __m256d zc = _mm256_blendv_pd(z, zero, _mm256_cmp_pd(z, zero, _CMP_LT_OQ));
            /* the capture profile in the pond's region (capture && x_from <= p.x < xd) */
            const __m256d cap = _mm256_and_pd(_mm256_and_pd(capture, _mm256_cmp_pd(px, XD, _CMP_LT_OQ)),
                                              _mm256_cmp_pd(px, X0, _CMP_GE_OQ));
            const __m256d wet =
                _mm256_or_pd(_mm256_and_pd(_mm256_and_pd(cap, cap_ok), _mm256_cmp_pd(zc, HD, _CMP_LE_OQ)),
                             _mm256_andnot_pd(cap, _mm256_and_pd(flow_ok, _mm256_cmp_pd(zc, H, _CMP_LE_OQ))));
            /* the profile of each lane; a group all of one profile skips the other's divisions */
            const int capm = _mm256_movemask_pd(cap) & sph;
            __m256d u;
            if (capm == sph)
                u = _mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(_mm256_mul_pd(bma, zc), HD), A), U); /* eq 53 */
            else if (!capm)
                u = _mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(_mm256_div_pd(zc, H), five), c45), U); /* eq 50 */
            else
                u = _mm256_blendv_pd(_mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(_mm256_div_pd(zc, H), five), c45), U),
                                     _mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(_mm256_mul_pd(bma, zc), HD), A), U),
                                     cap);
            const __m256d rx = _mm256_sub_pd(_mm256_mul_pd(dx, u), vx), ry = _mm256_sub_pd(_mm256_mul_pd(dy, u), vy),
                          rz = _mm256_sub_pd(_mm256_mul_pd(dz, u), vz);
            const __m256d speed = _mm256_sqrt_pd(
                _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(rx, rx), _mm256_mul_pd(ry, ry)), _mm256_mul_pd(rz, rz)));
            RX[ng] = rx, RY[ng] = ry, RZ[ng] = rz, SP[ng] = speed, RA[ng] = r, WT[ng] = wet;
            SPH[ng] = sph, KK[ng] = k;
            ng++;
        }
        for (int q = 0; q < ng; q++) {
            const __m256d rx = RX[q], ry = RY[q], rz = RZ[q], speed = SP[q], r = RA[q], wet = WT[q];
            const int sph = SPH[q], kq = KK[q];
            const __m256d area = _mm256_mul_pd(_mm256_mul_pd(pi, r), r),
                          volume = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(c43pi, r), r), r);
            const __m256d sk = _mm256_mul_pd(_mm256_mul_pd(kd, area), speed), bs = _mm256_mul_pd(mrho, volume);
            /* dry spheres get zero */
            const __m256d tx = _mm256_and_pd(wet, _mm256_add_pd(_mm256_mul_pd(rx, sk), _mm256_mul_pd(gx, bs))),
                          ty = _mm256_and_pd(wet, _mm256_add_pd(_mm256_mul_pd(ry, sk), _mm256_mul_pd(gy, bs))),
                          tz = _mm256_and_pd(wet, _mm256_add_pd(_mm256_mul_pd(rz, sk), _mm256_mul_pd(gz, bs)));
            if (sph == 15) { /* four spheres: their forces as 12 doubles in a row */
                __m256d ra, rb, rc;
                sd_lanes_rows3(tx, ty, tz, &ra, &rb, &rc);
                double *e = &ext[kq - k0].x;
                _mm256_storeu_pd(e, ra);
                _mm256_storeu_pd(e + 4, rb);
                _mm256_storeu_pd(e + 8, rc);
                continue;
            }
            /* back as rows (x, y, z, -), each sphere's written */
            __m256d row[4];
            sd_transpose4(tx, ty, tz, zero, row);
            for (int l = 0; l < 4; l++)
                if (sph >> l & 1) { /* x and y in one 16-byte store, z alone (no masked store: slow on AMD) */
                    _mm_storeu_pd(&ext[kq - k0 + l].x, _mm256_castpd256_pd128(row[l]));
                    ext[kq - k0 + l].z = _mm_cvtsd_f64(_mm256_extractf128_pd(row[l], 1));
                }
        }
    }
    return k;
}
#endif

/* The fluid force on body i, one by one (sd_fluid_force_total): the logs, and every body in a
 * uniform stream. */
static sd_vec3 fluid_log(const sd_water *fc, const sd_body_view *b, int i)
{
    sd_fluid_element e;
    e.shape = b->shape[i];
    e.pos = b->pos[i];
    e.vel = b->vel[i];
    e.axis = b->axis[i];
    e.radius = b->radius[i];
    e.length = 2.0 * b->half_length[i];
    /* the capture profile applies in the pond's region; elsewhere the flow one */
    const double x = b->pos[i].x;
    const sd_fluid_phase ph = fc->uniform                            ? SD_FLUID_UNIFORM
                              : (fc->capture && x < fc->xd && x >= fc->x_from) ? SD_FLUID_CAPTURE
                                                                                : SD_FLUID_FLOW;
    return sd_fluid_force_total(&fc->fp, ph, fc->h_d, &e);
}

#define SD_FLUID_LOGS SD_EXTERNAL_BLOCK /* the bodies of a block whose logs the lanes list */

/* The fluid forces on the moving bodies mov[k0 .. k1), into out[k - k0]: called by the world's
 * step for each block of up to SD_EXTERNAL_BLOCK of a thread's bodies just before it moves them
 * (sd_world_set_external_force_fn), so their data are still in that core's L1 when they move. Spheres in
 * batches (sd_fluid_sphere_batch: the same bits, vectorized), logs one by one. */
void sd_water_forces(void *ctx, const sd_world *w, const int32_t *mov, int k0, int k1, sd_vec3 *out)
{
    const sd_water *fc = ctx;
    const sd_body_view bv = sd_world_bodies(w), *b = &bv;
    const sd_fluid_params *fp = &fc->fp;
    const double xd = fc->xd, x_from = fc->x_from, h_d = fc->h_d;
    const int capture = fc->capture;
    if (fc->uniform) { /* a scene's uniform stream or still water: every body one by one */
        for (int k = k0; k < k1; k++)
            out[k - k0] = fluid_log(fc, b, mov[k]);
        return;
    }
    /* the spheres of mov[k0 .. kv) in SIMD lanes where the CPU has them (8 AVX-512 lanes, 4 AVX2
     * lanes), the rest through the batch */
    int kv = k0;
    /* the logs among the bodies the lanes went over, listed by them (a block holds up to
     * SD_FLUID_LOGS bodies): the loop below then starts where the lanes stopped, instead of
     * going over every body again for the logs and the rest */
    int32_t logs[SD_FLUID_LOGS];
    int nlogs = 0;
    int32_t *lp = k1 - k0 <= SD_FLUID_LOGS ? logs : NULL;
#ifdef SD_FLUID512
    const int simd = sd_world_simd_level(w); /* (one call a block, not two) */
    if (simd == SD_SIMD_AVX512) {
        fluid_spheres512(fc, b, mov, k0, k1, lp, &nlogs, out);
        kv = k1;
    } else if (simd == SD_SIMD_AVX2)
        kv = fluid_spheres256(fc, b, mov, k0, k1, lp, &nlogs, out);
#else
    lp = NULL;
#endif
    fluid_batch q;
    q.m = 0;
    /* the store's arrays held in locals: the batch's flush is a call, after which gcc would
     * load each array's address again for every body */
    const sd_vec3 *restrict pos = b->pos, *restrict vel = b->vel;
    const double *restrict rad = b->radius;
    for (int k = lp ? kv : k0; k < k1; k++) {
        const int i = mov[k];
        if (b->shape[i] == SD_SHAPE_SPHERE) {
            if (k < kv) continue;
            const int j = q.m++;
            const sd_vec3 p = pos[i], v = vel[i];
            q.idx[j] = k - k0;
            q.px[j] = p.x, q.py[j] = p.y, q.pz[j] = p.z;
            q.vx[j] = v.x, q.vy[j] = v.y, q.vz[j] = v.z;
            q.r[j] = rad[i];
            q.cap[j] = (capture && p.x < xd && p.x >= x_from) ? 1.0 : 0.0;
            if (q.m == FLUID_BATCH) fluid_flush(&q, fp, h_d, out);
            continue;
        }
        out[k - k0] = fluid_log(fc, b, i);
    }
    for (int l = 0; l < nlogs; l++)
        out[logs[l] - k0] = fluid_log(fc, b, mov[logs[l]]);
    if (q.m > 0) fluid_flush(&q, fp, h_d, out);
}
