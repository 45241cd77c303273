/* Contact springs (SPEC §3, eqs 10-12), inline so that the contact loop keeps the shear
 * spring in registers. Knows nothing of shapes; sd_law_make (contact_law.c) precomputes the
 * constants. */
#ifndef SD_CONTACT_LAW_H
#define SD_CONTACT_LAW_H

#include "world_internal.h"

/* Force on A from one contact; updates the shear spring in place. Returns the normal force.
 * sqm = sqrt(m_i m_j / (m_i + m_j)), or sqrt(m_i) against a fixed element. */
static inline double sd_contact_law(const sd_law *law, double sqm, sd_vec3 n, double overlap, sd_vec3 v_rel, double dt,
                                    sd_vec3 *shear, sd_vec3 *force_a)
{
    double vn = v3_dot(v_rel, n); /* > 0: separating */
    /* P_n = K_n δ + c_n δ̇ with δ̇ = -vn; no tension: a negative sum is zero */
    double pn = law->k_n * overlap - law->c_n_factor * sqm * vn;
    if (pn < 0.0) pn = 0.0;

    sd_vec3 vt = v3_madd(v_rel, n, -vn);
    /* rotate the stored spring into the current tangent plane, keeping its length */
    sd_vec3 s = *shear;
    double s2 = v3_norm2(s);
    if (s2 > 0.0) {
        double sn = v3_dot(s, n);
        s = v3_madd(s, n, -sn);
        double r2 = s2 - sn * sn;
        if (sn * sn < 1e-4 * s2) {
            /* small tilt (every step but the first of a contact): sqrt(s2/r2) to 2nd order,
             * relative error below 1e-8, without a square root */
            double x = sn * sn / r2;
            s = v3_scale(s, 1.0 + 0.5 * x - 0.375 * x * x);
        } else {
            r2 = v3_norm2(s);
            s = r2 > 0.0 ? v3_scale(s, sqrt(s2 / r2)) : v3(0.0, 0.0, 0.0);
        }
    }
    /* eq 11: P_s(t) = P_s(t - dt) + K_s Δδ_s, the spring opposing the relative slip */
    s = v3_madd(s, vt, -law->k_s * dt);
    double limit = law->cohesion + pn * law->tan_phi;
    double smag2 = v3_norm2(s);
    sd_vec3 ft;
    if (smag2 > limit * limit) {
        /* sliding: spring scaled back to the limit, no tangential dashpot */
        s = v3_scale(s, limit / sqrt(smag2));
        ft = s;
    } else {
        ft = v3_madd(s, vt, -law->c_s_factor * sqm);
        double fmag2 = v3_norm2(ft);
        if (fmag2 > limit * limit) ft = v3_scale(ft, limit / sqrt(fmag2));
    }
    *shear = s;
    *force_a = v3_madd(ft, n, pn);
    return pn;
}

/* The law of a contact between bodies ia and ib, or body ia and triangle t: law (the step's
 * one law) unless the world has several materials (sd_step_ctx.multi), then the pair's. */
static inline const sd_law *sd_law_bb(const sd_world *w, const sd_law *law, int ia, int ib)
{
    return w->ctx.multi ? &w->ctx.laws[sd_mat_pair(w->b.mat[ia], w->b.mat[ib])] : law;
}
static inline const sd_law *sd_law_bt(const sd_world *w, const sd_law *law, int ia, int t)
{
    return w->ctx.multi ? &w->ctx.laws[sd_mat_pair(w->b.mat[ia], w->w.mat[t])] : law;
}

#endif
