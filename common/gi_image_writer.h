/* gi_image_writer: a frame's image outputs (gi_write_image_outputs: EXR,
 * PNG) written on a thread of their own while the coordinator goes on with
 * the next frame of an animation: the workers need not wait for the
 * coordinator's compression.
 *
 * The writer owns a copy of the frame's output paths and the image itself
 * (the caller's is left empty), so nothing it touches changes under it.
 * Its outputs are noted in the job (gi_job_note_output) only once they are
 * written, by gi_image_writer_finish on the caller's thread; a write that
 * failed fails there, naming the file. A checkpoint must not claim a frame
 * whose outputs are still being written: call gi_image_writer_wait first. */
#ifndef GI_IMAGE_WRITER_H
#define GI_IMAGE_WRITER_H

#include "gi_image.h"
#include "gi_job.h"

typedef struct gi_image_writer gi_image_writer;

/* Starts writing the job's "exr" and "png" outputs of img (paths as the
 * job names them now, e.g. for the current frame). Takes img (left empty).
 * If no thread can be started, writes them before returning. */
gi_image_writer *gi_image_writer_start(gi_job *job, gi_image *img);
/* Waits until the write has ended (w may be NULL): 0 if it succeeded, -1
 * if not (gi_image_writer_finish tells why). */
int gi_image_writer_wait(gi_image_writer *w);
/* Waits, notes the outputs written, frees *w (NULL after; NULL: nothing to
 * do). Returns 0, or -1 with err if a write failed. */
int gi_image_writer_finish(gi_job *job, gi_image_writer **w, gi_error *err);

#endif
