/* Continuity probe of the contact kernels the engine uses for body-body pairs (narrow_bb in
 * src/contact.c): sd_geom_cyl_cyl (log against a fixed dam pipe, log against log) and
 * sd_geom_sphere_cyl (sphere against a pipe).
 *
 * A body is moved along many random smooth paths into and around another. In every step no
 * point of the moving bodies moves by more than a few micrometres (1-5 um translation, up to
 * 1e-4 rad rotation; the bound `disp` is computed per step), so the true penetration depth
 * cannot change by more than `disp` from one step to the next. Per step the kernel's manifold
 * gives the deepest overlap and the total normal force K_n sum_k overlap_k (K_n = 1e4 N/m, the
 * default linear law, a full spring per point as in the paper), and the engine's normal spring
 * force (its points sharing one contact's, sd_manifold_shares); the largest step-to-step jumps
 * are recorded with the configuration (before / after, feature ids) that produced them.
 *
 * Paths are steered (kernel-independently, along the line between the closest points of the
 * axis segments) towards a target depth of 0-3 mm that varies smoothly along the path, while
 * the body drifts sideways and tilts. Families: random orientation; nearly parallel; nearly
 * perpendicular (side across side, the crossing anywhere on the log, also beyond its end); end
 * first; rim first; random orientation near B's end; nearly parallel with the log's end at B's
 * end plane (+-3 mm, the log lying along a beam against the flume wall); end first with the
 * log's side flush with B's end plane (+-1 mm, a log pushed into a beam next to the wall); and
 * a sweep of a log lying on the pipe whose yaw passes exactly through parallel. Log against
 * log runs the same families with both logs moving. Deterministic (splitmix64).
 *
 * A step is a jump when the deepest overlap changes by more than 2 disp + 1 nm, or the sum of
 * the overlaps by more than 2 SD_MANIFOLD_MAX disp + 1 nm (what a continuous kernel, whose
 * contacts appear and vanish at zero overlap, stays within). Jumps are classed by the contact
 * that carries most of the change:
 *   same      the overlap of a feature present before and after jumps;
 *   count     a side-side (0) or disk-against-side (1, 2, 5, 6) contact appears or vanishes
 *             with a finite overlap (merging of near-duplicates, segment limits, admission);
 *   face      a disk-against-end-face contact (3, 4, 7, 8) appears or vanishes;
 *   fallback  the deep-overlap fallback (9) appears or vanishes.
 *
 * FINDINGS (numbers at K_n = 1e4 N/m). The cylinder-cylinder kernel (src/geom/cyl_cyl.c)
 * WAS NOT continuous at end faces, and this probe found why a full flume run recorded a
 * 100.6 N single-step peak on the intermediate beam (4-13 N otherwise):
 *  - face, near end face (~10 mm, ~100 N): a log pushed end first into a pipe with its side
 *    flush with the pipe's end plane (a log against the intermediate beam next to the flume
 *    wall). The point of the end disk nearest the pipe's axis lies beyond the pipe's end, so
 *    cc_disk_into dropped E (|tq| > hl_Q); F against that end face was admitted with depth =
 *    the width of the disk inside the pipe's length, ~2 r_log + the wall penetration: 9.995 mm
 *    (99.95 N) for a true depth of 0.12 mm, appearing and vanishing in one step.
 *  - face, far end face (up to 2 hl_Q: 300 mm / 3000 N against the pipe, 100 mm / 1000 N
 *    against a log): the same F test accepted the end face at the OTHER end of Q (the only
 *    limit was ov <= 2 hl_Q) whenever E of the same disk was not admitted.
 *    FIXED: F is admitted only when the end face is Q's nearest surface to its point, as E
 *    already requires for the side (`ov > Q->r - rho + tol` rejects it). test_geom_cyl and
 *    test_geom_sampling still pass (the latter's worst deep log-log error dropped from +94.8
 *    to +5.0 mm); here the largest face-class jump fell from 300 mm to 0.51 mm (1.06 mm over
 *    3x the paths with another seed). What is left are the two classes below, held at the
 *    levels the kernel reaches (KNOWN_DISCONTINUITIES):
  - fallback (up to ~3.6 mm): when no feature pair is admitted (rim against rim or a disk
 *    in Q's corner near its end) the fallback reports the smallest separating-axis overlap over
 *    8 fixed directions, an upper bound: it appears at 0.5-3.6 mm for true depths of 0.02-0.9
 *    mm, and contacts of up to 0.9 mm true depth get no contact at all in the step before.
 *  - count (up to ~5 mm): contacts appear or vanish with finite overlap: near-duplicates (points
 *    closer than min(r)/2, normals within ~25 deg) are merged with a hard threshold; the
 *    side-side contact exists only while the common perpendicular's feet lie inside both
 *    segments and the axes are not parallel to 1e-10, and for a log nearly parallel to a pipe
 *    its point races along the axis (s ~ offset / angle), so a third contact of full depth (up
 *    to the 3 mm probed) comes and goes; E at Q's end is admitted or not by the separating-axis
 *    test, and then over-estimates (3.5 mm for a true 0.37 mm). The deepest overlap is mostly
 *    continuous there, the total force is not.
 *  The sphere-cylinder kernel is continuous (1-Lipschitz in the sphere's motion) and is held
 *  to that.
 *
 * Usage: test_geom_continuity [scale [seed]] -- scale multiplies the number of paths for a
 * longer search by hand (ctest runs scale 1 with the built-in seed). Units: metres, newtons. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "contact_internal.h"
#include "core/rng.h"
#include "geom/geom.h"
#include "geom_ref.h"

#define K_N 1e4
#define SD_PI 3.14159265358979323846
static const double LOG_R = 0.005, LOG_HL = 0.05;   /* log phi 10 x 100 mm */
static const double PIPE_R = 0.009, PIPE_HL = 0.15; /* pipe phi 18 mm across the 0.3 m flume */

