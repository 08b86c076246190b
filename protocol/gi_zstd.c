/* gi_zstd: bounded zstd compression and decompression of payloads. */
#include "gi_zstd.h"

#include <stdlib.h>
#include <zstd.h>

/* One context of each kind per thread, kept: a fresh one per call spent
 * most of a small payload's time allocating and clearing its tables. */
static _Thread_local ZSTD_CCtx *cctx;
static _Thread_local ZSTD_DCtx *dctx;

int gi_zstd_compress(gi_buf *out, const void *src, size_t n, int level, gi_error *err)
{
    if (!cctx && !(cctx = ZSTD_createCCtx()))
        return gi_fail(err, GI_EINTERNAL, "zstd: cannot create a compression context");
    size_t bound = ZSTD_compressBound(n);
    if (ZSTD_isError(bound))
        return gi_fail(err, GI_EINTERNAL, "zstd: cannot compress %zu bytes: %s", n,
                       ZSTD_getErrorName(bound));
    gi_buf_reserve(out, bound);
    /* ZSTD_compressCCtx() writes the content size into the frame header, which
     * the receiver requires. */
    size_t r = ZSTD_compressCCtx(cctx, out->data + out->len, bound, src, n, level);
    if (ZSTD_isError(r))
        return gi_fail(err, GI_EINTERNAL, "zstd: compressing %zu bytes failed: %s", n,
                       ZSTD_getErrorName(r));
    out->len += r;
    return 0;
}

int gi_zstd_decompress(gi_buf *out, const void *src, size_t n, uint64_t max_size,
                       const char *what, gi_error *err)
{
    const uint8_t *s = src;
    /* A regular frame starts with ZSTD_MAGICNUMBER (little-endian). Skippable
     * frames would "decompress" to nothing and are refused outright. */
    if (n < 4 || ((uint32_t)s[0] | (uint32_t)s[1] << 8 | (uint32_t)s[2] << 16 |
                  (uint32_t)s[3] << 24) != ZSTD_MAGICNUMBER)
        return gi_fail(err, GI_EPROTO, "%s: payload is not a zstd frame", what);
    unsigned long long size = ZSTD_getFrameContentSize(src, n);
    if (size == ZSTD_CONTENTSIZE_ERROR)
        return gi_fail(err, GI_EPROTO, "%s: zstd frame header is corrupt", what);
    if (size == ZSTD_CONTENTSIZE_UNKNOWN)
        return gi_fail(err, GI_EPROTO, "%s: zstd frame does not declare its content size",
                       what);
    if (size > max_size || size > SIZE_MAX)
        return gi_fail(err, GI_EPROTO,
                       "%s: zstd frame declares %llu decompressed bytes, over the limit %llu",
                       what, size, (unsigned long long)max_size);
    size_t csize = ZSTD_findFrameCompressedSize(src, n);
    if (ZSTD_isError(csize))
        return gi_fail(err, GI_EPROTO, "%s: zstd frame is truncated or corrupt: %s", what,
                       ZSTD_getErrorName(csize));
    if (csize != n)
        return gi_fail(err, GI_EPROTO, "%s: %zu bytes follow the zstd frame", what, n - csize);

    if (!dctx && !(dctx = ZSTD_createDCtx()))
        return gi_fail(err, GI_ENOMEM, "%s: cannot create a zstd decompression context", what);
    uint8_t *dst = gi_try_malloc((size_t)size, err, what);
    if (!dst)
        return -1;
    size_t r = ZSTD_decompressDCtx(dctx, dst, (size_t)size, src, n);
    if (ZSTD_isError(r)) {
        free(dst);
        return gi_fail(err, GI_EPROTO, "%s: zstd: %s", what, ZSTD_getErrorName(r));
    }
    if (r != size) {
        free(dst);
        return gi_fail(err, GI_EPROTO, "%s: zstd frame declared %llu bytes but produced %zu",
                       what, size, r);
    }
    gi_buf_free(out);
    out->data = dst;
    out->len = out->cap = (size_t)size;
    return 0;
}
