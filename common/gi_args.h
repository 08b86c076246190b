/* gi_args: command-line option parsing shared by gi, gi-farmd and gi-worker.
 * Options are "--name VALUE" or "--name=VALUE". */
#ifndef GI_ARGS_H
#define GI_ARGS_H

#include <stdint.h>

/* If argv[*i] is option `name`: *out gets its value (advancing *i past a
 * separate value) and 1 is returned; -1 if the value is missing; 0 if
 * argv[*i] is another argument. */
int gi_args_take(int argc, char **argv, int *i, const char *name, const char **out);

/* A number in [lo, hi]; 0 on success, -1 if s is not one. */
int gi_args_number(const char *s, double lo, double hi, double *out);
/* An integer in [lo, hi]. */
int gi_args_int(const char *s, int64_t lo, int64_t hi, int64_t *out);
/* A byte count: an integer with an optional K, M, G or T suffix (powers
 * of 1024), at most 2^50. */
int gi_args_bytes(const char *s, uint64_t *out);

/* A duration in seconds within [lo, hi]: a decimal number (digits and at
 * most one point, no sign or exponent) with an optional unit s, m, h, d or
 * w (seconds by default): "90", "1.5h", "14d". */
int gi_args_duration(const char *s, double lo, double hi, double *out);

#endif
