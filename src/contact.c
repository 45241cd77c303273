/* Per-step contact evaluation, the pass's orchestration: the body-body pass (one thread:
 * contact_bb.c over the near list, near_list.c; T threads: owners.c), the body-wall pass
 * (contact_bt.c), the wall loads gathered on demand. Narrow phase through a shape-pair dispatch
 * (contact_manifold.c), history matched by feature; body-body forces summed into each body in
 * pair order (owned body ranges per thread, see below), body-triangle forces per pair then
 * gathered per body in pair order, so that 1 and N threads give the same bits. The files the
 * pass is split into share contact_internal.h and contact_kernels.h. */
#include <stdlib.h>
#include <string.h>

#include "contact_internal.h"

/* Body-body forces are added to the bodies in pair order: each body's force is the sum of its
 * pairs' contributions in ascending pair index, whatever the thread count, so 1 and N threads
 * give the same bits.
 * One thread: one pass over the pairs, adding as it goes.
 * T threads: the bodies are split into T index ranges holding about nbb/T pairs each (the
 * store is sorted by cell, so a range is a region of space) and thread t owns range t. At
 * each candidate rebuild the pairs whose two bodies have different owners ("cross" pairs, a
 * thin layer at the range boundaries) are listed, and each owner gets the list of pair indices touching its
 * range. Pass 1 computes the cross pairs, once each, into their own slots. Pass 2: each thread walks its list in
 * ascending order, computing the pairs it owns both sides of and adding them, and adding the stored cross pairs to its
 * side. Every pair is computed exactly once, and its history slot written by one thread only. */

static long sc_geom_run;

long sd_contact_sc_geom_count(void) { return __atomic_load_n(&sc_geom_run, __ATOMIC_RELAXED); }

static long sc_lanes_run, sc_lanes_redo;

long sd_contact_sc_lanes_count(long *redo)
{
    if (redo) *redo = __atomic_load_n(&sc_lanes_redo, __ATOMIC_RELAXED);
    return __atomic_load_n(&sc_lanes_run, __ATOMIC_RELAXED);
}

/* The threads' lane counts into the process's totals, after the pass: no shared write in the
 * hot loop (relaxed adds here only because two worlds may step in two threads at once). */
static void sc_lanes_fold(void *scratch, int T)
{
    for (int t = 0; t < T; t++) {
        struct sc_lanes *q = &((bb_scratch *)scratch)[t].q.sc;
        if (q->n_run) __atomic_fetch_add(&sc_lanes_run, q->n_run, __ATOMIC_RELAXED);
        if (q->n_redo) __atomic_fetch_add(&sc_lanes_redo, q->n_redo, __ATOMIC_RELAXED);
        if (q->n_geom) __atomic_fetch_add(&sc_geom_run, q->n_geom, __ATOMIC_RELAXED);
        q->n_run = q->n_redo = q->n_geom = 0;
    }
}

sd_status sd_contact_near_remake(sd_world *w)
{
#ifdef SD_FILTER512
    sd_avx2_tables_ready();
#endif
    w->near_drift = w->near_skin; /* as a drift past half the skin would */
#ifdef _OPENMP
    const int T = sd_owned_count(w);
    if (T > 1) return sd_owned_update(w, T);
#endif
    return sd_near_update(w);
}

sd_status sd_contact_compute(sd_world *w, int *integrated)
{
#ifdef SD_FILTER512
    sd_avx2_tables_ready();
#endif
    const sd_law *law = &sd_law_ctx_ready(w)->law;
    long count = 0;
    const int T = sd_owned_count(w);
    if (integrated) *integrated = 0;
    if (w->bb_scratch_n < T) {
        free(w->bb_scratch);
        w->bb_scratch_n = 0;
        w->bb_scratch = malloc((size_t)T * sizeof(bb_scratch));
        if (!w->bb_scratch) return SD_ERR_NOMEM;
        w->bb_scratch_n = T;
        for (int t = 0; t < T; t++) {
            bb_scratch *x = &((bb_scratch *)w->bb_scratch)[t];
            x->q.sc.n_run = x->q.sc.n_redo = x->q.sc.n_geom = 0;
            x->bed.n = 0;                           /* (found afresh) */
            memset(x->q.sink, 0, sizeof x->q.sink); /* (never read, but not garbage either) */
        }
    }
#ifdef _OPENMP
    if (T > 1) {
        sd_status st = sd_owned_update(w, T);
        if (!st) st = sd_near_springs_to(w, 2);
        if (st) return st;
        int moved = 0;
        sd_moves mv = SD_MOVES_NONE;
        count = sd_owned_pass(w, law, T, w->bb_scratch, integrated ? &moved : NULL, &mv);
        for (int t = 0; t < T; t++)
            w->wall_skipped += w->owned->wskip[t];
        if (moved) w->need_rebuild = 1;
        if (integrated) {
            *integrated = 1;
            sd_integrate_after_moves(w, &mv);
        }
    } else
#endif
    {
        sd_status nst = sd_near_update(w);
        if (!nst) nst = sd_near_springs_to(w, 1);
        if (nst) return nst;
        count = sd_bb_serial_pass(w, law, w->bb_scratch);
        count += sd_bt_range(w, law, w->wall_list, w->wall_n, &((bb_scratch *)w->bb_scratch)[0].wq);
        w->wall_skipped += w->wall_skip;
    }
    sc_lanes_fold(w->bb_scratch, T);
    w->contacts = count;
    w->wall_force_stale = 1;
    return SD_OK;
}

int sd_contact_near_count(const sd_world *w)
{
    const sd_owned *o = w->owned;
    if (o && o->stamp == w->near_version) {
        int m = 0;
        for (int t = 0; t < o->T; t++)
            m += o->seg1[t] - o->K[t];
        return m;
    }
    return w->near_soa_version == w->near_version + 1 ? w->near_n : 0;
}

/* Loads on the walls, in pair order (serial: few pairs, fixed order), from the wall pairs'
 * slots of the last step, when they are asked for (sd_world_group_force, a checkpoint, or
 * before the pair lists are taken apart): done every step, it read each thread's slots into
 * one thread's cache and cost 5-15 % of a two-thread step. The bodies' own totals are gathered
 * pair by pair onto each body after its body-body sum (sd_bt_range). */
void sd_contact_gather(sd_world *w)
{
    if (!w->wall_force_stale) return;
    w->wall_force_stale = 0;
    for (int t = 0; t < w->w.n; t++)
        w->w.force[t] = v3(0, 0, 0);
    for (int k = 0; k < w->bt.n; k++) {
        if (!w->bt.active[k]) continue;
        int t = w->bt.p[k].b;
        w->w.force[t] = v3_sub(w->w.force[t], w->bt.out[k]);
    }
}

static const sd_contact_kernels scalar_kernels = {NULL, NULL, NULL, NULL, NULL, NULL};

const sd_contact_kernels *sd_contact_kernels_for(int simd)
{
#ifdef SD_FILTER512
    if (simd == SD_SIMD_AVX512) return &sd_avx512_kernels;
    if (simd == SD_SIMD_AVX2) return &sd_avx2_kernels;
#else
    (void)simd;
#endif
    return &scalar_kernels;
}
