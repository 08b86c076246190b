/* Unit tests: the farm's control messages (handshake, heartbeat, drain,
 * cancel), worker authentication, secrets and tokens, per-connection frame
 * limits. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_auth.h"
#include "gi_frame.h"
#include "gi_msg.h"
#include "gi_msg_ctrl.h"
#include "gi_net.h"
#include "gi_test.h"

static gi_msg_hello sample_hello(void)
{
    gi_msg_hello h;
    memset(&h, 0, sizeof h);
    h.proto_min = 1;
    h.proto_max = 3;
    for (int i = 0; i < GI_MSG_NONCE_BYTES; i++)
        h.nonce[i] = (uint8_t)(7 * i + 1);
    h.name = "render-07";
    h.version = "0.1.0";
    h.procs = 8;
    h.slots = 12;
    h.cores = 16;
    h.memory = UINT64_C(68719476736);
    return h;
}

GI_TEST(test_msg_hello_roundtrip)
{
    gi_msg_hello h = sample_hello(), d;
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_hello_encode(&b, &h);
    gi_error err;
    GI_REQUIRE_OK(gi_msg_hello_decode(&b, &d, &err));
    GI_CHECK(d.proto_min == 1 && d.proto_max == 3);
    GI_CHECK(memcmp(d.nonce, h.nonce, GI_MSG_NONCE_BYTES) == 0);
    GI_CHECK(strcmp(d.name, "render-07") == 0 && strcmp(d.version, "0.1.0") == 0);
    GI_CHECK(d.procs == 8 && d.slots == 12 && d.cores == 16 && d.memory == h.memory);
    gi_msg_hello_free(&d);
    /* Every truncation and a trailing byte are refused. */
    for (size_t n = 0; n < b.len; n++) {
        gi_buf t = {b.data, n, n};
        GI_CHECK_MSG(gi_msg_hello_decode(&t, &d, &err) != 0, "prefix of %zu bytes accepted", n);
    }
    gi_buf_put_u8(&b, 0);
    GI_CHECK(gi_msg_hello_decode(&b, &d, &err) != 0);
    GI_CHECK(strstr(err.msg, "trailing") != NULL);
    gi_buf_free(&b);
}

GI_TEST(test_msg_hello_refusals)
{
    static const char *const what[] = {"empty name", "control character", "no processes",
                                       "slots < processes", "empty version range"};
    for (int c = 0; c < 5; c++) {
        gi_msg_hello h = sample_hello(), d;
        if (c == 0)
            h.name = "";
        if (c == 1)
            h.name = "evil\nlog line";
        if (c == 2)
            h.procs = 0;
        if (c == 3)
            h.slots = 4;
        if (c == 4)
            h.proto_min = 5;
        gi_buf b;
        gi_buf_init(&b);
        gi_msg_hello_encode(&b, &h);
        gi_error err;
        GI_CHECK_MSG(gi_msg_hello_decode(&b, &d, &err) != 0, "%s accepted", what[c]);
        GI_CHECK(strncmp(err.msg, "HELLO message", 13) == 0);
        gi_buf_free(&b);
    }
}

GI_TEST(test_msg_handshake_roundtrips)
{
    gi_error err;
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_challenge ch = {.proto = 1}, ch2;
    memset(ch.nonce, 0xab, sizeof ch.nonce);
    gi_msg_challenge_encode(&b, &ch);
    GI_REQUIRE_OK(gi_msg_challenge_decode(&b, &ch2, &err));
    GI_CHECK(ch2.proto == 1 && memcmp(ch2.nonce, ch.nonce, sizeof ch.nonce) == 0);

    uint8_t mac[GI_MSG_MAC_BYTES], mac2[GI_MSG_MAC_BYTES];
    for (int i = 0; i < GI_MSG_MAC_BYTES; i++)
        mac[i] = (uint8_t)i;
    gi_buf_reset(&b);
    gi_msg_auth_encode(&b, mac);
    GI_REQUIRE_OK(gi_msg_auth_decode(&b, mac2, &err));
    GI_CHECK(memcmp(mac, mac2, sizeof mac) == 0);
    b.len--;
    GI_CHECK(gi_msg_auth_decode(&b, mac2, &err) != 0);

    gi_msg_welcome w = {.worker_id = 42, .heartbeat_ms = 500, .lease_ms = 2000}, w2;
    memcpy(w.mac, mac, sizeof mac);
    gi_buf_reset(&b);
    gi_msg_welcome_encode(&b, &w);
    GI_REQUIRE_OK(gi_msg_welcome_decode(&b, &w2, &err));
    GI_CHECK(w2.worker_id == 42 && w2.heartbeat_ms == 500 && w2.lease_ms == 2000);
    /* A lease shorter than two heartbeats would expire on healthy workers. */
    w.lease_ms = 900;
    gi_buf_reset(&b);
    gi_msg_welcome_encode(&b, &w);
    GI_CHECK(gi_msg_welcome_decode(&b, &w2, &err) != 0);
    gi_buf_free(&b);
}

