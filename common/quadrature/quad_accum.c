/* quad_accum: additive image deltas (see quad_accum.h). */
#include "quad_accum.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int gi_quad_accum_init(gi_quad_accum *a, int width, int height, int channels, gi_error *err)
{
    memset(a, 0, sizeof *a);
    size_t n = (size_t)width * (size_t)height;
    a->width = width;
    a->height = height;
    a->channels = channels;
    a->px = gi_try_calloc(n * (size_t)channels, sizeof(double), err, "image delta");
    a->mark = gi_try_calloc(n, 1, err, "image delta");
    a->touched = gi_try_calloc(n, sizeof(uint32_t), err, "image delta");
    if (!a->px || !a->mark || !a->touched) {
        gi_quad_accum_free(a);
        return -1;
    }
    return 0;
}

void gi_quad_accum_free(gi_quad_accum *a)
{
    free(a->px);
    free(a->mark);
    free(a->touched);
    memset(a, 0, sizeof *a);
}

static int cmp_u32(const void *pa, const void *pb)
{
    uint32_t x = *(const uint32_t *)pa, y = *(const uint32_t *)pb;
    return x < y ? -1 : x > y;
}

double gi_quad_accum_take_l1(gi_quad_accum *a)
{
    double sum = 0;
    for (size_t i = 0; i < a->count; i++) {
        double *v = a->px + (size_t)a->touched[i] * a->channels;
        for (int c = 0; c < a->channels; c++) {
            sum += fabs(v[c]);
            v[c] = 0.0;
        }
        a->mark[a->touched[i]] = 0;
    }
    a->count = 0;
    return sum;
}

void gi_quad_accum_emit(gi_quad_accum *a, gi_buf *out)
{
    qsort(a->touched, a->count, sizeof(uint32_t), cmp_u32);
    gi_buf_put_u32(out, (uint32_t)a->count);
    for (size_t i = 0; i < a->count; i++) {
        uint32_t p = a->touched[i];
        double *v = a->px + (size_t)p * a->channels;
        gi_buf_put_u32(out, p);
        gi_buf_put_f64s(out, v, (size_t)a->channels);
        memset(v, 0, sizeof(double) * a->channels);
        a->mark[p] = 0;
    }
    a->count = 0;
}

int gi_quad_accum_check(const gi_reader *delta, int width, int height, int channels,
                        double bound, gi_error *err)
{
    gi_reader check = *delta;
    uint64_t npix = (uint64_t)width * (uint64_t)height;
    uint32_t count = gi_get_u32(&check);
    if (check.failed || count > npix ||
        (uint64_t)count * (4 + 8 * (uint64_t)channels) > check.left)
        return gi_fail(err, GI_EPROTO, "%s: bad pixel count", delta->what);
    int64_t prev = -1;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t p = gi_get_u32(&check);
        if (p >= npix || (int64_t)p <= prev)
            return gi_fail(err, GI_EPROTO, "%s: bad pixel index", delta->what);
        prev = p;
        for (int c = 0; c < channels; c++) {
            double v = gi_get_f64(&check);
            if (!(fabs(v) <= bound)) /* NaN too */
                return gi_fail(err, GI_EPROTO, "%s: pixel %u's value is %g, not within +-%g",
                               delta->what, p, v, bound);
        }
    }
    return 0;
}

int gi_quad_accum_apply(gi_reader *r, int width, int height, int channels, double bound,
                        double *image, gi_error *err)
{
    /* Check everything first: a refused delta leaves the image as it was. */
    if (gi_quad_accum_check(r, width, height, channels, bound, err))
        return -1;
    gi_quad_accum_add_delta(r, channels, image);
    return 0;
}

void gi_quad_accum_add_delta(gi_reader *r, int channels, double *image)
{
    uint32_t count = gi_get_u32(r);
    for (uint32_t i = 0; i < count; i++) {
        double *dst = image + (size_t)gi_get_u32(r) * channels;
        for (int c = 0; c < channels; c++)
            dst[c] += gi_get_f64(r);
    }
}
