/* gi_local_checkpoint: the checkpoint file of `gi render` (see the header). */
#include "gi_local_checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_fs.h"

#define LOCAL_CHECKPOINT_MAGIC 0x434C4947u /* "GILC" */
#define LOCAL_CHECKPOINT_VERSION 2u /* 1: no batch root */
#define LOCAL_BATCH_ROOT_MAX 4096

char *gi_local_checkpoint_path(const gi_job *job)
{
    size_t n = strlen(job->name) + 16;
    char *file = gi_xmalloc(n);
    snprintf(file, n, ".%s.checkpoint", job->name);
    char *path = gi_path_join(job->out_dir ? job->out_dir : ".", file);
    free(file);
    return path;
}

int gi_local_checkpoint_encode(const gi_jobrun *jr, const char *batch_root, gi_buf *out,
                               gi_error *err)
{
    char id[GI_HASH_HEX];
    gi_jobrun_identity(jr->job, id);
    gi_buf_put_u32(out, LOCAL_CHECKPOINT_MAGIC);
    gi_buf_put_u32(out, LOCAL_CHECKPOINT_VERSION);
    gi_buf_put_str(out, id);
    gi_buf_put_str(out, batch_root ? batch_root : "");
    return gi_jobrun_checkpoint(jr, out, err);
}

int gi_local_checkpoint_write(const gi_jobrun *jr, const char *batch_root, const char *path,
                              gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    int rc = gi_local_checkpoint_encode(jr, batch_root, &b, err);
    if (rc == 0)
        rc = gi_write_file_atomic(path, b.data, b.len, err);
    gi_buf_free(&b);
    return rc ? gi_error_prefix(err, "checkpoint %s", path) : 0;
}

/* The header of the checkpoint in data: 0 and *id, *root (malloc'ed; *root
 * NULL if none), the reader left at gi_jobrun_checkpoint's bytes; -1 if it
 * is not a checkpoint. */
static int read_header(const void *data, size_t len, const char *path, gi_reader *r, char **id,
                       char **root)
{
    gi_reader_init(r, data, len, path);
    uint32_t magic = gi_get_u32(r), version = gi_get_u32(r);
    *id = gi_get_str(r, GI_HASH_HEX);
    *root = NULL;
    if (!r->failed && version >= 2)
        *root = gi_get_str(r, LOCAL_BATCH_ROOT_MAX);
    if (r->failed || magic != LOCAL_CHECKPOINT_MAGIC || version < 1 ||
        version > LOCAL_CHECKPOINT_VERSION || !*id || (version >= 2 && !*root)) {
        free(*id);
        free(*root);
        *id = *root = NULL;
        return -1;
    }
    if (*root && !(*root)[0]) {
        free(*root);
        *root = NULL;
    }
    return 0;
}

int gi_local_checkpoint_restore(gi_jobrun *jr, gi_job *job, const char *path, char **batch_root,
                                gi_error *err)
{
    *batch_root = NULL;
    if (access(path, F_OK) != 0) {
        if (errno == ENOENT)
            return 0;
        return gi_fail(err, GI_EIO, "checkpoint %s: %s", path, strerror(errno));
    }
    gi_buf b;
    gi_buf_init(&b);
    if (gi_read_file(path, (size_t)1 << 40, &b, err)) {
        gi_buf_free(&b);
        return -1;
    }
    gi_reader r;
    char *id, *root;
    char want[GI_HASH_HEX];
    gi_jobrun_identity(job, want);
    int rc = 0;
    if (read_header(b.data, b.len, path, &r, &id, &root))
        rc = gi_fail(err, GI_EINVAL,
                     "%s: not a gi render checkpoint (run without --resume to start over)", path);
    else if (strcmp(id, want) != 0)
        rc = gi_fail(err, GI_EINVAL,
                     "%s: a checkpoint of another run (%s or its scene's files changed since); "
                     "run without --resume to start over",
                     path, job->file);
    free(id);
    if (rc == 0) {
        /* The run's bytes, read in place (a view of b's tail: not freed), not
         * copied: a big image's checkpoint is hundreds of MB. */
        const gi_buf rest = {b.data + (b.len - r.left), r.left, 0};
        gi_error e;
        if (gi_jobrun_restore(jr, job, &rest, &e) != 0) {
            if (gi_jobrun_finish_retryable(jr) && job->in_frame) /* an animation */
                rc = gi_fail(err, e.code, "%s; the frames rendered so far stay in %s: once "
                             "that is fixed, --resume writes their outputs and goes on", e.msg,
                             path);
            else if (gi_jobrun_finish_retryable(jr)) /* not "start over": that would lose it */
                rc = gi_fail(err, e.code, "%s; the whole result stays in %s: once that is "
                             "fixed, --resume writes the outputs", e.msg, path);
            else
                rc = gi_fail(err, e.code == GI_EPROTO ? GI_EINVAL : e.code,
                             "%s: %s; run without --resume to start over", path, e.msg);
        }
    }
    gi_buf_free(&b);
    if (rc) {
        free(root);
        return -1;
    }
    *batch_root = root;
    return 1;
}

char *gi_local_checkpoint_batch_root(const char *path)
{
    /* The header alone: a checkpoint can be hundreds of MB of sums. */
    int fd = gi_open_regular(path, O_RDONLY, NULL, NULL);
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (!f) {
        if (fd >= 0)
            close(fd);
        return NULL;
    }
    char head[16 + GI_HASH_HEX + LOCAL_BATCH_ROOT_MAX];
    size_t n = fread(head, 1, sizeof head, f);
    fclose(f);
    gi_reader r;
    char *id, *root;
    if (read_header(head, n, path, &r, &id, &root) == 0)
        free(id);
    return root;
}

int gi_local_batch_root_ours(const char *dir)
{
    if (!dir || dir[0] != '/')
        return 0;
    const char *base = strrchr(dir, '/') + 1;
    if (strncmp(base, "gi-render-", 10) != 0 || strstr(dir, "/../") || strstr(dir, "/./"))
        return 0;
    struct stat sb;
    return lstat(dir, &sb) == 0 && S_ISDIR(sb.st_mode) && sb.st_uid == geteuid() &&
           (sb.st_mode & 077) == 0;
}
