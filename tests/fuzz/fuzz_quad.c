/* fuzz_quad: libFuzzer target for the quadrature method's decoders: task
 * payloads, worker results (with the image delta; the coordinator's check
 * and the merge of what it decoded), and checkpoints. The
 * first byte picks the decoder (bits 0-1), the rule (bit 2) and a job
 * animated over 5 frames (bit 3: task payloads and checkpoints carry a
 * frame); the rest is the input. Any input must decode or fail with a
 * message; a task that decodes must encode back to the same bytes. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "quadrature/quad_farm.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    gi_error err;
    gi_quad_params p;
    gi_quad_params_default(&p);
    p.rule = data[0] & 4 ? GI_QUAD_GM : GI_QUAD_BOOLE;
    if (data[0] & 8) {
        p.anim.enabled = 1;
        p.anim.frames = 5;
    }
    gi_quad_rule rule;
    if (gi_quad_job_rule(&p, &rule, &err))
        abort();
    const uint8_t *in = data + 1;
    size_t n = size - 1;
    switch (data[0] & 3) {
    case 0:
    case 1: {
        gi_task t;
        memset(&t, 0, sizeof t);
        t.kind = (data[0] & 3) == 0 ? GI_QUAD_TASK_REFINE : GI_QUAD_TASK_MC;
        gi_buf_init(&t.payload);
        gi_buf_put(&t.payload, in, n);
        gi_quad_task_in q;
        if (gi_quad_task_decode(&t, &rule, p.anim.frames, &q, &err) == 0) {
            if (q.animated != p.anim.enabled || q.frame >= (q.animated ? 5u : 1u))
                abort();
            gi_buf out;
            gi_buf_init(&out);
            gi_quad_task_encode(&out, &q, &rule);
            if (out.len != n || memcmp(out.data, in, n) != 0)
                abort();
            gi_buf_free(&out);
            gi_quad_task_in_free(&q);
        }
        gi_buf_free(&t.payload);
        break;
    }
    case 2: {
        gi_buf b;
        gi_buf_init(&b);
        gi_buf_put(&b, in, n);
        /* The coordinator's check, and the merge of what it decoded: a
         * result the check accepts merges (task id from the length). */
        gi_job job;
        memset(&job, 0, sizeof job);
        job.method = &gi_method_quadrature;
        job.width = 6;
        job.height = 5;
        p.initial[0] = p.initial[1] = p.initial_path = 1;
        job.params = gi_xcalloc(1, sizeof p);
        memcpy(job.params, &p, sizeof p);
        gi_task_queue q;
        gi_task_queue_init(&q, 16);
        gi_task t;
        memset(&t, 0, sizeof t);
        t.id = n % 7;
        gi_buf dec;
        gi_buf_init(&dec);
        if (gi_quad_plan(&job, &q, &err))
            abort();
        if (gi_quad_check_result(&job, &t, &b, &dec, &err) == 0 &&
            gi_quad_merge_decoded(&job, &t, &dec, &q, &err) != 0)
            abort();
        gi_buf_free(&dec);
        gi_task_queue_free(&q);
        gi_quad_release(&job);
        gi_buf_free(&b);
        break;
    }
    default: {
        gi_job job;
        memset(&job, 0, sizeof job);
        job.method = &gi_method_quadrature;
        job.width = 6;
        job.height = 5;
        job.params = gi_xcalloc(1, sizeof p);
        memcpy(job.params, &p, sizeof p);
        gi_reader r;
        gi_reader_init(&r, in, n, "checkpoint");
        gi_quad_load(&job, &r, &err);
        gi_quad_release(&job);
        break;
    }
    }
    gi_quad_rule_free(&rule);
    return 0;
}
