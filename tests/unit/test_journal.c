/* Unit tests: the coordinator's journal (records, torn tails, damage,
 * durable appends, compaction). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_fs.h"
#include "gi_journal.h"
#include "gi_test.h"

#define HASH_A "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"

typedef struct seen {
    int n;
    gi_jrec_type types[16];
    uint64_t ids[16];
    char text[256];
    uint64_t merged;
    uint32_t end;
    char message[128];
    size_t manifest_count;
} seen;

static int collect(void *ctx, const gi_jrec *r, gi_error *err)
{
    seen *s = ctx;
    if (s->n < 16) {
        s->types[s->n] = r->type;
        s->ids[s->n] = r->job_id;
    }
    s->n++;
    if (r->type == GI_JREC_SUBMIT) {
        snprintf(s->text, sizeof s->text, "%s", r->text);
        s->manifest_count = r->manifest.count;
    }
    if (r->type == GI_JREC_CHECKPOINT)
        s->merged = r->merged;
    if (r->type == GI_JREC_END) {
        s->end = r->end;
        snprintf(s->message, sizeof s->message, "%s", r->message);
    }
    return 0;
}

/* A journal with SUBMIT, CHECKPOINT, END and PURGE records; *ends gets the
 * offset where each record ends. */
static void sample(gi_buf *b, size_t ends[4])
{
    gi_buf_put(b, "GIJ1", 4);
    gi_buf_put_u32(b, 1);
    gi_jrec r;
    gi_jrec_init(&r, GI_JREC_SUBMIT, 7);
    r.priority = 3;
    r.submitted = 1.5e9;
    r.file = "cornell.json";
    r.text = "{\"method\": \"pt\"}";
    gi_manifest_put(&r.manifest, "scene.json", HASH_A, 10);
    gi_jrec_encode(&r, b);
    gi_manifest_free(&r.manifest);
    ends[0] = b->len;
    gi_jrec_init(&r, GI_JREC_CHECKPOINT, 7);
    r.seq = 2;
    r.merged = 40;
    r.tasks = 96;
    gi_jrec_encode(&r, b);
    ends[1] = b->len;
    gi_jrec_init(&r, GI_JREC_END, 7);
    r.end = GI_JOB_END_FAILED;
    r.code = GI_EINVAL;
    r.message = "scene: bad mesh";
    r.when = 1.6e9;
    gi_jrec_encode(&r, b);
    ends[2] = b->len;
    gi_jrec_init(&r, GI_JREC_PURGE, 7);
    gi_jrec_encode(&r, b);
    ends[3] = b->len;
}

GI_TEST(test_journal_records_roundtrip)
{
    gi_buf b;
    gi_buf_init(&b);
    size_t ends[4];
    sample(&b, ends);
    seen s;
    memset(&s, 0, sizeof s);
    size_t valid, skipped;
    gi_error err;
    GI_REQUIRE(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == 0);
    GI_CHECK(s.n == 4 && valid == b.len);
    GI_CHECK(s.types[0] == GI_JREC_SUBMIT && s.types[1] == GI_JREC_CHECKPOINT &&
             s.types[2] == GI_JREC_END && s.types[3] == GI_JREC_PURGE);
    GI_CHECK(s.ids[3] == 7);
    GI_CHECK(strcmp(s.text, "{\"method\": \"pt\"}") == 0 && s.manifest_count == 1);
    GI_CHECK(s.merged == 40 && s.end == GI_JOB_END_FAILED);
    GI_CHECK(strcmp(s.message, "scene: bad mesh") == 0);
    gi_buf_free(&b);
}

static int keep_end(void *ctx, const gi_jrec *r, gi_error *err)
{
    (void)err;
    if (r->type == GI_JREC_END)
        *(gi_jrec *)ctx = *r; /* numbers only: its strings are freed after */
    return 0;
}

/* An END carries the run's summary (a restarted coordinator shows it); one
 * without (older journals) still reads, and so does a summary without the
 * tasks lost with their host (version 3); a summary out of range is damage. */
