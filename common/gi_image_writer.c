/* gi_image_writer: image outputs written on a thread (gi_image_writer.h). */
#include "gi_image_writer.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "gi_outputs.h"

struct gi_image_writer {
    pthread_t thread;
    int running; /* a thread was started and not yet joined */
    gi_image img;
    char *exr, *png; /* paths, or NULL */
    double exposure;
    int rc; /* the write's result, and its error */
    gi_error err;
};

/* Writes the EXR, then the PNG; stops at the first failure. */
static void write_all(gi_image_writer *w)
{
    w->rc = 0;
    if (w->exr)
        w->rc = gi_exr_write(w->exr, &w->img, &w->err);
    if (w->rc == 0 && w->png)
        w->rc = gi_png_write(w->png, &w->img, w->exposure, &w->err);
}

static void *writer_main(void *arg)
{
    write_all(arg);
    return NULL;
}

gi_image_writer *gi_image_writer_start(gi_job *job, gi_image *img)
{
    gi_image_writer *w = gi_xcalloc(1, sizeof *w);
    const char *exr = gi_job_output(job, "exr"), *png = gi_job_output(job, "png");
    w->exr = exr ? gi_job_output_path(job, exr) : NULL;
    w->png = png ? gi_job_output_path(job, png) : NULL;
    w->exposure = job->exposure;
    w->img = *img;
    memset(img, 0, sizeof *img);
    gi_error_clear(&w->err);
    w->running = pthread_create(&w->thread, NULL, writer_main, w) == 0;
    if (!w->running)
        write_all(w); /* no thread: write here */
    return w;
}

int gi_image_writer_wait(gi_image_writer *w)
{
    if (!w)
        return 0;
    if (w->running) {
        pthread_join(w->thread, NULL);
        w->running = 0;
    }
    return w->rc;
}

int gi_image_writer_finish(gi_job *job, gi_image_writer **wp, gi_error *err)
{
    gi_image_writer *w = *wp;
    if (!w)
        return 0;
    gi_image_writer_wait(w);
    int rc = w->rc;
    if (rc)
        *err = w->err;
    else {
        if (w->exr)
            gi_job_note_output(job, "exr", w->exr);
        if (w->png)
            gi_job_note_output(job, "png", w->png);
    }
    gi_image_free(&w->img);
    free(w->exr);
    free(w->png);
    free(w);
    *wp = NULL;
    return rc;
}
