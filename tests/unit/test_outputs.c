/* Unit tests: PLY and JSON outputs; image outputs written on a thread. */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_image.h"
#include "gi_job.h"
#include "gi_mesh.h"
#include "gi_outputs.h"
#include "gi_ply.h"
#include "gi_test.h"

GI_TEST(test_ply_output_reads_back_through_assimp)
{
    gi_error err;
    gi_vec3 pos[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    float rad[12] = {0.5f, 0.25f, 0.0f, 1, 1, 1, 0, 0, 0, 2, 0.1f, 0.2f};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    char path[600];
    snprintf(path, sizeof path, "%s/out.ply", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_ply_write(path, 4, pos, rad, 2, idx, 0.0, &err));
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(path, 1 << 20, &b, &err));
    /* Header + 4 vertices of 27 bytes + 2 faces of 13 bytes. */
    const char *end = strstr((const char *)b.data, "end_header\n");
    GI_REQUIRE(end);
    size_t body = b.len - (size_t)(end + 11 - (const char *)b.data);
    GI_CHECK(body == 4 * 27 + 2 * 13);
    /* Vertex 0's colour: sRGB of 0.5, 0.25, 0. */
    const uint8_t *v0 = (const uint8_t *)end + 11;
    GI_CHECK(v0[12] == gi_srgb8_from_linear(0.5) && v0[13] == gi_srgb8_from_linear(0.25) &&
             v0[14] == 0);
    /* An independent reader (assimp) sees the same geometry. */
    gi_dir_source ds;
    gi_dir_source_init(&ds, gi_test_tmpdir());
    gi_asset_source src = gi_dir_source_as_source(&ds);
    gi_mesh_data m;
    GI_REQUIRE_OK(gi_mesh_import(&src, "out.ply", &m, &err));
    GI_CHECK(m.triangle_count == 2);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&ds);
    gi_buf_free(&b);
    uint32_t bad[3] = {0, 1, 9};
    GI_CHECK(gi_ply_write(path, 4, pos, rad, 1, bad, 0.0, &err) == -1);
}

/* A frame's image outputs written on a thread (gi_image_writer) are the
 * bytes gi_write_image_outputs writes, under the frame's names, noted only
 * once finished; a write that fails (no such directory) fails at wait and
 * at finish, naming the file, and notes nothing. */
/* A job of nothing but the outputs f.exr and f.png into dir. */
static void exr_and_png_job(gi_job *job, char *dir)
{
    memset(job, 0, sizeof *job);
    job->outputs[0] = (gi_output_spec){"exr", "f.exr"};
    job->outputs[1] = (gi_output_spec){"png", "f.png"};
    job->output_count = 2;
    job->out_dir = dir;
}

