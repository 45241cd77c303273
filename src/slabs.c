/* One system over slab worlds along x (slabs.h, docs/decomposition.md): one slab as a rank holds
 * it, its step in phases with the exchange left to the caller (sd_slab), and n slabs in one
 * process exchanging by memory copies (sd_slabs). Through sabodem.h only. */
#include "slabs.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct sd_slab {
    int k, n;
    sd_world *w;
    double xb[SD_SLABS_MAX + 1], next_xb[SD_SLABS_MAX + 1];
    int next_set;
    double G;
    sd_grid_def grid;
    sd_slabs_opts o;
    size_t rsz;
    /* the owned bodies that slab r holds as ghosts (their refresh), by gid */
    int32_t *exp[SD_SLABS_MAX];
    int nexp[SD_SLABS_MAX], expcap[SD_SLABS_MAX];
    /* the messages of the last pack, one per slab: int32 records, int32 springs, then each
     * record as int32 owner + the record, then the springs */
    char *out[SD_SLABS_MAX];
    size_t nout[SD_SLABS_MAX], outcap[SD_SLABS_MAX];
    int nowned;
    long nrb;    /* redistributions done */
    double work; /* since the boundaries last moved */
    sd_slabs_stats st;
    char *rec;
};

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int grow(void **p, int *cap, int need, size_t elem)
{
    if (need <= *cap) return 0;
    int nc = *cap > 0 ? *cap : 64;
    while (nc < need)
        nc *= 2;
    void *q = realloc(*p, (size_t)nc * elem);
    if (!q) return -1;
    *p = q;
    *cap = nc;
    return 0;
}

static int dbl_cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static int slab_of(const sd_slab *s, double x)
{
    int k = 0;
    while (k + 1 < s->n && x >= s->xb[k + 1])
        k++;
    return k;
}

/* whether x lies within slab r or its ghost layer */
static int near_slab(const sd_slab *s, int r, double x) { return x >= s->xb[r] - s->G && x < s->xb[r + 1] + s->G; }

/* gid is here and not a ghost (a world's springs taken out for a rebuild may name bodies it
 * does not hold) */
static int owned_here(const sd_slab *s, int gid)
{
    sd_body_state b;
    return !sd_world_body_is_ghost(s->w, gid) && sd_world_body(s->w, gid, &b) == SD_OK;
}

/* ---- messages ---- */

static sd_status out_put(sd_slab *s, int r, const void *p, size_t len)
{
    if (s->nout[r] + len > s->outcap[r]) {
        size_t c = s->outcap[r] ? s->outcap[r] : 4096;
        while (c < s->nout[r] + len)
            c *= 2;
        char *q = realloc(s->out[r], c);
        if (!q) return SD_ERR_NOMEM;
        s->out[r] = q;
        s->outcap[r] = c;
    }
    memcpy(s->out[r] + s->nout[r], p, len);
    s->nout[r] += len;
    return SD_OK;
}

static void out_count(sd_slab *s, int r, int which)
{
    int32_t c;
    memcpy(&c, s->out[r] + which * sizeof(int32_t), sizeof c);
    c++;
    memcpy(s->out[r] + which * sizeof(int32_t), &c, sizeof c);
}

static sd_status out_record(sd_slab *s, int r, int32_t owner, const char *rec)
{
    sd_status st = out_put(s, r, &owner, sizeof owner);
    if (!st) st = out_put(s, r, rec, s->rsz);
    if (!st) out_count(s, r, 0);
    return st;
}

/* ---- the slab ---- */

