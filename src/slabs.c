/* One system over n slab worlds in one process, the exchange by memory copies (slabs.h,
 * docs/decomposition.md). Through sabodem.h only. */
#include "slabs.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct sd_slabs {
    int n;
    sd_world *w[SD_SLABS_MAX];
    double xb[SD_SLABS_MAX + 1];
    double next_xb[SD_SLABS_MAX + 1];
    int next_set;
    double G;
    sd_grid_def grid;
    sd_slabs_opts o;
    size_t rsz;
    /* by gid: the owning slab (-1: none), then the new one at a redistribution */
    int *owner, *nowner;
    int gcap;
    /* each slab's ghosts (gids) */
    int32_t *ghost[SD_SLABS_MAX];
    int nghost[SD_SLABS_MAX], ghost_cap[SD_SLABS_MAX];
    int nowned[SD_SLABS_MAX];
    double work[SD_SLABS_MAX]; /* since the boundaries last moved */
    sd_slabs_stats st;
    char *rec; /* scratch records */
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

static int slab_of(const sd_slabs *s, double x)
{
    int k = 0;
    while (k + 1 < s->n && x >= s->xb[k + 1])
        k++;
    return k;
}

/* whether x lies within slab k or its ghost layer */
static int near_slab(const sd_slabs *s, int k, double x) { return x >= s->xb[k] - s->G && x < s->xb[k + 1] + s->G; }

/* the gids' table for gids up to g */
static sd_status gids_fit(sd_slabs *s, int g)
{
    if (g < s->gcap) return SD_OK;
    int cap = s->gcap, cap2 = s->gcap;
    if (grow((void **)&s->owner, &cap, g + 1, sizeof(int)) || grow((void **)&s->nowner, &cap2, g + 1, sizeof(int)))
        return SD_ERR_NOMEM;
    for (int q = s->gcap; q < cap; q++)
        s->owner[q] = s->nowner[q] = -1;
    s->gcap = cap;
    return SD_OK;
}

/* Inner boundaries at the quantiles of a weight along x: each slab's work spread evenly over
 * the moving bodies it owns, in bins of a grid cell; a slab at least the ghost width wide (so
 * that, over MPI, a slab's ghosts come from its neighbours alone), where the domain allows. */
static void balance(sd_slabs *s, const double *work, double *xb)
{
    const int nbins = s->grid.nx;
    const double x0 = s->grid.lo.x, c = s->grid.cell;
    double *bin = calloc((size_t)nbins, sizeof(double));
    if (!bin) return;
    double total = 0.0;
    for (int k = 0; k < s->n; k++) {
        const sd_body_view v = sd_world_bodies(s->w[k]);
        int m = 0;
        for (int i = 0; i < v.n; i++)
            m += !v.fixed[i] && s->owner[v.gid[i]] == k;
        if (m == 0 || !(work[k] > 0.0)) continue;
        const double per = work[k] / m;
        for (int i = 0; i < v.n; i++) {
            if (v.fixed[i] || s->owner[v.gid[i]] != k) continue;
            long b = (long)floor((v.pos[i].x - x0) / c);
            b = b < 0 ? 0 : b >= nbins ? nbins - 1 : b;
            bin[b] += per;
            total += per;
        }
    }
    if (total > 0.0) {
        double acc = 0.0;
        int b = 0;
        for (int j = 1; j < s->n; j++) {
            const double want = total * j / s->n;
            while (b < nbins - 1 && acc + bin[b] < want)
                acc += bin[b++];
            const double f = bin[b] > 0.0 ? (want - acc) / bin[b] : 0.0;
            xb[j] = x0 + c * (b + (f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f));
        }
        /* at least the ghost width apart, inside the grid, if the grid is wide enough */
        const double wmin = s->G, hi = x0 + c * nbins;
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
    }
    free(bin);
}

/* The redistribution at a rebuild: the boundaries set, each body's new owner from its x, each
 * world given the springs of the pairs it may hold, its bodies and ghosts as the new boundaries
 * say (those it no longer holds removed, the others put from their owners' records). */
