/* fuzz_job: libFuzzer target for the job parser (JSON, schema, the
 * methods' parameter blocks). Any input must either parse or fail with a
 * one-line GI_EINVAL message; never crash, leak or hang. The same input
 * goes through gi_json_top_keys (gi validate's file kind), which must
 * read every object cJSON reads, and find only keys that cJSON finds; fed
 * in two pieces cut anywhere, or byte by byte, it must say the same. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "gi_json.h"

static const char *const keys[] = {"method", "objects", "emissions", NULL};

/* data fed as pieces of `piece` bytes, the first `first` long. */
static int top_keys_fed(const uint8_t *data, size_t size, size_t first, size_t piece,
                        unsigned *found)
{
    gi_json_top_keys_scan scan;
    gi_json_top_keys_begin(&scan, keys);
    int more = 1;
    for (size_t at = 0, n = first; more == 1 && at < size; at += n, n = piece) {
        if (n > size - at)
            n = size - at;
        more = gi_json_top_keys_feed(&scan, (const char *)data + at, n);
    }
    int rc = gi_json_top_keys_end(&scan, found);
    if ((more == 0) != (rc == 0))
        abort(); /* feed said closed, end did not (or the other way) */
    return rc;
}

static void top_keys(const uint8_t *data, size_t size)
{
    unsigned found;
    int rc = gi_json_top_keys((const char *)data, size, keys, &found);
    size_t cut = size ? data[size / 2] % (size + 1) : 0;
    unsigned found_cut, found_bytes;
    if (top_keys_fed(data, size, cut, size, &found_cut) != rc ||
        top_keys_fed(data, size, 1, 1, &found_bytes) != rc ||
        (rc == 0 && (found_cut != found || found_bytes != found)))
        abort();
    cJSON *doc;
    if (gi_json_parse((const char *)data, size, "fuzz.json", &doc, NULL) != 0)
        return;
    if (rc != 0)
        abort(); /* an object cJSON reads */
    for (unsigned k = 0; keys[k]; k++)
        if ((found >> k & 1) && !cJSON_GetObjectItemCaseSensitive(doc, keys[k]))
            abort();
    cJSON_Delete(doc);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    top_keys(data, size);
    gi_job job;
    gi_error err;
    gi_error_clear(&err);
    int rc = gi_job_parse((const char *)data, size, "fuzz.json", &job, &err);
    if (rc != 0 && (err.code != GI_EINVAL || strchr(err.msg, '\n') || !err.msg[0]))
        abort();
    gi_job_free(&job);
    return 0;
}
