/* fuzz_job: libFuzzer target for the job parser (JSON, schema, the
 * methods' parameter blocks). Any input must either parse or fail with a
 * one-line GI_EINVAL message; never crash, leak or hang. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    gi_job job;
    gi_error err;
    gi_error_clear(&err);
    int rc = gi_job_parse((const char *)data, size, "fuzz.json", &job, &err);
    if (rc != 0 && (err.code != GI_EINVAL || strchr(err.msg, '\n') || !err.msg[0]))
        abort();
    gi_job_free(&job);
    return 0;
}