static sd_status redistribute(sd_slabs *s)
{
    sd_status st = SD_OK;
    s->st.rebuilds++;
    if (s->o.rebalance > 0 && s->n > 1 && s->st.rebuilds % s->o.rebalance == 0 && !s->next_set) {
        double xb[SD_SLABS_MAX + 1];
        memcpy(xb, s->xb, sizeof xb);
        balance(s, s->work, xb);
        memcpy(s->next_xb, xb, sizeof xb);
        s->next_set = 1;
        memset(s->work, 0, sizeof s->work);
    }
    if (s->next_set) {
        for (int j = 1; j < s->n; j++) {
            s->st.boundary_moves += s->next_xb[j] != s->xb[j];
            s->xb[j] = s->next_xb[j];
        }
        s->next_set = 0;
    }
    /* the new owners, from the owners' own states */
    int gmax = -1;
    for (int k = 0; k < s->n; k++) {
        const sd_body_view v = sd_world_bodies(s->w[k]);
        for (int i = 0; i < v.n; i++)
            if (s->owner[v.gid[i]] == k) {
                s->nowner[v.gid[i]] = slab_of(s, v.pos[i].x);
                gmax = v.gid[i] > gmax ? v.gid[i] : gmax;
            }
    }
    /* every pair's spring from the owner of its first body (who holds every pair of the bodies
     * it owns: their partners are within the ghost width) */
    int ns = 0, scap = 0;
    sd_spring *sp = NULL;
    for (int k = 0; k < s->n && !st; k++) {
        const int m = sd_world_springs(s->w[k], NULL, 0);
        if (grow((void **)&sp, &scap, ns + m + 1, sizeof(sd_spring))) {
            st = SD_ERR_NOMEM;
            break;
        }
        sd_world_springs(s->w[k], sp + ns, m);
        const int base = ns;
        for (int q = 0; q < m; q++)
            if (s->owner[sp[base + q].gid_a] == k) sp[ns++] = sp[base + q];
    }
    /* the records of every owned body, by gid, before any world changes */
    char *recs = NULL;
    double *xs = NULL;
    if (!st) {
        recs = malloc((size_t)(gmax + 2) * s->rsz);
        xs = malloc((size_t)(gmax + 2) * sizeof(double));
        if (!recs || !xs) st = SD_ERR_NOMEM;
    }
    for (int k = 0; k < s->n && !st; k++) {
        const sd_body_view v = sd_world_bodies(s->w[k]);
        for (int i = 0; i < v.n; i++)
            if (s->owner[v.gid[i]] == k) {
                sd_world_body_record(s->w[k], v.gid[i], recs + (size_t)v.gid[i] * s->rsz);
                xs[v.gid[i]] = v.pos[i].x;
            }
    }
    sd_spring *put = NULL;
    int pcap = 0;
    int32_t *drop = NULL;
    int dcap = 0;
    for (int k = 0; k < s->n && !st; k++) {
        sd_world *w = s->w[k];
        /* the springs of the pairs whose bodies it will hold */
        int np = 0;
        if (grow((void **)&put, &pcap, ns + 1, sizeof(sd_spring))) {
            st = SD_ERR_NOMEM;
            break;
        }
        for (int q = 0; q < ns; q++) {
            const sd_spring *e = &sp[q];
            if (!near_slab(s, k, xs[e->gid_a])) continue;
            if (e->kind < 3 && !near_slab(s, k, xs[e->id_b])) continue;
            put[np++] = *e;
        }
        if ((st = sd_world_springs_put(w, put, np))) break;
        s->st.springs_sent += np;
        s->st.bytes += (double)np * sizeof(sd_spring);
        /* the bodies it no longer holds */
        const sd_body_view v = sd_world_bodies(w);
        int nd = 0;
        if (grow((void **)&drop, &dcap, v.n + 1, sizeof(int32_t))) {
            st = SD_ERR_NOMEM;
            break;
        }
        for (int i = 0; i < v.n; i++)
            if (!near_slab(s, k, xs[v.gid[i]])) drop[nd++] = v.gid[i];
        for (int q = 0; q < nd && !st; q++)
            st = sd_world_remove_body(w, drop[q]);
        /* the bodies it holds now, owned or ghosts, from their owners' records */
        s->nghost[k] = 0;
        s->nowned[k] = 0;
        for (int g = 0; g <= gmax && !st; g++) {
            if (s->owner[g] < 0 || !near_slab(s, k, xs[g])) continue;
            const int mine = s->nowner[g] == k;
            if (s->owner[g] != k) {
                s->st.ghost_records++;
                s->st.bytes += (double)s->rsz;
            }
            st = sd_world_body_put(w, recs + (size_t)g * s->rsz, !mine);
            if (mine) {
                s->nowned[k]++;
            } else {
                if (grow((void **)&s->ghost[k], &s->ghost_cap[k], s->nghost[k] + 1, sizeof(int32_t)))
                    st = SD_ERR_NOMEM;
                else
                    s->ghost[k][s->nghost[k]++] = g;
            }
        }
        sd_world_request_rebuild(w);
    }
    for (int g = 0; g <= gmax && !st; g++) {
        if (s->owner[g] < 0) continue;
        s->st.migrations += s->nowner[g] != s->owner[g];
        s->owner[g] = s->nowner[g];
    }
    free(sp);
    free(put);
    free(drop);
    free(recs);
    free(xs);
    return st;
}

