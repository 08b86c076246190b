/* gi_outputs: image and JSON outputs of a job (gi_outputs.h). */
#include "gi_outputs.h"

#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_thread_call.h"

/* A frame's image outputs: their paths (as the job names them when the
 * write starts), the image, and how the write went. */
struct gi_image_writer {
    gi_thread_call *call;  /* the write on its thread, until joined */
    gi_image owned;        /* the image, when the writer took it */
    const gi_image *img;   /* what is written: &owned, or the caller's */
    char *exr, *png;       /* paths, or NULL */
    double exposure;
    int rc;                /* the write's result, and its error */
    gi_error err;
};

static gi_image_writer *writer_new(gi_job *job, const gi_image *img)
{
    gi_image_writer *w = gi_xcalloc(1, sizeof *w);
    const char *exr = gi_job_output(job, "exr"), *png = gi_job_output(job, "png");
    w->exr = exr ? gi_job_output_path(job, exr) : NULL;
    w->png = png ? gi_job_output_path(job, png) : NULL;
    w->exposure = job->exposure;
    w->img = img;
    gi_error_clear(&w->err);
    return w;
}

/* Writes the EXR, then the PNG; stops at the first failure. A non-finite
 * pixel fails before either is started (gi_image_check_finite). */
static void write_all(gi_image_writer *w)
{
    w->rc = 0;
    if (w->exr || w->png)
        w->rc = gi_image_check_finite(w->img, w->exr ? w->exr : w->png, &w->err);
    if (w->rc == 0 && w->exr)
        w->rc = gi_exr_write(w->exr, w->img, &w->err);
    if (w->rc == 0 && w->png)
        w->rc = gi_png_write(w->png, w->img, w->exposure, &w->err);
}

static void writer_main(void *arg) { write_all(arg); }

int gi_write_image_outputs(gi_job *job, const gi_image *img, gi_error *err)
{
    gi_image_writer *w = writer_new(job, img);
    write_all(w);
    return gi_image_writer_finish(job, &w, NULL, err);
}

gi_image_writer *gi_image_writer_start(gi_job *job, gi_image *img)
{
    gi_image_writer *w = writer_new(job, NULL);
    w->owned = *img;
    w->img = &w->owned;
    memset(img, 0, sizeof *img);
    w->call = gi_thread_call_start(writer_main, w, -1); /* no thread: written here */
    return w;
}

int gi_image_writer_wait(gi_image_writer *w)
{
    if (!w)
        return 0;
    gi_thread_call_join(w->call);
    w->call = NULL;
    return w->rc;
}

const gi_image *gi_image_writer_failed(gi_image_writer *w)
{
    return gi_image_writer_wait(w) ? w->img : NULL;
}

int gi_image_writer_finish(gi_job *job, gi_image_writer **wp, gi_image *failed, gi_error *err)
{
    gi_image_writer *w = *wp;
    if (!w)
        return 0;
    int rc = gi_image_writer_wait(w);
    if (rc) {
        *err = w->err;
        if (failed && w->img == &w->owned) {
            *failed = w->owned;
            memset(&w->owned, 0, sizeof w->owned);
        }
    } else {
        if (w->exr)
            gi_job_note_output(job, "exr", w->exr);
        if (w->png)
            gi_job_note_output(job, "png", w->png);
    }
    gi_image_free(&w->owned);
    free(w->exr);
    free(w->png);
    free(w);
    *wp = NULL;
    return rc;
}

int gi_write_json_output(gi_job *job, const char *kind, const cJSON *doc, gi_error *err)
{
    const char *file = gi_job_output(job, kind);
    if (!file)
        return 0;
    char *text = cJSON_Print(doc);
    if (!text)
        return gi_fail(err, GI_ENOMEM, "%s: cannot format the %s output", job->name, kind);
    char *path = gi_job_output_path(job, file);
    size_t len = strlen(text);
    text[len] = '\n'; /* replaces the NUL: the file ends with a newline */
    int rc = gi_write_file_atomic(path, text, len + 1, err);
    if (rc == 0)
        gi_job_note_output(job, kind, path);
    free(path);
    cJSON_free(text);
    return rc;
}
