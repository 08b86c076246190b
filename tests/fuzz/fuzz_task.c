/* fuzz_task: libFuzzer target for the task payloads a worker reads from a
 * TASK message before it runs anything: pt tiles (pt_task.h), detp batches,
 * visibility and reference ranges, animation batches and tiles
 * (detp_task_decode), radiosity form-factor blocks and tiles (rad_task.h).
 * Quadrature's task payloads are in fuzz_quad.
 *
 * The first byte picks the decoder (% 10: 0 pt, 1..7 detp's task kinds,
 * 8 radiosity FF, 9 radiosity tile); its bit 7 takes the pt job with an
 * animation, the detp job without one, and radiosity tiles as a worker
 * reads them (emissions unknown) of a job with a camera path. The rest is
 * the payload, read against a fixed small job.
 *
 * Any payload must decode or fail with GI_EPROTO and a one-line message,
 * never crash, leak or hang. One that decodes must be in the job's range
 * (what the worker then relies on) and encode back to the same bytes.
 *
 * With GI_FUZZ_TASK_SEEDS=DIR in the environment it writes the seed corpus
 * instead, every task of the fixed job as the plans encode it (gi_tiles_plan,
 * detp_task_encode), and exits. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "detp/detp_method.h"
#include "gi_fs.h"
#include "pt/pt.h"
#include "pt/pt_task.h"
#include "radiosity/rad.h"
#include "radiosity/rad_task.h"

/* The fixed job. */
#define WIDTH 40
#define HEIGHT 30
#define SPP 64
#define PHOTONS 1000
#define BATCH 100
#define FRAMES 5
#define LIM 50      /* visibility vertices, reference indices */
#define ELEMENTS 77 /* radiosity */
#define EMISSIONS 3
#define DECODERS 10

static const char HASH[] = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";

static gi_pt_job_params pt_params, pt_anim_params;
static gi_detp_params detp_params, detp_still_params;
static gi_rad_params rad_params, rad_path_params;

/* The jobs' parameters, once (they are large, an animation block each, and
 * the decoders only read them). */
static void params_init(void)
{
    gi_pt_params_default(&pt_params.pt);
    pt_params.pt.spp = SPP;
    pt_anim_params = pt_params;
    pt_anim_params.anim.enabled = 1;
    pt_anim_params.anim.frames = FRAMES;
    detp_params.photon_count = PHOTONS;
    detp_params.batch = BATCH;
    detp_still_params = detp_params;
    detp_params.anim.enabled = 1;
    detp_params.anim.frames = FRAMES;
    strcpy(detp_params.anim.object, "mobile"); /* its batches' tasks need a moving object */
    rad_path_params.anim.enabled = 1;
    rad_path_params.anim.frames = FRAMES;
}

static void job_init(gi_job *job, int still)
{
    memset(job, 0, sizeof *job);
    job->width = WIDTH;
    job->height = HEIGHT;
    job->params = still ? &detp_still_params : &detp_params;
}

static void check_error(int rc, const gi_error *err)
{
    if (rc == 0 || err->code != GI_EPROTO || !err->msg[0] || strchr(err->msg, '\n'))
        abort();
}

static void same(const gi_buf *b, const uint8_t *data, size_t n)
{
    if (b->len != n || memcmp(b->data, data, n) != 0)
        abort();
}

static void put_tile(gi_buf *b, const gi_tile *t)
{
    gi_buf_put_u32(b, t->x0);
    gi_buf_put_u32(b, t->y0);
    gi_buf_put_u32(b, t->x1);
    gi_buf_put_u32(b, t->y1);
}

static void tile_in_image(const gi_tile *t)
{
    if (t->x0 >= t->x1 || t->y0 >= t->y1 || t->x1 > WIDTH || t->y1 > HEIGHT)
        abort();
}

