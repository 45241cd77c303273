/* Contact springs (SPEC §3, eqs 10–12): normal spring + dashpot without tension, incremental
 * tangential spring rotated into the current tangent plane, Mohr–Coulomb limit with cohesion.
 * Knows nothing of shapes. */
#include <string.h>

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

static sd_lane_law lane_of(const sd_law *l, double dt)
{
    return (sd_lane_law){l->k_n, l->c_n_factor, l->c_s_factor, l->tan_phi, l->cohesion, -l->k_s * dt};
}

/* The pairs' table (sd_step_ctx.laws, lanes), remade when what it is made of changed. A pair
 * set to def.contact's very springs keeps the pass on its one-law path (multi 0). */
static void table_ready(const sd_world *w, sd_step_ctx *c)
{
    if (c->made && c->version == w->mat_version && c->made_dt == c->dt &&
        !memcmp(&c->made_base, &w->def.contact, sizeof c->made_base))
        return;
    c->multi = 0;
    for (int k = 0; k < SD_MATERIALS_MAX * SD_MATERIALS_MAX; k++) {
        const sd_contact_def *d = w->mat_set[k] ? &w->mat_pair[k] : &w->def.contact;
        c->laws[k] = sd_law_make(d);
        c->lanes[k] = lane_of(&c->laws[k], c->dt);
        c->multi |= w->mat_set[k] && memcmp(d, &w->def.contact, sizeof *d) != 0;
    }
    c->made = 1;
    c->version = w->mat_version;
    c->made_dt = c->dt;
    c->made_base = w->def.contact;
}

const sd_step_ctx *sd_law_ctx_ready(sd_world *w)
{
    sd_step_ctx *c = &w->ctx;
    if (c->step == w->step + 1) return c;
    c->dt = w->def.dt;
    c->law = sd_law_make(&w->def.contact);
    c->lane = lane_of(&c->law, c->dt);
    table_ready(w, c);
    c->step = w->step + 1;
    return c;
}
