/* The batched sphere–sphere pass (contact.c: filter, vectorized law, redo of large spring
 * tilts, accumulation in pair order) against a plain per-pair reference written here from the
 * kernel's case 1 and the scalar law of contact_law.h: the same forces, torques and springs,
 * bit for bit, on 1 and 2 threads. The scene is a random overlapping cloud with fast random
 * motion, so that new contacts, held springs, small and large tilts of the spring, sliding and
 * a clipped dashpot all occur (counted, and required to occur). Empty slots carry stale
 * springs, which a new contact must not pick up. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "contact_law.h"
#include "core/rng.h"
#include "tuning.h"
#include "world_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

typedef struct {
    long pairs, touching, fresh, held, tilt_small, tilt_large, sliding, clipped;
    long edge, edge_touch; /* the pairs placed within the AVX2 filter's band, and of them touching */
} cases;

/* reference forces from the springs in old[], summed per body in ascending pair order */
static void reference(const sd_world *w, const sd_hist *old, sd_vec3 *F, sd_vec3 *T, sd_hist *hist, cases *c)
{
    const sd_bodies *b = &w->b;
    const sd_law law = sd_law_make(&w->def.contact);
    for (int i = 0; i < b->n; i++)
        F[i] = T[i] = v3(0, 0, 0);
    for (int k = 0; k < w->bb.n; k++) {
        const sd_pair *p = &w->bb.p[k];
        const int ia = p->a, ib = p->b;
        sd_hist *h = &hist[p->off];
        *h = old[p->off];
        c->pairs++;
        const sd_vec3 d = v3_sub(b->pos[ia], b->pos[ib]);
        const double ra = b->radius[ia], rb = b->radius[ib], rs = ra + rb;
        if (v3_norm2(d) >= rs * rs) {
            h->feature = -1;
            continue;
        }
        c->touching++;
        const double dist = sqrt(v3_norm2(d));
        const sd_vec3 n = dist > 1e-300 ? v3_scale(d, 1.0 / dist) : v3(0.0, 0.0, 1.0);
        const double ov = rs - dist, la = ra - 0.5 * ov, lb = rb - 0.5 * ov;
        /* contact point midway between the surfaces: r_a = -la n, r_b = lb n */
        const sd_vec3 wsum = v3_madd(v3_scale(b->omega[ia], la), b->omega[ib], lb);
        const sd_vec3 vrel = v3_sub(v3_sub(b->vel[ia], b->vel[ib]), v3_cross(wsum, n));
        sd_vec3 s = h->feature == 0 ? h->shear : v3(0, 0, 0);
        if (h->feature != 0)
            c->fresh++;
        else {
            c->held++;
            const double s2 = v3_norm2(s), sn = v3_dot(s, n);
            if (s2 > 0.0 && sn * sn < 1e-4 * s2)
                c->tilt_small++;
            else if (s2 > 0.0)
                c->tilt_large++;
        }
        sd_vec3 f;
        const double pn = sd_contact_law(&law, p->sqrt_m_eff, n, ov, vrel, w->def.dt, &s, &f);
        const double limit = law.cohesion + pn * law.tan_phi;
        const sd_vec3 ft = v3_madd(f, n, -pn);
        if (v3_norm2(s) >= limit * limit * (1.0 - 1e-9))
            c->sliding++;
        else if (v3_norm2(ft) >= limit * limit * (1.0 - 1e-9))
            c->clipped++;
        h->feature = 0;
        h->shear = s;
        const sd_vec3 nf = v3_cross(n, f);
        /* the bed roughness (fixed spheres) carries no load: its force stays zero */
        if (!b->fixed[ia]) {
            F[ia] = v3_add(F[ia], f);
            T[ia] = v3_add(T[ia], v3_scale(nf, -la));
        }
        if (!b->fixed[ib]) {
            F[ib] = v3_sub(F[ib], f);
            T[ib] = v3_add(T[ib], v3_scale(nf, -lb));
        }
    }
}

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static long mismatches(const sd_world *w, const sd_vec3 *F, const sd_vec3 *T, const sd_hist *hist)
{
    long bad = 0;
    for (int i = 0; i < w->b.n; i++) {
        const sd_vec3 f = w->b.force[i], t = w->b.torque[i];
        bad += !same(f.x, F[i].x) + !same(f.y, F[i].y) + !same(f.z, F[i].z);
        bad += !same(t.x, T[i].x) + !same(t.y, T[i].y) + !same(t.z, T[i].z);
    }
    for (int k = 0; k < w->bb.nh; k++) {
        const sd_hist *a = &w->bb.hist[k], *r = &hist[k];
        bad += a->feature != r->feature;
        if (r->feature == 0)
            bad += !same(a->shear.x, r->shear.x) + !same(a->shear.y, r->shear.y) + !same(a->shear.z, r->shear.z);
    }
    return bad;
}

