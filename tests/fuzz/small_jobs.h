/* small_jobs: the scene and the four small jobs (detp, a detp animation, pt,
 * radiosity) that fuzz_checkpoint and fuzz_result run in-process to record
 * their seeds and restore points. Their order is the selector byte's in
 * fuzz_checkpoint's corpus: append, never reorder. */
#ifndef GI_FUZZ_SMALL_JOBS_H
#define GI_FUZZ_SMALL_JOBS_H

#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_job.h"
#include "gi_jobrun.h"
#include "gi_worker_ctx.h"

static const char small_scene_text[] =
    "{\"camera\": {\"position\": [0, 0, -0.9], \"look_at\": [0, 0, 0], \"fov_y\": 60},"
    " \"materials\": {\"wall\": {\"diffuse\": [0.6, 0.6, 0.6]},"
    "  \"lamp\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [5, 5, 5]}},"
    " \"objects\": ["
    "  {\"name\": \"room\", \"material\": \"wall\","
    "   \"box\": {\"size\": [2, 2, 2], \"inward\": true}},"
    "  {\"name\": \"lamp\", \"material\": \"lamp\", \"quad\": {\"size\": [0.5, 0.5]},"
    "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
    "                   {\"translate\": [0, 0.99, 0]}]},"
    "  {\"name\": \"ball\", \"material\": \"wall\", \"mobile\": true,"
    "   \"sphere\": {\"radius\": 0.2, \"subdivisions\": 0}}]}";

#define SMALL_JOB_TEXTS \
    "{\"scene\": \"scene.json\", \"method\": \"detp\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"detp\": {\"photons\": 3000, \"batch\": 1000, \"tile\": 4, \"image_spp\": 1}," \
    " \"outputs\": {\"exr\": \"a.exr\", \"bin\": \"a.bin\", \"json\": \"a.json\"}}", \
    "{\"scene\": \"scene.json\", \"method\": \"detp\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"detp\": {\"photons\": 3000, \"batch\": 1000, \"tile\": 4, \"image_spp\": 1," \
    "  \"animation\": {\"object\": \"ball\", \"frames\": 3," \
    "   \"keyframes\": [{\"frame\": 0}, {\"frame\": 2, \"translate\": [0.2, 0, 0]}]}}," \
    " \"outputs\": {\"exr\": \"b.exr\", \"bin\": \"b.bin\", \"json\": \"b.json\"}}", \
    "{\"scene\": \"scene.json\", \"method\": \"pt\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"pt\": {\"spp\": 4, \"tile\": 4, \"pass_spp\": 1}," \
    " \"outputs\": {\"exr\": \"c.exr\"}}", \
    "{\"scene\": \"scene.json\", \"method\": \"radiosity\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"radiosity\": {\"patches\": 4, \"levels\": 1, \"rays\": 16, \"task_elements\": 40}," \
    " \"outputs\": {\"exr\": \"d.exr\", \"report\": \"d.json\"}}"
#define SMALL_JOBS 4
/* A detp and a radiosity camera path (the light computed once and seen
 * along it), which the targets append after their own jobs. */
#define SMALL_JOB_DETP_CAMERA \
    "{\"scene\": \"scene.json\", \"method\": \"detp\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"detp\": {\"photons\": 3000, \"batch\": 1000, \"tile\": 4, \"image_spp\": 1," \
    "  \"animation\": {\"frames\": 3, \"camera\": [" \
    "   {\"frame\": 0, \"position\": [0, 0, -0.9], \"look_at\": [0, 0, 0], \"fov_y\": 60}," \
    "   {\"frame\": 1, \"position\": [0.3, 0.2, -0.8], \"look_at\": [0, 0, 0], \"fov_y\": 70}]}}," \
    " \"outputs\": {\"exr\": \"f.exr\", \"bin\": \"f.bin\", \"json\": \"f.json\"}}"
#define SMALL_JOB_RAD_CAMERA \
    "{\"scene\": \"scene.json\", \"method\": \"radiosity\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"radiosity\": {\"patches\": 4, \"levels\": 1, \"rays\": 16, \"task_elements\": 40," \
    "  \"tile\": 4, \"animation\": {\"frames\": 3, \"camera\": [" \
    "   {\"frame\": 0, \"position\": [0, 0, -0.9], \"look_at\": [0, 0, 0], \"fov_y\": 60}," \
    "   {\"frame\": 1, \"position\": [0.3, 0.2, -0.8], \"look_at\": [0, 0, 0], \"fov_y\": 70}]}}," \
    " \"outputs\": {\"exr\": \"g.exr\", \"report\": \"g.json\"}}"

#define SMALL_JOB_PATH_MAX 300

static char small_jobs_dir[256];

static int small_jobs_remove_one(const char *path, const struct stat *st, int type,
                                 struct FTW *ftw)
{
    (void)st;
    (void)type;
    (void)ftw;
    return remove(path);
}

/* Removes the directory small_jobs_write made (atexit). */
static void small_jobs_remove(void)
{
    nftw(small_jobs_dir, small_jobs_remove_one, 16, FTW_DEPTH | FTW_PHYS);
}

/* A fresh directory under $TMPDIR named after `target`, with out/, the
 * scene and the n jobs of texts (their paths into paths); aborts on any
 * error: a fuzz target cannot start without them. */
static void small_jobs_write(const char *target, const char *const *texts, int n,
                             char (*paths)[SMALL_JOB_PATH_MAX])
{
    snprintf(small_jobs_dir, sizeof small_jobs_dir, "%s/gi-fuzz-%s.XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", target);
    gi_error err;
    if (!mkdtemp(small_jobs_dir))
        abort();
    char *out = gi_path_join(small_jobs_dir, "out");
    if (gi_mkdirs(out, &err))
        abort();
    free(out);
    char *scene = gi_path_join(small_jobs_dir, "scene.json");
    if (gi_write_file_atomic(scene, small_scene_text, strlen(small_scene_text), &err))
        abort();
    free(scene);
    for (int i = 0; i < n; i++) {
        snprintf(paths[i], SMALL_JOB_PATH_MAX, "%s/job%d.json", small_jobs_dir, i);
        if (gi_write_file_atomic(paths[i], texts[i], strlen(texts[i]), &err))
            abort();
    }
}

/* The job at path, its outputs under small_jobs_dir/out. */
static int small_jobs_load(const char *path, gi_job *job, gi_error *err)
{
    if (gi_job_load(path, job, err))
        return -1;
    job->out_dir = gi_path_join(small_jobs_dir, "out");
    return 0;
}

/* The job at path loaded, an in-process worker for it (its batches under
 * small_jobs_dir) and its run started, to be driven task by task. */
static int small_jobs_start(const char *path, gi_job *job, gi_worker_ctx *ctx, gi_jobrun *jr,
                            gi_error *err)
{
    if (small_jobs_load(path, job, err) ||
        gi_worker_ctx_load(ctx, 1, job->file, job->text, &job->manifest, NULL, NULL,
                           job->assets, err))
        return -1;
    ctx->batch_dir = gi_path_join(small_jobs_dir, "batches");
    return gi_jobrun_start(jr, job, err);
}

#endif
