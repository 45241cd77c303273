/* The contact pass's hot helpers that several of its files inline (static inline, so that
 * nothing on the hot path becomes an out-of-line call across files): the lanes' law constants,
 * the touch filters' steps for a log's pair, the sums onto the bodies, the records' packing,
 * a list's own spring slots, the near test. */
#ifndef SD_CONTACT_KERNELS_H
#define SD_CONTACT_KERNELS_H

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "contact_internal.h"


/* A log's pair that fails its kernel's first exact rejection (most of them): skips the
 * manifold round trip. */
static inline int log_pair_apart(const sd_bodies *b, const sd_pair *p)
{
    if (p->kind == SD_PAIR_SC) {
        const sd_cyl c = sd_body_cyl(b, p->b);
        double rho2;
        return sd_sphere_cyl_apart(b->pos[p->a], b->radius[p->a], &c, &rho2);
    }
    if (p->kind == SD_PAIR_CC) {
        const sd_cyl ca = sd_body_cyl(b, p->a), cb = sd_body_cyl(b, p->b);
        return sd_cyl_cyl_apart(&ca, &cb);
    }
    return 0;
}

/* The touch filter's step for a log's pair (entry i of the chunk): apart, it gets what the
 * manifold path gives for no contact (empty slots, no force); else it goes on to the manifold
 * path, listed in gen. */
static inline void filter_log_pair(const sd_world *w, const sd_pair *p, int i, int *used, int *gen, int *ng)
{
    if (log_pair_apart(&w->b, p)) {
        used[i] = 0;
        for (int s = 0; s < p->cap; s++)
            w->bb.hist[p->off + s].feature = -1;
    } else
        gen[(*ng)++] = i;
}

/* Whether body i is of the bed: from lim where the caller knows that the bed is the bodies
 * from lim on and no others (the passes after a sort: ss_batch's bed_lim, from sd_bb_bed_split),
 * else (lim < 0) from the store's flags. */
static inline int bed_at(const sd_bodies *b, int lim, int i) { return lim >= 0 ? i >= lim : sd_body_is_bed(b, i); }

static inline __attribute__((always_inline)) void add_pair_lim(sd_bodies *b, int lim, int i, int as_b,
                                                               const sd_pair_out *o)
{
    if (bed_at(b, lim, i)) return; /* its load is never read: stays zero (sd_bt_range adds nothing to a fixed body) */
    if (as_b) {
        b->force[i] = v3_sub(b->force[i], o->f_a);
        b->torque[i] = v3_add(b->torque[i], o->t_b);
    } else {
        b->force[i] = v3_add(b->force[i], o->f_a);
        b->torque[i] = v3_add(b->torque[i], o->t_a);
    }
}

/* add_pair_lim where the bed is the bodies from lim on (lim >= 0): a bed body's rows are
 * replaced by the two sink rows, chosen without a branch (a bed body comes at random among the
 * pairs of spheres resting on the roughness); the same sums into every other body. */
static inline __attribute__((always_inline)) void add_pair_sink(sd_bodies *b, int lim, int i, int as_b,
                                                                const sd_pair_out *o, sd_vec3 *sink)
{
    if (lim < 0) { /* (no bed split: the same for the whole pass) */
        add_pair_lim(b, lim, i, as_b, o);
        return;
    }
    const uintptr_t m = (uintptr_t)0 - (uintptr_t)(i >= lim), pf = (uintptr_t)&b->force[i],
                    pt = (uintptr_t)&b->torque[i];
    sd_vec3 *const f = (sd_vec3 *)(pf ^ ((pf ^ (uintptr_t)&sink[0]) & m)), *const t =
                                                                               (sd_vec3 *)(pt ^
                                                                                           ((pt ^ (uintptr_t)&sink[1]) &
                                                                                            m));
    if (as_b) {
        *f = v3_sub(*f, o->f_a);
        *t = v3_add(*t, o->t_b);
    } else {
        *f = v3_add(*f, o->f_a);
        *t = v3_add(*t, o->t_a);
    }
}

/* A record's cap and kind as the view holds them (ck): cap in the low half, kind in the high. */
static inline int32_t ck_pack(int kind, int cap)
{
    return (int32_t)((uint32_t)(uint16_t)cap | (uint32_t)(uint16_t)kind << 16);
}
static inline int ck_kind(int32_t ck) { return (int)((uint32_t)ck >> 16); }
/* the view's ck of an owner's cross entry (sd_owned_update): a kind of no pair */
#define SD_CK_CROSS ((int32_t)0x7FFF0000)

/* The touch filter's step for a chunk entry that is not a sphere pair: an owner's cross entry
 * (ks < 0: computed in pass 1, its side added by sd_bb_chunk's step 5) and, with defer, a
 * sphere-log pair (its apart test left to sd_avx2_sc_geom) go to gen as they are; a log's other pairs
 * through filter_log_pair. */
static inline void filter_other(const sd_world *w, const int32_t *ks, const soa_view *v, int j, int defer, int *used,
                                int *gen, int *ng)
{
    if (ks[j] < 0) {
        used[j] = 0;
        gen[(*ng)++] = j;
    } else if (defer && ck_kind(v->ck[j]) == SD_PAIR_SC)
        gen[(*ng)++] = j;
    else
        filter_log_pair(w, &w->bb.p[ks[j]], j, used, gen, ng);
}

/* (r_a + r_b)^2 of a pair's bodies, as the touch filters square it */
static inline double pair_rs2(const double *rad, const sd_pair *p)
{
    const double rs = rad[p->a] + rad[p->b];
    return rs * rs;
}

