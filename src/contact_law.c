/* Contact springs (SPEC §3, eqs 10–12): normal spring + dashpot without tension, incremental
 * tangential spring rotated into the current tangent plane, Mohr–Coulomb limit with cohesion.
 * Knows nothing of shapes. */
#include "world_internal.h"

sd_law sd_law_make(const sd_contact_def *d)
{
    sd_law l;
    l.k_n = d->k_n;
    l.k_s = d->k_s;
    l.c_n_factor = 2.0 * d->damping * sqrt(d->k_n);
    l.c_s_factor = 2.0 * d->damping * sqrt(d->k_s);
    l.tan_phi = d->tan_phi;
    l.cohesion = d->cohesion;
    return l;
}

double sd_contact_law(const sd_law *law, double m_eff, sd_vec3 n, double overlap, sd_vec3 v_rel,
                      double dt, sd_vec3 *shear, sd_vec3 *force_a)
{
    double sqm = sqrt(m_eff);
    double vn = v3_dot(v_rel, n); /* > 0: separating */
    /* P_n = K_n δ + c_n δ̇ with δ̇ = -vn; no tension: a negative sum is zero */
    double pn = law->k_n * overlap - law->c_n_factor * sqm * vn;
    if (pn < 0.0) pn = 0.0;

    sd_vec3 vt = v3_madd(v_rel, n, -vn);
    /* rotate the stored spring into the current tangent plane, keeping its length */
    sd_vec3 s = *shear;
    double s2 = v3_norm2(s);
    if (s2 > 0.0) {
        s = v3_madd(s, n, -v3_dot(s, n));
        double r2 = v3_norm2(s);
        s = r2 > 0.0 ? v3_scale(s, sqrt(s2 / r2)) : v3(0.0, 0.0, 0.0);
    }
    /* eq 11: P_s(t) = P_s(t - dt) + K_s Δδ_s, the spring opposing the relative slip */
    s = v3_madd(s, vt, -law->k_s * dt);
    double limit = law->cohesion + pn * law->tan_phi;
    double smag = sqrt(v3_norm2(s));
    sd_vec3 ft;
    if (smag > limit) {
        /* sliding: spring scaled back to the limit, no tangential dashpot */
        s = smag > 0.0 ? v3_scale(s, limit / smag) : s;
        ft = s;
    } else {
        ft = v3_madd(s, vt, -law->c_s_factor * sqm);
        double fmag = sqrt(v3_norm2(ft));
        if (fmag > limit) ft = v3_scale(ft, limit / fmag);
    }
    *shear = s;
    *force_a = v3_madd(ft, n, pn);
    return pn;
}
