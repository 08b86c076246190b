/* fuzz_ctrl: libFuzzer target for the farm's control message decoders
 * (HELLO, CHALLENGE, AUTH, WELCOME, HEARTBEAT / DRAIN task lists in both
 * forms, CANCEL).
 * The first byte picks the decoder, the rest is the payload. A payload
 * that decodes must encode back to the same bytes: every field is
 * explicit, nothing is dropped or defaulted. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_msg_ctrl.h"

static void same(const gi_buf *a, const gi_buf *b)
{
    if (a->len != b->len || (a->len && memcmp(a->data, b->data, a->len) != 0))
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
        gi_msg_hello m;
        if (gi_msg_hello_decode(&in, &m, &err) == 0) {
            gi_msg_hello_encode(&out, &m);
            same(&in, &out);
            gi_msg_hello_free(&m);
        }
        break;
    }
    case 1: {
        gi_msg_challenge m;
        if (gi_msg_challenge_decode(&in, &m, &err) == 0) {
            gi_msg_challenge_encode(&out, &m);
            same(&in, &out);
        }
        break;
    }
    case 2: {
        uint8_t mac[GI_MSG_MAC_BYTES];
        if (gi_msg_auth_decode(&in, mac, &err) == 0) {
            gi_msg_auth_encode(&out, mac);
            same(&in, &out);
        }
        break;
    }
    case 3: {
        gi_msg_welcome m;
        if (gi_msg_welcome_decode(&in, &m, &err) == 0) {
            gi_msg_welcome_encode(&out, &m);
            same(&in, &out);
        }
        break;
    }
    case 4:
    case 6: { /* a list in version 1's form, and with runs (protocol 2's HEARTBEAT) */
        int runs = data[0] % 7 == 6;
        gi_msg_tasklist m;
        if (gi_msg_tasklist_decode(&in, "HEARTBEAT message", runs, &m, &err) == 0) {
            gi_msg_tasklist_encode(&out, m.seq, m.refs, m.count, runs);
            same(&in, &out);
            gi_msg_tasklist_free(&m);
        }
        break;
    }
    default: {
        gi_msg_cancel m;
        if (gi_msg_cancel_decode(&in, &m, &err) == 0) {
            gi_msg_cancel_encode(&out, &m);
            same(&in, &out);
        }
        break;
    }
    }
    gi_buf_free(&in);
    gi_buf_free(&out);
    return 0;
}
