/* gi_child_faults: a pool child's test hooks, read once at its start. */
#include "gi_child_faults.h"

#include <stdlib.h>
#include <string.h>

#include "gi_error.h"
#include "gi_log.h"

static void spec_read(gi_fault_spec *s, const char *env)
{
    memset(s, 0, sizeof *s);
    const char *p = getenv(env);
    if (!p)
        return;
    size_t cap = 0;
    while (*p) {
        char *end;
        if (*p == '*') {
            s->every = 1;
            end = (char *)p + 1;
        } else {
            unsigned long long id = strtoull(p, &end, 10);
            unsigned long at = 0;
            if (end == p)
                return;
            if (*end == ':')
                at = strtoul(end + 1, &end, 10);
            if (s->count == cap) {
                cap = cap ? 2 * cap : 8;
                s->runs = gi_xrealloc(s->runs, cap * sizeof *s->runs);
            }
            s->runs[s->count++] = (gi_fault_run){id, (uint32_t)at};
        }
        while (*end && *end != ',')
            end++;
        p = *end ? end + 1 : end;
    }
}

void gi_child_faults_read(gi_child_faults *f)
{
    spec_read(&f->crash, GI_FAULT_CRASH_ENV);
    spec_read(&f->kill_host, GI_FAULT_KILL_HOST_ENV);
    spec_read(&f->stop_host, GI_FAULT_STOP_HOST_ENV);
    spec_read(&f->hang, GI_FAULT_HANG_ENV);
    spec_read(&f->slow, GI_FAULT_SLOW_ENV);
    spec_read(&f->bad_result, GI_FAULT_BAD_RESULT_ENV);
    static const char *const kinds[] = {"short", "nan", "huge"};
    const char *k = getenv(GI_FAULT_BAD_RESULT_KIND_ENV);
    f->bad_kind = k ? GI_FAULT_UNKNOWN : GI_FAULT_SHORT;
    for (int i = 0; k && i < GI_FAULT_UNKNOWN; i++)
        if (strcmp(k, kinds[i]) == 0)
            f->bad_kind = (gi_fault_damage_kind)i;
    const char *v = getenv(GI_FAULT_SLOW_S_ENV);
    f->slow_s = v ? atof(v) : 1.0;
}

void gi_child_faults_free(gi_child_faults *f)
{
    free(f->crash.runs);
    free(f->kill_host.runs);
    free(f->stop_host.runs);
    free(f->hang.runs);
    free(f->slow.runs);
    free(f->bad_result.runs);
    memset(f, 0, sizeof *f);
}

int gi_fault_hits(const gi_fault_spec *spec, uint64_t task_id, uint32_t attempt)
{
    if (spec->every)
        return 1;
    for (size_t i = 0; i < spec->count; i++)
        if (spec->runs[i].task == task_id && spec->runs[i].attempt == attempt)
            return 1;
    return 0;
}

void gi_fault_damage(const gi_child_faults *f, const gi_job *job, const gi_task *task,
                     gi_buf *result)
{
    unsigned long long id = (unsigned long long)task->id;
    if (f->bad_kind == GI_FAULT_UNKNOWN) {
        gi_warn("fault injection: %s=%s is not short, nan or huge: task %llu's result is "
                "sent as it is", GI_FAULT_BAD_RESULT_KIND_ENV,
                getenv(GI_FAULT_BAD_RESULT_KIND_ENV), id);
        return;
    }
    if (f->bad_kind == GI_FAULT_SHORT) {
        gi_warn("fault injection: task %llu's result is sent one byte short", id);
        result->len--;
        return;
    }
    const char *what = f->bad_kind == GI_FAULT_NAN ? "a NaN" : "a huge value";
    const gi_method *m = job->method;
    if (!m->damage_result ||
        m->damage_result(job, task, result, f->bad_kind == GI_FAULT_NAN ? GI_DAMAGE_NAN
                                                                         : GI_DAMAGE_HUGE)) {
        gi_warn("fault injection: task %llu's result has no value %s can replace: sent as it "
                "is", id, what);
        return;
    }
    gi_warn("fault injection: task %llu's result is sent with %s", id, what);
}
