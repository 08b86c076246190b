/* gi_rawpeer: a misbehaving worker for tests. Connects to a coordinator's
 * worker port, optionally authenticates with the farm secret
 * ($GI_FARM_SECRET_FILE), then sends one bad frame and reports how the
 * coordinator answered.
 *
 *   gi_rawpeer ADDR MODE
 *   MODE: oversized | badcrc | unknown-type | garbage | result-first |
 *         oversized-result | unexpected | version, each also as auth-MODE
 *         (after authenticating)
 *
 * Exit status 0 if the coordinator refused (an ERROR frame, then the
 * connection closed), printing "refused: <its message>"; 1 otherwise. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_auth.h"
#include "gi_frame.h"
#include "gi_msg.h"
#include "gi_msg_ctrl.h"
#include "gi_net.h"
#include "gi_netio.h"

static int die(const char *what, const gi_error *err)
{
    fprintf(stderr, "gi_rawpeer: %s: %s\n", what, err ? err->msg : "");
    return 1;
}

/* A header for a payload of `len` bytes (the payload itself is not sent). */
static void send_header(int fd, uint16_t type, uint64_t len)
{
    uint8_t h[GI_FRAME_HEADER_SIZE];
    gi_frame_header_write(h, type, 0, "", 0);
    gi_le_put_u64(h + 12, len);
    gi_write_all(fd, h, sizeof h, NULL);
}

static void send_bad(int fd, const char *mode)
{
    if (strcmp(mode, "oversized") == 0) {
        send_header(fd, GI_MSG_HELLO, (uint64_t)1 << 30);
    } else if (strcmp(mode, "result-first") == 0) {
        send_header(fd, GI_MSG_RESULT, 1 << 20);
    } else if (strcmp(mode, "oversized-result") == 0) {
        send_header(fd, GI_MSG_RESULT, (uint64_t)64 << 20);
    } else if (strcmp(mode, "badcrc") == 0) {
        gi_buf b;
        gi_buf_init(&b);
        gi_frame_encode(&b, GI_MSG_HELLO, "12345678\0\0\0\0", 12, 0);
        b.data[GI_FRAME_HEADER_SIZE + 3] ^= 0x40; /* a payload bit flipped in transit */
        gi_write_all(fd, b.data, b.len, NULL);
        gi_buf_free(&b);
    } else if (strcmp(mode, "unknown-type") == 0) {
        uint8_t h[GI_FRAME_HEADER_SIZE];
        gi_frame_header_write(h, 99, 0, "", 0); /* well formed, CRC right, type unknown */
        gi_write_all(fd, h, sizeof h, NULL);
    } else if (strcmp(mode, "garbage") == 0) {
        const char g[] = "GET / HTTP/1.1\r\nHost: x\r\n\r\n";
        gi_write_all(fd, g, sizeof g - 1, NULL);
    } else if (strcmp(mode, "version") == 0) {
        /* A worker from the future: speaks only versions 3-4. */
        gi_msg_hello h;
        memset(&h, 0, sizeof h);
        h.proto_min = 3;
        h.proto_max = 4;
        h.name = "future";
        h.version = "9.0";
        h.procs = h.slots = h.cores = 1;
        gi_buf b;
        gi_buf_init(&b);
        gi_msg_hello_encode(&b, &h);
        gi_frame_send(fd, GI_MSG_HELLO, b.data, b.len, 0, NULL);
        gi_buf_free(&b);
    } else if (strcmp(mode, "unexpected") == 0) {
        gi_buf b;
        gi_buf_init(&b);
        gi_msg_asset_put_encode(&b, "0000000000000000000000000000000000000000000000000000000000000000", "", 0);
        gi_frame_send(fd, GI_MSG_ASSET_PUT, b.data, b.len, 0, NULL);
        gi_buf_free(&b);
    }
}

static int authenticate(int fd, gi_error *err)
{
    gi_buf secret;
    gi_buf_init(&secret);
    if (gi_secret_read(NULL, "GI_FARM_SECRET_FILE", "GI_FARM_SECRET", "farm secret", NULL, &secret,
                       err))
        return -1;
    uint8_t key[GI_AUTH_KEY_BYTES];
    gi_auth_key(&secret, key);
    gi_secret_free(&secret);
    gi_msg_hello h;
    memset(&h, 0, sizeof h);
    h.proto_min = GI_PROTO_MIN;
    h.proto_max = GI_PROTO_MAX;
    gi_auth_random(h.nonce, sizeof h.nonce);
    h.name = "rawpeer";
    h.version = "test";
    h.procs = h.slots = h.cores = 1;
    gi_buf hello, b;
    gi_buf_init(&hello);
    gi_buf_init(&b);
    gi_msg_hello_encode(&hello, &h);
    gi_frame f;
    gi_msg_challenge ch;
    int rc = gi_frame_send(fd, GI_MSG_HELLO, hello.data, hello.len, 0, err);
    if (rc == 0 && (rc = gi_frame_recv(fd, NULL, "coordinator", &f, err)) == 1) {
        rc = f.type == GI_MSG_CHALLENGE ? gi_msg_challenge_decode(&f.payload, &ch, err)
                                        : gi_fail(err, GI_EPROTO, "no CHALLENGE");
        gi_frame_free(&f);
    } else if (rc == 0) {
        rc = gi_fail(err, GI_EIO, "closed");
    }
    if (rc == 0) {
        uint8_t mac[GI_MSG_MAC_BYTES];
        gi_auth_worker_mac(key, ch.nonce, h.nonce, hello.data, hello.len, mac);
        gi_msg_auth_encode(&b, mac);
        rc = gi_frame_send(fd, GI_MSG_AUTH, b.data, b.len, 0, err);
    }
    if (rc == 0 && (rc = gi_frame_recv(fd, NULL, "coordinator", &f, err)) == 1) {
        rc = f.type == GI_MSG_WELCOME ? 0 : gi_fail(err, GI_EPROTO, "no WELCOME (%s)",
                                                     gi_msg_type_name(f.type));
        gi_frame_free(&f);
    } else if (rc == 0) {
        rc = gi_fail(err, GI_EIO, "closed");
    }
    gi_buf_free(&hello);
    gi_buf_free(&b);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: gi_rawpeer ADDR MODE\n");
        return 2;
    }
    const char *mode = argv[2];
    gi_error err;
    int fd = gi_net_connect(argv[1], 5.0, &err);
    if (fd < 0)
        return die("connect", &err);
    if (strncmp(mode, "auth-", 5) == 0) {
        if (authenticate(fd, &err))
            return die("authenticate", &err);
        mode += 5;
    }
    send_bad(fd, mode);
    /* The coordinator answers with ERROR (perhaps after a HEARTBEAT or
     * other frames an authenticated worker gets), then closes. */
    for (;;) {
        gi_frame f;
        int got = gi_frame_recv(fd, NULL, "coordinator", &f, &err);
        if (got <= 0) {
            fprintf(stderr, "gi_rawpeer: connection ended without an ERROR frame\n");
            return 1;
        }
        if (f.type == GI_MSG_ERROR) {
            gi_error e;
            if (gi_msg_error_decode(&f.payload, &e, &err) == 0)
                printf("refused: %s\n", e.msg);
            gi_frame_free(&f);
            break;
        }
        gi_frame_free(&f);
    }
    char c;
    ssize_t n = read(fd, &c, 1);
    close(fd);
    if (n != 0) {
        fprintf(stderr, "gi_rawpeer: the connection stayed open after ERROR\n");
        return 1;
    }
    return 0;
}