GI_TEST(test_image_writer_writes_what_the_synchronous_writer_does)
{
    gi_error err;
    static const char *const names[] = {"R", "G", "B"};
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, 40, 30, 3, names, &err));
    for (int i = 0; i < 40 * 30 * 3; i++)
        img.pixels[i] = 0.001f * (float)(i % 997);
    char dir[600], sync_dir[700];
    snprintf(dir, sizeof dir, "%s/writer", gi_test_tmpdir());
    snprintf(sync_dir, sizeof sync_dir, "%s/sync", dir);
    GI_REQUIRE_OK(gi_mkdirs(sync_dir, &err));
    gi_job job;
    exr_and_png_job(&job, sync_dir);
    GI_REQUIRE_OK(gi_write_image_outputs(&job, &img, &err));
    job.out_dir = dir;
    job.in_frame = 1;
    job.frame = 7;
    gi_image copy;
    GI_REQUIRE_OK(gi_image_init(&copy, 40, 30, 3, names, &err));
    memcpy(copy.pixels, img.pixels, sizeof(float) * 40 * 30 * 3);
    int noted = job.written_count;
    gi_image_writer *w = gi_image_writer_start(&job, &copy);
    GI_CHECK(copy.pixels == NULL);   /* taken */
    job.frame = 8;                   /* the next frame goes on meanwhile */
    GI_CHECK(job.written_count == noted);
    GI_REQUIRE_OK(gi_image_writer_finish(&job, &w, NULL, &err));
    GI_CHECK(w == NULL && job.written_count == noted + 4);
    const char *pairs[2][2] = {{"sync/f.exr", "f.0007.exr"}, {"sync/f.png", "f.0007.png"}};
    for (int k = 0; k < 2; k++) {
        char a[800], b[800];
        snprintf(a, sizeof a, "%s/%s", dir, pairs[k][0]);
        snprintf(b, sizeof b, "%s/%s", dir, pairs[k][1]);
        gi_buf x, y;
        gi_buf_init(&x);
        gi_buf_init(&y);
        GI_REQUIRE_OK(gi_read_file(a, 1 << 24, &x, &err));
        GI_REQUIRE_OK(gi_read_file(b, 1 << 24, &y, &err));
        GI_CHECK_MSG(x.len == y.len && memcmp(x.data, y.data, x.len) == 0, "%s differs", b);
        gi_buf_free(&x);
        gi_buf_free(&y);
    }
    char gone[800];
    snprintf(gone, sizeof gone, "%s/no-such-dir", dir);
    job.out_dir = gone;
    /* A write that failed gives its image back, to be written again. */
    GI_REQUIRE_OK(gi_image_init(&copy, 40, 30, 3, names, &err));
    memcpy(copy.pixels, img.pixels, sizeof(float) * 40 * 30 * 3);
    w = gi_image_writer_start(&job, &img);
    GI_CHECK(gi_image_writer_wait(w) == -1);
    const gi_image *failed = gi_image_writer_failed(w);
    GI_CHECK(failed && failed->pixels &&
             memcmp(failed->pixels, copy.pixels, sizeof(float) * 40 * 30 * 3) == 0);
    gi_image back;
    memset(&back, 0, sizeof back);
    GI_CHECK(gi_image_writer_finish(&job, &w, &back, &err) == -1);
    GI_CHECK(strstr(err.msg, "f.0008.exr") != NULL);
    GI_CHECK(w == NULL && job.written_count == noted + 4);
    GI_CHECK(back.pixels && back.width == 40 &&
             memcmp(back.pixels, copy.pixels, sizeof(float) * 40 * 30 * 3) == 0);
    gi_image_free(&back);
    gi_image_free(&copy);
    GI_CHECK(gi_image_writer_failed(NULL) == NULL);
    GI_CHECK(gi_image_writer_finish(&job, &w, NULL, &err) == 0); /* nothing left */
    for (int i = 0; i < job.written_count; i++)
        free(job.written[i]);
}

/* A non-finite pixel reaching a job's image outputs (the methods' checks
 * should have made that impossible) fails the write before any file is
 * made, naming the frame's file, the pixel and the channel; the EXR writer
 * alone still keeps what it is given. */
GI_TEST(test_image_outputs_refuse_a_non_finite_pixel)
{
    gi_error err;
    static const char *const names[] = {"R", "G", "B"};
    char dir[600];
    snprintf(dir, sizeof dir, "%s/nonfinite", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_mkdirs(dir, &err));
    gi_job job;
    exr_and_png_job(&job, dir);
    job.in_frame = 1;
    job.frame = 3;
    const float bad[] = {INFINITY, -INFINITY, NAN};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        gi_image img;
        GI_REQUIRE_OK(gi_image_init(&img, 5, 4, 3, names, &err));
        for (int i = 0; i < 5 * 4 * 3; i++)
            img.pixels[i] = 1e38f;
        gi_image_at(&img, 2, 3)[1] = bad[k];
        char want[64];
        snprintf(want, sizeof want, "pixel (2, 3)'s G is %g", (double)bad[k]);
        GI_CHECK(gi_write_image_outputs(&job, &img, &err) == -1 && err.code == GI_EINTERNAL);
        GI_CHECK_MSG(strstr(err.msg, "f.0003.exr: ") && strstr(err.msg, want), "%s", err.msg);
        gi_image_writer *w = gi_image_writer_start(&job, &img);
        GI_CHECK(gi_image_writer_finish(&job, &w, NULL, &err) == -1);
        GI_CHECK_MSG(strstr(err.msg, want) != NULL, "%s", err.msg);
        gi_image_free(&img);
    }
    GI_CHECK(job.written_count == 0);
    DIR *d = opendir(dir);
    GI_REQUIRE(d != NULL);
    int files = 0;
    for (struct dirent *e; (e = readdir(d));)
        files += e->d_name[0] != '.';
    closedir(d);
    GI_CHECK_MSG(files == 0, "%d files written", files);
}

