/* The body-body pass: a chunk of pairs through the touch filter, the other shapes' manifolds,
 * the law in lanes and the sums onto the bodies (sd_bb_chunk), and the one-thread pass over
 * the near list (sd_bb_serial_pass; the owners' pass is in owners.c). */
#include <stdint.h>
#include <string.h>

#include "contact_kernels.h"
#include "contact_law.h"

/* One touching sphere–sphere pair by the scalar law (contact_law.h): the lanes that the batch
 * flags for a redo. Case 1 of the kernel: the contact point midway between the surfaces, lever
 * arms -la n (A) and lb n (B), so the relative velocity there is v_a - v_b - (la w_a + lb w_b) x n
 * and the torques are -la (n x f) on A and -lb (n x f) on B. */
static __attribute__((noinline)) void ss_scalar(const sd_world *w, const sd_law *law, const sd_pair *p, sd_hist *h,
                                                sd_pair_out *out)
{
    const sd_bodies *b = &w->b;
    const int ia = p->a, ib = p->b;
    sd_vec3 d = v3_sub(b->pos[ia], b->pos[ib]);
    double ra = b->radius[ia], rb = b->radius[ib], rs = ra + rb;
    double dist = sqrt(v3_norm2(d));
    sd_vec3 n = dist > 1e-300 ? v3_scale(d, 1.0 / dist) : v3(0.0, 0.0, 1.0);
    double ov = rs - dist;
    const double la = ra - 0.5 * ov, lb = rb - 0.5 * ov;
    sd_vec3 wsum = v3_madd(v3_scale(b->omega[ia], la), b->omega[ib], lb);
    sd_vec3 vrel = v3_sub(v3_sub(b->vel[ia], b->vel[ib]), v3_cross(wsum, n));
    sd_vec3 shear = h->feature == 0 ? h->shear : v3(0, 0, 0);
    sd_vec3 f;
    sd_contact_law(sd_law_bb(w, law, ia, ib), p->sqrt_m_eff, n, ov, vrel, w->def.dt, &shear, &f);
    h->feature = 0;
    h->shear = shear;
    out->f_a = f;
    sd_vec3 nf = v3_cross(n, f);
    out->t_a = v3_scale(nf, -la);
    out->t_b = v3_scale(nf, -lb);
}

/* ss_scalar on a lane's slot h: in a list's own slot (lsq) through a copy whose feature is the
 * lane's was, only the spring written back (the slot keeps its sqm; the pair keeps touching,
 * as ss_scalar leaves its feature 0, and so its flag). */
static void ss_redo(const sd_world *w, const sd_law *law, const sd_pair *p, sd_hist *h, int lsq, int32_t was,
                    sd_pair_out *out)
{
    if (!lsq) {
        ss_scalar(w, law, p, h, out);
        return;
    }
    sd_hist t = {.feature = was, .shear = h->shear};
    ss_scalar(w, law, p, &t, out);
    h->shear = t.shear;
}

/* s found again when the count of bodies or of rebuilds changed since (bodies move in the
 * store only at a rebuild). A zeroed s is found afresh. */
void sd_bb_bed_split(const sd_world *w, sd_bed_split *s)
{
    const sd_bodies *b = &w->b;
    if (s->n == b->n && s->stamp == w->timers.rebuilds && s->n > 0) return;
    s->n = b->n;
    s->stamp = w->timers.rebuilds;
    s->nf = sd_bed_start(b);
    s->bed_lim = s->nf;
    for (int i = 0; i < s->nf; i++)
        if (sd_body_is_bed(b, i)) {
            s->bed_lim = -1;
            break;
        }
}

/* x, or +0.0 where mask is 0 (mask all ones or all zeros) */
static inline double bits_and(double x, uint64_t mask)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    u &= mask;
    memcpy(&x, &u, sizeof u);
    return x;
}

/* Step 1 of sd_bb_chunk (the touch filter) for the chunk's entries i0 .. i1: which pairs touch,
 * with no branch on the answer (it is close to a coin toss in a dense bed). Each sphere pair's
 * geometry is written to the next free batch lane whether it touches or not; only a touching
 * pair moves the lane on (what the law needs is read once). A log's pair or a cross entry goes
 * to filter_other. */