static void run(int threads, int simd, cases *c, long *bad)
{
    sd_world_def d = sd_world_def_default();
    d.parallel_min = 0; /* the owned parallel pass even for this scene */
    d.threads = threads;
    d.tuning.simd = simd;
    sd_world *w;
    CHECK(sd_world_create(&d, &w) == SD_OK);
    sd_rng rng = {20261123};
    const int ncloud = 1500;
    for (int i = 0; i < ncloud; i++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = sd_rng_range(&rng, 0.0025, 0.01);
        s.pos = v3(sd_rng_range(&rng, 0, 0.2), sd_rng_range(&rng, 0, 0.1), sd_rng_range(&rng, 0, 0.1));
        s.vel = v3(sd_rng_range(&rng, -1, 1), sd_rng_range(&rng, -1, 1), sd_rng_range(&rng, -1, 1));
        s.omega = v3(sd_rng_range(&rng, -100, 100), sd_rng_range(&rng, -100, 100), sd_rng_range(&rng, -100, 100));
        s.fixed = i % 10 == 0; /* bed spheres: sqrt(m_i) for the effective mass */
        CHECK(sd_world_add_sphere(w, &s) >= 0);
    }
    /* pairs apart from the cloud, at centre distances within a relative 1e-6 of r_a + r_b:
     * the AVX2 filter keeps (r_a + r_b)^2 as a float and tests a pair exactly within a
     * relative 2^-22 of it (contact.c entry_rs2); the first evaluation (no move) has them */
    static const double rel[] = {-1e-6, -1e-7, -3e-8, -1e-8, -1e-9, -1e-12, 0.0, 1e-12, 1e-9, 1e-8, 3e-8, 1e-7, 1e-6};
    for (int k = 0; k < (int)(sizeof rel / sizeof rel[0]); k++) {
        sd_sphere_def s = sd_sphere_def_default();
        s.radius = sd_rng_range(&rng, 0.0025, 0.01);
        s.pos = v3(0.3 + 0.05 * k, 0.05, 0.05);
        s.fixed = 1;
        const double ra = s.radius;
        CHECK(sd_world_add_sphere(w, &s) >= 0);
        s.radius = sd_rng_range(&rng, 0.0025, 0.01);
        s.pos.x += (ra + s.radius) * (1.0 + rel[k]);
        s.fixed = 0;
        CHECK(sd_world_add_sphere(w, &s) >= 0);
        const double dx = s.pos.x - 0.3 - 0.05 * k, rs = ra + s.radius;
        c->edge += fabs(dx * dx / (rs * rs) - 1.0) < 0x1p-22;
        c->edge_touch += dx * dx < rs * rs;
    }
    const int n = w->b.n;
    CHECK(sd_neighbor_rebuild(w) == SD_OK);
    const int nh = w->bb.nh;
    sd_hist *old = malloc((size_t)(nh + 1) * sizeof *old), *hist = malloc((size_t)(nh + 1) * sizeof *hist);
    sd_vec3 *F = malloc((size_t)n * sizeof *F), *T = malloc((size_t)n * sizeof *T);
    CHECK(old && hist && F && T);
    /* three evaluations: all contacts new; springs held with small tilts (tiny moves); then
     * moves of up to 2 mm (inside the margin, so the list stays valid) turning many normals
     * by more than the small-angle rule allows */
    const double move[3] = {0.0, 1e-6, 2e-3};
    for (int e = 0; e < 3; e++) {
        for (int i = 0; i < n; i++)
            if (!w->b.fixed[i])
                w->b.pos[i] = v3_add(w->b.pos[i], v3(sd_rng_range(&rng, -1, 1) * move[e] / 1.8,
                                                     sd_rng_range(&rng, -1, 1) * move[e] / 1.8,
                                                     sd_rng_range(&rng, -1, 1) * move[e] / 1.8));
        w->near_stamp = -1; /* the bodies were moved by hand: the near list is stale */
        /* a slot without a held spring (feature != 0) may keep any old spring: a contact that
         * starts again must not see it (the springs into their slots first: the pass takes
         * them from there) */
        sd_near_springs_home(w);
        for (int k = 0; k < nh; k++)
            if (w->bb.hist[k].feature != 0)
                w->bb.hist[k].shear =
                    v3(sd_rng_range(&rng, -1, 1), sd_rng_range(&rng, -1, 1), sd_rng_range(&rng, -1, 1));
        memcpy(old, w->bb.hist, (size_t)nh * sizeof *old);
        reference(w, old, F, T, hist, c);
        CHECK(sd_contact_compute(w, NULL) == SD_OK);
        sd_near_springs_home(w);
        *bad += mismatches(w, F, T, hist);
    }
    free(old);
    free(hist);
    free(F);
    free(T);
    sd_world_destroy(w);
}

