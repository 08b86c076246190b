/* gi_batch_dir: per-job directories on a worker host for method caches
 * (e.g. the photon batch store of an animation job), docs/farm.md "Batch
 * directories".
 *
 * Every job a host runs gets <root>/<job id>-<16 hex digits of the hash of
 * the job's text>: the hash keeps a coordinator that reuses job ids (its
 * state was wiped) from meeting an older job's files. The pool children of
 * the host share it (same disk); the method creates it on first use
 * (gi_worker_batch_dir) and fills it; the host process (gi-worker's parent,
 * or gi render) removes it when the job ends, and sweeps directories left
 * idle for long (a coordinator that ended a job while the worker was away
 * never says so). */
#ifndef GI_BATCH_DIR_H
#define GI_BATCH_DIR_H

#include <stdint.h>

#include "gi_error.h"

/* Directories not modified for this long are swept (gi-worker). */
#define GI_BATCH_DIR_MAX_AGE_S (3.0 * 86400.0)

/* <root>/<job_id>-<hash16 of job_text> (malloc'ed). */
char *gi_batch_dir_path(const char *root, uint64_t job_id, const char *job_text);
/* Removes dir and everything below it (symbolic links are removed, not
 * followed). A missing dir is not an error. */
int gi_batch_dir_remove(const char *dir, gi_error *err);
/* Marks dir as in use (its mtime becomes now), if it exists. */
void gi_batch_dir_touch(const char *dir);
/* Removes the job directories under root not modified for max_age_s
 * seconds, except `keep` (NULL-terminated list of paths, may be NULL).
 * Returns how many were removed. */
int gi_batch_dir_sweep(const char *root, double max_age_s, const char *const *keep);
/* The same for the directories under root whose path accept() takes (gi
 * render's batch roots in $TMPDIR). */
int gi_batch_dir_sweep_where(const char *root, double max_age_s, int (*accept)(const char *path));
/* Removes every directory of job job_id under root, whatever its job text
 * (for a job that is over, which this process never loaded: a worker that
 * restarted since it wrote them). Returns how many were removed. */
int gi_batch_dir_remove_job(const char *root, uint64_t job_id);

#endif
