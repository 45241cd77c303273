/* The contact history (tangential springs) carried across a candidate rebuild: taken out of
 * the pair lists keyed by (gid, kind, gid or triangle) before the store is re-sorted, and put
 * into the new lists' slots by key after (LAMMPS GRANULAR's habit; docs/architecture.md). */
#include <stdlib.h>
#include <string.h>

#include "neighbor_internal.h"

static uint64_t pair_key(int32_t gid_a, int kind, int32_t id_b)
{
    return ((uint64_t)(uint32_t)gid_a << 32) | ((uint64_t)(uint32_t)kind << 29) | (uint64_t)(uint32_t)id_b;
}

static uint64_t key_of(const sd_world *w, const sd_pair *p)
{
    int32_t ida = w->b.gid[p->a];
    int32_t idb = (p->kind == SD_PAIR_ST || p->kind == SD_PAIR_CT) ? p->b : w->b.gid[p->b];
    return pair_key(ida, p->kind, idb);
}

/* Pair k of the two lists taken as one (body-body first, then body-triangle). */
static inline const sd_pair *any_pair(const sd_pairlist *const *lists, int k)
{
    return k < lists[0]->n ? &lists[0]->p[k] : &lists[1]->p[k - lists[0]->n];
}

static inline const sd_hist *any_hist(const sd_pairlist *const *lists, int k, const sd_pair *p)
{
    return (k < lists[0]->n ? lists[0]->hist : lists[1]->hist) + p->off;
}

/* The held springs of every pair, taken out of the lists before they are remade (sd_hist,
 * keyed by the pair's gids and kind, so they survive the reordering of the store). Grouped by
 * the first body's store index, ascending (a counting sort: the threads count their share of
 * the pairs per body, then each puts its entries in place), and inside a body in list order;
 * a pair's entries, in feature order, are one run. The list runs in store order and a pair's
 * first body is at most a slab of cells from its lower one, so the counts and the entries are
 * written within a window that the caches hold (grouped by gid, which the store does not
 * follow, the writes went anywhere: the collect took 109-186 ms a rebuild at 1e6 spheres,
 * 50-55 since, performance pass P41, in the git history). restore_history finds a body's entries through the rebuild's
 * sort, or, when the store changed since the collect, through the gid in the keys. */
sd_status sd_history_collect(sd_world *w)
{
    sd_near_springs_home(w); /* (the near list's springs into their slots) */
    if (w->keys_collected) return SD_OK;
    sd_contact_gather(w); /* the wall loads of the last step, before its pairs go */
    const sd_pairlist *lists[2] = {&w->bb, &w->bt};
    const int np = w->bb.n + w->bt.n, n = w->b.n;
    const int T = rebuild_threads(w, np);
    /* cnt[t * (n + 1) + i]: thread t's entries of body i, then where they go */
    const size_t ncnt = (size_t)T * (n + 1) + 1;
    if (ncnt > INT32_MAX || sd_grow((void **)&w->old_cnt, &w->old_cnt_cap, (int)ncnt, sizeof(int32_t)) ||
        sd_grow((void **)&w->old_start, &w->old_start_cap, n + 1, sizeof(int32_t)))
        return SD_ERR_NOMEM;
    int32_t *cnt = w->old_cnt;
    memset(cnt, 0, ncnt * sizeof(int32_t));
    /* only a body-body pair near when the near pairs were last made, since the last rebuild,
     * can hold a spring (contact.c near_keep_range): the others' records and slots are not
     * read, when those marks are there */
    const int nbb = w->bb.n;
    const uint8_t *mark =
        w->near_mark_rb == w->timers.rebuilds && w->near_mark_cap >= 2 * (nbb + 1) ? w->near_mark : NULL;
#pragma omp parallel for schedule(static, 1) num_threads(T) if (T > 1)
    for (int t = 0; t < T; t++) {
        int32_t *c = cnt + (size_t)t * (n + 1);
        const int k0 = (int)((long)np * t / T), k1 = (int)((long)np * (t + 1) / T);
        for (int k = k0; k < k1; k++) {
            if (mark && k < nbb && !mark[k]) continue;
            const sd_pair *p = any_pair(lists, k);
            const sd_hist *h = any_hist(lists, k, p);
            int m = 0;
            for (int s = 0; s < p->cap; s++)
                m += h[s].feature >= 0;
            c[p->a] += m;
        }
    }
    int total = 0;
    for (int i = 0; i < n; i++) {
        w->old_start[i] = total;
        for (int t = 0; t < T; t++) {
            const int32_t m = cnt[(size_t)t * (n + 1) + i];
            cnt[(size_t)t * (n + 1) + i] = total;
            total += m;
        }
    }
    w->old_start[n] = total;
    if (sd_grow((void **)&w->old_keys, &w->old_cap, total + 1, sizeof(uint64_t)) ||
        sd_grow((void **)&w->old_hist, &w->old_hist_cap, total + 1, sizeof(sd_hist)))
        return SD_ERR_NOMEM;
    uint64_t *keys = w->old_keys;
    sd_hist *hist = w->old_hist;
#pragma omp parallel for schedule(static, 1) num_threads(T) if (T > 1)
    for (int t = 0; t < T; t++) {
        int32_t *c = cnt + (size_t)t * (n + 1);
        const int k0 = (int)((long)np * t / T), k1 = (int)((long)np * (t + 1) / T);
        for (int k = k0; k < k1; k++) {
            if (mark && k < nbb && !mark[k]) continue;
            const sd_pair *p = any_pair(lists, k);
            const sd_hist *h = any_hist(lists, k, p);
            int m0 = -1, m = 0;
            for (int s = 0; s < p->cap; s++) {
                if (h[s].feature < 0) continue;
                if (m0 < 0) m0 = c[p->a];
                /* the pair's slots in feature order (insertion: a handful at most) */
                int j = m0 + m++;
                while (j > m0 && hist[j - 1].feature > h[s].feature) {
                    hist[j] = hist[j - 1];
                    j--;
                }
                hist[j] = h[s];
            }
            if (m0 < 0) continue;
            const uint64_t key = key_of(w, p);
            for (int j = m0; j < m0 + m; j++)
                keys[j] = key;
            c[p->a] = m0 + m;
        }
    }
    w->n_old = total;
    w->old_n_bodies = n;
    w->keys_collected = 1;
    w->bb.n = w->bt.n = 0;
    w->bb.nh = w->bt.nh = 0;
    return SD_OK;
}

