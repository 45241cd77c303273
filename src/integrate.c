/* Leapfrog (SPEC §2, eqs 7–9): v ← v + (F/m)Δt, x ← x + vΔt, the velocity lagging half a step.
 * Rotation of cylinders on the world-frame angular momentum: L ← L + TΔt, then the exact
 * torque-free motion of an axisymmetric body over Δt, which is a rotation about L by
 * |L|Δt/I_tr (space) composed with a spin about the body axis by (1/I_ax − 1/I_tr)(L·a)Δt
 * (body). That keeps L·a and the kinetic energy of a free log exact, where the plain update
 * q ← exp(ωΔt) q drifts at O(Δt) (see docs/physics.md). Spheres: ω ← ω + TΔt/I. */
#include "core/simd.h"
#include "world_internal.h"

#include <string.h>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#define SD_MOVE256 1 /* (core/simd.h has included immintrin.h) */
#endif

#ifdef _OPENMP
#include <omp.h>
#endif

/* the groups of four spheres moved in lanes (move_block256), by this thread (tests) */
static _Thread_local long move_lanes_groups;

long sd_integrate_lanes_count(void) { return move_lanes_groups; }

/* A log's rotation and its rebuild bounds (out of line, so that the sphere loop keeps its
 * running maxima in registers): returns the x of its downstream end. */
static __attribute__((noinline)) double cyl_step(sd_bodies *b, int i, double dt, double lim2, int *moved, double *dc)
{
    sd_vec3 L = v3_madd(b->angmom[i], b->torque[i], dt);
    b->angmom[i] = L;
    sd_vec3 a = b->axis[i];
    const sd_vec3 a_old = a;
    double spin = (b->inv_i_ax[i] - b->inv_i_tr[i]) * v3_dot(L, a) * dt;
    sd_quat q_body = quat_from_rotvec(v3(0.0, 0.0, spin));
    sd_quat q_space = quat_from_rotvec(v3_scale(L, b->inv_i_tr[i] * dt));
    sd_quat q = quat_normalize(quat_mul(q_space, quat_mul(b->quat[i], q_body)));
    b->quat[i] = q;
    a = quat_rotate(q, v3(0.0, 0.0, 1.0));
    b->axis[i] = a;
    /* ω = A I⁻¹ Aᵀ L for an axisymmetric inertia */
    b->omega[i] = v3_madd(v3_scale(L, b->inv_i_tr[i]), a, (b->inv_i_ax[i] - b->inv_i_tr[i]) * v3_dot(L, a));
    double d = sqrt(v3_norm2(v3_sub(b->pos[i], b->pos_ref[i]))) + b->hl[i] * sqrt(v3_norm2(v3_sub(a, b->axis_ref[i])));
    *moved |= d * d > lim2;
    /* how far its surface can have gone this step: the centre's move plus the tilt of the axis
     * times the bounding radius (with room for chord against arc); the spin about the axis
     * moves no surface */
    const double step = sqrt(v3_norm2(b->vel[i])) * dt + 1.01 * b->bound_r[i] * sqrt(v3_norm2(v3_sub(a, a_old)));
    *dc = step > *dc ? step : *dc;
    return b->pos[i].x + sd_body_x_extent(b, i);
}

/* The logs' moves in batches: cyl_step's operations, in its order, lane by lane over the
 * logs of a batch held field by field, so that the compiler runs them in SIMD lanes (its
 * divisions and square roots, each waited for in turn by one log, overlap across logs); the
 * sines and cosines one by one, as cyl_step calls them. The same bits as cyl_step: IEEE
 * operations give the same result in a lane as alone, and nothing is contracted. */
