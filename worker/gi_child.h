/* gi_child: the task loop of a pool child process.
 *
 * A child talks to its parent over one socket with protocol frames: it
 * receives JOB and TASK, asks for the bytes of assets it lacks (ASSET_NEED,
 * answered by ASSET_PUT), and answers each task with RESULT or FAIL. It
 * creates its own Embree device after the fork, and uses nothing it
 * inherited, so a remote worker's children and gi render's children run the
 * same code. */
#ifndef GI_CHILD_H
#define GI_CHILD_H

#include "gi_child_faults.h"

/* Frames between a parent and its children, both ways, are not compressed:
 * they share a host, where copying is cheaper than zstd (a farm worker
 * compresses once, for the network). */
#define GI_CHILD_LINK_COMPRESS 0

/* Runs until BYE or the parent goes away; returns the exit status.
 * batch_root (NULL: none): where the host keeps per-job batch directories
 * (gi_batch_dir.h); each loaded job's ctx.batch_dir lies below it. */
int gi_child_main(int fd, const char *batch_root);

/* Its test hooks (GI_FAULT_CRASH_TASK ...) are in gi_child_faults.h. */

#endif
