/* gi_farm_route: the API's paths to endpoints, and URL unescaping. */
#include "gi_farm_route.h"

#include <ctype.h>
#include <microhttpd.h>
#include <stdio.h>
#include <string.h>

/* Parses a decimal job id (no sign, no leading zeros beyond "0"). */
static int parse_id(const char *s, size_t n, uint64_t *out)
{
    if (n == 0 || n > 19 || (n > 1 && s[0] == '0'))
        return -1;
    uint64_t v = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9')
            return -1;
        v = v * 10 + (uint64_t)(s[i] - '0');
    }
    *out = v;
    return 0;
}

/* The output name or asset hash of the path: one too long to be either is
 * kept cut short and marked, to be refused as the name it is. */
static void set_name(gi_route *r, const char *p)
{
    if (strlen(p) < sizeof r->name)
        snprintf(r->name, sizeof r->name, "%s", p);
    else
        snprintf(r->name, sizeof r->name, "%.200s...", p);
}

/* 405, with the methods the path takes (the Allow header). */
static unsigned not_allowed(gi_route *r, const char *allow)
{
    r->allow = allow;
    return MHD_HTTP_METHOD_NOT_ALLOWED;
}

unsigned gi_route_find(const char *method, const char *url, gi_route *r)
{
    int get = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
    const char *p;
    if (strcmp(url, "/") == 0)
        return get ? (r->id = GI_ROUTE_DASHBOARD, 0) : not_allowed(r, "GET, HEAD");
    if (strcmp(url, "/metrics") == 0)
        return get ? (r->id = GI_ROUTE_METRICS, 0) : not_allowed(r, "GET, HEAD");
    if (strcmp(url, "/api/v1/workers") == 0)
        return get ? (r->id = GI_ROUTE_WORKERS, 0) : not_allowed(r, "GET, HEAD");
    if (strcmp(url, "/api/v1/jobs") == 0) {
        if (get)
            r->id = GI_ROUTE_JOBS_LIST;
        else if (strcmp(method, "POST") == 0)
            r->id = GI_ROUTE_JOBS_SUBMIT;
        else
            return not_allowed(r, "GET, HEAD, POST");
        return 0;
    }
    if (strncmp(url, "/api/v1/assets/", 15) == 0) {
        p = url + 15;
        set_name(r, p);
        if (strcmp(method, "PUT") == 0)
            r->id = GI_ROUTE_ASSET_PUT;
        else if (strcmp(method, "HEAD") == 0)
            r->id = GI_ROUTE_ASSET_HEAD;
        else
            return not_allowed(r, "HEAD, PUT");
        return 0;
    }
    if (strncmp(url, "/api/v1/jobs/", 13) == 0) {
        p = url + 13;
        const char *slash = strchr(p, '/');
        size_t n = slash ? (size_t)(slash - p) : strlen(p);
        if (parse_id(p, n, &r->job_id))
            return MHD_HTTP_NOT_FOUND;
        if (!slash) {
            if (get)
                r->id = GI_ROUTE_JOB_GET;
            else if (strcmp(method, "DELETE") == 0)
                r->id = GI_ROUTE_JOB_DELETE;
            else
                return not_allowed(r, "GET, HEAD, DELETE");
            return 0;
        }
        if (strcmp(slash, "/retry") == 0)
            return strcmp(method, "POST") == 0 ? (r->id = GI_ROUTE_JOB_RETRY, 0)
                                               : not_allowed(r, "POST");
        if (strncmp(slash, "/outputs/", 9) == 0 && slash[9] && !strchr(slash + 9, '/')) {
            set_name(r, slash + 9);
            return get ? (r->id = GI_ROUTE_JOB_OUTPUT, 0) : not_allowed(r, "GET, HEAD");
        }
    }
    return MHD_HTTP_NOT_FOUND;
}

static int hex_value(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c - 'A' + 10;
}

size_t gi_url_unescape(char *s)
{
    char *w = s;
    for (const char *r = s; *r;) {
        if (r[0] == '%' && isxdigit((unsigned char)r[1]) && isxdigit((unsigned char)r[2]) &&
            (r[1] != '0' || r[2] != '0')) {
            *w++ = (char)(hex_value(r[1]) * 16 + hex_value(r[2]));
            r += 3;
        } else {
            *w++ = *r++;
        }
    }
    *w = '\0';
    return (size_t)(w - s);
}
