/* gi_args: option values. */
#include "gi_args.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int gi_args_take(int argc, char **argv, int *i, const char *name, const char **out)
{
    size_t n = strlen(name);
    if (strncmp(argv[*i], name, n) == 0 && argv[*i][n] == '=') {
        *out = argv[*i] + n + 1;
        return 1;
    }
    if (strcmp(argv[*i], name) != 0)
        return 0;
    if (*i + 1 >= argc)
        return -1;
    *out = argv[++*i];
    return 1;
}

int gi_args_number(const char *s, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (!*s || *end || errno || !isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int gi_args_int(const char *s, int64_t lo, int64_t hi, int64_t *out)
{
    char *end;
    errno = 0;
    long long v = strtoll(s, &end, 10);
    /* strtoll skips leading blanks and a '+': plain digits only. */
    if (!*s || (*s != '-' && (*s < '0' || *s > '9')) || *end || errno || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int gi_args_bytes(const char *s, uint64_t *out)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (!*s || end == s || errno || s[0] < '0' || s[0] > '9')
        return -1;
    unsigned shift = 0;
    switch (*end) {
    case 'K': shift = 10; end++; break;
    case 'M': shift = 20; end++; break;
    case 'G': shift = 30; end++; break;
    case 'T': shift = 40; end++; break;
    default: break;
    }
    if (*end || v > (UINT64_C(1) << (50 - shift)))
        return -1;
    *out = (uint64_t)v << shift;
    return 0;
}

int gi_args_duration(const char *s, double lo, double hi, double *out)
{
    /* Plain digits and a point only: strtod would also take blanks, signs,
     * hex, exponents, "inf" and "nan", none of which an operator means. */
    size_t n = 0, points = 0, digits = 0;
    for (; s[n] && (isdigit((unsigned char)s[n]) || s[n] == '.'); n++) {
        points += s[n] == '.';
        digits += s[n] != '.';
    }
    if (!digits || points > 1 || n > 32)
        return -1;
    double unit = 1;
    switch (s[n]) {
    case '\0': break;
    case 's': unit = 1; break;
    case 'm': unit = 60; break;
    case 'h': unit = 3600; break;
    case 'd': unit = 86400; break;
    case 'w': unit = 7 * 86400; break;
    default: return -1;
    }
    if (s[n] && s[n + 1])
        return -1;
    char num[40];
    memcpy(num, s, n);
    num[n] = '\0';
    double v = strtod(num, NULL) * unit;
    if (!isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}