GI_TEST(test_journal_end_summary)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put(&b, "GIJ1", 4);
    gi_buf_put_u32(&b, 1);
    size_t head = b.len;
    gi_jrec r;
    gi_jrec_init(&r, GI_JREC_END, 3);
    r.end = GI_JOB_END_DONE;
    r.message = "";
    r.when = 1.7e9;
    r.has_summary = 1;
    r.started = 1.6e9;
    r.tasks = 96;
    r.merged = 96;
    r.retries = 2;
    r.rays = 123456789;
    r.samples = 4096;
    r.seconds = 12.5;
    r.fraction = 1;
    r.done = r.total = 4096;
    r.frame = 5;
    r.frames = 6;
    gi_jrec_encode(&r, &b);
    gi_jrec got;
    memset(&got, 0, sizeof got);
    size_t valid, skipped;
    gi_error err;
    GI_REQUIRE(gi_journal_parse(b.data, b.len, keep_end, &got, &valid, &skipped, &err) == 0);
    GI_CHECK(got.has_summary && got.started == 1.6e9 && got.tasks == 96 && got.merged == 96 &&
             got.retries == 2 && got.rays == 123456789 && got.samples == 4096 &&
             got.seconds == 12.5 && got.fraction == 1 && got.frame == 5 && got.frames == 6);
    GI_CHECK(!got.has_losses && got.losses == 0);
    b.len = head;
    r.has_losses = 1;
    r.losses = 17;
    gi_jrec_encode(&r, &b);
    size_t with_losses = b.len - head;
    memset(&got, 0, sizeof got);
    GI_REQUIRE(gi_journal_parse(b.data, b.len, keep_end, &got, &valid, &skipped, &err) == 0);
    GI_CHECK(got.has_losses && got.losses == 17 && got.retries == 2 && got.frames == 6);
    /* Encoded back the same, as read (what compaction writes). */
    gi_buf again;
    gi_buf_init(&again);
    got.message = (char *)""; /* keep_end kept numbers only; it was "" */
    gi_jrec_encode(&got, &again);
    GI_CHECK(again.len == with_losses && memcmp(again.data, b.data + head, again.len) == 0);
    gi_buf_free(&again);
    /* A merged count past the tasks: the record is damaged. */
    b.len = head;
    r.merged = 97;
    gi_jrec_encode(&r, &b);
    GI_CHECK(gi_journal_parse(b.data, b.len, keep_end, &got, &valid, &skipped, &err) != 0 &&
             valid == head);
    gi_buf_free(&b);
}

GI_TEST(test_journal_every_torn_tail)
{
    gi_buf b;
    gi_buf_init(&b);
    size_t ends[4];
    sample(&b, ends);
    /* A crash can stop an append after any byte: replay keeps exactly the
     * complete records before it. */
    for (size_t n = 8; n < b.len; n++) {
        seen s;
        memset(&s, 0, sizeof s);
        size_t valid, skipped;
        gi_error err;
        int rc = gi_journal_parse(b.data, n, collect, &s, &valid, &skipped, &err);
        int complete = 0;
        size_t want = 8;
        for (int i = 0; i < 4; i++)
            if (ends[i] <= n) {
                complete = i + 1;
                want = ends[i];
            }
        GI_CHECK_MSG(s.n == complete && valid == want, "at %zu bytes: %d records, valid %zu", n,
                     s.n, valid);
        GI_CHECK(rc == (want == n ? 0 : 1));
    }
    gi_buf_free(&b);
}

