/* gi_outputs: writing a job's image outputs (EXR linear float, PNG preview)
 * into its output directory, atomically, and noting them for the summary. */
#ifndef GI_OUTPUTS_H
#define GI_OUTPUTS_H

#include "gi_image.h"
#include "gi_job.h"

/* Writes the "exr" and "png" outputs the job asks for (either may be absent). */
int gi_write_image_outputs(gi_job *job, const gi_image *img, gi_error *err);

/* Writes a JSON document as the job's output of `kind` (e.g. "report"), if
 * the job asks for it: pretty-printed, temp file + rename. */
int gi_write_json_output(gi_job *job, const char *kind, const cJSON *doc, gi_error *err);

#endif
