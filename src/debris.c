/* Debris as designers describe it (debris.h). */
#include "debris.h"

#include <math.h>
#include <stdlib.h>

#include "core/vmath.h"

double sd_debris_phi(double z) { return 0.5 * erfc(-z * 0.70710678118654752440); }

static double npdf(double z) { return exp(-0.5 * z * z) / sqrt(2.0 * M_PI); }

double sd_debris_mass_cdf(const sd_grading_curve *g, double d)
{
    if (!(d > 0.0)) return 0.0;
    switch (g->type) {
    case SD_GRADING_LOGNORMAL:
        return sd_debris_phi(log(d / g->d50) / g->sigma);
    case SD_GRADING_ROSIN_RAMMLER: {
        const double scale = g->d50 / pow(log(2.0), 1.0 / g->exponent);
        return -expm1(-pow(d / scale, g->exponent));
    }
    case SD_GRADING_UNIFORM:
        return d <= g->d_min ? 0.0 : d >= g->d_max ? 1.0 : (d - g->d_min) / (g->d_max - g->d_min);
    case SD_GRADING_FULLER:
        return d >= g->d_max ? 1.0 : pow(d / g->d_max, g->exponent);
    }
    return 0.0;
}

int sd_debris_discretise(const sd_grading_curve *g, double *diam, double *frac)
{
    const int n = g->classes;
    const double f0 = sd_debris_mass_cdf(g, g->d_min), f1 = sd_debris_mass_cdf(g, g->d_max), total = f1 - f0;
    if (n < 1 || !(total > 0.0) || !(g->d_max > g->d_min)) return -1;
    const double ratio = log(g->d_max / g->d_min);
    /* largest first, as the paper's classes (and the placer, which places the big ones first) */
    for (int i = 0; i < n; i++) {
        const int k = n - 1 - i; /* bin k, from the small end */
        const double lo = k == 0 ? g->d_min : g->d_min * exp(ratio * k / n);
        const double hi = k == n - 1 ? g->d_max : g->d_min * exp(ratio * (k + 1) / n);
        diam[i] = sqrt(lo * hi);
        frac[i] = (sd_debris_mass_cdf(g, hi) - sd_debris_mass_cdf(g, lo)) / total;
    }
    return n;
}

int sd_debris_counts(int n, const double *diam, const double *frac, double volume, int *count)
{
    if (n < 1 || n > 64) return -1;
    int c[64], order[64];
    double left[64], vol[64], missing = volume;
    for (int i = 0; i < n; i++) {
        vol[i] = M_PI / 6.0 * diam[i] * diam[i] * diam[i];
        const double q = frac[i] * volume / vol[i];
        if (!(q <= SD_DEBRIS_MAX_COUNT)) return -1;
        c[i] = (int)floor(q);
        left[i] = (q - c[i]) * vol[i];
        missing -= c[i] * vol[i];
        order[i] = i;
    }
    /* insertion sort by the volume left over, largest first; stable, so ties keep class order */
    for (int i = 1; i < n; i++) {
        const int o = order[i];
        int j = i;
        while (j > 0 && left[order[j - 1]] < left[o]) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = o;
    }
    for (int k = 0; k < n; k++) {
        const int i = order[k];
        if (frac[i] > 0.0 && missing >= 0.5 * vol[i] && c[i] < SD_DEBRIS_MAX_COUNT) {
            c[i]++;
            missing -= vol[i];
        }
    }
    for (int i = 0; i < n; i++)
        count[i] = c[i];
    return 0;
}

/* z in [a, b] with P(Z <= z | a <= Z <= b) = u, Z standard normal: Φ(z) = Φ(a) + u (Φ(b) - Φ(a))
 * solved by Newton's method kept inside a shrinking bracket (bisection when a step leaves it).
 * For a > 0 it works on -Z, so that the probabilities it handles are those of the lower tail,
 * where Φ keeps its relative precision. */
static double normal_cut_inverse(double a, double b, double u)
{
    if (a > 0.0) return -normal_cut_inverse(-b, -a, 1.0 - u);
    const double pa = sd_debris_phi(a), pb = sd_debris_phi(b), target = pa + u * (pb - pa);
    double lo = a, hi = b, z = 0.5 * (a + b);
    for (int it = 0; it < 200 && hi - lo > 1e-15 * fmax(1.0, fabs(z)); it++) {
        const double f = sd_debris_phi(z) - target;
        if (f == 0.0) break;
        if (f < 0.0)
            lo = z;
        else
            hi = z;
        const double p = npdf(z), step = p > 0.0 ? z - f / p : NAN;
        const double next = step > lo && step < hi ? step : 0.5 * (lo + hi);
        const int done = fabs(next - z) <= 1e-15 * fmax(1.0, fabs(z));
        z = next;
        if (done) break;
    }
    return fmin(fmax(z, a), b);
}

