/* Unit tests: job submission bodies, the HTTP client's parsers, farm URLs,
 * the worker's asset cache, option values. */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "gi_args.h"
#include "gi_asset_cache.h"
#include "gi_farm_submit.h"
#include "gi_http_client.h"
#include "gi_test.h"

#define H1 "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef"

GI_TEST(test_submission_forms)
{
    gi_farm_submission s;
    gi_error err;
    const char *obj = "{\"job\": {\"scene\": \"s.json\", \"method\": \"pt\", \"seed\": 9007199254740992,"
                      " \"image\": {\"exposure\": 0.1}, \"a\": [\"\\u00e9\\n\", true, null]},"
                      " \"assets\": {\"s.json\": \"" H1 "\"}, \"priority\": 7}";
    GI_REQUIRE_OK(gi_farm_submission_parse(obj, strlen(obj), &s, &err));
    GI_CHECK(s.priority == 7 && strcmp(s.file, "job.json") == 0);
    GI_CHECK(s.manifest.count == 1 && strcmp(s.manifest.entries[0].hash, H1) == 0);
    /* The object is printed back exactly (2^53 keeps every digit; 0.1
     * parses back to the same double). */
    GI_CHECK(strstr(s.text, "\"seed\":9007199254740992") != NULL);
    cJSON *back = cJSON_Parse(s.text);
    GI_REQUIRE(back != NULL);
    double e = cJSON_GetObjectItem(cJSON_GetObjectItem(back, "image"), "exposure")->valuedouble;
    GI_CHECK(e == 0.1);
    GI_CHECK(strcmp(cJSON_GetArrayItem(cJSON_GetObjectItem(back, "a"), 0)->valuestring, "\xc3\xa9\n") == 0);
    cJSON_Delete(back);
    gi_farm_submission_free(&s);

    /* gi submit's form carries the file's text verbatim. */
    gi_manifest m;
    gi_manifest_init(&m);
    gi_manifest_put(&m, "../meshes/a b.obj", H1, 3);
    gi_buf b;
    gi_buf_init(&b);
    const char *text = "{\n  \"scene\": \"x\",\t\"method\": \"pt\" }\n";
    gi_farm_submission_build(&b, "my job.json", text, &m, 1000);
    GI_REQUIRE_OK(gi_farm_submission_parse((const char *)b.data, b.len, &s, &err));
    GI_CHECK(strcmp(s.text, text) == 0 && strcmp(s.file, "my job.json") == 0);
    GI_CHECK(s.priority == 1000 && gi_manifest_find(&s.manifest, "../meshes/a b.obj"));
    gi_farm_submission_free(&s);
    gi_manifest_free(&m);
    gi_buf_free(&b);
}

GI_TEST(test_submission_refusals)
{
    const char *bad[][2] = {
        {"{\"assets\": {}}", "exactly one of"},
        {"{\"job\": {}, \"job_text\": \"{}\", \"assets\": {}}", "exactly one of"},
        {"{\"job\": {}}", "assets: is required"},
        {"{\"job\": {}, \"assets\": []}", "expected an object"},
        {"{\"job\": {}, \"assets\": {\"a\": \"ABC\"}}", "assets.a: expected an asset hash"},
        {"{\"job\": {}, \"assets\": {\"a\": \"" H1 "\", \"a\": \"" H1 "\"}}", "appears twice"},
        {"{\"job\": {}, \"assets\": {}, \"priority\": 0}", "priority"},
        {"{\"job\": {}, \"assets\": {}, \"priority\": 1001}", "priority"},
        {"{\"job\": {}, \"assets\": {}, \"user\": \"x\"}", "unknown key"},
        {"{\"job\": {}, \"assets\": {}, \"file\": \"a\\nb\"}", "printable"},
        {"[1]", "must be a JSON object"},
        {"{\"job\": {}, \"assets\": {}} trailing", "unexpected text"},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(bad); i++) {
        gi_farm_submission s;
        gi_error err;
        GI_CHECK_MSG(gi_farm_submission_parse(bad[i][0], strlen(bad[i][0]), &s, &err) != 0,
                     "accepted: %s", bad[i][0]);
        GI_CHECK_MSG(strstr(err.msg, bad[i][1]) != NULL, "%s: \"%s\" lacks \"%s\"", bad[i][0],
                     err.msg, bad[i][1]);
    }
}

