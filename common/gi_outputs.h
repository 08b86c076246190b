/* gi_outputs: writing a job's image outputs (EXR linear float, PNG preview)
 * into its output directory, atomically, and noting them for the summary. */
#ifndef GI_OUTPUTS_H
#define GI_OUTPUTS_H

#include "gi_image.h"
#include "gi_job.h"

/* Writes the "exr" and "png" outputs the job asks for (either may be
 * absent), and notes them. */
int gi_write_image_outputs(gi_job *job, const gi_image *img, gi_error *err);

/* An animation frame's image outputs can also be written on a thread of
 * their own (gi_image_writer) while the coordinator goes on with the next
 * frame: the workers need not wait for the coordinator's compression.
 *
 * The writer owns a copy of the frame's output paths and the image itself
 * (the caller's is left empty), so nothing it touches changes under it.
 * Its outputs are noted in the job (gi_job_note_output) only once they are
 * written, by gi_image_writer_finish on the caller's thread; a write that
 * failed fails there, naming the file. A checkpoint must not claim a frame
 * whose outputs are still being written: call gi_image_writer_wait first. */
typedef struct gi_image_writer gi_image_writer;

/* Starts writing the job's "exr" and "png" outputs of img (paths as the
 * job names them now, e.g. for the current frame). Takes img (left empty).
 * If no thread can be started, writes them before returning. */
gi_image_writer *gi_image_writer_start(gi_job *job, gi_image *img);
/* Waits until the write has ended (w may be NULL): 0 if it succeeded, -1
 * if not (gi_image_writer_finish tells why). */
int gi_image_writer_wait(gi_image_writer *w);
/* The image of a write that failed (waiting for the write first), so that
 * a checkpoint can keep it to be written again; NULL if the write worked
 * (or w is NULL). */
const gi_image *gi_image_writer_failed(gi_image_writer *w);
/* Waits, notes the outputs written, frees *w (NULL after; NULL: nothing to
 * do). Returns 0, or -1 with err if a write failed: then the image goes to
 * *failed (an empty image) if that is given, to be written again, instead
 * of being lost with the writer. */
int gi_image_writer_finish(gi_job *job, gi_image_writer **w, gi_image *failed, gi_error *err);

/* Writes a JSON document as the job's output of `kind` (e.g. "report"), if
 * the job asks for it: pretty-printed, temp file + rename. */
int gi_write_json_output(gi_job *job, const char *kind, const cJSON *doc, gi_error *err);

#endif
