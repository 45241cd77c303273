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

/* How much two points' normals agree for sharing (cosine cn): 1 within 10 deg, 0 beyond 30 deg,
 * linear in the cosine between, so that a point's share changes continuously as its normal
 * turns away from the others'. */
static double share_kernel(double cn)
{
    const double c10 = 0.98480775301220802, c30 = 0.86602540378443860;
    return cn >= c10 ? 1.0 : (cn <= c30 ? 0.0 : (cn - c30) / (c10 - c30));
}

void sd_manifold_shares(sd_manifold *ms, int nm)
{
    double sum[SD_SHARE_MAX], scale[SD_SHARE_MAX];
    int nt = 0;
    for (int p = 0; p < nm; p++)
        nt += ms[p].n;
    if (nt > SD_SHARE_MAX) {
        /* (more wall contacts of one log than any scene has: each at full stiffness) */
        for (int p = 0; p < nm; p++)
            for (int k = 0; k < ms[p].n; k++)
                ms[p].share[k] = 1.0;
        return;
    }
    /* Every sum from the raw shares first, then the weights and the springs' overlaps in place.
     * Among points whose normals agree (kernel 1), a point's weight is w_k = s_k / S (S = sum
     * of the raw shares s_j, so the dashpots add up to one contact's), and its spring sees the
     * overlap d_k M S / Q (M = the deepest overlap d_j, Q = sum of s_j d_j), so the springs add
     * up to K_n M: one contact's spring on the depth of the pair's overlap, whatever the number
     * of points, and continuous as points come and go (a point that appears or leaves at any
     * depth only moves the load among the points). Weighting the springs by the shares alone
     * (K_n sum(s_j d_j) / S) softened a line contact as a shallower point joined it: a log
     * across a pipe near parallel settled up to 1.37 times deeper than crossed, and jumped back
     * as the end points left (docs/physics.md §16). One point: exactly its own overlap. */
    int i = 0;
    for (int p = 0; p < nm; p++)
        for (int k = 0; k < ms[p].n; k++, i++) {
            double s = 0.0, q = 0.0, deep = 0.0;
            for (int r = 0; r < nm; r++)
                for (int j = 0; j < ms[r].n; j++) {
                    const double kn = share_kernel(v3_dot(ms[p].normal[k], ms[r].normal[j]));
                    s += ms[r].share[j] * kn;
                    q += ms[r].share[j] * ms[r].overlap[j] * kn;
                    deep = fmax(deep, ms[r].overlap[j] * kn);
                }
            sum[i] = s;
            scale[i] = q > 0.0 ? deep * s / q : 1.0;
        }
    i = 0;
    for (int p = 0; p < nm; p++)
        for (int k = 0; k < ms[p].n; k++, i++) {
            ms[p].share[k] = sum[i] > 0.0 ? ms[p].share[k] / sum[i] : 1.0;
            ms[p].overlap[k] *= scale[i];
        }
}

int sd_manifold_carry_cc(const sd_manifold *m, const sd_hist *slots, int cap, sd_vec3 *seed)
{
    int nold = cap < SD_MANIFOLD_MAX ? cap : SD_MANIFOLD_MAX, carried = 0;
    int old_free[SD_MANIFOLD_MAX], new_free[SD_MANIFOLD_MAX], nof = 0, nnf = 0;
    for (int s = 0; s < nold; s++) {
        if (slots[s].feature < 0) continue;
        int seen = 0;
        for (int k = 0; k < m->n; k++)
            seen |= m->feature[k] == slots[s].feature;
        if (!seen) old_free[nof++] = s;
    }
    for (int k = 0; k < m->n; k++) {
        seed[k] = v3(0.0, 0.0, 0.0);
        int seen = 0;
        for (int s = 0; s < nold; s++)
            seen |= slots[s].feature == m->feature[k];
        if (!seen) new_free[nnf++] = k;
    }
    /* an end disk turning from a side to an end face (ids 1<->3, 2<->4, 5<->7, 6<->8) keeps its
     * spring; so does a lone contact that changed its type (side-side, disk, last resort) */
    for (int i = 0; i < nnf; i++) {
        const int f = m->feature[new_free[i]];
        for (int j = 0; j < nof; j++) {
            const int g = old_free[j] < 0 ? -1 : slots[old_free[j]].feature;
            const int same_disk = f >= 1 && f <= 8 && g >= 1 && g <= 8 && (f - 1) / 4 == (g - 1) / 4 &&
                                  (f - 1) % 2 == (g - 1) % 2;
            if (g >= 0 && (same_disk || (nnf == 1 && nof == 1))) {
                seed[new_free[i]] = slots[old_free[j]].shear;
                old_free[j] = -1;
                carried++;
                break;
            }
        }
    }
    return carried;
}

/* Apply the law to every point of a manifold, matching history slots by feature; a point with
 * no slot of its feature starts from seed[k] (a spring carried from another feature or pair,
 * or zero; NULL: zero). weighted: the point's force is its share (m->share, normalised) of
 * the one-point law's on m->overlap (the spring's overlap, after sd_manifold_shares), the
 * spring kept as the one-point law's. */
