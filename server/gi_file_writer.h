/* gi_file_writer: a buffer written to a file (atomically: gi_write_file_atomic)
 * on a thread of its own, so that a loop that must keep answering (gi-farmd)
 * does not wait for a big checkpoint to reach the disk. */
#ifndef GI_FILE_WRITER_H
#define GI_FILE_WRITER_H

#include "gi_buf.h"
#include "gi_error.h"

typedef struct gi_file_writer gi_file_writer;

/* Starts writing data (taken over: *data is left empty) to path. Never
 * NULL: without a thread, the file is written before it returns. */
gi_file_writer *gi_file_writer_start(const char *path, gi_buf *data);
/* 1 once the write has ended (gi_file_writer_finish then does not wait). */
int gi_file_writer_done(gi_file_writer *w);
/* Waits for the write to end and frees w: 0 if the file is in place, else -1
 * with err. *seconds (may be NULL): how long the write took. */
int gi_file_writer_finish(gi_file_writer *w, double *seconds, gi_error *err);

#endif
