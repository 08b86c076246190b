/* gi_fs: whole-file reads and atomic writes. */
#include "gi_fs.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_log.h"

int gi_open_regular(const char *path, int flags, struct stat *st, gi_error *err)
{
    /* O_NONBLOCK: opening a FIFO to read waits for a writer, forever. */
    int fd = open(path, flags | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        gi_fail(err, e == ENOENT ? GI_EINVAL : GI_EIO, "%s: %s", path, strerror(e));
        errno = e;
        return -1;
    }
    struct stat own;
    if (!st)
        st = &own;
    if (fstat(fd, st) != 0) {
        int e = errno;
        close(fd);
        gi_fail(err, GI_EIO, "%s: %s", path, strerror(e));
        errno = e;
        return -1;
    }
    if (!S_ISREG(st->st_mode)) {
        close(fd);
        gi_fail(err, GI_EINVAL, "%s: not a regular file", path);
        errno = EINVAL;
        return -1;
    }
    /* Reads of a regular file never block; the flag only matters to
     * writers (and to whatever the caller hands the descriptor to). */
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0) {
        int e = errno;
        close(fd);
        gi_fail(err, GI_EIO, "%s: %s", path, strerror(e));
        errno = e;
        return -1;
    }
    return fd;
}

int gi_read_file(const char *path, size_t max_bytes, gi_buf *out, gi_error *err)
{
    struct stat st;
    int fd = gi_open_regular(path, O_RDONLY, &st, err);
    if (fd < 0)
        return -1;
    if ((unsigned long long)st.st_size > max_bytes) {
        close(fd);
        return gi_fail(err, GI_EINVAL, "%s: file is %lld bytes, over the limit of %zu",
                       path, (long long)st.st_size, max_bytes);
    }
    gi_buf_reset(out);
    gi_buf_reserve(out, (size_t)st.st_size + 1);
    for (;;) {
        gi_buf_reserve(out, 65536);
        ssize_t n = read(fd, out->data + out->len, out->cap - out->len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            int e = errno;
            close(fd);
            return gi_fail(err, GI_EIO, "%s: read: %s", path, strerror(e));
        }
        if (n == 0)
            break;
        out->len += (size_t)n;
        if (out->len > max_bytes) {
            close(fd);
            return gi_fail(err, GI_EINVAL, "%s: file is over the limit of %zu bytes",
                           path, max_bytes);
        }
    }
    close(fd);
    return 0;
}

char *gi_temp_path(const char *path)
{
    static atomic_uint counter;
    unsigned n = atomic_fetch_add(&counter, 1);
    size_t len = strlen(path) + 64;
    char *tmp = gi_xmalloc(len);
    snprintf(tmp, len, "%s.tmp-%ld-%u", path, (long)getpid(), n);
    return tmp;
}

/* Digits just before `end` in s: 1 if one or more (*start: the first). */
static int digits_before(const char *s, const char *end, const char **start)
{
    const char *p = end;
    while (p > s && p[-1] >= '0' && p[-1] <= '9')
        p--;
    *start = p;
    return p < end;
}

/* The writer's pid of a gi_temp_path name, or -1 if name is not one. */
static long temp_name_pid(const char *name)
{
    const char *end = name + strlen(name), *p;
    if (!digits_before(name, end, &p) || p == name || p[-1] != '-')
        return -1;
    const char *pid_end = p - 1;
    if (!digits_before(name, pid_end, &p))
        return -1;
    if ((size_t)(p - name) < 5 || memcmp(p - 5, ".tmp-", 5) != 0 || pid_end - p > 9)
        return -1;
    return strtol(p, NULL, 10);
}

int gi_is_temp_name(const char *name) { return temp_name_pid(name) >= 0; }

int gi_is_stale_temp_name(const char *name)
{
    long pid = temp_name_pid(name);
    return pid > 0 && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
}

int gi_remove_stale_temps(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (!gi_is_stale_temp_name(e->d_name))
            continue; /* not a temporary file, or its writer may be alive */
        char *path = gi_path_join(dir, e->d_name);
        n += unlink(path) == 0;
        free(path);
    }
    closedir(d);
    return n;
}

int gi_commit_file(const char *tmp, const char *path, gi_error *err)
{
    int fd = open(tmp, O_RDONLY | O_CLOEXEC);
    if (fd < 0 || fsync(fd) != 0) {
        int e = errno;
        if (fd >= 0)
            close(fd);
        unlink(tmp);
        return gi_fail(err, GI_EIO, "%s: %s", tmp, strerror(e));
    }
    close(fd);
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return gi_fail(err, GI_EIO, "%s: rename: %s", path, strerror(e));
    }
    /* The rename itself is durable only once the directory is synced. */
    char *dir = gi_dirname(path);
    int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    int rc = 0;
    if (dfd < 0 || fsync(dfd) != 0)
        rc = gi_fail(err, GI_EIO, "%s: syncing the directory: %s", dir, strerror(errno));
    if (dfd >= 0)
        close(dfd);
    free(dir);
    return rc;
}

int gi_temp_finish(const char *tmp, const char *path, int rc, gi_error *err)
{
    if (rc == 0)
        return gi_commit_file(tmp, path, err); /* removes tmp on failure */
    unlink(tmp);
    return rc;
}

int gi_write_file_atomic(const char *path, const void *data, size_t len, gi_error *err)
{
    char *tmp = gi_temp_path(path);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        gi_fail(err, GI_EIO, "%s: %s", path, strerror(errno));
        free(tmp);
        return -1;
    }
    const unsigned char *p = data;
    while (len) {
        ssize_t n = write(fd, p, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            gi_fail(err, GI_EIO, "%s: write: %s", path, strerror(errno));
            close(fd);
            unlink(tmp);
            free(tmp);
            return -1;
        }
        p += n;
        len -= (size_t)n;
    }
    if (close(fd) != 0) {
        gi_fail(err, GI_EIO, "%s: close: %s", path, strerror(errno));
        unlink(tmp);
        free(tmp);
        return -1;
    }
    int rc = gi_commit_file(tmp, path, err);
    free(tmp);
    return rc;
}

