/* gi_test: a tiny unit test framework.
 *
 * GI_TEST(name) { ... } defines and registers a test (no central list).
 * The gi-tests binary runs one test per process (`gi-tests NAME`), lists
 * them (`gi-tests --list`), or runs all in-process (`gi-tests --all`).
 * Checks record a failure and continue; GI_REQUIRE stops the test. */
#ifndef GI_TEST_H
#define GI_TEST_H

#include <math.h>
#include <stdio.h>

typedef void (*gi_test_fn)(void);
void gi_test_register(const char *name, const char *file, gi_test_fn fn);
void gi_test_failed(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Scratch directory for this test (created, unique per run). */
const char *gi_test_tmpdir(void);
/* Root of the source tree (for scenes/ and tests/data/). */
const char *gi_test_srcdir(void);

#define GI_TEST(name)                                                                  \
    static void name(void);                                                            \
    __attribute__((constructor)) static void name##_register(void)                    \
    {                                                                                  \
        gi_test_register(#name, __FILE__, name);                                       \
    }                                                                                  \
    static void name(void)

#define GI_CHECK(cond)                                                                 \
    do {                                                                               \
        if (!(cond))                                                                   \
            gi_test_failed(__FILE__, __LINE__, "check failed: %s", #cond);             \
    } while (0)

#define GI_CHECK_MSG(cond, ...)                                                        \
    do {                                                                               \
        if (!(cond))                                                                   \
            gi_test_failed(__FILE__, __LINE__, __VA_ARGS__);                           \
    } while (0)

#define GI_REQUIRE(cond)                                                               \
    do {                                                                               \
        if (!(cond)) {                                                                 \
            gi_test_failed(__FILE__, __LINE__, "requirement failed: %s", #cond);       \
            return;                                                                    \
        }                                                                              \
    } while (0)

#define GI_CHECK_NEAR(a, b, tol)                                                       \
    do {                                                                               \
        double gi_a_ = (double)(a), gi_b_ = (double)(b), gi_t_ = (double)(tol);        \
        if (!(fabs(gi_a_ - gi_b_) <= gi_t_))                                           \
            gi_test_failed(__FILE__, __LINE__, "%s = %.9g, %s = %.9g, |diff| > %g", #a,   \
                           gi_a_, #b, gi_b_, gi_t_);                                   \
    } while (0)

#define GI_CHECK_REL(a, b, rel)                                                        \
    do {                                                                               \
        double gi_a_ = (double)(a), gi_b_ = (double)(b), gi_r_ = (double)(rel);        \
        if (!(fabs(gi_a_ - gi_b_) <= gi_r_ * fabs(gi_b_)))                             \
            gi_test_failed(__FILE__, __LINE__, "%s = %.9g vs %s = %.9g: relative error %.3g > %g", \
                           #a, gi_a_, #b, gi_b_, fabs(gi_a_ - gi_b_) / fabs(gi_b_), gi_r_); \
    } while (0)

/* For functions returning 0 / -1 with a gi_error named `err` in scope. */
#define GI_CHECK_OK(expr)                                                              \
    do {                                                                               \
        if ((expr) != 0)                                                               \
            gi_test_failed(__FILE__, __LINE__, "%s failed: %s", #expr, err.msg);       \
    } while (0)

#define GI_REQUIRE_OK(expr)                                                            \
    do {                                                                               \
        if ((expr) != 0) {                                                             \
            gi_test_failed(__FILE__, __LINE__, "%s failed: %s", #expr, err.msg);       \
            return;                                                                    \
        }                                                                              \
    } while (0)

#endif
