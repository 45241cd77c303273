/* Per-step contact evaluation: narrow phase through a shape-pair dispatch, history matched by
 * feature; body-body forces summed into each body in pair order (owned body ranges per thread,
 * see below), body-triangle forces per pair then gathered per body in pair order, so that 1
 * and N threads give the same bits. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>
#include <unistd.h>

#include "contact_law.h"
#include "core/simd.h"
#include "world_internal.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SD_NO_CLONES)
#include <immintrin.h>
#include <stddef.h>
#define SD_FILTER512 1
#endif

#ifdef _OPENMP
#include <omp.h>
#endif

void sd_pairlist_free(sd_pairlist *l)
{
    free(l->p);
    free(l->out);
    free(l->active);
    free(l->hist);
    memset(l, 0, sizeof(*l));
}

static int narrow_bb(const sd_bodies *b, const sd_pair *p, sd_manifold *m)
{
    int a = p->a, c = p->b;
    switch (p->kind) {
    case SD_PAIR_SS:
        return sd_geom_sphere_sphere(b->pos[a], b->radius[a], b->pos[c], b->radius[c], m);
    case SD_PAIR_SC: {
        sd_cyl cb = sd_body_cyl(b, c);
        return sd_geom_sphere_cyl(b->pos[a], b->radius[a], &cb, m);
    }
    default: {
        sd_cyl ca = sd_body_cyl(b, a), cb = sd_body_cyl(b, c);
        return sd_geom_cyl_cyl(&ca, &cb, m);
    }
    }
}

static int narrow_bt(const sd_bodies *b, const sd_walls *wl, const sd_pair *p, sd_manifold *m)
{
    const sd_tri *t = &wl->tri[p->b];
    if (!wl->active[p->b]) {
        m->n = 0;
        return 0;
    }
    if (p->kind == SD_PAIR_ST) return sd_geom_sphere_tri_e(b->pos[p->a], b->radius[p->a], t, &wl->edges[p->b], m);
    sd_cyl c = sd_body_cyl(b, p->a);
    return sd_geom_cyl_tri(&c, t, m);
}

/* Apply the law to every point of a manifold, matching history slots by feature. */
static int apply_manifold(const sd_world *w, const sd_law *law, const sd_manifold *m, int ia, int ib, int b_is_static,
                          double sqm, sd_hist *slots, int cap, sd_pair_out *out)
{
    const sd_bodies *b = &w->b;
    sd_hist old[SD_MANIFOLD_MAX];
    int nold = cap < SD_MANIFOLD_MAX ? cap : SD_MANIFOLD_MAX;
    for (int s = 0; s < nold; s++) {
        old[s] = slots[s];
        slots[s].feature = -1;
    }
    sd_vec3 fa = v3(0, 0, 0), ta = v3(0, 0, 0), tb = v3(0, 0, 0);
    int used = 0;
    for (int k = 0; k < m->n && used < cap; k++) {
        sd_vec3 ra = v3_sub(m->point[k], b->pos[ia]);
        sd_vec3 va = v3_add(b->vel[ia], v3_cross(b->omega[ia], ra));
        sd_vec3 vb = v3(0, 0, 0), rb = v3(0, 0, 0);
        if (!b_is_static) {
            rb = v3_sub(m->point[k], b->pos[ib]);
            vb = v3_add(b->vel[ib], v3_cross(b->omega[ib], rb));
        }
        sd_vec3 shear = v3(0, 0, 0);
        for (int s = 0; s < nold; s++)
            if (old[s].feature == m->feature[k]) {
                shear = old[s].shear;
                break;
            }
        sd_vec3 f;
        sd_contact_law(law, sqm, m->normal[k], m->overlap[k], v3_sub(va, vb), w->def.dt, &shear, &f);
        slots[used].feature = m->feature[k];
        slots[used].shear = shear;
        used++;
        fa = v3_add(fa, f);
        ta = v3_add(ta, v3_cross(ra, f));
        if (!b_is_static) tb = v3_sub(tb, v3_cross(rb, f));
    }
    out->f_a = fa;
    out->t_a = ta;
    out->t_b = tb;
    return used;
}

/* Sphere–sphere, the most common pair, in batches (ss_chunk below): a filter pass keeps the
 * touching pairs, a branch-free pass over arrays applies case 1 of the kernel and the law of
 * contact_law.h to all of them at once (the compiler vectorizes it), and the results go back in
 * pair order. The arithmetic is that of sd_contact_law, operation for operation (both sides of
 * every branch are computed and one is kept), so it gives the same bits as the scalar law. */
#define SS_CHUNK 128
#define SS_PAD 8
#define SC_CAP (SS_CHUNK + SS_PAD) /* (the sphere-log lanes: sc_geom256 stores four at a time) */

typedef struct {
    /* (the filter's lanes padded by SS_PAD: its AVX-512 form stores 8 lanes at a time) */
    double dx[SS_CHUNK + SS_PAD], dy[SS_CHUNK + SS_PAD], dz[SS_CHUNK + SS_PAD], ra[SS_CHUNK + SS_PAD],
        rb[SS_CHUNK + SS_PAD], sqm[SS_CHUNK + SS_PAD];
    double vx[SS_CHUNK], vy[SS_CHUNK], vz[SS_CHUNK];    /* v_a - v_b */
    double wax[SS_CHUNK], way[SS_CHUNK], waz[SS_CHUNK]; /* omega_a */
    double wbx[SS_CHUNK], wby[SS_CHUNK], wbz[SS_CHUNK]; /* omega_b */
    double sx[SS_CHUNK], sy[SS_CHUNK], sz[SS_CHUNK];    /* shear spring in, then out */
    double fx[SS_CHUNK], fy[SS_CHUNK], fz[SS_CHUNK];    /* force on A */
    double nfx[SS_CHUNK], nfy[SS_CHUNK], nfz[SS_CHUNK]; /* n x f */
    double la[SS_CHUNK], lb[SS_CHUNK];                  /* lever arms */
    double redo[SS_CHUNK];                              /* nonzero: redo with the scalar law */
    int32_t ia[SS_CHUNK + SS_PAD], ib[SS_CHUNK + SS_PAD], off[SS_CHUNK + SS_PAD]; /* bodies, history slot */
    int32_t was[SS_CHUNK + SS_PAD]; /* the slot's feature before this step */
    int32_t sel[SS_CHUNK + SS_PAD]; /* the pair's place in the chunk */
    int bed_lim;                    /* the sums' bed test (bed_at): set by each pass before its chunks */
    sd_hist *sh;                    /* the sphere lanes' slots: off[] into here (the chunk's view's) */
    int lsq;                        /* sh is a list's own springs: see soa_view.lsq */
    sd_vec3 sink[8];                /* where a bed body's sums go (ss_sums256, add_pair_sink): never read */
    /* an owner's cross entries in pass 2 (ks < 0: pair cross[~ks], computed in pass 1): their
     * results and flags, and the owner's bodies [own_lo, own_hi), whose side alone it adds */
    const sd_pair_out *xout;
    const uint8_t *xact;
    int own_lo, own_hi;
    struct sc_lanes {               /* sphere-log pairs touching at one point (bb_chunk step 2) */
        double nx[SC_CAP], ny[SC_CAP], nz[SC_CAP], ov[SC_CAP]; /* normal (on the sphere), overlap */
        double px[SC_CAP], py[SC_CAP], pz[SC_CAP];             /* contact point */
        double rax[SC_CAP], ray[SC_CAP], raz[SC_CAP];          /* point - centre, sphere */
        double rbx[SC_CAP], rby[SC_CAP], rbz[SC_CAP];          /* point - centre, log */
        double vax[SC_CAP], vay[SC_CAP], vaz[SC_CAP], wax[SC_CAP], way[SC_CAP], waz[SC_CAP];
        double vbx[SC_CAP], vby[SC_CAP], vbz[SC_CAP], wbx[SC_CAP], wby[SC_CAP], wbz[SC_CAP];
        double sqm[SC_CAP];
        double sx[SC_CAP], sy[SC_CAP], sz[SC_CAP]; /* spring in, then out */
        double fx[SC_CAP], fy[SC_CAP], fz[SC_CAP], tax[SC_CAP], tay[SC_CAP], taz[SC_CAP];
        double tbx[SC_CAP], tby[SC_CAP], tbz[SC_CAP];
        double redo[SC_CAP];
        int32_t feature[SC_CAP], i[SC_CAP]; /* the contact's feature, the pair's place */
        long n_run, n_redo, n_geom; /* lanes run, sent back, and filled by sc_geom256 since the last fold (tests) */
    } sc;
} ss_batch;

/* The constants of sd_contact_law for one pass of the lanes below. */
typedef struct {
    double k_n, c_n, c_s, tan_phi, coh, mks_dt;
} lane_law;

static inline lane_law lane_law_make(const sd_law *law, double dt)
{
    return (lane_law){law->k_n, law->c_n_factor, law->c_s_factor, law->tan_phi, law->cohesion, -law->k_s * dt};
}

/* sd_contact_law for one lane, operation for operation, with both sides of every branch
 * computed and one kept (so that the loops that call it vectorize): unit normal n, overlap ov,
 * relative velocity v at the contact, sqrt of the effective mass sqm, the stored spring s (in,
 * then out), the force f on A. Returns nonzero when the spring tilted past the small-angle
 * rule and the lane must be redone by the scalar law (rare: a normal turning fast). */
static inline __attribute__((always_inline)) double law_lane(const lane_law *L, double nx, double ny, double nz,
                                                             double ov, double vx, double vy, double vz, double sqm,
                                                             double *sx, double *sy, double *sz, double *fx, double *fy,
                                                             double *fz)
{
    const double vn = vx * nx + vy * ny + vz * nz;
    double pn = L->k_n * ov - L->c_n * sqm * vn;
    pn = pn < 0.0 ? 0.0 : pn;
    const double tx = vx + -vn * nx, ty = vy + -vn * ny, tz = vz + -vn * nz;
    const double s0x = *sx, s0y = *sy, s0z = *sz;
    const double s2 = s0x * s0x + s0y * s0y + s0z * s0z;
    const double sn = s0x * nx + s0y * ny + s0z * nz;
    const double px = s0x + -sn * nx, py = s0y + -sn * ny, pz = s0z + -sn * nz;
    const double r2 = s2 - sn * sn;
    const double x = sn * sn / r2;
    const double poly = 1.0 + 0.5 * x - 0.375 * x * x;
    const int has = s2 > 0.0;
    const double redo = sn * sn < 1e-4 * s2 ? 0.0 : (has ? 1.0 : 0.0);
    double ux = has ? px * poly : s0x, uy = has ? py * poly : s0y, uz = has ? pz * poly : s0z;
    ux = ux + L->mks_dt * tx;
    uy = uy + L->mks_dt * ty;
    uz = uz + L->mks_dt * tz;
    const double limit = L->coh + pn * L->tan_phi, lim2 = limit * limit;
    const double smag2 = ux * ux + uy * uy + uz * uz;
    const int slide = smag2 > lim2;
    const double mcs = -L->c_s * sqm;
    double gx = ux + mcs * tx, gy = uy + mcs * ty, gz = uz + mcs * tz;
    const double fmag2 = gx * gx + gy * gy + gz * gz;
    const int over = fmag2 > lim2;
    /* one square root and one division for whichever of the two limits applies */
    const double cut = limit / sqrt(slide ? smag2 : fmag2);
    gx = over ? gx * cut : gx;
    gy = over ? gy * cut : gy;
    gz = over ? gz * cut : gz;
    ux = slide ? ux * cut : ux;
    uy = slide ? uy * cut : uy;
    uz = slide ? uz * cut : uz;
    gx = slide ? ux : gx;
    gy = slide ? uy : gy;
    gz = slide ? uz : gz;
    *sx = ux;
    *sy = uy;
    *sz = uz;
    *fx = gx + pn * nx;
    *fy = gy + pn * ny;
    *fz = gz + pn * nz;
    return redo;
}

/* Step 4 of bb_chunk, the law in lanes, in two loops, each a shorter chain of dependent
 * operations (the square root and division of the normal, then the law's): more lanes in
 * flight at once. The first (ss_law_normal) leaves the unit normal in dx, dy, dz, the overlap
 * in ra and the velocity at the contact point in vx, vy, vz; the second (ss_law_spring, from
 * lane j0 on) runs law_lane. Where the CPU has AVX2 (not AVX-512), ss_law_spring256 takes the
 * second loop's groups of four first. */
SD_SIMD_CLONES
static void ss_law_normal(ss_batch *restrict q, int m)
{
    for (int j = 0; j < m; j++) {
        const double dx = q->dx[j], dy = q->dy[j], dz = q->dz[j];
        const double d2 = dx * dx + dy * dy + dz * dz;
        const double dist = sqrt(d2);
        const double inv = 1.0 / dist;
        const int far = dist > 1e-300;
        const double nx = far ? dx * inv : 0.0, ny = far ? dy * inv : 0.0, nz = far ? dz * inv : 1.0;
        const double ov = (q->ra[j] + q->rb[j]) - dist;
        const double la = q->ra[j] - 0.5 * ov, lb = q->rb[j] - 0.5 * ov;
        const double wx = q->wax[j] * la + lb * q->wbx[j], wy = q->way[j] * la + lb * q->wby[j],
                     wz = q->waz[j] * la + lb * q->wbz[j];
        q->vx[j] = q->vx[j] - (wy * nz - wz * ny);
        q->vy[j] = q->vy[j] - (wz * nx - wx * nz);
        q->vz[j] = q->vz[j] - (wx * ny - wy * nx);
        q->dx[j] = nx;
        q->dy[j] = ny;
        q->dz[j] = nz;
        q->ra[j] = ov;
        q->la[j] = la;
        q->lb[j] = lb;
    }
}

SD_SIMD_CLONES
static void ss_law_spring(const sd_law *law, double dt, ss_batch *restrict q, int j0, int m)
{
    const lane_law L = lane_law_make(law, dt);
    for (int j = j0; j < m; j++) {
        const double nx = q->dx[j], ny = q->dy[j], nz = q->dz[j];
        double sx = q->sx[j], sy = q->sy[j], sz = q->sz[j], fx, fy, fz;
        q->redo[j] =
            law_lane(&L, nx, ny, nz, q->ra[j], q->vx[j], q->vy[j], q->vz[j], q->sqm[j], &sx, &sy, &sz, &fx, &fy, &fz);
        q->sx[j] = sx;
        q->sy[j] = sy;
        q->sz[j] = sz;
        q->fx[j] = fx;
        q->fy[j] = fy;
        q->fz[j] = fz;
        q->nfx[j] = ny * fz - nz * fy;
        q->nfy[j] = nz * fx - nx * fz;
        q->nfz[j] = nx * fy - ny * fx;
    }
}

/* Cylinder features from 3 up are the ends of a clipped support line (src/geom/cyl_tri.c). */
#define SD_CYL_LINE_PART 3

/* Global id of a triangle feature: kind in the low 2 bits (0 face, 1 edge, 2 vertex). */
static int64_t tri_feature_gid(const sd_walls *wl, int t, int f)
{
    int tf = f & ((1 << SD_TRI_FEATURE_BITS) - 1);
    int64_t part = (int64_t)(f >> SD_TRI_FEATURE_BITS) << 40;
    if (tf == SD_TRI_FACE) return part | ((int64_t)t << 2);
    if (tf < SD_TRI_VERT0) return part | ((int64_t)wl->edge_id[t][tf - SD_TRI_EDGE0] << 2) | 1;
    return part | ((int64_t)wl->vert_id[t][tf - SD_TRI_VERT0] << 2) | 2;
}

static int tri_has_edge(const sd_walls *wl, int t, int32_t e)
{
    return wl->edge_id[t][0] == e || wl->edge_id[t][1] == e || wl->edge_id[t][2] == e;
}

static int tri_has_vert(const sd_walls *wl, int t, int32_t v)
{
    return wl->vert_id[t][0] == v || wl->vert_id[t][1] == v || wl->vert_id[t][2] == v;
}

