/* gi_published: checked reads of coordinator-published floats. */
#include "gi_published.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* Reads and checks the n floats the blob holds into out. */
static int read_values(const gi_buf *blob, const char *hash, const gi_published_layout *l,
                       size_t n, float *out, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, blob->data, blob->len, l->what);
    gi_get_f32s(&r, out, n);
    for (size_t i = 0; i < n; i++) {
        if (isfinite(out[i]) && fabsf(out[i]) <= GI_PUBLISHED_VALUE_MAX)
            continue;
        if (!isfinite(out[i]))
            return gi_fail(err, GI_EPROTO, "%s %.12s: %s %zu's value %u is not finite (%g)",
                           l->what, hash, l->entry, i / l->per, (unsigned)(i % l->per),
                           (double)out[i]);
        return gi_fail(err, GI_EPROTO, "%s %.12s: %s %zu's value %u is %g, beyond +-%g",
                       l->what, hash, l->entry, i / l->per, (unsigned)(i % l->per),
                       (double)out[i], (double)GI_PUBLISHED_VALUE_MAX);
    }
    return gi_reader_finish(&r, err);
}

float *gi_published_floats(const gi_buf *blob, const char *hash, const gi_published_layout *l,
                           gi_error *err)
{
    /* The size first: nothing is allocated for a count the blob does not hold. */
    size_t n = l->count * l->per;
    if (l->per == 0 || n / l->per != l->count || n > SIZE_MAX / 4 - 1 || blob->len != 4 * n) {
        gi_fail(err, GI_EPROTO, "%s %.12s: %zu bytes, expected %zu (%zu %s x %u floats)",
                l->what, hash, blob->len, 4 * n, l->count,
                l->count == 1 ? l->entry : l->entries, l->per);
        return NULL;
    }
    float *out = gi_try_malloc(4 * n + 4, err, l->what);
    if (out && read_values(blob, hash, l, n, out, err)) {
        free(out);
        return NULL;
    }
    return out;
}
