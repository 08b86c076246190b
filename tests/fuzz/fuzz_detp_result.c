/* fuzz_detp_result: libFuzzer target for what detp decodes from workers:
 * photon batch results (dense and sparse forms) and animation frame results
 * (exact integer sums). The first byte picks the decoder. Any input must
 * decode or fail with GI_EPROTO; never crash, leak or hang. The check-only
 * decode (NULL sums, what the coordinator runs as a result arrives) must
 * agree with the real decode into zeroed sums (each vertex comes once, so
 * one result alone never overflows them). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "detp/detp_method.h"

#define VERTICES 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    gi_error err;
    gi_error_clear(&err);
    gi_reader r;
    gi_reader_init(&r, data + 1, size - 1, "fuzz");
    gi_reader check = r;
    gi_error check_err;
    int rc, check_rc;
    if (data[0] & 2) {
        int64_t sum[3 * VERTICES] = {0}, hits[VERTICES] = {0};
        detp_anim_result h;
        rc = detp_decode_anim(&r, VERTICES, &h, sum, hits, &err);
        check_rc = detp_decode_anim(&check, VERTICES, &h, NULL, NULL, &check_err);
    } else {
        double irr[3 * VERTICES] = {0};
        uint64_t hits[VERTICES] = {0};
        detp_batch_result h;
        rc = detp_decode_batch(&r, VERTICES, &h, irr, hits, &err);
        check_rc = detp_decode_batch(&check, VERTICES, &h, NULL, NULL, &check_err);
    }
    if (rc != 0 && (err.code != GI_EPROTO || strchr(err.msg, '\n') || !err.msg[0]))
        abort();
    if ((check_rc == 0) != (rc == 0))
        abort();
    return 0;
}
