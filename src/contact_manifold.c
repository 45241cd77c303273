/* Shape dispatch (a pair's manifold through its geom/ kernel) and the contact law applied to
 * every point of a manifold, for the pairs that do not go through the lanes. */
#include "contact_internal.h"
#include "contact_law.h"

int sd_manifold_bb(const sd_bodies *b, const sd_pair *p, sd_manifold *m)
{
    int a = p->a, c = p->b;
    switch (p->kind) {
    case SD_PAIR_SS:
        return sd_geom_sphere_sphere(b->pos[a], b->radius[a], b->pos[c], b->radius[c], m);
    case SD_PAIR_SC: {
        sd_cyl cb = sd_body_cyl(b, c);
        return sd_geom_sphere_cyl(b->pos[a], b->radius[a], &cb, m);
    }
    default: {
        sd_cyl ca = sd_body_cyl(b, a), cb = sd_body_cyl(b, c);
        return sd_geom_cyl_cyl(&ca, &cb, m);
    }
    }
}

int sd_manifold_bt(const sd_bodies *b, const sd_walls *wl, const sd_pair *p, sd_manifold *m)
{
    const sd_tri *t = &wl->tri[p->b];
    if (!wl->active[p->b]) {
        m->n = 0;
        return 0;
    }
    if (p->kind == SD_PAIR_ST) return sd_geom_sphere_tri_e(b->pos[p->a], b->radius[p->a], t, &wl->edges[p->b], m);
    sd_cyl c = sd_body_cyl(b, p->a);
    return sd_geom_cyl_tri(&c, t, m);
}

/* Apply the law to every point of a manifold, matching history slots by feature. */
int sd_manifold_apply(const sd_world *w, const sd_law *law, const sd_manifold *m, int ia, int ib, int b_is_static,
                      double sqm, sd_hist *slots, int cap, sd_pair_out *out)
{
    const sd_bodies *b = &w->b;
    sd_hist old[SD_MANIFOLD_MAX];
    int nold = cap < SD_MANIFOLD_MAX ? cap : SD_MANIFOLD_MAX;
    for (int s = 0; s < nold; s++) {
        old[s] = slots[s];
        slots[s].feature = -1;
    }
    sd_vec3 fa = v3(0, 0, 0), ta = v3(0, 0, 0), tb = v3(0, 0, 0);
    int used = 0;
    for (int k = 0; k < m->n && used < cap; k++) {
        sd_vec3 ra = v3_sub(m->point[k], b->pos[ia]);
        sd_vec3 va = v3_add(b->vel[ia], v3_cross(b->omega[ia], ra));
        sd_vec3 vb = v3(0, 0, 0), rb = v3(0, 0, 0);
        if (!b_is_static) {
            rb = v3_sub(m->point[k], b->pos[ib]);
            vb = v3_add(b->vel[ib], v3_cross(b->omega[ib], rb));
        }
        sd_vec3 shear = v3(0, 0, 0);
        for (int s = 0; s < nold; s++)
            if (old[s].feature == m->feature[k]) {
                shear = old[s].shear;
                break;
            }
        sd_vec3 f;
        sd_contact_law(law, sqm, m->normal[k], m->overlap[k], v3_sub(va, vb), w->def.dt, &shear, &f);
        slots[used].feature = m->feature[k];
        slots[used].shear = shear;
        used++;
        fa = v3_add(fa, f);
        ta = v3_add(ta, v3_cross(ra, f));
        if (!b_is_static) tb = v3_sub(tb, v3_cross(rb, f));
    }
    out->f_a = fa;
    out->t_a = ta;
    out->t_b = tb;
    return used;
}