/* An entry's rs2 (sd_pair_soa), for the AVX2 filter (sd_avx2_ss_filter), which reads no ck: a
 * sphere pair's (r_a + r_b)^2 rounded to a float, so within a relative 2^-24 of the double;
 * +NaN where that would leave the float's normal range (the filter then tests every such pair
 * exactly); -1 for any other entry, whose sign tells that it is not a sphere pair. */
#define RS2_EDGE 0x1p-22 /* the filter's band around the float: wider than its rounding */
static inline float entry_rs2(const double *rad, const sd_pair *p)
{
    if (p->kind != SD_PAIR_SS) return -1.0f;
    const double r = pair_rs2(rad, p);
    return r >= 0x1p-100 && r <= 0x1p100 ? (float)r : NAN;
}

/* Entry j of s from the record p (and its first slot in hist; rad: the bodies' radii). */
static inline void pair_soa_set(sd_pair_soa *s, int j, const sd_pair *p, const sd_hist *hist, const double *rad)
{
    s->rs2[j] = entry_rs2(rad, p);
    s->a[j] = p->a;
    s->b[j] = p->b;
    s->off[j] = p->off;
    s->ck[j] = ck_pack(p->kind, p->cap);
    s->sqm[j] = p->sqrt_m_eff;
    s->act[j] = (uint8_t)(hist[p->off].feature >= 0);
}

/* A list's own spring slot (soa_view.lsq): sqrt_m_eff in the feature's 8 bytes (the feature
 * and its padding), the spring where bb.hist has it. */
_Static_assert(sizeof(sd_hist) == 32 && offsetof(sd_hist, shear) == 8, "a list's slot: sqm in the first 8 bytes");
static inline double slot_sqm(const sd_hist *h)
{
    double x;
    memcpy(&x, h, sizeof x);
    return x;
}

/* Entry k's spring out of its slot off[k] of bh into h[k], with its sqrt_m_eff sqm, and
 * off[k] pointed there (the near lists' springs in list order, springs_out below). */
static inline void spring_out(sd_hist *h, int32_t *off, int k, const sd_hist *bh, double sqm, int lsq)
{
    if (lsq) {
        h[k].shear = bh[off[k]].shear;
        memcpy(&h[k], &sqm, sizeof sqm);
    } else
        h[k] = bh[off[k]];
    off[k] = k;
}

static inline soa_view soa_at(const sd_pair_soa *s, int j0, sd_hist *sh, int lsq)
{
    return (soa_view){s->a + j0,   s->b + j0,   s->off + j0, s->ck + j0, s->sqm + j0,
                      s->rs2 + j0, s->act + j0, sh,          lsq,        j0};
}

/* Whether candidate p can touch before the bodies drift by half the skin (sd_near_update): its
 * gap is below the skin, or half of it with a body of the bed (from nf on), which does not
 * move: only the other closes the gap, by less than half the skin. */
static inline int near_test(const sd_world *w, double skin, const sd_pair *p, int nf)
{
    const sd_vec3 *pos = w->b.pos;
    const double *rad = w->b.radius;
    if (p->a >= nf || p->b >= nf) skin *= 0.5;
    if (p->kind == SD_PAIR_SS) {
        const double reach = rad[p->a] + rad[p->b] + skin;
        return v3_norm2(v3_sub(pos[p->a], pos[p->b])) <= reach * reach;
    }
    /* a log lies within its radius of its axis segment: two logs whose segments are farther
     * apart than their radii and the skin cannot touch (the drift bound counts their turning,
     * at their bounding radii) */
    if (p->kind == SD_PAIR_CC) return sd_axis_gap(&w->b, p->a, p->b) <= rad[p->a] + rad[p->b] + skin;
    /* nor a sphere farther than the radii and the skin from the segment */
    const sd_cyl c = sd_body_cyl(&w->b, p->b);
    const double ra = rad[p->a];
    const sd_vec3 d = v3_sub(pos[p->a], c.c);
    double t = v3_dot(d, c.a);
    t = t > c.hl ? c.hl : (t < -c.hl ? -c.hl : t);
    const double reach = ra + c.r + skin;
    return v3_norm2(v3_madd(d, c.a, -t)) <= reach * reach;
}

/* The sphere pairs' slots of the list whose springs are out as `out`, else bb.hist. */
static inline sd_hist *springs_of(const sd_world *w, int out, sd_hist *h)
{
    return w->springs_out == out ? h : w->bb.hist;
}

/* The slots of entries j0 .. j1 that hold a spring (act), with the front: the gather reads them
 * for the touching lanes only, about one candidate slot in three (the slots are the candidates',
 * 5.4 a sphere in the tiled bed, 2.8 near pairs, 1.7 touching), a sparse walk the hardware
 * prefetchers do not follow. Part of the front prefetch (front_prefetch.c), so the run's trial weighs it too.
 * `bench_scale --ab prefetch` (on/off) at 1e5 went from 0.92 (the front alone) to 0.83 on one
 * thread and from 0.99 to 0.81-0.85 on two; at 1e4, where the trial leaves it off, from 1.07-1.09
 * to 1.08-1.11. Without a branch: a test on act, true for three
 * entries in five at random, cost 10-17 % at 1e4 in mispredictions; the other entries prefetch
 * the list's first line, a hit. Into L2 (prefetcht2): 0.83 / 0.81 at 1e5 on one / two threads,
 * against 0.86 / 0.87 into L1. */
static inline void pf_hist(const sd_hist *h, const int32_t *off, const uint8_t *act, int j0, int j1, int lsq)
{
    if (lsq) /* (a list's own slots: entry j's at j, off not read) */
        for (int j = j0; j < j1; j++)
            __builtin_prefetch(h + (j & -(int32_t)act[j]), 1, 1);
    else
        for (int j = j0; j < j1; j++)
            __builtin_prefetch(h + (off[j] & -(int32_t)act[j]), 1, 1);
}

#endif