GI_TEST(test_msg_tasklist_and_cancel)
{
    gi_msg_taskref refs[3] = {{1, 2, 0, 0, 0}, {1, 7, 3, 0, 0}, {UINT64_MAX, 0, UINT32_MAX, 0, 0}};
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_tasklist_encode(&b, 99, refs, 3, 0);
    GI_CHECK(b.len == 12 + 3 * 20); /* version 1's form: no running flags */
    gi_msg_tasklist tl;
    gi_error err;
    GI_REQUIRE_OK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 0, &tl, &err));
    GI_CHECK(tl.seq == 99 && tl.count == 3);
    for (int i = 0; i < 3; i++)
        GI_CHECK(tl.refs[i].job_id == refs[i].job_id && tl.refs[i].task_id == refs[i].task_id &&
                 tl.refs[i].attempt == refs[i].attempt && !tl.refs[i].running &&
                 !tl.refs[i].run_ms);
    gi_msg_tasklist_free(&tl);
    /* Read as a list with runs, version 1's bytes do not fit. */
    GI_CHECK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 1, &tl, &err) != 0);
    /* A count the bytes cannot hold is refused before anything is allocated. */
    gi_buf_reset(&b);
    gi_buf_put_u64(&b, 1);
    gi_buf_put_u32(&b, 4000);
    GI_CHECK(gi_msg_tasklist_decode(&b, "DRAIN message", 0, &tl, &err) != 0);
    GI_CHECK(strstr(err.msg, "DRAIN message: 4000 task references") != NULL);
    gi_buf_reset(&b);
    gi_msg_tasklist_encode(&b, 0, NULL, 0, 0);
    GI_REQUIRE_OK(gi_msg_tasklist_decode(&b, "DRAIN message", 0, &tl, &err));
    GI_CHECK(tl.count == 0);
    gi_msg_tasklist_free(&tl);

    gi_msg_cancel c = {5, GI_MSG_ALL_TASKS}, c2;
    gi_buf_reset(&b);
    gi_msg_cancel_encode(&b, &c);
    GI_REQUIRE_OK(gi_msg_cancel_decode(&b, &c2, &err));
    GI_CHECK(c2.job_id == 5 && c2.task_id == GI_MSG_ALL_TASKS);
    gi_buf_free(&b);
}

/* Protocol 2's HEARTBEAT: each held task says whether it runs and for how
 * long; the coordinator counts task time limits from there. */
GI_TEST(test_msg_tasklist_runs)
{
    gi_msg_taskref refs[3] = {{1, 2, 0, 1, 1500}, {1, 7, 3, 0, 0}, {4, 5, 6, 1, UINT32_MAX}};
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_tasklist_encode(&b, 7, refs, 3, 1);
    GI_CHECK(b.len == 12 + 3 * 25);
    gi_msg_tasklist tl;
    gi_error err;
    GI_REQUIRE_OK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 1, &tl, &err));
    GI_CHECK(tl.seq == 7 && tl.count == 3);
    for (int i = 0; i < 3; i++)
        GI_CHECK(tl.refs[i].job_id == refs[i].job_id && tl.refs[i].task_id == refs[i].task_id &&
                 tl.refs[i].attempt == refs[i].attempt && tl.refs[i].running == refs[i].running &&
                 tl.refs[i].run_ms == refs[i].run_ms);
    gi_msg_tasklist_free(&tl);
    /* Read as version 1's form, the bytes do not fit. */
    GI_CHECK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 0, &tl, &err) != 0);
    /* A flag other than 0 or 1, and a queued task that has run, are refused
     * naming the reference. */
    size_t flag1 = 12 + 25 + 20; /* the second reference's running flag */
    b.data[flag1] = 2;
    GI_CHECK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 1, &tl, &err) != 0);
    GI_CHECK(strstr(err.msg, "HEARTBEAT message: task reference 1: running 2") != NULL);
    b.data[flag1] = 0;
    b.data[flag1 + 1] = 9;
    GI_CHECK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 1, &tl, &err) != 0);
    GI_CHECK(strstr(err.msg, "task reference 1: running 0, run_ms 9") != NULL);
    /* A queued task's run_ms is never sent, whatever the struct holds. */
    refs[1].run_ms = 5;
    gi_buf_reset(&b);
    gi_msg_tasklist_encode(&b, 7, refs, 3, 1);
    GI_REQUIRE_OK(gi_msg_tasklist_decode(&b, "HEARTBEAT message", 1, &tl, &err));
    GI_CHECK(tl.refs[1].run_ms == 0);
    gi_msg_tasklist_free(&tl);
    gi_buf_free(&b);
}

