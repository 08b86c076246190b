/* Unit tests: RNG, buffers, paths, JSON validation, name indices. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gi_assets.h"
#include "gi_auth.h"
#include "gi_buf.h"
#include "gi_fs.h"
#include "gi_image.h"
#include "gi_json.h"
#include "gi_name_index.h"
#include "gi_rng.h"
#include "gi_test.h"

GI_TEST(test_rng_splitmix_reference_values)
{
    /* SplitMix64 seeded with 1234567 (the reference generator's published
     * first outputs): our Weyl + mix is the same sequence. */
    gi_rng r;
    r.state = 1234567;
    r.has_spare = 0;
    GI_CHECK(gi_rng_u64(&r) == 6457827717110365317ull);
    GI_CHECK(gi_rng_u64(&r) == 3203168211198807973ull);
    GI_CHECK(gi_rng_u64(&r) == 9817491932198370423ull);
}

GI_TEST(test_rng_neighbouring_streams_are_uncorrelated)
{
    /* Streams that differ by one in stream or sample index (adjacent pixels,
     * consecutive samples) must not be correlated. */
    for (int which = 0; which < 2; which++) {
        double sxy = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
        int n = 20000;
        for (int i = 0; i < n; i++) {
            gi_rng a, b;
            gi_rng_init(&a, 5, (uint64_t)i, 0);
            if (which == 0)
                gi_rng_init(&b, 5, (uint64_t)i + 1, 0);
            else
                gi_rng_init(&b, 5, (uint64_t)i, 1);
            for (int k = 0; k < 4; k++) {
                double x = gi_rng_float(&a), y = gi_rng_float(&b);
                sxy += x * y;
                sx += x;
                sy += y;
                sxx += x * x;
                syy += y * y;
            }
        }
        double m = 4.0 * n;
        double cov = sxy / m - (sx / m) * (sy / m);
        double corr = cov / sqrt((sxx / m - (sx / m) * (sx / m)) * (syy / m - (sy / m) * (sy / m)));
        GI_CHECK_MSG(fabs(corr) < 0.02, "correlation %g (case %d)", corr, which);
    }
}

GI_TEST(test_rng_streams_are_keyed_and_uniform)
{
    gi_rng a, b, c;
    gi_rng_init(&a, 7, 100, 3);
    gi_rng_init(&b, 7, 100, 3);
    gi_rng_init(&c, 7, 100, 4);
    int same = 1, differ = 0;
    for (int i = 0; i < 64; i++) {
        uint32_t x = gi_rng_u32(&a), y = gi_rng_u32(&b), z = gi_rng_u32(&c);
        same &= x == y;
        differ |= x != z;
    }
    GI_CHECK(same);
    GI_CHECK(differ);
    /* Uniformity: mean and variance of 1e6 floats, and the range. */
    gi_rng r;
    gi_rng_init(&r, 1, 2, 3);
    double s = 0, s2 = 0;
    int n = 1000000, out_of_range = 0;
    for (int i = 0; i < n; i++) {
        float u = gi_rng_float(&r);
        out_of_range += !(u >= 0.0f && u < 1.0f);
        s += u;
        s2 += (double)u * u;
    }
    GI_CHECK(out_of_range == 0);
    GI_CHECK_NEAR(s / n, 0.5, 0.002);
    GI_CHECK_NEAR(s2 / n - (s / n) * (s / n), 1.0 / 12.0, 0.001);
    uint32_t counts[10] = {0};
    for (int i = 0; i < 100000; i++)
        counts[gi_rng_below(&r, 10)]++;
    for (int i = 0; i < 10; i++)
        GI_CHECK_NEAR(counts[i], 10000, 500);
}