/* the refresh's lists: each owned body for every other slab whose ghost layer it lies in */
static sd_status set_exports(sd_slab *s)
{
    for (int r = 0; r < s->n; r++)
        s->nexp[r] = 0;
    s->nowned = 0;
    const sd_body_view v = sd_world_bodies(s->w);
    for (int i = 0; i < v.n; i++) {
        if (!owned_here(s, v.gid[i])) continue;
        s->nowned++;
        for (int r = 0; r < s->n; r++) {
            if (r == s->k || !near_slab(s, r, v.pos[i].x)) continue;
            if (grow((void **)&s->exp[r], &s->expcap[r], s->nexp[r] + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
            s->exp[r][s->nexp[r]++] = v.gid[i];
        }
    }
    return SD_OK;
}

void sd_slab_first_bounds(const sd_world *whole, int n, double *xb)
{
    const sd_body_view v = sd_world_bodies(whole);
    xb[0] = -INFINITY;
    xb[n] = INFINITY;
    double *x = malloc((size_t)(v.n + 1) * sizeof(double));
    int m = 0;
    for (int i = 0; i < v.n && x; i++)
        if (!v.fixed[i]) x[m++] = v.pos[i].x;
    if (x) qsort(x, (size_t)m, sizeof(double), dbl_cmp);
    for (int j = 1; j < n; j++)
        xb[j] = x && m ? x[(long)m * j / n] : (double)j;
    free(x);
}

sd_status sd_slab_create(const sd_world *whole, const sd_grid_def *g, const sd_slabs_opts *o, int k, const double *xb,
                         sd_slab **out)
{
    *out = NULL;
    if (!whole || !g || !o || o->n < 1 || o->n > SD_SLABS_MAX || k < 0 || k >= o->n || o->ghost_width < 0.0)
        return SD_ERR_ARG;
    sd_slab *s = calloc(1, sizeof *s);
    if (!s) return SD_ERR_NOMEM;
    s->k = k;
    s->n = o->n;
    s->o = *o;
    s->grid = *g;
    s->rsz = sd_body_record_size();
    s->rec = malloc(s->rsz);
    memcpy(s->xb, xb, (size_t)(s->n + 1) * sizeof(double));
    sd_status st = s->rec ? SD_OK : SD_ERR_NOMEM;
    sd_world_def def = *sd_world_definition(whole);
    def.threads = o->threads > 0 ? o->threads : 1;
    const sd_body_view v = sd_world_bodies(whole);
    double br = 0.0;
    for (int i = 0; i < v.n; i++)
        br = v.bound_radius[i] > br ? v.bound_radius[i] : br;
    /* a pair is a candidate only when its centres are within both bounding radii plus the
     * margin along x (the sphere test, and the logs' boxes): the ghost layer holds every partner
     * of every owned body until the pairs are remade (the bodies change owner only then) */
    s->G = o->ghost_width > 0.0 ? o->ghost_width : (2.0 * br + def.margin) * (1.0 + 1e-9) + 1e-12;
    if (!st) st = sd_world_create(&def, &s->w);
    if (!st) st = sd_world_set_fixed_grid(s->w, g);
    /* every slab holds every triangle, in the same order (their indices key the springs) */
    const int nt = sd_world_triangle_count(whole);
    for (int t = 0; t < nt && !st; t++) {
        sd_vec3 c[3];
        int group, active;
        sd_world_triangle(whole, t, c, &group, &active);
        if (sd_world_add_triangle(s->w, c[0], c[1], c[2], group) != t) st = SD_ERR_ARG;
    }
    if (!st) st = sd_world_copy_materials(s->w, whole);
    for (int t = 0; t < nt && !st; t++) {
        sd_vec3 c[3];
        int group, active;
        sd_world_triangle(whole, t, c, &group, &active);
        if (!active) st = sd_world_set_group_active(s->w, group, 0);
    }
    if (!st) st = sd_world_set_clock(s->w, sd_world_time(whole), sd_world_step_count(whole));
    /* its bodies and springs, as a redistribution from the whole world would give them */
    for (int i = 0; i < v.n && !st; i++) {
        if (!near_slab(s, k, v.pos[i].x)) continue;
        st = sd_world_body_record(whole, v.gid[i], s->rec);
        if (!st) st = sd_world_body_put(s->w, s->rec, slab_of(s, v.pos[i].x) != k);
    }
    if (!st) {
        const int ns = sd_world_springs(whole, NULL, 0);
        sd_spring *sp = malloc((size_t)(ns + 1) * sizeof(sd_spring));
        if (!sp) st = SD_ERR_NOMEM;
        if (sp) sd_world_springs(whole, sp, ns);
        if (!st) st = sd_world_springs_put(s->w, sp, ns); /* (the ones of no pair here go unused) */
        free(sp);
    }
    if (!st) st = set_exports(s);
    if (st) {
        sd_slab_destroy(s);
        return st;
    }
    *out = s;
    return SD_OK;
}

void sd_slab_destroy(sd_slab *s)
{
    if (!s) return;
    sd_world_destroy(s->w);
    for (int r = 0; r < SD_SLABS_MAX; r++) {
        free(s->exp[r]);
        free(s->out[r]);
    }
    free(s->rec);
    free(s);
}

int sd_slab_wants_rebuild(const sd_slab *s) { return sd_world_needs_rebuild(s->w); }

int sd_slab_balance_due(const sd_slab *s)
{
    return s->o.rebalance > 0 && s->n > 1 && !s->next_set && (s->nrb + 1) % s->o.rebalance == 0;
}

int sd_slab_bins(const sd_slab *s) { return s->grid.nx; }

/* its work since the boundaries last moved, spread evenly over the moving bodies it owns, in
 * bins of a grid cell along x */
void sd_slab_work_bins(const sd_slab *s, double *bins)
{
    const int nb = s->grid.nx;
    memset(bins, 0, (size_t)nb * sizeof(double));
    const sd_body_view v = sd_world_bodies(s->w);
    int m = 0;
    for (int i = 0; i < v.n; i++)
        m += !v.fixed[i] && owned_here(s, v.gid[i]);
    if (m == 0 || !(s->work > 0.0)) return;
    const double per = s->work / m;
    for (int i = 0; i < v.n; i++) {
        if (v.fixed[i] || !owned_here(s, v.gid[i])) continue;
        long b = (long)floor((v.pos[i].x - s->grid.lo.x) / s->grid.cell);
        b = b < 0 ? 0 : b >= nb ? nb - 1 : b;
        bins[b] += per;
    }
}

/* the inner boundaries at the quantiles of the work summed over the slabs; slabs at least the
 * ghost width wide (so that over MPI a slab's ghosts would come from its neighbours alone),
 * inside the grid, where the grid is wide enough */
void sd_slab_balance(sd_slab *s, const double *bins)
{
    const int nb = s->grid.nx;
    const double x0 = s->grid.lo.x, c = s->grid.cell;
    double total = 0.0;
    for (int b = 0; b < nb; b++)
        total += bins[b];
    s->work = 0.0;
    if (!(total > 0.0)) return;
    double xb[SD_SLABS_MAX + 1];
    memcpy(xb, s->xb, sizeof xb);
    double acc = 0.0;
    int b = 0;
    for (int j = 1; j < s->n; j++) {
        const double want = total * j / s->n;
        while (b < nb - 1 && acc + bins[b] < want)
            acc += bins[b++];
        const double f = bins[b] > 0.0 ? (want - acc) / bins[b] : 0.0;
        xb[j] = x0 + c * (b + (f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f));
    }
    const double wmin = s->G, hi = x0 + c * nb;
    if ((s->n - 2) * wmin < hi - x0) {
        for (int j = 1; j < s->n; j++) {
            const double lo_j = j == 1 ? x0 : xb[j - 1] + wmin;
            if (xb[j] < lo_j) xb[j] = lo_j;
        }
        for (int j = s->n - 1; j >= 1; j--) {
            const double hi_j = j == s->n - 1 ? hi : xb[j + 1] - wmin;
            if (xb[j] > hi_j) xb[j] = hi_j;
        }
    }
    memcpy(s->next_xb, xb, sizeof xb);
    s->next_set = 1;
}

sd_status sd_slab_set_bounds(sd_slab *s, const double *x)
{
    for (int j = 1; j < s->n; j++)
        if (!isfinite(x[j]) || (j > 1 && !(x[j] >= x[j - 1]))) return SD_ERR_ARG;
    s->next_xb[0] = -INFINITY;
    s->next_xb[s->n] = INFINITY;
    for (int j = 1; j < s->n; j++)
        s->next_xb[j] = x[j];
    s->next_set = 1;
    return SD_OK;
}

sd_status sd_slab_pack(sd_slab *s, int any)
{
    sd_status st = SD_OK;
    const int32_t zero[2] = {0, 0};
    for (int r = 0; r < s->n && !st; r++) {
        s->nout[r] = 0;
        st = out_put(s, r, zero, sizeof zero);
    }
    if (st) return st;
    if (!any) { /* the refresh: each ghost's state from its owner */
        for (int r = 0; r < s->n && !st; r++)
            for (int q = 0; q < s->nexp[r] && !st; q++) {
                st = sd_world_body_record(s->w, s->exp[r][q], s->rec);
                if (!st) st = out_record(s, r, s->k, s->rec);
                s->st.ghost_records++;
                s->st.bytes += (double)(s->rsz + sizeof(int32_t));
            }
        return st;
    }
    /* the redistribution: the new boundaries; each owned body's record to every slab that will
     * hold it, with its new owner */
    s->nrb++;
    s->st.rebuilds++;
    if (s->next_set) {
        for (int j = 1; j < s->n; j++) {
            s->st.boundary_moves += s->next_xb[j] != s->xb[j];
            s->xb[j] = s->next_xb[j];
        }
        s->next_set = 0;
    }
    const sd_body_view v = sd_world_bodies(s->w);
    for (int i = 0; i < v.n && !st; i++) {
        if (!owned_here(s, v.gid[i])) continue;
        const int own = slab_of(s, v.pos[i].x);
        s->st.migrations += own != s->k;
        st = sd_world_body_record(s->w, v.gid[i], s->rec);
        for (int r = 0; r < s->n && !st; r++) {
            if (!near_slab(s, r, v.pos[i].x)) continue;
            st = out_record(s, r, own, s->rec);
            if (r != s->k) {
                s->st.ghost_records++;
                s->st.bytes += (double)(s->rsz + sizeof(int32_t));
            }
        }
    }
    /* the springs of the pairs whose first body it owns (every pair of an owned body is here:
     * its partner is within the ghost width) to every slab that will hold that body: those of
     * them whose pairs it makes take them */
    const int m = st ? 0 : sd_world_springs(s->w, NULL, 0);
    sd_spring *sp = malloc((size_t)(m + 1) * sizeof(sd_spring));
    if (!sp) return SD_ERR_NOMEM;
    sd_world_springs(s->w, sp, m);
    for (int q = 0; q < m && !st; q++) {
        if (!owned_here(s, sp[q].gid_a)) continue;
        sd_body_state b;
        if ((st = sd_world_body(s->w, sp[q].gid_a, &b))) break;
        for (int r = 0; r < s->n && !st; r++) {
            if (!near_slab(s, r, b.pos.x)) continue;
            st = out_put(s, r, &sp[q], sizeof(sd_spring));
            out_count(s, r, 1);
            if (r != s->k) {
                s->st.springs_sent++;
                s->st.bytes += (double)sizeof(sd_spring);
            }
        }
    }
    free(sp);
    return st;
}

const void *sd_slab_outbox(const sd_slab *s, int to, size_t *len)
{
    *len = to >= 0 && to < s->n ? s->nout[to] : 0;
    return to >= 0 && to < s->n ? s->out[to] : NULL;
}

/* a message's counts, NULL when it is too short for them */
static const char *msg_counts(const void *m, size_t len, size_t rsz, int32_t *nr, int32_t *ns)
{
    if (!m || len < 2 * sizeof(int32_t)) return NULL;
    memcpy(nr, m, sizeof(int32_t));
    memcpy(ns, (const char *)m + sizeof(int32_t), sizeof(int32_t));
    if (*nr < 0 || *ns < 0 ||
        len != 2 * sizeof(int32_t) + (size_t)*nr * (rsz + sizeof(int32_t)) + (size_t)*ns * sizeof(sd_spring))
        return NULL;
    return (const char *)m + 2 * sizeof(int32_t);
}

sd_status sd_slab_unpack(sd_slab *s, int any, const void *const *in, const size_t *len)
{
    sd_status st = SD_OK;
    const size_t step = s->rsz + sizeof(int32_t);
    if (!any) {
        for (int r = 0; r < s->n && !st; r++) {
            int32_t nr = 0, ns = 0;
            const char *p = msg_counts(in[r], len[r], s->rsz, &nr, &ns);
            if (!p) return SD_ERR_FORMAT;
            for (int q = 0; q < nr && !st; q++)
                st = sd_world_body_put(s->w, p + (size_t)q * step + sizeof(int32_t), 1);
        }
        return st;
    }
    /* the springs first (taken out of the pairs with the world's own, for the coming rebuild) */
    int nsp = 0, spcap = 0, gmax = -1;
    sd_spring *sp = NULL;
    for (int r = 0; r < s->n && !st; r++) {
        int32_t nr = 0, ns = 0;
        const char *p = msg_counts(in[r], len[r], s->rsz, &nr, &ns);
        if (!p) {
            st = SD_ERR_FORMAT;
            break;
        }
        for (int q = 0; q < nr; q++) {
            const int g = sd_body_record_gid(p + (size_t)q * step + sizeof(int32_t));
            gmax = g > gmax ? g : gmax;
        }
        if (grow((void **)&sp, &spcap, nsp + ns + 1, sizeof(sd_spring))) {
            st = SD_ERR_NOMEM;
            break;
        }
        memcpy(sp + nsp, p + (size_t)nr * step, (size_t)ns * sizeof(sd_spring));
        nsp += ns;
    }
    if (!st) st = sd_world_springs_put(s->w, sp, nsp);
    free(sp);
    /* the bodies it no longer holds, out; those it holds now, in from their owners' records */
    const sd_body_view v = sd_world_bodies(s->w);
    for (int i = 0; i < v.n; i++)
        gmax = v.gid[i] > gmax ? v.gid[i] : gmax;
    uint8_t *keep = st ? NULL : calloc((size_t)gmax + 2, 1);
    if (!st && !keep) st = SD_ERR_NOMEM;
    for (int r = 0; r < s->n && !st; r++) {
        int32_t nr = 0, ns = 0;
        const char *p = msg_counts(in[r], len[r], s->rsz, &nr, &ns);
        for (int q = 0; q < nr; q++)
            keep[sd_body_record_gid(p + (size_t)q * step + sizeof(int32_t))] = 1;
    }
    if (!st) {
        int nd = 0;
        int32_t *drop = malloc((size_t)(v.n + 1) * sizeof(int32_t));
        if (!drop) st = SD_ERR_NOMEM;
        for (int i = 0; i < v.n && drop; i++)
            if (!keep[v.gid[i]]) drop[nd++] = v.gid[i];
        for (int q = 0; q < nd && !st; q++)
            st = sd_world_remove_body(s->w, drop[q]);
        free(drop);
    }
    for (int r = 0; r < s->n && !st; r++) {
        int32_t nr = 0, ns = 0;
        const char *p = msg_counts(in[r], len[r], s->rsz, &nr, &ns);
        for (int q = 0; q < nr && !st; q++) {
            int32_t own;
            memcpy(&own, p + (size_t)q * step, sizeof own);
            st = sd_world_body_put(s->w, p + (size_t)q * step + sizeof(int32_t), own != s->k);
        }
    }
    free(keep);
    sd_world_request_rebuild(s->w);
    if (!st) st = set_exports(s);
    return st;
}

sd_status sd_slab_step_world(sd_slab *s)
{
    const double t0 = s->o.work_time ? now_s() : 0.0;
    sd_status st = sd_world_step(s->w);
    if (st) return st;
    if (s->o.work_time) {
        s->work += now_s() - t0;
    } else {
        int m = 0;
        const sd_body_view v = sd_world_bodies(s->w);
        for (int i = 0; i < v.n; i++)
            m += !v.fixed[i] && owned_here(s, v.gid[i]);
        s->work += m + (double)sd_world_contact_count(s->w);
    }
    s->st.steps++;
    return SD_OK;
}

sd_status sd_slab_state(const sd_slab *s, void **recs, int *nb, sd_spring **springs, int *ns)
{
    const sd_body_view v = sd_world_bodies(s->w);
    char *r = malloc((size_t)(s->nowned + 1) * s->rsz);
    const int m = sd_world_springs(s->w, NULL, 0);
    sd_spring *sp = malloc((size_t)(m + 1) * sizeof(sd_spring));
    if (!r || !sp) {
        free(r);
        free(sp);
        return SD_ERR_NOMEM;
    }
    int n = 0;
    for (int i = 0; i < v.n; i++)
        if (owned_here(s, v.gid[i]) && n < s->nowned) sd_world_body_record(s->w, v.gid[i], r + (size_t)n++ * s->rsz);
    sd_world_springs(s->w, sp, m);
    int q = 0;
    for (int k = 0; k < m; k++)
        if (owned_here(s, sp[k].gid_a)) sp[q++] = sp[k];
    *recs = r;
    *nb = n;
    *springs = sp;
    *ns = q;
    return SD_OK;
}

sd_status sd_slab_add_body(sd_slab *s, const void *rec, double x)
{
    if (slab_of(s, x) != s->k) return SD_OK;
    sd_status st = sd_world_body_put(s->w, rec, 0);
    if (!st) s->nowned++;
    return st;
}

int sd_slab_owns(const sd_slab *s, int gid) { return owned_here(s, gid); }

long sd_slab_contacts(const sd_slab *s)
{
    const int m = sd_world_springs(s->w, NULL, 0);
    sd_spring *sp = malloc((size_t)(m + 1) * sizeof(sd_spring));
    if (!sp) return -1;
    sd_world_springs(s->w, sp, m);
    long n = 0;
    for (int k = 0; k < m; k++)
        n += owned_here(s, sp[k].gid_a);
    free(sp);
    return n;
}

sd_world *sd_slab_world(sd_slab *s) { return s->w; }
const sd_slabs_stats *sd_slab_stats(const sd_slab *s) { return &s->st; }
int sd_slab_owned(const sd_slab *s) { return s->nowned; }
double sd_slab_ghost_width(const sd_slab *s) { return s->G; }
void sd_slab_bounds(const sd_slab *s, double *x) { memcpy(x, s->xb, (size_t)(s->n + 1) * sizeof(double)); }

/* ---- n slabs in one process ---- */

struct sd_slabs {
    int n;
    sd_slab *sl[SD_SLABS_MAX];
    double *bins, *sum;
};

sd_status sd_slabs_create(const sd_world *whole, const sd_grid_def *g, const sd_slabs_opts *o, sd_slabs **out)
{
    *out = NULL;
    if (!whole || !g || !o || o->n < 1 || o->n > SD_SLABS_MAX) return SD_ERR_ARG;
    sd_slabs *s = calloc(1, sizeof *s);
    if (!s) return SD_ERR_NOMEM;
    s->n = o->n;
    double xb[SD_SLABS_MAX + 1];
    sd_slab_first_bounds(whole, s->n, xb);
    sd_status st = SD_OK;
    for (int k = 0; k < s->n && !st; k++)
        st = sd_slab_create(whole, g, o, k, xb, &s->sl[k]);
    s->bins = malloc((size_t)(g->nx + 1) * sizeof(double));
    s->sum = malloc((size_t)(g->nx + 1) * sizeof(double));
    if (!st && (!s->bins || !s->sum)) st = SD_ERR_NOMEM;
    if (st) {
        sd_slabs_destroy(s);
        return st;
    }
    *out = s;
    return SD_OK;
}

void sd_slabs_destroy(sd_slabs *s)
{
    if (!s) return;
    for (int k = 0; k < s->n; k++)
        sd_slab_destroy(s->sl[k]);
    free(s->bins);
    free(s->sum);
    free(s);
}

sd_status sd_slabs_step(sd_slabs *s)
{
    int any = 0;
    for (int k = 0; k < s->n; k++)
        any |= sd_slab_wants_rebuild(s->sl[k]);
    if (any && sd_slab_balance_due(s->sl[0])) {
        const int nb = sd_slab_bins(s->sl[0]);
        memset(s->sum, 0, (size_t)nb * sizeof(double));
        for (int k = 0; k < s->n; k++) { /* (in slab order: the same sums on every slab) */
            sd_slab_work_bins(s->sl[k], s->bins);
            for (int b = 0; b < nb; b++)
                s->sum[b] += s->bins[b];
        }
        for (int k = 0; k < s->n; k++)
            sd_slab_balance(s->sl[k], s->sum);
    }
    sd_status st = SD_OK;
    for (int k = 0; k < s->n && !st; k++)
        st = sd_slab_pack(s->sl[k], any);
    for (int k = 0; k < s->n && !st; k++) {
        const void *in[SD_SLABS_MAX];
        size_t len[SD_SLABS_MAX];
        for (int r = 0; r < s->n; r++)
            in[r] = sd_slab_outbox(s->sl[r], k, &len[r]);
        st = sd_slab_unpack(s->sl[k], any, in, len);
    }
    for (int k = 0; k < s->n && !st; k++)
        st = sd_slab_step_world(s->sl[k]);
    return st;
}

sd_status sd_slabs_run(sd_slabs *s, long steps)
{
    for (long q = 0; q < steps; q++) {
        sd_status st = sd_slabs_step(s);
        if (st) return st;
    }
    return SD_OK;
}

uint64_t sd_slabs_state_hash(sd_slabs *s)
{
    const size_t rsz = sd_body_record_size();
    char *recs = NULL;
    sd_spring *sp = NULL;
    int nb = 0, ns = 0;
    uint64_t h = 0;
    for (int k = 0; k < s->n; k++) {
        void *r;
        sd_spring *q;
        int a, b;
        if (sd_slab_state(s->sl[k], &r, &a, &q, &b)) goto out;
        char *r2 = realloc(recs, (size_t)(nb + a + 1) * rsz);
        sd_spring *q2 = realloc(sp, (size_t)(ns + b + 1) * sizeof(sd_spring));
        if (r2) recs = r2;
        if (q2) sp = q2;
        if (!r2 || !q2) {
            free(r);
            free(q);
            goto out;
        }
        memcpy(recs + (size_t)nb * rsz, r, (size_t)a * rsz);
        memcpy(sp + ns, q, (size_t)b * sizeof(sd_spring));
        nb += a;
        ns += b;
        free(r);
        free(q);
    }
    h = sd_state_hash_records(recs, nb, sp, ns);
out:
    free(recs);
    free(sp);
    return h;
}

void sd_slabs_bounds(const sd_slabs *s, double *x) { sd_slab_bounds(s->sl[0], x); }

sd_status sd_slabs_set_bounds(sd_slabs *s, const double *x)
{
    for (int k = 0; k < s->n; k++) {
        sd_status st = sd_slab_set_bounds(s->sl[k], x);
        if (st) return st;
    }
    return SD_OK;
}

sd_slabs_stats sd_slabs_get_stats(const sd_slabs *s)
{
    sd_slabs_stats t = *sd_slab_stats(s->sl[0]);
    for (int k = 1; k < s->n; k++) {
        const sd_slabs_stats *u = sd_slab_stats(s->sl[k]);
        t.migrations += u->migrations;
        t.ghost_records += u->ghost_records;
        t.springs_sent += u->springs_sent;
        t.bytes += u->bytes;
    }
    return t;
}

int sd_slabs_count(const sd_slabs *s) { return s->n; }
sd_world *sd_slabs_world(sd_slabs *s, int k) { return k >= 0 && k < s->n ? sd_slab_world(s->sl[k]) : NULL; }
int sd_slabs_owned(const sd_slabs *s, int k) { return k >= 0 && k < s->n ? sd_slab_owned(s->sl[k]) : 0; }
double sd_slabs_ghost_width(const sd_slabs *s) { return sd_slab_ghost_width(s->sl[0]); }
