/* gi_local_checkpoint: `gi render`'s checkpoint, so that an interrupted or
 * killed render resumes (`gi render JOB --resume`) instead of starting over.
 *
 * The file is OUT/.NAME.checkpoint (NAME: the job's name), written whole
 * under a temporary name and renamed: u32 magic "GILC", u32 version, the
 * job's identity (BLAKE2b-256, hex, of the job file's text and of the name
 * and hash of every file its scene read), then gi_jobrun_checkpoint's bytes.
 * A checkpoint of another job (edited, or its scene's files changed) is
 * refused rather than resumed. */
#ifndef GI_LOCAL_CHECKPOINT_H
#define GI_LOCAL_CHECKPOINT_H

#include "gi_job.h"
#include "gi_jobrun.h"

/* OUT/.NAME.checkpoint (malloc'ed). */
char *gi_local_checkpoint_path(const gi_job *job);
int gi_local_checkpoint_write(const gi_jobrun *jr, const char *path, gi_error *err);
/* Restores jr from path in place of gi_jobrun_start: 1 restored, 0 no file,
 * -1 an error (GI_EINVAL for a checkpoint of another job or a damaged one). */
int gi_local_checkpoint_restore(gi_jobrun *jr, gi_job *job, const char *path, gi_error *err);

#endif
