/* Deterministic random numbers: splitmix64 (one 64-bit state, easy to checkpoint). */
#ifndef SD_RNG_H
#define SD_RNG_H

#include <stdint.h>

typedef struct {
    uint64_t s;
} sd_rng;

static inline uint64_t sd_rng_next(sd_rng *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

/* uniform in [0, 1) */
static inline double sd_rng_uniform(sd_rng *r) { return (double)(sd_rng_next(r) >> 11) * 0x1.0p-53; }
static inline double sd_rng_range(sd_rng *r, double lo, double hi) { return lo + (hi - lo) * sd_rng_uniform(r); }

#endif
