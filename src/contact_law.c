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
