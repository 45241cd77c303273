/* The driver: builds the scene, runs the phases of SPEC §6, writes the outputs. Output and
 * phase logic happen between steps, never inside them. */
#include "run.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "build.h"
#include "core/binio.h"
#include "core/simd.h"
#include "fluid.h"
#include "io_vtk.h"
#include "core/status.h"
#include "core/vmath.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#include <immintrin.h>
#define SD_FLUID512 1
#endif

enum { PH_PACK = 0, PH_FLOW = 1, PH_CAPTURE = 2, PH_DONE = 3, PH_RUN = 4 };
static const char *phase_names[] = {"packing", "flow", "capture", "done", "run"};

typedef struct {
    const sd_scenario *s;
    const sd_run_opts *o;
    sd_world *w;
    sd_build_info info;
    FILE *series, *traj;
    char dir[1024];
    int phase;
    double vol_total_class[SD_MAX_CLASSES], vol_total_logs;
    double vol_passed_class[SD_MAX_CLASSES], vol_passed_logs;
    int n_passed;
    double h_d;
    double last_cross_time;
    double ke_peak;
    double pipe_peak[2 * SD_MAX_PIPES], pipe_impulse[2 * SD_MAX_PIPES];
    double pipe_peak_t[2 * SD_MAX_PIPES]; /* when the peak happened (pipes exist from the capture start) */
    sd_vec3 pipe_impulse_vec[2 * SD_MAX_PIPES];
    double dam_force_now;
    double phase_end[4];
    double phase_wall[4];
    int flow_len_done;
    double flow_len, flow_q05, flow_q95, flow_front, flow_len_time;
    int n_snap;
    sd_vtk_series pvd;
    int pvd_on;
    double wall0;
    long rate_step0;           /* world step and wall clock when this process started stepping */
    double rate_wall0;         /* (a restart continues from the checkpoint's step) */
    double phase_t0, phase_w0; /* simulated and wall time at the start of the current phase */
    int flow_ended;            /* the flow phase has ended; the capture starts at the next step */
    int dam_built;             /* the pipes are in the world (sd_build_dam at the capture start) */
    const char *restarted_from;
    double flow_wall; /* wall time from the start to the flow end, build included (a restarted
                       * run: that of the run that wrote the checkpoint) */
    struct fluid_ctx {
        sd_fluid_params fp;
        double h_d, xd;
        int capture;
    } fluid; /* what the step's fluid forces need (set_fluid) */
    /* the side views asked for so far (the arrival's, the end's), for the caller to draw */
    int n_plots;
    sd_run_picture plots[SD_RUN_PICTURES];
} run_ctx;

static double body_volume(const sd_body_view *b, int i)
{
    double r = b->radius[i];
    return b->shape[i] == SD_SHAPE_SPHERE ? 4.0 / 3.0 * M_PI * r * r * r : M_PI * r * r * 2.0 * b->half_length[i];
}

static int is_debris(const sd_body_view *b, int i) { return !b->fixed[i]; }

/* Volume still upstream of the dam: centre upstream of the pipes' axis plane. */
static double x_trap(const run_ctx *c) { return c->s->x_dam + 0.5 * c->s->pipe_diam; }

/* An element crossing the dam (SPEC §6: the capture settles when none has crossed for
 * quiet_time): a moving element whose centre is past the trap plane xt by less than 2 cm and
 * moves downstream faster than the rest speed of SPEC §6 (~1 mm/s). An element lodged among
 * the pipes with its centre just past the plane is at rest there, not crossing: counted, it
 * held the default run's capture to its time limit (docs/physics.md §13). */
#define SD_REST_SPEED 1e-3

int sd_run_crossing(const sd_world *w, double xt)
{
    const sd_body_view bv = sd_world_bodies(w), *b = &bv;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && b->pos[i].x >= xt && b->pos[i].x < xt + 0.02 && b->vel[i].x > SD_REST_SPEED) return 1;
    return 0;
}

static void volumes_upstream(const run_ctx *c, double *cls, double *logs, int *n_up)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        cls[k] = 0.0;
    *logs = 0.0;
    *n_up = 0;
    double xt = x_trap(c);
    for (int i = 0; i < b->n; i++) {
        if (!is_debris(b, i) || b->pos[i].x >= xt) continue;
        (*n_up)++;
        if (b->shape[i] == SD_SHAPE_CYLINDER)
            *logs += body_volume(b, i);
        else if (b->tag[i] >= 0 && b->tag[i] < SD_MAX_CLASSES)
            cls[b->tag[i]] += body_volume(b, i);
    }
}

static double trap_ratio(const run_ctx *c, double *per_class, double *logs_ratio, int *n_up)
{
    double cls[SD_MAX_CLASSES], logs;
    volumes_upstream(c, cls, &logs, n_up);
    double up = logs, tot = c->vol_total_logs;
    for (int k = 0; k < SD_MAX_CLASSES; k++) {
        up += cls[k];
        tot += c->vol_total_class[k];
        if (per_class) per_class[k] = c->vol_total_class[k] > 0 ? cls[k] / c->vol_total_class[k] : 0.0;
    }
    if (logs_ratio) *logs_ratio = c->vol_total_logs > 0 ? logs / c->vol_total_logs : 0.0;
    return tot > 0 ? up / tot : 0.0;
}

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
__attribute__((target("avx512f,avx512vl"))) static void fluid_spheres512(const struct fluid_ctx *fc,
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
                  c43pi = _mm512_set1_pd(4.0 / 3.0 * M_PI), XD = _mm512_set1_pd(fc->xd), zero = _mm512_setzero_pd();
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
        /* the capture profile upstream of the dam (capture && p.x < x_dam) */
        const __mmask8 cap = (__mmask8)(capture & _mm512_cmp_pd_mask(px, XD, _CMP_LT_OQ));
        const __mmask8 wet = (__mmask8)((cap & cap_ok & _mm512_cmp_pd_mask(zc, HD, _CMP_LE_OQ)) |
                                        (~cap & flow_ok & _mm512_cmp_pd_mask(zc, H, _CMP_LE_OQ)));
        /* the profile of each lane; a group all of one profile (nearly every group) skips the
         * other's divisions, the costliest part of this loop */
        __m512d u;
        if ((cap & sph) == sph)
            u = _mm512_mul_pd(_mm512_add_pd(_mm512_div_pd(_mm512_mul_pd(bma, zc), HD), A), U); /* eq 51 */
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
__attribute__((target("avx2"))) static int fluid_spheres256(const struct fluid_ctx *fc, const sd_body_view *b,
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
                  c43pi = _mm256_set1_pd(4.0 / 3.0 * M_PI), XD = _mm256_set1_pd(fc->xd), zero = _mm256_setzero_pd();
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
            /* the capture profile upstream of the dam (capture && p.x < x_dam) */
            const __m256d cap = _mm256_and_pd(capture, _mm256_cmp_pd(px, XD, _CMP_LT_OQ));
            const __m256d wet =
                _mm256_or_pd(_mm256_and_pd(_mm256_and_pd(cap, cap_ok), _mm256_cmp_pd(zc, HD, _CMP_LE_OQ)),
                             _mm256_andnot_pd(cap, _mm256_and_pd(flow_ok, _mm256_cmp_pd(zc, H, _CMP_LE_OQ))));
            /* the profile of each lane; a group all of one profile skips the other's divisions */
            const int capm = _mm256_movemask_pd(cap) & sph;
            __m256d u;
            if (capm == sph)
                u = _mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(_mm256_mul_pd(bma, zc), HD), A), U); /* eq 51 */
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