GI_TEST(test_http_head_parse)
{
    const char *ok = "HTTP/1.1 201 Created\r\nContent-Type: application/json\r\n"
                     "content-length: 12\r\n\r\n{\"id\": 3}...";
    gi_http_head h;
    size_t n;
    gi_error err;
    GI_REQUIRE(gi_http_parse_head(ok, strlen(ok), &h, &n, &err) == 1);
    GI_CHECK(h.status == 201 && h.content_length == 12 && !h.chunked);
    GI_CHECK(strncmp(ok + n, "{\"id\"", 5) == 0);
    /* Incomplete: more bytes needed (every prefix of the head). */
    for (size_t k = 0; k + 1 < n; k++)
        GI_CHECK(gi_http_parse_head(ok, k, &h, &n, &err) == 0);
    const char *bad[] = {"HTTP/2 200 OK\r\n\r\n", "HTTP/1.1 2x0 OK\r\n\r\n",
                         "HTTP/1.1 200 OK\r\nno colon\r\n\r\n",
                         "HTTP/1.1 200 OK\r\nContent-Length: -1\r\n\r\n",
                         "HTTP/1.1 200 OK\r\nTransfer-Encoding: gzip\r\n\r\n"};
    for (size_t i = 0; i < GI_ARRAY_LEN(bad); i++)
        GI_CHECK_MSG(gi_http_parse_head(bad[i], strlen(bad[i]), &h, &n, &err) == -1, "accepted %s",
                     bad[i]);
    const char *ch = "HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n";
    GI_REQUIRE(gi_http_parse_head(ch, strlen(ch), &h, &n, &err) == 1);
    GI_CHECK(h.chunked && h.content_length == -1);
}

GI_TEST(test_http_dechunk)
{
    gi_buf b;
    gi_buf_init(&b);
    const char *body = "5;ext=1\r\nhello\r\nB\r\n, world!!!!\r\n0\r\nTrailer: x\r\n\r\n";
    gi_buf_put(&b, body, strlen(body));
    gi_error err;
    GI_REQUIRE_OK(gi_http_dechunk(&b, &err));
    GI_CHECK(b.len == 16 && memcmp(b.data, "hello, world!!!!", 16) == 0);
    const char *bad[] = {"5\r\nhel", "5\r\nhelloXX0\r\n\r\n", "zz\r\n", "5\r\nhello\r\n",
                         "fffffffffffffffff\r\n"};
    for (size_t i = 0; i < GI_ARRAY_LEN(bad); i++) {
        gi_buf_reset(&b);
        gi_buf_put(&b, bad[i], strlen(bad[i]));
        GI_CHECK_MSG(gi_http_dechunk(&b, &err) != 0, "accepted %s", bad[i]);
    }
    gi_buf_free(&b);
}

GI_TEST(test_http_url_parse)
{
    gi_http_url u;
    gi_error err;
    GI_REQUIRE_OK(gi_http_url_parse("http://farm.example:7070/prefix/", &u, &err));
    GI_CHECK(strcmp(u.hostport, "farm.example:7070") == 0 && strcmp(u.prefix, "/prefix") == 0);
    gi_http_url_free(&u);
    GI_REQUIRE_OK(gi_http_url_parse("http://[::1]", &u, &err));
    GI_CHECK(strcmp(u.hostport, "[::1]:80") == 0 && strcmp(u.prefix, "") == 0);
    gi_http_url_free(&u);
    GI_CHECK(gi_http_url_parse("https://farm:7070", &u, &err) != 0);
    GI_CHECK(gi_http_url_parse("http:///x", &u, &err) != 0);
}

