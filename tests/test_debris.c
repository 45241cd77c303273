/* Debris as designers describe it (src/debris.c, the loader's spheres.grading,
 * spheres.distribution and logs.length/diameter.*; docs/scenario.md), against hand-computed
 * counts and closed forms:
 *  1. counts by largest remainder in volume: d = 20, 10 mm at 50/50 % of V = 0.1 L are
 *     q = 37.5/π = 11.94 and 300/π = 95.49 spheres: 12 and 95; three equal classes at 40, 35,
 *     25 % of 10.6 spheres' volume: 4, 4, 3 (the two largest remainders);
 *  2. over many volumes and fractions: every class within one sphere of its ideal count, the
 *     total within half the largest sphere of V, and so each realised mass fraction within
 *     (v_i + f_i v_max / 2) / V_real of the one asked;
 *  3. the curves cut into classes against their closed forms: the edges equal in ln d, the
 *     class diameter the edges' geometric mean, the fractions the CDF differences (lognormal
 *     by erf, independently of the code's erfc, to 1e-12; Fuller's classes a geometric series
 *     of ratio r^n; uniform's (hi - lo)/(d_max - d_min); Rosin–Rammler's F(d50) = 1/2,
 *     F(d') = 1 - 1/e);
 *  4. log sizes: every draw inside [min, max]; for 20,000 draws of seed 7 the sample mean
 *     within 4 standard errors of the cut distribution's mean (uniform, normal and lognormal,
 *     the last by quadrature) and the sample variance within 4 of its own standard errors;
 *     seed 1's first draws stored exactly (uniform: plain arithmetic on splitmix64);
 *  5. the loader: the counts it writes into spheres.counts; the errors, each naming its key
 *     at file:line:col: fractions not summing to 1 (tolerance 1e-6), a negative fraction, a
 *     grading with spheres.counts, a grading without spheres.volume, a distribution's missing
 *     parameter, a log size both fixed and drawn;
 *  6. the builder: a flume with drawn log sizes makes logs of exactly the drawn sizes (the
 *     bodies' radius, length and mass), its count from K_w the one nearest V_t, K_w as `check`
 *     reports it from the drawn volumes, and the time-step check with the smallest log the
 *     distributions allow. */
#include <stdlib.h>
#include <string.h>

#include "build.h"
#include "check.h"
#include "core/vmath.h"
#include "debris.h"
#include "sabodem.h"
#include "scenario.h"
#include "scene_report.h"

static double sphere_vol(double d) { return M_PI / 6.0 * d * d * d; }

static void counts_by_hand(void)
{
    const double d[2] = {0.02, 0.01}, f[2] = {0.5, 0.5};
    int c[2] = {0, 0};
    CHECK(sd_debris_counts(2, d, f, 1e-4, c) == 0);
    /* q = 0.5e-4 / (π d³ / 6): 37.5/π = 11.94 (left 0.94 of a 20 mm sphere) and 300/π = 95.49
     * (left 0.49 of a 10 mm one); missing 0.94 v0 + 0.49 v1 >= v0 / 2: the 20 mm class first
     * gets one more, then 7.4e-9 m^3 too much, and the 10 mm class none */
    CHECK(c[0] == 12 && c[1] == 95);
    CHECK_NEAR(12 * sphere_vol(0.02) + 95 * sphere_vol(0.01), M_PI / 6.0 * 1.91e-4, 1e-18);

    const double e[3] = {0.01, 0.01, 0.01}, g[3] = {0.40, 0.35, 0.25};
    int n[3] = {0, 0, 0};
    /* 10.6 spheres' volume: q = 4.24, 3.71, 2.65; floors 4, 3, 2 leave 1.6 spheres: the
     * remainders 0.71 and 0.65 get one each (1.6 -> 0.6 -> -0.4), 0.24 none */
    CHECK(sd_debris_counts(3, e, g, 10.6 * sphere_vol(0.01), n) == 0);
    CHECK(n[0] == 4 && n[1] == 4 && n[2] == 3);

    /* a class of zero fraction gets nothing; more than 1e7 spheres in a class is refused */
    const double h[2] = {1.0, 0.0};
    CHECK(sd_debris_counts(2, e, h, 3.4 * sphere_vol(0.01), n) == 0 && n[0] == 3 && n[1] == 0);
    CHECK(sd_debris_counts(2, e, h, 2e7 * sphere_vol(0.01), n) == -1 && n[0] == 3);
}

