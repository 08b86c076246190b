/* gi_farm_route: which endpoint of gi-farmd's HTTP API a request's method
 * and path name (docs/farm.md, "API"), with the job id and the output name
 * or asset hash the path holds, and the unescaping of paths and query
 * values. Both read bytes any client sends; gi_farm_api.c acts on them. */
#ifndef GI_FARM_ROUTE_H
#define GI_FARM_ROUTE_H

#include <stddef.h>
#include <stdint.h>

typedef enum {
    GI_ROUTE_NONE,
    GI_ROUTE_DASHBOARD,
    GI_ROUTE_METRICS,
    GI_ROUTE_JOBS_LIST,
    GI_ROUTE_JOBS_SUBMIT,
    GI_ROUTE_JOB_GET,
    GI_ROUTE_JOB_DELETE,
    GI_ROUTE_JOB_RETRY,
    GI_ROUTE_JOB_OUTPUT,
    GI_ROUTE_ASSET_PUT,
    GI_ROUTE_ASSET_HEAD,
    GI_ROUTE_WORKERS
} gi_route_id;

typedef struct gi_route {
    gi_route_id id;
    uint64_t job_id;   /* the job routes */
    char name[256];    /* output name or asset hash; one too long is cut and ends in "..." */
    const char *allow; /* a 405's Allow header (static) */
} gi_route;

/* Maps method + path (unescaped, without the query) to a route: 0 = found
 * (r->id set), else the HTTP status, 404 (no such path) or 405 (the path
 * does not take the method: r->allow names those it takes). */
unsigned gi_route_find(const char *method, const char *url, gi_route *r);

/* Unescapes s in place as libmicrohttpd does (%XX, hex digits of either
 * case), except that %00 stays as written: a NUL would cut what the
 * handlers see, so that /api/v1/jobs/1%00x would read as job 1. Returns
 * the new length. */
size_t gi_url_unescape(char *s);

#endif
