/* The near list (the body-body candidates worth testing each step), the wall-near list, and
 * the sphere pairs' springs held in a near list's own order. */
#include <stdint.h>
#include <string.h>

#include "contact_kernels.h"

/* near_test of candidates k0 .. k1-1 into keep[k - k0] (1 or 0; returned), then what it means for each:
 * a pair left out has its springs cleared, as the pass would clear them. Only a pair that was
 * near when the near pairs were last made (near_mark), or any pair after a rebuild (fresh: the
 * carried springs), can hold a spring, since only the pass sets one and it sees near pairs
 * only: the other candidates' spring slots are not touched, which spares each remaking a
 * cache line per candidate. The answers first, alone, then their consequences with one
 * seldom-taken branch: the loop that did both as it went, branching on a coin toss, took 18 ns
 * a candidate. */
static const uint8_t *near_keep_range(sd_world *w, double skin, int k0, int k1, int fresh, int nf)
{
    const sd_pair *restrict pairs = w->bb.p;
    uint8_t *restrict keep = w->near_mark + w->bb.n + 1 + k0; /* (near_mark's second half) */
    int k = k0;
    if (w->kern->near_test) k = w->kern->near_test(w, skin, k0, k1, keep, nf);
    for (; k < k1; k++)
        keep[k - k0] = (uint8_t)near_test(w, skin, &pairs[k], nf);
    uint8_t *restrict mark = w->near_mark;
    sd_hist *restrict hist = w->bb.hist;
    for (int j = k0; j < k1; j++) {
        const int kp = keep[j - k0];
        if ((kp ^ 1) & (fresh | mark[j])) { /* (one branch, seldom taken: kp is a coin toss) */
            const sd_pair *p = &pairs[j];
            for (int s = 0; s < p->cap; s++)
                hist[p->off + s].feature = -1;
        }
        mark[j] = (uint8_t)kp;
    }
    return keep;
}

/* near_mark sized for the candidates (its second half: the answers' scratch, keep[] of
 * near_keep_range at each candidate's place); returns whether this making of the near pairs is
 * the first since the rebuild (fresh), or -1 when out of memory. */
int sd_near_mark_ready(sd_world *w)
{
    if (sd_grow((void **)&w->near_mark, &w->near_mark_cap, 2 * (w->bb.n + 1), 1)) return -1;
    const int fresh = w->near_mark_rb != w->timers.rebuilds;
    w->near_mark_rb = w->timers.rebuilds;
    return fresh;
}

/* The near ones among candidates kb .. ke-1 (ke - kb <= NEAR_BLOCK), ascending, into near[];
 * returns how many. Their answers made (near_keep_range), then found 8 at a time (a 64-bit word
 * of answer bytes, each 0 or 1), while the block's records are still in L1: writing every
 * candidate's records and overwriting those not kept cost as much as the tests, with about one
 * candidate in four kept in the paper's flow. */
int sd_near_block(sd_world *w, double skin, int kb, int ke, int fresh, int nf, int32_t *near)
{
    const uint8_t *kp = near_keep_range(w, skin, kb, ke, fresh, nf);
    int n = 0;
    for (int j8 = 0; j8 < ke - kb; j8 += 8) {
        uint64_t word = 0;
        if (ke - kb - j8 >= 8)
            memcpy(&word, kp + j8, 8);
        else
            for (int l = 0; l < ke - kb - j8; l++)
                word |= (uint64_t)kp[j8 + l] << 8 * l;
        for (; word; word &= word - 1)
            near[n++] = kb + j8 + __builtin_ctzll(word) / 8;
    }
    return n;
}

/* The candidates worth testing (sd_near_update), into out in ascending order, with their
 * records; returns how many. */
static int near_filter(sd_world *w, double skin, int fresh, int32_t *out, sd_pair_soa *soa, sd_hist *sh)
{
    const sd_pair *pairs = w->bb.p;
    const sd_hist *hist = w->bb.hist;
    const int nbb = w->bb.n, nf = sd_bed_start(&w->b);
    int m = 0;
    int32_t near[NEAR_BLOCK];
    for (int kb = 0; kb < nbb; kb += NEAR_BLOCK) {
        const int ke = nbb - kb < NEAR_BLOCK ? nbb : kb + NEAR_BLOCK;
        const int nn = sd_near_block(w, skin, kb, ke, fresh, nf, near);
        for (int q = 0; q < nn; q++) {
            const sd_pair *p = &pairs[near[q]];
            out[m] = near[q];
            /* (its records too, while the record is at hand; with sh, a sphere pair's spring
             * out into the list's order, its slot's line just read for the flag) */
            pair_soa_set(soa, m, p, hist, w->b.radius);
            if (sh && p->kind == SD_PAIR_SS) spring_out(sh, soa->off, m, hist, soa->sqm[m], w->springs_lsq);
            m++;
        }
    }
    return m;
}