static void counts_bound(void)
{
    const double d[5] = {0.025, 0.02, 0.012, 0.007, 0.004};
    int worst_class = 0, worst_total = 0, worst_frac = 0, cases = 0;
    for (int a = 0; a < 40; a++) {
        /* fractions from a simple deterministic sequence, normalised */
        double f[5], sum = 0.0;
        for (int k = 0; k < 5; k++) {
            f[k] = 0.05 + fmod(0.37 * (a + 1) * (k + 2) + 0.11 * k, 1.0);
            sum += f[k];
        }
        for (int k = 0; k < 5; k++)
            f[k] /= sum;
        for (double V = 2e-5; V < 5e-2; V *= 1.37) {
            int c[5];
            CHECK(sd_debris_counts(5, d, f, V, c) == 0);
            double vr = 0.0, vmax = sphere_vol(d[0]);
            for (int k = 0; k < 5; k++) {
                const double q = f[k] * V / sphere_vol(d[k]);
                if (!(fabs(c[k] - q) < 1.0)) worst_class++;
                vr += c[k] * sphere_vol(d[k]);
            }
            if (!(fabs(vr - V) <= 0.5 * vmax * (1 + 1e-12))) worst_total++;
            for (int k = 0; k < 5 && vr > 0; k++) {
                const double got = c[k] * sphere_vol(d[k]) / vr;
                if (!(fabs(got - f[k]) <= (sphere_vol(d[k]) + 0.5 * f[k] * vmax) / vr * (1 + 1e-12))) worst_frac++;
            }
            cases++;
        }
    }
    CHECK(cases > 500);
    CHECK(worst_class == 0);
    CHECK(worst_total == 0);
    CHECK(worst_frac == 0);
}

static double phi_erf(double z) { return 0.5 * (1.0 + erf(z / sqrt(2.0))); }

