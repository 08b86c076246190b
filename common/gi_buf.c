/* gi_buf: growable buffers and explicit little-endian serialization. */
#include "gi_buf.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void gi_buf_init(gi_buf *b)
{
    b->data = NULL;
    b->len = b->cap = 0;
}

void gi_buf_free(gi_buf *b)
{
    free(b->data);
    gi_buf_init(b);
}

void gi_buf_reset(gi_buf *b) { b->len = 0; }

void gi_buf_reserve(gi_buf *b, size_t extra)
{
    if (b->cap - b->len >= extra)
        return;
    size_t cap = b->cap ? b->cap : 256;
    while (cap - b->len < extra)
        cap *= 2;
    b->data = gi_xrealloc(b->data, cap);
    b->cap = cap;
}

void gi_buf_move(gi_buf *dst, gi_buf *src)
{
    gi_buf_free(dst);
    *dst = *src;
    gi_buf_init(src);
}

uint8_t *gi_buf_grow(gi_buf *b, size_t n)
{
    gi_buf_reserve(b, n);
    uint8_t *p = b->data + b->len;
    b->len += n;
    return p;
}

void gi_buf_put(gi_buf *b, const void *p, size_t n)
{
    if (n)
        memcpy(gi_buf_grow(b, n), p, n);
}

void gi_buf_printf(gi_buf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n <= 0)
        return;
    /* The NUL vsnprintf writes goes into room reserved past the end. */
    gi_buf_reserve(b, (size_t)n + 1);
    va_start(ap, fmt);
    vsnprintf((char *)b->data + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

void gi_le_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

void gi_le_put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

void gi_le_put_u64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

uint16_t gi_le_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

uint32_t gi_le_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

uint64_t gi_le_get_u64(const uint8_t *p)
{
    return (uint64_t)gi_le_get_u32(p) | ((uint64_t)gi_le_get_u32(p + 4) << 32);
}

void gi_buf_put_u8(gi_buf *b, uint8_t v) { *gi_buf_grow(b, 1) = v; }
void gi_buf_put_u16(gi_buf *b, uint16_t v) { gi_le_put_u16(gi_buf_grow(b, 2), v); }
void gi_buf_put_u32(gi_buf *b, uint32_t v) { gi_le_put_u32(gi_buf_grow(b, 4), v); }
void gi_buf_put_u64(gi_buf *b, uint64_t v) { gi_le_put_u64(gi_buf_grow(b, 8), v); }
void gi_buf_put_i64(gi_buf *b, int64_t v) { gi_buf_put_u64(b, (uint64_t)v); }

void gi_buf_put_f32(gi_buf *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    gi_buf_put_u32(b, u);
}

void gi_buf_put_f64(gi_buf *b, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    gi_buf_put_u64(b, u);
}

void gi_buf_put_str(gi_buf *b, const char *s)
{
    size_t n = s ? strlen(s) : 0;
    gi_buf_put_u32(b, (uint32_t)n);
    gi_buf_put(b, s, n);
}

void gi_buf_put_blob(gi_buf *b, const void *p, size_t n)
{
    gi_buf_put_u64(b, n);
    gi_buf_put(b, p, n);
}

/* IEEE floats in host order are the wire's little-endian bytes on a
 * little-endian host: arrays then move with one memcpy. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define GI_HOST_LE 1
#else
#define GI_HOST_LE 0
#endif

void gi_buf_put_f32s(gi_buf *b, const float *v, size_t n)
{
    uint8_t *p = gi_buf_grow(b, 4 * n);
    if (GI_HOST_LE) {
        memcpy(p, v, 4 * n);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, &v[i], 4);
        gi_le_put_u32(p + 4 * i, u);
    }
}

void gi_buf_put_f64s(gi_buf *b, const double *v, size_t n)
{
    uint8_t *p = gi_buf_grow(b, 8 * n);
    if (GI_HOST_LE) {
        memcpy(p, v, 8 * n);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint64_t u;
        memcpy(&u, &v[i], 8);
        gi_le_put_u64(p + 8 * i, u);
    }
}

void gi_reader_init(gi_reader *r, const void *data, size_t len, const char *what)
{
    r->p = data;
    r->left = len;
    r->failed = 0;
    r->what = what;
}

int gi_get(gi_reader *r, void *out, size_t n)
{
    if (r->failed || n > r->left) {
        r->failed = 1;
        if (out && n)
            memset(out, 0, n);
        return -1;
    }
    if (out && n)
        memcpy(out, r->p, n);
    r->p += n;
    r->left -= n;
    return 0;
}

uint8_t gi_get_u8(gi_reader *r)
{
    uint8_t v;
    gi_get(r, &v, 1);
    return v;
}

uint16_t gi_get_u16(gi_reader *r)
{
    uint8_t p[2];
    gi_get(r, p, 2);
    return gi_le_get_u16(p);
}

uint32_t gi_get_u32(gi_reader *r)
{
    uint8_t p[4];
    gi_get(r, p, 4);
    return gi_le_get_u32(p);
}

uint64_t gi_get_u64(gi_reader *r)
{
    uint8_t p[8];
    gi_get(r, p, 8);
    return gi_le_get_u64(p);
}

int64_t gi_get_i64(gi_reader *r) { return (int64_t)gi_get_u64(r); }

float gi_get_f32(gi_reader *r)
{
    uint32_t u = gi_get_u32(r);
    float v;
    memcpy(&v, &u, 4);
    return v;
}

double gi_get_f64(gi_reader *r)
{
    uint64_t u = gi_get_u64(r);
    double v;
    memcpy(&v, &u, 8);
    return v;
}

char *gi_get_str(gi_reader *r, size_t max_len)
{
    uint32_t n = gi_get_u32(r);
    if (r->failed || n > max_len || n > r->left) {
        r->failed = 1;
        return NULL;
    }
    /* A string field never holds a NUL: it would cut the C string short
     * and make the decoded message say something else than its bytes. */
    if (memchr(r->p, 0, n)) {
        r->failed = 1;
        return NULL;
    }
    char *s = gi_xmalloc((size_t)n + 1);
    gi_get(r, s, n);
    s[n] = '\0';
    return s;
}

const uint8_t *gi_get_blob(gi_reader *r, size_t max_len, size_t *len)
{
    uint64_t n = gi_get_u64(r);
    *len = 0;
    if (r->failed || n > max_len || n > r->left) {
        r->failed = 1;
        return NULL;
    }
    const uint8_t *p = r->p;
    gi_get(r, NULL, (size_t)n);
    *len = (size_t)n;
    return p;
}

int gi_get_f32s(gi_reader *r, float *out, size_t n)
{
    if (r->failed || n > r->left / 4) {
        r->failed = 1;
        return -1;
    }
    if (GI_HOST_LE)
        return gi_get(r, out, 4 * n);
    for (size_t i = 0; i < n; i++)
        out[i] = gi_get_f32(r);
    return 0;
}

int gi_get_f64s(gi_reader *r, double *out, size_t n)
{
    if (r->failed || n > r->left / 8) {
        r->failed = 1;
        return -1;
    }
    if (GI_HOST_LE)
        return gi_get(r, out, 8 * n);
    for (size_t i = 0; i < n; i++)
        out[i] = gi_get_f64(r);
    return 0;
}

int gi_reader_finish(gi_reader *r, gi_error *err)
{
    if (r->failed)
        return gi_fail(err, GI_EPROTO, "%s: truncated or oversized field", r->what);
    if (r->left)
        return gi_fail(err, GI_EPROTO, "%s: %zu unexpected trailing bytes", r->what,
                       r->left);
    return 0;
}
