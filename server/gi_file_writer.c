/* gi_file_writer: a file written on a thread of its own (see the header). */
#include "gi_file_writer.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "gi_clock.h"
#include "gi_fs.h"

struct gi_file_writer {
    pthread_t thread;
    int threaded;
    char *path;
    gi_buf data;
    int rc;
    double seconds;
    gi_error err;
    atomic_int done;
};

static void *write_main(void *arg)
{
    gi_file_writer *w = arg;
    double t0 = gi_now();
    w->rc = gi_write_file_atomic(w->path, w->data.data, w->data.len, &w->err);
    w->seconds = gi_now() - t0;
    atomic_store(&w->done, 1);
    return NULL;
}

gi_file_writer *gi_file_writer_start(const char *path, gi_buf *data)
{
    gi_file_writer *w = gi_xcalloc(1, sizeof *w);
    w->path = gi_xstrdup(path);
    w->data = *data;
    gi_buf_init(data);
    atomic_init(&w->done, 0);
    w->threaded = pthread_create(&w->thread, NULL, write_main, w) == 0;
    if (!w->threaded)
        write_main(w);
    return w;
}

int gi_file_writer_done(gi_file_writer *w) { return atomic_load(&w->done); }

int gi_file_writer_finish(gi_file_writer *w, double *seconds, gi_error *err)
{
    if (w->threaded)
        pthread_join(w->thread, NULL);
    int rc = w->rc;
    if (seconds)
        *seconds = w->seconds;
    if (rc && err)
        *err = w->err;
    gi_buf_free(&w->data);
    free(w->path);
    free(w);
    return rc;
}