static void curves(void)
{
    double diam[16], frac[16];
    /* lognormal, d50 = 10 mm, sigma = 0.5, cut to [4, 30] mm, 5 classes */
    sd_grading_curve g = {SD_GRADING_LOGNORMAL, 0.01, 0.5, 0.0, 0.004, 0.03, 5};
    CHECK(sd_debris_discretise(&g, diam, frac) == 5);
    const double z0 = log(0.004 / 0.01) / 0.5, z1 = log(0.03 / 0.01) / 0.5, tot = phi_erf(z1) - phi_erf(z0);
    double sum = 0.0;
    for (int i = 0; i < 5; i++) {
        const int k = 4 - i; /* largest first */
        const double lo = 0.004 * pow(7.5, k / 5.0), hi = 0.004 * pow(7.5, (k + 1) / 5.0);
        CHECK_REL(diam[i], sqrt(lo * hi), 1e-13);
        const double want = (phi_erf(log(hi / 0.01) / 0.5) - phi_erf(log(lo / 0.01) / 0.5)) / tot;
        CHECK_NEAR(frac[i], want, 1e-12);
        sum += frac[i];
    }
    CHECK_NEAR(sum, 1.0, 1e-14);
    CHECK_NEAR(sd_debris_mass_cdf(&g, 0.01), 0.5, 1e-16);
    CHECK_NEAR(sd_debris_mass_cdf(&g, 0.01 * exp(0.5)), 0.841344746068542948, 1e-15); /* Φ(1) */
    /* symmetric about d50 in ln d: symmetric fractions, the upper half 1/2 */
    sd_grading_curve s = {SD_GRADING_LOGNORMAL, 0.01, 0.7, 0.0, 0.0025, 0.04, 6};
    CHECK(sd_debris_discretise(&s, diam, frac) == 6);
    for (int i = 0; i < 3; i++)
        CHECK_NEAR(frac[i], frac[5 - i], 1e-13);
    CHECK_NEAR(frac[0] + frac[1] + frac[2], 0.5, 1e-13);
    CHECK_REL(diam[2] * diam[3], 0.01 * 0.01, 1e-13);

    /* Fuller, n = 0.5, [5, 20] mm, 4 classes: f ∝ lo^n (r^n - 1), r = 4^(1/4): each class's
     * fraction is r^n times the next smaller one's, and they sum to 1 */
    sd_grading_curve f = {SD_GRADING_FULLER, 0.0, 0.0, 0.5, 0.005, 0.02, 4};
    CHECK(sd_debris_discretise(&f, diam, frac) == 4);
    const double rn = pow(pow(4.0, 0.25), 0.5);
    for (int i = 0; i < 3; i++)
        CHECK_REL(frac[i] / frac[i + 1], rn, 1e-12);
    CHECK_REL(frac[3], (pow(0.005 * pow(4.0, 0.25), 0.5) - pow(0.005, 0.5)) / (pow(0.02, 0.5) - pow(0.005, 0.5)), 1e-12);

    /* uniform by mass over d: (hi - lo) / (d_max - d_min) */
    sd_grading_curve u = {SD_GRADING_UNIFORM, 0.0, 0.0, 0.0, 0.005, 0.02, 3};
    CHECK(sd_debris_discretise(&u, diam, frac) == 3);
    const double e1 = 0.005 * pow(4.0, 1.0 / 3.0), e2 = 0.005 * pow(4.0, 2.0 / 3.0);
    CHECK_REL(frac[2], (e1 - 0.005) / 0.015, 1e-13);
    CHECK_REL(frac[1], (e2 - e1) / 0.015, 1e-13);
    CHECK_REL(frac[0], (0.02 - e2) / 0.015, 1e-13);

    /* Rosin–Rammler: F(d50) = 1/2; at d' = d50 / (ln 2)^(1/n), 1 - 1/e */
    sd_grading_curve r = {SD_GRADING_ROSIN_RAMMLER, 0.012, 0.0, 2.5, 0.005, 0.025, 6};
    CHECK_NEAR(sd_debris_mass_cdf(&r, 0.012), 0.5, 1e-15);
    CHECK_NEAR(sd_debris_mass_cdf(&r, 0.012 / pow(log(2.0), 1 / 2.5)), 1.0 - exp(-1.0), 1e-15);
    CHECK(sd_debris_discretise(&r, diam, frac) == 6);
    /* no mass in the range: refused (the curve's far tail, below double precision) */
    sd_grading_curve none = {SD_GRADING_LOGNORMAL, 0.01, 0.01, 0.0, 0.5, 0.6, 4};
    CHECK(sd_debris_discretise(&none, diam, frac) == -1);
}

/* the cut lognormal's mean by Simpson's rule on ln x (independent of the code's closed form) */
static double lognormal_cut_mean(double mean, double sd, double lo, double hi)
{
    const double s2 = log(1.0 + sd * sd / (mean * mean)), s = sqrt(s2), mu = log(mean) - 0.5 * s2;
    const int n = 20000;
    const double a = log(lo), b = log(hi), h = (b - a) / n;
    double num = 0.0, den = 0.0;
    for (int i = 0; i <= n; i++) {
        const double y = a + i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        const double p = exp(-0.5 * (y - mu) * (y - mu) / s2) / s;
        num += w * p * exp(y);
        den += w * p;
    }
    return num / den;
}