/* The fluid force on log i, one by one (sd_fluid_force_total). */
static sd_vec3 fluid_log(const struct fluid_ctx *fc, const sd_body_view *b, int i)
{
    sd_fluid_element e;
    e.shape = b->shape[i];
    e.pos = b->pos[i];
    e.vel = b->vel[i];
    e.axis = b->axis[i];
    e.radius = b->radius[i];
    e.length = 2.0 * b->half_length[i];
    /* the capture profile applies upstream of the dam; passed elements keep the flow one */
    const sd_fluid_phase ph = (fc->capture && b->pos[i].x < fc->xd) ? SD_FLUID_CAPTURE : SD_FLUID_FLOW;
    return sd_fluid_force_total(&fc->fp, ph, fc->h_d, &e);
}

#define SD_FLUID_LOGS SD_EXTERNAL_BLOCK /* the bodies of a block whose logs the lanes list */

/* The fluid forces on the moving bodies mov[k0 .. k1), into out[k - k0]: called by the world's
 * step for each block of up to SD_EXTERNAL_BLOCK of a thread's bodies just before it moves them
 * (sd_world_set_external_force_fn), so their data are still in that core's L1 when they move. Spheres in
 * batches (sd_fluid_sphere_batch: the same bits, vectorized), logs one by one. */
static void fluid_range(void *ctx, const sd_world *w, const int32_t *mov, int k0, int k1, sd_vec3 *out)
{
    const struct fluid_ctx *fc = ctx;
    const sd_body_view bv = sd_world_bodies(w), *b = &bv;
    const sd_fluid_params *fp = &fc->fp;
    const double xd = fc->xd, h_d = fc->h_d;
    const int capture = fc->capture;
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
    if (sd_world_simd_level(w) == SD_SIMD_AVX512) {
        fluid_spheres512(fc, b, mov, k0, k1, lp, &nlogs, out);
        kv = k1;
    } else if (sd_world_simd_level(w) == SD_SIMD_AVX2)
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
            q.cap[j] = (capture && p.x < xd) ? 1.0 : 0.0;
            if (q.m == FLUID_BATCH) fluid_flush(&q, fp, h_d, out);
            continue;
        }
        out[k - k0] = fluid_log(fc, b, i);
    }
    for (int l = 0; l < nlogs; l++)
        out[logs[l] - k0] = fluid_log(fc, b, mov[logs[l]]);
    if (q.m > 0) fluid_flush(&q, fp, h_d, out);
}

/* The fluid forces of the current phase for the coming step: handed to the world, which calls
 * fluid_range inside the step; none while packing (the external forces stay as they are). */
static void set_fluid(run_ctx *c)
{
    const sd_scenario *s = c->s;
    if (!s->water_on || c->phase == PH_PACK || c->phase == PH_RUN) {
        sd_world_set_external_force_fn(c->w, NULL, NULL);
        return;
    }
    sd_fluid_params fp = sd_fluid_params_default(s->slope_deg * M_PI / 180.0);
    fp.U = s->water_u;
    fp.h = s->water_h;
    fp.rho = s->water_rho;
    fp.C_D = s->water_cd;
    fp.gravity = sd_world_definition(c->w)->gravity;
    c->fluid.fp = fp;
    c->fluid.xd = s->x_dam;
    c->fluid.capture = c->phase == PH_CAPTURE;
    c->fluid.h_d = c->h_d;
    sd_world_set_external_force_fn(c->w, fluid_range, &c->fluid);
}

double sd_run_capture_depth(const sd_scenario *s, const sd_world *w)
{
    const sd_body_view bv = sd_world_bodies(w), *b = &bv;
    double h = s->water_h, xd = s->x_dam, lo = xd - s->water_probe;
    for (int i = 0; i < b->n; i++) {
        if (b->fixed[i] || b->pos[i].x < lo || b->pos[i].x > xd || b->pos[i].z <= h) continue;
        /* the deposit sets the pond level; a log floating on the pond does not (docs/physics.md) */
        if (!s->water_hd_floating && b->mass[i] <= s->water_rho * body_volume(b, i)) continue;
        h = b->pos[i].z;
    }
    return h;
}

static void update_h_d(run_ctx *c) { c->h_d = sd_run_capture_depth(c->s, c->w); }

static void remove_passed(run_ctx *c)
{
    sd_body_view bv = sd_world_bodies(c->w);
    const sd_body_view *b = &bv;
    for (int i = b->n - 1; i >= 0; i--) {
        if (b->fixed[i] || b->pos[i].x <= c->s->x_end) continue;
        if (b->shape[i] == SD_SHAPE_CYLINDER)
            c->vol_passed_logs += body_volume(b, i);
        else if (b->tag[i] >= 0 && b->tag[i] < SD_MAX_CLASSES)
            c->vol_passed_class[b->tag[i]] += body_volume(b, i);
        c->n_passed++;
        sd_world_remove_body(c->w, b->gid[i]);
        bv = sd_world_bodies(c->w); /* (the last body took i's place: those above i are done) */
    }
}

/* Downstream extent of an element beyond its centre along x: r for a sphere, and for a log
 * the farthest point of the cylinder, hl |a_x| + r sqrt(1 - a_x^2). */

/* The front: the farthest downstream surface of any moving element (kept by the step). */
static double front_x(const run_ctx *c) { return sd_world_front_x(c->w); }

static double upstream_ke(const run_ctx *c)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    double e = 0.0, xt = x_trap(c);
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && b->pos[i].x < xt) e += 0.5 * b->mass[i] * v3_norm2(b->vel[i]);
    return e;
}

static double max_speed(const run_ctx *c)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    double v = 0.0;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i]) v = fmax(v, v3_norm2(b->vel[i]));
    return sqrt(v);
}

typedef struct {
    double x, v;
} xv;

static int cmp_xv(const void *pa, const void *pb)
{
    const xv *a = pa, *b = pb;
    return (a->x > b->x) - (a->x < b->x);
}

/* Flow length (SPEC §8): spread between the 5 % and 95 % volume quantiles of x over the
 * volume that has left the reservoir. */
