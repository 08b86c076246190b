/* Unit tests: job submission bodies, the HTTP client's parsers, farm URLs,
 * the worker's asset cache, option values. */
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "gi_args.h"
#include "gi_asset_cache.h"
#include "gi_farm_submit.h"
#include "gi_fs.h"
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
        {"{\"job\": {\"a\": [1, {\"seed\": 1e400}]}, \"assets\": {}}",
         "job.a[1].seed: not a finite number"},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(bad); i++) {
        gi_farm_submission s;
        gi_error err;
        GI_CHECK_MSG(gi_farm_submission_parse(bad[i][0], strlen(bad[i][0]), &s, &err) != 0,
                     "accepted: %s", bad[i][0]);
        GI_CHECK_MSG(strstr(err.msg, bad[i][1]) != NULL, "%s: \"%s\" lacks \"%s\"", bad[i][0],
                     err.msg, bad[i][1]);
    }
    /* After a NUL (a terminator counted in the length) only more may come. */
    static const char nul_then[] = "{\"job\": {}, \"assets\": {}}\0garbage";
    gi_farm_submission s;
    gi_error err;
    GI_CHECK(gi_farm_submission_parse(nul_then, sizeof nul_then - 1, &s, &err) != 0 &&
             strstr(err.msg, "unexpected text"));
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

/* One canned response from a process listening on 127.0.0.1; returns the
 * farm URL to reach it (the child exits after one connection). */
static pid_t serve_once(const char *response, char *url, size_t n)
{
    int ls = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t al = sizeof a;
    if (ls < 0 || bind(ls, (struct sockaddr *)&a, sizeof a) || listen(ls, 1) ||
        getsockname(ls, (struct sockaddr *)&a, &al))
        return -1;
    snprintf(url, n, "http://127.0.0.1:%d", ntohs(a.sin_port));
    pid_t pid = fork();
    if (pid == 0) {
        int c = accept(ls, NULL, NULL);
        char buf[4096];
        size_t got = 0;
        while (got < sizeof buf - 1) { /* the request's head */
            ssize_t r = read(c, buf + got, sizeof buf - 1 - got);
            if (r <= 0)
                break;
            got += (size_t)r;
            buf[got] = '\0';
            if (strstr(buf, "\r\n\r\n"))
                break;
        }
        /* In small pieces, so that chunks straddle the reads. */
        for (size_t i = 0, len = strlen(response); i < len; i += 7) {
            if (write(c, response + i, len - i < 7 ? len - i : 7) < 0)
                break;
            usleep(200);
        }
        close(c);
        _exit(0);
    }
    close(ls);
    return pid;
}

static int download(const char *response, const char *path, gi_error *err)
{
    char url_text[64];
    pid_t pid = serve_once(response, url_text, sizeof url_text);
    if (pid < 0)
        return gi_fail(err, GI_EIO, "cannot listen");
    gi_http_url u;
    if (gi_http_url_parse(url_text, &u, err))
        return -1;
    gi_http_request rq = {.method = "GET", .path = "/x", .timeout_s = 10};
    gi_buf body;
    gi_buf_init(&body);
    int status = gi_http_do(&u, &rq, &body, 1024, path, err);
    gi_buf_free(&body);
    gi_http_url_free(&u);
    waitpid(pid, NULL, 0);
    return status;
}

/* A transport failure says whether the request reached the server whole
 * (gi retries a request that may have been acted on only when a second
 * one changes nothing). */
GI_TEST(test_http_failure_stages)
{
    char path[512];
    snprintf(path, sizeof path, "%s/nothing.bin", gi_test_tmpdir());
    gi_error err;
    /* Read, then closed without an answer: it may have been acted on. */
    GI_CHECK(download("", path, &err) == GI_HTTP_FAILED);
    GI_CHECK(strstr(err.msg, "closed the connection before answering") != NULL);
    /* Nobody listening: it never went. */
    int ls = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t al = sizeof a;
    GI_REQUIRE(bind(ls, (struct sockaddr *)&a, sizeof a) == 0 &&
               getsockname(ls, (struct sockaddr *)&a, &al) == 0);
    close(ls); /* bound, never listened: the port refuses */
    char url[64];
    snprintf(url, sizeof url, "http://127.0.0.1:%d", ntohs(a.sin_port));
    gi_http_url u;
    GI_REQUIRE_OK(gi_http_url_parse(url, &u, &err));
    gi_http_request rq = {.method = "POST", .path = "/x", .timeout_s = 5};
    gi_buf body;
    gi_buf_init(&body);
    GI_CHECK(gi_http_do(&u, &rq, &body, 1024, NULL, &err) == GI_HTTP_UNSENT);
    gi_buf_free(&body);
    gi_http_url_free(&u);
}

/* Downloads go to the file whether the body comes chunked (a proxy may
 * re-chunk the farm's) or with a length (and no further). */