GI_TEST(test_buf_roundtrip_and_reader_limits)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_u8(&b, 0xab);
    gi_buf_put_u16(&b, 0x1234);
    gi_buf_put_u32(&b, 0xdeadbeefu);
    gi_buf_put_u64(&b, 0x0123456789abcdefull);
    gi_buf_put_f32(&b, -1.5f);
    gi_buf_put_f64(&b, 3.25);
    gi_buf_put_str(&b, "hello");
    gi_buf_put_blob(&b, "xyz", 3);
    /* Little-endian on the wire whatever the host. */
    GI_CHECK(b.data[1] == 0x34 && b.data[2] == 0x12);
    gi_reader r;
    gi_reader_init(&r, b.data, b.len, "test");
    GI_CHECK(gi_get_u8(&r) == 0xab);
    GI_CHECK(gi_get_u16(&r) == 0x1234);
    GI_CHECK(gi_get_u32(&r) == 0xdeadbeefu);
    GI_CHECK(gi_get_u64(&r) == 0x0123456789abcdefull);
    GI_CHECK(gi_get_f32(&r) == -1.5f);
    GI_CHECK(gi_get_f64(&r) == 3.25);
    char *s = gi_get_str(&r, 100);
    GI_CHECK(s && strcmp(s, "hello") == 0);
    free(s);
    size_t len;
    const uint8_t *p = gi_get_blob(&r, 100, &len);
    GI_CHECK(p && len == 3 && memcmp(p, "xyz", 3) == 0);
    gi_error err;
    GI_CHECK(gi_reader_finish(&r, &err) == 0);

    /* A string longer than its limit fails without allocating it. */
    gi_reader_init(&r, b.data, b.len, "test");
    gi_get(&r, NULL, 1 + 2 + 4 + 8 + 4 + 8);
    GI_CHECK(gi_get_str(&r, 4) == NULL);
    GI_CHECK(gi_reader_finish(&r, &err) == -1 && err.code == GI_EPROTO);
    /* A declared length beyond the data fails. */
    gi_buf c;
    gi_buf_init(&c);
    gi_buf_put_u64(&c, 1ull << 60);
    gi_reader_init(&r, c.data, c.len, "huge");
    GI_CHECK(gi_get_blob(&r, (size_t)-1, &len) == NULL);
    GI_CHECK(r.failed);
    /* Trailing bytes are an error. */
    gi_reader_init(&r, b.data, b.len, "trailing");
    gi_get_u8(&r);
    GI_CHECK(gi_reader_finish(&r, &err) == -1);
    GI_CHECK(strstr(err.msg, "trailing") != NULL);
    gi_buf_free(&b);
    gi_buf_free(&c);
}

