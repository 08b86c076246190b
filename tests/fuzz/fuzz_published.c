/* fuzz_published: libFuzzer target for the data a coordinator publishes
 * for its tasks (gi_job_publish) as workers read it: detp's per-vertex
 * radiance (detp_radiance_decode) and radiosity's per-element corner
 * radiosities (gi_rad_corners_decode), both through gi_published_floats.
 *
 * The first byte picks the reader (bit 0: 0 detp, 1 radiosity) and the
 * entry count (bits 1..7); the rest is the blob.
 *
 * Any blob must read or fail with GI_EPROTO and a one-line message naming
 * the blob, never crash, leak or hang. One that reads must have exactly
 * the layout's size, hold only finite values within GI_PUBLISHED_VALUE_MAX
 * (what the shaders rely on), and be what the blob's bytes say.
 *
 * With GI_FUZZ_PUBLISHED_SEEDS=DIR in the environment it writes the seed
 * corpus instead (blobs as the methods publish them, and ones each check
 * refuses) and exits. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "detp/detp_method.h"
#include "gi_fs.h"
#include "gi_published.h"
#include "radiosity/rad_task.h"

static const char HASH[] = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";

static void one_input(const uint8_t *data, size_t size, int must_read)
{
    int rad = data[0] & 1;
    uint32_t count = data[0] >> 1;
    gi_buf blob = {(uint8_t *)data + 1, size - 1, size - 1};
    gi_error err;
    gi_error_clear(&err);
    float *v = rad ? gi_rad_corners_decode(&blob, HASH, count, &err)
                   : detp_radiance_decode(&blob, HASH, count, &err);
    if (!v) {
        if (must_read || err.code != GI_EPROTO || !strstr(err.msg, "published") ||
            !strstr(err.msg, "0123456789ab") || strchr(err.msg, '\n'))
            abort();
        return;
    }
    size_t n = (size_t)count * (rad ? 9 : 3);
    if (blob.len != 4 * n || (n && memcmp(v, blob.data, blob.len) != 0)) /* little-endian */
        abort();
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]) || fabsf(v[i]) > GI_PUBLISHED_VALUE_MAX)
            abort();
    free(v);
}

/* Writes one seed: the selector byte, then the floats. */
static void seed(const char *dir, const char *name, int rad, uint32_t count, const float *v,
                 size_t n, int must_read)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_u8(&b, (uint8_t)(count << 1 | (uint32_t)rad));
    gi_buf_put_f32s(&b, v, n);
    one_input(b.data, b.len, must_read);
    gi_error err;
    if (gi_write_file_atomic(path, b.data, b.len, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    gi_buf_free(&b);
}

static void write_seeds(const char *dir)
{
    gi_error err;
    if (gi_mkdirs(dir, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    float v[9 * 6];
    for (size_t i = 0; i < sizeof v / sizeof *v; i++)
        v[i] = (float)(i % 7) * 0.25f;
    seed(dir, "detp-ok", 0, 12, v, 36, 1);
    seed(dir, "rad-ok", 1, 6, v, 54, 1);
    seed(dir, "detp-short", 0, 12, v, 35, 0);
    seed(dir, "rad-long", 1, 5, v, 54, 0);
    v[10] = NAN;
    seed(dir, "detp-nan", 0, 12, v, 36, 0);
    v[10] = INFINITY;
    seed(dir, "rad-inf", 1, 6, v, 54, 0);
    v[10] = -FLT_MAX;
    seed(dir, "detp-huge", 0, 12, v, 36, 0);
    v[10] = -GI_PUBLISHED_VALUE_MAX;
    seed(dir, "rad-largest", 1, 6, v, 54, 1);
    seed(dir, "empty", 0, 0, v, 0, 1);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    const char *dir = getenv("GI_FUZZ_PUBLISHED_SEEDS");
    if (dir) {
        write_seeds(dir);
        exit(0);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size >= 1)
        one_input(data, size, 0);
    return 0;
}