/* Flat-mesh rule for a log (cylinder–triangle pairs only). An edge of a flat floor shared by
 * two coplanar triangles (a seam), or a vertex shared by coplanar triangles, lies in the plane:
 * contacts of the log there are artefacts of the meshing (a cut of the log's support line, or
 * the seam under its side or end face, which would push the log along the floor). Contact X at
 * such a seam or vertex of triangle t is dropped when another contact Y of the same log is
 *  - a face contact on a triangle owning the feature (any part of the log);
 *  - a cut of the support line at the same seam while X is a cut too (both cuts go: the line's
 *    ends, rims or boundary edges, carry the log);
 *  - a cut of the support line on another triangle owning the feature while X is not a cut;
 *  - an edge/vertex contact (not a cut) listed earlier on another triangle owning the feature
 *    while X is not a cut (one of them is kept). */
static int is_line_cut(const sd_walls *wl, int t, int f, sd_vec3 n)
{
    int tf = f & ((1 << SD_TRI_FEATURE_BITS) - 1);
    return tf != SD_TRI_FACE && tf < SD_TRI_VERT0 && (f >> SD_TRI_FEATURE_BITS) >= SD_CYL_LINE_PART &&
           fabs(v3_dot(n, wl->tri[t].n)) > 1.0 - 1e-12;
}

static int flat_mesh_drop(const sd_walls *wl, int t, int is_edge, int32_t id, int x_cut, int tq, int fo, sd_vec3 no,
                          int y_first)
{
    if (is_edge) {
        if (!wl->edge_flat[id] || !tri_has_edge(wl, tq, id)) return 0;
    } else {
        if (!tri_has_vert(wl, tq, id) || fabs(v3_dot(wl->tri[t].n, wl->tri[tq].n)) < 1.0 - 1e-12) return 0;
    }
    int tfo = fo & ((1 << SD_TRI_FEATURE_BITS) - 1);
    if (tfo == SD_TRI_FACE) return 1;
    int y_cut = is_line_cut(wl, tq, fo, no);
    if (x_cut) return y_cut && is_edge && wl->edge_id[tq][tfo - SD_TRI_EDGE0] == id;
    if (tq == t) return 0;
    return y_cut || y_first;
}

/* Mesh rule: an edge contact is dropped when the same body part has a face contact on a
 * triangle owning that edge, or the same edge was already taken; a vertex contact when a face
 * or edge contact touches that vertex, or the vertex was already taken. A sphere rolling across
 * a shared edge of a flat mesh thus always feels exactly one contact. */
void sd_contact_mesh_dedup(const sd_walls *wl, const sd_pair *pairs, sd_manifold *man, int from, int to)
{
    for (int p = from; p < to; p++) {
        sd_manifold *m = &man[p];
        for (int k = 0; k < m->n; k++) {
            int f = m->feature[k];
            int tf = f & ((1 << SD_TRI_FEATURE_BITS) - 1);
            if (tf == SD_TRI_FACE) continue;
            int part = f >> SD_TRI_FEATURE_BITS;
            int t = pairs[p].b;
            int64_t gid = tri_feature_gid(wl, t, f);
            int is_edge = tf < SD_TRI_VERT0;
            int32_t id = is_edge ? wl->edge_id[t][tf - SD_TRI_EDGE0] : wl->vert_id[t][tf - SD_TRI_VERT0];
            int drop = 0;
            if (pairs[p].kind == SD_PAIR_CT) {
                int x_cut = is_line_cut(wl, t, f, m->normal[k]);
                for (int q = from; q < to && !drop; q++)
                    for (int kk = 0; kk < man[q].n && !drop; kk++)
                        if (!(q == p && kk == k))
                            drop = flat_mesh_drop(wl, t, is_edge, id, x_cut, pairs[q].b, man[q].feature[kk],
                                                  man[q].normal[kk], q < p || (q == p && kk < k));
            }
            for (int q = from; q < to && !drop; q++) {
                const sd_manifold *o = &man[q];
                int tq = pairs[q].b;
                for (int kk = 0; kk < o->n && !drop; kk++) {
                    if (q == p && kk == k) continue;
                    int fo = o->feature[kk];
                    int tfo = fo & ((1 << SD_TRI_FEATURE_BITS) - 1);
                    if ((fo >> SD_TRI_FEATURE_BITS) != part) continue;
                    if (tfo == SD_TRI_FACE) {
                        drop = is_edge ? tri_has_edge(wl, tq, id) : tri_has_vert(wl, tq, id);
                    } else if (tfo < SD_TRI_VERT0) {
                        if (is_edge) {
                            /* the same edge seen from the other triangle: keep the first */
                            drop = (q < p || (q == p && kk < k)) && tri_feature_gid(wl, tq, fo) == gid;
                        } else {
                            int32_t e = wl->edge_id[tq][tfo - SD_TRI_EDGE0];
                            drop = wl->edge_vert[e][0] == id || wl->edge_vert[e][1] == id;
                        }
                    } else if (!is_edge) {
                        drop = (q < p || (q == p && kk < k)) && tri_feature_gid(wl, tq, fo) == gid;
                    }
                }
            }
            if (drop) {
                /* mark dropped with overlap 0; compacted below */
                m->overlap[k] = -1.0;
            }
        }
    }
    for (int p = from; p < to; p++) {
        sd_manifold *m = &man[p];
        int j = 0;
        for (int k = 0; k < m->n; k++) {
            if (m->overlap[k] < 0.0) continue;
            if (j != k) {
                m->normal[j] = m->normal[k];
                m->point[j] = m->point[k];
                m->overlap[j] = m->overlap[k];
                m->feature[j] = m->feature[k];
            }
            j++;
        }
        m->n = j;
    }
}

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
    sd_contact_law(law, p->sqrt_m_eff, n, ov, vrel, w->def.dt, &shear, &f);
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
 * from lim on and no others (the passes after a sort: ss_batch's bed_lim, from bed_split),
 * else (lim < 0) from the store's flags. */
static inline int bed_at(const sd_bodies *b, int lim, int i) { return lim >= 0 ? i >= lim : sd_body_is_bed(b, i); }

static inline __attribute__((always_inline)) void add_pair_lim(sd_bodies *b, int lim, int i, int as_b,
                                                               const sd_pair_out *o)
{
    if (bed_at(b, lim, i)) return; /* its load is never read: stays zero (bt_range adds nothing to a fixed body) */
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

/* s found again when the count of bodies or of rebuilds changed since (bodies move in the
 * store only at a rebuild). A zeroed s is found afresh. */
static void bed_split(const sd_world *w, sd_bed_split *s)
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

/* A chunk's pair records field by field (sd_pair_soa, offset to the chunk's first entry): what
 * the touch filter reads of each pair, in entry order. */
typedef struct {
    const int32_t *a, *b, *off, *ck;
    const double *sqm;
    const float *rs2;
    uint8_t *act; /* (written by the touch filter) */
    sd_hist *sh;  /* where the sphere pairs' off point: bb.hist, or the list's own springs */
    /* sh is a near list's own springs (springs_out): there a sphere pair's slot holds its
     * sqrt_m_eff where bb.hist has the feature (slot_sqm), so that the law's mass comes with
     * the spring for the touching pairs instead of in a stream of its own for every entry, and
     * the feature is the entry's flag (act) */
    int lsq;
    int k0; /* the chunk's first entry (with lsq, a sphere pair's off is its entry's index) */
} soa_view;

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

static int pair_soa_reserve(sd_pair_soa *s, int n)
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

/* A record's cap and kind as the view holds them (ck): cap in the low half, kind in the high. */
static inline int32_t ck_pack(int kind, int cap)
{
    return (int32_t)((uint32_t)(uint16_t)cap | (uint32_t)(uint16_t)kind << 16);
}
static inline int ck_kind(int32_t ck) { return (int)((uint32_t)ck >> 16); }
/* the view's ck of an owner's cross entry (owned_update): a kind of no pair */
#define SD_CK_CROSS ((int32_t)0x7FFF0000)

/* The touch filter's step for a chunk entry that is not a sphere pair: an owner's cross entry
 * (ks < 0: computed in pass 1, its side added by bb_chunk's step 5) and, with defer, a
 * sphere-log pair (its apart test left to sc_geom256) go to gen as they are; a log's other pairs
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

/* An entry's rs2 (sd_pair_soa), for the AVX2 filter (ss_filter256), which reads no ck: a
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

static soa_view soa_at(const sd_pair_soa *s, int j0, sd_hist *sh, int lsq)
{
    return (soa_view){s->a + j0,   s->b + j0,   s->off + j0, s->ck + j0, s->sqm + j0,
                      s->rs2 + j0, s->act + j0, sh,          lsq,        j0};
}

/* Step 1 of bb_chunk (the touch filter) for the chunk's entries i0 .. i1: which pairs touch,
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

/* Step 3 of bb_chunk for the touching lanes j0 .. m: velocities, spins and the stored spring of
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


#ifdef SD_FILTER512
/* Step 1 of bb_chunk (the touch filter) for 8 pairs at a time, in AVX-512: the pair records
 * loaded from the chunk's view v, both centres and radii and the spring's feature gathered
 * into lanes, the touch test with the
 * scalar loop's operations in its order (same bits), the touching sphere pairs packed into the
 * batch by compress and stored 8 lanes wide (the arrays are padded by SS_PAD). A pair of
 * another kind (a log's) in a group takes the scalar loop's path for it, in pair order. Runs
 * while 8 pairs remain and returns where it stopped. */
__attribute__((target("avx512f,avx512vl,popcnt"))) static int ss_filter512(const sd_world *w, const int32_t *ks,
                                                                           const soa_view *v, int i, int n, int *used,
                                                                           ss_batch *q, int *mp, int *gen, int *ngp)
{
    sd_hist *hist = v->sh;
    const double *pos = &w->b.pos[0].x, *rad = w->b.radius;
    int m = *mp, ng = *ngp;
    const __m256i one = _mm256_set1_epi32(1), none = _mm256_set1_epi32(-1), hi16 = _mm256_set1_epi32((int)0xFFFF0000u),
                  lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (; i + 8 <= n; i += 8) {
        /* the records field by field, in entry order (loads, where gathering them from the
         * store's scattered lines cost the one-thread step 12-14 %: docs/performance-log.md §P10); cap in the low half
         * of ck and kind in the high half, kind SD_PAIR_SS is 0 */
        const __m256i ck = _mm256_loadu_si256((const __m256i *)(v->ck + i)),
                      a = _mm256_loadu_si256((const __m256i *)(v->a + i)),
                      b = _mm256_loadu_si256((const __m256i *)(v->b + i)),
                      off = _mm256_loadu_si256((const __m256i *)(v->off + i));
        const __mmask8 other = _mm256_test_epi32_mask(ck, hi16), ss = (__mmask8)~other;
        const __m256i a3 = _mm256_add_epi32(a, _mm256_add_epi32(a, a)),
                      b3 = _mm256_add_epi32(b, _mm256_add_epi32(b, b));
        const __m512d dx = _mm512_sub_pd(_mm512_i32gather_pd(a3, pos, 8), _mm512_i32gather_pd(b3, pos, 8));
        const __m512d dy = _mm512_sub_pd(_mm512_i32gather_pd(a3, pos + 1, 8), _mm512_i32gather_pd(b3, pos + 1, 8));
        const __m512d dz = _mm512_sub_pd(_mm512_i32gather_pd(a3, pos + 2, 8), _mm512_i32gather_pd(b3, pos + 2, 8));
        const __m512d ra = _mm512_i32gather_pd(a, rad, 8), rb = _mm512_i32gather_pd(b, rad, 8);
        const __m512d rs = _mm512_add_pd(ra, rb);
        const __m512d d2 =
            _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
        /* t = !(d2 >= rs^2), as the scalar loop (true for an unordered pair too); sphere pairs only */
        const __mmask8 t = (__mmask8)(_mm512_cmp_pd_mask(d2, _mm512_mul_pd(rs, rs), _CMP_NGE_UQ) & ss);
        /* the spring's feature (slot off, 32-byte slots: index 4 off, scale 8), of the sphere
         * lanes only: the others' off point into bb.hist, which need not be where hist is */
        /* (in a list's own slots, from the entries' flags: 0 with a spring, else -1) */
        const __m256i was =
            v->lsq ? _mm256_sub_epi32(_mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(v->act + i))), one)
                   : _mm256_mmask_i32gather_epi32(none, ss, _mm256_slli_epi32(off, 2),
                                                  (const int *)((const char *)hist + offsetof(sd_hist, feature)), 8);
        _mm256_mask_storeu_epi32(used + i, ss, _mm256_maskz_mov_epi32(t, one));
        /* the entries' flags: a spring after this step where they touch (soa_view.act; this
         * form reads the slots themselves) */
        for (int l = 0; l < 8; l++)
            v->act[i + l] = (uint8_t)(t >> l & 1);
        /* was | (t - 1): stored only where it changes (a contact that has just ended) */
        __mmask8 gone = v->lsq ? 0 : (__mmask8)(~t & ss & _mm256_cmpneq_epi32_mask(was, none));
        if (gone) {
            int32_t o[8];
            _mm256_storeu_si256((__m256i *)o, off);
            for (; gone; gone &= (__mmask8)(gone - 1))
                hist[o[__builtin_ctz(gone)]].feature = -1;
        }
        _mm512_storeu_pd(q->dx + m, _mm512_maskz_compress_pd(t, dx));
        _mm512_storeu_pd(q->dy + m, _mm512_maskz_compress_pd(t, dy));
        _mm512_storeu_pd(q->dz + m, _mm512_maskz_compress_pd(t, dz));
        _mm512_storeu_pd(q->ra + m, _mm512_maskz_compress_pd(t, ra));
        _mm512_storeu_pd(q->rb + m, _mm512_maskz_compress_pd(t, rb));
        if (!v->lsq) _mm512_storeu_pd(q->sqm + m, _mm512_maskz_compress_pd(t, _mm512_loadu_pd(v->sqm + i)));
        _mm256_storeu_si256((__m256i *)(q->ia + m), _mm256_maskz_compress_epi32(t, a));
        _mm256_storeu_si256((__m256i *)(q->ib + m), _mm256_maskz_compress_epi32(t, b));
        _mm256_storeu_si256((__m256i *)(q->off + m), _mm256_maskz_compress_epi32(t, off));
        _mm256_storeu_si256((__m256i *)(q->was + m), _mm256_maskz_compress_epi32(t, was));
        _mm256_storeu_si256((__m256i *)(q->sel + m),
                            _mm256_maskz_compress_epi32(t, _mm256_add_epi32(_mm256_set1_epi32(i), lane)));
        m += __builtin_popcount(t);
        /* the log pairs and cross entries of the group, as the scalar loop takes them, but a
         * sphere-log pair's apart test left to sc_geom256's lanes, as ss_filter256 leaves it
         * (its kind from the view: the pair store's line is read only for the other log pairs) */
        const int defer = w->sw[SD_SW_SC_LANES] && w->sw[SD_SW_SC_GEOM];
        for (__mmask8 o = other; o; o &= (__mmask8)(o - 1))
            filter_other(w, ks, v, i + __builtin_ctz(o), defer, used, gen, &ng);
    }
    *mp = m;
    *ngp = ng;
    return i;
}

/* Step 3 of bb_chunk in AVX-512, 8 lanes at a time (the last group masked): the touching
 * pairs' velocities, spins and stored springs gathered into the batch, a new contact's spring
 * +0.0 as the scalar loop's mask gives it (same bits). */
