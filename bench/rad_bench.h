/* rad_bench: what the radiosity benchmark drivers share: a clock (the
 * library's, gi_rad_seconds) and a fatal error exit. */
#ifndef GI_RAD_BENCH_H
#define GI_RAD_BENCH_H

#include <stdio.h>
#include <stdlib.h>

#include "gi_clock.h"
#include "gi_error.h"
#include "radiosity/rad_relight.h"

static inline double now(void) { return gi_now(); }

/* Prints "<program>: <message>" and exits 1. */
static inline void rad_bench_die(const char *program, const gi_error *err)
{
    fprintf(stderr, "%s: %s\n", program, err->msg);
    exit(1);
}

#endif