static int one(gi_job *job, int which, int flag, gi_task *t)
{
    int rc;
    gi_error err;
    gi_error_clear(&err);
    gi_buf out;
    gi_buf_init(&out);
    const uint8_t *in = t->payload.data;
    size_t n = t->payload.len;
    if (which == 0) {
        job->params = flag ? &pt_anim_params : &pt_params;
        t->kind = PT_TASK_TILE;
        gi_pt_task pt;
        rc = gi_pt_task_decode(job, t, &pt, &err);
        if (rc) {
            check_error(rc, &err);
        } else {
            tile_in_image(&pt.tile);
            if (pt.s0 >= pt.s1 || pt.s1 > SPP || pt.frame >= (flag ? FRAMES : 1))
                abort();
            put_tile(&out, &pt.tile);
            gi_buf_put_u32(&out, pt.s0);
            gi_buf_put_u32(&out, pt.s1);
            if (flag)
                gi_buf_put_u32(&out, pt.frame);
            same(&out, in, n);
        }
    } else if (which <= 7) {
        t->kind = (uint32_t)which;
        detp_task_in d;
        rc = detp_task_decode(job, t, LIM, &d, &err);
        if (rc) {
            check_error(rc, &err);
        } else {
            if (t->kind == DETP_TASK_BATCH || t->kind == DETP_TASK_ANIM_BATCH ||
                t->kind == DETP_TASK_ANIM_UPDATE)
                if (d.p0 >= d.p1 || d.p1 > PHOTONS)
                    abort();
            if ((t->kind == DETP_TASK_VISIBILITY || t->kind == DETP_TASK_REFERENCE) &&
                (d.a >= d.b || d.b > LIM))
                abort();
            if (t->kind >= DETP_TASK_ANIM_BATCH && d.frame >= FRAMES)
                abort();
            if (t->kind == DETP_TASK_TILE || t->kind == DETP_TASK_ANIM_TILE) {
                tile_in_image(&d.tile);
                if (!gi_hash_is_valid(d.hash))
                    abort();
            }
            detp_task_encode(t->kind, &d, &out);
            same(&out, in, n);
        }
    } else if (which == 8) {
        t->kind = RAD_TASK_FF;
        uint32_t e0, e1;
        rc = gi_rad_task_block_decode(t, ELEMENTS, &e0, &e1, &err);
        if (rc) {
            check_error(rc, &err);
        } else {
            if (e0 >= e1 || e1 > ELEMENTS)
                abort();
            gi_buf_put_u32(&out, e0);
            gi_buf_put_u32(&out, e1);
            same(&out, in, n);
        }
    } else {
        t->kind = RAD_TASK_TILE;
        job->params = flag ? &rad_path_params : &rad_params;
        uint32_t emissions = flag ? UINT32_MAX : EMISSIONS;
        gi_rad_tile_task tt;
        rc = gi_rad_task_tile_decode(job, t, emissions, &tt, &err);
        if (rc) {
            check_error(rc, &err);
        } else {
            tile_in_image(&tt.tile);
            if (tt.emission >= emissions || !gi_hash_is_valid(tt.hash) ||
                tt.frame >= (flag ? FRAMES : 1))
                abort();
            put_tile(&out, &tt.tile);
            gi_buf_put_u32(&out, tt.emission);
            gi_buf_put_str(&out, tt.hash);
            if (flag)
                gi_buf_put_u32(&out, tt.frame);
            same(&out, in, n);
        }
    }
    gi_buf_free(&out);
    return rc;
}

static void one_input(const uint8_t *data, size_t size, int must_decode)
{
    gi_job job;
    int flag = data[0] >> 7;
    job_init(&job, flag);
    gi_task t;
    memset(&t, 0, sizeof t);
    t.id = 7;
    gi_buf_init(&t.payload);
    gi_buf_put(&t.payload, data + 1, size - 1);
    if (one(&job, (data[0] & 0x7f) % DECODERS, flag, &t) && must_decode)
        abort();
    gi_buf_free(&t.payload);
}

/* Writes one seed: the decoder's byte, then the payload. */
static void seed(const char *dir, int which, const gi_buf *payload, int *count)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%d-%03d", dir, which, (*count)++);
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_u8(&b, (uint8_t)which);
    gi_buf_put(&b, payload->data, payload->len);
    one_input(b.data, b.len, 1); /* the plans' payloads decode */
    gi_error err;
    if (gi_write_file_atomic(path, b.data, b.len, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    gi_buf_free(&b);
}

/* Tile tasks as gi_tiles_plan writes them (16-pixel tiles), with extra. */
static void seed_tiles(const char *dir, int which, const gi_buf *extra, int *count)
{
    gi_task_queue q;
    gi_task_queue_init(&q, 0);
    gi_tiles_plan(&q, 0, WIDTH, HEIGHT, 16, 1, extra);
    for (size_t i = 0; i < q.count; i++)
        seed(dir, which, &q.tasks[i].payload, count);
    gi_task_queue_free(&q);
}

static void write_seeds(const char *dir)
{
    gi_error err;
    if (gi_mkdirs(dir, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    int count = 0;
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_u32(&b, 8);
    gi_buf_put_u32(&b, SPP);
    seed_tiles(dir, 0, &b, &count);
    gi_buf_put_u32(&b, FRAMES - 1); /* an animation's frame */
    seed_tiles(dir, 0x80, &b, &count);
    detp_task_in d = {.p0 = 300, .p1 = 400, .a = 10, .b = LIM, .frame = 2, .batch = 3};
    memcpy(d.hash, HASH, sizeof HASH);
    for (uint32_t kind = DETP_TASK_BATCH; kind <= DETP_TASK_ANIM_UPDATE; kind++) {
        if (kind == DETP_TASK_TILE)
            continue;
        d.frame = kind == DETP_TASK_ANIM_BATCH ? 0 : 2;
        gi_buf_reset(&b);
        detp_task_encode(kind, &d, &b);
        seed(dir, (int)kind, &b, &count);
    }
    for (int anim = 0; anim < 2; anim++) { /* plan_tiles's extra bytes */
        gi_buf_reset(&b);
        gi_buf_put_str(&b, HASH);
        if (anim)
            gi_buf_put_u32(&b, FRAMES - 1);
        seed_tiles(dir, anim ? DETP_TASK_ANIM_TILE : DETP_TASK_TILE, &b, &count);
    }
    gi_buf_reset(&b);
    gi_buf_put_u32(&b, 70);
    gi_buf_put_u32(&b, ELEMENTS);
    seed(dir, 8, &b, &count);
    gi_buf_reset(&b);
    gi_buf_put_u32(&b, EMISSIONS - 1);
    gi_buf_put_str(&b, HASH);
    seed_tiles(dir, 9, &b, &count);
    gi_buf_put_u32(&b, FRAMES - 1); /* a camera path's frame */
    seed_tiles(dir, 0x80 | 9, &b, &count);
    gi_buf_free(&b);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    params_init();
    const char *dir = getenv("GI_FUZZ_TASK_SEEDS");
    if (dir) {
        write_seeds(dir);
        exit(0);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size >= 1)
        one_input(data, size, 0);
    return 0;
}