GI_TEST(test_asset_cache)
{
    char dir[512];
    snprintf(dir, sizeof dir, "%s/cache", gi_test_tmpdir());
    gi_asset_cache c;
    gi_error err;
    GI_REQUIRE_OK(gi_asset_cache_open(&c, dir, 3000, &err));
    char h[3][GI_HASH_HEX];
    char data[3][1200];
    for (int i = 0; i < 3; i++) {
        memset(data[i], 'a' + i, sizeof data[i]);
        gi_hash_hex(data[i], sizeof data[i], h[i]);
    }
    gi_buf b;
    gi_buf_init(&b);
    GI_CHECK(gi_asset_cache_get(&c, h[0], &b, &err) == 0);
    GI_CHECK_OK(gi_asset_cache_put(&c, h[0], data[0], sizeof data[0], &err));
    GI_CHECK(gi_asset_cache_get(&c, h[0], &b, &err) == 1 && b.len == sizeof data[0]);
    /* Damaged on disk: noticed, deleted, reported as missing. */
    char p[1024];
    snprintf(p, sizeof p, "%s/%.2s/%s", dir, h[0], h[0]);
    FILE *f = fopen(p, "r+b");
    fputc('z', f);
    fclose(f);
    GI_CHECK(gi_asset_cache_get(&c, h[0], &b, &err) == 0);
    GI_CHECK(access(p, F_OK) != 0);
    /* Over the bound: the least recently used go first. */
    GI_CHECK_OK(gi_asset_cache_put(&c, h[0], data[0], sizeof data[0], &err));
    struct timespec old[2] = {{1000, 0}, {1000, 0}};
    utimensat(AT_FDCWD, p, old, 0);
    GI_CHECK_OK(gi_asset_cache_put(&c, h[1], data[1], sizeof data[1], &err));
    GI_CHECK_OK(gi_asset_cache_put(&c, h[2], data[2], sizeof data[2], &err));
    GI_CHECK(gi_asset_cache_get(&c, h[0], &b, &err) == 0);
    GI_CHECK(gi_asset_cache_get(&c, h[2], &b, &err) == 1);
    GI_CHECK(c.bytes <= 3000 && c.evicted >= 1);
    gi_asset_cache_close(&c);
    /* A cache reopened knows its size. */
    GI_REQUIRE_OK(gi_asset_cache_open(&c, dir, 3000, &err));
    GI_CHECK(c.bytes > 0 && c.bytes <= 3000);
    gi_asset_cache_close(&c);
    gi_buf_free(&b);
}

GI_TEST(test_args_values)
{
    uint64_t v;
    GI_CHECK(gi_args_bytes("512", &v) == 0 && v == 512);
    GI_CHECK(gi_args_bytes("64M", &v) == 0 && v == (UINT64_C(64) << 20));
    GI_CHECK(gi_args_bytes("2T", &v) == 0 && v == (UINT64_C(2) << 40));
    GI_CHECK(gi_args_bytes("1.5G", &v) != 0 && gi_args_bytes("-1", &v) != 0);
    GI_CHECK(gi_args_bytes("2000T", &v) != 0 && gi_args_bytes("", &v) != 0);
    double d;
    GI_CHECK(gi_args_number("0.25", 0, 1, &d) == 0 && d == 0.25);
    GI_CHECK(gi_args_number("nan", 0, 1, &d) != 0 && gi_args_number("2", 0, 1, &d) != 0);
    char *argv[] = {"gi", "--out=x", "--out", "y", "--out", NULL};
    int i = 1;
    const char *o;
    GI_CHECK(gi_args_take(5, argv, &i, "--out", &o) == 1 && strcmp(o, "x") == 0);
    i = 2;
    GI_CHECK(gi_args_take(5, argv, &i, "--out", &o) == 1 && strcmp(o, "y") == 0 && i == 3);
    i = 4;
    GI_CHECK(gi_args_take(5, argv, &i, "--out", &o) == -1);
    i = 1;
    GI_CHECK(gi_args_take(5, argv, &i, "--outx", &o) == 0);
}
