/* gi_zstd: one-shot zstd compression for payloads, and a decompressor that
 * never trusts the sender's sizes.
 *
 * Only single frames with the content size in the frame header are accepted:
 * the declared size is checked against a limit before anything is allocated,
 * the output buffer is exactly that size, and the frame must fill it exactly.
 * That closes the "zip bomb" (a few bytes that expand to gigabytes) and
 * streams that never say how big they will get. */
#ifndef GI_ZSTD_H
#define GI_ZSTD_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

/* Level 1: result payloads are float and double arrays with noisy low
 * mantissa bits; a simulated pt result (per-pixel sums of 16 noisy samples)
 * came out 5.7% smaller at level 1 and at level 3 alike, and level 3 took
 * twice the CPU in a worker's relay, CPU taken from the renderers on the
 * same host. */
#define GI_ZSTD_LEVEL 1

/* Appends one zstd frame holding src[0..n) (content size recorded) to out.
 * Fails only if zstd itself fails (GI_EINTERNAL). */
int gi_zstd_compress(gi_buf *out, const void *src, size_t n, int level, gi_error *err);

/* Decompresses src[0..n), which must be exactly one zstd frame declaring a
 * content size <= max_size, into *out (an initialised gi_buf; its previous
 * bytes are freed and it ends up holding exactly the content). Refuses with
 * GI_EPROTO, messages prefixed by `what`: a non-zstd or skippable frame,
 * bytes after the frame, an undeclared or oversized content size, corrupt
 * data, or output shorter than declared. GI_ENOMEM if the allocation fails. */
int gi_zstd_decompress(gi_buf *out, const void *src, size_t n, uint64_t max_size,
                       const char *what, gi_error *err);

#endif