/* 1: the cylinder-cylinder kernel has the known discontinuities listed above; the test allows
 * them at the levels the current kernel reaches (and fails on any other kind of jump or a
 * larger one). Set to 0 once the kernel is fixed: then every jump of the cylinder-cylinder
 * kernel fails, as it does for the sphere-cylinder kernel. */
#define KNOWN_DISCONTINUITIES 1
/* Levels allowed for the known classes (metres of the total overlap, i.e. force / K_n). Seen
 * in the default run after the end-face fix: face 0.51 mm, fallback 0.53 mm, count 2.67 mm;
 * at 3x the paths with seed 12345: face 1.06 mm, fallback 1.77 mm, count 3.0 mm; before the
 * fix, over 4 other seeds at 5x the paths: fallback 3.59 mm, count 4.95 mm. */
#define KNOWN_FACE_JUMP 3e-3
#define KNOWN_FALLBACK_JUMP 5e-3
#define KNOWN_COUNT_JUMP 7e-3
/* The engine's normal spring force of the pair (m_engine: the points' springs sum to K_n times
 * the deepest overlap where their normals agree) jumps with the deepest overlap on the random
 * paths (seen: 1.93 / 2.06 mm, at 3x the paths with seed 12345 2.91 / 2.99 mm), and only by
 * the merging of near-duplicates' shares for a log lying along the pipe, its yaw through
 * parallel (0.048 mm at 2.7 mm deep; 0.060 mm at 3x; the sum of the points' own overlaps
 * jumps by 2.67 mm there). */
#define KNOWN_ENGINE_JUMP 5e-3
#define KNOWN_ENGINE_JUMP_YAW 1e-4

static sd_rng rng = {0x6a09e667f3bcc909ULL}; /* the engine's splitmix64 (core/rng.h) */
static double urand(void) { return sd_rng_uniform(&rng); }
static double urange(double lo, double hi) { return sd_rng_range(&rng, lo, hi); }
static double rsign(void) { return urand() < 0.5 ? -1.0 : 1.0; }
static sd_vec3 rand_unit(void)
{
    for (;;) {
        sd_vec3 v = v3(urange(-1, 1), urange(-1, 1), urange(-1, 1));
        double n = v3_norm(v);
        if (n > 0.1 && n <= 1.0) return v3_scale(v, 1.0 / n);
    }
}
/* random unit vector perpendicular to unit a */
static sd_vec3 rand_perp(sd_vec3 a)
{
    for (;;) {
        sd_vec3 v = rand_unit();
        sd_vec3 w = v3_madd(v, a, -v3_dot(v, a));
        double n = v3_norm(w);
        if (n > 0.1) return v3_scale(w, 1.0 / n);
    }
}
/* a turned by angle ang towards the perpendicular unit p */
static sd_vec3 tilt(sd_vec3 a, sd_vec3 p, double ang) { return v3_normalize(v3_add(v3_scale(a, cos(ang)), v3_scale(p, sin(ang)))); }
static sd_vec3 rotate(sd_vec3 v, sd_vec3 rotvec) { return quat_rotate(quat_from_rotvec(rotvec), v); }
static sd_vec3 clampv(sd_vec3 v, double m)
{
    double n = v3_norm(v);
    return n > m ? v3_scale(v, m / n) : v;
}

/* closest points of the axis segments (kernel-independent steering direction): alternating
 * clamped projections, enough for a direction */
static void seg_closest(const sd_cyl *a, const sd_cyl *b, sd_vec3 *pa, sd_vec3 *pb)
{
    double s = 0.0, t = 0.0;
    for (int it = 0; it < 8; it++) {
        t = v3_dot(v3_sub(v3_madd(a->c, a->a, s), b->c), b->a);
        t = fmax(-b->hl, fmin(b->hl, t));
        s = v3_dot(v3_sub(v3_madd(b->c, b->a, t), a->c), a->a);
        s = fmax(-a->hl, fmin(a->hl, s));
    }
    *pa = v3_madd(a->c, a->a, s);
    *pb = v3_madd(b->c, b->a, t);
}
static sd_vec3 seg_point_closest(const sd_cyl *b, sd_vec3 x)
{
    double t = fmax(-b->hl, fmin(b->hl, v3_dot(v3_sub(x, b->c), b->a)));
    return v3_madd(b->c, b->a, t);
}

/* ------------------------------------------- reference: sampled deepest penetration ---- */
/* Written independently of the kernels: the deepest penetration of a sampled surface point
 * of either cylinder into the other (exact signed distance, sdf_cyl in geom_ref.h), coarse
 * grid then local refinement around the best samples. Only used to report the true depth of
 * the worst cases.
 * part 0 side (u = axial position, v = angle), 1 / 2 end disk - / + (u = radius, v = angle) */
