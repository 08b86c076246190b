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

/* Frames between a parent and its children, both ways, are not compressed:
 * they share a host, where copying is cheaper than zstd (a farm worker
 * compresses once, for the network). */
#define GI_CHILD_LINK_COMPRESS 0

/* Runs until BYE or the parent goes away; returns the exit status.
 * batch_root (NULL: none): where the host keeps per-job batch directories
 * (gi_batch_dir.h); each loaded job's ctx.batch_dir lies below it. */
int gi_child_main(int fd, const char *batch_root);

/* Fault injection for tests: GI_FAULT_CRASH_TASK="ID[:ATTEMPT][,ID[:ATTEMPT]...]"
 * makes a child kill itself with SIGKILL after computing task ID on that
 * attempt (default 0), before sending the result. */
#define GI_FAULT_CRASH_ENV "GI_FAULT_CRASH_TASK"
/* GI_FAULT_KILL_HOST_TASK, in the same form, makes the child that gets task
 * ID on that attempt kill its parent (the gi-worker, or `gi render`) with
 * SIGKILL, then itself, before running it: a task that takes its host down. */
#define GI_FAULT_KILL_HOST_ENV "GI_FAULT_KILL_HOST_TASK"
/* GI_FAULT_STOP_HOST_TASK, likewise, makes it SIGSTOP its parent, then run
 * the task: a host gone silent (its leases expire) until SIGCONT. */
#define GI_FAULT_STOP_HOST_ENV "GI_FAULT_STOP_HOST_TASK"
/* GI_FAULT_HANG_TASK, likewise, makes the child that gets task ID on that
 * attempt hang (sleep until killed) instead of running it: a task that
 * never ends, for task time limits (task_timeout). */
#define GI_FAULT_HANG_ENV "GI_FAULT_HANG_TASK"
/* GI_FAULT_SLOW_TASK, likewise, makes the child sleep GI_FAULT_SLOW_S
 * seconds (default 1) before running task ID on that attempt: a task that
 * takes long and ends, so that others wait queued behind it. */
#define GI_FAULT_SLOW_ENV "GI_FAULT_SLOW_TASK"
#define GI_FAULT_SLOW_S_ENV "GI_FAULT_SLOW_S"

#endif