static inline void ss_filter_range(const sd_world *w, const int32_t *ks, const soa_view *v, int i0, int i1, int *used,
                                   ss_batch *q, int *mp, int *gen, int *ngp)
{
    sd_hist *restrict hist = v->sh;
    const sd_vec3 *restrict pos = w->b.pos;
    const double *restrict rad = w->b.radius;
    int m = *mp;
    for (int i = i0; i < i1; i++) {
        /* the records from the chunk's view, in entry order (kind in ck's high half,
         * SD_PAIR_SS is 0) */
        if (ck_kind(v->ck[i])) {
            filter_other(w, ks, v, i, 0, used, gen, ngp);
            continue;
        }
        const int ia = v->a[i], ib = v->b[i], off = v->off[i];
        const sd_vec3 pa = pos[ia], pb = pos[ib];
        const double dx = pa.x - pb.x, dy = pa.y - pb.y, dz = pa.z - pb.z;
        const double ra = rad[ia], rb = rad[ib], rs = ra + rb;
        const int t = !(dx * dx + dy * dy + dz * dz >= rs * rs);
        /* the slot's feature from the entry's flag (0 with a spring, else -1) */
        const int act = v->act[i], was = act - 1;
        used[i] = t;
        q->dx[m] = dx, q->dy[m] = dy, q->dz[m] = dz;
        q->ra[m] = ra, q->rb[m] = rb;
        if (!v->lsq) q->sqm[m] = v->sqm[i]; /* (else the gather takes it from the slot) */
        q->ia[m] = ia, q->ib[m] = ib, q->off[m] = off, q->was[m] = was, q->sel[m] = i;
        m += t;
        v->act[i] = (uint8_t)t;
        /* a contact that has just ended loses its spring (few in a step; in a list's own
         * slots, the flag is the feature) */
        if (act & !t & !v->lsq) hist[off].feature = -1;
    }
    *mp = m;
}

/* Step 3 of sd_bb_chunk for the touching lanes j0 .. m: velocities, spins and the stored spring of
 * each. */
static inline void ss_gather_range(const sd_world *w, ss_batch *q, int j0, int m)
{
    const sd_hist *restrict hist = q->sh;
    const sd_vec3 *restrict vel = w->b.vel, *restrict omega = w->b.omega;
    const double *restrict rad = w->b.radius;
    for (int j = j0; j < m; j++) {
        const int ia = q->ia[j], ib = q->ib[j];
        const sd_hist *h = &hist[q->off[j]];
        q->ra[j] = rad[ia], q->rb[j] = rad[ib]; /* (the AVX2 filter leaves them to the gather) */
        const sd_vec3 va = vel[ia], vb = vel[ib], wa = omega[ia], wb = omega[ib];
        q->vx[j] = va.x - vb.x, q->vy[j] = va.y - vb.y, q->vz[j] = va.z - vb.z;
        q->wax[j] = wa.x, q->way[j] = wa.y, q->waz[j] = wa.z;
        q->wbx[j] = wb.x, q->wby[j] = wb.y, q->wbz[j] = wb.z;
        /* a new contact starts from zero: the stored spring's bits masked, with no branch on
         * it (a select compiled into one; new contacts come at random in a flow) */
        const uint64_t keep = -(uint64_t)(q->was[j] == 0);
        q->sx[j] = bits_and(h->shear.x, keep), q->sy[j] = bits_and(h->shear.y, keep),
        q->sz[j] = bits_and(h->shear.z, keep);
        if (q->lsq) q->sqm[j] = slot_sqm(h);
    }
}

/* The lanes' results into their pairs' slots and out[]; a lane the law sends back (its spring
 * tilted past the small-angle rule) through sd_manifold_apply, from the slot not yet written. */
