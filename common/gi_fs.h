/* gi_fs: whole-file reads and atomic writes.
 *
 * Outputs are never half-written: writers produce `<path>.tmp-<pid>-<n>` in
 * the same directory, fsync it, and rename it over the final name. */
#ifndef GI_FS_H
#define GI_FS_H

#include <stddef.h>

#include "gi_buf.h"
#include "gi_error.h"

struct stat;
/* Opens path (flags | O_CLOEXEC) if it is a regular file, filling *st (if
 * not NULL). A FIFO, device or directory is refused without blocking. On
 * failure returns -1, err says why naming path (GI_EINVAL: missing or not a
 * regular file) and errno is open's (ENOENT: missing) or EINVAL. */
int gi_open_regular(const char *path, int flags, struct stat *st, gi_error *err);

/* Reads a whole file; refuses files larger than max_bytes or not regular. */
int gi_read_file(const char *path, size_t max_bytes, gi_buf *out, gi_error *err);

/* A fresh temporary name next to `path` (malloc'ed). */
char *gi_temp_path(const char *path);
/* `name` is one gi_temp_path made: it ends in .tmp-<pid>-<n> (a write cut
 * short, never an output, whatever else the name holds). */
int gi_is_temp_name(const char *name);
/* `name` is a temporary file's whose writer is gone (a render or
 * coordinator killed while writing). */
int gi_is_stale_temp_name(const char *name);
/* Removes such files from dir; returns how many. */
int gi_remove_stale_temps(const char *dir);
/* fsyncs `tmp` and renames it to `path`; removes tmp on failure. */
int gi_commit_file(const char *tmp, const char *path, gi_error *err);
/* Ends a write to a temporary file: commits it to path if rc == 0, else
 * removes it. Returns rc, or -1 if the commit failed. */
int gi_temp_finish(const char *tmp, const char *path, int rc, gi_error *err);
/* Writes bytes to path atomically (temp + fsync + rename). */
int gi_write_file_atomic(const char *path, const void *data, size_t len, gi_error *err);

/* Appends bytes to path (created if missing) whole or not at all: a write
 * cut short (a full disk) is cut back off, so the file never ends in half
 * a record. A full or read-only disk is GI_EHOST (gi_disk_errcode). */
int gi_append_whole(const char *path, const void *data, size_t len, gi_error *err);

/* Calls fn for every regular file one level below dir's two-character
 * subdirectories (content-addressed stores: dir/ab/abcd...). Names starting
 * with '.' are skipped. */
void gi_fs_walk_fanout(const char *dir,
                       void (*fn)(void *ctx, const char *path, const char *name,
                                  const struct stat *st),
                       void *ctx);

/* mkdir -p; a full or read-only disk is GI_EHOST (gi_disk_errcode). */
int gi_mkdirs(const char *dir, gi_error *err);
/* An output directory made (mkdir -p) and proved writable by creating and
 * removing a file in it, so that a render finds out before it runs, not
 * after: an empty name, a file in the way or no permission fail. */
int gi_output_dir_ready(const char *dir, gi_error *err);
/* Directory part of a path ("." if none), malloc'ed. */
char *gi_dirname(const char *path);
/* dir + "/" + name, unless name is absolute or dir is "" or "."; malloc'ed. */
char *gi_path_join(const char *dir, const char *name);
/* Lexical normalization: removes "." and "x/.." pairs, repeated slashes. */
char *gi_path_normalize(const char *path);

#endif