static sd_vec3 cyl_point(const sd_cyl *c, sd_vec3 fu, sd_vec3 fv, int part, double u, double v)
{
    sd_vec3 rad = v3_add(v3_scale(fu, cos(v)), v3_scale(fv, sin(v)));
    if (part == 0) return v3_add(v3_madd(c->c, c->a, u), v3_scale(rad, c->r));
    return v3_add(v3_madd(c->c, c->a, part == 1 ? -c->hl : c->hl), v3_scale(rad, u));
}
static double deepest_into(const sd_cyl *P, const sd_cyl *Q)
{
    sd_vec3 fu = v3_any_perp(P->a), fv = v3_cross(P->a, fu);
    /* only the part of P's side near Q */
    double tq = v3_dot(v3_sub(Q->c, P->c), P->a), rq = sqrt(Q->hl * Q->hl + Q->r * Q->r);
    double lo = fmax(-P->hl, tq - rq), hi = fmin(P->hl, tq + rq);
    double best = -INFINITY;
    for (int part = 0; part < 3; part++) {
        double u0 = part == 0 ? lo : 0.0, u1 = part == 0 ? hi : P->r;
        if (u1 < u0) continue;
        const int nu = part == 0 ? 81 : 9, nv = 72;
        double cu[4] = {u0, u0, u0, u0}, cv[4] = {0, 0, 0, 0}, cd[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                double u = u0 + (u1 - u0) * i / (nu - 1), v = 2.0 * SD_PI * j / nv;
                double d = -sdf_cyl(Q, cyl_point(P, fu, fv, part, u, v));
                for (int k = 0; k < 4; k++)
                    if (d > cd[k]) {
                        for (int m = 3; m > k; m--) {
                            cd[m] = cd[m - 1];
                            cu[m] = cu[m - 1];
                            cv[m] = cv[m - 1];
                        }
                        cd[k] = d;
                        cu[k] = u;
                        cv[k] = v;
                        break;
                    }
            }
        for (int k = 0; k < 4; k++) {
            double du = (u1 - u0) / (nu - 1), dv = 2.0 * SD_PI / nv, bu = cu[k], bv = cv[k], bd = cd[k];
            for (int lev = 0; lev < 6; lev++) {
                double nbu = bu, nbv = bv;
                for (int i = -6; i <= 6; i++)
                    for (int j = -6; j <= 6; j++) {
                        double u = fmax(u0, fmin(u1, bu + du * i / 6.0)), v = bv + dv * j / 6.0;
                        double d = -sdf_cyl(Q, cyl_point(P, fu, fv, part, u, v));
                        if (d > bd) {
                            bd = d;
                            nbu = u;
                            nbv = v;
                        }
                    }
                bu = nbu;
                bv = nbv;
                du /= 6.0;
                dv /= 6.0;
            }
            if (bd > best) best = bd;
        }
    }
    return best;
}
static double ref_depth_cc(const sd_cyl *a, const sd_cyl *b) { return fmax(deepest_into(a, b), deepest_into(b, a)); }

/* ---------------------------------------------------------------- records ---- */
typedef struct {
    int is_sphere;
    sd_cyl a, b; /* for a sphere: a.c, a.r */
    sd_manifold m;
} snap;

typedef struct {
    double jmax, jsum; /* jumps of the deepest overlap and of the sum of overlaps (m) */
    double disp;       /* bound on the motion of any point in that step (m) */
    int family, path, step, feature;
    snap before, after;
} event;

enum { J_SAME, J_COUNT, J_FACE, J_FALLBACK, J_NCLASS };
static const char *class_name[J_NCLASS] = {"same", "count", "face", "fallback"};

typedef struct {
    const char *name;
    long steps, in_contact, jumps;
    double max_disp;
    double max_ratio;           /* largest (jump of the deepest overlap - 1e-12 m) / disp */
    event worst_max, worst_sum; /* largest jumps, any class */
    event worst_eng;            /* largest jump of the engine's normal spring force (in jsum, m) */
    long eng_jumps;             /* steps where it jumps by more than 2 disp + 1 nm */
    event deepest;              /* deepest overlap the kernel reported anywhere */
    long cls_count[J_NCLASS];
    event cls_worst[J_NCLASS]; /* largest jump of the sum per class */
    long fam_jumps[9];
    event fam_worst[9]; /* largest jump of the sum per family */
    /* feature-set transitions of the jumps (count, largest jump of the sum) */
    int ntr;
    unsigned tr_from[64], tr_to[64];
    long tr_count[64];
    double tr_max[64];
} stats;

static double m_max(const sd_manifold *m)
{
    double x = 0.0;
    for (int k = 0; k < m->n; k++) x = fmax(x, m->overlap[k]);
    return x;
}
static double m_sum(const sd_manifold *m)
{
    double x = 0.0;
    for (int k = 0; k < m->n; k++) x += m->overlap[k];
    return x;
}
/* The normal spring force the engine puts on A for this manifold, over K_n (m): the points'
 * shares made weights and their springs' overlaps (sd_manifold_shares, model.md §4), summed
 * along their normals. */
static sd_vec3 m_engine(const sd_manifold *m0)
{
    sd_manifold m = *m0;
    sd_manifold_shares(&m, 1);
    sd_vec3 f = v3(0.0, 0.0, 0.0);
    for (int k = 0; k < m.n; k++) f = v3_madd(f, m.normal[k], m.share[k] * m.overlap[k]);
    return f;
}
static unsigned m_set(const sd_manifold *m)
{
    unsigned s = 0;
    for (int k = 0; k < m->n; k++) s |= 1u << m->feature[k];
    return s;
}
static double m_ov(const sd_manifold *m, int f, int *found)
{
    for (int k = 0; k < m->n; k++)
        if (m->feature[k] == f) {
            *found = 1;
            return m->overlap[k];
        }
    *found = 0;
    return 0.0;
}

