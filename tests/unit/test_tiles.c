/* Unit tests: image tiles shaded from surface data. */
#include <stdio.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_job.h"
#include "gi_tile_hits.h"
#include "gi_tiles.h"
#include "gi_test.h"
#include "test_helpers.h"

/* Shades each surface with its material's diffuse colour. */
static gi_vec3 albedo_shader(void *user, const gi_hit *h, gi_vec3 p, gi_vec3 wo)
{
    const gi_scene *s = user;
    return gi_scene_tri_material(s, h->tri)->diffuse;
}

GI_TEST(test_tiles_cover_the_image_and_do_not_depend_on_tile_size)
{
    gi_error err;
    gi_job job;
    memset(&job, 0, sizeof job);
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &job.scene, &err));
    job.width = 37;
    job.height = 29;
    job.seed = 3;
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &job.scene, &err));
    gi_image img[2];
    int sizes[2] = {8, 64};
    for (int k = 0; k < 2; k++) {
        GI_REQUIRE_OK(gi_image_init(&img[k], job.width, job.height, 3, NULL, &err));
        gi_task_queue q;
        gi_task_queue_init(&q, 0);
        gi_buf extra;
        gi_buf_init(&extra);
        gi_buf_put_u32(&extra, 0xabcdef01u);
        gi_tiles_plan(&q, 7, job.width, job.height, sizes[k], 4, &extra);
        double cost = 0;
        for (size_t i = 0; i < q.count; i++) {
            gi_reader r;
            gi_reader_init(&r, q.tasks[i].payload.data, q.tasks[i].payload.len, "tile task");
            gi_tile t;
            GI_REQUIRE_OK(gi_tile_read(&r, job.width, job.height, &t, &err));
            GI_CHECK(gi_get_u32(&r) == 0xabcdef01u && r.left == 0 && q.tasks[i].kind == 7);
            cost += q.tasks[i].cost;
            gi_buf res;
            gi_buf_init(&res);
            GI_REQUIRE_OK(gi_tile_render(&rt, &job, gi_job_camera(&job), &t, 4, albedo_shader,
                                         &job.scene, &res, &err));
            GI_REQUIRE_OK(gi_tile_merge(&img[k], &t, &res, &err));
            gi_buf_free(&res);
        }
        GI_CHECK_NEAR(cost, 37.0 * 29.0 * 4.0, 1e-9);
        gi_buf_free(&extra);
        gi_task_queue_free(&q);
    }
    GI_CHECK(memcmp(img[0].pixels, img[1].pixels, sizeof(float) * 37 * 29 * 3) == 0);
    /* The red wall is in the left half, the green one in the right half,
     * and the image is wider than the box: the outer columns see nothing. */
    int red_left = 0, green_right = 0, wrong_side = 0;
    for (int x = 0; x < job.width; x++) {
        float *p = gi_image_at(&img[0], x, 14);
        int red = fabsf(p[0] - 0.63f) < 1e-6f && fabsf(p[1] - 0.065f) < 1e-6f;
        int green = fabsf(p[0] - 0.14f) < 1e-6f && fabsf(p[1] - 0.45f) < 1e-6f;
        red_left += red && x < job.width / 2;
        green_right += green && x > job.width / 2;
        wrong_side += (red && x > job.width / 2) || (green && x < job.width / 2);
    }
    GI_CHECK(red_left > 0 && green_right > 0 && wrong_side == 0);
    GI_CHECK(gi_image_at(&img[0], 0, 14)[0] == 0.0f);
    gi_image_free(&img[0]);
    gi_image_free(&img[1]);
    gi_rt_free(&rt);
    gi_scene_free(&job.scene);
}

/* A tile's hits file (gi_tile_hits.h) reads back as written, and only for
 * its own tile and spp; damage (every byte flipped, every truncation), a
 * triangle the scene does not have or a hit behind the camera make it
 * "trace again" (0), never an I/O error. */
GI_TEST(test_tile_hits_file_round_trips_and_refuses_damage)
{
    gi_error err;
    char dir[1024], path[1200];
    snprintf(dir, sizeof dir, "%s/tile-hits", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_mkdirs(dir, &err));
    gi_tile t = {16, 8, 20, 11};
    enum { SPP = 2, N = 4 * 3 * SPP, TRIS = 10 };
    gi_tile_hit hits[N], back[2 * N]; /* room for the spp + 1 read below */
    for (int i = 0; i < N; i++)
        hits[i] = (gi_tile_hit){i % 5 == 0 ? GI_TILE_HIT_NONE : (uint32_t)(i % TRIS),
                                0.01f * (float)i, 0.5f - 0.01f * (float)i, 3.0f + (float)i};
    GI_REQUIRE_OK(gi_tile_hits_write(dir, &t, SPP, hits, &err));
    GI_CHECK(gi_tile_hits_read(dir, &t, SPP, TRIS, back, &err) == 1);
    GI_CHECK(memcmp(hits, back, sizeof hits) == 0);
    GI_CHECK(gi_tile_hits_read(dir, &t, SPP + 1, TRIS, back, &err) == 0); /* no such file */
    GI_CHECK(gi_tile_hits_read(dir, &t, SPP, TRIS - 1, back, &err) == 0);
    GI_CHECK(strstr(err.msg, "no triangle") != NULL);

    snprintf(path, sizeof path, "%s/tile.16.8.20.11.2.hits", dir);
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(path, 1 << 20, &b, &err));
    GI_CHECK(b.len == 56 + sizeof hits);
    /* Another tile's file of the same size under this tile's name. */
    gi_tile other = {0, 0, 4, 3};
    GI_REQUIRE_OK(gi_tile_hits_write(dir, &other, SPP, hits, &err));
    char other_path[1200];
    snprintf(other_path, sizeof other_path, "%s/tile.0.0.4.3.2.hits", dir);
    GI_REQUIRE(rename(other_path, path) == 0);
    GI_CHECK(gi_tile_hits_read(dir, &t, SPP, TRIS, back, &err) == 0);
    GI_CHECK(strstr(err.msg, "another tile") != NULL);
    size_t read = 0, io_errors = 0, tried = 0;
    for (size_t i = 0; i < b.len; i++) {
        b.data[i] ^= 0x10;
        GI_REQUIRE_OK(gi_write_file_atomic(path, b.data, b.len, &err));
        b.data[i] ^= 0x10;
        int rc = gi_tile_hits_read(dir, &t, SPP, TRIS, back, &err);
        read += rc == 1;
        io_errors += rc < 0;
        tried++;
    }
    for (size_t len = 0; len < b.len; len++) {
        GI_REQUIRE_OK(gi_write_file_atomic(path, b.data, len, &err));
        int rc = gi_tile_hits_read(dir, &t, SPP, TRIS, back, &err);
        read += rc == 1;
        io_errors += rc < 0;
        tried++;
    }
    GI_CHECK_MSG(read == 0 && io_errors == 0, "%zu of %zu damaged files read, %zu errors", read,
                 tried, io_errors);
    hits[3].t = -1.0f; /* valid CRCs, a hit behind the camera */
    GI_REQUIRE_OK(gi_tile_hits_write(dir, &t, SPP, hits, &err));
    GI_CHECK(gi_tile_hits_read(dir, &t, SPP, TRIS, back, &err) == 0);
    gi_buf_free(&b);
}
