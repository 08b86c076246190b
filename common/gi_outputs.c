/* gi_outputs: image outputs of a job. */
#include "gi_outputs.h"

#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"

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
