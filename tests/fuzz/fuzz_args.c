/* fuzz_args: libFuzzer target for the option value parsers (gi_args: byte
 * sizes, integers, numbers, durations such as gi-farmd's --keep-ended).
 * The input is one option value (NUL-terminated here). A value a parser
 * takes must be in its range, and a duration must be what its number
 * times its unit says. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_args.h"

static void check_duration(const char *s)
{
    double d;
    if (gi_args_duration(s, 1, 1e9, &d) != 0)
        return;
    if (!(d >= 1 && d <= 1e9))
        abort();
    size_t n = strlen(s);
    char last = s[n - 1];
    double unit = last == 'm' ? 60 : last == 'h' ? 3600 : last == 'd' ? 86400
                  : last == 'w' ? 604800 : 1;
    if (!strchr("0123456789.smhdw", last) || fabs(strtod(s, NULL) * unit - d) > 1e-9 * d)
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 1);
    memcpy(s, data, size);
    s[size] = '\0';
    uint64_t b;
    if (gi_args_bytes(s, &b) == 0 && b > (UINT64_C(1) << 50))
        abort();
    int64_t i;
    if (gi_args_int(s, -1000, 1000, &i) == 0 && (i < -1000 || i > 1000))
        abort();
    double x;
    if (gi_args_number(s, 0, 1, &x) == 0 && !(x >= 0 && x <= 1))
        abort();
    check_duration(s);
    free(s);
    return 0;
}
