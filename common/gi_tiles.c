/* gi_tiles: tile tasks for images shaded from precomputed surface data. */
#include "gi_tiles.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "gi_camera.h"
#include "gi_rng.h"

void gi_tiles_plan(gi_task_queue *q, uint32_t kind, int width, int height, int tile, int spp,
                   const gi_buf *extra)
{
    for (int y0 = 0; y0 < height; y0 += tile)
        for (int x0 = 0; x0 < width; x0 += tile) {
            int x1 = x0 + tile < width ? x0 + tile : width;
            int y1 = y0 + tile < height ? y0 + tile : height;
            gi_task *t = gi_task_queue_add(q, kind, (double)(x1 - x0) * (y1 - y0) * spp);
            gi_buf_put_u32(&t->payload, (uint32_t)x0);
            gi_buf_put_u32(&t->payload, (uint32_t)y0);
            gi_buf_put_u32(&t->payload, (uint32_t)x1);
            gi_buf_put_u32(&t->payload, (uint32_t)y1);
            if (extra)
                gi_buf_put(&t->payload, extra->data, extra->len);
        }
}

int gi_tile_read(gi_reader *r, int width, int height, gi_tile *t, gi_error *err)
{
    t->x0 = gi_get_u32(r);
    t->y0 = gi_get_u32(r);
    t->x1 = gi_get_u32(r);
    t->y1 = gi_get_u32(r);
    if (r->failed || t->x0 >= t->x1 || t->y0 >= t->y1 || t->x1 > (uint32_t)width ||
        t->y1 > (uint32_t)height)
        return gi_fail(err, GI_EPROTO, "%s: tile out of range", r->what);
    return 0;
}

/* The moving object of gi_tile_render_split, and the hits of the rest. */
typedef struct split_ctx {
    uint32_t object;
    gi_vec3 c;
    float r2; /* its bounding sphere, radius squared */
    gi_tile_hit *rest;
    int rest_known;
} split_ctx;

/* The ray (unit dir) passes within sqrt(r2) of c somewhere in [0, tfar]. */
static int ray_meets_sphere(gi_vec3 org, gi_vec3 dir, gi_vec3 c, float r2, float tfar)
{
    gi_vec3 oc = gi_sub(c, org);
    float b = gi_dot(oc, dir);
    float d2 = gi_dot(oc, oc) - b * b;
    if (d2 > r2)
        return 0;
    float half = sqrtf(r2 - d2);
    return b + half >= 0.0f && b - half <= tfar;
}

/* One primary ray's hit: through the whole scene, or split into the rest
 * (known, or traced and kept in *rest) and the object alone. */
static int primary_hit(gi_rt *rt, split_ctx *sp, gi_tile_hit *rest, gi_vec3 org, gi_vec3 dir,
                       gi_hit *h)
{
    if (!sp)
        return gi_rt_intersect(rt, org, dir, 0.0f, FLT_MAX, h);
    int any;
    if (sp->rest_known) {
        any = rest->tri != GI_TILE_HIT_NONE;
        h->tri = rest->tri;
        h->u = rest->u;
        h->v = rest->v;
        h->t = rest->t;
    } else {
        any = gi_rt_intersect_except(rt, sp->object, org, dir, 0.0f, FLT_MAX, h);
        *rest = (gi_tile_hit){any ? h->tri : GI_TILE_HIT_NONE, any ? h->u : 0.0f,
                              any ? h->v : 0.0f, any ? h->t : 0.0f};
    }
    h->ng = gi_v3(0, 0, 0); /* not kept: the same whether traced or known */
    float tfar = any ? h->t : FLT_MAX;
    if (ray_meets_sphere(org, dir, sp->c, sp->r2, tfar)) {
        rt->rays++;
        any |= gi_rt_intersect_in(rt, rt->alone[sp->object], org, dir, 0.0f, tfar, h);
    }
    return any;
}

