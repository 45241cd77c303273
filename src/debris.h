/* Debris as designers describe it (docs/scenario.md "Debris as designers give it"): a grading by
 * mass fractions turned into whole spheres per class, a continuous grading curve cut into
 * classes, and log sizes drawn from distributions. Pure functions of their arguments; the
 * scenario loader and the builders call them. */
#ifndef SD_DEBRIS_H
#define SD_DEBRIS_H

#include "core/rng.h"

/* A continuous grading curve (spheres.distribution.type), by mass: F(d) is the mass fraction
 * finer than d. */
enum {
    SD_GRADING_NONE = 0,
    SD_GRADING_LOGNORMAL = 1,     /* F = Φ((ln d - ln d50) / sigma) */
    SD_GRADING_ROSIN_RAMMLER = 2, /* F = 1 - exp(-(d / d')^n), d' = d50 / (ln 2)^(1/n) */
    SD_GRADING_UNIFORM = 3,       /* F = (d - d_min) / (d_max - d_min): the mass spread evenly over d */
    SD_GRADING_FULLER = 4         /* F = (d / d_max)^n (Fuller and Thompson: n = 0.5) */
};

typedef struct {
    int type;        /* SD_GRADING_* */
    double d50;      /* median by mass, m (lognormal, Rosin–Rammler) */
    double sigma;    /* standard deviation of ln d (lognormal) */
    double exponent; /* n (Rosin–Rammler, Fuller) */
    double d_min, d_max; /* the curve is cut to [d_min, d_max] and scaled to a total of 1, m */
    int classes;     /* the number of classes it is cut into */
} sd_grading_curve;

/* A size drawn per log (logs.length.*, logs.diameter.*). */
enum { SD_SIZE_FIXED = 0, SD_SIZE_UNIFORM = 1, SD_SIZE_NORMAL = 2, SD_SIZE_LOGNORMAL = 3 };

typedef struct {
    int type;        /* SD_SIZE_* */
    double mean, sd; /* normal and lognormal: the untruncated distribution's mean and standard
                      * deviation (of the size itself, not of its logarithm), m */
    double min, max; /* the range: uniform over it; normal and lognormal cut to it, m */
} sd_size_dist;

/* The largest count of spheres one class may hold (spheres.counts' range). */
#define SD_DEBRIS_MAX_COUNT 10000000

/* The mass fraction finer than d of the untruncated curve (0 <= F <= 1, non-decreasing). */
double sd_debris_mass_cdf(const sd_grading_curve *g, double d);

/* The curve cut into g->classes classes of equal width in ln d between d_min and d_max (edges
 * b_k = d_min (d_max/d_min)^(k/N)), largest first: class i's diameter is the geometric mean of
 * its edges, its mass fraction (F(b_hi) - F(b_lo)) / (F(d_max) - F(d_min)). Fills diam[] and
 * frac[] (g->classes each) and returns the count, or -1 when the curve holds no mass in
 * [d_min, d_max] (its fractions would be 0/0). */
int sd_debris_discretise(const sd_grading_curve *g, double *diam, double *frac);

/* Whole spheres per class for a solid volume V split by mass fractions frac (summing to 1):
 * the ideal count of class i is q_i = frac_i V / v_i, v_i = π d_i³ / 6. Each class first gets
 * floor(q_i); then, in order of the volume left over in each class ((q_i - floor q_i) v_i,
 * largest first; ties: the earlier class), a class gets one sphere more while the volume still
 * missing from the total is at least half that sphere. So every class is within one sphere of
 * its ideal count and the total solid volume within half the largest sphere of V (largest
 * remainder, measured in volume). Returns 0, or -1 with count untouched when a class would
 * need more than SD_DEBRIS_MAX_COUNT spheres. */
int sd_debris_counts(int n, const double *diam, const double *frac, double volume, int *count);

/* A size for the uniform number u in [0, 1): fixed (the value given), or the inverse of the
 * distribution's CDF cut to [min, max] (one draw, no rejection). */
double sd_debris_size(const sd_size_dist *d, double fixed, double u);
/* E[x] and E[x²] of the (cut) distribution; the fixed value and its square for a fixed size. */
void sd_debris_size_moments(const sd_size_dist *d, double fixed, double *m1, double *m2);

/* The logs' own random stream, apart from the placer's (so that drawing log sizes leaves the
 * positions of every existing scenario as they were): each log takes two numbers of it, its
 * length first, then its diameter, whether or not either is fixed. */
sd_rng sd_debris_log_stream(long seed);
void sd_debris_log_next(sd_rng *r, const sd_size_dist *length, double length_fixed, const sd_size_dist *diameter,
                        double diameter_fixed, double *len, double *diam);

/* Φ, the standard normal CDF (by erfc: accurate in both tails). */
double sd_debris_phi(double z);

#endif
