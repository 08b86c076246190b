/* detp_task: detp's task payloads, written by the coordinator's plans and
 * read by the workers (and by the coordinator again, as results arrive).
 * The bytes come from outside the process, so every field is checked
 * against the job before a worker acts on it: a bad payload is a GI_EPROTO
 * error naming the task, never a run over a wrong range. */
#include <stdlib.h>
#include <string.h>

#include "detp_method.h"

/* The kinds' names in messages (index: DETP_TASK_*). */
static const char *const kind_name[] = {
    "", "batch", "visibility", "reference", "tile", "animation batch", "animation update",
    "animation tile"};

void detp_task_encode(uint32_t kind, const detp_task_in *in, gi_buf *out)
{
    switch (kind) {
    case DETP_TASK_BATCH:
        gi_buf_put_u64(out, in->p0);
        gi_buf_put_u64(out, in->p1);
        break;
    case DETP_TASK_VISIBILITY:
    case DETP_TASK_REFERENCE:
        gi_buf_put_u32(out, in->a);
        gi_buf_put_u32(out, in->b);
        break;
    case DETP_TASK_ANIM_BATCH:
    case DETP_TASK_ANIM_UPDATE:
        gi_buf_put_u32(out, in->frame);
        gi_buf_put_u32(out, in->batch);
        gi_buf_put_u64(out, in->p0);
        gi_buf_put_u64(out, in->p1);
        break;
    case DETP_TASK_TILE:
    case DETP_TASK_ANIM_TILE:
        /* What gi_tiles_plan writes, with plan_tiles's extra bytes. */
        gi_buf_put_u32(out, in->tile.x0);
        gi_buf_put_u32(out, in->tile.y0);
        gi_buf_put_u32(out, in->tile.x1);
        gi_buf_put_u32(out, in->tile.y1);
        gi_buf_put_str(out, in->hash);
        if (kind == DETP_TASK_ANIM_TILE)
            gi_buf_put_u32(out, in->frame);
        break;
    }
}

/* A batch's photons [p0, p1): within the job, at most one batch long. */
static int photons_ok(const gi_detp_params *p, uint64_t p0, uint64_t p1)
{
    return p0 < p1 && p1 <= p->photon_count && p1 - p0 <= (uint64_t)GI_DETP_MAX_BATCH;
}

static int decode_tile(const gi_job *job, const gi_task *t, gi_reader *r, detp_task_in *in,
                       gi_error *err)
{
    const gi_detp_params *p = job->params;
    if (gi_tile_read(r, job->width, job->height, &in->tile, err))
        return -1;
    char *hash = gi_get_str(r, GI_HASH_HEX - 1);
    int ok = hash && gi_hash_is_valid(hash);
    if (ok)
        memcpy(in->hash, hash, GI_HASH_HEX);
    free(hash);
    /* An animation's tile: the frame whose pose the mobile takes. */
    if (t->kind == DETP_TASK_ANIM_TILE)
        in->frame = gi_get_u32(r);
    if (gi_reader_finish(r, err))
        return -1;
    if (!ok)
        return gi_fail(err, GI_EPROTO, "detp tile task %llu: bad radiance hash",
                       (unsigned long long)t->id);
    if (t->kind == DETP_TASK_ANIM_TILE && (!p->anim.enabled || in->frame >= p->anim.frames))
        return gi_fail(err, GI_EPROTO, "detp animation tile task %llu: frame %u of %u",
                       (unsigned long long)t->id, in->frame,
                       p->anim.enabled ? p->anim.frames : 0);
    return 0;
}

int detp_task_decode(const gi_job *job, const gi_task *t, uint32_t lim, detp_task_in *in,
                     gi_error *err)
{
    const gi_detp_params *p = job->params;
    memset(in, 0, sizeof *in);
    if (t->kind < DETP_TASK_BATCH || t->kind > DETP_TASK_ANIM_TILE)
        return gi_fail(err, GI_EPROTO, "detp: unknown task kind %u", t->kind);
    const char *what = kind_name[t->kind];
    gi_reader r;
    gi_reader_init(&r, t->payload.data, t->payload.len, "detp task");
    switch (t->kind) {
    case DETP_TASK_BATCH:
        in->p0 = gi_get_u64(&r);
        in->p1 = gi_get_u64(&r);
        if (gi_reader_finish(&r, err))
            return -1;
        if (!photons_ok(p, in->p0, in->p1))
            break;
        return 0;
    case DETP_TASK_VISIBILITY:
    case DETP_TASK_REFERENCE:
        in->a = gi_get_u32(&r);
        in->b = gi_get_u32(&r);
        if (gi_reader_finish(&r, err))
            return -1;
        if (in->a >= in->b || in->b > lim)
            break;
        return 0;
    case DETP_TASK_ANIM_BATCH:
    case DETP_TASK_ANIM_UPDATE:
        in->frame = gi_get_u32(&r);
        in->batch = gi_get_u32(&r);
        in->p0 = gi_get_u64(&r);
        in->p1 = gi_get_u64(&r);
        if (gi_reader_finish(&r, err))
            return -1;
        /* Frame 0 traces a batch, later frames update it; a batch starts
         * where the plan's batch size puts it. */
        if (!gi_anim_moves_object(&p->anim) || in->frame >= p->anim.frames ||
            (in->frame == 0) != (t->kind == DETP_TASK_ANIM_BATCH) ||
            !photons_ok(p, in->p0, in->p1) ||
            in->p0 != (uint64_t)in->batch * (uint64_t)p->batch)
            break;
        return 0;
    default:
        return decode_tile(job, t, &r, in, err);
    }
    return gi_fail(err, GI_EPROTO, "detp %s task %llu: bad payload (out of the job's range)",
                   what, (unsigned long long)t->id);
}