/* An animation's output names: the frame before the extension, padded to
 * four digits or as many as its last frame has, so they sort in order. */
GI_TEST(test_frame_output_names_sort_in_frame_order)
{
    gi_job job;
    memset(&job, 0, sizeof job);
    job.out_dir = "o";
    char *p = gi_job_output_path(&job, "a.exr");
    GI_CHECK(strcmp(p, "o/a.exr") == 0);
    free(p);
    job.in_frame = 1;
    job.frame = 3;
    job.frame_count = 24;
    p = gi_job_output_path(&job, "a.exr");
    GI_CHECK_MSG(strcmp(p, "o/a.0003.exr") == 0, "%s", p);
    free(p);
    job.frame_count = 10000; /* frames 0 to 9999 */
    p = gi_job_output_path(&job, "noext");
    GI_CHECK_MSG(strcmp(p, "o/noext.0003") == 0, "%s", p);
    free(p);
    job.frame_count = 10002;
    p = gi_job_output_path(&job, "a.exr");
    GI_CHECK_MSG(strcmp(p, "o/a.00003.exr") == 0, "%s", p);
    free(p);
    job.frame = 10001;
    p = gi_job_output_path(&job, "a.exr");
    GI_CHECK_MSG(strcmp(p, "o/a.10001.exr") == 0, "%s", p);
    free(p);
    job.frame_count = 100000;
    job.frame = 7;
    p = gi_job_output_path(&job, "a.b.png");
    GI_CHECK_MSG(strcmp(p, "o/a.b.00007.png") == 0, "%s", p);
    free(p);
}

GI_TEST(test_output_kind_of_a_written_name)
{
    gi_output_spec outs[] = {{"exr", "img.exr"},
                             {"report", "img-report.json"},
                             {"json", "v.json"},
                             {"bin", "raw"}};
    const char *k;
    GI_CHECK((k = gi_job_output_kind(outs, 4, "img.exr")) && strcmp(k, "exr") == 0);
    GI_CHECK((k = gi_job_output_kind(outs, 4, "img.0012.exr")) && strcmp(k, "exr") == 0);
    GI_CHECK((k = gi_job_output_kind(outs, 4, "img-red.exr")) && strcmp(k, "exr") == 0);
    /* The longer stem wins: img-report.json is not a set of img.exr's. */
    GI_CHECK((k = gi_job_output_kind(outs, 4, "img-report.json")) && strcmp(k, "report") == 0);
    GI_CHECK((k = gi_job_output_kind(outs, 4, "img-report.0003.json")) &&
             strcmp(k, "report") == 0);
    GI_CHECK((k = gi_job_output_kind(outs, 4, "v.00003.json")) && strcmp(k, "json") == 0);
    GI_CHECK((k = gi_job_output_kind(outs, 4, "raw.0001")) && strcmp(k, "bin") == 0);
    GI_CHECK(gi_job_output_kind(outs, 4, "img.png") == NULL);
    GI_CHECK(gi_job_output_kind(outs, 4, "img.exr.tmp") == NULL);
    GI_CHECK(gi_job_output_kind(outs, 4, "imgx.exr") == NULL);
    GI_CHECK(gi_job_output_kind(outs, 4, "img..exr") == NULL); /* nothing between */
    GI_CHECK(gi_job_output_kind(outs, 0, "img.exr") == NULL);
}