/* Where each new body's carried springs are: old_rng[i] = {first, end} in the old entries.
 * by_index: the rebuild made the collect itself and only its sort moved the bodies since, so
 * body i's entries are those of the store index it came from (in nearly the store's order).
 * Else (a body came or went, or the entries came from a checkpoint) each gid's one run is
 * found from the keys and looked up by gid. */
static sd_status old_ranges(sd_world *w, int by_index)
{
    const int n = w->b.n;
    if (sd_grow((void **)&w->old_rng, &w->old_rng_cap, n + 1, sizeof(*w->old_rng))) return SD_ERR_NOMEM;
    int32_t(*rng)[2] = w->old_rng;
    if (w->n_old == 0) {
        memset(rng, 0, (size_t)(n + 1) * sizeof(*rng));
        return SD_OK;
    }
    if (by_index) {
        const int32_t *perm = w->rb_perm, *st = w->old_start;
        const int pm = w->rb_perm_m;
#pragma omp parallel for num_threads(w->nthreads) schedule(static) if (n > w->def.parallel_min)
        for (int i = 0; i < n; i++) {
            const int j = i < pm ? perm[i] : i;
            rng[i][0] = st[j];
            rng[i][1] = st[j + 1];
        }
        return SD_OK;
    }
    const int G = w->next_gid;
    int32_t(*gr)[2] = calloc((size_t)G + 1, sizeof(*gr));
    if (!gr) return SD_ERR_NOMEM;
    for (int k = 0; k < w->n_old;) {
        const int64_t g = (int64_t)(w->old_keys[k] >> 32);
        int e = k + 1;
        while (e < w->n_old && (int64_t)(w->old_keys[e] >> 32) == g)
            e++;
        if (g >= 0 && g < G) gr[g][0] = k, gr[g][1] = e;
        k = e;
    }
    for (int i = 0; i < n; i++) {
        const int g = w->b.gid[i];
        rng[i][0] = gr[g][0];
        rng[i][1] = gr[g][1];
    }
    free(gr);
    return SD_OK;
}

/* Put carried history into the new lists' slots: the entries of the pair's key are a run
 * inside its first body's few entries (old_ranges). */
#define HIST_PF 8
static sd_status restore_history(sd_world *w, sd_pairlist *l)
{
    if (sd_grow((void **)&l->hist, &l->hcap, l->nh + 1, sizeof(sd_hist))) return SD_ERR_NOMEM;
    if (l == &w->bt) { /* the wall pairs' results (sd_contact_gather) */
        if (sd_grow((void **)&l->out, &l->out_cap, l->n + 1, sizeof(sd_vec3))) return SD_ERR_NOMEM;
        if (sd_grow((void **)&l->active, &l->active_cap, l->n + 1, 1)) return SD_ERR_NOMEM;
        memset(l->active, 0, (size_t)l->n + 1);
    }
    const int32_t(*rng)[2] = (const int32_t(*)[2])w->old_rng;
    /* each pair fills its own slots */
#pragma omp parallel for num_threads(w->nthreads) schedule(static) if (l->n > w->def.parallel_min)
    for (int k = 0; k < l->n; k++) {
        const sd_pair *p = &l->p[k];
        for (int s = 0; s < p->cap; s++)
            l->hist[p->off + s].feature = -1;
        if (w->n_old == 0) continue;
        if (k + HIST_PF < l->n) {
            const int at = rng[l->p[k + HIST_PF].a][0];
            __builtin_prefetch(&w->old_keys[at], 0, 3);
            __builtin_prefetch(&w->old_hist[at], 0, 3);
        }
        int lo = rng[p->a][0];
        const int hi = rng[p->a][1];
        if (lo == hi) continue;
        const uint64_t key = key_of(w, p);
        while (lo < hi && w->old_keys[lo] != key) /* the pair's run inside its body's entries */
            lo++;
        for (int s = 0; lo < hi && w->old_keys[lo] == key && s < p->cap; lo++, s++)
            l->hist[p->off + s] = w->old_hist[lo];
    }
    return SD_OK;
}

/* The carried springs into the new pair lists' slots (by_index: see old_ranges); the old
 * entries are spent. */
sd_status sd_history_restore(sd_world *w, int by_index)
{
    sd_status st = old_ranges(w, by_index);
    if (!st) st = restore_history(w, &w->bb);
    if (!st) st = restore_history(w, &w->bt);
    if (st) return st;
    w->n_old = 0;
    return SD_OK;
}
