/* fuzz_detp_result: libFuzzer target for what detp decodes from workers:
 * photon batch results (dense and sparse forms) and animation frame results
 * (exact integer sums). The first byte picks the decoder (bit 1), and for
 * animation results the bound on a value (bit 2: INT64_MAX / 3, as a frame
 * of 3 batches has, else none). Any input must
 * decode or fail with GI_EPROTO; never crash, leak or hang. The check-only
 * decode (NULL sums: the result's form alone) must agree with the real
 * decode into zeroed sums (each vertex comes once, so one result alone never
 * overflows them); against totals near the limits, the decode that only
 * reads them (the coordinator's check as a result arrives), with or without
 * a bound on them, must agree with the one that adds, and an add that fails
 * must leave the totals as they were. */
#include <float.h>
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
        int64_t max = data[0] & 4 ? INT64_MAX / 3 : INT64_MAX;
        int64_t sum[3 * VERTICES] = {0}, hits[VERTICES] = {0};
        detp_anim_result h;
        rc = detp_decode_anim(&r, VERTICES, max, &h, sum, hits, 1, &err);
        check_rc = detp_decode_anim(&check, VERTICES, max, &h, NULL, NULL, 0, &check_err);
        for (size_t i = 0; rc && i < VERTICES; i++)
            if (sum[3 * i] || sum[3 * i + 1] || sum[3 * i + 2] || hits[i])
                abort(); /* a refused add leaves the totals as they were */
        /* Against totals near both limits: the pass that only reads them
         * says exactly whether the one that adds succeeds. */
        int64_t near[3 * VERTICES], near_hits[VERTICES];
        for (size_t i = 0; i < 3 * VERTICES; i++)
            near[i] = i & 1 ? INT64_MIN + (int64_t)i : INT64_MAX - (int64_t)i;
        for (size_t i = 0; i < VERTICES; i++)
            near_hits[i] = INT64_MAX - (int64_t)i;
        gi_reader a, b;
        gi_reader_init(&a, data + 1, size - 1, "fuzz");
        b = a;
        int64_t kept[3 * VERTICES], kept_hits[VERTICES];
        memcpy(kept, near, sizeof kept);
        memcpy(kept_hits, near_hits, sizeof kept_hits);
        int only_read =
            detp_decode_anim(&a, VERTICES, max, &h, near, near_hits, 0, &check_err);
        if (memcmp(kept, near, sizeof kept) || memcmp(kept_hits, near_hits, sizeof kept_hits))
            abort(); /* only read */
        /* The coordinator's check reads the totals only for values that
         * could take one beyond their bound out of range: the same answer,
         * against these totals and against ones of a middling bound. */
        int64_t mid[3 * VERTICES] = {0}, mid_hits[VERTICES] = {0};
        for (size_t i = 0; i < 3 * VERTICES; i += 5)
            mid[i] = i & 2 ? -((int64_t)1 << 62) - (int64_t)i : ((int64_t)1 << 62) + (int64_t)i;
        mid_hits[3] = (int64_t)1 << 61;
        for (int k = 0; k < 2; k++) {
            int64_t *s = k ? mid : near, *hs = k ? mid_hits : near_hits;
            gi_reader c, d;
            gi_reader_init(&c, data + 1, size - 1, "fuzz");
            d = c;
            uint64_t bound = detp_anim_bound(s, hs, VERTICES);
            if ((detp_anim_decode(&c, VERTICES, max, &h, s, hs, bound, NULL, &check_err) == 0) !=
                (detp_anim_decode(&d, VERTICES, max, &h, s, hs, INT64_MAX, NULL, &check_err) == 0))
                abort();
        }
        int added = detp_decode_anim(&b, VERTICES, max, &h, near, near_hits, 1, &check_err);
        if ((only_read == 0) != (added == 0))
            abort();
        /* A refused add leaves the totals as they were. */
        if (added && (memcmp(kept, near, sizeof kept) ||
                      memcmp(kept_hits, near_hits, sizeof kept_hits)))
            abort();
    } else {
        double irr[3 * VERTICES] = {0};
        uint64_t hits[VERTICES] = {0};
        detp_batch_result h;
        double bound = size & 1 ? FLT_MAX : 1e3; /* a job's share of the floats, or less */
        rc = detp_decode_batch(&r, VERTICES, bound, &h, irr, hits, &err);
        check_rc = detp_decode_batch(&check, VERTICES, bound, &h, NULL, NULL, &check_err);
    }
    if (rc != 0 && (err.code != GI_EPROTO || strchr(err.msg, '\n') || !err.msg[0]))
        abort();
    if ((check_rc == 0) != (rc == 0))
        abort();
    return 0;
}
