/* fuzz_args: libFuzzer target for the option value parsers (gi_args: byte
 * sizes, integers, numbers, durations such as gi-farmd's --keep-ended;
 * gi_net_split: the HOST:PORT of --listen and --coordinator). The input is
 * one option value (NUL-terminated here), given to every parser. A value
 * a parser takes must be in its range, a duration must be what its number
 * times its unit says, and an address must split into parts that put
 * together give it back. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_args.h"
#include "gi_net.h"

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

/* A HOST:PORT or [IPv6]:PORT address (--listen, --coordinator) that splits
 * must be its parts put back together: nothing dropped, nothing added. */
static void check_address(const char *s)
{
    char *host, *port;
    gi_error err;
    if (gi_net_split(s, &host, &port, &err) != 0) {
        if (host || port)
            abort();
        return;
    }
    int v6 = s[0] == '[';
    size_t n = strlen(host) + strlen(port) + 4;
    char *back = malloc(n);
    snprintf(back, n, v6 ? "[%s]:%s" : "%s:%s", host, port);
    if (!host[0] || !port[0] || strcmp(back, s) != 0 || strtol(port, NULL, 10) > 65535)
        abort();
    free(back);
    free(host);
    free(port);
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
    check_address(s);
    free(s);
    return 0;
}