__attribute__((target("avx512f,avx512vl"))) static void ss_gather512(const sd_world *w, ss_batch *q, int m)
{
    const double *vel = &w->b.vel[0].x, *om = &w->b.omega[0].x;
    const char *sh = (const char *)q->sh + offsetof(sd_hist, shear);
    const __m512d zero = _mm512_setzero_pd();
    for (int j = 0; j < m; j += 8) {
        const __mmask8 live = (__mmask8)(m - j >= 8 ? 0xFF : (1u << (m - j)) - 1u);
        const __m256i ia = _mm256_maskz_loadu_epi32(live, q->ia + j), ib = _mm256_maskz_loadu_epi32(live, q->ib + j);
        const __m256i a3 = _mm256_add_epi32(ia, _mm256_add_epi32(ia, ia)),
                      b3 = _mm256_add_epi32(ib, _mm256_add_epi32(ib, ib));
        _mm512_storeu_pd(q->vx + j, _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, live, a3, vel, 8),
                                                  _mm512_mask_i32gather_pd(zero, live, b3, vel, 8)));
        _mm512_storeu_pd(q->vy + j, _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, live, a3, vel + 1, 8),
                                                  _mm512_mask_i32gather_pd(zero, live, b3, vel + 1, 8)));
        _mm512_storeu_pd(q->vz + j, _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, live, a3, vel + 2, 8),
                                                  _mm512_mask_i32gather_pd(zero, live, b3, vel + 2, 8)));
        _mm512_storeu_pd(q->wax + j, _mm512_mask_i32gather_pd(zero, live, a3, om, 8));
        _mm512_storeu_pd(q->way + j, _mm512_mask_i32gather_pd(zero, live, a3, om + 1, 8));
        _mm512_storeu_pd(q->waz + j, _mm512_mask_i32gather_pd(zero, live, a3, om + 2, 8));
        _mm512_storeu_pd(q->wbx + j, _mm512_mask_i32gather_pd(zero, live, b3, om, 8));
        _mm512_storeu_pd(q->wby + j, _mm512_mask_i32gather_pd(zero, live, b3, om + 1, 8));
        _mm512_storeu_pd(q->wbz + j, _mm512_mask_i32gather_pd(zero, live, b3, om + 2, 8));
        /* the spring of a held contact (its feature was 0); 32-byte slots: index 4 off, scale 8 */
        const __mmask8 held = (__mmask8)(live & _mm256_cmpeq_epi32_mask(_mm256_maskz_loadu_epi32(live, q->was + j),
                                                                        _mm256_setzero_si256()));
        const __m256i o4 = _mm256_slli_epi32(_mm256_maskz_loadu_epi32(live, q->off + j), 2);
        _mm512_storeu_pd(q->sx + j, _mm512_mask_i32gather_pd(zero, held, o4, sh, 8));
        _mm512_storeu_pd(q->sy + j, _mm512_mask_i32gather_pd(zero, held, o4, sh + 8, 8));
        _mm512_storeu_pd(q->sz + j, _mm512_mask_i32gather_pd(zero, held, o4, sh + 16, 8));
        if (q->lsq) /* (a list's own slot: sqm in the first 8 bytes) */
            _mm512_storeu_pd(q->sqm + j, _mm512_mask_i32gather_pd(zero, live, o4, sh - 8, 8));
    }
}

/* p[a[k]] - p[b[k]] for the four vec3 rows of the array p, in lanes x, y, z */
__attribute__((target("avx2"))) static inline void diff_lanes(const double *p, const int32_t *a, const int32_t *b,
                                                              __m256d *x, __m256d *y, __m256d *z)
{
    __m256d r[4];
    sd_transpose4(_mm256_sub_pd(SD_XYZ_LOAD(p, a[0]), SD_XYZ_LOAD(p, b[0])),
                  _mm256_sub_pd(SD_XYZ_LOAD(p, a[1]), SD_XYZ_LOAD(p, b[1])),
                  _mm256_sub_pd(SD_XYZ_LOAD(p, a[2]), SD_XYZ_LOAD(p, b[2])),
                  _mm256_sub_pd(SD_XYZ_LOAD(p, a[3]), SD_XYZ_LOAD(p, b[3])), r);
    *x = r[0], *y = r[1], *z = r[2];
}

/* Lane compress for AVX2, indexed by a 4-bit mask of kept lanes: the kept lanes moved down in
 * order. perm_pd: _mm256_permutevar8x32 indices for 4 doubles; shuf_i32: _mm_shuffle_epi8
 * bytes for 4 int32. Filled once, by the first world's first contact pass (call_once). */
static int32_t perm_pd[16][8];
static uint8_t shuf_i32[16][16];
static int32_t bit_i32[16][4]; /* lane k: bit k of the mask, 0 or 1 */
static uint32_t bit_u8[16];     /* byte k: bit k of the mask, 0 or 1 */

static once_flag simd_tables_once = ONCE_FLAG_INIT;

static void simd_tables_init(void)
{
    for (int mask = 0; mask < 16; mask++) {
        int n = 0;
        bit_u8[mask] = 0;
        for (int k = 0; k < 4; k++) {
            bit_i32[mask][k] = (mask >> k) & 1;
            bit_u8[mask] |= (uint32_t)((mask >> k) & 1) << (8 * k);
            if (!((mask >> k) & 1)) continue;
            perm_pd[mask][2 * n] = 2 * k, perm_pd[mask][2 * n + 1] = 2 * k + 1;
            for (int c = 0; c < 4; c++)
                shuf_i32[mask][4 * n + c] = (uint8_t)(4 * k + c);
            n++;
        }
        for (; n < 4; n++) { /* the rest: anything (never read) */
            perm_pd[mask][2 * n] = 0, perm_pd[mask][2 * n + 1] = 1;
            for (int c = 0; c < 4; c++)
                shuf_i32[mask][4 * n + c] = 0x80;
        }
    }
}

/* Step 1 of bb_chunk in AVX2, 4 pairs at a time: ss_filter_range's operations in its order
 * (same bits), the centres read as rows (SD_XYZ_LOAD) and turned into lanes,
 * the touching pairs packed into the batch by a permutation from a table and stored 4 lanes
 * wide (the arrays are padded by SS_PAD). The group's other entries go to gen as they are (not
 * through filter_other: bb_chunk's step 2 takes them through other_pair). Runs while 4 pairs
 * remain and returns where it stopped; gen has room for 4 past *ngp (*ngp <= i). */
__attribute__((target("avx2,popcnt"))) static int ss_filter256(const sd_world *w, const soa_view *v, int i, int n,
                                                               int *used, ss_batch *q, int *mp, int *gen, int *ngp)
{
    sd_hist *hist = v->sh;
    const double *pos = &w->b.pos[0].x;
    /* the view's arrays in locals: the packing's 16-byte stores may alias anything, and gcc
     * loaded each address from *v again after them */
    const int32_t *const va = v->a, *const vb = v->b, *const voff = v->off;
    const double *const vsqm = v->sqm, *const rad = w->b.radius;
    const float *const vrs2 = v->rs2;
    uint8_t *const vact = v->act;
    const int lsq = v->lsq;
    int m = *mp, ng = *ngp;
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    for (; i + 4 <= n; i += 4) {
        /* the lanes of sphere pairs, by the sign of the entries' rs2 (-1 for any other:
         * entry_rs2; ck is not read); a log's pair takes the scalar loop's path after the
         * group (in pair order among the log pairs) */
        const __m128 rs2f = _mm_loadu_ps(vrs2 + i);
        const int ss = ~_mm_movemask_ps(rs2f) & 15;
        __m256d dx, dy, dz;
        diff_lanes(pos, va + i, vb + i, &dx, &dy, &dz);
        const __m256d d2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
        /* t = !(d2 >= rs^2), as the scalar loop (true for an unordered pair too), from the
         * entry's rs^2 as a float (4 bytes of stream, not 8): below it less a relative 2^-22, a
         * pair touches; at or above it plus as much, it does not (the float is within 2^-24 of
         * rs^2); in between, or with a NaN, the radii are read and the test made exactly (a
         * gap within ~1e-7 of the radii: seldom). The radii themselves are read by the gather
         * for the touching lanes (ss_gather256) */
        const __m256d r = _mm256_cvtps_pd(rs2f);
        const int in = _mm256_movemask_pd(
                      _mm256_cmp_pd(d2, _mm256_mul_pd(r, _mm256_set1_pd(1.0 - RS2_EDGE)), _CMP_LT_OQ)),
                  out = _mm256_movemask_pd(
                      _mm256_cmp_pd(d2, _mm256_mul_pd(r, _mm256_set1_pd(1.0 + RS2_EDGE)), _CMP_GE_OQ));
        int t = in & ss, edge = ~(in | out) & ss & 15;
        if (edge) {
            double d2l[4];
            _mm256_storeu_pd(d2l, d2);
            for (; edge; edge &= edge - 1) {
                const int l = __builtin_ctz((unsigned)edge);
                const double rs = rad[va[i + l]] + rad[vb[i + l]];
                t |= !(d2l[l] >= rs * rs) << l;
            }
        }
        /* the slots' features from the entries' flags (0 with a spring, else -1), not from the
         * slots: a line of its own for each near pair, most of them apart in a flow (the
         * slots' load was a tenth of this loop's samples in the paper's capture) */
        uint32_t act4;
        memcpy(&act4, vact + i, sizeof act4);
        const __m128i was = _mm_sub_epi32(_mm_cvtepu8_epi32(_mm_cvtsi32_si128((int)act4)), _mm_set1_epi32(1));
        const int had = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(was, _mm_setzero_si128())));
        _mm_storeu_si128((__m128i *)(used + i), _mm_loadu_si128((const __m128i *)bit_i32[t]));
        /* the flags for the next step: a spring where they touch now */
        memcpy(vact + i, &bit_u8[t], sizeof act4);
        /* a contact that has just ended loses its spring (few in a step, so the branch is
         * seldom taken) */
        int gone = lsq ? 0 : ~t & had & ss;
        for (; gone; gone &= gone - 1)
            hist[voff[i + __builtin_ctz((unsigned)gone)]].feature = -1;
        const __m256i pp = _mm256_loadu_si256((const __m256i *)perm_pd[t]);
        const __m128i ps = _mm_loadu_si128((const __m128i *)shuf_i32[t]);
#define PACK_PD(dst, x) _mm256_storeu_pd((dst) + m, _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(x), pp)))
#define PACK_I32(dst, x) _mm_storeu_si128((__m128i *)((dst) + m), _mm_shuffle_epi8((x), ps))
        PACK_PD(q->dx, dx);
        PACK_PD(q->dy, dy);
        PACK_PD(q->dz, dz);
        if (!lsq) PACK_PD(q->sqm, _mm256_loadu_pd(vsqm + i)); /* (else the gather: the slot) */
        PACK_I32(q->ia, _mm_loadu_si128((const __m128i *)(va + i)));
        PACK_I32(q->ib, _mm_loadu_si128((const __m128i *)(vb + i)));
        /* (in a list's own slots, off is the entry's index: not read) */
        PACK_I32(q->off,
                 lsq ? _mm_add_epi32(_mm_set1_epi32(v->k0 + i), lane) : _mm_loadu_si128((const __m128i *)(voff + i)));
        PACK_I32(q->was, was);
        PACK_I32(q->sel, _mm_add_epi32(_mm_set1_epi32(i), lane));
#undef PACK_PD
#undef PACK_I32
        m += __builtin_popcount((unsigned)t);
        /* the group's other entries (a log's pair, an owner's cross entry) listed in gen as they
         * are, by the same table, and sorted out in step 2 (other_pair; a sphere-log pair's
         * apart test left to sc_geom256's lanes, its kind read from the view there). A loop over
         * them here, like the scalar filter's, ran a number of times that changes from group to
         * group where logs are, and its exit was mispredicted: the packing ~2.5 % slower
         * (docs/performance-log.md) */
        const int om = ~ss & 15;
        _mm_storeu_si128((__m128i *)(gen + ng), _mm_shuffle_epi8(_mm_add_epi32(_mm_set1_epi32(i), lane),
                                                                 _mm_loadu_si128((const __m128i *)shuf_i32[om])));
        ng += __builtin_popcount((unsigned)om);
    }
    *mp = m;
    *ngp = ng;
    return i;
}

/* Step 3 of bb_chunk in AVX2, 4 touching lanes at a time: each body's velocity and spin read as
 * a row and turned into lanes, the slot's spring likewise, masked to +0.0 for a new contact as
 * ss_gather_range does (same bits). Returns where it stopped (the rest: ss_gather_range). */
_Static_assert(sizeof(sd_hist) == 32 && offsetof(sd_hist, shear) == 8, "ss_gather256 reads a slot as 4 doubles");

__attribute__((target("avx2"))) static int ss_gather256(const sd_world *w, ss_batch *q, int m)
{
    const double *vel = &w->b.vel[0].x, *om = &w->b.omega[0].x, *rad = w->b.radius;
    const sd_hist *hist = q->sh;
    int j = 0;
    for (; j + 4 <= m; j += 4) {
        const int a0 = q->ia[j], a1 = q->ia[j + 1], a2 = q->ia[j + 2], a3 = q->ia[j + 3];
        const int b0 = q->ib[j], b1 = q->ib[j + 1], b2 = q->ib[j + 2], b3 = q->ib[j + 3];
        __m256d r[4];
        __m256d x, y, z;
        /* the radii (the AVX2 filter tests the entries' (r_a + r_b)^2 and leaves them) */
        _mm256_storeu_pd(q->ra + j, _mm256_setr_pd(rad[a0], rad[a1], rad[a2], rad[a3]));
        _mm256_storeu_pd(q->rb + j, _mm256_setr_pd(rad[b0], rad[b1], rad[b2], rad[b3]));
        diff_lanes(vel, q->ia + j, q->ib + j, &x, &y, &z);
        _mm256_storeu_pd(q->vx + j, x);
        _mm256_storeu_pd(q->vy + j, y);
        _mm256_storeu_pd(q->vz + j, z);
        sd_transpose4(SD_XYZ_LOAD(om, a0), SD_XYZ_LOAD(om, a1), SD_XYZ_LOAD(om, a2), SD_XYZ_LOAD(om, a3), r);
        _mm256_storeu_pd(q->wax + j, r[0]);
        _mm256_storeu_pd(q->way + j, r[1]);
        _mm256_storeu_pd(q->waz + j, r[2]);
        sd_transpose4(SD_XYZ_LOAD(om, b0), SD_XYZ_LOAD(om, b1), SD_XYZ_LOAD(om, b2), SD_XYZ_LOAD(om, b3), r);
        _mm256_storeu_pd(q->wbx + j, r[0]);
        _mm256_storeu_pd(q->wby + j, r[1]);
        _mm256_storeu_pd(q->wbz + j, r[2]);
        /* the slots as rows (feature and padding, shear x, y, z): a held contact's (was 0) kept */
        sd_transpose4(_mm256_loadu_pd((const double *)&hist[q->off[j]]),
                      _mm256_loadu_pd((const double *)&hist[q->off[j + 1]]),
                      _mm256_loadu_pd((const double *)&hist[q->off[j + 2]]),
                      _mm256_loadu_pd((const double *)&hist[q->off[j + 3]]), r);
        const __m256d keep = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(
            _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(q->was + j)), _mm_setzero_si128())));
        if (q->lsq) _mm256_storeu_pd(q->sqm + j, r[0]); /* (a list's own slot: sqm first) */
        _mm256_storeu_pd(q->sx + j, _mm256_and_pd(r[1], keep));
        _mm256_storeu_pd(q->sy + j, _mm256_and_pd(r[2], keep));
        _mm256_storeu_pd(q->sz + j, _mm256_and_pd(r[3], keep));
    }
    return j;
}

/* *p + (x, y, z) of row r, or *p - it (sub): add_pair_lim's v3_add / v3_sub, x and y in one
 * 16-byte operation */
__attribute__((target("avx2"))) static inline void row_add(sd_vec3 *p, __m256d r, int sub)
{
    const __m128d xy = _mm_loadu_pd(&p->x), rxy = _mm256_castpd256_pd128(r);
    const double rz = _mm_cvtsd_f64(_mm256_extractf128_pd(r, 1));
    _mm_storeu_pd(&p->x, sub ? _mm_sub_pd(xy, rxy) : _mm_add_pd(xy, rxy));
    p->z = sub ? p->z - rz : p->z + rz;
}

