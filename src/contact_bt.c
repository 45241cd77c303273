/* The body-wall pass: each body near a wall with its triangle pairs, a sphere's single face
 * contact through the law in lanes, the rest through the manifold and the mesh rule. */
#include <stdint.h>

#include "contact_kernels.h"
#include "contact_law.h"

#define BT_LOCAL 16 /* wall candidates of one body whose manifolds sd_bt_range keeps on the stack */

/* The batch's lanes through the law, then each into its pair's slot and onto its sphere (the
 * sphere's only contact with the walls: nothing else is summed onto it in sd_bt_range). */
static void bt_flush(sd_world *w, const sd_law *law, bt_batch *q, int m)
{
    sd_bodies *b = &w->b;
    if (w->ctx.multi) {
        int32_t lw[BT_CHUNK] = {0};
        for (int j = 0; j < m; j++) {
            const sd_pair *p = &w->bt.p[q->k[j]];
            lw[j] = sd_mat_pair(b->mat[p->a], w->w.mat[p->b]);
        }
        sd_lane_law_bt_mat(w->ctx.lanes, lw, q, m);
    } else
        sd_lane_law_bt(&w->ctx.lane, q, m);
    for (int j = 0; j < m; j++) {
        const int k = q->k[j];
        const sd_pair *p = &w->bt.p[k];
        sd_hist *h = &w->bt.hist[p->off];
        sd_pair_out o;
        if (q->redo[j] != 0.0) {
            /* the scalar law from the slot's spring, not yet overwritten */
            const sd_vec3 n = v3(q->nx[j], q->ny[j], q->nz[j]), r = v3(q->rx[j], q->ry[j], q->rz[j]);
            const sd_vec3 v = v3_add(v3(q->vx[j], q->vy[j], q->vz[j]), v3_cross(v3(q->wx[j], q->wy[j], q->wz[j]), r));
            sd_vec3 shear = h->feature == SD_TRI_FACE ? h->shear : v3(0, 0, 0), f;
            sd_contact_law(sd_law_bt(w, law, p->a, p->b), q->sqm[j], n, q->ov[j], v, w->def.dt, &shear, &f);
            h->shear = shear;
            o.f_a = v3_add(v3(0, 0, 0), f);
            o.t_a = v3_add(v3(0, 0, 0), v3_cross(r, f));
        } else {
            h->shear = v3(q->sx[j], q->sy[j], q->sz[j]);
            o.f_a = v3(q->fx[j], q->fy[j], q->fz[j]);
            o.t_a = v3(q->tx[j], q->ty[j], q->tz[j]);
        }
        h->feature = SD_TRI_FACE;
        for (int s = 1; s < p->cap; s++)
            h[s].feature = -1;
        w->bt.out[k] = o.f_a;
        w->bt.active[k] = 1;
        const int i = p->a;
        b->force[i] = v3_add(b->force[i], o.f_a);
        b->torque[i] = v3_add(b->torque[i], o.t_a);
    }
}

#define BT_SNAP 32 /* a body's wall springs that sd_bt_range keeps to carry across features */

/* Whether a spring held last step by a body's contact (feature fo on the wall pair's triangle
 * to_) goes on in its contact x (feature fn, on triangle tn) of this step: the same body part
 * (a log's part, the high bits of the feature; a sphere has one), on the same triangle (a
 * sphere or a rim passing from a face to an edge or a vertex) or on another triangle with the
 * new point within a tenth of the body's radius of the old triangle (a seam or a crease
 * crossed in the last step; a corner's other wall, touched a radius away from this one, is
 * not). */
static int bt_carries(const sd_walls *wl, int to_, int fo, int tn, int fn, sd_vec3 x, double radius)
{
    if ((fo >> SD_TRI_FEATURE_BITS) != (fn >> SD_TRI_FEATURE_BITS)) return 0;
    if (to_ == tn) return 1;
    int tf;
    const sd_vec3 q = sd_geom_closest_on_tri(&wl->tri[to_], x, &tf);
    return v3_norm2(v3_sub(q, x)) <= 0.01 * radius * radius;
}

/* A sphere's wall candidates from .. to-1 when they give one face contact at most and nothing
 * near an edge: the contact (if any) into the batch's next lane, the other pairs emptied.
 * Returns 0 (and touches nothing) when the general path must decide. */
