/* Workers' checked reads of published data (gi_published.h): detp's
 * radiance and radiosity's corner data, as each method's reader sees them. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp/detp_method.h"
#include "gi_published.h"
#include "gi_test.h"
#include "radiosity/rad_task.h"

static const char HASH[] = "a1b2c3d4e5f60718293a4b5c6d7e8f90a1b2c3d4e5f60718293a4b5c6d7e8f9";

/* A blob of n floats, value i = i / 4. */
static void blob_of(gi_buf *b, size_t n)
{
    gi_buf_init(b);
    for (size_t i = 0; i < n; i++)
        gi_buf_put_f32(b, (float)i * 0.25f);
}

static void set_value(gi_buf *b, size_t i, float v) { memcpy(b->data + 4 * i, &v, 4); }

/* Reads b with detp's reader (rad: radiosity's) for count entries; NULL
 * and err->msg on failure. */
static float *read_blob(const gi_buf *b, int rad, uint32_t count, gi_error *err)
{
    gi_error_clear(err);
    return rad ? gi_rad_corners_decode(b, HASH, count, err)
               : detp_radiance_decode(b, HASH, count, err);
}

static void refused(const gi_buf *b, int rad, uint32_t count, const char *want)
{
    gi_error err;
    float *v = read_blob(b, rad, count, &err);
    GI_CHECK_MSG(!v && err.code == GI_EPROTO && strcmp(err.msg, want) == 0,
                 "refused as \"%s\", not \"%s\"", want, v ? "(read)" : err.msg);
    free(v);
}

GI_TEST(published_radiance_read_exactly)
{
    gi_buf b;
    blob_of(&b, 12);
    gi_error err;
    float *v = read_blob(&b, 0, 4, &err);
    GI_REQUIRE(v != NULL);
    for (size_t i = 0; i < 12; i++)
        GI_CHECK(v[i] == (float)i * 0.25f);
    free(v);
    set_value(&b, 5, -GI_PUBLISHED_VALUE_MAX); /* the largest a shader takes */
    v = read_blob(&b, 0, 4, &err);
    GI_CHECK(v && v[5] == -GI_PUBLISHED_VALUE_MAX);
    free(v);
    gi_buf_free(&b);
}

GI_TEST(published_radiance_refused)
{
    gi_buf b;
    blob_of(&b, 12);
    refused(&b, 0, 5, "detp: published radiance a1b2c3d4e5f6: 48 bytes, expected 60 "
                      "(5 vertices x 3 floats)");
    b.len--;
    refused(&b, 0, 4, "detp: published radiance a1b2c3d4e5f6: 47 bytes, expected 48 "
                      "(4 vertices x 3 floats)");
    b.len++;
    set_value(&b, 7, NAN);
    refused(&b, 0, 4, "detp: published radiance a1b2c3d4e5f6: vertex 2's value 1 is not "
                      "finite (nan)");
    set_value(&b, 7, -INFINITY);
    refused(&b, 0, 4, "detp: published radiance a1b2c3d4e5f6: vertex 2's value 1 is not "
                      "finite (-inf)");
    set_value(&b, 7, 1.0f);
    set_value(&b, 11, FLT_MAX); /* finite, but interpolated with emission: inf */
    refused(&b, 0, 4, "detp: published radiance a1b2c3d4e5f6: vertex 3's value 2 is "
                      "3.40282e+38, beyond +-8.50706e+37");
    gi_buf_free(&b);
}

GI_TEST(published_corners_refused)
{
    gi_buf b;
    blob_of(&b, 27);
    gi_error err;
    float *v = read_blob(&b, 1, 3, &err);
    GI_CHECK(v && v[26] == 6.5f);
    free(v);
    refused(&b, 1, 1, "radiosity: published image data a1b2c3d4e5f6: 108 bytes, expected 36 "
                      "(1 element x 9 floats)");
    set_value(&b, 20, NAN);
    refused(&b, 1, 3, "radiosity: published image data a1b2c3d4e5f6: element 2's value 2 is "
                      "not finite (nan)");
    set_value(&b, 20, 0.0f);
    set_value(&b, 0, -1e38f);
    refused(&b, 1, 3, "radiosity: published image data a1b2c3d4e5f6: element 0's value 0 is "
                      "-1e+38, beyond +-8.50706e+37");
    gi_buf_free(&b);
}
