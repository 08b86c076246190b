/* fuzz_job: libFuzzer target for the job parser (JSON, schema, the
 * methods' parameter blocks). Any input must either parse or fail with a
 * one-line GI_EINVAL message; never crash, leak or hang. The same input
 * goes through gi_json_top_keys (gi validate's file kind), which must
 * read every object cJSON reads, and find only keys that cJSON finds. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "gi_json.h"

static void top_keys(const uint8_t *data, size_t size)
{
    static const char *const keys[] = {"method", "objects", "emissions", NULL};
    unsigned found;
    int rc = gi_json_top_keys((const char *)data, size, keys, &found);
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