#define CYL_BATCH 32
typedef struct {
    /* in: angular momentum, torque, axis (before), orientation (before, then after),
     * inverse inertias, centre less its rebuild reference, axis at the rebuild, half length,
     * bounding radius, |v|^2 */
    double mx[CYL_BATCH], my[CYL_BATCH], mz[CYL_BATCH], tx[CYL_BATCH], ty[CYL_BATCH], tz[CYL_BATCH];
    double ax[CYL_BATCH], ay[CYL_BATCH], az[CYL_BATCH];
    double qw[CYL_BATCH], qx[CYL_BATCH], qy[CYL_BATCH], qz[CYL_BATCH];
    double iax[CYL_BATCH], itr[CYL_BATCH], dx[CYL_BATCH], dy[CYL_BATCH], dz[CYL_BATCH];
    double rx[CYL_BATCH], ry[CYL_BATCH], rz[CYL_BATCH], hl[CYL_BATCH], br[CYL_BATCH], v2[CYL_BATCH];
    /* the body spin (about the axis) and the space rotation vector, their angles, and the sine
     * and cosine of half of each */
    double spin[CYL_BATCH], angb[CYL_BATCH], px[CYL_BATCH], py[CYL_BATCH], pz[CYL_BATCH], angs[CYL_BATCH];
    double sinb[CYL_BATCH], cosb[CYL_BATCH], sins[CYL_BATCH], coss[CYL_BATCH];
    /* out: the new axis, spin vector, (the drift bound)^2 and the surface's step */
    double nx[CYL_BATCH], ny[CYL_BATCH], nz[CYL_BATCH], ox[CYL_BATCH], oy[CYL_BATCH], oz[CYL_BATCH];
    double d2[CYL_BATCH], step[CYL_BATCH];
} cyl_batch;

/* cyl_step up to its rotation vectors and their angles (quat_from_rotvec's v3_norm) */
SD_SIMD_CLONES
static void cyl_batch_angles(cyl_batch *restrict c, int n, double dt)
{
    for (int j = 0; j < n; j++) {
        const sd_vec3 L = v3_madd(v3(c->mx[j], c->my[j], c->mz[j]), v3(c->tx[j], c->ty[j], c->tz[j]), dt);
        c->mx[j] = L.x, c->my[j] = L.y, c->mz[j] = L.z;
        const double spin = (c->iax[j] - c->itr[j]) * v3_dot(L, v3(c->ax[j], c->ay[j], c->az[j])) * dt;
        c->spin[j] = spin;
        c->angb[j] = v3_norm(v3(0.0, 0.0, spin));
        const sd_vec3 phi = v3_scale(L, c->itr[j] * dt);
        c->px[j] = phi.x, c->py[j] = phi.y, c->pz[j] = phi.z;
        c->angs[j] = v3_norm(phi);
    }
}

/* quat_from_rotvec from the angle ang of the rotation vector (x, y, z), given the sine sn and
 * cosine cs of its half: both of its branches, then the one it takes */
static inline void rotvec_quat(double x, double y, double z, double ang, double sn, double cs, double *w, double *qx,
                               double *qy, double *qz)
{
    const double s = sn / ang;
    const double tw = 1.0 - ang * ang / 8.0, tx = 0.5 * x, ty = 0.5 * y, tz = 0.5 * z;
    const double tn = sqrt(tw * tw + tx * tx + ty * ty + tz * tz);
    const int tiny = ang < 1e-12;
    *w = tiny ? tw / tn : cs;
    *qx = tiny ? tx / tn : x * s;
    *qy = tiny ? ty / tn : y * s;
    *qz = tiny ? tz / tn : z * s;
}

/* the rest of cyl_step, with its own vmath calls: the orientation, axis and spin vector, the
 * drift bound and the step */