/* The level a world runs at (tuning.c): the CPU's best, AVX2 on an AMD CPU with AVX-512 (its
 * gathers are slower there), what was asked for capped at the CPU's; and what the environment's
 * SD_SIMD and SD_NO_AVX512 ask for (sd_tuning_from_env, the one reader of the environment). */
static void simd_choice(void)
{
    enum { S = SD_SIMD_SCALAR, A2 = SD_SIMD_AVX2, A5 = SD_SIMD_AVX512, AU = SD_SIMD_AUTO };
    CHECK(sd_tuning_simd_level(AU, A5, 0) == A5); /* Intel with AVX-512 */
    CHECK(sd_tuning_simd_level(AU, A5, 1) == A2); /* AMD with AVX-512 */
    CHECK(sd_tuning_simd_level(AU, A2, 1) == A2); /* AMD without (the Zen 3 VM) */
    CHECK(sd_tuning_simd_level(AU, S, 0) == S);
    CHECK(sd_tuning_simd_level(A5, A5, 1) == A5); /* asked for */
    CHECK(sd_tuning_simd_level(A5, A2, 1) == A2); /* not there: the CPU's */
    CHECK(sd_tuning_simd_level(A2, A5, 0) == A2);
    CHECK(sd_tuning_simd_level(S, A5, 1) == S);
    CHECK(sd_tuning_simd_level(99, A5, 0) == A5); /* out of range: as auto */
    static const struct {
        const char *simd, *no512;
        int level, status;
    } env[] = {
        {NULL, NULL, AU, SD_OK},        {"avx2", NULL, A2, SD_OK},   {"1", NULL, A2, SD_OK},
        {"scalar", NULL, S, SD_OK},     {"0", NULL, S, SD_OK},       {"avx512", NULL, A5, SD_OK},
        {"auto", NULL, AU, SD_OK},      {NULL, "1", S, SD_OK},       {"avx512", "1", S, SD_OK},
        {NULL, "0", AU, SD_OK},         {NULL, "", AU, SD_OK},       {"bogus", NULL, AU, SD_ERR_ARG},
    };
    for (size_t k = 0; k < sizeof env / sizeof env[0]; k++) {
        if (env[k].simd) setenv("SD_SIMD", env[k].simd, 1); else unsetenv("SD_SIMD");
        if (env[k].no512) setenv("SD_NO_AVX512", env[k].no512, 1); else unsetenv("SD_NO_AVX512");
        sd_tuning t;
        char msg[160];
        const sd_status st = sd_tuning_from_env(&t, msg, sizeof msg);
        CHECK(st == (sd_status)env[k].status);
        CHECK(t.simd == env[k].level);
        if (st) CHECK(strstr(msg, "SD_SIMD=bogus") != NULL);
    }
    unsetenv("SD_SIMD");
    unsetenv("SD_NO_AVX512");
    setenv("SD_PREFETCH", "on", 1);
    sd_tuning t;
    CHECK(sd_tuning_from_env(&t, NULL, 0) == SD_OK && t.prefetch == SD_PREFETCH_ON);
    setenv("SD_PREFETCH", "sometimes", 1);
    CHECK(sd_tuning_from_env(&t, NULL, 0) == SD_ERR_ARG && t.prefetch == SD_PREFETCH_AUTO);
    unsetenv("SD_PREFETCH");
}

int main(void)
{
    simd_choice();
    /* every level of the hand-written SIMD kernels the CPU has (the touch filter and gather in
     * the scalar loops, 4 AVX2 lanes, 8 AVX-512 lanes), each on 1 and 2 threads */
    int levels = 0;
    for (int level = SD_SIMD_SCALAR; level <= SD_SIMD_AVX512; level++) {
        if (level > sd_cpu_simd_level()) continue; /* not on this CPU */
        levels++;
        for (int threads = 1; threads <= 2; threads++) {
            cases c = {0};
            long bad = 0;
            run(threads, level, &c, &bad);
            printf("SIMD level %d, threads %d: %ld pair evaluations, %ld touching (%ld new, %ld held: %ld small tilt, "
                   "%ld large tilt), %ld sliding, %ld dashpot clipped; %ld values differ from the reference\n",
                   level, threads, c.pairs, c.touching, c.fresh, c.held, c.tilt_small, c.tilt_large, c.sliding,
                   c.clipped, bad);
            CHECK(bad == 0);
            /* the scene must exercise every branch of the law and both spring-tilt paths */
            CHECK(c.touching > 1000);
            CHECK(c.fresh > 100);
            CHECK(c.tilt_small > 100);
            CHECK(c.tilt_large > 100);
            CHECK(c.sliding > 10);
            CHECK(c.clipped > 10);
            /* pairs at the edge of touching on both sides of it, in the AVX2 filter's band */
            CHECK(c.edge >= 8 && c.edge_touch >= 4 && c.edge_touch <= c.edge);
        }
    }
    CHECK(levels >= 1);
    return check_report("test_ss_batch");
}