static void sc_flush(const sd_world *w, const sd_law *law, struct sc_lanes *q, int m, const int32_t *ks,
                     const soa_view *v, sd_pair_out *out, int *used)
{
    if (w->ctx.multi) {
        int32_t lw[SC_CAP] = {0};
        for (int j = 0; j < m; j++)
            lw[j] = sd_mat_pair(w->b.mat[v->a[q->i[j]]], w->b.mat[v->b[q->i[j]]]);
        sd_lane_law_sc_mat(w->ctx.lanes, lw, q, m);
    } else
        sd_lane_law_sc(&w->ctx.lane, q, m);
    long redo = 0;
    for (int j = 0; j < m; j++)
        redo += q->redo[j] != 0.0;
    /* (counts for the tests, in this thread's scratch; folded after the pass) */
    q->n_run += m;
    q->n_redo += redo;
    for (int j = 0; j < m; j++) {
        const int i = q->i[j];
        sd_hist *h = &w->bb.hist[v->off[i]]; /* (the slot from the chunk's view: the pair store's
                                              * line is read only for a redo) */
        if (q->redo[j] != 0.0) {
            const sd_pair *p = &w->bb.p[ks[i]];
            sd_manifold m1;
            m1.n = 1;
            m1.normal[0] = v3(q->nx[j], q->ny[j], q->nz[j]);
            m1.point[0] = v3(q->px[j], q->py[j], q->pz[j]);
            m1.overlap[0] = q->ov[j];
            m1.feature[0] = q->feature[j];
            used[i] = sd_manifold_apply(w, sd_law_bb(w, law, p->a, p->b), &m1, p->a, p->b, 0, p->sqrt_m_eff, h, p->cap,
                                        NULL, 0, &out[i]);
            continue;
        }
        h->feature = q->feature[j];
        h->shear = v3(q->sx[j], q->sy[j], q->sz[j]);
        out[i].f_a = v3(q->fx[j], q->fy[j], q->fz[j]);
        out[i].t_a = v3(q->tax[j], q->tay[j], q->taz[j]);
        out[i].t_b = v3(q->tbx[j], q->tby[j], q->tbz[j]);
        used[i] = 1;
    }
}

/* Step 2 of sd_bb_chunk for a log's pair (chunk entry i) not taken by the sphere-log lanes:
 * filter_log_pair's apart test, where the touch filter left it (the AVX2 filter lists every
 * entry that is not a sphere pair as it is; the other filters' entries have passed it, and
 * pass it again), then sd_bb_pair_general. Returns the lanes it filled. */
static int other_pair(const sd_world *w, const sd_law *law, const sd_pair *p, int i, struct sc_lanes *q, int j,
                      sd_pair_out *out, int *used)
{
    if (log_pair_apart(&w->b, p)) {
        used[i] = 0;
        for (int s = 0; s < p->cap; s++)
            w->bb.hist[p->off + s].feature = -1;
        return 0;
    }
    return sd_manifold_general_pair(w, law, p, i, q, j, out, used);
}

/* The pairs ks[0 .. n) (n <= SS_CHUNK): forces into out[i], contact points into used[i]. Each
 * pair's result depends on that pair alone, so any split into chunks gives the same bits.
 * With acc, the chunk also adds each pair in contact onto its two bodies, in chunk order (the
 * sphere pairs straight from the law's lanes, their out[] not written): the caller passes it
 * where nothing of its own comes between these pairs. An owner's cross entry (ks[i] < 0, acc
 * given: pass 2 of sd_owned_pass) is not computed: its used[i] is 0, and step 5 adds the
 * owner's side of pass 1's result (q->xout, q->xact) in its place. */