SD_SIMD_CLONES
static void cyl_batch_turn(cyl_batch *restrict c, int n, double dt)
{
    for (int j = 0; j < n; j++) {
        sd_quat qb, qs;
        rotvec_quat(0.0, 0.0, c->spin[j], c->angb[j], c->sinb[j], c->cosb[j], &qb.w, &qb.x, &qb.y, &qb.z);
        rotvec_quat(c->px[j], c->py[j], c->pz[j], c->angs[j], c->sins[j], c->coss[j], &qs.w, &qs.x, &qs.y, &qs.z);
        const sd_quat q0 = {c->qw[j], c->qx[j], c->qy[j], c->qz[j]};
        const sd_quat q = quat_normalize(quat_mul(qs, quat_mul(q0, qb)));
        c->qw[j] = q.w, c->qx[j] = q.x, c->qy[j] = q.y, c->qz[j] = q.z;
        const sd_vec3 a = quat_rotate(q, v3(0.0, 0.0, 1.0));
        c->nx[j] = a.x, c->ny[j] = a.y, c->nz[j] = a.z;
        const sd_vec3 L = v3(c->mx[j], c->my[j], c->mz[j]);
        const double itr = c->itr[j];
        const sd_vec3 om = v3_madd(v3_scale(L, itr), a, (c->iax[j] - itr) * v3_dot(L, a));
        c->ox[j] = om.x, c->oy[j] = om.y, c->oz[j] = om.z;
        const double d = sqrt(v3_norm2(v3(c->dx[j], c->dy[j], c->dz[j]))) +
                         c->hl[j] * sqrt(v3_norm2(v3_sub(a, v3(c->rx[j], c->ry[j], c->rz[j]))));
        c->d2[j] = d * d;
        c->step[j] = sqrt(c->v2[j]) * dt + 1.01 * c->br[j] * sqrt(v3_norm2(v3_sub(a, v3(c->ax[j], c->ay[j], c->az[j]))));
    }
}

/* cyl_step for the logs lg[0 .. n) (body indices; their centres already moved), in batches;
 * returns the largest x of their downstream ends. */
static double cyl_steps(sd_bodies *b, const int32_t *lg, int n, double dt, double lim2, int *moved, double *dc)
{
    cyl_batch c;
    double xf = -INFINITY;
    for (int k0 = 0; k0 < n; k0 += CYL_BATCH) {
        const int m = n - k0 < CYL_BATCH ? n - k0 : CYL_BATCH;
        for (int j = 0; j < m; j++) {
            const int i = lg[k0 + j];
            c.mx[j] = b->angmom[i].x, c.my[j] = b->angmom[i].y, c.mz[j] = b->angmom[i].z;
            c.tx[j] = b->torque[i].x, c.ty[j] = b->torque[i].y, c.tz[j] = b->torque[i].z;
            c.ax[j] = b->axis[i].x, c.ay[j] = b->axis[i].y, c.az[j] = b->axis[i].z;
            c.qw[j] = b->quat[i].w, c.qx[j] = b->quat[i].x, c.qy[j] = b->quat[i].y, c.qz[j] = b->quat[i].z;
            c.iax[j] = b->inv_i_ax[i], c.itr[j] = b->inv_i_tr[i];
            const sd_vec3 d = v3_sub(b->pos[i], b->pos_ref[i]);
            c.dx[j] = d.x, c.dy[j] = d.y, c.dz[j] = d.z;
            c.rx[j] = b->axis_ref[i].x, c.ry[j] = b->axis_ref[i].y, c.rz[j] = b->axis_ref[i].z;
            c.hl[j] = b->hl[i], c.br[j] = b->bound_r[i], c.v2[j] = v3_norm2(b->vel[i]);
        }
        cyl_batch_angles(&c, m, dt);
        for (int j = 0; j < m; j++) { /* (one sincos call each, as cyl_step's) */
            c.sinb[j] = sin(0.5 * c.angb[j]), c.cosb[j] = cos(0.5 * c.angb[j]);
            c.sins[j] = sin(0.5 * c.angs[j]), c.coss[j] = cos(0.5 * c.angs[j]);
        }
        cyl_batch_turn(&c, m, dt);
        for (int j = 0; j < m; j++) {
            const int i = lg[k0 + j];
            b->angmom[i] = v3(c.mx[j], c.my[j], c.mz[j]);
            b->quat[i] = (sd_quat){c.qw[j], c.qx[j], c.qy[j], c.qz[j]};
            b->axis[i] = v3(c.nx[j], c.ny[j], c.nz[j]);
            b->omega[i] = v3(c.ox[j], c.oy[j], c.oz[j]);
            *moved |= c.d2[j] > lim2;
            *dc = c.step[j] > *dc ? c.step[j] : *dc;
            const double x = b->pos[i].x + sd_body_x_extent(b, i);
            xf = x > xf ? x : xf;
        }
    }
    return xf;
}