/* The bodies among i0 .. i1-1 with wall pairs that are near touching one, into list
 * (ascending; returns how many; *skip: how many were left out): near when the centre's distance
 * to a triangle's plane (no nearer than that to the triangle) less the radius, or a log's
 * extent along the plane's normal, is below half the skin. A body
 * farther from every plane cannot reach one before the near pairs are remade (walls do not
 * move; a triangle switched on forces a rebuild). All of them when switch SD_SW_WALL_NEAR is off. */
int sd_near_walls(sd_world *w, double skin, int i0, int i1, int32_t *list, long *skip)
{
    const sd_bodies *b = &w->b;
    const sd_walls *wl = &w->w;
    const sd_pair *p = w->bt.p;
    const int kend = w->csr.bt_start[i1];
    int m = 0;
    long left = 0;
    for (int from = w->csr.bt_start[i0]; from < kend;) {
        const int i = p[from].a, to = w->csr.bt_start[i + 1];
        const int sphere = b->shape[i] == SD_SHAPE_SPHERE;
        /* half the skin: a wall does not move, only the body closes the gap, by less than half
         * the skin before the near pairs are remade */
        const double hs = 0.5 * skin, reach = b->radius[i] + hs;
        int near = !w->sw[SD_SW_WALL_NEAR];
        for (int k = from; k < to; k++) {
            const sd_tri *t = &wl->tri[p[k].b];
            /* a log reaches hl |a.n| + r sqrt(1 - (a.n)^2) along the plane's normal, its
             * extent there whatever its spin: a log lying on the bed roughness, half its
             * bounding radius off the floor, is not near it (the near pairs' drift bound
             * counts a log's turning, at its bounding radius) */
            double rk = reach;
            if (!sphere) {
                const double an = fabs(v3_dot(b->axis[i], t->n)), s2 = 1.0 - an * an;
                rk = b->hl[i] * an + b->radius[i] * sqrt(s2 > 0.0 ? s2 : 0.0) + hs;
            }
            near |= wl->active[p[k].b] && fabs(v3_dot(v3_sub(b->pos[i], t->v[0]), t->n)) < rk;
        }
        list[m] = i;
        m += near;
        left += !near;
        from = to;
    }
    *skip = left;
    return m;
}

/* The sphere pairs' springs of a near list in the list's own order (world_internal.h,
 * springs_out). The candidates' slots are 5.4 a sphere in a dense bed, against 2.8 near pairs
 * and 1.7 touching: the pass walked them as a sparse run of lines, one or two a sphere and
 * step, which past the last-level cache came from DRAM. In the list's order the springs are
 * one stream, read and written in step with the records (at 1e5 spheres the step 0.87-0.89x). They go out as a list is
 * made (near_filter, sd_owned_update: the slot's line is read there for the flag), or at a pass's start when they were
 * put back since (sd_near_springs_to), and back (sd_near_springs_home) before the list is remade or anything reads
 * bb.hist. Below: entries k0 .. k1 of a list (candidate indices, an owner's cross entry negative) whose records s are
 * of a sphere pair (ck kind 0; the others keep their slots in bb.hist). */
static void springs_out_range(sd_world *w, sd_pair_soa *s, sd_hist *h, int k0, int k1)
{
    for (int k = k0; k < k1; k++)
        if (ck_kind(s->ck[k]) == SD_PAIR_SS) spring_out(h, s->off, k, w->bb.hist, s->sqm[k], w->springs_lsq);
}

static void springs_home_range(sd_world *w, const int32_t *list, sd_pair_soa *s, const sd_hist *h, int k0, int k1)
{
    const sd_pair *restrict pairs = w->bb.p;
    sd_hist *restrict bh = w->bb.hist;
    for (int k = k0; k < k1; k++)
        if (ck_kind(s->ck[k]) == SD_PAIR_SS) {
            const int off = pairs[list[k]].off;
            if (w->springs_lsq) { /* (the feature from the entry's flag: the slot holds the sqm there) */
                bh[off].feature = s->act[k] ? 0 : -1;
                bh[off].shear = h[k].shear;
            } else
                bh[off] = h[k];
            s->off[k] = off;
        }
}

