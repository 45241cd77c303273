/* Minimal test harness: each test program is one ctest case; CHECK_* record failures with
 * file:line and the numbers involved, and the program exits non-zero if any failed. */
#ifndef SD_CHECK_H
#define SD_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int check_failures = 0;
static int check_count = 0;

#define CHECK(cond)                                                                  \
    do {                                                                             \
        check_count++;                                                               \
        if (!(cond)) {                                                               \
            check_failures++;                                                        \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
        }                                                                            \
    } while (0)

/* |a - b| <= tol (absolute) */
#define CHECK_NEAR(a, b, tol)                                                                    \
    do {                                                                                         \
        double check_a_ = (a), check_b_ = (b), check_t_ = (tol);                                 \
        check_count++;                                                                           \
        if (!(fabs(check_a_ - check_b_) <= check_t_)) {                                          \
            check_failures++;                                                                    \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.17g, %s = %.17g, tol %.3g\n",      \
                    __FILE__, __LINE__, #a, check_a_, #b, check_b_, check_t_);                   \
        }                                                                                        \
    } while (0)

/* |a - b| <= rel * |b| */
#define CHECK_REL(a, b, rel)                                                                     \
    do {                                                                                         \
        double check_a_ = (a), check_b_ = (b), check_r_ = (rel);                                 \
        check_count++;                                                                           \
        if (!(fabs(check_a_ - check_b_) <= check_r_ * fabs(check_b_))) {                         \
            check_failures++;                                                                    \
            fprintf(stderr, "%s:%d: CHECK_REL failed: %s = %.17g, %s = %.17g, rel %.3g (%.3g)\n", \
                    __FILE__, __LINE__, #a, check_a_, #b, check_b_, check_r_,                    \
                    fabs(check_a_ - check_b_) / fabs(check_b_));                                 \
        }                                                                                        \
    } while (0)

#define CHECK_VEC_NEAR(a, b, tol)             \
    do {                                      \
        CHECK_NEAR((a).x, (b).x, tol);        \
        CHECK_NEAR((a).y, (b).y, tol);        \
        CHECK_NEAR((a).z, (b).z, tol);        \
    } while (0)

static inline int check_report(const char *name)
{
    if (check_failures) {
        fprintf(stderr, "%s: %d of %d checks FAILED\n", name, check_failures, check_count);
        return 1;
    }
    printf("%s: all %d checks passed\n", name, check_count);
    return 0;
}

#endif