/* One body's move (move_block's loop body): e its external force. A log's centre moves here,
 * its turning is left to the caller (its index appended to lg). */
static inline __attribute__((always_inline)) void move_one(int i, sd_vec3 e, double dt, sd_vec3 g,
                                                           const sd_vec3 *restrict force,
                                                           const double *restrict inv_mass, sd_vec3 *restrict vel,
                                                           sd_vec3 *restrict pos, sd_vec3 *restrict omega,
                                                           const sd_vec3 *restrict torque,
                                                           const double *restrict inv_i_ax,
                                                           const double *restrict radius,
                                                           const uint8_t *restrict shape, double *vm, double *xf,
                                                           int32_t *restrict lg, int *nlg)
{
    const sd_vec3 f = v3_add(force[i], e);
    const sd_vec3 acc = v3_madd(g, f, inv_mass[i]);
    /* the new velocity and centre kept in registers, not read back from the store right
     * after being written (x and y by one 16-byte store): on AMD Zen 3 a tenth of this
     * loop's samples sat on the read of y, as if it waited for the store. The same values
     * either way. */
    const sd_vec3 vn = v3_madd(vel[i], acc, dt);
    const sd_vec3 pn = v3_madd(pos[i], vn, dt);
    vel[i] = vn;
    pos[i] = pn;
    if (shape[i] == SD_SHAPE_SPHERE) {
        omega[i] = v3_madd(omega[i], torque[i], dt * inv_i_ax[i]);
        /* a sphere's displacement since the rebuild is bounded by the summed largest |v| dt
         * (sd_integrate_after_moves checks it exactly only when that bound nears half the
         * margin) */
        const double v2 = v3_norm2(vn);
        *vm = v2 > *vm ? v2 : *vm;
        const double x = pn.x + radius[i];
        *xf = x > *xf ? x : *xf;
    } else {
        lg[(*nlg)++] = i;
    }
}

/* The moves of a block's spheres, and the centres of its logs (their turning left to the
 * caller: their indices appended to lg, whose new count is returned). The arrays through
 * restrict parameters: through b, gcc loaded each array's address again after every store
 * (the loop's hottest samples sat on those loads). */
static inline int move_block(const int32_t *restrict mov, int kb, int ke, double dt, sd_vec3 g,
                             const sd_vec3 *restrict force, const sd_vec3 *restrict ext,
                             const double *restrict inv_mass, sd_vec3 *restrict vel, sd_vec3 *restrict pos,
                             sd_vec3 *restrict omega, const sd_vec3 *restrict torque,
                             const double *restrict inv_i_ax, const double *restrict radius,
                             const uint8_t *restrict shape, double *vmax, double *xfront, int32_t *restrict lg,
                             int nlg, const int ext_blk)
{
    double vm = *vmax, xf = *xfront;
    for (int k = kb; k < ke; k++) {
        const int i = mov[k];
        /* the external force from the block's buffer (ext_blk: ext[k - kb]), the store's, or
         * none set (ext NULL: a zero, added all the same) */
        move_one(i, ext ? ext[ext_blk ? k - kb : i] : v3(0.0, 0.0, 0.0), dt, g, force, inv_mass, vel, pos, omega,
                 torque, inv_i_ax, radius, shape, &vm, &xf, lg, &nlg);
    }
    *vmax = vm;
    *xfront = xf;
    return nlg;
}