/* Before a step that keeps the pairs: each ghost's state from its owner */
static sd_status refresh_ghosts(sd_slabs *s)
{
    for (int k = 0; k < s->n; k++)
        for (int q = 0; q < s->nghost[k]; q++) {
            const int g = s->ghost[k][q];
            sd_status st = sd_world_body_record(s->w[s->owner[g]], g, s->rec);
            if (!st) st = sd_world_body_put(s->w[k], s->rec, 1);
            if (st) return st;
            s->st.ghost_records++;
            s->st.bytes += (double)s->rsz;
        }
    return SD_OK;
}

sd_status sd_slabs_step(sd_slabs *s)
{
    int any = 0;
    for (int k = 0; k < s->n; k++)
        any |= sd_world_needs_rebuild(s->w[k]);
    sd_status st = any ? redistribute(s) : refresh_ghosts(s);
    if (st) return st;
    for (int k = 0; k < s->n; k++) {
        const double t0 = s->o.work_time ? now_s() : 0.0;
        if ((st = sd_world_step(s->w[k]))) return st;
        if (s->o.work_time)
            s->work[k] += now_s() - t0;
        else {
            int m = 0;
            const sd_body_view v = sd_world_bodies(s->w[k]);
            for (int i = 0; i < v.n; i++)
                m += !v.fixed[i] && s->owner[v.gid[i]] == k;
            s->work[k] += m + (double)sd_world_contact_count(s->w[k]);
        }
    }
    s->st.steps++;
    return SD_OK;
}

sd_status sd_slabs_run(sd_slabs *s, long steps)
{
    for (long q = 0; q < steps; q++) {
        sd_status st = sd_slabs_step(s);
        if (st) return st;
    }
    return SD_OK;
}

sd_status sd_slabs_create(const sd_world *whole, const sd_grid_def *g, const sd_slabs_opts *o, sd_slabs **out)
{
    *out = NULL;
    if (!whole || !g || !o || o->n < 1 || o->n > SD_SLABS_MAX || o->ghost_width < 0.0) return SD_ERR_ARG;
    sd_slabs *s = calloc(1, sizeof *s);
    if (!s) return SD_ERR_NOMEM;
    s->n = o->n;
    s->o = *o;
    s->grid = *g;
    s->rsz = sd_body_record_size();
    s->rec = malloc(s->rsz);
    sd_status st = s->rec ? SD_OK : SD_ERR_NOMEM;
    sd_world_def def = *sd_world_definition(whole);
    def.threads = 1;
    const sd_body_view v = sd_world_bodies(whole);
    double br = 0.0;
    int gmax = -1;
    for (int i = 0; i < v.n; i++) {
        br = v.bound_radius[i] > br ? v.bound_radius[i] : br;
        gmax = v.gid[i] > gmax ? v.gid[i] : gmax;
    }
    /* a pair is a candidate only when its centres are within both bounding radii plus the
     * margin along x (the sphere test, and the logs' boxes): the ghost layer holds every partner
     * of every owned body until the pairs are remade (the bodies change owner only then) */
    s->G = o->ghost_width > 0.0 ? o->ghost_width : (2.0 * br + def.margin) * (1.0 + 1e-9) + 1e-12;
    if (!st) st = gids_fit(s, gmax + 1);
    for (int k = 0; k < s->n && !st; k++) {
        if ((st = sd_world_create(&def, &s->w[k]))) break;
        if ((st = sd_world_set_fixed_grid(s->w[k], g))) break;
        /* every world holds every triangle, in the same order (their indices key the springs) */
        const int nt = sd_world_triangle_count(whole);
        for (int t = 0; t < nt && !st; t++) {
            sd_vec3 c[3];
            int group, active;
            sd_world_triangle(whole, t, c, &group, &active);
            if (sd_world_add_triangle(s->w[k], c[0], c[1], c[2], group) != t) st = SD_ERR_ARG;
        }
        for (int t = 0; t < nt && !st; t++) {
            sd_vec3 c[3];
            int group, active;
            sd_world_triangle(whole, t, c, &group, &active);
            if (!active) st = sd_world_set_group_active(s->w[k], group, 0);
        }
        if (!st) st = sd_world_set_clock(s->w[k], sd_world_time(whole), sd_world_step_count(whole));
    }
    if (st) {
        sd_slabs_destroy(s);
        return st;
    }
    /* the first boundaries: as many moving bodies in each slab */
    s->xb[0] = -INFINITY;
    s->xb[s->n] = INFINITY;
    {
        double *x = malloc((size_t)(v.n + 1) * sizeof(double));
        int m = 0;
        if (!x) st = SD_ERR_NOMEM;
        for (int i = 0; i < v.n && x; i++)
            if (!v.fixed[i]) x[m++] = v.pos[i].x;
        if (x) qsort(x, (size_t)m, sizeof(double), dbl_cmp);
        for (int j = 1; j < s->n && x; j++)
            s->xb[j] = m ? x[(long)m * j / s->n] : s->grid.lo.x + s->grid.cell * s->grid.nx * j / s->n;
        free(x);
    }
    for (int j = 1; j < s->n; j++)
        if (s->xb[j] < s->xb[j - 1]) s->xb[j] = s->xb[j - 1];
    /* the bodies and the springs, as a redistribution from the whole world would give them */
    for (int i = 0; i < v.n && !st; i++) {
        const int gid = v.gid[i];
        const int own = slab_of(s, v.pos[i].x);
        s->owner[gid] = own;
        if ((st = sd_world_body_record(whole, gid, s->rec))) break;
        for (int k = 0; k < s->n && !st; k++) {
            if (!near_slab(s, k, v.pos[i].x)) continue;
            st = sd_world_body_put(s->w[k], s->rec, own != k);
            if (st) break;
            if (own == k)
                s->nowned[k]++;
            else if (grow((void **)&s->ghost[k], &s->ghost_cap[k], s->nghost[k] + 1, sizeof(int32_t)))
                st = SD_ERR_NOMEM;
            else
                s->ghost[k][s->nghost[k]++] = gid;
        }
    }
    if (!st) {
        const int ns = sd_world_springs(whole, NULL, 0);
        sd_spring *sp = malloc((size_t)(ns + 1) * sizeof(sd_spring));
        if (!sp) st = SD_ERR_NOMEM;
        if (sp) sd_world_springs(whole, sp, ns);
        for (int k = 0; k < s->n && !st; k++)
            st = sd_world_springs_put(s->w[k], sp, ns); /* (the ones of no pair there go unused) */
        free(sp);
    }
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
    for (int k = 0; k < s->n; k++) {
        sd_world_destroy(s->w[k]);
        free(s->ghost[k]);
    }
    free(s->owner);
    free(s->nowner);
    free(s->rec);
    free(s);
}