/* Step 5 of bb_chunk (with acc) in AVX2 for the lanes j .. j+3, when none is to be redone
 * (returns 0 and does nothing otherwise): the torques of four lanes at once, the slots' springs
 * stored as 32-byte rows (the feature 0), and each pair onto its two bodies in lane order as
 * add_pair_lim does (same bits; a bed body's rows into q->sink, where the bed is from
 * q->bed_lim on). */
__attribute__((target("avx2"))) static int ss_sums256(ss_batch *q, int j, sd_bodies *acc)
{
    const __m256d zero = _mm256_setzero_pd();
    if (_mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(q->redo + j), zero, _CMP_NEQ_UQ))) return 0;
    sd_hist *hist = q->sh;
    const __m256d nfx = _mm256_loadu_pd(q->nfx + j), nfy = _mm256_loadu_pd(q->nfy + j),
                  nfz = _mm256_loadu_pd(q->nfz + j);
    const __m256d sign = _mm256_set1_pd(-0.0); /* -la as the scalar loop negates it: the sign bit flipped */
    const __m256d mla = _mm256_xor_pd(_mm256_loadu_pd(q->la + j), sign),
                  mlb = _mm256_xor_pd(_mm256_loadu_pd(q->lb + j), sign);
    __m256d hr[4], fr[4], ta[4], tb[4];
    /* the slot's first 8 bytes: the feature 0 and its padding, or in a list's own slot the sqm
     * it holds */
    sd_transpose4(q->lsq ? _mm256_loadu_pd(q->sqm + j) : zero, _mm256_loadu_pd(q->sx + j), _mm256_loadu_pd(q->sy + j),
                  _mm256_loadu_pd(q->sz + j), hr);
    sd_transpose4(_mm256_loadu_pd(q->fx + j), _mm256_loadu_pd(q->fy + j), _mm256_loadu_pd(q->fz + j), zero, fr);
    sd_transpose4(_mm256_mul_pd(nfx, mla), _mm256_mul_pd(nfy, mla), _mm256_mul_pd(nfz, mla), zero, ta);
    sd_transpose4(_mm256_mul_pd(nfx, mlb), _mm256_mul_pd(nfy, mlb), _mm256_mul_pd(nfz, mlb), zero, tb);
    /* the bodies' arrays in locals: each row's 32-byte store may alias anything, and gcc
     * loaded the addresses from *acc again after every one */
    sd_vec3 *const force = acc->force, *const torque = acc->torque;
    const int lim = q->bed_lim;
    if (lim >= 0) {
        /* the bed from lim on: a lane's B body of the bed (a pair's A never is: its B would be
         * too) adds into a sink row instead of a branch, taken at random where spheres rest on
         * the bed */
        sd_vec3 *const sink = q->sink;
        for (int k = 0; k < 4; k++) {
            const int ia = q->ia[j + k], ib = q->ib[j + k], bed = ib >= lim;
            _mm256_storeu_pd((double *)&hist[q->off[j + k]], hr[k]);
            if (ia < lim) {
                row_add(&force[ia], fr[k], 0);
                row_add(&torque[ia], ta[k], 0);
            }
            /* (the select in integer bits: as a ternary gcc made it a branch again) */
            const uintptr_t m = (uintptr_t)0 - (uintptr_t)bed, pf = (uintptr_t)&force[ib], pt = (uintptr_t)&torque[ib];
            sd_vec3 *const fb = (sd_vec3 *)(pf ^ ((pf ^ (uintptr_t)&sink[2 * k]) & m)),
                           *const tq = (sd_vec3 *)(pt ^ ((pt ^ (uintptr_t)&sink[2 * k + 1]) & m));
            row_add(fb, fr[k], 1);
            row_add(tq, tb[k], 0);
        }
        return 1;
    }
    for (int k = 0; k < 4; k++) {
        const int ia = q->ia[j + k], ib = q->ib[j + k];
        _mm256_storeu_pd((double *)&hist[q->off[j + k]], hr[k]);
        if (!bed_at(acc, lim, ia)) {
            row_add(&force[ia], fr[k], 0);
            row_add(&torque[ia], ta[k], 0);
        }
        if (!bed_at(acc, lim, ib)) {
            row_add(&force[ib], fr[k], 1);
            row_add(&torque[ib], tb[k], 0);
        }
    }
    return 1;
}
#endif

#ifdef SD_FILTER512
/* the calling thread's groups run in lanes, and of them those that skipped the limit (tests) */
static _Thread_local long ss_law256_groups, ss_law256_skips;

long sd_ss_law256_count(long *skipped)
{
    if (skipped) *skipped = ss_law256_skips;
    return ss_law256_groups;
}

/* ss_law_spring in AVX2 for the lanes 0 .. m & ~3, four at a time: law_lane's operations in
 * its order, each select a blend (the same bits), and its limit's square root and division
 * left out of a group where no lane slides and no lane's force passes the limit (three groups
 * in four on a bed at rest: they were a fifth of this loop's samples there). Returns the lanes
 * done. */
__attribute__((target("avx2"))) static int ss_law_spring256(const sd_law *law, double dt, ss_batch *restrict q, int m)
{
    const lane_law L = lane_law_make(law, dt);
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5),
                  c375 = _mm256_set1_pd(0.375), c1e4 = _mm256_set1_pd(1e-4), sign = _mm256_set1_pd(-0.0),
                  kn = _mm256_set1_pd(L.k_n), cn = _mm256_set1_pd(L.c_n), mks = _mm256_set1_pd(L.mks_dt),
                  coh = _mm256_set1_pd(L.coh), tphi = _mm256_set1_pd(L.tan_phi), mcsf = _mm256_set1_pd(-L.c_s);
    int j = 0;
    for (; j + 4 <= m; j += 4) {
        const __m256d nx = _mm256_loadu_pd(q->dx + j), ny = _mm256_loadu_pd(q->dy + j), nz = _mm256_loadu_pd(q->dz + j);
        const __m256d vx = _mm256_loadu_pd(q->vx + j), vy = _mm256_loadu_pd(q->vy + j), vz = _mm256_loadu_pd(q->vz + j);
        const __m256d ov = _mm256_loadu_pd(q->ra + j), sqm = _mm256_loadu_pd(q->sqm + j);
        const __m256d s0x = _mm256_loadu_pd(q->sx + j), s0y = _mm256_loadu_pd(q->sy + j),
                      s0z = _mm256_loadu_pd(q->sz + j);
        const __m256d vn =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, nx), _mm256_mul_pd(vy, ny)), _mm256_mul_pd(vz, nz));
        __m256d pn = _mm256_sub_pd(_mm256_mul_pd(kn, ov), _mm256_mul_pd(_mm256_mul_pd(cn, sqm), vn));
        pn = _mm256_blendv_pd(pn, zero, _mm256_cmp_pd(pn, zero, _CMP_LT_OQ));
        const __m256d mvn = _mm256_xor_pd(vn, sign);
        const __m256d tx = _mm256_add_pd(vx, _mm256_mul_pd(mvn, nx)), ty = _mm256_add_pd(vy, _mm256_mul_pd(mvn, ny)),
                      tz = _mm256_add_pd(vz, _mm256_mul_pd(mvn, nz));
        const __m256d s2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(s0x, s0x), _mm256_mul_pd(s0y, s0y)), _mm256_mul_pd(s0z, s0z));
        const __m256d sn =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(s0x, nx), _mm256_mul_pd(s0y, ny)), _mm256_mul_pd(s0z, nz));
        const __m256d msn = _mm256_xor_pd(sn, sign);
        const __m256d px = _mm256_add_pd(s0x, _mm256_mul_pd(msn, nx)), py = _mm256_add_pd(s0y, _mm256_mul_pd(msn, ny)),
                      pz = _mm256_add_pd(s0z, _mm256_mul_pd(msn, nz));
        const __m256d sn2 = _mm256_mul_pd(sn, sn);
        const __m256d r2 = _mm256_sub_pd(s2, sn2);
        const __m256d x = _mm256_div_pd(sn2, r2);
        const __m256d poly =
            _mm256_sub_pd(_mm256_add_pd(one, _mm256_mul_pd(half, x)), _mm256_mul_pd(_mm256_mul_pd(c375, x), x));
        const __m256d has = _mm256_cmp_pd(s2, zero, _CMP_GT_OQ);
        /* redo = sn^2 < 1e-4 s2 ? 0 : (has ? 1 : 0) */
        const __m256d redo =
            _mm256_andnot_pd(_mm256_cmp_pd(sn2, _mm256_mul_pd(c1e4, s2), _CMP_LT_OQ), _mm256_and_pd(has, one));
        __m256d ux = _mm256_blendv_pd(s0x, _mm256_mul_pd(px, poly), has),
                uy = _mm256_blendv_pd(s0y, _mm256_mul_pd(py, poly), has),
                uz = _mm256_blendv_pd(s0z, _mm256_mul_pd(pz, poly), has);
        ux = _mm256_add_pd(ux, _mm256_mul_pd(mks, tx));
        uy = _mm256_add_pd(uy, _mm256_mul_pd(mks, ty));
        uz = _mm256_add_pd(uz, _mm256_mul_pd(mks, tz));
        const __m256d limit = _mm256_add_pd(coh, _mm256_mul_pd(pn, tphi)), lim2 = _mm256_mul_pd(limit, limit);
        const __m256d smag2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ux, ux), _mm256_mul_pd(uy, uy)), _mm256_mul_pd(uz, uz));
        const __m256d slide = _mm256_cmp_pd(smag2, lim2, _CMP_GT_OQ);
        const __m256d mcs = _mm256_mul_pd(mcsf, sqm);
        __m256d gx = _mm256_add_pd(ux, _mm256_mul_pd(mcs, tx)), gy = _mm256_add_pd(uy, _mm256_mul_pd(mcs, ty)),
                gz = _mm256_add_pd(uz, _mm256_mul_pd(mcs, tz));
        const __m256d fmag2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(gx, gx), _mm256_mul_pd(gy, gy)), _mm256_mul_pd(gz, gz));
        const __m256d over = _mm256_cmp_pd(fmag2, lim2, _CMP_GT_OQ);
        ss_law256_groups++;
        if (!_mm256_movemask_pd(_mm256_or_pd(slide, over)))
            ss_law256_skips++;
        else {
            const __m256d cut = _mm256_div_pd(limit, _mm256_sqrt_pd(_mm256_blendv_pd(fmag2, smag2, slide)));
            gx = _mm256_blendv_pd(gx, _mm256_mul_pd(gx, cut), over);
            gy = _mm256_blendv_pd(gy, _mm256_mul_pd(gy, cut), over);
            gz = _mm256_blendv_pd(gz, _mm256_mul_pd(gz, cut), over);
            ux = _mm256_blendv_pd(ux, _mm256_mul_pd(ux, cut), slide);
            uy = _mm256_blendv_pd(uy, _mm256_mul_pd(uy, cut), slide);
            uz = _mm256_blendv_pd(uz, _mm256_mul_pd(uz, cut), slide);
            gx = _mm256_blendv_pd(gx, ux, slide);
            gy = _mm256_blendv_pd(gy, uy, slide);
            gz = _mm256_blendv_pd(gz, uz, slide);
        }
        const __m256d fx = _mm256_add_pd(gx, _mm256_mul_pd(pn, nx)), fy = _mm256_add_pd(gy, _mm256_mul_pd(pn, ny)),
                      fz = _mm256_add_pd(gz, _mm256_mul_pd(pn, nz));
        _mm256_storeu_pd(q->redo + j, redo);
        _mm256_storeu_pd(q->sx + j, ux), _mm256_storeu_pd(q->sy + j, uy), _mm256_storeu_pd(q->sz + j, uz);
        _mm256_storeu_pd(q->fx + j, fx), _mm256_storeu_pd(q->fy + j, fy), _mm256_storeu_pd(q->fz + j, fz);
        _mm256_storeu_pd(q->nfx + j, _mm256_sub_pd(_mm256_mul_pd(ny, fz), _mm256_mul_pd(nz, fy)));
        _mm256_storeu_pd(q->nfy + j, _mm256_sub_pd(_mm256_mul_pd(nz, fx), _mm256_mul_pd(nx, fz)));
        _mm256_storeu_pd(q->nfz + j, _mm256_sub_pd(_mm256_mul_pd(nx, fy), _mm256_mul_pd(ny, fx)));
    }
    return j;
}
#endif

/* A sphere-log pair whose manifold is one point (the sphere against the log's side or end:
 * most of them) through the law in lanes, like the walls' face contacts: apply_manifold's
 * arithmetic for a one-point manifold between two moving bodies, operation for operation
 * (same bits). */
static void sc_lane_fill(const sd_world *w, const sd_pair *p, const sd_manifold *mf, const sd_hist *h, int i,
                         struct sc_lanes *q, int j)
{
    const sd_bodies *b = &w->b;
    const int a = p->a, c = p->b;
    const sd_vec3 pt = mf->point[0], ra = v3_sub(pt, b->pos[a]), rb = v3_sub(pt, b->pos[c]);
    const sd_vec3 va = b->vel[a], wa = b->omega[a], vb = b->vel[c], wb = b->omega[c];
    q->nx[j] = mf->normal[0].x, q->ny[j] = mf->normal[0].y, q->nz[j] = mf->normal[0].z, q->ov[j] = mf->overlap[0];
    q->px[j] = pt.x, q->py[j] = pt.y, q->pz[j] = pt.z;
    q->rax[j] = ra.x, q->ray[j] = ra.y, q->raz[j] = ra.z;
    q->rbx[j] = rb.x, q->rby[j] = rb.y, q->rbz[j] = rb.z;
    q->vax[j] = va.x, q->vay[j] = va.y, q->vaz[j] = va.z, q->wax[j] = wa.x, q->way[j] = wa.y, q->waz[j] = wa.z;
    q->vbx[j] = vb.x, q->vby[j] = vb.y, q->vbz[j] = vb.z, q->wbx[j] = wb.x, q->wby[j] = wb.y, q->wbz[j] = wb.z;
    q->sqm[j] = p->sqrt_m_eff;
    /* the spring of the same feature, or a new one (the pair has one slot) */
    const int same = h->feature == mf->feature[0];
    q->sx[j] = same ? h->shear.x : 0.0, q->sy[j] = same ? h->shear.y : 0.0, q->sz[j] = same ? h->shear.z : 0.0;
    q->feature[j] = mf->feature[0];
    q->i[j] = i;
}

static long sc_geom_run;

long sd_sc_geom_count(void) { return __atomic_load_n(&sc_geom_run, __ATOMIC_RELAXED); }

static long sc_lanes_run, sc_lanes_redo;

long sd_sc_lanes_count(long *redo)
{
    if (redo) *redo = __atomic_load_n(&sc_lanes_redo, __ATOMIC_RELAXED);
    return __atomic_load_n(&sc_lanes_run, __ATOMIC_RELAXED);
}

/* A pair of another shape (chunk entry i) through its kernel: a one-point sphere-log contact
 * into lane msc of q (returns 1), anything else through apply_manifold now (returns 0). Out of
 * line: inlined, it crowded the sphere pass's registers. */