#ifdef SD_MOVE256
/* move_block in AVX2 lanes, for four spheres at a time that sit next to each other in the store
 * (i .. i + 3, the moving bodies' usual order): their rows of 3 doubles make 12 doubles in a
 * row, three 256-bit registers, and the moves are the same operations on each element (the
 * per-body factors 1/m and Δt/I spread to the elements by permutes); |v|^2 and the front take
 * the rows apart into x, y, z lanes. The same bits as move_one: the same IEEE operations in
 * the same order, nothing contracted, and maxima taken in any order give the same maximum.
 * Any other body (a log, a fixed body between, a block's last 1-3) goes through move_one. */
__attribute__((target("avx2"))) static int move_block256(const int32_t *restrict mov, int kb, int ke, double dt,
                                                         sd_vec3 g, const sd_vec3 *restrict force,
                                                         const sd_vec3 *restrict ext, const double *restrict inv_mass,
                                                         sd_vec3 *restrict vel, sd_vec3 *restrict pos,
                                                         sd_vec3 *restrict omega, const sd_vec3 *restrict torque,
                                                         const double *restrict inv_i_ax,
                                                         const double *restrict radius, const uint8_t *restrict shape,
                                                         double *vmax, double *xfront, int32_t *restrict lg,
                                                         int nlg, const int ext_blk)
{
    double vm = *vmax, xf = *xfront;
    const __m256d vdt = _mm256_set1_pd(dt), zero = _mm256_setzero_pd();
    /* g spread over the rows' elements: x y z x | y z x y | z x y z */
    const __m256d g0 = _mm256_setr_pd(g.x, g.y, g.z, g.x), g1 = _mm256_setr_pd(g.y, g.z, g.x, g.y),
                  g2 = _mm256_setr_pd(g.z, g.x, g.y, g.z);
    __m256d vm4 = _mm256_set1_pd(-INFINITY), xf4 = vm4;
    const uint32_t four = 0x01010101u * SD_SHAPE_SPHERE;
    int ones = 0; /* the bodies moved one by one (the rest in groups: no count in the lanes' path) */
    for (int k = kb; k < ke; k++) {
        const int i = mov[k];
        /* four bodies side by side in the store (mov ascends, so mov[k + 3] == i + 3 says it),
         * then four spheres (their shape bytes as one word: SD_SHAPE_SPHERE is 0, so the word
         * is read only once the four are known to be there) */
        int group = k + 4 <= ke && mov[k + 3] == i + 3;
        if (group) {
            uint32_t sh;
            memcpy(&sh, shape + i, sizeof sh);
            group = sh == four;
        }
        if (!group) {
            move_one(i, ext ? ext[ext_blk ? k - kb : i] : v3(0.0, 0.0, 0.0), dt, g, force, inv_mass, vel, pos, omega,
                     torque, inv_i_ax, radius, shape, &vm, &xf, lg, &nlg);
            ones++;
            continue;
        }
        const double *fp = &force[i].x, *ep = ext ? &ext[ext_blk ? k - kb : i].x : NULL;
        double *vp = &vel[i].x, *pp = &pos[i].x, *op = &omega[i].x;
        const double *tp = &torque[i].x;
        /* 1/m and Δt/I of bodies 0..3 spread as b0 b0 b0 b1 | b1 b1 b2 b2 | b2 b3 b3 b3 */
        const __m256d im = _mm256_loadu_pd(inv_mass + i);
        const __m256d sa = _mm256_mul_pd(vdt, _mm256_loadu_pd(inv_i_ax + i));
        const __m256d m0 = _mm256_permute4x64_pd(im, 0x40), m1 = _mm256_permute4x64_pd(im, 0xA5),
                      m2 = _mm256_permute4x64_pd(im, 0xFE);
        const __m256d s0 = _mm256_permute4x64_pd(sa, 0x40), s1 = _mm256_permute4x64_pd(sa, 0xA5),
                      s2 = _mm256_permute4x64_pd(sa, 0xFE);
        __m256d v[3], p[3];
        const __m256d m[3] = {m0, m1, m2}, s[3] = {s0, s1, s2}, gg[3] = {g0, g1, g2};
        for (int r = 0; r < 3; r++) {
            const __m256d f = _mm256_add_pd(_mm256_loadu_pd(fp + 4 * r), ep ? _mm256_loadu_pd(ep + 4 * r) : zero);
            const __m256d acc = _mm256_add_pd(gg[r], _mm256_mul_pd(m[r], f));
            v[r] = _mm256_add_pd(_mm256_loadu_pd(vp + 4 * r), _mm256_mul_pd(vdt, acc));
            p[r] = _mm256_add_pd(_mm256_loadu_pd(pp + 4 * r), _mm256_mul_pd(vdt, v[r]));
            _mm256_storeu_pd(vp + 4 * r, v[r]);
            _mm256_storeu_pd(pp + 4 * r, p[r]);
            const __m256d om =
                _mm256_add_pd(_mm256_loadu_pd(op + 4 * r), _mm256_mul_pd(s[r], _mm256_loadu_pd(tp + 4 * r)));
            _mm256_storeu_pd(op + 4 * r, om);
        }
        __m256d vx, vy, vz, px, py, pz;
        sd_rows3_lanes(v[0], v[1], v[2], &vx, &vy, &vz);
        const __m256d v2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, vx), _mm256_mul_pd(vy, vy)),
                                         _mm256_mul_pd(vz, vz));
        vm4 = _mm256_max_pd(v2, vm4); /* v2 > vm4 ? v2 : vm4, as move_one */
        sd_rows3_lanes(p[0], p[1], p[2], &px, &py, &pz);
        (void)py, (void)pz; /* (compiled away) */
        xf4 = _mm256_max_pd(_mm256_add_pd(px, _mm256_loadu_pd(radius + i)), xf4);
        k += 3;
    }
    move_lanes_groups += (ke - kb - ones) / 4;
    double l[8];
    _mm256_storeu_pd(l, vm4);
    _mm256_storeu_pd(l + 4, xf4);
    for (int j = 0; j < 4; j++) {
        vm = l[j] > vm ? l[j] : vm;
        xf = l[4 + j] > xf ? l[4 + j] : xf;
    }
    *vmax = vm;
    *xfront = xf;
    return nlg;
}
#endif