/* the lognormal's parameters of ln x from the mean and standard deviation of x */
static void lognormal_params(double mean, double sd, double *mu, double *s)
{
    const double s2 = log1p((sd / mean) * (sd / mean));
    *s = sqrt(s2);
    *mu = log(mean) - 0.5 * s2;
}

double sd_debris_size(const sd_size_dist *d, double fixed, double u)
{
    switch (d->type) {
    case SD_SIZE_UNIFORM:
        return d->min + (d->max - d->min) * u;
    case SD_SIZE_NORMAL: {
        const double z = normal_cut_inverse((d->min - d->mean) / d->sd, (d->max - d->mean) / d->sd, u);
        return fmin(fmax(d->mean + d->sd * z, d->min), d->max);
    }
    case SD_SIZE_LOGNORMAL: {
        double mu, s;
        lognormal_params(d->mean, d->sd, &mu, &s);
        const double z = normal_cut_inverse((log(d->min) - mu) / s, (log(d->max) - mu) / s, u);
        return fmin(fmax(exp(mu + s * z), d->min), d->max);
    }
    }
    return fixed;
}

void sd_debris_size_moments(const sd_size_dist *d, double fixed, double *m1, double *m2)
{
    switch (d->type) {
    case SD_SIZE_UNIFORM:
        *m1 = 0.5 * (d->min + d->max);
        *m2 = (d->min * d->min + d->min * d->max + d->max * d->max) / 3.0;
        return;
    case SD_SIZE_NORMAL: {
        /* the cut normal: mean μ + σ (φ(α) - φ(β)) / Z, variance σ² (1 + (α φ(α) - β φ(β)) / Z
         * - ((φ(α) - φ(β)) / Z)²), Z = Φ(β) - Φ(α) */
        const double a = (d->min - d->mean) / d->sd, b = (d->max - d->mean) / d->sd;
        const double Z = a > 0.0 ? sd_debris_phi(-a) - sd_debris_phi(-b) : sd_debris_phi(b) - sd_debris_phi(a);
        const double r = (npdf(a) - npdf(b)) / Z;
        *m1 = d->mean + d->sd * r;
        const double var = d->sd * d->sd * (1.0 + (a * npdf(a) - b * npdf(b)) / Z - r * r);
        *m2 = var + *m1 * *m1;
        return;
    }
    case SD_SIZE_LOGNORMAL: {
        /* E[x^k] of the cut lognormal: exp(k μ + k² s² / 2) (Φ(β - k s) - Φ(α - k s)) / Z */
        double mu, s;
        lognormal_params(d->mean, d->sd, &mu, &s);
        const double a = (log(d->min) - mu) / s, b = (log(d->max) - mu) / s;
        const double Z = sd_debris_phi(b) - sd_debris_phi(a);
        *m1 = exp(mu + 0.5 * s * s) * (sd_debris_phi(b - s) - sd_debris_phi(a - s)) / Z;
        *m2 = exp(2.0 * mu + 2.0 * s * s) * (sd_debris_phi(b - 2.0 * s) - sd_debris_phi(a - 2.0 * s)) / Z;
        return;
    }
    }
    *m1 = fixed;
    *m2 = fixed * fixed;
}

sd_rng sd_debris_log_stream(long seed)
{
    /* another multiplier and offset than the placer's stream (build.c): the two sequences of
     * splitmix64 states start far apart */
    sd_rng r = {(uint64_t)seed * 0xD1B54A32D192ED03ULL + 0x6C6F672073697A65ULL};
    return r;
}

void sd_debris_log_next(sd_rng *r, const sd_size_dist *length, double length_fixed, const sd_size_dist *diameter,
                        double diameter_fixed, double *len, double *diam)
{
    const double u_len = sd_rng_uniform(r), u_diam = sd_rng_uniform(r);
    *len = sd_debris_size(length, length_fixed, u_len);
    *diam = sd_debris_size(diameter, diameter_fixed, u_diam);
}