static void render(gi_rt *rt, const gi_job *job, const gi_camera *camera, const gi_tile *t,
                   int spp, split_ctx *sp, gi_surface_shader shade, void *user, gi_buf *result)
{
    gi_camera_frame cam;
    gi_camera_frame_init(&cam, camera, job->width, job->height);
    size_t npix = (size_t)(t->x1 - t->x0) * (t->y1 - t->y0);
    float *px = gi_xcalloc(npix * 3, sizeof *px);
    size_t k = 0;
    uint64_t seed_key = gi_rng_seed_key(job->seed);
    for (uint32_t y = t->y0; y < t->y1; y++)
        for (uint32_t x = t->x0; x < t->x1; x++, k++) {
            uint64_t pixel = (uint64_t)y * (uint64_t)job->width + x;
            uint64_t pixel_key = gi_rng_stream_key(seed_key, pixel);
            double sum[3] = {0, 0, 0};
            for (int s = 0; s < spp; s++) {
                gi_rng rng; /* gi_rng_init(seed, pixel, s) */
                gi_rng_init_stream(&rng, pixel_key, (uint32_t)s);
                float jx = spp > 1 ? gi_rng_float(&rng) : 0.5f;
                float jy = spp > 1 ? gi_rng_float(&rng) : 0.5f;
                gi_vec3 dir = gi_camera_dir(&cam, (float)x + jx, (float)y + jy);
                gi_hit h;
                gi_tile_hit *rest = sp ? &sp->rest[k * (size_t)spp + (size_t)s] : NULL;
                if (!primary_hit(rt, sp, rest, cam.origin, dir, &h))
                    continue;
                gi_vec3 L = shade(user, &h, gi_madd(cam.origin, dir, h.t), gi_neg(dir));
                sum[0] += L.x;
                sum[1] += L.y;
                sum[2] += L.z;
            }
            for (int c = 0; c < 3; c++)
                px[3 * k + c] = (float)(sum[c] / spp);
        }
    gi_buf_put_f32s(result, px, npix * 3);
    free(px);
}

int gi_tile_render(gi_rt *rt, const gi_job *job, const gi_camera *cam, const gi_tile *t, int spp,
                   gi_surface_shader shade, void *user, gi_buf *result, gi_error *err)
{
    (void)err;
    render(rt, job, cam, t, spp, NULL, shade, user, result);
    return 0;
}

int gi_tile_render_split(gi_rt *rt, const gi_job *job, const gi_camera *cam, const gi_tile *t,
                         int spp, uint32_t object, gi_vec3 c, float r, gi_tile_hit *rest,
                         int rest_known,
                         gi_surface_shader shade, void *user, gi_buf *result, gi_error *err)
{
    if (!gi_rt_splits(rt, object))
        return gi_fail(err, GI_EINTERNAL, "gi_tile_render_split: object %u is not mobile",
                       object);
    /* Grown well past rounding: a false pass only costs a ray. */
    float rr = r * 1.001f + 1e-4f * (1.0f + gi_length(c));
    split_ctx sp = {object, c, rr * rr, rest, rest_known};
    render(rt, job, cam, t, spp, &sp, shade, user, result);
    return 0;
}

int gi_tile_check_result(const gi_tile *t, const uint8_t *px, size_t len, gi_error *err)
{
    uint32_t w = t->x1 - t->x0;
    size_t want = (size_t)w * (t->y1 - t->y0) * 12;
    if (len != want)
        return gi_fail(err, GI_EPROTO, "tile result has %zu bytes, expected %zu", len, want);
    for (size_t i = 0; i + 4 <= len; i += 4) {
        float v;
        memcpy(&v, px + i, 4); /* little-endian hosts only (gi_buf.h) */
        if (!isfinite(v)) {
            size_t pix = i / 12;
            return gi_fail(err, GI_EPROTO, "pixel (%u, %u) is not finite (%g)",
                           t->x0 + (uint32_t)(pix % w), t->y0 + (uint32_t)(pix / w), (double)v);
        }
    }
    return 0;
}

int gi_tile_merge(gi_image *img, const gi_tile *t, const gi_buf *result, gi_error *err)
{
    size_t npix = (size_t)(t->x1 - t->x0) * (t->y1 - t->y0);
    if (img->channels < 3 || t->x1 > (uint32_t)img->width || t->y1 > (uint32_t)img->height)
        return gi_fail(err, GI_EINTERNAL, "tile does not fit the image");
    if (result->len != npix * 3 * 4)
        return gi_fail(err, GI_EPROTO, "tile result has %zu bytes, expected %zu", result->len,
                       npix * 12);
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "tile result");
    for (uint32_t y = t->y0; y < t->y1; y++) {
        if (img->channels == 3) { /* a row of the tile is a run of the image's */
            gi_get_f32s(&r, gi_image_at(img, (int)t->x0, (int)y), (size_t)(t->x1 - t->x0) * 3);
            continue;
        }
        for (uint32_t x = t->x0; x < t->x1; x++) {
            float *p = gi_image_at(img, (int)x, (int)y);
            for (int c = 0; c < 3; c++)
                p[c] = gi_get_f32(&r);
        }
    }
    return gi_reader_finish(&r, err);
}
