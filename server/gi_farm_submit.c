/* gi_farm_submit: parsing and building job submission bodies. */
#include "gi_farm_submit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "gi_json.h"

#define SUBMIT_WHAT "job submission"
#define MAX_ASSET_NAME 4096
#define MAX_FILE 255

void gi_farm_submission_free(gi_farm_submission *s)
{
    free(s->file);
    free(s->text);
    gi_manifest_free(&s->manifest);
    s->file = s->text = NULL;
}

static int parse_assets(gi_jv *v, const cJSON *assets, gi_manifest *m)
{
    if (!assets)
        return gi_jv_fail(v, "assets", "is required (file name -> uploaded asset hash)");
    if (!cJSON_IsObject(assets))
        return gi_jv_fail(v, "assets", "expected an object of file name -> asset hash");
    for (const cJSON *a = assets->child; a; a = a->next) {
        char p[600];
        gi_json_path(p, sizeof p, "assets", a->string);
        size_t n = strlen(a->string);
        if (n == 0 || n > MAX_ASSET_NAME)
            return gi_jv_fail(v, "assets", "file names must have 1-%d bytes", MAX_ASSET_NAME);
        if (!cJSON_IsString(a) || !gi_hash_is_valid(a->valuestring))
            return gi_jv_fail(v, p, "expected an asset hash (64 lower-case hex digits)");
        if (gi_manifest_find(m, a->string))
            return gi_jv_fail(v, p, "key appears twice");
        gi_manifest_put(m, a->string, a->valuestring, 0);
    }
    return 0;
}

/* Prints a JSON value so that parsing it again gives the very same values.
 * (cJSON's printer keeps 15 significant digits when they compare equal
 * within its tolerance: 2^53 would come back as 9007199254740990, and the
 * farm would render another job than `gi render` does.) Numbers get %.17g,
 * which round-trips every double; strings and literals are cJSON's. */
static int print_exact(const cJSON *v, const char *path, gi_buf *out, gi_error *err)
{
    if (cJSON_IsNumber(v)) {
        /* 1e400 reads as inf, which JSON cannot write. */
        if (!isfinite(v->valuedouble))
            return gi_fail(err, GI_EINVAL, "%s: %s: not a finite number", SUBMIT_WHAT, path);
        char n[64];
        int k = snprintf(n, sizeof n, "%.17g", v->valuedouble);
        gi_buf_put(out, n, (size_t)k);
        return 0;
    }
    if (cJSON_IsObject(v) || cJSON_IsArray(v)) {
        int obj = cJSON_IsObject(v);
        gi_buf_put_u8(out, obj ? '{' : '[');
        int i = 0;
        for (const cJSON *c = v->child; c; c = c->next, i++) {
            char sub[512];
            if (obj)
                gi_json_path(sub, sizeof sub, path, c->string);
            else
                gi_json_index_path(sub, sizeof sub, path, i);
            if (c != v->child)
                gi_buf_put_u8(out, ',');
            if (obj) {
                cJSON *key = cJSON_CreateString(c->string);
                char *k = cJSON_PrintUnformatted(key);
                cJSON_Delete(key);
                if (!k)
                    return gi_fail(err, GI_ENOMEM, "%s: cannot print the job", SUBMIT_WHAT);
                gi_buf_put(out, k, strlen(k));
                gi_buf_put_u8(out, ':');
                cJSON_free(k);
            }
            if (print_exact(c, sub, out, err))
                return -1;
        }
        gi_buf_put_u8(out, obj ? '}' : ']');
        return 0;
    }
    char *t = cJSON_PrintUnformatted(v); /* strings, true, false, null */
    if (!t)
        return gi_fail(err, GI_ENOMEM, "%s: cannot print the job", SUBMIT_WHAT);
    gi_buf_put(out, t, strlen(t));
    cJSON_free(t);
    return 0;
}

int gi_farm_submission_parse(const char *body, size_t len, gi_farm_submission *out,
                             gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_manifest_init(&out->manifest);
    out->priority = GI_FARM_PRIORITY_DEFAULT;
    if (len > GI_FARM_SUBMIT_MAX_BYTES)
        return gi_fail(err, GI_EINVAL, "%s: %zu bytes (limit %zu)", SUBMIT_WHAT, len,
                       GI_FARM_SUBMIT_MAX_BYTES);
    cJSON *doc;
    if (gi_json_parse(body, len, SUBMIT_WHAT, &doc, err))
        return -1;
    gi_jv v = {SUBMIT_WHAT, err};
    static const char *const keys[] = {"job", "job_text", "assets", "priority", "file", NULL};
    const cJSON *job, *assets;
    const char *job_text = NULL, *file = NULL;
    int64_t priority = GI_FARM_PRIORITY_DEFAULT;
    int rc = -1;
    if (gi_jv_keys(&v, doc, "", keys) || gi_jv_member_object(&v, doc, "", "job", 0, &job) ||
        gi_jv_string(&v, doc, "", "job_text", 0, &job_text) ||
        gi_jv_int(&v, doc, "", "priority", 0, 1, GI_FARM_PRIORITY_MAX, &priority) ||
        gi_jv_string(&v, doc, "", "file", 0, &file))
        goto out;
    assets = cJSON_GetObjectItemCaseSensitive(doc, "assets");
    if (!job == !job_text) {
        gi_jv_fail(&v, "", "give the job as exactly one of \"job\" (an object) or \"job_text\"");
        goto out;
    }
    if (file) {
        size_t n = strlen(file);
        int ok = n >= 1 && n <= MAX_FILE;
        for (size_t i = 0; ok && i < n; i++)
            ok = file[i] >= 0x20 && file[i] < 0x7f;
        if (!ok) {
            gi_jv_fail(&v, "file", "expected 1-%d printable characters", MAX_FILE);
            goto out;
        }
    }
    if (parse_assets(&v, assets, &out->manifest))
        goto out;
    if (job_text) {
        if (strlen(job_text) > GI_JOB_MAX_BYTES) {
            gi_jv_fail(&v, "job_text", "longer than %u bytes", GI_JOB_MAX_BYTES);
            goto out;
        }
        out->text = gi_xstrdup(job_text);
    } else {
        gi_buf t;
        gi_buf_init(&t);
        if (print_exact(job, "job", &t, err)) {
            gi_buf_free(&t);
            goto out;
        }
        gi_buf_put_u8(&t, 0);
        out->text = (char *)t.data;
    }
    out->file = gi_xstrdup(file ? file : "job.json");
    out->priority = (uint32_t)priority;
    rc = 0;
out:
    cJSON_Delete(doc);
    if (rc)
        gi_farm_submission_free(out);
    return rc;
}

void gi_farm_submission_build(gi_buf *out, const char *file, const char *job_text,
                              const gi_manifest *manifest, uint32_t priority)
{
    cJSON *doc = cJSON_CreateObject();
    cJSON_AddStringToObject(doc, "file", file);
    cJSON_AddNumberToObject(doc, "priority", priority);
    cJSON *assets = cJSON_AddObjectToObject(doc, "assets");
    for (size_t i = 0; i < manifest->count; i++)
        cJSON_AddStringToObject(assets, manifest->entries[i].name, manifest->entries[i].hash);
    cJSON_AddStringToObject(doc, "job_text", job_text);
    char *s = cJSON_PrintUnformatted(doc);
    if (!s) {
        fprintf(stderr, "gi: out of memory building a job submission\n");
        abort();
    }
    gi_buf_put(out, s, strlen(s));
    cJSON_free(s);
    cJSON_Delete(doc);
}