GI_TEST(test_journal_damage_and_bad_header)
{
    gi_buf b;
    gi_buf_init(&b);
    size_t ends[4];
    sample(&b, ends);
    /* A bit of the last record: a torn tail, cut there. */
    b.data[ends[2] + 9] ^= 1;
    seen s;
    memset(&s, 0, sizeof s);
    size_t valid, skipped;
    gi_error err;
    GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == 1);
    GI_CHECK(s.n == 3 && valid == ends[2] && skipped == 0);
    GI_CHECK_MSG(strstr(err.msg, "fails its CRC") != NULL, "%s", err.msg);
    /* Damaged records one after the other: the first is not followed by an
     * intact one, so the tail is cut there. */
    b.data[ends[1] + 9] ^= 1;
    memset(&s, 0, sizeof s);
    GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == 1);
    GI_CHECK(s.n == 2 && valid == ends[1] && skipped == 0);
    b.data[ends[0] + 14] ^= 1;
    memset(&s, 0, sizeof s);
    GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == 1);
    GI_CHECK(s.n == 1 && valid == ends[0] && skipped == 0);
    b.data[3] = '2';
    GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == -1);
    gi_buf_free(&b);
}

/* Bit rot in the middle (an intact record right after it) loses that
 * record only; the first record too. */
GI_TEST(test_journal_damaged_record_in_the_middle)
{
    gi_buf b;
    gi_buf_init(&b);
    size_t ends[4];
    sample(&b, ends);
    size_t starts[4] = {8, ends[0], ends[1], ends[2]};
    for (int k = 0; k < 3; k++) {
        for (int at = 0; at < 3; at++) { /* the type, the payload, the CRC */
            size_t byte = at == 0 ? starts[k] : at == 1 ? starts[k] + 14 : ends[k] - 1;
            b.data[byte] ^= 0x10;
            seen s;
            memset(&s, 0, sizeof s);
            size_t valid, skipped;
            gi_error err;
            int rc = gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err);
            GI_CHECK_MSG(rc == 0 && skipped == 1 && s.n == 3 && valid == b.len,
                         "record %d, byte %zu: rc %d, %zu skipped, %d read", k, byte, rc,
                         skipped, s.n);
            GI_CHECK(s.types[0] == (k == 0 ? GI_JREC_CHECKPOINT : GI_JREC_SUBMIT));
            GI_CHECK(s.types[2] == GI_JREC_PURGE);
            b.data[byte] ^= 0x10;
        }
    }
    /* Through the file: kept aside, reported as damage (the caller compacts). */
    char path[512];
    snprintf(path, sizeof path, "%s/journal-rot", gi_test_tmpdir());
    b.data[starts[1] + 14] ^= 1;
    gi_error err;
    GI_REQUIRE_OK(gi_write_file_atomic(path, b.data, b.len, &err));
    gi_journal j;
    seen s;
    memset(&s, 0, sizeof s);
    int damaged;
    GI_REQUIRE_OK(gi_journal_open(&j, path, collect, &s, &damaged, &err));
    GI_CHECK(damaged && s.n == 3 && s.types[1] == GI_JREC_END && j.size == b.len);
    gi_journal_close(&j);
    gi_buf_free(&b);
}

/* Job ids are in [1, 2^53 - 1]: the API's JSON numbers, and the next id
 * never wraps. A record with another id is damage. */
GI_TEST(test_journal_job_id_range)
{
    static const struct {
        uint64_t id;
        int ok;
    } cases[] = {{0, 0}, {1, 1}, {GI_JOB_ID_MAX, 1}, {GI_JOB_ID_MAX + 1, 0}, {UINT64_MAX, 0}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        gi_buf b;
        gi_buf_init(&b);
        gi_buf_put(&b, "GIJ1", 4);
        gi_buf_put_u32(&b, 3);
        gi_jrec r;
        gi_jrec_init(&r, GI_JREC_RETRY, cases[c].id);
        r.when = 1.7e9;
        gi_jrec_encode(&r, &b);
        size_t first = b.len;
        gi_jrec_init(&r, GI_JREC_PURGE, 5);
        gi_jrec_encode(&r, &b);
        seen s;
        memset(&s, 0, sizeof s);
        size_t valid, skipped;
        gi_error err;
        /* In the middle: skipped; last: a damaged tail. */
        int rc = gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err);
        GI_CHECK_MSG(rc == 0 && skipped == !cases[c].ok && s.n == 1 + cases[c].ok,
                     "id %llu: rc %d, %zu skipped", (unsigned long long)cases[c].id, rc, skipped);
        memset(&s, 0, sizeof s);
        rc = gi_journal_parse(b.data, first, collect, &s, &valid, &skipped, &err);
        GI_CHECK(rc == !cases[c].ok && s.n == cases[c].ok);
        if (!cases[c].ok)
            GI_CHECK_MSG(strstr(err.msg, "out of range") != NULL, "%s", err.msg);
        gi_buf_free(&b);
    }
}

