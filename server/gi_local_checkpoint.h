/* gi_local_checkpoint: `gi render`'s checkpoint, so that an interrupted or
 * killed render resumes (`gi render JOB --resume`) instead of starting over.
 *
 * The file is OUT/.NAME.checkpoint (NAME: the job's name), written whole
 * under a temporary name and renamed: u32 magic "GILC", u32 version, the
 * job's identity (BLAKE2b-256, hex, of the job file's text and of the name
 * and hash of every file its scene read), the render's batch root (a
 * string, empty if none: version 2 on), then gi_jobrun_checkpoint's bytes.
 * A checkpoint of another job (edited, or its scene's files changed) is
 * refused rather than resumed.
 *
 * The batch root is where the pool children keep an animation's photon
 * batches (gi_local.c). A stopped render leaves it behind with its
 * checkpoint, so that the resumed one reads the batches instead of tracing
 * them again; since the path comes from a file, it is used (or removed)
 * only if gi_local_batch_root_ours says it is one of ours. */
#ifndef GI_LOCAL_CHECKPOINT_H
#define GI_LOCAL_CHECKPOINT_H

#include "gi_job.h"
#include "gi_jobrun.h"

/* OUT/.NAME.checkpoint (malloc'ed). */
char *gi_local_checkpoint_path(const gi_job *job);
/* The checkpoint's bytes, appended to out (batch_root may be NULL). */
int gi_local_checkpoint_encode(const gi_jobrun *jr, const char *batch_root, gi_buf *out,
                               gi_error *err);
/* Encodes and writes it to path, atomically. */
int gi_local_checkpoint_write(const gi_jobrun *jr, const char *batch_root, const char *path,
                              gi_error *err);
/* Restores jr from path in place of gi_jobrun_start: 1 restored, 0 no file,
 * -1 an error (GI_EINVAL for a checkpoint of another job or a damaged one).
 * *batch_root: the recorded batch root (malloc'ed) or NULL, when restored. */
int gi_local_checkpoint_restore(gi_jobrun *jr, gi_job *job, const char *path, char **batch_root,
                                gi_error *err);
/* The batch root recorded in the checkpoint at path, whatever its job
 * (malloc'ed), or NULL (none, no file, not a checkpoint). */
char *gi_local_checkpoint_batch_root(const char *path);
/* 1 if dir is a batch root this user's `gi render` made: an absolute path
 * whose last part starts "gi-render-", a directory (not a link) owned by
 * this user that no one else can enter. */
int gi_local_batch_root_ours(const char *dir);

#endif
