/* Unit tests that run a whole job in this process (see the header). */
#include "test_drive.h"

#include <string.h>

int gi_test_drive(gi_jobrun *jr, gi_worker_ctx *ctx, uint64_t stop, gi_error *err)
{
    for (uint64_t ran = 0; ran < stop && !gi_jobrun_done(jr); ran++) {
        const gi_task *t = gi_jobrun_lease(jr);
        if (!t) /* one worker, nothing leased elsewhere: a task is always due */
            return gi_fail(err, GI_EINTERNAL, "nothing to lease before the job is done");
        gi_buf res;
        gi_buf_init(&res);
        int rc = gi_worker_run_task(ctx, t, &res, err);
        if (rc == 0)
            gi_jobrun_complete(jr, t->id, t->attempt, &res, &ctx->stats); /* jr->failed says */
        gi_buf_free(&res);
        if (rc)
            return rc;
        if (jr->failed)
            break;
    }
    if (jr->failed)
        return gi_fail(err, jr->error.code, "%s", jr->error.msg);
    return 0;
}

int gi_test_drive_checked(gi_jobrun *jr, gi_worker_ctx *ctx, unsigned ahead, gi_error *err)
{
    enum { MOST = 8 };
    uint64_t id[MOST];
    uint32_t at[MOST];
    gi_buf res[MOST];
    ahead = ahead < 1 ? 1 : ahead > MOST ? MOST : ahead;
    while (!gi_jobrun_done(jr)) {
        unsigned n = 0;
        int rc = 0;
        const gi_task *t;
        while (n < ahead && (t = gi_jobrun_lease(jr))) {
            id[n] = t->id;
            at[n] = t->attempt;
            gi_buf_init(&res[n]);
            if (rc == 0)
                rc = gi_worker_run_task(ctx, t, &res[n], err);
            n++;
        }
        if (n == 0)
            return gi_fail(err, GI_EINTERNAL, "nothing to lease before the job is done");
        while (n-- > 0) {
            if (rc == 0 && gi_jobrun_check_result(jr, id[n], at[n], &res[n], err))
                rc = gi_error_prefix(err, "refused");
            if (rc == 0)
                gi_jobrun_complete(jr, id[n], at[n], &res[n], &ctx->stats);
            gi_buf_free(&res[n]);
        }
        if (rc)
            return rc;
        if (jr->failed)
            return gi_fail(err, jr->error.code, "%s", jr->error.msg);
    }
    return 0;
}

int gi_test_refuse(gi_jobrun *jr, const gi_task *t, const gi_buf *bad, const char *want,
                   gi_error *err)
{
    uint64_t id = t->id;
    uint32_t attempt = t->attempt;
    if (gi_jobrun_check_result(jr, id, attempt, bad, err) == 0)
        return gi_fail(err, GI_EINTERNAL, "task %llu: a bad result was accepted",
                       (unsigned long long)id);
    gi_error why = *err;
    gi_jobrun_fail(jr, id, attempt, &why);
    if (why.code != GI_EPROTO || !strstr(why.msg, want))
        return gi_fail(err, GI_EINTERNAL, "unexpected refusal: %s", why.msg);
    if (jr->failed)
        return gi_fail(err, GI_EINTERNAL, "the job failed: %s", jr->error.msg);
    return 0;
}
