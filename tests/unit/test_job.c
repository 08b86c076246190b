/* Unit tests: job documents' top-level fields (gi_job.c), here the task
 * time limit, task_timeout. */
#include <stdio.h>
#include <string.h>

#include "gi_job.h"
#include "gi_test.h"

/* Parses a pt job whose top level has `extra` (e.g. "\"task_timeout\": 5, "). */
static int parse_with(const char *extra, gi_job *job, gi_error *err)
{
    char text[512];
    snprintf(text, sizeof text, "{%s\"scene\": \"s.json\", \"method\": \"pt\"}", extra);
    return gi_job_parse(text, strlen(text), "t.json", job, err);
}

GI_TEST(test_job_task_timeout_is_optional_and_kept)
{
    gi_job job;
    gi_error err;
    GI_REQUIRE_OK(parse_with("", &job, &err));
    GI_CHECK(job.task_timeout == 0); /* none: the coordinator's default applies */
    gi_job_free(&job);
    const double ok[] = {1, 2.5, 600, 1e6};
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) {
        char extra[64];
        snprintf(extra, sizeof extra, "\"task_timeout\": %g, ", ok[i]);
        GI_REQUIRE_OK(parse_with(extra, &job, &err));
        GI_CHECK_MSG(job.task_timeout == ok[i], "%s: got %g", extra, job.task_timeout);
        gi_job_free(&job);
    }
}

/* Bad values are refused with one line naming the file and the field. */
GI_TEST(test_job_task_timeout_is_validated)
{
    static const struct {
        const char *value, *says;
    } bad[] = {
        {"0", "t.json: task_timeout: 0 is out of range [1, 1e+06]"},
        {"0.5", "t.json: task_timeout: 0.5 is out of range [1, 1e+06]"},
        {"-600", "t.json: task_timeout: -600 is out of range [1, 1e+06]"},
        {"1000001", "t.json: task_timeout: 1000001 is out of range [1, 1e+06]"},
        {"\"600\"", "t.json: task_timeout: expected a number, got a string"},
        {"true", "t.json: task_timeout: expected a number"},
        {"null", "t.json: task_timeout: expected a number"},
        {"[600]", "t.json: task_timeout: expected a number"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char extra[64];
        snprintf(extra, sizeof extra, "\"task_timeout\": %s, ", bad[i].value);
        gi_job job;
        gi_error err;
        gi_error_clear(&err);
        GI_CHECK_MSG(parse_with(extra, &job, &err) == -1, "%s accepted", bad[i].value);
        GI_CHECK(err.code == GI_EINVAL);
        GI_CHECK_MSG(strstr(err.msg, bad[i].says) != NULL, "%s: \"%s\"", bad[i].value, err.msg);
        gi_job_free(&job);
    }
    /* Its place is the top level: inside a method's block it is unknown. */
    const char *text = "{\"scene\": \"s.json\", \"method\": \"pt\", \"pt\": {\"task_timeout\": 5}}";
    gi_job job;
    gi_error err;
    GI_CHECK(gi_job_parse(text, strlen(text), "t.json", &job, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "task_timeout") != NULL, "%s", err.msg);
    gi_job_free(&job);
}
