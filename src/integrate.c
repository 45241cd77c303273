/* Leapfrog (SPEC §2, eqs 7–9): v ← v + (F/m)Δt, x ← x + vΔt, the velocity lagging half a step.
 * Rotation of cylinders on the world-frame angular momentum: L ← L + TΔt, then the exact
 * torque-free motion of an axisymmetric body over Δt, which is a rotation about L by
 * |L|Δt/I_tr (space) composed with a spin about the body axis by (1/I_ax − 1/I_tr)(L·a)Δt
 * (body). That keeps L·a and the kinetic energy of a free log exact, where the plain update
 * q ← exp(ωΔt) q drifts at O(Δt) (see docs/physics.md). Spheres: ω ← ω + TΔt/I. */
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

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

#define SD_EXT_BLOCK 128

int sd_integrate_list(sd_world *w, const int32_t *mov, int k0, int k1, double *v2max, double *dcyl, double *xfront)
{
    sd_bodies *b = &w->b;
    const double dt = w->def.dt;
    const sd_vec3 g = w->def.gravity;
    const double lim2 = 0.25 * w->def.margin * w->def.margin;
    int moved = 0;
    double vm = *v2max, dc = *dcyl, xf = *xfront;
    for (int kb = k0; kb < k1; kb += SD_EXT_BLOCK) {
        const int ke = k1 - kb < SD_EXT_BLOCK ? k1 : kb + SD_EXT_BLOCK;
        /* the external forces of a block just before it moves: its bodies are still in L1 */
        if (w->ext_fn) w->ext_fn(w->ext_ctx, w, mov, kb, ke);
        for (int k = kb; k < ke; k++) {
            const int i = mov[k];
            const sd_vec3 f = v3_add(b->force[i], b->ext_force[i]);
            const sd_vec3 acc = v3_madd(g, f, b->inv_mass[i]);
            /* the new velocity and centre kept in registers, not read back from the store
             * right after being written (x and y by one 16-byte store): on AMD Zen 3 a tenth
             * of this loop's samples sat on the read of y, as if it waited for the store. The
             * same values either way. */
            const sd_vec3 vn = v3_madd(b->vel[i], acc, dt);
            const sd_vec3 pn = v3_madd(b->pos[i], vn, dt);
            b->vel[i] = vn;
            b->pos[i] = pn;
            double x;
            if (b->shape[i] == SD_SHAPE_SPHERE) {
                b->omega[i] = v3_madd(b->omega[i], b->torque[i], dt * b->inv_i_ax[i]);
                /* a sphere's displacement since the rebuild is bounded by the summed largest
                 * |v| dt (sd_world_after_moves checks it exactly only when that bound nears half
                 * the margin) */
                const double v2 = v3_norm2(vn);
                vm = v2 > vm ? v2 : vm;
                x = pn.x + b->radius[i];
            } else {
                x = cyl_step(b, i, dt, lim2, &moved, &dc);
            }
            xf = x > xf ? x : xf;
        }
    }
    *v2max = vm;
    *dcyl = dc;
    *xfront = xf;
    return moved;
}

/* The moving bodies only (w->mov, made current by sd_world_step): a fixed body has no
 * triangle pairs to gather and does not move; split evenly among the threads. */
void sd_integrate(sd_world *w)
{
    const int nm = w->mov_n;
    int moved = 0;
    double v2 = 0.0, dc = 0.0, xf = -INFINITY;
#ifdef _OPENMP
#pragma omp parallel reduction(| : moved) reduction(max : v2, dc, xf) if (nm > w->def.parallel_min)
    {
        int k0, k1;
        sd_mov_share(w, omp_get_thread_num(), omp_get_num_threads(), &k0, &k1);
        moved |= sd_integrate_list(w, w->mov, k0, k1, &v2, &dc, &xf);
    }
#else
    moved = sd_integrate_list(w, w->mov, 0, nm, &v2, &dc, &xf);
#endif
    if (moved) w->need_rebuild = 1;
    sd_world_after_moves(w, v2, dc, xf);
}