int gi_append_whole(const char *path, const void *data, size_t len, gi_error *err)
{
    int fd = open(path, O_WRONLY | O_APPEND | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) {
        int e = errno;
        if (fd >= 0)
            close(fd);
        return gi_fail(err, gi_disk_errcode(e), "%s: %s", path, strerror(e));
    }
    const unsigned char *p = data;
    size_t left = len;
    while (left) {
        ssize_t n = write(fd, p, left);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            int e = n < 0 ? errno : ENOSPC;
            if (ftruncate(fd, st.st_size) != 0)
                gi_warn("%s: cannot cut off a short write: %s", path, strerror(errno));
            close(fd);
            return gi_fail(err, gi_disk_errcode(e), "%s: write: %s", path, strerror(e));
        }
        p += n;
        left -= (size_t)n;
    }
    if (close(fd) != 0)
        return gi_fail(err, gi_disk_errcode(errno), "%s: close: %s", path, strerror(errno));
    return 0;
}

void gi_fs_walk_fanout(const char *dir,
                       void (*fn)(void *ctx, const char *path, const char *name,
                                  const struct stat *st),
                       void *ctx)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (strlen(e->d_name) != 2 || e->d_name[0] == '.')
            continue;
        char *sub = gi_path_join(dir, e->d_name);
        DIR *s = opendir(sub);
        struct dirent *a;
        while (s && (a = readdir(s))) {
            if (a->d_name[0] == '.')
                continue;
            char *p = gi_path_join(sub, a->d_name);
            struct stat st;
            if (stat(p, &st) == 0 && S_ISREG(st.st_mode))
                fn(ctx, p, a->d_name, &st);
            free(p);
        }
        if (s)
            closedir(s);
        free(sub);
    }
    closedir(d);
}

int gi_mkdirs(const char *dir, gi_error *err)
{
    char *p = gi_xstrdup(dir);
    for (char *s = p + 1; *s; s++) {
        if (*s != '/')
            continue;
        *s = '\0';
        if (mkdir(p, 0755) != 0 && errno != EEXIST) {
            gi_fail(err, gi_disk_errcode(errno), "%s: mkdir: %s", p, strerror(errno));
            free(p);
            return -1;
        }
        *s = '/';
    }
    int rc = 0;
    if (*p && mkdir(p, 0755) != 0 && errno != EEXIST)
        rc = gi_fail(err, gi_disk_errcode(errno), "%s: mkdir: %s", p, strerror(errno));
    free(p);
    return rc;
}

int gi_output_dir_ready(const char *dir, gi_error *err)
{
    if (!*dir)
        return gi_fail(err, GI_EINVAL, "an empty directory name (use . for this one)");
    if (gi_mkdirs(dir, err))
        return -1;
    struct stat st;
    if (stat(dir, &st) != 0)
        return gi_fail(err, GI_EIO, "%s: %s", dir, strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return gi_fail(err, GI_EINVAL, "%s: not a directory", dir);
    char *probe = gi_path_join(dir, ".gi-write-test.XXXXXX");
    int fd = mkstemp(probe);
    int rc = 0;
    if (fd < 0) {
        rc = gi_fail(err, GI_EIO, "%s: cannot write there: %s", dir, strerror(errno));
    } else {
        close(fd);
        unlink(probe);
    }
    free(probe);
    return rc;
}

char *gi_dirname(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return gi_xstrdup(".");
    if (slash == path)
        return gi_xstrdup("/");
    size_t n = (size_t)(slash - path);
    char *d = gi_xmalloc(n + 1);
    memcpy(d, path, n);
    d[n] = '\0';
    return d;
}

char *gi_path_join(const char *dir, const char *name)
{
    if (name[0] == '/' || !dir[0] || strcmp(dir, ".") == 0)
        return gi_xstrdup(name);
    size_t n = strlen(dir) + strlen(name) + 2;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/%s", dir, name);
    return p;
}

char *gi_path_normalize(const char *path)
{
    size_t n = strlen(path);
    char *out = gi_xmalloc(n + 2);
    int absolute = path[0] == '/';
    /* Stack of component start offsets in `out`. */
    size_t *starts = gi_xmalloc((n / 2 + 2) * sizeof *starts);
    size_t depth = 0, len = 0, ups = 0;
    if (absolute)
        out[len++] = '/';
    const char *s = path;
    while (*s) {
        while (*s == '/')
            s++;
        const char *e = s;
        while (*e && *e != '/')
            e++;
        size_t cl = (size_t)(e - s);
        if (cl == 0)
            break;
        if (cl == 1 && s[0] == '.') {
            /* skip */
        } else if (cl == 2 && s[0] == '.' && s[1] == '.' && depth > ups) {
            len = starts[--depth];
            if (len > (size_t)absolute)
                len--; /* drop the separator before the component */
        } else if (cl == 2 && s[0] == '.' && s[1] == '.' && absolute) {
            /* "/.." is "/" */
        } else {
            if (len > (size_t)absolute)
                out[len++] = '/';
            starts[depth++] = len;
            if (cl == 2 && s[0] == '.' && s[1] == '.')
                ups++;
            memcpy(out + len, s, cl);
            len += cl;
        }
        s = e;
    }
    if (len == 0)
        out[len++] = '.';
    out[len] = '\0';
    free(starts);
    return out;
}