static void note_transition(stats *st, unsigned from, unsigned to, double jump)
{
    for (int i = 0; i < st->ntr; i++)
        if (st->tr_from[i] == from && st->tr_to[i] == to) {
            st->tr_count[i]++;
            if (jump > st->tr_max[i]) st->tr_max[i] = jump;
            return;
        }
    if (st->ntr < 64) {
        st->tr_from[st->ntr] = from;
        st->tr_to[st->ntr] = to;
        st->tr_count[st->ntr] = 1;
        st->tr_max[st->ntr] = jump;
        st->ntr++;
    }
}

/* the class of a jump: the feature whose overlap changes most, present on both sides or not */
static int classify(const snap *b, const snap *a, int *feature)
{
    double best = -1.0;
    int cls = J_SAME;
    *feature = -1;
    for (int side = 0; side < 2; side++) {
        const sd_manifold *m = side ? &b->m : &a->m;
        for (int k = 0; k < m->n; k++) {
            int f = m->feature[k], f0, f1;
            double d = fabs(m_ov(&a->m, f, &f1) - m_ov(&b->m, f, &f0));
            if (d <= best) continue;
            best = d;
            *feature = f;
            if (!b->is_sphere && f == 9)
                cls = J_FALLBACK;
            else if (f0 && f1)
                cls = J_SAME;
            else if (b->is_sphere)
                cls = J_COUNT; /* sphere: one contact whose feature changes */
            else if (f == 3 || f == 4 || f == 7 || f == 8)
                cls = J_FACE;
            else
                cls = J_COUNT;
        }
    }
    return cls;
}

static void set_event(event *e, double jmax, double jsum, double disp, int family, int path, int step, int feature,
                      const snap *before, const snap *after)
{
    e->jmax = jmax;
    e->jsum = jsum;
    e->disp = disp;
    e->family = family;
    e->path = path;
    e->step = step;
    e->feature = feature;
    e->before = *before;
    e->after = *after;
}

static void record(stats *st, const snap *before, const snap *after, double disp, int family, int path, int step)
{
    double jmax = fabs(m_max(&after->m) - m_max(&before->m));
    double jsum = fabs(m_sum(&after->m) - m_sum(&before->m));
    st->steps++;
    if (after->m.n) st->in_contact++;
    if (disp > st->max_disp) st->max_disp = disp;
    if (disp > 0.0 && (jmax - 1e-12) / disp > st->max_ratio) st->max_ratio = (jmax - 1e-12) / disp;
    if (m_max(&after->m) > st->deepest.jmax)
        set_event(&st->deepest, m_max(&after->m), 0.0, disp, family, path, step, -1, before, after);
    if (jmax > st->worst_max.jmax) set_event(&st->worst_max, jmax, jsum, disp, family, path, step, -1, before, after);
    if (jsum > st->worst_sum.jsum) set_event(&st->worst_sum, jmax, jsum, disp, family, path, step, -1, before, after);
    const double jeng = v3_norm(v3_sub(m_engine(&after->m), m_engine(&before->m)));
    if (jeng > 2.0 * disp + 1e-9) st->eng_jumps++;
    if (jeng > st->worst_eng.jsum) set_event(&st->worst_eng, jmax, jeng, disp, family, path, step, -1, before, after);
    /* what a continuous kernel stays within */
    if (jmax <= 2.0 * disp + 1e-9 && jsum <= 2.0 * SD_MANIFOLD_MAX * disp + 1e-9) return;
    int f, cls = classify(before, after, &f);
    st->jumps++;
    st->cls_count[cls]++;
    if (jsum > st->cls_worst[cls].jsum)
        set_event(&st->cls_worst[cls], jmax, jsum, disp, family, path, step, f, before, after);
    st->fam_jumps[family]++;
    if (jsum > st->fam_worst[family].jsum)
        set_event(&st->fam_worst[family], jmax, jsum, disp, family, path, step, f, before, after);
    note_transition(st, m_set(&before->m), m_set(&after->m), jsum);
}

/* ------------------------------------------------------------------ printing ---- */
static const char *family_name[] = {"random",       "near-parallel",           "near-perpendicular",
                                    "end-first",    "rim-first",               "near B's end",
                                    "near-parallel at B's end", "end-first at B's end", "yaw through parallel"};

static void print_set(unsigned s)
{
    printf("{");
    int first = 1;
    for (int k = 0; k < 16; k++)
        if (s & (1u << k)) {
            printf(first ? "%d" : ",%d", k);
            first = 0;
        }
    printf("}");
}

static void print_snap(const char *tag, const snap *s)
{
    if (s->is_sphere)
        printf("      %s: sphere c=(%.17g, %.17g, %.17g) r=%.6g", tag, s->a.c.x, s->a.c.y, s->a.c.z, s->a.r);
    else
        printf("      %s: A c=(%.17g, %.17g, %.17g) a=(%.17g, %.17g, %.17g) r=%.6g hl=%.6g", tag, s->a.c.x, s->a.c.y,
               s->a.c.z, s->a.a.x, s->a.a.y, s->a.a.z, s->a.r, s->a.hl);
    if (s->is_sphere)
        printf("; true depth %.4f mm\n", (s->a.r - sdf_cyl(&s->b, s->a.c)) * 1e3);
    else
        printf("; sampled true depth %.4f mm\n", ref_depth_cc(&s->a, &s->b) * 1e3);
    printf("              B c=(%.17g, %.17g, %.17g) a=(%.17g, %.17g, %.17g) r=%.6g hl=%.6g\n", s->b.c.x, s->b.c.y, s->b.c.z,
           s->b.a.x, s->b.a.y, s->b.a.z, s->b.r, s->b.hl);
    for (int k = 0; k < s->m.n; k++)
        printf("              f=%d ov=%.4f mm n=(%+.4f %+.4f %+.4f) p=(%.5f %.5f %.5f)\n", s->m.feature[k],
               s->m.overlap[k] * 1e3, s->m.normal[k].x, s->m.normal[k].y, s->m.normal[k].z, s->m.point[k].x,
               s->m.point[k].y, s->m.point[k].z);
    if (!s->m.n) printf("              (no contact)\n");
}