static void sample(const sd_size_dist *d, int n, unsigned seed, double *mean, double *var, int *outside)
{
    sd_rng r = sd_debris_log_stream(seed);
    double s = 0.0, s2 = 0.0;
    *outside = 0;
    for (int i = 0; i < n; i++) {
        double len, dia;
        sd_debris_log_next(&r, d, 0.1, d, 0.01, &len, &dia);
        if (!(len >= d->min && len <= d->max) || !(dia >= d->min && dia <= d->max)) (*outside)++;
        s += len;
        s2 += len * len;
    }
    *mean = s / n;
    *var = s2 / n - *mean * *mean;
}

static void log_sizes(void)
{
    const int N = 20000;
    double m, v;
    int out;
    /* uniform [0.06, 0.14]: mean 0.10, variance 0.08²/12; the variance estimate's standard error
     * sqrt((μ4 - σ⁴)/N) with μ4 = w⁴/80, σ⁴ = w⁴/144 */
    sd_size_dist u = {SD_SIZE_UNIFORM, 0, 0, 0.06, 0.14};
    sample(&u, N, 7, &m, &v, &out);
    CHECK(out == 0);
    const double w = 0.08, var_u = w * w / 12;
    CHECK_NEAR(m, 0.10, 4 * sqrt(var_u / N));
    CHECK_NEAR(v, var_u, 4 * w * w * sqrt((1.0 / 80 - 1.0 / 144) / N));
    double m1, m2;
    sd_debris_size_moments(&u, 0, &m1, &m2);
    CHECK_NEAR(m1, 0.10, 1e-17);
    CHECK_NEAR(m2 - m1 * m1, var_u, 1e-17);

    /* normal, mean 0.1, sd 0.03, cut to [0.07, 0.16]: α = -1, β = 2; mean μ + σ (φ(α) - φ(β)) / Z */
    sd_size_dist g = {SD_SIZE_NORMAL, 0.1, 0.03, 0.07, 0.16};
    sample(&g, N, 7, &m, &v, &out);
    CHECK(out == 0);
    const double pa = exp(-0.5) / sqrt(2 * M_PI), pb = exp(-2.0) / sqrt(2 * M_PI), Z = phi_erf(2) - phi_erf(-1);
    const double mean_g = 0.1 + 0.03 * (pa - pb) / Z;
    const double var_g = 0.03 * 0.03 * (1 + (-1 * pa - 2 * pb) / Z - ((pa - pb) / Z) * ((pa - pb) / Z));
    CHECK_NEAR(m, mean_g, 4 * sqrt(var_g / N));
    /* the variance's standard error bounded by that of the uncut normal's, sqrt(2/N) σ² */
    CHECK_NEAR(v, var_g, 4 * sqrt(2.0 / N) * 0.03 * 0.03);
    sd_debris_size_moments(&g, 0, &m1, &m2);
    CHECK_NEAR(m1, mean_g, 1e-14);
    CHECK_NEAR(m2 - m1 * m1, var_g, 1e-14);

    /* lognormal, mean 0.01, sd 0.004, cut to [0.005, 0.02] */
    sd_size_dist l = {SD_SIZE_LOGNORMAL, 0.01, 0.004, 0.005, 0.02};
    sample(&l, N, 7, &m, &v, &out);
    CHECK(out == 0);
    const double mean_l = lognormal_cut_mean(0.01, 0.004, 0.005, 0.02);
    CHECK_NEAR(m, mean_l, 4 * sqrt(0.004 * 0.004 / N));
    sd_debris_size_moments(&l, 0, &m1, &m2);
    CHECK_REL(m1, mean_l, 1e-9);

    /* fixed: the value given, and the stream still advances by two numbers a log */
    sd_size_dist fx = {SD_SIZE_FIXED, 0, 0, 0, 0};
    sd_rng r1 = sd_debris_log_stream(1), r2 = sd_debris_log_stream(1);
    double len, dia;
    sd_debris_log_next(&r1, &fx, 0.1, &fx, 0.01, &len, &dia);
    CHECK(len == 0.1 && dia == 0.01);
    sd_rng_next(&r2);
    sd_rng_next(&r2);
    CHECK(r1.s == r2.s);

    /* seed 1's first three logs, uniform L in [0.05, 0.15] m and d in [0.008, 0.012] m: stored */
    sd_size_dist ul = {SD_SIZE_UNIFORM, 0, 0, 0.05, 0.15}, ud = {SD_SIZE_UNIFORM, 0, 0, 0.008, 0.012};
    static const double stored[3][2] = {{0x1.58a5e0dbd7589p-4, 0x1.665d0664f9p-7},
                                        {0x1.dbf08d1e90c2ep-4, 0x1.59ec5064558bap-7},
                                        {0x1.49e78527e9ccp-4, 0x1.0809a3d6b8a97p-7}};
    sd_rng r = sd_debris_log_stream(1);
    for (int k = 0; k < 3; k++) {
        sd_debris_log_next(&r, &ul, 0.1, &ud, 0.01, &len, &dia);
        CHECK(len == stored[k][0] && dia == stored[k][1]);
        if (len != stored[k][0] || dia != stored[k][1]) printf("seed 1 log %d drew %a %a\n", k, len, dia);
    }
}