static void measure_flow_length(run_ctx *c)
{
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    xv *a = malloc((size_t)(b->n + 1) * sizeof(*a));
    if (!a) return;
    int m = 0;
    double tot = 0.0;
    for (int i = 0; i < b->n; i++)
        if (!b->fixed[i] && b->pos[i].x > c->s->x_gate) {
            a[m].x = b->pos[i].x;
            a[m].v = body_volume(b, i);
            tot += a[m].v;
            m++;
        }
    qsort(a, (size_t)m, sizeof(*a), cmp_xv);
    double acc = 0.0, q05 = NAN, q95 = NAN;
    for (int k = 0; k < m; k++) {
        acc += a[k].v;
        if (isnan(q05) && acc >= 0.05 * tot) q05 = a[k].x;
        if (isnan(q95) && acc >= 0.95 * tot) q95 = a[k].x;
    }
    free(a);
    c->flow_q05 = q05;
    c->flow_q95 = q95;
    c->flow_len = q95 - q05;
    c->flow_front = front_x(c);
    c->flow_len_time = sd_world_time(c->w);
    c->flow_len_done = 1;
}

static void write_series_row(run_ctx *c)
{
    if (!c->series) return;
    double cls[SD_MAX_CLASSES], logs;
    int n_up;
    volumes_upstream(c, cls, &logs, &n_up);
    double up = logs;
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        up += cls[k];
    double pv = c->s->flume_on ? trap_ratio(c, NULL, NULL, &n_up) : 0.0;
    fprintf(c->series, "%.6f,%s,%.6f,%.9e,%.9e,%ld,%.6e,%.6f,%.6f,%d,%d\n", sd_world_time(c->w), phase_names[c->phase],
            sd_world_body_count(c->w) ? front_x(c) : 0.0, up, sd_world_kinetic_energy(c->w), sd_world_contact_count(c->w),
            c->dam_force_now, pv, c->h_d, sd_world_body_count(c->w), c->n_passed);
}

static void write_traj(run_ctx *c)
{
    if (!c->traj) return;
    for (int k = 0; k < c->s->n_traj; k++) {
        sd_body_state st;
        if (sd_world_body(c->w, c->s->traj_ids[k], &st)) continue;
        fprintf(c->traj,
                "%.9f,%d,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e,%.9f,%.9f,%.9f,%.9e,%.9e,%.9e\n",
                sd_world_time(c->w), st.gid, st.pos.x, st.pos.y, st.pos.z, st.vel.x, st.vel.y, st.vel.z, st.omega.x, st.omega.y,
                st.omega.z, st.axis.x, st.axis.y, st.axis.z, st.force.x, st.force.y, st.force.z);
    }
}

static int snapshot(run_ctx *c, const char *name)
{
    if (!c->s->vtk_on) return 0;
    const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
    size_t cap = (size_t)(b->n + 1);
    sd_vec3 *pos = malloc(cap * sizeof(sd_vec3)), *vel = malloc(cap * sizeof(sd_vec3)),
            *ax = malloc(cap * sizeof(sd_vec3));
    double *rad = malloc(cap * sizeof(double)), *len = malloc(cap * sizeof(double));
    int *id = malloc(cap * sizeof(int)), *tag = malloc(cap * sizeof(int));
    int rc = -1;
    if (pos && vel && ax && rad && len && id && tag) {
        char r1[256], r2[256], f[1400];
        snprintf(r1, sizeof r1, "spheres_%s.vtp", name);
        snprintf(r2, sizeof r2, "cylinders_%s.vtp", name);
        for (int pass = 0; pass < 2; pass++) {
            size_t m = 0;
            for (int i = 0; i < b->n; i++) {
                if ((b->shape[i] == SD_SHAPE_SPHERE) != (pass == 0)) continue;
                pos[m] = b->pos[i];
                vel[m] = b->vel[i];
                ax[m] = b->axis[i];
                rad[m] = b->radius[i];
                len[m] = 2.0 * b->half_length[i];
                id[m] = b->gid[i];
                tag[m] = b->tag[i];
                m++;
            }
            snprintf(f, sizeof f, "%s/%s", c->dir, pass == 0 ? r1 : r2);
            rc = pass == 0 ? sd_vtk_write_spheres(f, m, pos, rad, vel, id, tag)
                           : sd_vtk_write_cylinders(f, m, pos, ax, len, rad, vel, id, tag);
            if (rc) break;
        }
        if (!rc && c->pvd_on) {
            rc = sd_vtk_series_add(&c->pvd, sd_world_time(c->w), 0, r1);
            if (!rc) rc = sd_vtk_series_add(&c->pvd, sd_world_time(c->w), 1, r2);
        }
    }
    free(pos);
    free(vel);
    free(ax);
    free(rad);
    free(len);
    free(id);
    free(tag);
    c->n_snap++;
    return rc;
}

static int write_walls(run_ctx *c)
{
    if (!c->s->vtk_on) return 0;
    const int nt = sd_world_triangle_count(c->w);
    char f[1200];
    snprintf(f, sizeof f, "%s/walls.vtp", c->dir);
    sd_vec3 *v = malloc((size_t)(3 * nt + 1) * sizeof(sd_vec3));
    int *g = malloc((size_t)(nt + 1) * sizeof(int));
    int rc = -1;
    if (v && g) {
        for (int t = 0; t < nt; t++)
            sd_world_triangle(c->w, t, &v[3 * t], &g[t], NULL);
        rc = sd_vtk_write_triangles(f, (size_t)nt, v, g);
    }
    free(v);
    free(g);
    return rc;
}

/* A side view of snapshot `name` into png, from the snapshot's files, for the caller to draw
 * after the run (sd_run_result.pictures: the driver starts no program). The arrival's picture,
 * drawn when the front reached the dam, held the two threads up for the ~1.5 s of a Python
 * process; drawn at the end beside the final one, the two cost the run ~1.5 s instead of ~3. */
static void plot(run_ctx *c, const char *name, const char *png, double xmin, double xmax)
{
    if (!c->s->png_on || !c->s->vtk_on || c->n_plots >= SD_RUN_PICTURES) return;
    sd_run_picture *p = &c->plots[c->n_plots++];
    snprintf(p->spheres, sizeof p->spheres, "%s/spheres_%s.vtp", c->dir, name);
    snprintf(p->logs, sizeof p->logs, "%s/cylinders_%s.vtp", c->dir, name);
    snprintf(p->png, sizeof p->png, "%s/%s", c->dir, png);
    p->x_dam = c->s->x_dam;
    p->x_min = xmin;
    p->x_max = xmax;
}

static void progress(run_ctx *c, double t_end_est)
{
    double wall = sd_now() - c->rate_wall0;
    double sps = wall > 0 ? (double)(sd_world_step_count(c->w) - c->rate_step0) / wall : 0.0;
    double eta = sps > 0 && t_end_est > sd_world_time(c->w) ? (t_end_est - sd_world_time(c->w)) / sd_world_definition(c->w)->dt / sps : 0.0;
    if (!c->o->log) return;
    if (c->o->progress_tty)
        fprintf(c->o->log, "\r%-8s t = %8.4f s  %9.0f steps/s  %6d elements  ETA %6.0f s   ", phase_names[c->phase],
                sd_world_time(c->w), sps, sd_world_body_count(c->w), eta);
    else
        fprintf(c->o->log, "phase=%s t=%.4f steps_per_s=%.0f elements=%d passed=%d eta_s=%.0f\n", phase_names[c->phase],
                sd_world_time(c->w), sps, sd_world_body_count(c->w), c->n_passed, eta);
    fflush(c->o->log);
}