static void print_event(const char *what, const event *e)
{
    printf("    %s: deepest overlap %.4f mm, total force %.2f N (%.4f mm) in a step moving points <= %.2f um; "
           "family %s, path %d, step %d",
           what, e->jmax * 1e3, e->jsum * K_N, e->jsum * 1e3, e->disp * 1e6, family_name[e->family], e->path, e->step);
    if (e->feature >= 0) printf(", carried by feature %d", e->feature);
    printf("\n");
    print_snap("before", &e->before);
    print_snap("after ", &e->after);
}

static void print_stats(const stats *st)
{
    printf("\n== %s: %ld steps (%ld in contact), largest step motion %.2f um\n", st->name, st->steps, st->in_contact,
           st->max_disp * 1e6);
    printf("  largest jumps: deepest overlap %.4f mm (%.2f N), total force %.2f N (%.4f mm of overlap); "
           "deepest overlap reported %.4f mm\n",
           st->worst_max.jmax * 1e3, st->worst_max.jmax * K_N, st->worst_sum.jsum * K_N, st->worst_sum.jsum * 1e3,
           st->deepest.jmax * 1e3);
    printf("  largest jump of the deepest overlap / step motion: %.3f\n", st->max_ratio);
    printf("  the engine's normal spring force (points sharing one contact's, model.md 4): largest jump %.2f N "
           "(%.4f mm of overlap), %ld steps with a jump beyond 2 x the step motion\n",
           st->worst_eng.jsum * K_N, st->worst_eng.jsum * 1e3, st->eng_jumps);
    if (st->eng_jumps) print_event("largest jump of the engine's force (as 'total force')", &st->worst_eng);
    printf("  steps with a jump beyond the continuity bound: %ld (", st->jumps);
    for (int c = 0; c < J_NCLASS; c++)
        printf("%s %s %ld%s", c ? "," : "", class_name[c], st->cls_count[c], c + 1 < J_NCLASS ? "" : ")\n");
    for (int c = 0; c < J_NCLASS; c++)
        if (st->cls_count[c]) {
            char what[64];
            snprintf(what, sizeof what, "largest '%s' jump", class_name[c]);
            print_event(what, &st->cls_worst[c]);
        }
    if (st->worst_max.jmax > 0.0 && st->jumps) print_event("largest jump of the deepest overlap", &st->worst_max);
    printf("  per family: jumps, largest jump of the total force (feature sets before -> after)\n");
    for (int fam = 0; fam < 9; fam++)
        if (st->fam_jumps[fam]) {
            const event *e = &st->fam_worst[fam];
            printf("    %-26s %5ld  %8.2f N  ", family_name[fam], st->fam_jumps[fam], e->jsum * K_N);
            print_set(m_set(&e->before.m));
            printf(" -> ");
            print_set(m_set(&e->after.m));
            printf("\n");
        }
    for (int fam = 0; fam < 9; fam++)
        if (st->fam_jumps[fam] && st->fam_worst[fam].jsum * K_N >= 50.0 && st->fam_worst[fam].jsum < 2.0 * LOG_R + 1e-3) {
            char what[96];
            snprintf(what, sizeof what, "largest jump, family %s", family_name[fam]);
            print_event(what, &st->fam_worst[fam]);
        }
    if (st->ntr) {
        printf("  feature sets before -> after of the jumps (count, largest jump of the total force):\n");
        for (int i = 0; i < st->ntr; i++) {
            printf("    ");
            print_set(st->tr_from[i]);
            printf(" -> ");
            print_set(st->tr_to[i]);
            printf(": %ld, %.2f N\n", st->tr_count[i], st->tr_max[i] * K_N);
        }
    }
}

/* ------------------------------------------------------------------ motion ---- */
/* smooth random walk of a step vector, magnitude <= vmax */
static sd_vec3 wander(sd_vec3 v, double vmax)
{
    v = v3_add(v3_scale(v, 0.97), v3_scale(rand_unit(), 0.25 * vmax));
    return clampv(v, vmax);
}

/* target depth along a path: a smooth bump of height 0-3 mm, sometimes offset below 0 to
 * graze in and out of contact */
typedef struct {
    double D, off, period, phase;
} target;
static target rand_target(int nsteps)
{
    target t;
    t.D = urange(0.0, 3e-3);
    t.off = urand() < 0.25 ? urange(-2e-4, 0.0) : 0.0;
    t.period = urange(0.4, 1.5) * nsteps;
    t.phase = urange(0.0, 1.0);
    return t;
}
static double target_at(const target *t, int k)
{
    return t->off + t->D * (0.5 - 0.5 * cos(2.0 * SD_PI * (k / t->period + t->phase)));
}

/* normal step along `out` (from B towards A) that moves the depth towards the target, <= 3 um */
static double steer(double depth, double targ, int contact)
{
    double v = contact ? 0.5 * (depth - targ) : -3e-6; /* no contact: move in */
    return fmax(-3e-6, fmin(3e-6, v));
}

