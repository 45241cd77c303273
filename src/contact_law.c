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

const sd_step_ctx *sd_law_ctx_ready(sd_world *w)
{
    sd_step_ctx *c = &w->ctx;
    if (c->step == w->step + 1) return c;
    c->dt = w->def.dt;
    c->law = sd_law_make(&w->def.contact);
    const sd_law *l = &c->law;
    c->lane = (sd_lane_law){l->k_n, l->c_n_factor, l->c_s_factor, l->tan_phi, l->cohesion, -l->k_s * c->dt};
    c->step = w->step + 1;
    return c;
}