static int bt_sphere_face(sd_world *w, int i, int from, int to, bt_batch *q, int *m)
{
    const sd_bodies *b = &w->b;
    const sd_walls *wl = &w->w;
    const sd_vec3 c = b->pos[i];
    const double r = b->radius[i];
    int hit = -1;
    double s_hit = 0.0;
    for (int k = from; k < to; k++) {
        const int t = w->bt.p[k].b;
        if (!wl->active[t]) continue;
        double s;
        const int kind = sd_sphere_tri_class(c, r, &wl->tri[t], &wl->edges[t], &s);
        if (kind == 2 || (kind == 1 && hit >= 0)) return 0;
        if (kind == 1) {
            hit = k;
            s_hit = s;
        }
    }
    sd_vec3 n = v3(0, 0, 0), pt = v3(0, 0, 0), shear = v3(0, 0, 0);
    double ov = 0.0;
    int have = 0;
    if (hit >= 0) {
        const sd_pair *p = &w->bt.p[hit];
        sd_hist *h = &w->bt.hist[p->off];
        sd_sphere_tri_face(c, r, &wl->tri[p->b], s_hit, &n, &ov, &pt);
        /* the spring of the same feature (a face: the first slot holding it), else one this
         * contact carries from another feature of the triangle or from the triangle it left
         * (bt_carries; into the slot, where the lanes' redo reads it), or a new one */
        for (int s = 0; s < p->cap && s < SD_MANIFOLD_MAX && !have; s++)
            if (h[s].feature == SD_TRI_FACE) {
                shear = h[s].shear;
                have = 1;
            }
        for (int k = from; k < to && !have; k++) {
            const sd_hist *o = &w->bt.hist[w->bt.p[k].off];
            if (o->feature >= 0 && bt_carries(wl, w->bt.p[k].b, o->feature, p->b, SD_TRI_FACE, pt, r)) {
                shear = o->shear;
                have = 1;
            }
        }
        h->feature = SD_TRI_FACE;
        h->shear = shear;
    }
    for (int k = from; k < to; k++) {
        if (k == hit) continue;
        const sd_pair *p = &w->bt.p[k];
        for (int s = 0; s < p->cap; s++)
            w->bt.hist[p->off + s].feature = -1;
        w->bt.active[k] = 0;
    }
    if (hit < 0) return 1;
    const sd_pair *p = &w->bt.p[hit];
    const sd_vec3 ra = v3_sub(pt, c), v = b->vel[i], om = b->omega[i];
    const int j = (*m)++;
    q->nx[j] = n.x, q->ny[j] = n.y, q->nz[j] = n.z, q->ov[j] = ov;
    q->rx[j] = ra.x, q->ry[j] = ra.y, q->rz[j] = ra.z;
    q->vx[j] = v.x, q->vy[j] = v.y, q->vz[j] = v.z;
    q->wx[j] = om.x, q->wy[j] = om.y, q->wz[j] = om.z;
    q->sqm[j] = p->sqrt_m_eff;
    q->sx[j] = shear.x, q->sy[j] = shear.y, q->sz[j] = shear.z;
    q->k[j] = hit;
    return 1;
}

/* the rows of body j that the contact passes read and write, prefetched (six plain prefetches:
 * the same rows through sd_front_prefetch_rows's line loops lost the front prefetch's whole gain at 1e5) */
static inline void pf_body(const sd_bodies *b, int j)
{
    __builtin_prefetch(&b->pos[j], 0, 3);
    __builtin_prefetch(&b->vel[j], 0, 3);
    __builtin_prefetch(&b->omega[j], 0, 3);
    __builtin_prefetch(&b->radius[j], 0, 3);
    __builtin_prefetch(&b->force[j], 1, 3);
    __builtin_prefetch(&b->torque[j], 1, 3);
}

/* Body–triangle pairs of the bodies i0 .. i1-1: narrow phase, mesh dedup, law, into each
 * pair's slot (gathered per body in pair order by sd_contact_gather). */