GI_TEST(test_http_download_to_file)
{
    char path[512];
    snprintf(path, sizeof path, "%s/download.bin", gi_test_tmpdir());
    gi_error err;
    gi_buf b;
    gi_buf_init(&b);
    GI_CHECK(download("HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n"
                      "5\r\nhello\r\n1;ext=1\r\n \r\n10\r\n0123456789abcdef\r\n0\r\n\r\n",
                      path, &err) == 200);
    GI_REQUIRE_OK(gi_read_file(path, 100, &b, &err));
    GI_CHECK_MSG(b.len == 22 && memcmp(b.data, "hello 0123456789abcdef", 22) == 0, "%.*s",
                 (int)b.len, (const char *)b.data);
    GI_CHECK(download("HTTP/1.1 200 OK\r\nContent-Length: 3\r\n\r\nabcEXTRA", path, &err) ==
             200);
    GI_REQUIRE_OK(gi_read_file(path, 100, &b, &err));
    GI_CHECK(b.len == 3 && memcmp(b.data, "abc", 3) == 0);
    /* Cut short or malformed: an error, and the file as it was. */
    GI_CHECK(download("HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n5\r\nhel", path,
                      &err) < 0);
    GI_CHECK(download("HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n5\r\nhelloX\r\n",
                      path, &err) < 0);
    GI_REQUIRE_OK(gi_read_file(path, 100, &b, &err));
    GI_CHECK(b.len == 3 && memcmp(b.data, "abc", 3) == 0);
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

/* In a child process (the lock is per process): 0 if it opens the cache,
 * 1 if it is refused as in use, saying what to do; 2 otherwise. */
static int other_process_opens(const char *dir)
{
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        gi_asset_cache c;
        gi_error err;
        if (gi_asset_cache_open(&c, dir, 3000, &err) == 0)
            _exit(c.bytes > 0 ? 0 : 2);
        _exit(err.code == GI_EINVAL && strstr(err.msg, dir) &&
                      strstr(err.msg, "in use by another gi-worker") &&
                      strstr(err.msg, "--cache DIR of its own")
                  ? 1
                  : 2);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status))
        return -1;
    return WEXITSTATUS(status);
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
    /* One user at a time: a second gi-worker given the same directory is
     * refused, saying what to do; once the first closes it, it may. */
    GI_CHECK(other_process_opens(dir) == 1);
    gi_asset_cache_close(&c);
    GI_CHECK(other_process_opens(dir) == 0);
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
    GI_CHECK(gi_args_bytes(" 5", &v) != 0 && gi_args_bytes("+5", &v) != 0);
    int64_t n;
    GI_CHECK(gi_args_int("-3", -5, 5, &n) == 0 && n == -3);
    GI_CHECK(gi_args_int(" 5", 1, 9, &n) != 0 && gi_args_int("+5", 1, 9, &n) != 0);
    GI_CHECK(gi_args_int("5 ", 1, 9, &n) != 0 && gi_args_int("0x5", 1, 9, &n) != 0);
    double d;
    GI_CHECK(gi_args_number("0.25", 0, 1, &d) == 0 && d == 0.25);
    GI_CHECK(gi_args_number("nan", 0, 1, &d) != 0 && gi_args_number("2", 0, 1, &d) != 0);
    GI_CHECK(gi_args_duration("90", 1, 1e9, &d) == 0 && d == 90);
    GI_CHECK(gi_args_duration("1.5h", 1, 1e9, &d) == 0 && d == 5400);
    GI_CHECK(gi_args_duration("14d", 1, 1e9, &d) == 0 && d == 14 * 86400);
    GI_CHECK(gi_args_duration("2w", 1, 1e9, &d) == 0 && d == 14 * 86400);
    GI_CHECK(gi_args_duration("30m", 1, 1e9, &d) == 0 && d == 1800);
    GI_CHECK(gi_args_duration(".5s", 0.1, 1e9, &d) == 0 && d == 0.5);
    GI_CHECK(gi_args_duration("0.5", 1, 1e9, &d) != 0); /* under lo */
    GI_CHECK(gi_args_duration("", 1, 1e9, &d) != 0 && gi_args_duration("d", 1, 1e9, &d) != 0);
    GI_CHECK(gi_args_duration(" 5", 1, 1e9, &d) != 0 && gi_args_duration("+5", 1, 1e9, &d) != 0);
    GI_CHECK(gi_args_duration("5dd", 1, 1e9, &d) != 0 && gi_args_duration("5y", 1, 1e9, &d) != 0);
    GI_CHECK(gi_args_duration("1e3", 1, 1e9, &d) != 0 && gi_args_duration("inf", 1, 1e9, &d) != 0);
    GI_CHECK(gi_args_duration("1.2.3", 1, 1e9, &d) != 0 && gi_args_duration(".", 1, 1e9, &d) != 0);
    GI_CHECK(gi_args_duration("99999999999w", 1, 1e9, &d) != 0);
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