void sd_bb_chunk(const sd_world *w, const sd_law *law, const int32_t *ks, const soa_view *v, int n, sd_pair_out *out,
                 int *used, ss_batch *q, sd_bodies *acc)
{
    const sd_pair *restrict pairs = w->bb.p;
    sd_hist *restrict hist = v->sh;
    const sd_contact_kernels *K = w->kern; /* (the SIMD kernels at this world's level) */
    int gen[SS_CHUNK];
    int m = 0, ng = 0;
    q->sh = v->sh;
    q->lsq = v->lsq;
    /* 1. which pairs touch (ss_filter_range) */
    {
        /* (8 pairs at a time in AVX-512, 4 in AVX2, where the CPU has it; the rest, or all,
         * in the scalar loop) */
        int i = 0;
        if (K->ss_filter) i = K->ss_filter(w, ks, v, 0, n, used, q, &m, gen, &ng);
        ss_filter_range(w, ks, v, i, n, used, q, &m, gen, &ng);
    }
    /* 2. the other shapes, through the manifold */
    {
        int msc = 0;
        if (K->sc_geom && w->sw[SD_SW_SC_LANES] && w->sw[SD_SW_SC_GEOM]) {
            /* the sphere-log pairs in lanes (sd_avx2_sc_geom), the others first, one by one: each
             * pair's result is its own, whatever the order (same bits) */
            int sg[SS_CHUNK], nsg = 0;
            for (int g = 0; g < ng; g++) {
                const int i = gen[g];
                if (ks[i] < 0) continue; /* (a cross entry: done in pass 1) */
                /* kind and cap from the view (ck), the record read only for the others */
                if (v->ck[i] == ck_pack(SD_PAIR_SC, 1))
                    sg[nsg++] = i;
                else
                    msc += other_pair(w, law, &pairs[ks[i]], i, &q->sc, msc, out, used);
            }
            msc = K->sc_geom(w, law, ks, v, sg, nsg, &q->sc, msc, out, used);
        } else
            for (int g = 0; g < ng; g++) {
                const int i = gen[g];
                if (ks[i] >= 0) msc += other_pair(w, law, &pairs[ks[i]], i, &q->sc, msc, out, used);
            }
        if (msc > 0) sc_flush(w, law, &q->sc, msc, ks, v, out, used);
    }
    /* 3. the rest of what the law needs of the touching spheres */
    {
        const int j = K->ss_gather ? K->ss_gather(w, q, m) : 0;
        ss_gather_range(w, q, j, m);
    }
    /* 4. the law, vectorized (with several materials, each lane's from the table, by the
     * loop that the compiler vectorizes: the AVX2 loop holds one law in its registers) */
    {
        sd_lane_law_ss_normal(q, m);
        if (w->ctx.multi) {
            int32_t lw[SS_CHUNK] = {0};
            for (int j = 0; j < m; j++)
                lw[j] = sd_mat_pair(w->b.mat[q->ia[j]], w->b.mat[q->ib[j]]);
            sd_lane_law_ss_spring_mat(w->ctx.lanes, lw, q, m);
        } else {
            const int j = K->ss_law_spring && w->sw[SD_SW_SS_LAW256] ? K->ss_law_spring(&w->ctx.lane, q, m) : 0;
            sd_lane_law_ss_spring(&w->ctx.lane, q, j, m);
        }
    }
    /* 5. results and springs back */
    if (acc) {
        /* every pair in contact onto its two bodies in chunk order: the sphere pairs from the
         * lanes (sel ascending), the other shapes' pairs (gen ascending) from out[] between */
        int g = 0;
        for (int j = 0; j <= m; j++) {
            const int i = j < m ? q->sel[j] : n;
            for (; g < ng && gen[g] < i; g++) {
                const int e = gen[g];
                if (used[e] > 0) { /* A then B, its bodies from the view (not the store's line) */
                    add_pair_sink(acc, q->bed_lim, v->a[e], 0, &out[e], q->sink);
                    add_pair_sink(acc, q->bed_lim, v->b[e], 1, &out[e], q->sink);
                } else if (ks[e] < 0 && q->xact[~ks[e]]) { /* a cross entry in contact: the owner's side */
                    const int ia = v->a[e], own_a = ia >= q->own_lo && ia < q->own_hi;
                    add_pair_lim(acc, q->bed_lim, own_a ? ia : v->b[e], !own_a, &q->xout[~ks[e]]);
                }
            }
            if (j == m) break;
            /* four lanes at once where no other shape's pair comes between them and none is
             * to be redone (nearly always) */
            if (K->ss_sums && j + 4 <= m && (g == ng || gen[g] > q->sel[j + 3]) && K->ss_sums(q, j, acc)) {
                j += 3;
                continue;
            }
            const int ia = q->ia[j], ib = q->ib[j];
            sd_hist *h = &hist[q->off[j]];
            if (q->redo[j] != 0.0) {
                ss_redo(w, law, &pairs[ks[i]], h, q->lsq, q->was[j], &out[i]);
                add_pair_lim(acc, q->bed_lim, ia, 0, &out[i]);
                add_pair_lim(acc, q->bed_lim, ib, 1, &out[i]);
                continue;
            }
            if (!q->lsq) h->feature = 0; /* (a list's own slot keeps its sqm there) */
            h->shear = v3(q->sx[j], q->sy[j], q->sz[j]);
            const double mla = -q->la[j], mlb = -q->lb[j];
            sd_pair_out o;
            o.f_a = v3(q->fx[j], q->fy[j], q->fz[j]);
            o.t_a = v3(q->nfx[j] * mla, q->nfy[j] * mla, q->nfz[j] * mla);
            o.t_b = v3(q->nfx[j] * mlb, q->nfy[j] * mlb, q->nfz[j] * mlb);
            add_pair_lim(acc, q->bed_lim, ia, 0, &o); /* (a pair's A is never of the bed) */
            add_pair_sink(acc, q->bed_lim, ib, 1, &o, q->sink);
        }
        return;
    }
    for (int j = 0; j < m; j++) {
        const int i = q->sel[j];
        sd_hist *h = &hist[q->off[j]];
        if (q->redo[j] != 0.0) {
            ss_redo(w, law, &pairs[ks[i]], h, q->lsq, q->was[j], &out[i]);
            continue;
        }
        if (!q->lsq) h->feature = 0;
        h->shear = v3(q->sx[j], q->sy[j], q->sz[j]);
        const double mla = -q->la[j], mlb = -q->lb[j];
        out[i].f_a = v3(q->fx[j], q->fy[j], q->fz[j]);
        out[i].t_a = v3(q->nfx[j] * mla, q->nfy[j] * mla, q->nfz[j] * mla);
        out[i].t_b = v3(q->nfx[j] * mlb, q->nfy[j] * mlb, q->nfz[j] * mlb);
    }
}