/* ------------------------------------------------------ cylinder against cylinder ---- */

/* Initial axis of A and the point s0 of A's axis that is put on the approach ray; B's axis b,
 * approach direction n0 (perpendicular to b). *y0 (position of the ray along B's axis) may be
 * changed by the family. */
static void family_axis(int family, const sd_cyl *B, sd_vec3 n0, sd_vec3 *a, double *s0, double *y0)
{
    const double hl = LOG_HL, r = LOG_R;
    sd_vec3 b = B->a, t0 = v3_normalize(v3_cross(b, n0));
    switch (family) {
    default: /* random; near B's end (y0 chosen by the caller) */
        *a = rand_unit();
        *s0 = urange(-hl - r, hl + r);
        break;
    case 1: /* nearly parallel */
        *a = v3_scale(tilt(b, rand_perp(b), pow(10.0, urange(-7.0, -1.3))), rsign());
        *s0 = urange(-hl - r, hl + r);
        break;
    case 2: /* nearly perpendicular, across B's side; the crossing anywhere on A, also beyond its end */
        *a = tilt(tilt(t0, n0, urange(-0.3, 0.3)), b, rsign() * pow(10.0, urange(-7.0, -1.3)));
        *s0 = urand() < 0.5 ? urange(-hl - r, hl + r) : rsign() * urange(hl - 2.0 * r, hl + r);
        break;
    case 3: /* end first (the + end towards B) */
        *a = tilt(v3_neg(n0), rand_perp(n0), urange(0.0, 0.3));
        *s0 = hl;
        break;
    case 4: /* rim first */
        *a = tilt(v3_neg(n0), rand_perp(n0), urange(0.3, 1.35));
        *s0 = hl;
        break;
    case 6: { /* nearly parallel, one end of A at B's end plane +-3 mm; A mostly inside B's
               * length (a log along a beam against the wall), sometimes mostly outside */
        double sa = rsign(), eb = rsign();
        *a = v3_scale(tilt(b, rand_perp(b), pow(10.0, urange(-7.0, -1.3))), sa);
        *y0 = eb * (B->hl + urange(-3e-3, 3e-3));
        /* the end of A at y0: the one pointing out of B (inside) or into B (outside) */
        double out = urand() < 0.75 ? 1.0 : -1.0;
        *s0 = out * eb * sa * hl;
        break;
    }
    case 7: /* end first, the side of A flush with B's end plane +-1 mm (a log pushed end first
             * into a beam next to the flume wall) */
        *a = tilt(v3_neg(n0), rand_perp(n0), urange(0.0, 0.3));
        *s0 = hl;
        *y0 = rsign() * (B->hl - r + urange(-1e-3, 1e-3));
        break;
    }
}

typedef struct {
    double vA, wA; /* step limits of A (m, rad) */
    double vB, wB; /* of B (0: fixed) */
} motion;

static double cyl_disp(double dv, double dw, const sd_cyl *c) { return dv + dw * sqrt(c->hl * c->hl + c->r * c->r); }

static void cc_eval(const sd_cyl *a, const sd_cyl *b, snap *s)
{
    s->is_sphere = 0;
    s->a = *a;
    s->b = *b;
    sd_geom_cyl_cyl(a, b, &s->m);
}

/* one steered path of A against B (B fixed when mo.vB = mo.wB = 0) */
static void cc_path(stats *st, int family, int path, sd_cyl A, sd_cyl B, motion mo, int nsteps)
{
    target tg = rand_target(nsteps);
    double wmaxA = mo.wA * urange(0.01, 1.0);
    sd_vec3 vA = v3_scale(rand_unit(), urange(0.0, 0.6) * mo.vA), wA = v3_scale(rand_unit(), urange(0.0, 1.0) * wmaxA);
    sd_vec3 vB = v3_scale(rand_unit(), urange(0.0, 1.0) * mo.vB), wB = v3_scale(rand_unit(), urange(0.0, 1.0) * mo.wB);
    snap prev, cur;
    cc_eval(&A, &B, &prev);
    sd_vec3 start_rel = v3_sub(A.c, B.c);
    for (int k = 0; k < nsteps; k++) {
        sd_vec3 pa, pb;
        seg_closest(&A, &B, &pa, &pb);
        sd_vec3 out = v3_sub(pa, pb);
        double no = v3_norm(out);
        out = no > 1e-9 ? v3_scale(out, 1.0 / no) : v3_normalize(v3_sub(A.c, B.c));
        double vn = steer(m_max(&prev.m), target_at(&tg, k), prev.m.n > 0);
        /* sideways drift, held within ~10 mm of the start (relative to B) */
        vA = wander(vA, 0.6 * mo.vA);
        sd_vec3 rel = v3_sub(v3_sub(A.c, B.c), start_rel);
        rel = v3_madd(rel, out, -v3_dot(rel, out));
        if (v3_norm(rel) > 0.01) vA = v3_madd(vA, rel, -0.02 * mo.vA / v3_norm(rel));
        sd_vec3 tan = v3_madd(vA, out, -v3_dot(vA, out));
        sd_vec3 dA = clampv(v3_madd(tan, out, vn), mo.vA);
        wA = wander(wA, wmaxA);
        A.c = v3_add(A.c, dA);
        A.a = v3_normalize(rotate(A.a, wA));
        double disp = cyl_disp(v3_norm(dA), v3_norm(wA), &A);
        if (mo.vB > 0.0 || mo.wB > 0.0) {
            vB = wander(vB, mo.vB);
            wB = wander(wB, mo.wB);
            B.c = v3_add(B.c, vB);
            B.a = v3_normalize(rotate(B.a, wB));
            disp += cyl_disp(v3_norm(vB), v3_norm(wB), &B);
        }
        cc_eval(&A, &B, &cur);
        record(st, &prev, &cur, disp, family, path, k);
        prev = cur;
    }
}

