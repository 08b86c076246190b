/* fuzz_msg: libFuzzer target for the message payload decoders (JOB, TASK,
 * RESULT, FAIL, ASSET_NEED, ASSET_PUT, ERROR). The first byte picks the
 * decoder, the rest is the payload. A payload that decodes must encode back
 * to the same bytes (every field is explicit, nothing is dropped). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_msg.h"

static void same(const gi_buf *a, const uint8_t *b, size_t n)
{
    if (a->len != n || memcmp(a->data, b, n) != 0)
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    gi_buf in, out;
    gi_buf_init(&in);
    gi_buf_init(&out);
    gi_buf_put(&in, data + 1, size - 1);
    gi_error err;
    switch (data[0] % 7) {
    case 0: {
        gi_msg_job m;
        if (gi_msg_job_decode(&in, &m, &err) == 0) {
            gi_msg_job_free(&m);
        }
        break;
    }
    case 1: {
        gi_msg_task m;
        if (gi_msg_task_decode(&in, &m, &err) == 0) {
            gi_msg_task_encode(&out, m.job_id, &m.task);
            same(&out, in.data, in.len);
            gi_task_free(&m.task);
        }
        break;
    }
    case 2: {
        gi_msg_result m;
        if (gi_msg_result_decode(&in, &m, &err) == 0) {
            gi_msg_result_encode(&out, m.job_id, m.task_id, m.attempt, &m.stats, m.data.data,
                                 m.data.len);
            same(&out, in.data, in.len);
            gi_buf_free(&m.data);
        }
        break;
    }
    case 3: {
        gi_msg_fail m;
        gi_msg_fail_decode(&in, &m, &err);
        break;
    }
    case 4: {
        char hash[GI_HASH_HEX];
        if (gi_msg_asset_need_decode(&in, hash, &err) == 0) {
            gi_msg_asset_need_encode(&out, hash);
            same(&out, in.data, in.len);
        }
        break;
    }
    case 5: {
        char hash[GI_HASH_HEX];
        const uint8_t *p;
        size_t n;
        if (gi_msg_asset_put_decode(&in, hash, &p, &n, &err) == 0) {
            gi_msg_asset_put_encode(&out, hash, p, n);
            same(&out, in.data, in.len);
        }
        break;
    }
    default: {
        gi_error e;
        gi_msg_error_decode(&in, &e, &err);
        break;
    }
    }
    gi_buf_free(&in);
    gi_buf_free(&out);
    return 0;
}
