/* gi_asset_cache: the worker's content-addressed disk cache. */
#include "gi_asset_cache.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_clock.h"
#include "gi_fs.h"
#include "gi_log.h"

#define LOCK_WAIT_S 3.0 /* for the directory's lock, held by another worker */

typedef struct cached_file {
    char path[4600];
    uint64_t size;
    double mtime;
} cached_file;

typedef struct file_list {
    cached_file *v;
    size_t n, cap;
} file_list;

static void list_one(void *ctx, const char *path, const char *name, const struct stat *st)
{
    file_list *out = ctx;
    if (gi_is_temp_name(name)) { /* a write cut short */
        unlink(path);
        return;
    }
    cached_file cf;
    snprintf(cf.path, sizeof cf.path, "%s", path);
    cf.size = (uint64_t)st->st_size;
    cf.mtime = (double)st->st_mtim.tv_sec + 1e-9 * (double)st->st_mtim.tv_nsec;
    if (out->n == out->cap) {
        out->cap = out->cap ? 2 * out->cap : 64;
        out->v = gi_xrealloc(out->v, out->cap * sizeof *out->v);
    }
    out->v[out->n++] = cf;
}

/* Lists the cache's files (for sizing and eviction). */
static void scan(const gi_asset_cache *c, file_list *out)
{
    gi_fs_walk_fanout(c->dir, list_one, out);
}

int gi_asset_cache_open(gi_asset_cache *c, const char *dir, uint64_t max_bytes, gi_error *err)
{
    memset(c, 0, sizeof *c);
    c->lock_fd = -1;
    if (gi_mkdirs(dir, err))
        return gi_error_prefix(err, "asset cache");
    char lock[4200];
    snprintf(lock, sizeof lock, "%s/.lock", dir);
    int fd = open(lock, O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (fd < 0)
        return gi_fail(err, GI_EIO, "asset cache: %s: %s", lock, strerror(errno));
    /* A POSIX record lock: held by this process, not by the pool children
     * it forks (a worker killed -9 frees it at once, even while they die),
     * and honoured over NFS. A file system without locks (ENOLCK) is let be. */
    struct flock fl = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
    /* A worker just killed may still be on its way out (kill returns before
     * the process is gone; a restart script goes on at once): wait for it. */
    int busy;
    double give_up = gi_now() + LOCK_WAIT_S;
    while ((busy = fcntl(fd, F_SETLK, &fl) != 0 && (errno == EACCES || errno == EAGAIN)) &&
           gi_now() < give_up)
        nanosleep(&(struct timespec){0, 50 * 1000 * 1000}, NULL);
    if (busy) {
        close(fd);
        return gi_fail(err, GI_EINVAL,
                       "asset cache %s is in use by another gi-worker (on this host, or on one "
                       "that shares the directory): give each gi-worker a --cache DIR of its "
                       "own, and a --name",
                       dir);
    }
    c->lock_fd = fd;
    c->dir = gi_xstrdup(dir);
    c->max_bytes = max_bytes;
    file_list l = {0};
    scan(c, &l);
    for (size_t i = 0; i < l.n; i++)
        c->bytes += l.v[i].size;
    free(l.v);
    return 0;
}

void gi_asset_cache_close(gi_asset_cache *c)
{
    free(c->dir);
    c->dir = NULL;
    if (c->lock_fd >= 0)
        close(c->lock_fd);
    c->lock_fd = -1;
}

static void path_of(const gi_asset_cache *c, const char *hash, char *out, size_t n)
{
    snprintf(out, n, "%s/%.2s/%s", c->dir, hash, hash);
}

int gi_asset_cache_get(gi_asset_cache *c, const char *hash, gi_buf *out, gi_error *err)
{
    char p[4400];
    path_of(c, hash, p, sizeof p);
    if (access(p, F_OK) != 0) {
        c->misses++;
        return 0;
    }
    if (gi_read_file(p, GI_ASSET_MAX_BYTES, out, err))
        return -1;
    char actual[GI_HASH_HEX];
    gi_hash_hex(out->data, out->len, actual);
    if (strcmp(actual, hash) != 0) {
        gi_warn("asset cache: %s is damaged (its bytes hash to %.12s); fetching it again", p,
                actual);
        c->bytes -= c->bytes >= out->len ? out->len : c->bytes;
        unlink(p);
        c->misses++;
        return 0;
    }
    utimensat(AT_FDCWD, p, NULL, 0); /* recently used */
    c->hits++;
    return 1;
}

static int by_mtime(const void *a, const void *b)
{
    double x = ((const cached_file *)a)->mtime, y = ((const cached_file *)b)->mtime;
    return x < y ? -1 : x > y;
}

static void evict(gi_asset_cache *c)
{
    file_list l = {0};
    scan(c, &l);
    qsort(l.v, l.n, sizeof *l.v, by_mtime);
    uint64_t total = 0;
    for (size_t i = 0; i < l.n; i++)
        total += l.v[i].size;
    uint64_t target = c->max_bytes / 10 * 9;
    for (size_t i = 0; i < l.n && total > target; i++) {
        if (unlink(l.v[i].path) == 0) {
            total -= l.v[i].size;
            c->evicted++;
        }
    }
    c->bytes = total;
    free(l.v);
}

int gi_asset_cache_put(gi_asset_cache *c, const char *hash, const void *data, size_t len,
                       gi_error *err)
{
    char d[4300], p[4400];
    snprintf(d, sizeof d, "%s/%.2s", c->dir, hash);
    if (mkdir(d, 0700) != 0 && errno != EEXIST)
        return gi_fail(err, GI_EIO, "asset cache: %s: %s", d, strerror(errno));
    path_of(c, hash, p, sizeof p);
    if (access(p, F_OK) == 0)
        return 0;
    if (gi_write_file_atomic(p, data, len, err))
        return gi_error_prefix(err, "asset cache");
    c->bytes += len;
    if (c->max_bytes && c->bytes > c->max_bytes)
        evict(c);
    return 0;
}
