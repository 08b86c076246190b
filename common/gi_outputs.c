/* gi_outputs: image outputs of a job. */
#include "gi_outputs.h"

#include <stdlib.h>

int gi_write_image_outputs(gi_job *job, const gi_image *img, gi_error *err)
{
    const char *exr = gi_job_output(job, "exr"), *png = gi_job_output(job, "png");
    if (exr) {
        char *path = gi_job_output_path(job, exr);
        int rc = gi_exr_write(path, img, err);
        if (rc == 0)
            gi_job_note_output(job, "exr", path);
        free(path);
        if (rc)
            return -1;
    }
    if (png) {
        char *path = gi_job_output_path(job, png);
        int rc = gi_png_write(path, img, job->exposure, err);
        if (rc == 0)
            gi_job_note_output(job, "png", path);
        free(path);
        if (rc)
            return -1;
    }
    return 0;
}
