/* fuzz_api: libFuzzer target for how gi-farmd reads a request's path: the
 * unescaping libmicrohttpd calls back (gi_url_unescape, also for query
 * values such as ?purge=) and the routing of the unescaped path to an
 * endpoint with its job id and output name or asset hash (gi_route_find).
 * The first byte picks the method (% 8: GET, HEAD, POST, PUT, DELETE,
 * PATCH, OPTIONS, "get"), the rest is the path as it came, cut at a NUL as
 * libmicrohttpd hands it over.
 *
 * Properties: the unescaped path is no longer than the one sent, holds
 * what its length says, and percent-encoded again whole unescapes back to
 * itself; the route is found (0), 404, or 405 with an Allow list that does
 * not hold the method; a job's route holds the path's id, which written
 * back as gi's client writes it ("/api/v1/jobs/%llu") routes to the same
 * job; a name is the path's rest, or cut and marked when too long. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_farm_route.h"

static const char *const methods[] = {"GET",   "HEAD",    "POST", "PUT",
                                      "DELETE", "PATCH", "OPTIONS", "get"};

/* 1 if the comma-separated list holds the method as one of its items. */
static int listed(const char *allow, const char *method)
{
    size_t n = strlen(method);
    for (const char *p = allow; p && *p;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if (len == n && memcmp(p, method, n) == 0)
            return 1;
        p = comma ? comma + 2 : NULL;
    }
    return 0;
}

static void unescape_round_trip(const char *path)
{
    char *s = strdup(path);
    if (!s)
        abort();
    size_t n = gi_url_unescape(s);
    if (n > strlen(path) || strlen(s) != n)
        abort();
    /* Every byte as %XX: unescaping gives it back (a kept "%00" too). */
    char *enc = malloc(3 * n + 1);
    if (!enc)
        abort();
    for (size_t i = 0; i < n; i++)
        snprintf(enc + 3 * i, 4, "%%%02X", (unsigned char)s[i]);
    enc[3 * n] = '\0';
    if (gi_url_unescape(enc) != n || memcmp(enc, s, n) != 0)
        abort();
    /* No escape left to undo: unchanged. */
    if (!strchr(path, '%') && strcmp(s, path) != 0)
        abort();
    free(enc);
    free(s);
}

static void check_name(const gi_route *r, const char *rest)
{
    size_t n = strlen(rest);
    if (n < sizeof r->name) {
        if (strcmp(r->name, rest) != 0)
            abort();
    } else if (strlen(r->name) != 203 || strncmp(r->name, rest, 200) != 0 ||
               strcmp(r->name + 200, "...") != 0) {
        abort();
    }
}

static void route(const char *method, const char *url)
{
    gi_route r;
    memset(&r, 0, sizeof r);
    unsigned status = gi_route_find(method, url, &r);
    if (status == 405) {
        if (!r.allow || listed(r.allow, method))
            abort();
        return;
    }
    if (status == 404)
        return;
    if (status != 0 || r.id == GI_ROUTE_NONE)
        abort();
    switch (r.id) {
    case GI_ROUTE_JOB_GET:
    case GI_ROUTE_JOB_DELETE:
    case GI_ROUTE_JOB_RETRY:
    case GI_ROUTE_JOB_OUTPUT: {
        char canon[64];
        int len = snprintf(canon, sizeof canon, "/api/v1/jobs/%llu",
                           (unsigned long long)r.job_id);
        if (strncmp(url, canon, (size_t)len) != 0 || (url[len] && url[len] != '/'))
            abort();
        gi_route again;
        memset(&again, 0, sizeof again);
        if (gi_route_find("GET", canon, &again) != 0 || again.id != GI_ROUTE_JOB_GET ||
            again.job_id != r.job_id)
            abort();
        if (r.id == GI_ROUTE_JOB_OUTPUT)
            check_name(&r, url + len + strlen("/outputs/"));
        break;
    }
    case GI_ROUTE_ASSET_PUT:
    case GI_ROUTE_ASSET_HEAD:
        check_name(&r, url + strlen("/api/v1/assets/"));
        break;
    default:
        break;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    const char *method = methods[data[0] % 8];
    char *url = malloc(size);
    if (!url)
        abort();
    memcpy(url, data + 1, size - 1);
    url[size - 1] = '\0';
    unescape_round_trip(url);
    gi_url_unescape(url);
    route(method, url);
    free(url);
    return 0;
}
