/* gi_file_writer: a file written on a thread of its own (see the header). */
#include "gi_file_writer.h"

#include <stdlib.h>

#include "gi_clock.h"
#include "gi_fs.h"
#include "gi_thread_call.h"

struct gi_file_writer {
    gi_thread_call *call;
    char *path;
    gi_buf data;
    int rc;
    double seconds;
    gi_error err;
};

static void write_main(void *arg)
{
    gi_file_writer *w = arg;
    double t0 = gi_now();
    w->rc = gi_write_file_atomic(w->path, w->data.data, w->data.len, &w->err);
    w->seconds = gi_now() - t0;
}

gi_file_writer *gi_file_writer_start(const char *path, gi_buf *data)
{
    gi_file_writer *w = gi_xcalloc(1, sizeof *w);
    w->path = gi_xstrdup(path);
    w->data = *data;
    gi_buf_init(data);
    w->call = gi_thread_call_start(write_main, w, -1);
    return w;
}

int gi_file_writer_done(gi_file_writer *w) { return gi_thread_call_done(w->call); }

int gi_file_writer_finish(gi_file_writer *w, double *seconds, gi_error *err)
{
    gi_thread_call_join(w->call);
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