/* The version a coordinator picks: the highest both speak. */
GI_TEST(test_msg_proto_choose)
{
    GI_CHECK(gi_msg_proto_choose(1, 1) == 1);              /* an older worker */
    GI_CHECK(gi_msg_proto_choose(1, 2) == 2);              /* this build's */
    GI_CHECK(gi_msg_proto_choose(1, 9) == GI_PROTO_MAX);   /* a newer one that speaks ours */
    GI_CHECK(gi_msg_proto_choose(2, 2) == 2);
    GI_CHECK(gi_msg_proto_choose(3, 4) == 0);              /* none in common */
    GI_CHECK(gi_msg_proto_choose(0, 0) == 0);
    GI_CHECK(GI_PROTO_MIN <= GI_PROTO_RUNS && GI_PROTO_RUNS <= GI_PROTO_MAX);
}

/* A FAIL keeps its code: a host's full disk (GI_EHOST) must reach the
 * coordinator as such, or the task's attempts are spent on it. */
GI_TEST(test_msg_fail_keeps_host_disk_code)
{
    GI_CHECK(gi_disk_errcode(ENOSPC) == GI_EHOST && gi_disk_errcode(EDQUOT) == GI_EHOST &&
             gi_disk_errcode(EROFS) == GI_EHOST && gi_disk_errcode(EIO) == GI_EHOST);
    GI_CHECK(gi_disk_errcode(ENOENT) == GI_EIO && gi_disk_errcode(EACCES) == GI_EIO);
    gi_error why, err;
    gi_fail(&why, gi_disk_errcode(ENOSPC), "b0.f0.base: write: %s", strerror(ENOSPC));
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_fail_encode(&b, 3, 4, 1, &why);
    gi_msg_fail m;
    GI_REQUIRE_OK(gi_msg_fail_decode(&b, &m, &err));
    GI_CHECK(m.job_id == 3 && m.task_id == 4 && m.attempt == 1 && m.error.code == GI_EHOST);
    GI_CHECK(strcmp(m.error.msg, why.msg) == 0);
    /* A code from a newer build is an internal error, not a crash. */
    gi_buf_reset(&b);
    why.code = (gi_errcode)(GI_EHOST + 1);
    gi_msg_fail_encode(&b, 3, 4, 1, &why);
    GI_REQUIRE_OK(gi_msg_fail_decode(&b, &m, &err));
    GI_CHECK(m.error.code == GI_EINTERNAL);
    gi_buf_free(&b);
}

static void key_from(const char *s, uint8_t key[GI_AUTH_KEY_BYTES])
{
    gi_buf b = {(uint8_t *)s, strlen(s), strlen(s)};
    gi_auth_key(&b, key);
}

GI_TEST(test_auth_macs)
{
    uint8_t k1[32], k2[32], cn[32], wn[32], m1[32], m2[32];
    key_from("the farm secret, 32 bytes long..", k1);
    key_from("another farm's secret, not ours.", k2);
    gi_auth_random(cn, sizeof cn);
    gi_auth_random(wn, sizeof wn);
    GI_CHECK(memcmp(cn, wn, 32) != 0);
    const char hello[] = "hello payload";
    gi_auth_worker_mac(k1, cn, wn, hello, sizeof hello, m1);
    gi_auth_worker_mac(k1, cn, wn, hello, sizeof hello, m2);
    GI_CHECK(gi_auth_mac_equal(m1, m2));
    gi_auth_worker_mac(k2, cn, wn, hello, sizeof hello, m2); /* wrong secret */
    GI_CHECK(!gi_auth_mac_equal(m1, m2));
    gi_auth_worker_mac(k1, wn, cn, hello, sizeof hello, m2); /* nonces swapped */
    GI_CHECK(!gi_auth_mac_equal(m1, m2));
    gi_auth_worker_mac(k1, cn, wn, "hello payloaD", sizeof hello, m2); /* HELLO altered */
    GI_CHECK(!gi_auth_mac_equal(m1, m2));
    /* The coordinator's proof is not the worker's, even over the same bytes. */
    gi_auth_coord_mac(k1, cn, wn, 0, m2);
    GI_CHECK(!gi_auth_mac_equal(m1, m2));
    gi_auth_coord_mac(k1, wn, cn, 1, m1);
    gi_auth_coord_mac(k1, wn, cn, 2, m2); /* bound to the worker id */
    GI_CHECK(!gi_auth_mac_equal(m1, m2));
}