GI_TEST(test_journal_file_append_replay_rewrite)
{
    char path[512];
    snprintf(path, sizeof path, "%s/journal", gi_test_tmpdir());
    unlink(path);
    gi_journal j;
    seen s;
    memset(&s, 0, sizeof s);
    int damaged;
    gi_error err;
    GI_REQUIRE_OK(gi_journal_open(&j, path, collect, &s, &damaged, &err));
    GI_CHECK(s.n == 0 && !damaged);
    gi_jrec r;
    for (uint64_t id = 1; id <= 3; id++) {
        gi_jrec_init(&r, GI_JREC_CHECKPOINT, id);
        r.merged = id;
        r.tasks = 10;
        GI_CHECK_OK(gi_journal_append(&j, &r, &err));
    }
    gi_journal_close(&j);
    /* A torn append: reported, the file kept aside, the tail dropped. */
    FILE *f = fopen(path, "ab");
    fwrite("\002\000\000\000\100", 1, 5, f);
    fclose(f);
    memset(&s, 0, sizeof s);
    GI_REQUIRE_OK(gi_journal_open(&j, path, collect, &s, &damaged, &err));
    GI_CHECK(s.n == 3 && damaged && s.merged == 3);
    /* Compaction: only what is given survives, and appends go on after it. */
    gi_jrec keep;
    gi_jrec_init(&keep, GI_JREC_CHECKPOINT, 9);
    keep.merged = 5;
    keep.tasks = 6;
    const gi_jrec *list[] = {&keep};
    GI_CHECK_OK(gi_journal_rewrite(&j, list, 1, &err));
    gi_jrec_init(&r, GI_JREC_PURGE, 9);
    GI_CHECK_OK(gi_journal_append(&j, &r, &err));
    gi_journal_close(&j);
    memset(&s, 0, sizeof s);
    GI_REQUIRE_OK(gi_journal_open(&j, path, collect, &s, &damaged, &err));
    GI_CHECK(s.n == 2 && !damaged && s.ids[0] == 9 && s.types[1] == GI_JREC_PURGE);
    gi_journal_close(&j);
}

GI_TEST(test_journal_retry_record_and_versions)
{
    /* The sample is a version 1 journal (no RETRY): still read. */
    gi_buf b;
    gi_buf_init(&b);
    size_t ends[4];
    sample(&b, ends);
    b.len = ends[2]; /* SUBMIT, CHECKPOINT, END */
    gi_jrec r;
    gi_jrec_init(&r, GI_JREC_RETRY, 7);
    r.when = 1.7e9;
    gi_jrec_encode(&r, &b);
    seen s;
    memset(&s, 0, sizeof s);
    size_t valid, skipped;
    gi_error err;
    GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == 0);
    GI_CHECK(s.n == 4 && s.types[3] == GI_JREC_RETRY && s.ids[3] == 7 && valid == b.len);
    /* RETRY records; END summaries; their losses; SUBMIT keys and FETCHED */
    for (uint8_t v = 2; v <= 5; v++) {
        b.data[4] = v;
        memset(&s, 0, sizeof s);
        GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == 0 &&
                 s.n == 4);
    }
    b.data[4] = 6; /* a later build's */
    GI_CHECK(gi_journal_parse(b.data, b.len, collect, &s, &valid, &skipped, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "version 6 is not supported") != NULL, "%s", err.msg);
    gi_buf_free(&b);
}

typedef struct keyed {
    int n;
    char key[80];
    int has_key;
    double fetched;
} keyed;

