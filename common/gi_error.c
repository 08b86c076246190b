/* gi_error: error records and checked allocation. */
#include "gi_error.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int vfail(gi_error *err, gi_errcode code, int errnum, const char *fmt, va_list ap)
{
    if (err) {
        err->code = code;
        err->sys_errno = errnum;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        /* Keep messages on one line: a multi-line message breaks logs and the
         * "one-line error" promise. */
        for (char *p = err->msg; *p; p++)
            if (*p == '\n' || *p == '\r')
                *p = ' ';
    }
    return -1;
}

int gi_fail(gi_error *err, gi_errcode code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail(err, code, 0, fmt, ap);
    va_end(ap);
    return -1;
}

int gi_fail_errno(gi_error *err, gi_errcode code, int errnum, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail(err, code, errnum, fmt, ap);
    va_end(ap);
    return -1;
}

int gi_error_prefix(gi_error *err, const char *fmt, ...)
{
    if (!err)
        return -1;
    char prefix[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, ap);
    va_end(ap);
    char old[sizeof err->msg];
    memcpy(old, err->msg, sizeof old);
    size_t n = strlen(prefix), m = strnlen(old, sizeof old - 1);
    if (n > sizeof err->msg - 3)
        n = sizeof err->msg - 3;
    memcpy(err->msg, prefix, n);
    memcpy(err->msg + n, ": ", 2);
    n += 2;
    if (m > sizeof err->msg - 1 - n)
        m = sizeof err->msg - 1 - n;
    memcpy(err->msg + n, old, m);
    err->msg[n + m] = '\0';
    return -1;
}

void gi_error_clear(gi_error *err)
{
    if (err) {
        err->code = GI_OK;
        err->sys_errno = 0;
        err->msg[0] = '\0';
    }
}

const char *gi_fmt_count(char buf[32], double d)
{
    snprintf(buf, 32, fabs(d) <= 1e15 ? "%.0f" : "%g", d);
    return buf;
}

const char *gi_errcode_name(gi_errcode code)
{
    switch (code) {
    case GI_OK: return "ok";
    case GI_EINVAL: return "invalid input";
    case GI_EIO: return "i/o error";
    case GI_ENOMEM: return "out of memory";
    case GI_EPROTO: return "protocol error";
    case GI_ECRASH: return "worker crashed";
    case GI_ECANCEL: return "cancelled";
    case GI_EINTERNAL: return "internal error";
    case GI_EHOST: return "host disk error";
    }
    return "unknown error";
}

gi_errcode gi_disk_errcode(int errnum)
{
    switch (errnum) {
    case ENOSPC:
    case EDQUOT:
    case EROFS:
    case EIO: return GI_EHOST;
    default: return GI_EIO;
    }
}

int gi_error_exit_status(const gi_error *err)
{
    return (err && err->code == GI_EINVAL) ? 2 : 1;
}

static void oom(size_t n)
{
    fprintf(stderr, "gi: out of memory allocating %zu bytes\n", n);
    abort();
}

void *gi_xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p)
        oom(n);
    return p;
}

void *gi_xcalloc(size_t count, size_t size)
{
    void *p = calloc(count ? count : 1, size ? size : 1);
    if (!p)
        oom(count * size);
    return p;
}

void *gi_xrealloc(void *p, size_t n)
{
    void *q = realloc(p, n ? n : 1);
    if (!q)
        oom(n);
    return q;
}

char *gi_xstrdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = gi_xmalloc(n);
    memcpy(p, s, n);
    return p;
}

void *gi_try_malloc(size_t n, gi_error *err, const char *what)
{
    void *p = malloc(n ? n : 1);
    if (!p)
        gi_fail(err, GI_ENOMEM, "%s: cannot allocate %zu bytes", what, n);
    return p;
}

void *gi_try_calloc(size_t count, size_t size, gi_error *err, const char *what)
{
    if (size && count > SIZE_MAX / size) {
        gi_fail(err, GI_ENOMEM, "%s: size overflow (%zu x %zu)", what, count, size);
        return NULL;
    }
    void *p = calloc(count ? count : 1, size ? size : 1);
    if (!p)
        gi_fail(err, GI_ENOMEM, "%s: cannot allocate %zu bytes", what, count * size);
    return p;
}