GI_TEST(test_token_compare)
{
    const char *t = "s3cret-token-value";
    gi_buf tok = {(uint8_t *)t, strlen(t), strlen(t)};
    GI_CHECK(gi_token_equal(&tok, t, strlen(t)));
    GI_CHECK(!gi_token_equal(&tok, t, strlen(t) - 1));
    GI_CHECK(!gi_token_equal(&tok, "s3cret-token-valuf", strlen(t)));
    GI_CHECK(!gi_token_equal(&tok, "", 0));
}

static void write_file(const char *path, const char *text, mode_t mode)
{
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
    chmod(path, mode);
}

GI_TEST(test_secret_read)
{
    char path[512];
    snprintf(path, sizeof path, "%s/secret", gi_test_tmpdir());
    gi_buf s;
    gi_buf_init(&s);
    gi_error err;
    write_file(path, "0123456789abcdef0123\n", 0600);
    GI_REQUIRE_OK(gi_secret_read(path, NULL, NULL, "farm secret", NULL, &s, &err));
    GI_CHECK(s.len == 20 && memcmp(s.data, "0123456789abcdef0123", 20) == 0);
    /* Readable by others: refused, and the message holds no secret byte. */
    chmod(path, 0644);
    GI_CHECK(gi_secret_read(path, NULL, NULL, "farm secret", NULL, &s, &err) != 0);
    GI_CHECK(strstr(err.msg, "chmod 600") && !strstr(err.msg, "0123456789"));
    /* systemd's credentials directory: a credential shows 0440 where ACLs
     * grant it to the service's user; others' bits are still refused. */
    char creds[512], cred[600];
    snprintf(creds, sizeof creds, "%s/credentials", gi_test_tmpdir());
    mkdir(creds, 0500);
    chmod(creds, 0700);
    snprintf(cred, sizeof cred, "%s/farm-secret", creds);
    write_file(cred, "0123456789abcdef0123\n", 0440);
    GI_CHECK(gi_secret_read(cred, NULL, NULL, "farm secret", NULL, &s, &err) != 0);
    setenv("CREDENTIALS_DIRECTORY", creds, 1);
    GI_REQUIRE_OK(gi_secret_read(cred, NULL, NULL, "farm secret", NULL, &s, &err));
    GI_CHECK(s.len == 20);
    chmod(cred, 0444);
    GI_CHECK(gi_secret_read(cred, NULL, NULL, "farm secret", NULL, &s, &err) != 0);
    chmod(path, 0640); /* not in the credentials directory */
    GI_CHECK(gi_secret_read(path, NULL, NULL, "farm secret", NULL, &s, &err) != 0);
    unsetenv("CREDENTIALS_DIRECTORY");
    write_file(path, "short\n", 0600);
    GI_CHECK(gi_secret_read(path, NULL, NULL, "farm secret", NULL, &s, &err) != 0);
    GI_CHECK(strstr(err.msg, "shorter than 16 bytes") != NULL);
    /* From a variable naming a file, then from the value itself, which is
     * then removed from the environment. */
    write_file(path, "file secret, long enough", 0600);
    setenv("GI_TEST_SECRET_FILE", path, 1);
    GI_REQUIRE_OK(gi_secret_read(NULL, "GI_TEST_SECRET_FILE", "GI_TEST_SECRET", "x", NULL, &s,
                                 &err));
    GI_CHECK(s.len == 24);
    unsetenv("GI_TEST_SECRET_FILE");
    setenv("GI_TEST_SECRET", "environment secret value", 1);
    GI_REQUIRE_OK(gi_secret_read(NULL, "GI_TEST_SECRET_FILE", "GI_TEST_SECRET", "x", NULL, &s,
                                 &err));
    GI_CHECK(s.len == 24 && memcmp(s.data, "environment", 11) == 0);
    GI_CHECK(getenv("GI_TEST_SECRET") == NULL);
    GI_CHECK(gi_secret_read(NULL, "GI_TEST_SECRET_FILE", "GI_TEST_SECRET", "API token",
                            "--token-file", &s, &err) != 0);
    /* It says how to give one: the option, the variables. */
    GI_CHECK_MSG(strstr(err.msg, "no API token: name its file with --token-file or "
                                 "GI_TEST_SECRET_FILE, or set GI_TEST_SECRET"),
                 "%s", err.msg);
    gi_secret_free(&s);
}