static __attribute__((noinline)) int pair_general(const sd_world *w, const sd_law *law, const sd_pair *p, int i,
                                                  struct sc_lanes *q, int msc, sd_pair_out *out, int *used)
{
    sd_manifold m;
    sd_hist *h = &w->bb.hist[p->off];
    if (p->kind == SD_PAIR_CC) {
        /* two logs (or a log and a pipe): the axis that showed them apart last time first */
        sd_vec3 sep = h->feature == SD_HIST_SEP_AXIS ? h->shear : v3(0.0, 0.0, 0.0);
        const sd_cyl ca = sd_body_cyl(&w->b, p->a), cb = sd_body_cyl(&w->b, p->b);
        sd_geom_cyl_cyl_sep(&ca, &cb, &m, &sep);
        used[i] = apply_manifold(w, law, &m, p->a, p->b, 0, p->sqrt_m_eff, h, p->cap, &out[i]);
        if (m.n == 0 && (sep.x != 0.0 || sep.y != 0.0 || sep.z != 0.0)) {
            h->feature = SD_HIST_SEP_AXIS;
            h->shear = sep;
        }
        return 0;
    }
    narrow_bb(&w->b, p, &m);
    if (p->kind == SD_PAIR_SC && m.n == 1 && p->cap == 1 && w->sw[SD_SW_SC_LANES]) {
        sc_lane_fill(w, p, &m, h, i, q, msc);
        return 1;
    }
    used[i] = apply_manifold(w, law, &m, p->a, p->b, 0, p->sqrt_m_eff, h, p->cap, &out[i]);
    return 0;
}

SD_SIMD_CLONES
static void sc_batch_law(const sd_law *law, double dt, struct sc_lanes *restrict q, int m)
{
    const lane_law L = lane_law_make(law, dt);
    for (int j = 0; j < m; j++) {
        const double rax = q->rax[j], ray = q->ray[j], raz = q->raz[j], rbx = q->rbx[j], rby = q->rby[j],
                     rbz = q->rbz[j];
        /* v_a + w_a x r_a - (v_b + w_b x r_b) */
        const double vax = q->vax[j] + (q->way[j] * raz - q->waz[j] * ray),
                     vay = q->vay[j] + (q->waz[j] * rax - q->wax[j] * raz),
                     vaz = q->vaz[j] + (q->wax[j] * ray - q->way[j] * rax);
        const double vbx = q->vbx[j] + (q->wby[j] * rbz - q->wbz[j] * rby),
                     vby = q->vby[j] + (q->wbz[j] * rbx - q->wbx[j] * rbz),
                     vbz = q->vbz[j] + (q->wbx[j] * rby - q->wby[j] * rbx);
        double sx = q->sx[j], sy = q->sy[j], sz = q->sz[j], fx, fy, fz;
        q->redo[j] = law_lane(&L, q->nx[j], q->ny[j], q->nz[j], q->ov[j], vax - vbx, vay - vby, vaz - vbz, q->sqm[j],
                              &sx, &sy, &sz, &fx, &fy, &fz);
        q->sx[j] = sx;
        q->sy[j] = sy;
        q->sz[j] = sz;
        /* apply_manifold's sums, from zero */
        q->fx[j] = 0.0 + fx;
        q->fy[j] = 0.0 + fy;
        q->fz[j] = 0.0 + fz;
        q->tax[j] = 0.0 + (ray * fz - raz * fy);
        q->tay[j] = 0.0 + (raz * fx - rax * fz);
        q->taz[j] = 0.0 + (rax * fy - ray * fx);
        q->tbx[j] = 0.0 - (rby * fz - rbz * fy);
        q->tby[j] = 0.0 - (rbz * fx - rbx * fz);
        q->tbz[j] = 0.0 - (rbx * fy - rby * fx);
    }
}

/* The lanes' results into their pairs' slots and out[]; a lane the law sends back (its spring
 * tilted past the small-angle rule) through apply_manifold, from the slot not yet written. */
static void sc_flush(const sd_world *w, const sd_law *law, struct sc_lanes *q, int m, const int32_t *ks,
                     const soa_view *v, sd_pair_out *out, int *used)
{
    sc_batch_law(law, w->def.dt, q, m);
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
            used[i] = apply_manifold(w, law, &m1, p->a, p->b, 0, p->sqrt_m_eff, h, p->cap, &out[i]);
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

#ifdef SD_FILTER512
/* The vec3 rows i[0..3] of the array p (3 doubles each) as lanes x, y, z (r[0..2]). */
__attribute__((target("avx2"))) static inline void rows4(const double *p, const int i[4], __m256d r[4])
{
    sd_transpose4(SD_XYZ_LOAD(p, i[0]), SD_XYZ_LOAD(p, i[1]), SD_XYZ_LOAD(p, i[2]), SD_XYZ_LOAD(p, i[3]), r);
}

/* Rows i[0..3] of p into the lane arrays x, y, z at j. */
__attribute__((target("avx2"))) static inline void rows4_store(const double *p, const int i[4], double *x, double *y,
                                                               double *z, int j)
{
    __m256d r[4];
    rows4(p, i, r);
    _mm256_storeu_pd(x + j, r[0]), _mm256_storeu_pd(y + j, r[1]), _mm256_storeu_pd(z + j, r[2]);
}

/* Four sphere-log pairs in lanes: the spheres' centres (c) and radii (rs), the logs' centres
 * (b), axes (a), radii (rc) and half-lengths (hl), d = c - b and t = d.a, and w = d + (-t) a with
 * rho2 = |w|^2 (sd_sphere_cyl_apart's and sd_cyl_signed_dist's first operations, in their
 * order). */
typedef struct {
    __m256d cx, cy, cz, bx, by, bz, ax, ay, az, rs, rc, hl, t, wx, wy, wz, rho2;
} sc_quad;

__attribute__((target("avx2"))) static inline void sc_quad_load(const sd_bodies *b, const int sa[4], const int lc[4],
                                                               sc_quad *s)
{
    const double *pos = &b->pos[0].x, *axis = &b->axis[0].x, *rad = b->radius, *hlen = b->hl;
    __m256d r[4];
    rows4(pos, sa, r);
    s->cx = r[0], s->cy = r[1], s->cz = r[2];
    rows4(pos, lc, r);
    s->bx = r[0], s->by = r[1], s->bz = r[2];
    rows4(axis, lc, r);
    s->ax = r[0], s->ay = r[1], s->az = r[2];
    s->rs = _mm256_setr_pd(rad[sa[0]], rad[sa[1]], rad[sa[2]], rad[sa[3]]);
    s->rc = _mm256_setr_pd(rad[lc[0]], rad[lc[1]], rad[lc[2]], rad[lc[3]]);
    s->hl = _mm256_setr_pd(hlen[lc[0]], hlen[lc[1]], hlen[lc[2]], hlen[lc[3]]);
    const __m256d dx = _mm256_sub_pd(s->cx, s->bx), dy = _mm256_sub_pd(s->cy, s->by), dz = _mm256_sub_pd(s->cz, s->bz);
    s->t = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, s->ax), _mm256_mul_pd(dy, s->ay)), _mm256_mul_pd(dz, s->az));
    const __m256d mt = _mm256_xor_pd(s->t, _mm256_set1_pd(-0.0));
    s->wx = _mm256_add_pd(dx, _mm256_mul_pd(mt, s->ax));
    s->wy = _mm256_add_pd(dy, _mm256_mul_pd(mt, s->ay));
    s->wz = _mm256_add_pd(dz, _mm256_mul_pd(mt, s->az));
    s->rho2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(s->wx, s->wx), _mm256_mul_pd(s->wy, s->wy)),
                            _mm256_mul_pd(s->wz, s->wz));
}

/* Where four sphere centres lie against their logs (sd_cyl_signed_dist's operations, in their
 * order): axd = |t| - hl (> 0 beyond the end plane), rho = |w|, rd = rho - r (> 0 outside the
 * side surface); the masks side, end face and rim (beyond both), known = any of the three (not
 * known: a centre inside the log, left to the scalar path), and sd the distance to the nearest
 * feature where known (0 elsewhere; the rim's sqrt only where a lane is there). */
typedef struct {
    __m256d axd, rho, rd, side, end, rim, known, sd;
} sc_case;

__attribute__((target("avx2"))) static inline void sc_case_of(const sc_quad *u, sc_case *k)
{
    const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0);
    k->axd = _mm256_sub_pd(_mm256_andnot_pd(sign, u->t), u->hl);
    k->rho = _mm256_sqrt_pd(u->rho2);
    k->rd = _mm256_sub_pd(k->rho, u->rc);
    const __m256d ax_in = _mm256_cmp_pd(k->axd, zero, _CMP_LE_OQ), ax_out = _mm256_cmp_pd(k->axd, zero, _CMP_GT_OQ);
    const __m256d rd_in = _mm256_cmp_pd(k->rd, zero, _CMP_LE_OQ), rd_out = _mm256_cmp_pd(k->rd, zero, _CMP_GT_OQ);
    k->side = _mm256_and_pd(ax_in, rd_out);
    k->end = _mm256_and_pd(rd_in, ax_out);
    k->rim = _mm256_and_pd(ax_out, rd_out);
    k->known = _mm256_or_pd(_mm256_or_pd(k->side, k->end), k->rim);
    __m256d sd = zero;
    if (_mm256_movemask_pd(k->rim))
        sd = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(k->rd, k->rd), _mm256_mul_pd(k->axd, k->axd)));
    k->sd = _mm256_blendv_pd(_mm256_blendv_pd(sd, k->axd, k->end), k->rd, k->side);
}

/* The bodies of the sphere-log pairs sg[0 .. nl) (chunk entries, 1 <= nl <= 4) into four
 * lanes, the last pair repeated past nl: from the chunk's view (the pair store's lines are not
 * read). */
static inline void sc_group(const soa_view *v, const int *sg, int nl, int sa[4], int lc[4])
{
    for (int l = 0; l < 4; l++) {
        const int i = sg[l < nl ? l : nl - 1];
        sa[l] = v->a[i], lc[l] = v->b[i];
    }
}

/* Step 2 of bb_chunk for the sphere-log pairs sg[0 .. n) (chunk entries, one spring slot each,
 * whose apart test the touch filter may have left to this pass) in AVX2, 4 at a time (the last
 * 1-3 in a group padded with the last of them): first the apart test, then
 * sd_geom_sphere_cyl's contact on the log's side, an end face or an end rim, and sc_lane_fill,
 * with their operations in their order (same bits), lane by lane into q from msc on. A pair
 * whose centre is on the axis or inside the log, or that does not touch after all (near a
 * rim), goes through pair_general as before. Returns the lanes filled. The scalar path spent
 * ~12 % of the settled packing's step here (docs/performance-log.md §P18). */