int sd_manifold_apply(const sd_world *w, const sd_law *law, const sd_manifold *m, int ia, int ib, int b_is_static,
                      double sqm, sd_hist *slots, int cap, const sd_vec3 *seed, int weighted, sd_pair_out *out)
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
        sd_vec3 shear = seed ? seed[k] : v3(0, 0, 0);
        for (int s = 0; s < nold; s++)
            if (old[s].feature == m->feature[k]) {
                shear = old[s].shear;
                break;
            }
        sd_vec3 f;
        sd_contact_law(law, sqm, m->normal[k], m->overlap[k], v3_sub(va, vb), w->def.dt, &shear, &f);
        if (weighted) f = v3_scale(f, m->share[k]);
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

/* A sphere-log pair whose manifold is one point (the sphere against the log's side or end:
 * most of them) through the law in lanes, like the walls' face contacts: sd_manifold_apply's
 * arithmetic for a one-point manifold between two moving bodies, operation for operation
 * (same bits). */
static void sc_lane_fill(const sd_world *w, const sd_pair *p, const sd_manifold *mf, const sd_hist *h, int i,
                         struct sc_lanes *q, int j)
{
    const sd_bodies *b = &w->b;
    const int a = p->a, c = p->b;
    const sd_vec3 pt = mf->point[0], ra = v3_sub(pt, b->pos[a]), rb = v3_sub(pt, b->pos[c]);
    const sd_vec3 va = b->vel[a], wa = b->omega[a], vb = b->vel[c], wb = b->omega[c];
    q->nx[j] = mf->normal[0].x, q->ny[j] = mf->normal[0].y, q->nz[j] = mf->normal[0].z, q->ov[j] = mf->overlap[0];
    q->px[j] = pt.x, q->py[j] = pt.y, q->pz[j] = pt.z;
    q->rax[j] = ra.x, q->ray[j] = ra.y, q->raz[j] = ra.z;
    q->rbx[j] = rb.x, q->rby[j] = rb.y, q->rbz[j] = rb.z;
    q->vax[j] = va.x, q->vay[j] = va.y, q->vaz[j] = va.z, q->wax[j] = wa.x, q->way[j] = wa.y, q->waz[j] = wa.z;
    q->vbx[j] = vb.x, q->vby[j] = vb.y, q->vbz[j] = vb.z, q->wbx[j] = wb.x, q->wby[j] = wb.y, q->wbz[j] = wb.z;
    q->sqm[j] = p->sqrt_m_eff;
    /* the spring of the same feature, or a new one (the pair has one slot) */
    const int same = h->feature == mf->feature[0];
    q->sx[j] = same ? h->shear.x : 0.0, q->sy[j] = same ? h->shear.y : 0.0, q->sz[j] = same ? h->shear.z : 0.0;
    q->feature[j] = mf->feature[0];
    q->i[j] = i;
}

/* A pair of another shape (chunk entry i) through its kernel: a one-point sphere-log contact
 * into lane msc of q (returns 1), anything else through sd_manifold_apply now (returns 0). Out of
 * line: inlined, it crowded the sphere pass's registers. */
__attribute__((noinline)) int sd_manifold_general_pair(const sd_world *w, const sd_law *law, const sd_pair *p, int i,
                                                       struct sc_lanes *q, int msc, sd_pair_out *out, int *used)
{
    sd_manifold m;
    sd_hist *h = &w->bb.hist[p->off];
    law = sd_law_bb(w, law, p->a, p->b);
    if (p->kind == SD_PAIR_CC) {
        /* two logs (or a log and a pipe): the axis that showed them apart last time first */
        sd_vec3 sep = h->feature == SD_HIST_SEP_AXIS ? h->shear : v3(0.0, 0.0, 0.0);
        const sd_cyl ca = sd_body_cyl(&w->b, p->a), cb = sd_body_cyl(&w->b, p->b);
        sd_geom_cyl_cyl_sep(&ca, &cb, &m, &sep);
        sd_vec3 seed[SD_MANIFOLD_MAX] = {{0}};
        sd_manifold_carry_cc(&m, h, p->cap, seed);
        sd_manifold_shares(&m, 1);
        used[i] = sd_manifold_apply(w, law, &m, p->a, p->b, 0, p->sqrt_m_eff, h, p->cap, seed, 1, &out[i]);
        if (m.n == 0 && (sep.x != 0.0 || sep.y != 0.0 || sep.z != 0.0)) {
            h->feature = SD_HIST_SEP_AXIS;
            h->shear = sep;
        }
        return 0;
    }
    sd_manifold_bb(&w->b, p, &m);
    if (p->kind == SD_PAIR_SC && m.n == 1 && p->cap == 1 && w->sw[SD_SW_SC_LANES]) {
        sc_lane_fill(w, p, &m, h, i, q, msc);
        return 1;
    }
    used[i] = sd_manifold_apply(w, law, &m, p->a, p->b, 0, p->sqrt_m_eff, h, p->cap, NULL, 0, &out[i]);
    return 0;
}