uint64_t sd_slabs_state_hash(sd_slabs *s)
{
    int nb = 0, ns = 0, bcap = 0, scap = 0;
    char *recs = NULL;
    sd_spring *sp = NULL;
    uint64_t h = 0;
    for (int k = 0; k < s->n; k++) {
        const sd_body_view v = sd_world_bodies(s->w[k]);
        for (int i = 0; i < v.n; i++) {
            if (s->owner[v.gid[i]] != k) continue;
            int cap = bcap;
            if (grow((void **)&recs, &cap, (int)((nb + 1) * s->rsz), 1)) goto out;
            bcap = cap;
            sd_world_body_record(s->w[k], v.gid[i], recs + (size_t)nb * s->rsz);
            nb++;
        }
        const int m = sd_world_springs(s->w[k], NULL, 0);
        if (grow((void **)&sp, &scap, ns + m + 1, sizeof(sd_spring))) goto out;
        sd_world_springs(s->w[k], sp + ns, m);
        const int base = ns;
        for (int q = 0; q < m; q++)
            if (s->owner[sp[base + q].gid_a] == k) sp[ns++] = sp[base + q];
    }
    h = sd_state_hash_records(recs, nb, sp, ns);
out:
    free(recs);
    free(sp);
    return h;
}

void sd_slabs_bounds(const sd_slabs *s, double *x) { memcpy(x, s->xb, (size_t)(s->n + 1) * sizeof(double)); }

sd_status sd_slabs_set_bounds(sd_slabs *s, const double *x)
{
    for (int j = 1; j < s->n; j++)
        if (!(x[j] >= (j > 1 ? x[j - 1] : -INFINITY)) || !isfinite(x[j])) return SD_ERR_ARG;
    s->next_xb[0] = -INFINITY;
    s->next_xb[s->n] = INFINITY;
    for (int j = 1; j < s->n; j++)
        s->next_xb[j] = x[j];
    s->next_set = 1;
    return SD_OK;
}

sd_slabs_stats sd_slabs_get_stats(const sd_slabs *s) { return s->st; }
int sd_slabs_count(const sd_slabs *s) { return s->n; }
sd_world *sd_slabs_world(sd_slabs *s, int k) { return k >= 0 && k < s->n ? s->w[k] : NULL; }
int sd_slabs_owner(const sd_slabs *s, int gid) { return gid >= 0 && gid < s->gcap ? s->owner[gid] : -1; }
int sd_slabs_owned(const sd_slabs *s, int k) { return k >= 0 && k < s->n ? s->nowned[k] : 0; }
double sd_slabs_ghost_width(const sd_slabs *s) { return s->G; }