static int write_summary(run_ctx *c, sd_run_result *res, int status_code, const char *status_msg)
{
    char path[1200], tmp[1300];
    snprintf(path, sizeof path, "%s/summary.json", c->dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) return -1;
    const sd_scenario *s = c->s;
    double per[SD_MAX_CLASSES] = {0}, logs_ratio = 0.0;
    int n_up = 0;
    double pv = s->flume_on ? trap_ratio(c, per, &logs_ratio, &n_up) : 0.0;
    fprintf(f, "{\n  \"scenario\": \"%s\",\n  \"status\": \"%s\",\n  \"exit_code\": %d,\n", s->path, status_msg,
            status_code);
    fprintf(f, "  \"simulated_time_s\": %.6f,\n  \"steps\": %ld,\n  \"wall_time_s\": %.3f,\n", sd_world_time(c->w), sd_world_step_count(c->w),
            sd_now() - c->wall0);
    fprintf(f, "  \"state_hash\": \"%016llx\",\n", (unsigned long long)sd_world_state_hash(c->w));
    /* the hand-written kernels this run used (the same bits at every level: for the speed) */
    static const char *const simd_names[] = {"auto", "scalar", "avx2", "avx512"};
    fprintf(f, "  \"simd_kernels\": \"%s\",\n", simd_names[sd_world_simd_level(c->w)]);
    /* the front prefetch (a hint: the same bits either way) and, in auto mode, the last trial's
     * verdict and its time on over off */
    double pf_ratio = 0.0;
    int pf_trial = -1;
    const int pf_on = sd_world_prefetch(c->w, &pf_trial, &pf_ratio) == SD_PREFETCH_ON;
    if (sd_world_definition(c->w)->tuning.prefetch != SD_PREFETCH_AUTO)
        fprintf(f, "  \"front_prefetch\": \"%s (set)\",\n", pf_on ? "on" : "off");
    else if (pf_trial < 0)
        fprintf(f, "  \"front_prefetch\": \"%s (no trial)\",\n", pf_on ? "on" : "off");
    else
        fprintf(f, "  \"front_prefetch\": \"%s (trial: on/off %.3f)\",\n", pf_trial ? "on" : "off", pf_ratio);
    if (c->restarted_from) {
        fprintf(f, "  \"restarted_from\": \"");
        for (const char *q = c->restarted_from; *q; q++)
            fprintf(f, *q == '"' || *q == '\\' ? "\\%c" : "%c", *q);
        fprintf(f, "\",\n  \"restart_flow_wall_s\": %.3f,\n", c->flow_wall);
    }
    sd_world_timers tm = sd_world_get_timers(c->w);
    fprintf(f,
            "  \"timers_s\": {\"rebuild\": %.3f, \"contacts\": %.3f, \"moves\": %.3f, \"checks\": %.3f, "
            "\"rebuilds\": %ld},\n",
            tm.rebuild, tm.contacts, tm.moves, tm.checks, tm.rebuilds);
    fprintf(f,
            "  \"elements\": {\"moving_spheres\": %d, \"logs\": %d, \"roughness_spheres\": %d, \"pipes\": %d, "
            "\"triangles\": %d, \"passed\": %d, \"remaining\": %d},\n",
            c->info.n_spheres, c->info.n_logs, c->info.n_rough, c->info.n_pipes, sd_world_triangle_count(c->w),
            c->n_passed, sd_world_body_count(c->w));
    if (s->flume_on) {
        res->p_v = pv;
        for (int k = 0; k < SD_MAX_CLASSES; k++)
            res->p_v_class[k] = per[k];
        res->p_v_logs = logs_ratio;
        res->n_upstream = n_up;
        fprintf(f, "  \"trap_ratio\": %.6f,\n  \"capture_limit_s\": %.3f,\n  \"trap_ratio_class\": [", pv,
                s->capture_limit);
        for (int k = 0; k < s->n_classes; k++)
            fprintf(f, "%s{\"diameter\": %g, \"p_v\": %.6f}", k ? ", " : "", s->class_diam[k], per[k]);
        double vt = c->vol_total_logs, vs = 0;
        for (int k = 0; k < SD_MAX_CLASSES; k++)
            vs += c->vol_total_class[k];
        fprintf(f,
                "],\n  \"trap_ratio_logs\": %.6f,\n  \"k_w\": %.6f,\n  \"solid_volume_m3\": {\"spheres\": %.9e, "
                "\"logs\": %.9e},\n",
                logs_ratio, vt + vs > 0 ? vt / (vt + vs) : 0.0, vs, vt);
        /* deposit height at the dam: top of the highest element within the probe length */
        double dep = 0.0;
        const sd_body_view bv = sd_world_bodies(c->w), *b = &bv;
        for (int i = 0; i < b->n; i++)
            if (!b->fixed[i] && b->pos[i].x >= s->x_dam - s->water_probe && b->pos[i].x <= x_trap(c))
                dep = fmax(dep, b->pos[i].z + b->bound_radius[i]);
        fprintf(f, "  \"deposit_height_at_dam_m\": %.5f,\n", dep);
        fprintf(f, "  \"phase_end_s\": {\"packing\": %.4f, \"flow\": %.4f, \"capture\": %.4f},\n", c->phase_end[0],
                c->phase_end[1], c->phase_end[2]);
        fprintf(f, "  \"phase_wall_s\": {\"packing\": %.2f, \"flow\": %.2f, \"capture\": %.2f},\n", c->phase_wall[0],
                c->phase_wall[1], c->phase_wall[2]);
        if (c->flow_len_done)
            fprintf(f,
                    "  \"flow_at_1m_before_dam\": {\"t\": %.4f, \"length_q05_q95_m\": %.4f, \"q05_m\": %.4f, "
                    "\"q95_m\": %.4f, \"front_m\": %.4f},\n",
                    c->flow_len_time, c->flow_len, c->flow_q05, c->flow_q95, c->flow_front);
        fprintf(f, "  \"pipes\": [\n");
        for (int k = 0; k < c->info.n_pipes; k++)
            fprintf(f,
                    "    {\"gid\": %d, \"kind\": \"%s\", \"%s\": %.4f, \"peak_force_N\": %.6e, \"peak_time_s\": %.5f, "
                    "\"impulse_Ns\": %.6e, \"impulse_x_Ns\": %.6e}%s\n",
                    c->info.pipe_gid[k], c->info.pipe_is_column[k] ? "column" : "beam",
                    c->info.pipe_is_column[k] ? "y_m" : "z_axis_m", c->info.pipe_coord[k], c->pipe_peak[k],
                    c->pipe_peak_t[k], c->pipe_impulse[k], c->pipe_impulse_vec[k].x,
                    k + 1 < c->info.n_pipes ? "," : "");
        fprintf(f, "  ],\n");
    }
    sd_scenario_echo_json(s, f);
    fprintf(f, "\n}\n");
    int bad = ferror(f);
    if (fclose(f) || bad) return -1;
    return rename(tmp, path);
}