int sd_integrate_list(sd_world *w, const int32_t *mov, int k0, int k1, sd_moves *mm)
{
    sd_bodies *b = &w->b;
    const double dt = w->def.dt;
    const sd_vec3 g = w->def.gravity;
    const double lim2 = 0.25 * w->def.margin * w->def.margin;
    int moved = 0;
    double vm = mm->v2, dc = mm->dc, xf = mm->xf;
    /* the logs, turned in batches once a batch has gathered (each body's move is its own) */
    int32_t lg[CYL_BATCH + SD_EXT_BLOCK];
    sd_vec3 ext[SD_EXT_BLOCK]; /* a block's external forces (ext_fn) */
    /* the external forces: the block's buffer from ext_fn (ext[k - kb]), else the store's, or
     * none (NULL) while none was ever set */
    const int blk = w->ext_fn != NULL;
    const sd_vec3 *const ex = blk ? ext : (w->ext_any || !w->sw[SD_SW_EXT_SKIP]) ? b->ext_force : NULL;
    int nlg = 0;
#ifdef SD_MOVE256
    const int lanes = w->sw[SD_SW_MOVE_LANES] && w->simd >= SD_SIMD_AVX2;
#endif
    for (int kb = k0; kb < k1; kb += SD_EXT_BLOCK) {
        const int ke = k1 - kb < SD_EXT_BLOCK ? k1 : kb + SD_EXT_BLOCK;
        /* the external forces of a block just before it moves: its bodies are still in L1 */
        if (blk) w->ext_fn(w->ext_ctx, w, mov, kb, ke, ext);
#ifdef SD_MOVE256
        if (lanes)
            nlg = move_block256(mov, kb, ke, dt, g, b->force, ex, b->inv_mass, b->vel, b->pos, b->omega, b->torque,
                                b->inv_i_ax, b->radius, b->shape, &vm, &xf, lg, nlg, blk);
        else
#endif
            nlg = move_block(mov, kb, ke, dt, g, b->force, ex, b->inv_mass, b->vel, b->pos, b->omega, b->torque,
                             b->inv_i_ax, b->radius, b->shape, &vm, &xf, lg, nlg, blk);
        if (!w->sw[SD_SW_CYL_BATCH]) {
            for (int q = 0; q < nlg; q++) {
                const double x = cyl_step(b, lg[q], dt, lim2, &moved, &dc);
                xf = x > xf ? x : xf;
            }
            nlg = 0;
        } else if (nlg >= CYL_BATCH) {
            const double x = cyl_steps(b, lg, nlg, dt, lim2, &moved, &dc);
            xf = x > xf ? x : xf;
            nlg = 0;
        }
    }
    if (nlg > 0) {
        const double x = cyl_steps(b, lg, nlg, dt, lim2, &moved, &dc);
        xf = x > xf ? x : xf;
    }
    *mm = (sd_moves){vm, dc, xf};
    return moved;
}

