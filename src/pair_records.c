/* Pair lists and pair records (sd_pair_soa, field by field): their storage. */
#include <stdlib.h>
#include <string.h>

#include "contact_internal.h"

void sd_pairlist_free(sd_pairlist *l)
{
    free(l->p);
    free(l->out);
    free(l->active);
    free(l->hist);
    memset(l, 0, sizeof(*l));
}

void sd_pair_soa_free(sd_pair_soa *s)
{
    free(s->a);
    free(s->b);
    free(s->off);
    free(s->ck);
    free(s->sqm);
    free(s->rs2);
    free(s->act);
    memset(s, 0, sizeof *s);
}

int sd_pair_soa_reserve(sd_pair_soa *s, int n)
{
    if (n <= s->cap && s->a) return 0;
    int cap = s->cap > 0 ? s->cap : 64;
    while (cap < n)
        cap *= 2;
    sd_pair_soa t = *s;
    t.a = realloc(s->a, (size_t)cap * sizeof(int32_t));
    if (t.a) s->a = t.a;
    t.b = realloc(s->b, (size_t)cap * sizeof(int32_t));
    if (t.b) s->b = t.b;
    t.off = realloc(s->off, (size_t)cap * sizeof(int32_t));
    if (t.off) s->off = t.off;
    t.ck = realloc(s->ck, (size_t)cap * sizeof(int32_t));
    if (t.ck) s->ck = t.ck;
    t.sqm = realloc(s->sqm, (size_t)cap * sizeof(double));
    if (t.sqm) s->sqm = t.sqm;
    t.rs2 = realloc(s->rs2, (size_t)cap * sizeof(float));
    if (t.rs2) s->rs2 = t.rs2;
    t.act = realloc(s->act, (size_t)cap);
    if (t.act) s->act = t.act;
    if (!t.a || !t.b || !t.off || !t.ck || !t.sqm || !t.rs2 || !t.act) return 1;
    s->cap = cap;
    return 0;
}