static int keep_key(void *ctx, const gi_jrec *r, gi_error *err)
{
    keyed *k = ctx;
    (void)err;
    k->n++;
    if (r->type == GI_JREC_SUBMIT) {
        k->has_key = r->key != NULL;
        snprintf(k->key, sizeof k->key, "%s", r->key ? r->key : "");
    }
    if (r->type == GI_JREC_FETCHED)
        k->fetched = r->when;
    return 0;
}

/* Version 5: a SUBMIT ends with its Idempotency-Key (one without, as
 * before, still reads: no key), and FETCHED records the first download of
 * a done job's outputs. A key that is not one, or a FETCHED time out of
 * range, is damage. */
GI_TEST(test_journal_submit_key_and_fetched)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put(&b, "GIJ1", 4);
    gi_buf_put_u32(&b, 5);
    size_t head = b.len;
    gi_jrec r;
    gi_jrec_init(&r, GI_JREC_SUBMIT, 4);
    r.file = "a.json";
    r.text = "{}";
    r.key = "0123456789abcdef-_ABCDEF";
    gi_jrec_encode(&r, &b);
    size_t keyed_len = b.len - head;
    gi_jrec_init(&r, GI_JREC_FETCHED, 4);
    r.when = 1.7e9;
    gi_jrec_encode(&r, &b);
    keyed k;
    memset(&k, 0, sizeof k);
    size_t valid, skipped;
    gi_error err;
    GI_REQUIRE(gi_journal_parse(b.data, b.len, keep_key, &k, &valid, &skipped, &err) == 0);
    GI_CHECK(k.n == 2 && k.has_key && strcmp(k.key, "0123456789abcdef-_ABCDEF") == 0);
    GI_CHECK(k.fetched == 1.7e9 && valid == b.len);
    /* Without a key: 4 bytes (the length) and the key shorter. */
    gi_buf plain;
    gi_buf_init(&plain);
    gi_jrec_init(&r, GI_JREC_SUBMIT, 4);
    r.file = "a.json";
    r.text = "{}";
    gi_jrec_encode(&r, &plain);
    GI_CHECK(plain.len + 4 + strlen("0123456789abcdef-_ABCDEF") == keyed_len);
    gi_buf_free(&plain);
    /* Keys that are not keys: too short, too long, a character outside. */
    static const char *bad[] = {"0123456789abcde", "0123456789abcdef0123456789abcdef"
                                "0123456789abcdef0123456789abcdef0", "0123456789abcdef!"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        GI_CHECK(!gi_submit_key_valid(bad[i]));
        b.len = head;
        gi_jrec_init(&r, GI_JREC_SUBMIT, 4);
        r.file = "a.json";
        r.text = "{}";
        r.key = (char *)bad[i];
        gi_jrec_encode(&r, &b);
        memset(&k, 0, sizeof k);
        GI_CHECK_MSG(gi_journal_parse(b.data, b.len, keep_key, &k, &valid, &skipped, &err) == 1 &&
                         k.n == 0 && valid == head,
                     "key \"%s\" read", bad[i]);
    }
    GI_CHECK(gi_submit_key_valid("0123456789abcdef") &&
             gi_submit_key_valid("0123456789abcdef0123456789abcdef"
                                 "0123456789abcdef0123456789abcdef"));
    static const double bad_when[] = {0, -1, 1.0 / 0.0};
    for (size_t i = 0; i < sizeof bad_when / sizeof bad_when[0]; i++) {
        b.len = head;
        gi_jrec_init(&r, GI_JREC_FETCHED, 4);
        r.when = bad_when[i];
        gi_jrec_encode(&r, &b);
        memset(&k, 0, sizeof k);
        GI_CHECK(gi_journal_parse(b.data, b.len, keep_key, &k, &valid, &skipped, &err) == 1 &&
                 k.n == 0);
        GI_CHECK_MSG(strstr(err.msg, "FETCHED") != NULL, "%s", err.msg);
    }
    gi_buf_free(&b);
}