__attribute__((target("avx2"))) static int sc_geom256(const sd_world *w, const sd_law *law, const int32_t *ks,
                                                      const soa_view *v, const int *sg, int n, struct sc_lanes *q,
                                                      int msc, sd_pair_out *out, int *used)
{
    const sd_bodies *b = &w->b;
    const double *vel = &b->vel[0].x, *om = &b->omega[0].x;
    const sd_pair *pairs = w->bb.p;
    const sd_hist *hist = w->bb.hist;
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), mone = _mm256_set1_pd(-1.0),
                  sign = _mm256_set1_pd(-0.0), tiny = _mm256_set1_pd(1e-280), mhalf = _mm256_set1_pd(-0.5);
    /* 1. the touch filter's apart test (sd_sphere_cyl_apart, its operations), which
     * ss_filter256 leaves to this pass, then sd_geom_sphere_cyl's own (sd >= r past the side,
     * an end face or a rim, as 2 computes it): either way the pair gets what filter_log_pair
     * gives it (no contact, its slot emptied); the others, in order, into sg2. (A pair the
     * scalar filter already found not apart is found so again.) A pass of its own, though 2
     * loads the same rows again (from L1): so that 2 meets touching pairs only and takes its
     * groups four lanes at a time. */
    int sg2[SS_CHUNK], n2 = 0;
    {
        for (int g = 0; g < n; g += 4) {
            /* the last group padded with its last pair (its extra lanes dropped) */
            const int nl = n - g < 4 ? n - g : 4;
            int sa[4], lc[4];
            sc_group(v, sg + g, nl, sa, lc);
            sc_quad u;
            sc_quad_load(b, sa, lc, &u);
            const __m256d rr = _mm256_add_pd(u.rc, u.rs);
            sc_case k;
            sc_case_of(&u, &k);
            const __m256d apart = _mm256_or_pd(_mm256_cmp_pd(k.axd, u.rs, _CMP_GE_OQ),
                                               _mm256_cmp_pd(u.rho2, _mm256_mul_pd(rr, rr), _CMP_GE_OQ));
            const __m256d miss = _mm256_and_pd(_mm256_and_pd(k.known, _mm256_cmp_pd(k.sd, u.rs, _CMP_GE_OQ)),
                                               _mm256_cmp_pd(u.rho2, tiny, _CMP_GT_OQ));
            const int drop = _mm256_movemask_pd(_mm256_or_pd(apart, miss));
            for (int l = 0; l < nl; l++) {
                const int i = sg[g + l];
                if (drop >> l & 1) {
                    used[i] = 0;
                    w->bb.hist[v->off[i]].feature = -1; /* (one slot) */
                } else
                    sg2[n2++] = i;
            }
        }
    }
    sg = sg2;
    n = n2;
    /* 2. the contacts */
    for (int g = 0; g < n; g += 4) {
        const int nl = n - g < 4 ? n - g : 4; /* (the last group padded, as in 1) */
        int sa[4], lc[4];
        sc_group(v, sg + g, nl, sa, lc);
        sc_quad u;
        sc_quad_load(b, sa, lc, &u);
        const __m256d cx = u.cx, cy = u.cy, cz = u.cz, bx = u.bx, by = u.by, bz = u.bz, ax = u.ax, ay = u.ay,
                      az = u.az, rs = u.rs, t = u.t, wx = u.wx, wy = u.wy, wz = u.wz, rho2 = u.rho2;
        sc_case k;
        sc_case_of(&u, &k);
        const __m256d e = _mm256_blendv_pd(mone, one, _mm256_cmp_pd(t, zero, _CMP_GE_OQ));
        const __m256d axd = k.axd, rd = k.rd, side = k.side, end = k.end, rim = k.rim;
        const __m256d inv = _mm256_div_pd(one, k.rho);
        const __m256d radx = _mm256_mul_pd(wx, inv), rady = _mm256_mul_pd(wy, inv), radz = _mm256_mul_pd(wz, inv);
        /* beyond the rim: radial (rd / dist) + a (e ax / dist); only where a lane is there (a
         * sphere on a log's side or end face: nearly all) */
        __m256d nx = zero, ny = zero, nz = zero;
        if (_mm256_movemask_pd(rim)) {
            const __m256d dist = k.sd; /* (the rim's distance in its lanes) */
            const __m256d k1 = _mm256_div_pd(rd, dist), k2 = _mm256_div_pd(_mm256_mul_pd(e, axd), dist);
            nx = _mm256_add_pd(_mm256_mul_pd(radx, k1), _mm256_mul_pd(ax, k2));
            ny = _mm256_add_pd(_mm256_mul_pd(rady, k1), _mm256_mul_pd(ay, k2));
            nz = _mm256_add_pd(_mm256_mul_pd(radz, k1), _mm256_mul_pd(az, k2));
        }
        const __m256d eax = _mm256_mul_pd(ax, e), eay = _mm256_mul_pd(ay, e), eaz = _mm256_mul_pd(az, e);
        nx = _mm256_blendv_pd(_mm256_blendv_pd(nx, eax, end), radx, side);
        ny = _mm256_blendv_pd(_mm256_blendv_pd(ny, eay, end), rady, side);
        nz = _mm256_blendv_pd(_mm256_blendv_pd(nz, eaz, end), radz, side);
        const __m256d sd = k.sd;
        /* the lanes done here: a contact (sd < r) on the side, an end face or a rim, off the
         * axis; the padded lanes of the last group repeat its last pair, so a group of whole
         * lanes is ok == 15 */
        const int ok = _mm256_movemask_pd(_mm256_and_pd(_mm256_and_pd(k.known, _mm256_cmp_pd(rho2, tiny, _CMP_GT_OQ)),
                                                        _mm256_cmp_pd(sd, rs, _CMP_LT_OQ)));
        /* sd_geom_sphere_cyl: overlap, the surface point c + (-sd) n, the point + (-0.5 ov) n */
        const __m256d ov = _mm256_sub_pd(rs, sd), msd = _mm256_xor_pd(sd, sign), mh = _mm256_mul_pd(mhalf, ov);
        const __m256d ptx = _mm256_add_pd(_mm256_add_pd(cx, _mm256_mul_pd(msd, nx)), _mm256_mul_pd(mh, nx)),
                      pty = _mm256_add_pd(_mm256_add_pd(cy, _mm256_mul_pd(msd, ny)), _mm256_mul_pd(mh, ny)),
                      ptz = _mm256_add_pd(_mm256_add_pd(cz, _mm256_mul_pd(msd, nz)), _mm256_mul_pd(mh, nz));
        const int sidem = _mm256_movemask_pd(side), endm = _mm256_movemask_pd(end),
                  negm = _mm256_movemask_pd(_mm256_cmp_pd(e, zero, _CMP_LT_OQ));
        if (ok == 15) { /* (nearly always) four lanes at once, nl of them kept */
            const int j = msc;
            _mm256_storeu_pd(q->nx + j, nx), _mm256_storeu_pd(q->ny + j, ny), _mm256_storeu_pd(q->nz + j, nz);
            _mm256_storeu_pd(q->ov + j, ov);
            _mm256_storeu_pd(q->px + j, ptx), _mm256_storeu_pd(q->py + j, pty), _mm256_storeu_pd(q->pz + j, ptz);
            _mm256_storeu_pd(q->rax + j, _mm256_sub_pd(ptx, cx)), _mm256_storeu_pd(q->ray + j, _mm256_sub_pd(pty, cy));
            _mm256_storeu_pd(q->raz + j, _mm256_sub_pd(ptz, cz));
            _mm256_storeu_pd(q->rbx + j, _mm256_sub_pd(ptx, bx)), _mm256_storeu_pd(q->rby + j, _mm256_sub_pd(pty, by));
            _mm256_storeu_pd(q->rbz + j, _mm256_sub_pd(ptz, bz));
            rows4_store(vel, sa, q->vax, q->vay, q->vaz, j);
            rows4_store(om, sa, q->wax, q->way, q->waz, j);
            rows4_store(vel, lc, q->vbx, q->vby, q->vbz, j);
            rows4_store(om, lc, q->wbx, q->wby, q->wbz, j);
            for (int l = 0; l < nl; l++) {
                const int f = sidem >> l & 1 ? 0 : (negm >> l & 1 ? 1 : 2) + (endm >> l & 1 ? 0 : 2);
                const sd_hist *h = &hist[v->off[sg[g + l]]];
                const int same = h->feature == f;
                q->sqm[j + l] = v->sqm[sg[g + l]];
                q->sx[j + l] = same ? h->shear.x : 0.0, q->sy[j + l] = same ? h->shear.y : 0.0;
                q->sz[j + l] = same ? h->shear.z : 0.0;
                q->feature[j + l] = f;
                q->i[j + l] = sg[g + l];
            }
            msc += nl;
            q->n_geom += nl;
            continue;
        }
        double L[13][4];
        _mm256_storeu_pd(L[0], nx), _mm256_storeu_pd(L[1], ny), _mm256_storeu_pd(L[2], nz);
        _mm256_storeu_pd(L[3], ov);
        _mm256_storeu_pd(L[4], ptx), _mm256_storeu_pd(L[5], pty), _mm256_storeu_pd(L[6], ptz);
        _mm256_storeu_pd(L[7], _mm256_sub_pd(ptx, cx)), _mm256_storeu_pd(L[8], _mm256_sub_pd(pty, cy));
        _mm256_storeu_pd(L[9], _mm256_sub_pd(ptz, cz));
        _mm256_storeu_pd(L[10], _mm256_sub_pd(ptx, bx)), _mm256_storeu_pd(L[11], _mm256_sub_pd(pty, by));
        _mm256_storeu_pd(L[12], _mm256_sub_pd(ptz, bz));
        for (int l = 0; l < nl; l++) {
            const int i = sg[g + l];
            if (!(ok >> l & 1)) {
                msc += pair_general(w, law, &pairs[ks[i]], i, q, msc, out, used);
                continue;
            }
            /* sc_lane_fill */
            const int j = msc++;
            q->n_geom++;
            const int a = sa[l], c = lc[l];
            /* feature: 0 side, 1 / 2 end face at -hl / +hl, 3 / 4 rim there */
            const int f = sidem >> l & 1 ? 0 : (negm >> l & 1 ? 1 : 2) + (endm >> l & 1 ? 0 : 2);
            q->nx[j] = L[0][l], q->ny[j] = L[1][l], q->nz[j] = L[2][l], q->ov[j] = L[3][l];
            q->px[j] = L[4][l], q->py[j] = L[5][l], q->pz[j] = L[6][l];
            q->rax[j] = L[7][l], q->ray[j] = L[8][l], q->raz[j] = L[9][l];
            q->rbx[j] = L[10][l], q->rby[j] = L[11][l], q->rbz[j] = L[12][l];
            q->vax[j] = vel[3 * a], q->vay[j] = vel[3 * a + 1], q->vaz[j] = vel[3 * a + 2];
            q->wax[j] = om[3 * a], q->way[j] = om[3 * a + 1], q->waz[j] = om[3 * a + 2];
            q->vbx[j] = vel[3 * c], q->vby[j] = vel[3 * c + 1], q->vbz[j] = vel[3 * c + 2];
            q->wbx[j] = om[3 * c], q->wby[j] = om[3 * c + 1], q->wbz[j] = om[3 * c + 2];
            q->sqm[j] = v->sqm[i];
            const sd_hist *h = &hist[v->off[i]];
            const int same = h->feature == f;
            q->sx[j] = same ? h->shear.x : 0.0, q->sy[j] = same ? h->shear.y : 0.0, q->sz[j] = same ? h->shear.z : 0.0;
            q->feature[j] = f;
            q->i[j] = i;
        }
    }
    return msc;
}
#endif

/* Step 2 of bb_chunk for a log's pair (chunk entry i) not taken by the sphere-log lanes:
 * filter_log_pair's apart test, where the touch filter left it (the AVX2 filter lists every
 * entry that is not a sphere pair as it is; the other filters' entries have passed it, and
 * pass it again), then pair_general. Returns the lanes it filled. */
static int other_pair(const sd_world *w, const sd_law *law, const sd_pair *p, int i, struct sc_lanes *q, int j,
                      sd_pair_out *out, int *used)
{
    if (log_pair_apart(&w->b, p)) {
        used[i] = 0;
        for (int s = 0; s < p->cap; s++)
            w->bb.hist[p->off + s].feature = -1;
        return 0;
    }
    return pair_general(w, law, p, i, q, j, out, used);
}

/* The pairs ks[0 .. n) (n <= SS_CHUNK): forces into out[i], contact points into used[i]. Each
 * pair's result depends on that pair alone, so any split into chunks gives the same bits.
 * With acc, the chunk also adds each pair in contact onto its two bodies, in chunk order (the
 * sphere pairs straight from the law's lanes, their out[] not written): the caller passes it
 * where nothing of its own comes between these pairs. An owner's cross entry (ks[i] < 0, acc
 * given: pass 2 of bb_owned_pass) is not computed: its used[i] is 0, and step 5 adds the
 * owner's side of pass 1's result (q->xout, q->xact) in its place. */