long sd_bb_serial_pass(sd_world *w, const sd_law *law, bb_scratch *x)
{
    sd_bodies *b = &w->b;
    long count = 0;
    const int nn = w->near_n; /* (sd_near_update made the list and its records) */
    const int pf = sd_front_prefetch_on(w);
    int front = -1;
    sd_bb_bed_split(w, &x->bed);
    x->q.bed_lim = x->bed.bed_lim;
    if (x->bed.bed_lim >= 0) {
        /* the bodies before the bed as two runs (the bed's load stays zero; none at all: the
         * arrays may be NULL, which memset must not get even for 0 bytes) */
        if (x->bed.nf > 0) {
            memset(b->force, 0, (size_t)x->bed.nf * sizeof(sd_vec3));
            memset(b->torque, 0, (size_t)x->bed.nf * sizeof(sd_vec3));
        }
    } else
        for (int i = 0; i < b->n; i++)
            if (!sd_body_is_bed(b, i)) { /* (two stores: the chained assignment read torque back) */
                b->force[i] = v3(0, 0, 0);
                b->torque[i] = v3(0, 0, 0);
            }
    sd_hist *const sh = springs_of(w, 1, w->near_hist);
    const int lsq = sh != w->bb.hist && w->springs_lsq; /* (soa_view.lsq) */
    for (int k0 = 0; k0 < nn; k0 += SS_CHUNK) {
        const int n = nn - k0 < SS_CHUNK ? nn - k0 : SS_CHUNK;
        /* the chunk adds its pairs onto the bodies itself, in pair order */
        if (pf) {
            const int p0 = k0 + PF_CHUNKS * SS_CHUNK, p1 = p0 + SS_CHUNK < nn ? p0 + SS_CHUNK : nn;
            if (p1 > p0) {
                sd_front_prefetch_rows(b, w->near_soa.a, w->near_soa.b, p0, p1, b->n, &front);
                pf_hist(sh, w->near_soa.off, w->near_soa.act, p0, p1, lsq);
            }
        }
        const soa_view v = soa_at(&w->near_soa, k0, sh, lsq);
        sd_bb_chunk(w, law, &w->near[k0], &v, n, x->out, x->used, &x->q, b);
        for (int i = 0; i < n; i++)
            count += x->used[i];
    }
    return count;
}