void sd_near_springs_home(sd_world *w)
{
    if (w->springs_out == 1)
        springs_home_range(w, w->near, &w->near_soa, w->near_hist, 0, w->near_n);
    else if (w->springs_out == 2) {
        /* each owner's segment by a thread of its own, as the lists were made */
        sd_owned *o = w->owned;
#pragma omp parallel for schedule(static, 1) num_threads(o->T) if (o->T > 1 && w->bb.n > w->def.parallel_min)
        for (int t = 0; t < o->T; t++)
            springs_home_range(w, o->list, &o->soa, o->hist, o->K[t], o->seg1[t]);
    }
    w->springs_out = 0;
}

/* The springs of the list the pass is about to use out of their slots, from wherever they
 * are (after a hash or a checkpoint, or the other pass's list), in the slots' form the switch
 * asks for (sd_slot_sqm_set): `out` 1 the serial list (near list current), 2 the owners'
 * (sd_owned_update has made them current). Only put back when the switch is off. */
sd_status sd_near_springs_to(sd_world *w, int out)
{
    if (w->springs_out == out && w->sw[SD_SW_SPRINGS_LIST] && w->springs_lsq == w->sw[SD_SW_SLOT_SQM]) return SD_OK;
    sd_near_springs_home(w);
    if (!w->sw[SD_SW_SPRINGS_LIST]) return SD_OK;
    w->springs_lsq = w->sw[SD_SW_SLOT_SQM];
    if (out == 1) {
        if (sd_grow((void **)&w->near_hist, &w->near_hist_cap, w->near_n + 1, sizeof(sd_hist))) return SD_ERR_NOMEM;
        springs_out_range(w, &w->near_soa, w->near_hist, 0, w->near_n);
    } else {
        sd_owned *o = w->owned;
        if (sd_grow((void **)&o->hist, &o->hist_cap, o->K[o->T] + 1, sizeof(sd_hist))) return SD_ERR_NOMEM;
        for (int t = 0; t < o->T; t++)
            springs_out_range(w, &o->soa, o->hist, o->K[t], o->seg1[t]);
    }
    w->springs_out = out;
    return SD_OK;
}

/* The near pairs (of either pass) still good: no rebuild since, and no surface has drifted
 * half the near skin (sd_near_update). */
int sd_near_still_good(const sd_world *w)
{
    return w->near_stamp == w->timers.rebuilds && !w->rebuild_every_step && 2.0 * w->near_drift < 0.999 * w->near_skin;
}

/* The near pairs have just been made (by either pass) with this skin. */
void sd_near_made(sd_world *w, double skin)
{
    w->near_version++;
    w->near_stamp = w->timers.rebuilds;
    w->near_drift = 0.0;
    w->near_skin = skin;
}

/* The near list (w->near): the body-body pairs worth testing each step. A pair whose gap
 * exceeds the near skin s (w->near_skin) cannot touch before the moving bodies have drifted
 * by s/2 between them (near_drift, summed from each step's largest move of a surface), so it
 * is left out until then: its force is exactly zero, its spring is cleared here as the pass
 * would clear it, and every body sums the same pairs in the same order (same bits). In a dense
 * bed the margin's candidates are twice the contacts; most of the rest are far beyond s. */
sd_status sd_near_update(sd_world *w)
{
    const int nbb = w->bb.n;
    /* (near_soa_version: not remade since by the owners' path, which keeps its own lists) */
    if (sd_near_still_good(w) && w->near_nbb == nbb && w->near && w->near_soa_version == w->near_version + 1)
        return SD_OK;
    sd_near_springs_home(w); /* (from the list about to go) */
    const double skin = SD_NEAR_SKIN * w->def.margin;
    if (sd_grow((void **)&w->near, &w->near_cap, nbb + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    const int fresh = sd_near_mark_ready(w);
    if (fresh < 0 || sd_pair_soa_reserve(&w->near_soa, nbb + 1) ||
        sd_grow((void **)&w->wall_list, &w->wall_list_cap, w->b.n + 1, sizeof(int32_t)))
        return SD_ERR_NOMEM;
    /* the springs out as the list is made (springs_out 1), when the switch is on */
    if (w->sw[SD_SW_SPRINGS_LIST] && sd_grow((void **)&w->near_hist, &w->near_hist_cap, nbb + 1, sizeof(sd_hist)))
        return SD_ERR_NOMEM;
    w->springs_lsq = w->sw[SD_SW_SLOT_SQM];
    w->near_n = near_filter(w, skin, fresh, w->near, &w->near_soa, w->sw[SD_SW_SPRINGS_LIST] ? w->near_hist : NULL);
    w->springs_out = w->sw[SD_SW_SPRINGS_LIST] ? 1 : 0;
    w->wall_n = sd_near_walls(w, skin, 0, w->b.n, w->wall_list, &w->wall_skip);
    w->near_nbb = nbb;
    sd_near_made(w, skin);
    w->near_soa_version = w->near_version + 1;
    return SD_OK;
}