void sd_integrate_after_moves(sd_world *w, const sd_moves *m)
{
    const double step = sqrt(m->v2) * w->def.dt;
    /* the near pairs: the farthest any surface went, a sphere's or a log's */
    w->near_drift += step > m->dc ? step : m->dc;
    /* no sphere can have moved more than ref_drift since the rebuild: the exact test of
     * each against half the margin (what the cylinders get every step) only once that bound
     * is near it, with the same outcome */
    w->ref_drift += step;
    if (!w->need_rebuild && w->ref_drift >= 0.5 * w->def.margin * (1.0 - 1e-3)) {
        const sd_bodies *b = &w->b;
        const double lim2 = 0.25 * w->def.margin * w->def.margin;
        const int nm = w->mov_n;
        int moved = 0;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) reduction(| : moved) if (nm > w->def.parallel_min)
        for (int k = 0; k < nm; k++) {
            const int i = w->mov[k];
            moved |= b->shape[i] == SD_SHAPE_SPHERE && v3_norm2(v3_sub(b->pos[i], b->pos_ref[i])) > lim2;
        }
        if (moved) w->need_rebuild = 1;
    }
    w->front = m->xf;
    w->front_step = w->step + 1; /* the step that is ending */
    w->front_bn = w->b.n;
}

/* The moving bodies only (w->mov, made current by sd_world_step): a fixed body has no
 * triangle pairs to gather and does not move; split evenly among the threads. */
void sd_integrate(sd_world *w)
{
    const int nm = w->mov_n;
    int moved = 0;
    sd_moves mm = SD_MOVES_NONE;
#ifdef _OPENMP
#pragma omp parallel num_threads(w->nthreads) reduction(| : moved) reduction(moves_max : mm) if (nm > w->def.parallel_min)
    {
        int k0, k1;
        sd_mov_share(w, omp_get_thread_num(), omp_get_num_threads(), &k0, &k1);
        moved |= sd_integrate_list(w, w->mov, k0, k1, &mm);
    }
#else
    moved = sd_integrate_list(w, w->mov, 0, nm, &mm);
#endif
    if (moved) w->need_rebuild = 1;
    sd_integrate_after_moves(w, &mm);
}
