/* The body-body pass's front prefetch: when it runs (by the size guess, or the trial that times
 * it on and off during a run), and the rows and slots it fetches. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contact_internal.h"

/* The bodies' front. The pass takes the pairs in lower-body order, so it reaches each body for
 * the first time as the upper body of some pair, a little ahead of the bodies it is at: those
 * rows (centre, radius, velocity, spin, force, torque) are the lines the hardware prefetchers
 * miss, six arrays read at a ragged edge. When the step's data do not stay in the last-level
 * cache they come from DRAM, and the pass waits for them: 1e5 and 1e6 spheres cost 1.3-1.9x
 * what 1e4 cost. So the pass looks PF_CHUNKS chunks ahead, finds the
 * highest body those pairs touch and prefetches the rows from the last such body up to it. With
 * the data in cache it only costs instructions (2-4 % at 1e4 spheres on the Zen 3 VM, 6-7 % on
 * the Zen 5 VM), hence the size test: on when the bodies times PF_BYTES_PER_BODY exceed a quarter
 * of the last-level cache (which holds more than this step's data; a VM shares it with others).
 * On the Zen 3 VM (32 MiB) the gain starts between 15,000 and 20,000 spheres, where the test puts
 * it (16,384); on the Zen 5 VM only near 60,000 (at 30,000 on is 6-13 % slower), so the size
 * test is only the guess before the run has tried both (sd_pf_trial, world.c) and for scenes too
 * small to try (below SD_PF_MIN_BODIES, where it says off on any last-level cache of 4 MiB or
 * more). */
#define PF_BYTES_PER_BODY 512 /* about what one step reads and writes per sphere (bodies, pairs) */
#define PF_LLC_SHARE 4        /* the data may take 1 / PF_LLC_SHARE of the last-level cache */
int sd_front_prefetch_on(const sd_world *w)
{
    static const int order[4] = {0, 1, 1, 0}; /* a trial's blocks: off on on off */
    const int mode = w->sw[SD_SW_PREFETCH];
    if (mode != SD_PREFETCH_AUTO) return mode == SD_PREFETCH_ON;
    if (w->pf.blk >= 0) return order[w->pf.blk & 3];
    if (w->pf.verdict >= 0) return w->pf.verdict;
    return (long)w->b.n * PF_BYTES_PER_BODY * PF_LLC_SHARE > w->llc_bytes;
}

int sd_front_prefetch_verdict(const sd_world *w, double *ratio)
{
    if (ratio) *ratio = w->pf.ratio;
    return w->pf.verdict;
}

static inline void pf_rows(const void *p0, const void *p1, int write)
{
    for (const char *c = (const char *)((uintptr_t)p0 & ~(uintptr_t)63); c < (const char *)p1; c += 64)
        if (write)
            __builtin_prefetch(c, 1, 3);
        else
            __builtin_prefetch(c, 0, 3);
}

/* Entries j0 .. j1 of the records (a, b): the rows of the bodies below lim beyond *front that
 * they touch (at most 4 per entry back from the highest), and *front moved on to it. */
void sd_front_prefetch_rows(const sd_bodies *b, const int32_t *pa, const int32_t *pb, int j0, int j1, int lim,
                            int *front)
{
    int hi = *front;
    for (int j = j0; j < j1; j++) {
        const int m = pa[j] > pb[j] ? pa[j] : pb[j];
        hi = m > hi && m < lim ? m : hi;
    }
    if (hi <= *front) return;
    const int lo = *front + 1 > hi - 4 * (j1 - j0) ? *front + 1 : hi - 4 * (j1 - j0);
    pf_rows(b->pos + lo, b->pos + hi + 1, 0);
    pf_rows(b->radius + lo, b->radius + hi + 1, 0);
    pf_rows(b->vel + lo, b->vel + hi + 1, 0);
    pf_rows(b->omega + lo, b->omega + hi + 1, 0);
    pf_rows(b->force + lo, b->force + hi + 1, 1);
    pf_rows(b->torque + lo, b->torque + hi + 1, 1);
    *front = hi;
}

/* The front prefetch's trial (sd_pf_trial): a block lasts about 2e6 particle-steps (2 to 100
 * steps), so that a trial takes a few seconds at any size. */
void sd_front_prefetch_trial_before(sd_world *w)
{
    sd_pf_trial *p = &w->pf;
    const int n = w->b.n;
    if (w->sw[SD_SW_PREFETCH] != SD_PREFETCH_AUTO) {
        p->blk = -1; /* (a trial under a forced setting would time one mode against itself) */
        return;
    }
    if (p->blk >= 0 || n < SD_PF_MIN_BODIES) return;
    if (w->step < p->next && 4 * labs((long)n - p->n) <= n) return;
    const long s = 2000000L / n;
    p->blk_steps = s < 2 ? 2 : s > 100 ? 100 : (int)s;
    p->blk = p->in_blk = 0;
    p->n = n;
    p->acc = 0.0;
}

static int cmp_dbl(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void sd_front_prefetch_trial_after(sd_world *w, double pass_s)
{
    sd_pf_trial *p = &w->pf;
    if (p->blk < 0) return;
    p->acc += pass_s;
    if (++p->in_blk < p->blk_steps) return;
    p->t[p->blk & 3] = p->acc;
    p->acc = 0.0;
    p->in_blk = 0;
    if ((++p->blk & 3) == 0) {
        const double off = p->t[0] + p->t[3];
        p->r[p->blk / 4 - 1] = off > 0.0 ? (p->t[1] + p->t[2]) / off : 1.0;
    }
    if (p->blk < 4 * SD_PF_GROUPS) return;
    double r[SD_PF_GROUPS];
    memcpy(r, p->r, sizeof r);
    qsort(r, SD_PF_GROUPS, sizeof r[0], cmp_dbl);
    p->ratio = 0.5 * (r[(SD_PF_GROUPS - 1) / 2] + r[SD_PF_GROUPS / 2]); /* (the median) */
    p->verdict = p->ratio < 1.0;
    p->blk = -1;
    p->next = w->step + SD_PF_RETRY;
}