/* Put A (axis a fixed, point s0 of its axis on the ray base + lambda n0) at first contact plus
 * up to 20 um of gap: scan inwards, then bisect on the kernel's contact / no contact. */
static int place(sd_cyl *A, const sd_cyl *B, sd_vec3 base, sd_vec3 n0, double s0)
{
    double far = B->r + A->r + 2.0 * A->hl + 2e-3, lo = far, hi = -1.0;
    sd_manifold m;
    for (double lam = far; lam > 0.0; lam -= 2e-4) {
        A->c = v3_madd(v3_madd(base, n0, lam), A->a, -s0);
        if (sd_geom_cyl_cyl(A, B, &m)) {
            hi = lam;
            break;
        }
        lo = lam;
    }
    if (hi < 0.0) return 0;
    for (int it = 0; it < 40; it++) {
        double mid = 0.5 * (lo + hi);
        A->c = v3_madd(v3_madd(base, n0, mid), A->a, -s0);
        if (sd_geom_cyl_cyl(A, B, &m))
            hi = mid;
        else
            lo = mid;
    }
    A->c = v3_madd(v3_madd(base, n0, lo + urange(0.0, 2e-5)), A->a, -s0);
    return 1;
}

static void run_cc(stats *st, double rB, double hlB, int moving_b, int npaths, int nsteps)
{
    int path = 0;
    for (int p = 0; p < npaths; p++) {
        int family = p % 8;
        sd_cyl B = mkcyl(v3(0, 0, 0), v3(0, 1, 0), rB, hlB);
        if (moving_b) B = mkcyl(v3(urange(-1, 1), urange(-1, 1), urange(-1, 1)), rand_unit(), rB, hlB);
        sd_vec3 n0 = rand_perp(B.a);
        double y0 = family == 5 ? rsign() * urange(hlB - 0.02, hlB + 0.01) : urange(-0.8, 0.8) * hlB;
        sd_vec3 a;
        double s0;
        family_axis(family, &B, n0, &a, &s0, &y0);
        sd_cyl A = mkcyl(v3(0, 0, 0), a, LOG_R, LOG_HL);
        if (!place(&A, &B, v3_madd(B.c, B.a, y0), n0, s0)) continue;
        motion mo;
        mo.vA = urange(1e-6, 5e-6);
        mo.wA = 1e-4;
        mo.vB = moving_b ? urange(0.5e-6, 2.5e-6) : 0.0;
        mo.wB = moving_b ? 1e-4 : 0.0;
        if (moving_b) mo.vA *= 0.5;
        cc_path(st, family, path++, A, B, mo, nsteps);
    }
}

/* A log lying on the pipe (depth d) whose yaw about the vertical passes exactly through 0
 * (axes parallel), with a small pitch and a sideways offset; axis and centre set directly. */
static void run_yaw_sweep(stats *st, int nsweeps, int nsteps)
{
    sd_cyl B = mkcyl(v3(0, 0, 0), v3(0, 1, 0), PIPE_R, PIPE_HL);
    for (int p = 0; p < nsweeps; p++) {
        double d = urange(0.0, 3e-3), y0 = urange(-0.1, 0.1), x0 = p % 3 == 0 ? 0.0 : urange(-2e-3, 2e-3);
        double pitch = p % 2 ? 0.0 : urange(-1e-3, 1e-3), dphi = urange(1e-6, 1e-4);
        int k0 = nsteps / 2;
        snap prev, cur;
        for (int k = 0; k < nsteps; k++) {
            double phi = (k - k0) * dphi;
            sd_cyl A = mkcyl(v3(x0, y0, PIPE_R + LOG_R - d), v3(0, 1, 0), LOG_R, LOG_HL);
            A.a = v3(sin(phi) * cos(pitch), cos(phi) * cos(pitch), sin(pitch)); /* exactly (0, 1, 0) at phi = pitch = 0 */
            cc_eval(&A, &B, &cur);
            if (k > 0) record(st, &prev, &cur, dphi * sqrt(LOG_HL * LOG_HL + LOG_R * LOG_R), 8, p, k);
            prev = cur;
        }
    }
}

/* ------------------------------------------------------- sphere against cylinder ---- */
static void sc_eval(sd_vec3 c, double r, const sd_cyl *b, snap *s)
{
    s->is_sphere = 1;
    memset(&s->a, 0, sizeof s->a);
    s->a.c = c;
    s->a.r = r;
    s->b = *b;
    sd_geom_sphere_cyl(c, r, b, &s->m);
}