static void accumulate_pipes(run_ctx *c)
{
    double tot = 0.0;
    for (int k = 0; k < c->info.n_pipes; k++) {
        sd_body_state st;
        if (sd_world_body(c->w, c->info.pipe_gid[k], &st)) continue;
        double f = v3_norm(st.force);
        tot += f;
        if (f > c->pipe_peak[k]) {
            c->pipe_peak[k] = f;
            c->pipe_peak_t[k] = sd_world_time(c->w);
        }
        c->pipe_impulse[k] += f * sd_world_definition(c->w)->dt;
        c->pipe_impulse_vec[k] = v3_madd(c->pipe_impulse_vec[k], st.force, sd_world_definition(c->w)->dt);
    }
    c->dam_force_now = tot;
}

/* ---------------------------------------------------------------- branching ---- */

/* The capture phase begins: the grid dam's pipes go in now, not at the build, so that packing
 * and flow do not depend on the dam layout (SPEC §6, docs/physics.md "Flow end and branching").
 * A straight run and a run restarted from a flow-end checkpoint both come through here. */
static sd_status capture_start(run_ctx *c)
{
    const sd_scenario *s = c->s;
    sd_status st = sd_build_dam(c->w, s, &c->info);
    if (st) return st;
    c->dam_built = 1;
    c->phase = PH_CAPTURE;
    c->phase_t0 = sd_world_time(c->w);
    c->phase_w0 = sd_now();
    c->last_cross_time = sd_world_time(c->w);
    update_h_d(c);
    snapshot(c, "arrival");
    plot(c, "arrival", "side_arrival.png", s->x_dam - 1.2, s->x_end);
    return SD_OK;
}

/* The driver's state in the checkpoint's extra blob: a tagged, versioned byte string. It is
 * written only at the flow end (before the pipes exist), so the pipe accumulators are zero and
 * not stored. The build's random numbers are spent before the first step; the driver draws
 * none later, so there is no rng state to carry. */
#define BLOB_MAGIC "SDRUNv1"

static long file_len(FILE *f)
{
    if (!f || fflush(f)) return -1;
    return ftell(f);
}

static void state_pack(const run_ctx *c, sd_bin_writer *b, long series_len, long traj_len)
{
    sd_bin_put(b, BLOB_MAGIC, 8);
    sd_bin_put_u64(b, sd_scenario_branch_hash(c->s));
    sd_bin_put_i32(b, c->phase);
    sd_bin_put_i32(b, c->flow_ended);
    sd_bin_put_i32(b, c->dam_built);
    sd_bin_put_i32(b, c->n_passed);
    sd_bin_put_i32(b, c->flow_len_done);
    sd_bin_put_i32(b, c->n_snap);
    sd_bin_put_i32(b, c->info.n_rough);
    sd_bin_put_i32(b, c->info.n_spheres);
    sd_bin_put_i32(b, c->info.n_logs);
    sd_bin_put_i32(b, c->info.first_moving_gid);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        sd_bin_put_f64(b, c->vol_total_class[k]);
    sd_bin_put_f64(b, c->vol_total_logs);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        sd_bin_put_f64(b, c->vol_passed_class[k]);
    sd_bin_put_f64(b, c->vol_passed_logs);
    sd_bin_put_f64(b, c->h_d);
    sd_bin_put_f64(b, c->last_cross_time);
    sd_bin_put_f64(b, c->ke_peak);
    sd_bin_put_f64(b, c->dam_force_now);
    for (int k = 0; k < 4; k++)
        sd_bin_put_f64(b, c->phase_end[k]);
    for (int k = 0; k < 4; k++)
        sd_bin_put_f64(b, c->phase_wall[k]);
    sd_bin_put_f64(b, c->flow_len);
    sd_bin_put_f64(b, c->flow_q05);
    sd_bin_put_f64(b, c->flow_q95);
    sd_bin_put_f64(b, c->flow_front);
    sd_bin_put_f64(b, c->flow_len_time);
    sd_bin_put_f64(b, c->phase_t0);
    sd_bin_put_f64(b, sd_now() - c->wall0);
    sd_bin_put_i64(b, series_len);
    sd_bin_put_i64(b, traj_len);
    /* the VTK series so far (file names relative to the output directory) */
    int np = c->pvd_on ? (int)c->pvd.n : 0;
    sd_bin_put_i32(b, np);
    for (int k = 0; k < np; k++) {
        int32_t len = (int32_t)strlen(c->pvd.file[k]);
        sd_bin_put_f64(b, c->pvd.time[k]);
        sd_bin_put_i32(b, c->pvd.part[k]);
        sd_bin_put_i32(b, len);
        sd_bin_put(b, c->pvd.file[k], (size_t)len);
    }
}

typedef struct {
    long series_len, traj_len;
    double wall_before;
    int npvd;
    double *pvd_time;
    int *pvd_part;
    char **pvd_file;
} restored;

static void restored_free(restored *r)
{
    for (int k = 0; k < r->npvd; k++)
        free(r->pvd_file[k]);
    free(r->pvd_time);
    free(r->pvd_part);
    free(r->pvd_file);
    memset(r, 0, sizeof *r);
}