static void bb_chunk(const sd_world *w, const sd_law *law, const int32_t *ks, const soa_view *v, int n,
                     sd_pair_out *out, int *used, ss_batch *q, sd_bodies *acc)
{
    const sd_pair *restrict pairs = w->bb.p;
    sd_hist *restrict hist = v->sh;
    int gen[SS_CHUNK];
    int m = 0, ng = 0;
    q->sh = v->sh;
    q->lsq = v->lsq;
    /* 1. which pairs touch (ss_filter_range) */
    {
        /* (8 pairs at a time in AVX-512, 4 in AVX2, where the CPU has it; the rest, or all,
         * in the scalar loop) */
        int i = 0;
#ifdef SD_FILTER512
        if (w->simd == SD_SIMD_AVX512)
            i = ss_filter512(w, ks, v, 0, n, used, q, &m, gen, &ng);
        else if (w->simd == SD_SIMD_AVX2)
            i = ss_filter256(w, v, 0, n, used, q, &m, gen, &ng);
#endif
        ss_filter_range(w, ks, v, i, n, used, q, &m, gen, &ng);
    }
    /* 2. the other shapes, through the manifold */
    {
        int msc = 0;
#ifdef SD_FILTER512
        if (w->simd >= SD_SIMD_AVX2 && w->sw[SD_SW_SC_LANES] && w->sw[SD_SW_SC_GEOM]) {
            /* the sphere-log pairs in lanes (sc_geom256), the others first, one by one: each
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
            msc = sc_geom256(w, law, ks, v, sg, nsg, &q->sc, msc, out, used);
        } else
#endif
            for (int g = 0; g < ng; g++) {
                const int i = gen[g];
                if (ks[i] >= 0) msc += other_pair(w, law, &pairs[ks[i]], i, &q->sc, msc, out, used);
            }
        if (msc > 0) sc_flush(w, law, &q->sc, msc, ks, v, out, used);
    }
    /* 3. the rest of what the law needs of the touching spheres */
    {
        int j = 0;
#ifdef SD_FILTER512
        if (w->simd == SD_SIMD_AVX512) {
            ss_gather512(w, q, m);
            j = m;
        } else if (w->simd == SD_SIMD_AVX2)
            j = ss_gather256(w, q, m);
#endif
        ss_gather_range(w, q, j, m);
    }
    /* 4. the law, vectorized */
    {
        ss_law_normal(q, m);
        int j = 0;
#ifdef SD_FILTER512
        if (w->simd == SD_SIMD_AVX2 && w->sw[SD_SW_SS_LAW256]) j = ss_law_spring256(law, w->def.dt, q, m);
#endif
        ss_law_spring(law, w->def.dt, q, j, m);
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
#ifdef SD_FILTER512
            /* four lanes at once where no other shape's pair comes between them and none is
             * to be redone (nearly always) */
            if (w->simd >= SD_SIMD_AVX2 && j + 4 <= m && (g == ng || gen[g] > q->sel[j + 3]) &&
                ss_sums256(q, j, acc)) {
                j += 3;
                continue;
            }
#endif
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

#define BT_LOCAL 16 /* wall candidates of one body whose manifolds bt_range keeps on the stack */

/* Sphere–wall contacts on a face, in batches like the sphere pairs: a sphere whose wall
 * candidates give one face contact and nothing near an edge (nearly every sphere on a floor or
 * a side wall) skips the manifold and the mesh dedup, and its contact goes through the law in
 * lanes. The arithmetic is apply_manifold's for a one-point manifold, operation for operation
 * (same bits). */
#define BT_CHUNK 64
typedef struct {
    double nx[BT_CHUNK], ny[BT_CHUNK], nz[BT_CHUNK], ov[BT_CHUNK]; /* normal on the sphere, overlap */
    double rx[BT_CHUNK], ry[BT_CHUNK], rz[BT_CHUNK];               /* contact point - centre */
    double vx[BT_CHUNK], vy[BT_CHUNK], vz[BT_CHUNK];               /* the sphere's velocity */
    double wx[BT_CHUNK], wy[BT_CHUNK], wz[BT_CHUNK];               /* its spin */
    double sqm[BT_CHUNK];
    double sx[BT_CHUNK], sy[BT_CHUNK], sz[BT_CHUNK]; /* spring in, then out */
    double fx[BT_CHUNK], fy[BT_CHUNK], fz[BT_CHUNK]; /* force on the sphere */
    double tx[BT_CHUNK], ty[BT_CHUNK], tz[BT_CHUNK]; /* torque on it */
    double redo[BT_CHUNK];
    int32_t k[BT_CHUNK]; /* the pair */
} bt_batch;

SD_SIMD_CLONES
static void bt_batch_law(const sd_law *law, double dt, bt_batch *restrict q, int m)
{
    const lane_law L = lane_law_make(law, dt);
    for (int j = 0; j < m; j++) {
        const double nx = q->nx[j], ny = q->ny[j], nz = q->nz[j], rx = q->rx[j], ry = q->ry[j], rz = q->rz[j];
        /* v + w x r (the wall is still: v - 0 is v) */
        const double vx = q->vx[j] + (q->wy[j] * rz - q->wz[j] * ry), vy = q->vy[j] + (q->wz[j] * rx - q->wx[j] * rz),
                     vz = q->vz[j] + (q->wx[j] * ry - q->wy[j] * rx);
        double sx = q->sx[j], sy = q->sy[j], sz = q->sz[j], fx, fy, fz;
        q->redo[j] = law_lane(&L, nx, ny, nz, q->ov[j], vx, vy, vz, q->sqm[j], &sx, &sy, &sz, &fx, &fy, &fz);
        q->sx[j] = sx;
        q->sy[j] = sy;
        q->sz[j] = sz;
        /* apply_manifold's sums, from zero */
        q->fx[j] = 0.0 + fx;
        q->fy[j] = 0.0 + fy;
        q->fz[j] = 0.0 + fz;
        q->tx[j] = 0.0 + (ry * fz - rz * fy);
        q->ty[j] = 0.0 + (rz * fx - rx * fz);
        q->tz[j] = 0.0 + (rx * fy - ry * fx);
    }
}

/* per-thread scratch of the body-body pass */
typedef struct {
    ss_batch q;
    sd_pair_out out[SS_CHUNK];
    int used[SS_CHUNK];
    bt_batch wq;
    sd_bed_split bed; /* the serial pass's (the owners keep theirs in sd_owned) */
} bb_scratch;

/* The batch's lanes through the law, then each into its pair's slot and onto its sphere (the
 * sphere's only contact with the walls: nothing else is summed onto it in bt_range). */
static void bt_flush(sd_world *w, const sd_law *law, bt_batch *q, int m)
{
    sd_bodies *b = &w->b;
    bt_batch_law(law, w->def.dt, q, m);
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
            sd_contact_law(law, q->sqm[j], n, q->ov[j], v, w->def.dt, &shear, &f);
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
    for (int k = from; k < to; k++) {
        if (k == hit) continue;
        const sd_pair *p = &w->bt.p[k];
        for (int s = 0; s < p->cap; s++)
            w->bt.hist[p->off + s].feature = -1;
        w->bt.active[k] = 0;
    }
    if (hit < 0) return 1;
    const sd_pair *p = &w->bt.p[hit];
    const sd_hist *h = &w->bt.hist[p->off];
    sd_vec3 n, pt;
    double ov;
    sd_sphere_tri_face(c, r, &wl->tri[p->b], s_hit, &n, &ov, &pt);
    /* the spring of the same feature (a face: the first slot holding it) or a new one */
    sd_vec3 shear = v3(0, 0, 0);
    for (int s = 0; s < p->cap && s < SD_MANIFOLD_MAX; s++)
        if (h[s].feature == SD_TRI_FACE) {
            shear = h[s].shear;
            break;
        }
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
 * the same rows through pf_front's line loops lost the front prefetch's whole gain at 1e5,
 * docs/performance-log.md §P15) */
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
static long bt_range(sd_world *w, const sd_law *law, const int32_t *list, int nl, bt_batch *q)
{
    sd_bodies *b = &w->b;
    long count = 0;
    int m = 0;
    /* the bodies near a wall (wall_near_range, made with the near pairs, which the callers have
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
            multi += narrow_bt(b, &w->w, &w->bt.p[k], &man[k - from]) > 0;
        if (multi > 1) sd_contact_mesh_dedup(&w->w, &w->bt.p[from], man, 0, to - from);
        /* each pair into its slot (the wall loads, sd_contact_gather) and onto its body after
         * the body-body sum, in pair order */
        sd_vec3 f = b->force[i], t = b->torque[i];
        for (int k = from; k < to; k++) {
            const sd_pair *p = &w->bt.p[k];
            if (man[k - from].n == 0) {
                /* no contact (most wall candidates): what apply_manifold leaves, empty springs;
                 * the slot's force is not read while the pair is inactive */
                for (int s = 0; s < p->cap; s++)
                    w->bt.hist[p->off + s].feature = -1;
                w->bt.active[k] = 0;
                continue;
            }
            /* the result summed from registers: read back from the slot, each 16-byte load
             * waited for the two 8-byte stores it spans (no store forwarding) */
            sd_pair_out o;
            int used =
                apply_manifold(w, law, &man[k - from], p->a, -1, 1, p->sqrt_m_eff, &w->bt.hist[p->off], p->cap, &o);
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

/* Whether candidate p can touch before the bodies drift by half the skin (near_update): its
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

#ifdef SD_FILTER512
/* near_test of candidates k0 .. while 4 remain, the sphere pairs' in AVX2 lanes (the centres
 * as rows, near_test's operations; a log's pair through near_test); returns where it stopped. */
__attribute__((target("avx2"))) static int near_test256(const sd_world *w, double skin, int k0, int k1,
                                                        uint8_t *restrict keep, int nf)
{
    const double *pos = &w->b.pos[0].x, *rad = w->b.radius;
    const sd_pair *pairs = w->bb.p;
    const __m256d skv = _mm256_set1_pd(skin), hsv = _mm256_set1_pd(0.5 * skin);
    const __m128i nf1 = _mm_set1_epi32(nf - 1);
    int k = k0;
    for (; k + 4 <= k1; k += 4) {
        const sd_pair *p = pairs + k;
        const int32_t a[4] = {p[0].a, p[1].a, p[2].a, p[3].a}, b[4] = {p[0].b, p[1].b, p[2].b, p[3].b};
        __m256d dx, dy, dz;
        diff_lanes(pos, a, b, &dx, &dy, &dz);
        /* half the skin where a body is of the bed (near_test), chosen by lane masks */
        const __m128i bed = _mm_or_si128(_mm_cmpgt_epi32(_mm_loadu_si128((const __m128i *)a), nf1),
                                         _mm_cmpgt_epi32(_mm_loadu_si128((const __m128i *)b), nf1));
        const __m256d sk = _mm256_blendv_pd(skv, hsv, _mm256_castsi256_pd(_mm256_cvtepi32_epi64(bed)));
        const __m256d reach = _mm256_add_pd(_mm256_add_pd(_mm256_setr_pd(rad[a[0]], rad[a[1]], rad[a[2]], rad[a[3]]),
                                                          _mm256_setr_pd(rad[b[0]], rad[b[1]], rad[b[2]], rad[b[3]])),
                                            sk);
        const __m256d d2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
        const int in = _mm256_movemask_pd(_mm256_cmp_pd(d2, _mm256_mul_pd(reach, reach), _CMP_LE_OQ));
        for (int l = 0; l < 4; l++)
            keep[k + l - k0] = (uint8_t)(p[l].kind == SD_PAIR_SS ? in >> l & 1 : near_test(w, skin, &p[l], nf));
    }
    return k;
}
#endif

/* near_test of candidates k0 .. k1-1 into keep[k - k0] (1 or 0; returned), then what it means for each:
 * a pair left out has its springs cleared, as the pass would clear them. Only a pair that was
 * near when the near pairs were last made (near_mark), or any pair after a rebuild (fresh: the
 * carried springs), can hold a spring, since only the pass sets one and it sees near pairs
 * only: the other candidates' spring slots are not touched, which spares each remaking a
 * cache line per candidate. The answers first, alone, then their consequences with one
 * seldom-taken branch: the loop that did both as it went, branching on a coin toss, took 18 ns
 * a candidate (docs/performance-log.md §P13). */
#define NEAR_BLOCK 512 /* candidates whose answers are made at a time, then kept (owned_update, near_filter) */
static const uint8_t *near_keep_range(sd_world *w, double skin, int k0, int k1, int fresh, int nf)
{
    const sd_pair *restrict pairs = w->bb.p;
    uint8_t *restrict keep = w->near_mark + w->bb.n + 1 + k0; /* (near_mark's second half) */
    int k = k0;
#ifdef SD_FILTER512
    if (w->simd >= SD_SIMD_AVX2) k = near_test256(w, skin, k0, k1, keep, nf);
#endif
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
static int near_mark_ready(sd_world *w)
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
static int near_block(sd_world *w, double skin, int kb, int ke, int fresh, int nf, int32_t *near)
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

/* The candidates worth testing (near_update), into out in ascending order, with their
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
        const int nn = near_block(w, skin, kb, ke, fresh, nf, near);
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
static int wall_near_range(sd_world *w, double skin, int i0, int i1, int32_t *list, long *skip)
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
 * one stream, read and written in step with the records (at 1e5 spheres the step 0.87-0.89x,
 * docs/performance-log.md §P39). They go out as a list is made (near_filter, owned_update:
 * the slot's line is read there for the flag), or at a pass's start when they were put back
 * since (springs_to), and back (sd_contact_springs_home) before the
 * list is remade or anything reads bb.hist. Below: entries k0 .. k1 of a list (candidate
 * indices, an owner's cross entry negative) whose records s are of a sphere pair (ck kind 0;
 * the others keep their slots in bb.hist). */
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

void sd_contact_springs_home(sd_world *w)
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

/* The sphere pairs' slots of the list whose springs are out as `out`, else bb.hist. */
static inline sd_hist *springs_of(const sd_world *w, int out, sd_hist *h)
{
    return w->springs_out == out ? h : w->bb.hist;
}

/* The springs of the list the pass is about to use out of their slots, from wherever they
 * are (after a hash or a checkpoint, or the other pass's list), in the slots' form the switch
 * asks for (sd_slot_sqm_set): `out` 1 the serial list (near list current), 2 the owners'
 * (owned_update has made them current). Only put back when the switch is off. */
static sd_status springs_to(sd_world *w, int out)
{
    if (w->springs_out == out && w->sw[SD_SW_SPRINGS_LIST] && w->springs_lsq == w->sw[SD_SW_SLOT_SQM]) return SD_OK;
    sd_contact_springs_home(w);
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
 * half the near skin (near_update). */
static int near_still_good(const sd_world *w)
{
    return w->near_stamp == w->timers.rebuilds && !w->rebuild_every_step && 2.0 * w->near_drift < 0.999 * w->near_skin;
}

/* The near pairs have just been made (by either pass) with this skin. */
static void near_made(sd_world *w, double skin)
{
    w->near_version++;
    w->near_stamp = w->timers.rebuilds;
    w->near_drift = 0.0;
    w->near_skin = skin;
}

static int bb_owners(const sd_world *w);

static sd_owned *owned_get(sd_world *w)
{
    if (!w->owned) w->owned = calloc(1, sizeof *w->owned);
    return w->owned;
}

/* The near list (w->near): the body-body pairs worth testing each step. A pair whose gap
 * exceeds the near skin s (w->near_skin) cannot touch before the moving bodies have drifted
 * by s/2 between them (near_drift, summed from each step's largest move of a surface), so it
 * is left out until then: its force is exactly zero, its spring is cleared here as the pass
 * would clear it, and every body sums the same pairs in the same order (same bits). In a dense
 * bed the margin's candidates are twice the contacts; most of the rest are far beyond s. */
static sd_status near_update(sd_world *w)
{
    const int nbb = w->bb.n;
    /* (near_soa_version: not remade since by the owners' path, which keeps its own lists) */
    if (near_still_good(w) && w->near_nbb == nbb && w->near && w->near_soa_version == w->near_version + 1) return SD_OK;
    sd_contact_springs_home(w); /* (from the list about to go) */
    const double skin = SD_NEAR_SKIN * w->def.margin;
    if (sd_grow((void **)&w->near, &w->near_cap, nbb + 1, sizeof(int32_t))) return SD_ERR_NOMEM;
    const int fresh = near_mark_ready(w);
    if (fresh < 0 || pair_soa_reserve(&w->near_soa, nbb + 1) ||
        sd_grow((void **)&w->wall_list, &w->wall_list_cap, w->b.n + 1, sizeof(int32_t)))
        return SD_ERR_NOMEM;
    /* the springs out as the list is made (springs_out 1), when the switch is on */
    if (w->sw[SD_SW_SPRINGS_LIST] && sd_grow((void **)&w->near_hist, &w->near_hist_cap, nbb + 1, sizeof(sd_hist)))
        return SD_ERR_NOMEM;
    w->springs_lsq = w->sw[SD_SW_SLOT_SQM];
    w->near_n = near_filter(w, skin, fresh, w->near, &w->near_soa, w->sw[SD_SW_SPRINGS_LIST] ? w->near_hist : NULL);
    w->springs_out = w->sw[SD_SW_SPRINGS_LIST] ? 1 : 0;
    w->wall_n = wall_near_range(w, skin, 0, w->b.n, w->wall_list, &w->wall_skip);
    w->near_nbb = nbb;
    near_made(w, skin);
    w->near_soa_version = w->near_version + 1;
    return SD_OK;
}

/* The bodies' front. The pass takes the pairs in lower-body order, so it reaches each body for
 * the first time as the upper body of some pair, a little ahead of the bodies it is at: those
 * rows (centre, radius, velocity, spin, force, torque) are the lines the hardware prefetchers
 * miss, six arrays read at a ragged edge. When the step's data do not stay in the last-level
 * cache they come from DRAM, and the pass waits for them: 1e5 and 1e6 spheres cost 1.3-1.9x
 * what 1e4 cost (docs/performance-log.md §5). So the pass looks PF_CHUNKS chunks ahead, finds the
 * highest body those pairs touch and prefetches the rows from the last such body up to it. With
 * the data in cache it only costs instructions (2-4 % at 1e4 spheres on the Zen 3 VM, 6-7 % on
 * the Zen 5 VM), hence the size test: on when the bodies times PF_BYTES_PER_BODY exceed a quarter
 * of the last-level cache (which holds more than this step's data; a VM shares it with others).
 * On the Zen 3 VM (32 MiB) the gain starts between 15,000 and 20,000 spheres, where the test puts
 * it (16,384); on the Zen 5 VM only near 60,000 (at 30,000 on is 6-13 % slower), so the size
 * test is only the guess before the run has tried both (sd_pf_trial, world.c) and for scenes too
 * small to try (below SD_PF_MIN_BODIES, where it says off on any last-level cache of 4 MiB or
 * more). */
#define PF_CHUNKS 2
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
static void pf_front(const sd_bodies *b, const int32_t *pa, const int32_t *pb, int j0, int j1, int lim, int *front)
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

/* The slots of entries j0 .. j1 that hold a spring (act), with the front: the gather reads them
 * for the touching lanes only, about one candidate slot in three (the slots are the candidates',
 * 5.4 a sphere in the tiled bed, 2.8 near pairs, 1.7 touching), a sparse walk the hardware
 * prefetchers do not follow. Part of the front prefetch, so the run's trial weighs it too.
 * `bench_scale --ab prefetch` (on/off) at 1e5 went from 0.92 (the front alone) to 0.83 on one
 * thread and from 0.99 to 0.81-0.85 on two; at 1e4, where the trial leaves it off, from 1.07-1.09
 * to 1.08-1.11 (docs/performance-log.md §P38). Without a branch: a test on act, true for three
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

static long bb_serial_pass(sd_world *w, const sd_law *law, bb_scratch *x)
{
    sd_bodies *b = &w->b;
    long count = 0;
    const int nn = w->near_n; /* (near_update made the list and its records) */
    const int pf = sd_front_prefetch_on(w);
    int front = -1;
    bed_split(w, &x->bed);
    x->q.bed_lim = x->bed.bed_lim;
    if (x->bed.bed_lim >= 0) {
        /* the bodies before the bed as two runs (the bed's load stays zero) */
        memset(b->force, 0, (size_t)x->bed.nf * sizeof(sd_vec3));
        memset(b->torque, 0, (size_t)x->bed.nf * sizeof(sd_vec3));
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
                pf_front(b, w->near_soa.a, w->near_soa.b, p0, p1, b->n, &front);
                pf_hist(sh, w->near_soa.off, w->near_soa.act, p0, p1, lsq);
            }
        }
        const soa_view v = soa_at(&w->near_soa, k0, sh, lsq);
        bb_chunk(w, law, &w->near[k0], &v, n, x->out, x->used, &x->q, b);
        for (int i = 0; i < n; i++)
            count += x->used[i];
    }
    return count;
}

/* owner of body i: the t with B[t] <= i < B[t + 1] */
static inline int owner_of(int i, const int *B, int T)
{
    int lo = 0, hi = T - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) >> 1;
        if (i >= B[mid])
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* The body a pair is split by: its lower index, or the other body where that one is the
 * bed (which is never written, and sits after the moving bodies in the store). */
static inline int pair_lead(const sd_bodies *b, const sd_pair *p)
{
    const int lo = p->a < p->b ? p->a : p->b, hi = p->a < p->b ? p->b : p->a;
    return sd_body_is_bed(b, lo) ? hi : lo;
}

/* The owners of a pair's two bodies; a bed body takes its partner's owner (nothing is added
 * to it), so a pair with the bed is never a cross pair wherever the bed sits. */
static inline void pair_owners(const sd_bodies *b, const sd_pair *p, const int *B, int T, int *ta, int *tb)
{
    const int bed_a = sd_body_is_bed(b, p->a), bed_b = sd_body_is_bed(b, p->b);
    *ta = owner_of(bed_a ? p->b : p->a, B, T);
    *tb = bed_b || bed_a ? *ta : owner_of(p->b, B, T);
}

/* New split fractions f[0..T] (f[0] = 0, f[T] = 1) that would have given the T owners the
 * same time, had each owner's time tau[t] been spread evenly over its share f[t]..f[t+1];
 * taken half way from the old split (measured times are noisy), then the times restart. The
 * cost of a pair depends on where it is (a log jam at the dam, a bed at rest upstream), which
 * a split by pair count does not see. Any split gives the same bits. */
static void rebalance(double *f, double *tau, int T)
{
    double total = 0.0;
    for (int t = 0; t < T; t++)
        total += tau[t];
    if (total > 0.0) {
        double nf[SD_MAX_OWNERS + 1];
        int t = 0;
        double acc = 0.0;
        for (int k = 1; k < T; k++) {
            const double target = total * k / T;
            while (t < T - 1 && acc + tau[t] < target) {
                acc += tau[t];
                t++;
            }
            double x = tau[t] > 0.0 ? (target - acc) / tau[t] : 0.5;
            x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
            nf[k] = f[t] + x * (f[t + 1] - f[t]);
        }
        for (int k = 1; k < T; k++) {
            double v = 0.5 * (f[k] + nf[k]);
            f[k] = v < f[k - 1] ? f[k - 1] : (v > 1.0 ? 1.0 : v);
        }
    }
    for (int t = 0; t < T; t++)
        tau[t] = 0.0;
}

/* The owners' times since the split was set differ by more than a few per cent (checked after
 * some passes, so that one slow step does not move it): the split is redone with the same near
 * list. On this 2-vCPU VM one CPU often runs this pass 20-30 % slower than the other for
 * minutes (another tenant on its core's caches), and which one changes: a split set only at
 * each new near list (every 10^2-10^4 steps) left the fast thread waiting at every step. */
#define SD_BALANCE_PASSES 50
static int uneven(sd_owned *o)
{
    if (++o->passes < SD_BALANCE_PASSES) return 0;
    double lo = INFINITY, hi = 0.0;
    for (int t = 0; t < o->T; t++) {
        lo = o->tau[t] < lo ? o->tau[t] : lo;
        hi = o->tau[t] > hi ? o->tau[t] : hi;
    }
    if (hi <= 1.03 * lo) { /* even enough: keep the split, time afresh */
        for (int t = 0; t < o->T; t++)
            o->tau[t] = 0.0;
        o->passes = 0;
        return 0;
    }
    return 1;
}


/* How many chunks of SS_CHUNK owner t's block of cross pairs makes. */
static inline int owned_xchunks(const sd_owned *o, int t) { return (o->xb[t] - o->K[t] + SS_CHUNK - 1) / SS_CHUNK; }

/* The first candidate at or after k0 whose lower body is at least i (the candidates are
 * generated by their lower body, ascending). */
static int first_led_by(const sd_world *w, int k0, int i)
{
    int lo = k0, hi = w->bb.n;
    while (lo < hi) {
        const int mid = (lo + hi) >> 1;
        if (pair_lead(&w->b, &w->bb.p[mid]) < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The body ranges, the owners' near lists and the cross pairs for T owners, remade when the
 * near pairs would change (near_update's rule: a rebuild, or a drift past half the near skin)
 * or the owners' times drift apart. Each owner filters its own candidates (those whose lower
 * body it owns) into its own segment, in pair order: the pairs it owns both sides of with
 * their records, and a mark for each cross pair. Which candidates are near does not change
 * the bits (near_update), so a remake for balance filters afresh. O(candidates) on all
 * threads; no list is copied from one thread's work to another's. */
#ifdef _OPENMP
static sd_status owned_update(sd_world *w, int T)
{
    const int n = w->b.n, nbb = w->bb.n;
    sd_owned *o = w->owned;
    const int same = o && o->T == T && o->n == n && o->nbb == nbb && o->pairs == w->bb.p && o->rb == w->timers.rebuilds;
    if (same && o->stamp == w->near_version && near_still_good(w) && !uneven(o)) return SD_OK;
    sd_contact_springs_home(w); /* (from the lists about to go) */
    if (!(o = owned_get(w))) return SD_ERR_NOMEM;
    if (o->T != T) { /* new: even shares */
        for (int t = 0; t <= T; t++)
            o->fo[t] = (double)t / T;
        for (int t = 0; t < T; t++)
            o->tau[t] = 0.0;
    } else {
        rebalance(o->fo, o->tau, T);
    }
    o->passes = 0;
    /* split by candidates, not bodies (they are generated by their lower body, ascending):
     * range t starts at the lower body of candidate nbb fo[t] */
    o->B[0] = 0;
    o->B[T] = n;
    for (int t = 1; t < T; t++) {
        long k = (long)(nbb * o->fo[t]);
        if (k > nbb - 1) k = nbb - 1;
        if (k < 0) k = 0;
        o->B[t] = nbb > 0 ? pair_lead(&w->b, &w->bb.p[k]) : 0;
        if (o->B[t] < o->B[t - 1]) o->B[t] = o->B[t - 1];
    }
    o->K[0] = 0;
    o->K[T] = nbb;
    for (int t = 1; t < T; t++)
        o->K[t] = first_led_by(w, o->K[t - 1], o->B[t]);
    bed_split(w, &o->bed);
    /* owner t's segment and its cross pairs (cross[K[t] ..]) sit at its candidates' place: no
     * owner waits for another's */
    if (sd_grow((void **)&o->list, &o->list_cap, nbb + 1, sizeof(int32_t)) ||
        sd_grow((void **)&o->cross, &o->cap, nbb + 1, sizeof(int32_t)) ||
        sd_grow((void **)&o->xo, &o->xo_cap, nbb + 1, sizeof(uint8_t)) ||
        sd_grow((void **)&o->xout, &o->xout_cap, nbb + 1, sizeof(sd_pair_out)) ||
        sd_grow((void **)&o->xact, &o->xact_cap, nbb + 1, sizeof(uint8_t)) || pair_soa_reserve(&o->soa, nbb + 1) ||
        pair_soa_reserve(&o->xsoa, nbb + 1) || sd_grow((void **)&w->wall_list, &w->wall_list_cap, n + 1, sizeof(int32_t)))
        return SD_ERR_NOMEM;
    const double skin = SD_NEAR_SKIN * w->def.margin;
    const int fresh = near_mark_ready(w);
    if (fresh < 0) return SD_ERR_NOMEM;
    /* the springs out as the lists are made (springs_out 2), when the switch is on */
    const int take = w->sw[SD_SW_SPRINGS_LIST], lsq = w->sw[SD_SW_SLOT_SQM];
    w->springs_lsq = lsq;
    if (take && sd_grow((void **)&o->hist, &o->hist_cap, nbb + 1, sizeof(sd_hist))) return SD_ERR_NOMEM;
#pragma omp parallel num_threads(T)
    {
        const int tid = omp_get_thread_num(), nthr = omp_get_num_threads();
        for (int t = tid; t < T; t += nthr) {
            const int k0 = o->K[t], k1 = o->K[t + 1];
            /* its bodies near a wall, at its bodies' place */
            o->wn[t] = wall_near_range(w, skin, o->B[t], o->B[t + 1], w->wall_list + o->B[t], &o->wskip[t]);
            /* the near ones into its segment in pair order, each cross pair as ~c (its record's
             * kind made SD_CK_CROSS, which no filter takes for a sphere pair) */
            const unsigned i0 = (unsigned)o->B[t], len = (unsigned)(o->B[t + 1] - o->B[t]);
            const int nf = o->bed.nf;
            int m = k0, xc = k0;
            /* the records' arrays held in restrict locals: through o, every store made gcc
             * load the next array's address again (about half of this loop's samples) */
            int32_t *restrict sa = o->soa.a, *restrict sb = o->soa.b, *restrict so = o->soa.off,
                              *restrict sc = o->soa.ck, *restrict list = o->list;
            double *restrict sq = o->soa.sqm;
            float *restrict sr = o->soa.rs2;
            const double *restrict rad = w->b.radius;
            uint8_t *restrict sf = o->soa.act;
            const sd_pair *restrict pairs = w->bb.p;
            const sd_hist *restrict hist = w->bb.hist;
            sd_hist *restrict oh = o->hist;
            int32_t near[NEAR_BLOCK];
            for (int kb = k0; kb < k1; kb += NEAR_BLOCK) {
                const int ke = k1 - kb < NEAR_BLOCK ? k1 : kb + NEAR_BLOCK;
                const int nn = near_block(w, skin, kb, ke, fresh, nf, near);
                for (int qn = 0; qn < nn; qn++) {
                    const int k = near[qn];
                    const sd_pair *p = &pairs[k];
                    int cross = 0, ta = t, tb = t;
                    /* both its own or the bed (after o->bed.nf, its partner's owner's: most) */
                    if (!(((unsigned)p->a - i0 < len || p->a >= nf) && ((unsigned)p->b - i0 < len || p->b >= nf))) {
                        pair_owners(&w->b, p, o->B, T, &ta, &tb);
                        cross = ta != tb;
                    }
                    sa[m] = p->a; /* (pair_soa_set) */
                    sb[m] = p->b;
                    so[m] = p->off;
                    sc[m] = ck_pack(p->kind, p->cap);
                    sq[m] = p->sqrt_m_eff;
                    sr[m] = entry_rs2(rad, p);
                    sf[m] = (uint8_t)(hist[p->off].feature >= 0);
                    list[m] = k;
                    if (take && !cross && p->kind == SD_PAIR_SS) /* (its slot's line just read) */
                        spring_out(oh, so, m, hist, sq[m], lsq);
                    if (cross) { /* few */
                        o->cross[xc] = k;
                        o->xo[xc] = (uint8_t)(ta == t ? tb : ta);
                        pair_soa_set(&o->xsoa, xc, p, hist, rad);
                        list[m] = ~xc++;
                        sc[m] = SD_CK_CROSS;
                        sr[m] = -1.0f; /* (not a sphere pair of this list: entry_rs2) */
                    }
                    m++;
                }
            }
            o->seg1[t] = m;
            o->xb[t] = xc; /* its cross pairs: cross[K[t] .. xb[t]-1] */
        }
    }
    near_made(w, skin);
    w->springs_out = take ? 2 : 0;
    o->stamp = w->near_version;
    o->rb = w->timers.rebuilds;
    o->T = T;
    o->n = n;
    o->nbb = nbb;
    o->pairs = w->bb.p;
    return SD_OK;
}

/* After pass 1 and its barrier, owner t reads and writes the bodies of its range only (its
 * own pairs, the stored cross pairs, its bodies' wall pairs): so it can also move its bodies
 * at once, while they are in its cache, with no barrier. */
static long bb_owned_pass(sd_world *w, const sd_law *law, int T, bb_scratch *scratch, int *moved_out, sd_moves *mv)
{
    sd_bodies *b = &w->b;
    sd_owned *o = w->owned;
    /* the cross pairs' chunks: each owner's block cut in chunks of SS_CHUNK, taken in turn */
    int nch = 0;
    for (int t = 0; t < T; t++)
        nch += owned_xchunks(o, t);
    long count = 0;
    int moved = 0;
    sd_moves mm = SD_MOVES_NONE;
    const int pf = sd_front_prefetch_on(w);
    sd_hist *const sh = springs_of(w, 2, o->hist); /* (the own entries' springs) */
    const int lsq = sh != w->bb.hist && w->springs_lsq; /* (soa_view.lsq) */
#pragma omp parallel num_threads(T) reduction(+ : count) reduction(| : moved) reduction(moves_max : mm)
    {
        const int nthr = omp_get_num_threads(), tid = omp_get_thread_num();
        bb_scratch *x = &scratch[tid];
        x->q.bed_lim = o->bed.bed_lim;
        x->q.xout = o->xout, x->q.xact = o->xact;
        /* pass 1: the cross pairs, into their own slots */
        /* (chunks taken as threads come free: they come before a barrier, so an uneven split
         * is waited for. Given all to the owner of their lower body, a tenth of the paper's
         * packing step was spent waiting here; split in two halves by count, one half often
         * took twice the other's time on the sphere bench) */
#pragma omp for schedule(dynamic, 1) nowait
        for (int h = 0; h < nch; h++) {
            int t = 0, c = h;
            while (c >= owned_xchunks(o, t)) /* (T blocks: a few steps) */
                c -= owned_xchunks(o, t++);
            c = o->K[t] + c * SS_CHUNK;
            const int n = o->xb[t] - c < SS_CHUNK ? o->xb[t] - c : SS_CHUNK;
            const soa_view v = soa_at(&o->xsoa, c, w->bb.hist, 0);
            bb_chunk(w, law, &o->cross[c], &v, n, x->out, x->used, &x->q, NULL);
            /* into the cross pairs' own arrays, in cross order: the lines each owner then
             * reads from the other's cache are packed, not one or two per pair of the store */
            for (int i = 0; i < n; i++) {
                const int u = x->used[i] > 0;
                if (u) o->xout[c + i] = x->out[i]; /* (read only where xact is set) */
                o->xact[c + i] = (uint8_t)u;
                count += x->used[i];
            }
        }
#pragma omp barrier
        const double t0 = omp_get_wtime();
        /* pass 2: each owner its span, in pair order */
        for (int t = tid; t < T; t += nthr) {
            const int i0 = o->B[t], i1 = o->B[t + 1], i1f = i1 < o->bed.nf ? i1 : o->bed.nf;
            /* its forces and torques zeroed, as two runs (the bed, from nf on, is left alone:
             * its load stays zero, add_pair_lim adds nothing to it, so zeroing a bed body before nf,
             * should there be one, would change nothing either) */
            if (i1f > i0) {
                memset(&b->force[i0], 0, (size_t)(i1f - i0) * sizeof(sd_vec3));
                memset(&b->torque[i0], 0, (size_t)(i1f - i0) * sizeof(sd_vec3));
            }
            /* the cross pairs of lower owners that touch its bodies, ascending: each comes
             * before every pair of its own (a lower lower body) */
            for (int s = 0; s < t; s++)
                for (int c = o->K[s]; c < o->xb[s]; c++)
                    if (o->xo[c] == t && o->xact[c]) { /* (its bodies from the record's view) */
                        const int ia = o->xsoa.a[c], own_a = ia >= i0 && ia < i1;
                        add_pair_lim(b, x->q.bed_lim, own_a ? ia : o->xsoa.b[c], !own_a, &o->xout[c]);
                    }
            /* then its own segment, with its cross pairs in their places (bb_chunk adds this
             * owner's side of each from pass 1's result, in pair order) */
            const int s0 = o->K[t], s1 = o->seg1[t];
            x->q.own_lo = i0, x->q.own_hi = i1;
            int front = i0 - 1; /* (its records hold every entry's pair, cross ones too) */
            for (int j0 = s0; j0 < s1; j0 += SS_CHUNK) {
                const int j1 = s1 - j0 < SS_CHUNK ? s1 : j0 + SS_CHUNK;
                if (pf) {
                    const int p0 = j0 + PF_CHUNKS * SS_CHUNK, p1 = p0 + SS_CHUNK < s1 ? p0 + SS_CHUNK : s1;
                    if (p1 > p0) {
                        pf_front(b, o->soa.a, o->soa.b, p0, p1, i1, &front);
                        pf_hist(sh, o->soa.off, o->soa.act, p0, p1, lsq);
                    }
                }
                const int n = j1 - j0;
                const soa_view v = soa_at(&o->soa, j0, sh, lsq);
                bb_chunk(w, law, &o->list[j0], &v, n, x->out, x->used, &x->q, b);
                for (int i = 0; i < n; i++)
                    count += x->used[i]; /* (a cross entry's 0: counted in pass 1) */
            }
            /* its bodies' wall pairs, then its moving bodies */
            count += bt_range(w, law, w->wall_list + i0, o->wn[t], &x->wq);
            if (moved_out)
                moved |= sd_integrate_list(w, w->mov, sd_mov_lower(w->mov, w->mov_n, i0),
                                           sd_mov_lower(w->mov, w->mov_n, i1), &mm);
        }
        if (nthr == T) o->tau[tid] += omp_get_wtime() - t0;
    }
    if (moved_out) *moved_out = moved;
    *mv = mm;
    return count;
}
#endif

/* how many owners the body-body pass uses: 1 (serial) for one thread or a small scene */
static int bb_owners(const sd_world *w)
{
#ifdef _OPENMP
    int T = w->nthreads;
    if (T > SD_MAX_OWNERS) T = SD_MAX_OWNERS;
    if (T > 1 && w->bb.n > w->def.parallel_min && w->b.n >= 4 * T) return T;
#endif
    (void)w;
    return 1;
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
    call_once(&simd_tables_once, simd_tables_init);
#endif
    w->near_drift = w->near_skin; /* as a drift past half the skin would */
#ifdef _OPENMP
    const int T = bb_owners(w);
    if (T > 1) return owned_update(w, T);
#endif
    return near_update(w);
}

sd_status sd_contact_compute(sd_world *w, int *integrated)
{
#ifdef SD_FILTER512
    call_once(&simd_tables_once, simd_tables_init);
#endif
    sd_law law = sd_law_make(&w->def.contact);
    long count = 0;
    const int T = bb_owners(w);
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
            x->bed.n = 0; /* (found afresh) */
            memset(x->q.sink, 0, sizeof x->q.sink); /* (never read, but not garbage either) */
        }
    }
#ifdef _OPENMP
    if (T > 1) {
        sd_status st = owned_update(w, T);
        if (!st) st = springs_to(w, 2);
        if (st) return st;
        int moved = 0;
        sd_moves mv = SD_MOVES_NONE;
        count = bb_owned_pass(w, &law, T, w->bb_scratch, integrated ? &moved : NULL, &mv);
        for (int t = 0; t < T; t++)
            w->wall_skipped += w->owned->wskip[t];
        if (moved) w->need_rebuild = 1;
        if (integrated) {
            *integrated = 1;
            sd_world_after_moves(w, &mv);
        }
    } else
#endif
    {
        sd_status nst = near_update(w);
        if (!nst) nst = springs_to(w, 1);
        if (nst) return nst;
        count = bb_serial_pass(w, &law, w->bb_scratch);
        count += bt_range(w, &law, w->wall_list, w->wall_n, &((bb_scratch *)w->bb_scratch)[0].wq);
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
 * pair by pair onto each body after its body-body sum (bt_range). */
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