long sd_bt_range(sd_world *w, const sd_law *law, const int32_t *list, int nl, bt_batch *q)
{
    sd_bodies *b = &w->b;
    long count = 0;
    int m = 0;
    /* the bodies near a wall (sd_near_walls, made with the near pairs, which the callers have
     * just made current), each with its pairs (grouped by body): the others would get exactly
     * nothing (no contact, their pairs' slots already empty), the same bits */
    const int pf = sd_front_prefetch_on(w);
    for (int l = 0; l < nl; l++) {
        const int i = list[l];
        /* (the body 4 ahead: the bodies with wall pairs are a sparse subset, which the
         * hardware prefetchers do not follow; when the front prefetch is on) */
        if (pf && l + 4 < nl) pf_body(b, list[l + 4]);
        const int from = w->csr.bt_start[i], to = w->csr.bt_start[i + 1];
        if (b->shape[i] == SD_SHAPE_SPHERE) {
            const int m0 = m;
            if (bt_sphere_face(w, i, from, to, q, &m)) {
                count += m - m0;
                if (m == BT_CHUNK) {
                    bt_flush(w, law, q, m);
                    m = 0;
                }
                continue;
            }
        }
        /* the body's manifolds on the stack when they fit (they stay in L1: the store's
         * array is a quarter-kilobyte per pair, mostly written and read for "no contact") */
        sd_manifold loc[BT_LOCAL];
        sd_manifold *man = to - from <= BT_LOCAL ? loc : &w->bt_man[from];
        int multi = 0;
        for (int k = from; k < to; k++)
            multi += sd_manifold_bt(b, &w->w, &w->bt.p[k], &man[k - from]) > 0;
        if (multi > 1) sd_contact_mesh_dedup(&w->w, &w->bt.p[from], man, 0, to - from);
        /* a log's wall contacts share the stiffness where their normals agree (a face or a side
         * lying on a floor of one or several triangles) */
        const int weighted = b->shape[i] != SD_SHAPE_SPHERE;
        if (weighted && multi > 0) sd_manifold_shares(man, to - from);
        /* the body's springs of the last step, for the contacts that carry one from another
         * feature or triangle (bt_carries): those whose feature this step's pair lacks */
        int32_t snap_k[BT_SNAP];
        sd_hist snap[BT_SNAP];
        int nsnap = 0;
        for (int k = from; k < to && nsnap < BT_SNAP; k++) {
            const sd_pair *p = &w->bt.p[k];
            const sd_manifold *mk = &man[k - from];
            for (int s = 0; s < p->cap && nsnap < BT_SNAP; s++) {
                const sd_hist *h = &w->bt.hist[p->off + s];
                int seen = 0;
                for (int j = 0; j < mk->n; j++)
                    seen |= mk->feature[j] == h->feature;
                if (h->feature >= 0 && !seen) {
                    snap_k[nsnap] = k;
                    snap[nsnap++] = *h;
                }
            }
        }
        /* each pair into its slot (the wall loads, sd_contact_gather) and onto its body after
         * the body-body sum, in pair order */
        sd_vec3 f = b->force[i], t = b->torque[i];
        for (int k = from; k < to; k++) {
            const sd_pair *p = &w->bt.p[k];
            if (man[k - from].n == 0) {
                /* no contact (most wall candidates): what sd_manifold_apply leaves, empty springs;
                 * the slot's force is not read while the pair is inactive */
                for (int s = 0; s < p->cap; s++)
                    w->bt.hist[p->off + s].feature = -1;
                w->bt.active[k] = 0;
                continue;
            }
            /* the result summed from registers: read back from the slot, each 16-byte load
             * waited for the two 8-byte stores it spans (no store forwarding) */
            sd_pair_out o;
            const sd_manifold *mk = &man[k - from];
            sd_vec3 seed[SD_MANIFOLD_MAX];
            const sd_hist *hk = &w->bt.hist[p->off];
            for (int j = 0; j < mk->n; j++) {
                seed[j] = v3(0, 0, 0);
                int own = 0;
                for (int s = 0; s < p->cap; s++)
                    own |= hk[s].feature == mk->feature[j];
                for (int s = 0; s < nsnap && !own; s++)
                    if (snap[s].feature >= 0 && bt_carries(&w->w, w->bt.p[snap_k[s]].b, snap[s].feature, p->b,
                                                           mk->feature[j], mk->point[j], b->radius[i])) {
                        seed[j] = snap[s].shear;
                        snap[s].feature = -1; /* (taken) */
                        break;
                    }
            }
            int used = sd_manifold_apply(w, sd_law_bt(w, law, p->a, p->b), mk, p->a, -1, 1, p->sqrt_m_eff,
                                         &w->bt.hist[p->off], p->cap, nsnap ? seed : NULL, weighted, &o);
            w->bt.out[k] = o.f_a;
            w->bt.active[k] = (uint8_t)(used > 0);
            count += used;
            if (used > 0) {
                f = v3_add(f, o.f_a);
                t = v3_add(t, o.t_a);
            }
        }
        b->force[i] = f;
        b->torque[i] = t;
    }
    if (m > 0) bt_flush(w, law, q, m);
    return count;
}