/* 0 on success; otherwise writes why to msg. */
static int state_unpack(run_ctx *c, const void *blob, size_t len, restored *r, char *msg, size_t msglen)
{
    memset(r, 0, sizeof *r);
    sd_bin_reader b;
    sd_bin_reader_init(&b, blob, len);
    char magic[8];
    sd_bin_get(&b, magic, 8);
    if (b.bad || memcmp(magic, BLOB_MAGIC, 8)) {
        snprintf(msg, msglen, "holds no run-driver state of this version (not written by 'sabodem run' at a flow end)");
        return -1;
    }
    uint64_t h = sd_bin_get_u64(&b);
    if (h != sd_scenario_branch_hash(c->s)) {
        snprintf(msg, msglen,
                 "was written for other scenario parameters than %s (a restart may change only the capture-phase keys:"
                 " dam.l_h, dam.l_v, dam.top_beam, dam.columns, dam.beams, phases.capture_limit, phases.quiet_time,"
                 " phases.ke_fraction, water.probe, water.h_d_floating)",
                 c->s->path);
        return -1;
    }
    c->phase = sd_bin_get_i32(&b);
    c->flow_ended = sd_bin_get_i32(&b);
    c->dam_built = sd_bin_get_i32(&b);
    c->n_passed = sd_bin_get_i32(&b);
    c->flow_len_done = sd_bin_get_i32(&b);
    c->n_snap = sd_bin_get_i32(&b);
    c->info.n_rough = sd_bin_get_i32(&b);
    c->info.n_spheres = sd_bin_get_i32(&b);
    c->info.n_logs = sd_bin_get_i32(&b);
    c->info.first_moving_gid = sd_bin_get_i32(&b);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        c->vol_total_class[k] = sd_bin_get_f64(&b);
    c->vol_total_logs = sd_bin_get_f64(&b);
    for (int k = 0; k < SD_MAX_CLASSES; k++)
        c->vol_passed_class[k] = sd_bin_get_f64(&b);
    c->vol_passed_logs = sd_bin_get_f64(&b);
    c->h_d = sd_bin_get_f64(&b);
    c->last_cross_time = sd_bin_get_f64(&b);
    c->ke_peak = sd_bin_get_f64(&b);
    c->dam_force_now = sd_bin_get_f64(&b);
    for (int k = 0; k < 4; k++)
        c->phase_end[k] = sd_bin_get_f64(&b);
    for (int k = 0; k < 4; k++)
        c->phase_wall[k] = sd_bin_get_f64(&b);
    c->flow_len = sd_bin_get_f64(&b);
    c->flow_q05 = sd_bin_get_f64(&b);
    c->flow_q95 = sd_bin_get_f64(&b);
    c->flow_front = sd_bin_get_f64(&b);
    c->flow_len_time = sd_bin_get_f64(&b);
    c->phase_t0 = sd_bin_get_f64(&b);
    r->wall_before = sd_bin_get_f64(&b);
    r->series_len = (long)sd_bin_get_i64(&b);
    r->traj_len = (long)sd_bin_get_i64(&b);
    int np = sd_bin_get_i32(&b);
    if (b.bad || np < 0 || (size_t)np > sd_bin_left(&b) / 16) {
        snprintf(msg, msglen, "run-driver state is truncated or malformed");
        return -1;
    }
    r->pvd_time = calloc((size_t)np + 1, sizeof(double));
    r->pvd_part = calloc((size_t)np + 1, sizeof(int));
    r->pvd_file = calloc((size_t)np + 1, sizeof(char *));
    if (!r->pvd_time || !r->pvd_part || !r->pvd_file) {
        snprintf(msg, msglen, "out of memory");
        restored_free(r);
        return -1;
    }
    for (int k = 0; k < np && !b.bad; k++) {
        r->pvd_time[k] = sd_bin_get_f64(&b);
        r->pvd_part[k] = sd_bin_get_i32(&b);
        int32_t l = sd_bin_get_i32(&b);
        if (b.bad || l <= 0 || l > 255 || (size_t)l > sd_bin_left(&b)) {
            b.bad = 1;
            break;
        }
        r->pvd_file[k] = malloc((size_t)l + 1);
        if (!r->pvd_file[k]) {
            b.bad = 1;
            break;
        }
        r->npvd = k + 1;
        sd_bin_get(&b, r->pvd_file[k], (size_t)l);
        r->pvd_file[k][l] = '\0';
        if (strchr(r->pvd_file[k], '/')) b.bad = 1;
    }
    if (b.bad || sd_bin_left(&b)) {
        snprintf(msg, msglen, "run-driver state is truncated or malformed");
        restored_free(r);
        return -1;
    }
    int ok = c->phase == PH_FLOW && c->flow_ended == 1 && c->dam_built == 0 && c->n_passed >= 0 && c->n_snap >= 0 &&
             r->series_len >= 0 && r->traj_len >= -1 && isfinite(c->phase_t0) && isfinite(c->h_d);
    if (!ok) {
        snprintf(msg, msglen, "is not a flow-end checkpoint of a flume run");
        restored_free(r);
        return -1;
    }
    return 0;
}

static void dir_of(const char *path, char *buf, size_t n)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(buf, n, ".");
    else if (slash == path)
        snprintf(buf, n, "/");
    else
        snprintf(buf, n, "%.*s", (int)(slash - path), path);
}