static void run_sc(stats *st, int npaths, int nsteps)
{
    const sd_cyl B = mkcyl(v3(0, 0, 0), v3(0, 1, 0), PIPE_R, PIPE_HL);
    for (int p = 0; p < npaths; p++) {
        double r = urange(0.0025, 0.010);
        int near_end = p % 2;
        double y0 = near_end ? rsign() * urange(PIPE_HL - 0.01, PIPE_HL + 0.005) : urange(-0.12, 0.12);
        sd_vec3 n0 = near_end ? rand_unit() : rand_perp(B.a);
        sd_vec3 base = v3(0, y0, 0);
        sd_manifold m;
        double far = PIPE_R + r + 0.02, lo = far, hi = -1.0;
        for (double lam = far; lam > 0.0; lam -= 2e-4) {
            if (sd_geom_sphere_cyl(v3_madd(base, n0, lam), r, &B, &m)) {
                hi = lam;
                break;
            }
            lo = lam;
        }
        if (hi < 0.0) continue;
        for (int it = 0; it < 40; it++) {
            double mid = 0.5 * (lo + hi);
            if (sd_geom_sphere_cyl(v3_madd(base, n0, mid), r, &B, &m))
                hi = mid;
            else
                lo = mid;
        }
        sd_vec3 c = v3_madd(base, n0, lo), start = c;
        target tg = rand_target(nsteps);
        double vmax = urange(1e-6, 5e-6);
        sd_vec3 v = v3_scale(rand_unit(), urange(0.0, vmax));
        snap prev, cur;
        sc_eval(c, r, &B, &prev);
        for (int k = 0; k < nsteps; k++) {
            sd_vec3 out = v3_sub(c, seg_point_closest(&B, c));
            double no = v3_norm(out);
            out = no > 1e-9 ? v3_scale(out, 1.0 / no) : n0;
            double vn = steer(m_max(&prev.m), target_at(&tg, k), prev.m.n > 0);
            v = wander(v, 0.6 * vmax);
            sd_vec3 rel = v3_sub(c, start);
            rel = v3_madd(rel, out, -v3_dot(rel, out));
            if (v3_norm(rel) > 0.01) v = v3_madd(v, rel, -0.02 * vmax / v3_norm(rel));
            sd_vec3 tan = v3_madd(v, out, -v3_dot(v, out));
            sd_vec3 dc = clampv(v3_madd(tan, out, vn), vmax);
            c = v3_add(c, dc);
            sc_eval(c, r, &B, &cur);
            record(st, &prev, &cur, v3_norm(dc), near_end ? 5 : 0, p, k);
            prev = cur;
        }
    }
}

/* ------------------------------------------------------------------- main ---- */
static void init_stats(stats *st, const char *name)
{
    memset(st, 0, sizeof *st);
    st->name = name;
}

/* the allowed levels of the known discontinuity classes of the cylinder-cylinder kernel */
static void check_cc(const stats *st, double hlB, double engine_jump)
{
    CHECK(st->worst_eng.jsum <= engine_jump);
    CHECK(st->steps > 0 && st->in_contact > st->steps / 2);
    CHECK(st->max_disp <= 20e-6);
    /* never a jump of the overlap of one and the same contact */
    CHECK(st->cls_count[J_SAME] == 0);
#if KNOWN_DISCONTINUITIES
    /* FINDING: fallback over-estimates at first contact, and contacts of finite depth
     * appearing / vanishing; see the header. Held at the levels the current kernel reaches.
     * The end-face jumps (up to 2 hl_B before the fix) must stay at the millimetre level. */
    (void)hlB;
    CHECK(st->cls_worst[J_FACE].jsum <= KNOWN_FACE_JUMP);
    CHECK(st->cls_worst[J_FALLBACK].jsum <= KNOWN_FALLBACK_JUMP);
    CHECK(st->cls_worst[J_COUNT].jsum <= KNOWN_COUNT_JUMP);
    CHECK(st->deepest.jmax <= KNOWN_COUNT_JUMP);
#else
    (void)hlB;
    CHECK(st->jumps == 0);
    CHECK(st->deepest.jmax <= 4e-3); /* nothing far deeper than the probed 0-3 mm */
#endif
}

int main(int argc, char **argv)
{
    int scale = argc > 1 ? atoi(argv[1]) : 1;
    if (scale < 1) scale = 1;
    if (argc > 2) rng.s = strtoull(argv[2], NULL, 0);

    static stats log_pipe, log_log, yaw, sph;
    init_stats(&log_pipe, "log (A, phi 10 x 100 mm) against a fixed pipe (B, phi 18 x 300 mm)");
    init_stats(&log_log, "log (A) against log (B), both moving");
    init_stats(&yaw, "log lying on the pipe, yaw through parallel");
    init_stats(&sph, "sphere (A, r 2.5-10 mm) against a fixed pipe (B)");

    run_cc(&log_pipe, PIPE_R, PIPE_HL, 0, 800 * scale, 1500);
    run_cc(&log_log, LOG_R, LOG_HL, 1, 400 * scale, 1500);
    run_yaw_sweep(&yaw, 60 * scale, 400);
    run_sc(&sph, 300 * scale, 1500);

    printf("continuity of the contact kernels along smooth paths (K_n = %g N/m; jumps in mm of overlap and N)\n", K_N);
    print_stats(&log_pipe);
    print_stats(&log_log);
    print_stats(&yaw);
    print_stats(&sph);

    check_cc(&log_pipe, PIPE_HL, KNOWN_ENGINE_JUMP);
    check_cc(&log_log, LOG_HL, KNOWN_ENGINE_JUMP);
    check_cc(&yaw, PIPE_HL, KNOWN_ENGINE_JUMP_YAW);
    /* sphere-cylinder: continuous, 1-Lipschitz in the sphere's motion */
    CHECK(sph.steps > 0 && sph.in_contact > sph.steps / 2);
    CHECK(sph.jumps == 0);
    CHECK(sph.max_ratio <= 1.0 + 1e-6);
    return check_report("test_geom_continuity");
}