GI_TEST(test_path_normalize)
{
    static const char *cases[][2] = {
        {"a/b/c", "a/b/c"},     {"a/./b", "a/b"},       {"a/../b", "b"},
        {"a/b/../../c", "c"},   {"../a", "../a"},       {"../../a/../b", "../../b"},
        {"/x/../y", "/y"},      {"/..", "/"},           {"a//b///c/", "a/b/c"},
        {".", "."},             {"a/..", "."},          {"./a/./b/.", "a/b"},
        {"scenes/x/../y.json", "scenes/y.json"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char *n = gi_path_normalize(cases[i][0]);
        GI_CHECK_MSG(strcmp(n, cases[i][1]) == 0, "normalize(%s) = %s, expected %s",
                     cases[i][0], n, cases[i][1]);
        free(n);
    }
}

GI_TEST(test_atomic_write_and_read_limits)
{
    gi_error err;
    char path[512];
    snprintf(path, sizeof path, "%s/atomic.txt", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_write_file_atomic(path, "hello", 5, &err));
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(path, 100, &b, &err));
    GI_CHECK(b.len == 5 && memcmp(b.data, "hello", 5) == 0);
    GI_CHECK(gi_read_file(path, 4, &b, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(gi_write_file_atomic("/nonexistent-dir/x", "a", 1, &err) == -1);
    gi_buf_free(&b);
}

/* An append the disk cuts short (here a file size limit, as a full disk
 * would) leaves the file as it was, not ending in half a record. */
GI_TEST(test_append_whole_or_nothing)
{
    char path[512];
    snprintf(path, sizeof path, "%s/append.log", gi_test_tmpdir());
    unlink(path);
    gi_error err;
    GI_REQUIRE_OK(gi_append_whole(path, "line 1\n", 7, &err));
    pid_t kid = fork();
    GI_REQUIRE(kid >= 0);
    if (kid == 0) {
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit lim = {.rlim_cur = 10, .rlim_max = RLIM_INFINITY};
        int cut = setrlimit(RLIMIT_FSIZE, &lim) == 0 &&
                  gi_append_whole(path, "line 2 is long\n", 15, &err) == -1;
        _exit(cut ? 0 : 1);
    }
    int status;
    GI_REQUIRE(waitpid(kid, &status, 0) == kid);
    GI_CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    GI_REQUIRE_OK(gi_append_whole(path, "line 3\n", 7, &err));
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(path, 100, &b, &err));
    GI_CHECK_MSG(b.len == 14 && memcmp(b.data, "line 1\nline 3\n", 14) == 0, "%.*s",
                 (int)b.len, (const char *)b.data);
    gi_buf_free(&b);
}

/* A FIFO named as a journal, checkpoint, image or secret file is refused at
 * once: open() used to wait for a writer forever. */
GI_TEST(test_fifo_is_refused_without_blocking)
{
    char path[512];
    snprintf(path, sizeof path, "%s/fifo", gi_test_tmpdir());
    unlink(path);
    GI_REQUIRE(mkfifo(path, 0600) == 0);
    alarm(20); /* a hang fails the test instead of the whole run */
    gi_error err;
    gi_buf b;
    gi_buf_init(&b);
    GI_CHECK(gi_read_file(path, 100, &b, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK_MSG(strstr(err.msg, path) && strstr(err.msg, "not a regular file"), "%s", err.msg);
    GI_CHECK(gi_secret_read(path, NULL, NULL, "farm secret", NULL, &b, &err) != 0);
    GI_CHECK_MSG(strstr(err.msg, "not a regular file"), "%s", err.msg);
    int w, h;
    unsigned char *rgb = NULL;
    GI_CHECK(gi_png_read(path, &w, &h, &rgb, &err) != 0 && err.code == GI_EINVAL);
    gi_image img;
    GI_CHECK(gi_exr_read(path, &img, &err) != 0 && err.code == GI_EINVAL);
    alarm(0);
    gi_buf_free(&b);
    unlink(path);
}

GI_TEST(test_temp_names_are_told_from_outputs)
{
    char *t = gi_temp_path("out/a.exr");
    GI_CHECK_MSG(gi_is_temp_name(t), "%s", t);
    free(t);
    GI_CHECK(gi_is_temp_name("a.exr.tmp-12-0"));
    /* Output names a job may give. */
    GI_CHECK(!gi_is_temp_name("a.tmp-1.exr"));
    GI_CHECK(!gi_is_temp_name("a.tmp-1-2.exr"));
    GI_CHECK(!gi_is_temp_name("a.tmp-"));
    GI_CHECK(!gi_is_temp_name("a.tmp--3"));
    GI_CHECK(!gi_is_temp_name("a.tmp-x-3"));
    GI_CHECK(!gi_is_temp_name("tmp-1-2"));
    GI_CHECK(!gi_is_temp_name("12"));
}

/* Temporary files of writers that are gone go; a live writer's and real
 * outputs stay. */
GI_TEST(test_stale_temp_files_are_removed)
{
    pid_t dead = fork();
    if (dead == 0)
        _exit(0);
    GI_REQUIRE(dead > 0 && waitpid(dead, NULL, 0) == dead);
    char dir[512], names[3][128], path[1024];
    snprintf(dir, sizeof dir, "%s/stale-temps", gi_test_tmpdir());
    gi_error err;
    GI_REQUIRE_OK(gi_mkdirs(dir, &err));
    snprintf(names[0], sizeof names[0], "a.exr.tmp-%ld-0", (long)dead);
    snprintf(names[1], sizeof names[1], "a.exr.tmp-%ld-1", (long)getpid());
    snprintf(names[2], sizeof names[2], "a.tmp-%ld-2.exr", (long)dead);
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        GI_REQUIRE_OK(gi_write_file_atomic(path, "x", 1, &err));
    }
    GI_CHECK(gi_remove_stale_temps(dir) == 1);
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        GI_CHECK_MSG((access(path, F_OK) == 0) == (i > 0), "%s", names[i]);
    }
}

static int parse_doc(const char *text, cJSON **out, gi_error *err)
{
    return gi_json_parse(text, strlen(text), "t.json", out, err);
}

GI_TEST(test_json_errors_name_file_and_field)
{
    gi_error err;
    cJSON *doc;
    GI_CHECK(parse_doc("{\"a\": 1,\n \"b\": }", &doc, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "t.json:2:") != NULL, "%s", err.msg);
    GI_CHECK(parse_doc("[1]", &doc, &err) == -1);
    GI_CHECK(parse_doc("{} x", &doc, &err) == -1);
    GI_CHECK(parse_doc("", &doc, &err) == -1);
    /* A NUL in a string would cut it short where a name is checked. */
    GI_CHECK(parse_doc("{\"name\": \"a\\u0000/../x\"}", &doc, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "t.json:1:12: a string holds a NUL") != NULL, "%s", err.msg);
    GI_CHECK(parse_doc("{\"name\":\n \"\\\\u0000\", \"k\\u0000\": 1}", &doc, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "t.json:2:15:") != NULL, "%s", err.msg); /* the key's, not "\\u0000" */
    GI_REQUIRE_OK(parse_doc("{\"name\": \"\\\\u0000 \\u0041\"}", &doc, &err));
    GI_CHECK(strcmp(cJSON_GetObjectItem(doc, "name")->valuestring, "\\u0000 A") == 0);
    cJSON_Delete(doc);

    GI_REQUIRE_OK(parse_doc("{\"n\": 1.5, \"i\": 3, \"s\": \"x\", \"big\": 1e999, "
                            "\"seed\": 9007199254740993, \"huge\": 5000000000000001, "
                            "\"v\": [1, 2], \"o\": {\"k\": true}, \"dup\": 1, \"dup\": 2}",
                            &doc, &err));
    gi_jv v = {"t.json", &err};
    double d = 0;
    int64_t i = 0;
    GI_CHECK(gi_jv_number(&v, doc, "", "n", 1, 0, 10, &d) == 0 && d == 1.5);
    GI_CHECK(gi_jv_int(&v, doc, "", "n", 1, 0, 10, &i) == -1);
    GI_CHECK_MSG(strstr(err.msg, "t.json: n: expected an integer") != NULL, "%s", err.msg);
    GI_CHECK(gi_jv_int(&v, doc, "", "i", 1, 0, 2, &i) == -1);
    GI_CHECK(strstr(err.msg, "out of range") != NULL);
    /* 2^53 + 1 reads as 2^53: the message must not name 9007199254740992. */
    GI_CHECK(gi_jv_int(&v, doc, "", "seed", 1, 0, ((int64_t)1 << 53) - 1, &i) == -1);
    GI_CHECK_MSG(strstr(err.msg, "t.json: seed: out of range [0, 9007199254740991] (and "
                               "integers of 2^53 or more are not exact in JSON)") != NULL,
                 "%s", err.msg);
    /* Exact, but printed short: 16 digits of priority help nobody. */
    GI_CHECK(gi_jv_int(&v, doc, "", "huge", 1, 1, 100, &i) == -1);
    GI_CHECK_MSG(strstr(err.msg, "t.json: huge: 5e+15 is out of range [1, 100]") != NULL, "%s",
                 err.msg);
    char num[32];
    GI_CHECK(strcmp(gi_fmt_count(num, 1e308), "1e+308") == 0);
    GI_CHECK(strcmp(gi_fmt_count(num, -123456789012345.0), "-123456789012345") == 0);
    GI_CHECK(gi_jv_int(&v, doc, "", "s", 1, 0, 2, &i) == -1);
    GI_CHECK(strstr(err.msg, "got a string") != NULL);
    GI_CHECK(gi_jv_number(&v, doc, "", "big", 1, -1e300, 1e300, &d) == -1);
    GI_CHECK(strstr(err.msg, "not finite") != NULL);
    GI_CHECK(gi_jv_number(&v, doc, "", "missing", 1, 0, 1, &d) == -1);
    GI_CHECK(strstr(err.msg, "missing: missing (required)") != NULL);
    d = 42;
    GI_CHECK(gi_jv_number(&v, doc, "", "missing", 0, 0, 1, &d) == 0 && d == 42);
    gi_vec3 v3;
    GI_CHECK(gi_jv_vec3(&v, doc, "", "v", 1, 0, 1, &v3) == -1);
    static const char *const allowed[] = {"n", "i", "s", "big", "seed", "huge", "v", "o", NULL};
    GI_CHECK(gi_jv_keys(&v, doc, "", allowed) == -1);
    GI_CHECK_MSG(strstr(err.msg, "dup: unknown key") != NULL, "%s", err.msg);
    static const char *const allowed2[] = {"n",    "i", "s", "big", "seed",
                                           "huge", "v", "o", "dup", NULL};
    GI_CHECK(gi_jv_keys(&v, doc, "", allowed2) == -1);
    GI_CHECK_MSG(strstr(err.msg, "dup: key appears twice") != NULL, "%s", err.msg);
    const cJSON *o;
    GI_CHECK(gi_jv_member_object(&v, doc, "", "o", 1, &o) == 0 && o);
    static const char *const okeys[] = {"x", NULL};
    GI_CHECK(gi_jv_keys(&v, o, "o", okeys) == -1);
    GI_CHECK_MSG(strstr(err.msg, "o.k: unknown key (expected one of: x)") != NULL, "%s", err.msg);
    cJSON_Delete(doc);
}

/* Every name added is found at its index through the table's growth, names
 * that share a prefix or differ in one byte are told apart, and a name never
 * added (or any name in an empty index) is not found. */
GI_TEST(test_name_index_finds_every_name)
{
    enum { N = 50000 };
    gi_name_index x;
    gi_name_index_init(&x);
    GI_CHECK(gi_name_index_find(&x, "a") == -1 && gi_name_index_find(&x, "") == -1);
    char (*names)[16] = malloc(N * sizeof *names);
    GI_REQUIRE(names);
    for (int i = 0; i < N; i++) {
        snprintf(names[i], sizeof names[i], "n%d", i);
        gi_name_index_add(&x, names[i], (uint32_t)(N - 1 - i));
    }
    GI_CHECK(x.count == N && x.cap >= 2 * (size_t)N);
    int wrong = 0;
    for (int i = 0; i < N; i++)
        wrong += gi_name_index_find(&x, names[i]) != N - 1 - i;
    GI_CHECK_MSG(wrong == 0, "%d names found at the wrong index", wrong);
    GI_CHECK(gi_name_index_find(&x, "n") == -1 && gi_name_index_find(&x, "n50000") == -1 &&
             gi_name_index_find(&x, "n1x") == -1 && gi_name_index_find(&x, "") == -1);
    gi_name_index_free(&x);
    GI_CHECK(x.count == 0 && gi_name_index_find(&x, "n1") == -1);
    free(names);
}

GI_TEST(test_name_index_forgets_names)
{
    enum { N = 3000 };
    gi_name_index x;
    gi_name_index_init(&x);
    GI_CHECK(gi_name_index_remove(&x, "a") == 0);
    char (*names)[16] = malloc(N * sizeof *names);
    GI_REQUIRE(names);
    for (int i = 0; i < N; i++) {
        snprintf(names[i], sizeof names[i], "k%d", i);
        gi_name_index_add(&x, names[i], (uint32_t)i);
    }
    /* Every third name, in an order that wraps around the table's end. */
    int removed = 0;
    for (int i = N - 1; i >= 0; i -= 3)
        removed += gi_name_index_remove(&x, names[i]);
    GI_CHECK(removed == N / 3 && x.count == (size_t)(N - N / 3));
    GI_CHECK(gi_name_index_remove(&x, names[N - 1]) == 0 && gi_name_index_remove(&x, "k") == 0);
    int wrong = 0;
    for (int i = 0; i < N; i++) {
        int64_t want = (N - 1 - i) % 3 == 0 ? -1 : i;
        wrong += gi_name_index_find(&x, names[i]) != want;
    }
    GI_CHECK_MSG(wrong == 0, "%d names wrong after removals", wrong);
    /* Removed names come back with new entries. */
    for (int i = N - 1; i >= 0; i -= 3)
        gi_name_index_add(&x, names[i], (uint32_t)(i + N));
    wrong = 0;
    for (int i = 0; i < N; i++)
        wrong += gi_name_index_find(&x, names[i]) != ((N - 1 - i) % 3 == 0 ? i + N : i);
    GI_CHECK_MSG(wrong == 0, "%d names wrong after adding them again", wrong);
    gi_name_index_free(&x);
    free(names);
}

GI_TEST(test_manifest_and_store_look_up_many_files)
{
    enum { N = 5000 };
    gi_manifest m;
    gi_manifest_init(&m);
    gi_asset_store *s = gi_asset_store_new();
    char name[32], hash[GI_HASH_HEX];
    for (int i = 0; i < N; i++) {
        snprintf(name, sizeof name, "meshes/m%d.obj", i);
        gi_hash_hex(name, strlen(name), hash);
        gi_manifest_put(&m, name, hash, (uint64_t)i);
        gi_asset_store_put(s, hash, name, strlen(name));
    }
    GI_REQUIRE(m.count == N && gi_asset_store_count(s) == N);
    int wrong = 0;
    for (int i = 0; i < N; i++) {
        snprintf(name, sizeof name, "meshes/m%d.obj", i);
        gi_hash_hex(name, strlen(name), hash);
        const gi_manifest_entry *e = gi_manifest_find(&m, name);
        const gi_buf *b = gi_asset_store_get(s, hash);
        wrong += !e || e->size != (uint64_t)i || strcmp(e->hash, hash) != 0 ||
                 !gi_manifest_has_hash(&m, hash) || !b || b->len != strlen(name) ||
                 memcmp(b->data, name, b->len) != 0;
    }
    GI_CHECK_MSG(wrong == 0, "%d files not found as put", wrong);
    /* A name given new bytes: its old hash is gone, unless another name has it. */
    char h0[GI_HASH_HEX], h1[GI_HASH_HEX];
    gi_hash_hex("meshes/m0.obj", 13, h0);
    gi_hash_hex("meshes/m1.obj", 13, h1);
    gi_manifest_put(&m, "meshes/m0.obj", h1, 7);
    GI_CHECK(!gi_manifest_has_hash(&m, h0) && gi_manifest_has_hash(&m, h1));
    GI_CHECK(gi_manifest_find(&m, "meshes/m0.obj")->size == 7 && m.count == N);
    gi_manifest_put(&m, "meshes/m1.obj", h0, 1);
    GI_CHECK(gi_manifest_has_hash(&m, h0) && gi_manifest_has_hash(&m, h1));
    /* The store forgets what is removed, keeps the rest. */
    GI_CHECK(gi_asset_store_remove(s, h0) == 1 && gi_asset_store_remove(s, h0) == 0);
    GI_CHECK(!gi_asset_store_get(s, h0) && gi_asset_store_get(s, h1));
    GI_CHECK(gi_asset_store_count(s) == N - 1);
    for (int i = 2; i < N; i += 2) {
        snprintf(name, sizeof name, "meshes/m%d.obj", i);
        gi_hash_hex(name, strlen(name), hash);
        GI_CHECK(gi_asset_store_remove(s, hash) == 1);
    }
    wrong = 0;
    for (int i = 1; i < N; i++) {
        snprintf(name, sizeof name, "meshes/m%d.obj", i);
        gi_hash_hex(name, strlen(name), hash);
        const gi_buf *b = gi_asset_store_get(s, hash);
        wrong += i % 2 ? !b || memcmp(b->data, name, b->len) != 0 : b != NULL;
    }
    GI_CHECK_MSG(wrong == 0, "%d files wrong in the store after removals", wrong);
    gi_asset_store_free(s);
    gi_manifest_free(&m);
}