/* load YAML text; returns the loader's status and what it wrote to its error stream */
static int load(sd_scenario *s, const char *text, char *err, size_t n)
{
    FILE *f = tmpfile();
    const int rc = sd_scenario_load_string(s, text, "t.yaml", NULL, 0, f);
    rewind(f);
    const size_t got = fread(err, 1, n - 1, f);
    err[got] = 0;
    fclose(f);
    return rc;
}

static void loader(void)
{
    sd_scenario s;
    char err[2048];
    CHECK(load(&s, "flume: {on: true}\nspheres:\n  grading: {diameters: [0.02, 0.01], mass_fractions: [0.5, 0.5]}\n"
                   "  volume: 1.0e-4\n",
               err, sizeof err) == 0);
    CHECK(s.n_classes == 2 && s.class_count[0] == 12 && s.class_count[1] == 95 && s.class_diam[0] == 0.02);
    CHECK(s.class_source == SD_CLASSES_GRADING && s.class_target[0] == 0.5);
    sd_scenario_free(&s);
    /* fractions within 1e-6 of 1 are taken (scaled), 2e-6 off refused */
    CHECK(load(&s, "spheres:\n  grading: {diameters: [0.02, 0.01], mass_fractions: [0.5, 0.5000009]}\n  volume: 1.0e-4\n",
               err, sizeof err) == 0);
    sd_scenario_free(&s);
    CHECK(load(&s, "spheres:\n  grading: {diameters: [0.02, 0.01], mass_fractions: [0.5, 0.502]}\n  volume: 1.0e-4\n", err,
               sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:54: spheres.grading.mass_fractions sum to 1.002, not 1 (within 1e-6)") != NULL);
    CHECK(load(&s, "spheres:\n  grading: {diameters: [0.02, 0.01], mass_fractions: [1.5, -0.5]}\n  volume: 1.0e-4\n", err,
               sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:55: spheres.grading.mass_fractions: must be in [0, 1]") != NULL);
    CHECK(load(&s, "spheres:\n  grading: {diameters: [0.02, -0.01], mass_fractions: [0.5, 0.5]}\n  volume: 1.0e-4\n", err,
               sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:31: spheres.grading.diameters: must be > 0") != NULL);
    CHECK(load(&s, "spheres:\n  counts: [1, 2]\n  grading: {diameters: [0.02, 0.01], mass_fractions: [0.5, 0.5]}\n"
                   "  volume: 1.0e-4\n",
               err, sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:11: spheres.counts conflicts with spheres.grading") != NULL);
    CHECK(load(&s, "spheres:\n  grading: {diameters: [0.02, 0.01], mass_fractions: [0.5, 0.5]}\n", err, sizeof err) != 0);
    CHECK(strstr(err, "spheres.grading needs spheres.volume") != NULL);
    CHECK(load(&s, "spheres:\n  volume: 1.0e-4\n", err, sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:11: spheres.volume is used only with") != NULL);
    CHECK(load(&s, "spheres:\n  grading: {diameters: [0.02], mass_fractions: [1]}\n  volume: 1.0e-4\n"
                   "  distribution: {type: uniform, d_min: 0.005, d_max: 0.02}\n",
               err, sizeof err) != 0);
    CHECK(strstr(err, "give spheres.grading or spheres.distribution, not both") != NULL);
    CHECK(load(&s, "spheres:\n  distribution: {type: rosin_rammler, d50: 0.01, d_min: 0.005, d_max: 0.02}\n"
                   "  volume: 1.0e-4\n",
               err, sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:24: spheres.distribution.type = rosin_rammler needs spheres.distribution.exponent > 0") !=
          NULL);
    /* a distribution through the loader: the classes and counts of debris.c */
    CHECK(load(&s, "spheres:\n  distribution: {type: fuller, exponent: 0.5, d_min: 0.005, d_max: 0.02, classes: 4}\n"
                   "  volume: 2.0e-3\n",
               err, sizeof err) == 0);
    double diam[16], frac[16];
    int cnt[16];
    sd_grading_curve fu = {SD_GRADING_FULLER, 0, 0, 0.5, 0.005, 0.02, 4};
    CHECK(sd_debris_discretise(&fu, diam, frac) == 4 && sd_debris_counts(4, diam, frac, 2e-3, cnt) == 0);
    CHECK(s.n_classes == 4 && s.n_class_counts == 4 && s.class_source == SD_CLASSES_CURVE);
    for (int k = 0; k < 4; k++)
        CHECK(s.class_count[k] == cnt[k] && s.class_diam[k] == diam[k] && s.class_target[k] == frac[k]);
    sd_scenario_free(&s);
    /* log sizes */
    CHECK(load(&s, "logs:\n  length: {type: uniform, min: 0.05, max: 0.15}\n", err, sizeof err) == 0);
    CHECK(s.log_length_dist.type == SD_SIZE_UNIFORM && s.log_length_dist.max == 0.15 && s.log_length == 0.1);
    sd_scenario_free(&s);
    const char *const ov[1] = {"logs.length=0.12"};
    FILE *f = tmpfile();
    CHECK(sd_scenario_load_string(&s, "logs:\n  length: {type: uniform, min: 0.05, max: 0.15}\n", "t.yaml", ov, 1, f) != 0);
    rewind(f);
    err[fread(err, 1, sizeof err - 1, f)] = 0;
    fclose(f);
    CHECK(strstr(err, "--set:1:13: logs.length conflicts with logs.length.type") != NULL);
    CHECK(load(&s, "logs:\n  diameter: {type: normal, mean: 0.01, min: 0.005, max: 0.02}\n", err, sizeof err) != 0);
    CHECK(strstr(err, "logs.diameter.type needs logs.diameter.sd > 0") != NULL);
    CHECK(load(&s, "logs:\n  diameter: {type: uniform, min: 0.02, max: 0.01}\n", err, sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:34: logs.diameter.type needs 0 < logs.diameter.min < logs.diameter.max") != NULL);
    CHECK(load(&s, "logs:\n  length: {max: 0.2}\n", err, sizeof err) != 0);
    CHECK(strstr(err, "t.yaml:2:17: logs.length.max is set but logs.length.type is fixed") != NULL);
}

/* a small flume without roughness and dam, drawn log sizes, K_w = 0.2 */
static const char *flume_text =
    "flume: {on: true, roughness: false, x_gate: 0.6, pack_height: 0.3}\n"
    "dam: {on: false}\n"
    "spheres: {diameters: [0.02, 0.01], counts: [40, 200]}\n"
    "logs:\n"
    "  k_w: 0.2\n"
    "  length: {type: normal, mean: 0.1, sd: 0.03, min: 0.05, max: 0.16}\n"
    "  diameter: {type: uniform, min: 0.008, max: 0.012}\n";

static void builder(void)
{
    sd_scenario s;
    char err[1024];
    CHECK(load(&s, flume_text, err, sizeof err) == 0);
    sd_log_stats ls;
    sd_build_log_stats(&s, &ls);
    /* the count: the stream's logs in order, the total nearest V_t = K_w V / (1 - K_w) */
    const double vs = 40 * sphere_vol(0.02) + 200 * sphere_vol(0.01), vt = 0.2 * vs / 0.8;
    sd_rng r = sd_debris_log_stream(s.seed);
    static double lens[4096], dias[4096];
    double sum = 0.0;
    CHECK(ls.n > 5 && ls.n < 4000);
    for (int k = 0; k <= ls.n && k < 4096; k++) {
        sd_debris_log_next(&r, &s.log_length_dist, 0.1, &s.log_diam_dist, 0.01, &lens[k], &dias[k]);
        if (k < ls.n) sum += M_PI / 4 * dias[k] * dias[k] * lens[k];
    }
    const double next = M_PI / 4 * dias[ls.n] * dias[ls.n] * lens[ls.n];
    const double last = M_PI / 4 * dias[ls.n - 1] * dias[ls.n - 1] * lens[ls.n - 1];
    CHECK(fabs(sum - vt) <= fabs(sum + next - vt) && fabs(sum - vt) <= fabs(sum - last - vt));
    CHECK_REL(ls.volume, sum, 1e-12);

    sd_world *w;
    CHECK(sd_world_create(&s.world, &w) == SD_OK);
    sd_build_info info;
    CHECK(sd_build_scene(w, &s, &info, stderr) == SD_OK);
    CHECK(info.n_logs == ls.n && info.n_spheres == 240);
    /* the logs are the first moving bodies, in the stream's order, of exactly its sizes */
    double lmin = 1, lmax = 0, vol = 0.0;
    for (int g = info.first_moving_gid; g < info.first_moving_gid + info.n_logs; g++) {
        sd_body_state b;
        CHECK(sd_world_body(w, g, &b) == SD_OK && b.shape == SD_SHAPE_CYLINDER);
        const int k = g - info.first_moving_gid;
        CHECK(b.length == lens[k] && b.radius == 0.5 * dias[k]);
        CHECK_REL(b.mass, 800.0 * M_PI * b.radius * b.radius * b.length, 1e-14);
        lmin = fmin(lmin, b.length);
        lmax = fmax(lmax, b.length);
        vol += M_PI * b.radius * b.radius * b.length;
    }
    CHECK(lmin == ls.len_min && lmax == ls.len_max && lmin >= 0.05 && lmax <= 0.16);
    CHECK_REL(vol, ls.volume, 1e-12);
    /* K_w of the scene as check reports it: the drawn logs' volume over all */
    CHECK_REL(sd_scene_k_w(&s), ls.volume / (ls.volume + vs), 1e-12);
    CHECK_NEAR(sd_scene_k_w(&s), 0.2, 0.5 * fmax(next, last) / vs);
    /* the time-step check takes the smallest log the distributions allow: 50 mm by 8 mm */
    const char *const ov[3] = {"solver.dt=2e-4", "spheres.diameters=[0.02]", "spheres.counts=[40]"};
    FILE *f = tmpfile();
    sd_scenario t;
    CHECK(sd_scenario_load_string(&t, flume_text, "t.yaml", ov, 3, f) != 0);
    rewind(f);
    err[fread(err, 1, sizeof err - 1, f)] = 0;
    fclose(f);
    char want[64];
    snprintf(want, sizeof want, "smallest mass %g kg", 800.0 * M_PI * 0.004 * 0.004 * 0.05);
    CHECK(strstr(err, want) != NULL);
    sd_world_destroy(w);
    sd_scenario_free(&s);
}

int main(void)
{
    counts_by_hand();
    counts_bound();
    curves();
    log_sizes();
    loader();
    builder();
    return check_report("test_debris");
}
