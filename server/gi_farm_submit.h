/* gi_farm_submit: the body of POST /api/v1/jobs (docs/farm.md, "API").
 *
 *   {
 *     "job": { ...the job document... },     or "job_text": "<the job file's text>"
 *     "assets": {"scene.json": "<BLAKE2b-256 hex>", "meshes/a.obj": "<hex>", ...},
 *     "priority": 10,                         optional, 1-1000, default 10
 *     "file": "cornell.json"                  optional, names the job in messages
 *   }
 *
 * "assets" maps every file name the job's scene reads (as the scene and job
 * spell it) to the hash of an asset uploaded with PUT /api/v1/assets/{hash}.
 * The coordinator resolves names through this map only. `gi submit` sends
 * job_text, so workers parse exactly the bytes of the user's file; curl
 * users can send the job as an object. Parsing is strict (unknown keys,
 * wrong types, malformed hashes are errors). */
#ifndef GI_FARM_SUBMIT_H
#define GI_FARM_SUBMIT_H

#include <stddef.h>
#include <stdint.h>

#include "gi_assets.h"
#include "gi_buf.h"
#include "gi_error.h"

#define GI_FARM_PRIORITY_DEFAULT 10
#define GI_FARM_PRIORITY_MAX 1000
#define GI_FARM_SUBMIT_MAX_BYTES ((size_t)32 << 20) /* a job (16 MiB) and its asset map */

typedef struct gi_farm_submission {
    char *file;
    char *text; /* the job document's text */
    gi_manifest manifest;
    uint32_t priority;
} gi_farm_submission;

int gi_farm_submission_parse(const char *body, size_t len, gi_farm_submission *out,
                             gi_error *err);
void gi_farm_submission_free(gi_farm_submission *s);

/* The body `gi submit` sends: job_text verbatim. */
void gi_farm_submission_build(gi_buf *out, const char *file, const char *job_text,
                              const gi_manifest *manifest, uint32_t priority);

#endif