GI_TEST(test_frame_zero_limit_refuses_type)
{
    gi_frame_limits lim = gi_frame_limits_default();
    lim.max_payload[GI_MSG_RESULT] = 0;
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, NULL, "peer");
    gi_frame_decoder_set_limits(&d, &lim);
    gi_buf b;
    gi_buf_init(&b);
    gi_frame_encode(&b, GI_MSG_BYE, NULL, 0, 0);     /* empty: fine */
    gi_frame_encode(&b, GI_MSG_RESULT, NULL, 0, 0);  /* empty: passes, the caller decides */
    gi_frame_encode(&b, GI_MSG_RESULT, "x", 1, 0);   /* refused from its header */
    gi_frame_decoder_feed(&d, b.data, b.len);
    gi_frame f;
    gi_error err;
    GI_CHECK(gi_frame_decoder_next(&d, &f, &err) == 1 && f.type == GI_MSG_BYE);
    gi_frame_free(&f);
    GI_CHECK(gi_frame_decoder_next(&d, &f, &err) == 1 && f.type == GI_MSG_RESULT);
    gi_frame_free(&f);
    GI_CHECK(gi_frame_decoder_next(&d, &f, &err) == -1);
    GI_CHECK(strstr(err.msg, "RESULT frames are not accepted on this connection") != NULL);
    gi_frame_decoder_free(&d);
    gi_buf_free(&b);
}

/* A worker sends results uncompressed to a coordinator on its own host. */
GI_TEST(test_net_peer_is_loopback)
{
    int sv[2];
    GI_REQUIRE(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
    GI_CHECK(gi_net_peer_is_loopback(sv[0]) == 1);
    close(sv[0]);
    close(sv[1]);
    gi_error err;
    char bound[64];
    int l = gi_net_listen("127.0.0.1:0", bound, sizeof bound, &err);
    GI_REQUIRE_OK(l < 0 ? -1 : 0);
    int c = gi_net_connect(bound, 5.0, &err);
    GI_REQUIRE_OK(c < 0 ? -1 : 0);
    GI_CHECK(gi_net_peer_is_loopback(c) == 1);
    close(c);
    close(l);
    int p[2];
    GI_REQUIRE(pipe(p) == 0);
    GI_CHECK(gi_net_peer_is_loopback(p[0]) == 0); /* not a socket */
    close(p[0]);
    close(p[1]);
    /* Another host (TEST-NET-1, RFC 5737): a UDP connect sends nothing, but
     * needs a route, which a sandbox may lack. */
    int u = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons(9)};
    inet_pton(AF_INET, "192.0.2.1", &a.sin_addr);
    if (u >= 0 && connect(u, (struct sockaddr *)&a, sizeof a) == 0)
        GI_CHECK(gi_net_peer_is_loopback(u) == 0);
    if (u >= 0)
        close(u);
}

/* A connect nobody answers carries its errno (gi-worker tells "no gi-farmd
 * listening yet" by ECONNREFUSED, not by the message's words); the message
 * says it as before. Any other failure has no errno of its own. */
GI_TEST(test_net_connect_refused_carries_errno)
{
    gi_error err;
    char bound[64], want[128];
    int l = gi_net_listen("127.0.0.1:0", bound, sizeof bound, &err);
    GI_REQUIRE_OK(l < 0 ? -1 : 0);
    close(l); /* the port is free now: a connect there is refused */
    GI_CHECK(gi_net_connect(bound, 5.0, &err) == -1);
    GI_CHECK(err.code == GI_EIO && err.sys_errno == ECONNREFUSED);
    snprintf(want, sizeof want, "cannot connect to %s: %s", bound, strerror(ECONNREFUSED));
    GI_CHECK(strcmp(err.msg, want) == 0);
    gi_error_prefix(&err, "coordinator");
    GI_CHECK(err.sys_errno == ECONNREFUSED);
    gi_fail(&err, GI_EIO, "the session ended");
    GI_CHECK(err.sys_errno == 0);
    gi_fail_errno(&err, GI_EIO, ECONNREFUSED, "x");
    gi_error_clear(&err);
    GI_CHECK(err.sys_errno == 0 && err.code == GI_OK);
    GI_CHECK(gi_net_connect("127.0.0.1:notaport", 1.0, &err) == -1 && err.sys_errno == 0);
}