static int same_dir(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* dst := the first len bytes of src (len < 0: all of it); src and dst may be the same file. */
static int copy_prefix(const char *src, const char *dst, long len, char *msg, size_t msglen)
{
    FILE *f = fopen(src, "rb");
    if (!f) {
        snprintf(msg, msglen, "%s: cannot open: %s", src, strerror(errno));
        return -1;
    }
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    while (buf) {
        if (n == cap) {
            char *q = realloc(buf, cap * 2);
            if (!q) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = q;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0 || (len >= 0 && n >= (size_t)len)) break;
    }
    fclose(f);
    if (!buf) {
        snprintf(msg, msglen, "%s: out of memory", src);
        return -1;
    }
    if (len >= 0 && n < (size_t)len) {
        snprintf(msg, msglen,
                 "%s: %zu bytes, shorter than the %ld the checkpoint recorded (not the checkpoint's own output?)", src,
                 n, len);
        free(buf);
        return -1;
    }
    if (len >= 0) n = (size_t)len;
    char tmp[1400];
    snprintf(tmp, sizeof tmp, "%s.tmp", dst);
    FILE *g = fopen(tmp, "wb");
    int bad = !g || fwrite(buf, 1, n, g) != n;
    if (g && fclose(g)) bad = 1;
    if (!bad && rename(tmp, dst)) bad = 1;
    free(buf);
    if (bad) {
        snprintf(msg, msglen, "%s: cannot write: %s", dst, strerror(errno));
        unlink(tmp);
        return -1;
    }
    return 0;
}

/* The outputs of packing and flow continue in the new run's directory: the time series up to
 * the checkpoint (the recorded lengths) and, when the checkpoint lives elsewhere, the VTK
 * files listed in the series. */
static int restore_outputs(run_ctx *c, const restored *r, char *msg, size_t msglen)
{
    char src[1100], a[1300], b[1300];
    dir_of(c->restarted_from, src, sizeof src);
    snprintf(a, sizeof a, "%s/series.csv", src);
    snprintf(b, sizeof b, "%s/series.csv", c->dir);
    if (copy_prefix(a, b, r->series_len, msg, msglen)) return -1;
    if (c->s->n_traj > 0 && r->traj_len >= 0) {
        snprintf(a, sizeof a, "%s/trajectories.csv", src);
        snprintf(b, sizeof b, "%s/trajectories.csv", c->dir);
        if (copy_prefix(a, b, r->traj_len, msg, msglen)) return -1;
    }
    if (c->s->vtk_on && !same_dir(src, c->dir)) {
        for (int k = -1; k < r->npvd; k++) {
            const char *name = k < 0 ? "walls.vtp" : r->pvd_file[k];
            snprintf(a, sizeof a, "%s/%s", src, name);
            snprintf(b, sizeof b, "%s/%s", c->dir, name);
            char why[1400];
            if (copy_prefix(a, b, -1, why, sizeof why) && c->o->log)
                fprintf(c->o->log, "note: %s (the VTK series of the new run lacks it)\n", why);
        }
    }
    return 0;
}

static sd_status checkpoint_flow_end(run_ctx *c, const char *path)
{
    long sl = file_len(c->series), tl = c->traj ? file_len(c->traj) : -1;
    if (sl < 0 || (c->traj && tl < 0)) return SD_ERR_IO;
    sd_bin_writer b;
    sd_bin_writer_init(&b);
    state_pack(c, &b, sl, tl);
    sd_status st = b.err ? SD_ERR_NOMEM : sd_checkpoint_write(path, c->w, b.p, b.n);
    sd_bin_writer_fini(&b);
    return st;
}

/* ---------------------------------------------------------------- the run ---- */

static void close_outputs(run_ctx *c)
{
    if (c->series) fclose(c->series);
    if (c->traj) fclose(c->traj);
    if (c->pvd_on) sd_vtk_series_free(&c->pvd);
    c->series = c->traj = NULL;
    c->pvd_on = 0;
}

int sd_run_scenario(const sd_scenario *s, const sd_run_opts *o, sd_run_result *res)
{
    run_ctx c;
    memset(&c, 0, sizeof c);
    memset(res, 0, sizeof(*res));
    c.s = s;
    c.o = o;
    c.wall0 = sd_now();
    sd_status st;
    restored rs;
    memset(&rs, 0, sizeof rs);
    if (o->restart) {
        if (!s->flume_on) {
            fprintf(o->err, "%s: a restart needs a flume scenario (flume.on)\n", s->path);
            return 2;
        }
        char msg[1600];
        void *blob = NULL;
        size_t blen = 0;
        st = sd_checkpoint_read(o->restart, &c.w, &blob, &blen, msg, sizeof msg);
        if (st) {
            fprintf(o->err, "%s\n", msg[0] ? msg : sd_status_message(st));
            return 2;
        }
        int bad = state_unpack(&c, blob, blen, &rs, msg, sizeof msg);
        free(blob);
        if (bad) {
            fprintf(o->err, "%s: %s\n", o->restart, msg);
            sd_world_destroy(c.w);
            return 2;
        }
        /* the thread count is the caller's (the bits do not depend on it) */
        int threads = s->world.threads;
#ifdef _OPENMP
        if (threads <= 0) threads = omp_get_max_threads();
#endif
        if (threads > 0) sd_world_set_threads(c.w, threads);
        sd_world_set_tuning(c.w, &s->world.tuning); /* (and how it runs, too) */
        c.restarted_from = o->restart;
        c.flow_wall = rs.wall_before;
    } else {
        st = sd_world_create(&s->world, &c.w);
        if (st) {
            fprintf(o->err, "%s: %s\n", s->path, sd_status_message(st));
            return 2;
        }
        /* without the dam pipes: they go in at the start of the capture phase (capture_start) */
        st = sd_build_scene_ex(c.w, s, &c.info, o->err, 0);
        if (!st) st = sd_world_check(c.w);
        if (st) {
            if (st == SD_ERR_UNSTABLE)
                fprintf(o->err, "%s: solver.dt: %s\n", s->path, sd_status_message(st));
            else
                fprintf(o->err, "%s: cannot build the scene: %s\n", s->path, sd_status_message(st));
            sd_world_destroy(c.w);
            return 2;
        }
    }
    /* only now, with valid input, does the output directory appear */
    snprintf(c.dir, sizeof c.dir, "%s", o->outdir);
    if (sd_mkdir_p(c.dir)) {
        fprintf(o->err, "%s: cannot create output directory: %s\n", c.dir, strerror(errno));
        restored_free(&rs);
        sd_world_destroy(c.w);
        return 2;
    }
    if (c.restarted_from) {
        char msg[1600];
        if (restore_outputs(&c, &rs, msg, sizeof msg)) {
            fprintf(o->err, "%s: cannot continue the outputs of %s: %s\n", c.dir, o->restart, msg);
            restored_free(&rs);
            sd_world_destroy(c.w);
            return 1;
        }
    }
    char path[1200];
    const char *mode = c.restarted_from ? "a" : "w";
    snprintf(path, sizeof path, "%s/series.csv", c.dir);
    c.series = fopen(path, mode);
    if (c.series && !c.restarted_from)
        fprintf(c.series,
                "t,phase,front_x,volume_upstream_m3,kinetic_energy_J,contacts,dam_force_N,p_v,h_d,elements,passed\n");
    if (s->n_traj > 0) {
        snprintf(path, sizeof path, "%s/trajectories.csv", c.dir);
        c.traj = fopen(path, mode);
        if (c.traj && !c.restarted_from) fprintf(c.traj, "t,id,x,y,z,vx,vy,vz,wx,wy,wz,ax,ay,az,fx,fy,fz\n");
    }
    int pvd_bad = 0;
    if (s->vtk_on) {
        snprintf(path, sizeof path, "%s/series.pvd", c.dir);
        c.pvd_on = sd_vtk_series_init(&c.pvd, path) == 0;
        for (int k = 0; c.pvd_on && k < rs.npvd; k++)
            if (sd_vtk_series_add(&c.pvd, rs.pvd_time[k], rs.pvd_part[k], rs.pvd_file[k])) pvd_bad = 1;
    }
    restored_free(&rs);
    if (!c.series || (s->n_traj > 0 && !c.traj) || (s->vtk_on && !c.pvd_on) || pvd_bad ||
        (!c.restarted_from && write_walls(&c))) {
        fprintf(o->err, "%s: cannot write output files: %s\n", c.dir, strerror(errno));
        close_outputs(&c);
        sd_world_destroy(c.w);
        return 1;
    }
    const sd_body_view bv = sd_world_bodies(c.w), *b = &bv;
    const double dt = s->world.dt;
    if (!c.restarted_from) {
        for (int i = 0; i < b->n; i++) {
            if (b->fixed[i]) continue;
            if (b->shape[i] == SD_SHAPE_CYLINDER)
                c.vol_total_logs += body_volume(b, i);
            else if (b->tag[i] >= 0 && b->tag[i] < SD_MAX_CLASSES)
                c.vol_total_class[b->tag[i]] += body_volume(b, i);
        }
        c.phase = s->flume_on ? PH_PACK : PH_RUN;
        c.h_d = s->water_h;
        c.phase_t0 = 0.0;
    }
    c.phase_w0 = sd_now();
    long log_every = (long)llround(s->log_interval / dt);
    if (log_every < 1) log_every = 1;
    long traj_every = (long)llround(s->traj_interval / dt);
    if (traj_every < 1) traj_every = 1;
    long snap_every = s->snapshot_interval > 0 ? (long)llround(s->snapshot_interval / dt) : 0;
    long progress_every = 2000;
    double t_end_est = s->flume_on ? s->packing_time + 4.0 + s->capture_limit : s->duration;
    int code = 0;
    const char *msg = "finished";
    if (!c.restarted_from) {
        snapshot(&c, "initial");
        write_series_row(&c);
        write_traj(&c);
    }
    c.rate_step0 = sd_world_step_count(c.w);
    c.rate_wall0 = sd_now();
    for (;;) {
        if (o->stop && *o->stop) {
            code = 130;
            msg = "interrupted";
            res->interrupted = 1;
            break;
        }
        if (c.phase == PH_RUN && sd_world_time(c.w) >= s->duration - 0.5 * dt) break;
        if (c.phase == PH_DONE) break;
        if (c.flow_ended && !c.dam_built) {
            /* the branch point: a flow-end checkpoint holds the state of exactly this moment, and
             * a restart from it comes in here, so both go through capture_start alike */
            if (o->checkpoint_flow_end && !c.restarted_from) {
                st = checkpoint_flow_end(&c, o->checkpoint_flow_end);
                if (st) {
                    fprintf(o->err, "%s: cannot write the flow-end checkpoint: %s (%s)\n", o->checkpoint_flow_end,
                            sd_status_message(st), strerror(errno));
                    code = 1;
                    msg = "checkpoint failed";
                    break;
                }
                if (o->log && !o->progress_tty)
                    fprintf(o->log, "flow-end checkpoint %s written at t = %.4f s\n", o->checkpoint_flow_end,
                            sd_world_time(c.w));
            }
            if (o->stop_at_flow_end) {
                res->stopped_at_flow_end = 1;
                msg = "stopped at the flow end";
                break;
            }
            st = capture_start(&c);
            if (st) {
                fprintf(o->err, "%s: cannot add the dam pipes: %s\n", s->path, sd_status_message(st));
                code = 1;
                msg = sd_status_message(st);
                break;
            }
        }
        set_fluid(&c);
        st = sd_world_step(c.w);
        if (st) {
            fprintf(o->err, "%s: step %ld, t = %.6f s: %s\n", s->path, sd_world_step_count(c.w), sd_world_time(c.w), sd_status_message(st));
            code = 1;
            msg = sd_status_message(st);
            break;
        }
        long step = sd_world_step_count(c.w);
        if (c.info.n_pipes) accumulate_pipes(&c);
        int next = c.phase;
        if (s->flume_on && step % 100 == 0) {
            int before = c.n_passed;
            remove_passed(&c);
            double tph = sd_world_time(c.w) - c.phase_t0;
            if (sd_run_crossing(c.w, x_trap(&c))) c.last_cross_time = sd_world_time(c.w);
            if (c.n_passed != before) c.last_cross_time = sd_world_time(c.w);
            if (c.phase == PH_PACK) {
                if (tph >= s->packing_time - 0.5 * dt) next = PH_FLOW;
            } else if (c.phase == PH_CAPTURE) {
                update_h_d(&c);
                double ke = upstream_ke(&c);
                if (ke > c.ke_peak) c.ke_peak = ke;
                int quiet = sd_world_time(c.w) - c.last_cross_time >= s->quiet_time && ke < s->ke_fraction * c.ke_peak;
                if (tph >= s->capture_limit || (tph > s->quiet_time && quiet)) next = PH_DONE;
            }
        }
        if (c.phase == PH_FLOW && !c.flow_ended) {
            /* checked at every step, so that the front has moved less than one step's travel
             * (~v dt) past the dam face when the pipes appear (docs/physics.md) */
            double fx = front_x(&c), tph = sd_world_time(c.w) - c.phase_t0;
            if (step % 100 == 0 && !c.flow_len_done && s->x_dam - 1.0 > s->x_gate && fx >= s->x_dam - 1.0)
                measure_flow_length(&c);
            if (fx >= s->x_dam || tph >= s->flow_limit) next = PH_CAPTURE;
        }
        if (next != c.phase) {
            c.phase_end[c.phase] = sd_world_time(c.w);
            c.phase_wall[c.phase] = sd_now() - c.phase_w0;
            c.phase_w0 = sd_now();
            if (o->log && !o->progress_tty)
                fprintf(o->log, "phase %s ended at t = %.4f s (max speed %.4f m/s)\n", phase_names[c.phase], sd_world_time(c.w),
                        max_speed(&c));
            if (c.phase == PH_PACK) {
                sd_world_set_group_active(c.w, SD_GROUP_GATE, 0);
                snapshot(&c, "packed");
                c.phase_t0 = sd_world_time(c.w);
                c.phase = next;
            } else if (next == PH_CAPTURE) {
                /* the capture (pipes, capture fluid) starts at the top of the next iteration */
                c.flow_ended = 1;
                c.flow_wall = sd_now() - c.wall0; /* the build included */
            } else {
                c.phase_t0 = sd_world_time(c.w);
                c.phase = next;
            }
        }
        if (step % log_every == 0) write_series_row(&c);
        if (c.traj && step % traj_every == 0) write_traj(&c);
        if (snap_every && step % snap_every == 0) {
            char name[64];
            snprintf(name, sizeof name, "%06d", c.n_snap);
            snapshot(&c, name);
        }
        if (step % progress_every == 0) progress(&c, t_end_est);
    }
    if (o->log && o->progress_tty) fputc('\n', o->log);
    if (res->stopped_at_flow_end) {
        /* a shared flow: its outputs end at the checkpoint, which the branches continue */
        close_outputs(&c);
    } else {
        if (c.phase != PH_DONE && c.phase != PH_RUN && !c.flow_ended) {
            c.phase_end[c.phase] = sd_world_time(c.w);
            c.phase_wall[c.phase] = sd_now() - c.phase_w0;
        } else if (c.phase == PH_CAPTURE) {
            c.phase_end[c.phase] = sd_world_time(c.w);
            c.phase_wall[c.phase] = sd_now() - c.phase_w0;
        }
        write_series_row(&c);
        snapshot(&c, "final");
        if (s->flume_on && code == 0) plot(&c, "final", "side_final.png", s->x_dam - 1.0, s->x_end);
        fclose(c.series);
        c.series = NULL;
        if (c.traj) fclose(c.traj);
        c.traj = NULL;
        if (c.pvd_on) {
            sd_vtk_series_flush(&c.pvd);
            sd_vtk_series_free(&c.pvd);
            c.pvd_on = 0;
        }
    }
    if (write_summary(&c, res, code, msg)) {
        fprintf(o->err, "%s: cannot write summary.json: %s\n", c.dir, strerror(errno));
        if (!code) code = 1;
    }
    res->n_passed = c.n_passed;
    for (int k = 0; k < c.info.n_pipes; k++)
        res->peak_dam_force = fmax(res->peak_dam_force, c.pipe_peak[k]);
    res->steps = sd_world_step_count(c.w);
    res->wall_time = sd_now() - c.wall0;
    res->n_pictures = c.n_plots;
    memcpy(res->pictures, c.plots, (size_t)c.n_plots * sizeof c.plots[0]);
    res->flow_wall = c.flow_wall;
    res->restarted = c.restarted_from != NULL;
    res->state_hash = sd_world_state_hash(c.w);
    for (int k = 0; k < 4; k++)
        res->phase_end[k] = c.phase_end[k];
    sd_world_destroy(c.w);
    return code;
}

int sd_run_check_restart(const sd_scenario *s, const char *path, char *msg, size_t msglen)
{
    sd_world *w = NULL;
    void *blob = NULL;
    size_t len = 0;
    char m[1600];
    sd_status st = sd_checkpoint_read(path, &w, &blob, &len, m, sizeof m);
    if (st) {
        snprintf(msg, msglen, "%s", m[0] ? m : sd_status_message(st));
        return -1;
    }
    run_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    restored r;
    int bad = state_unpack(&c, blob, len, &r, m, sizeof m);
    free(blob);
    sd_world_destroy(w);
    if (bad) {
        snprintf(msg, msglen, "%s: %s", path, m);
        return -1;
    }
    restored_free(&r);
    return 0;
}
