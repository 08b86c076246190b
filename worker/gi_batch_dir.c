/* gi_batch_dir: naming, removing and sweeping per-job batch directories. */
#include "gi_batch_dir.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_assets.h"
#include "gi_log.h"

char *gi_batch_dir_path(const char *root, uint64_t job_id, const char *job_text)
{
    char hash[GI_HASH_HEX];
    gi_hash_hex(job_text, strlen(job_text), hash);
    size_t n = strlen(root) + 48;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/%llu-%.16s", root, (unsigned long long)job_id, hash);
    return p;
}

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)ftw;
    int rc = flag == FTW_DP ? rmdir(path) : unlink(path);
    if (rc != 0 && errno != ENOENT)
        gi_debug("%s: %s", path, strerror(errno));
    return 0; /* go on: remove what can be removed */
}

int gi_batch_dir_remove(const char *dir, gi_error *err)
{
    struct stat st;
    if (lstat(dir, &st) != 0)
        return errno == ENOENT ? 0 : gi_fail(err, GI_EIO, "%s: %s", dir, strerror(errno));
    nftw(dir, remove_one, 16, FTW_DEPTH | FTW_PHYS);
    if (lstat(dir, &st) == 0)
        return gi_fail(err, GI_EIO, "%s: could not remove everything below it", dir);
    return 0;
}

void gi_batch_dir_touch(const char *dir)
{
    utimensat(AT_FDCWD, dir, NULL, 0); /* missing: nothing to keep */
}

/* A name gi_batch_dir_path makes: digits, '-', 16 hex digits. */
static int is_job_dir_name(const char *name)
{
    const char *p = name;
    while (*p >= '0' && *p <= '9')
        p++;
    if (p == name || *p++ != '-' || strlen(p) != 16)
        return 0;
    return strspn(p, "0123456789abcdef") == 16;
}

/* Removes the directories under root that accept(name, path, ctx) takes,
 * not modified for max_age_s seconds and not in keep. */
static int sweep(const char *root, double max_age_s, const char *const *keep,
                 int (*accept)(const char *name, const char *path, void *ctx), void *ctx)
{
    DIR *d = opendir(root);
    if (!d)
        return 0;
    time_t now = time(NULL);
    int removed = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        char p[4400];
        snprintf(p, sizeof p, "%s/%s", root, e->d_name);
        if (!accept(e->d_name, p, ctx))
            continue; /* not ours: never removed */
        struct stat st;
        if (lstat(p, &st) != 0 || !S_ISDIR(st.st_mode))
            continue;
        if ((double)(now - st.st_mtime) < max_age_s)
            continue;
        int kept = 0;
        for (const char *const *k = keep; k && *k && !kept; k++)
            kept = strcmp(*k, p) == 0;
        if (kept)
            continue;
        gi_error err;
        if (gi_batch_dir_remove(p, &err))
            gi_warn("batch directory sweep: %s", err.msg);
        else
            removed++;
    }
    closedir(d);
    return removed;
}

static int job_dir(const char *name, const char *path, void *ctx)
{
    (void)path;
    (void)ctx;
    return is_job_dir_name(name);
}

int gi_batch_dir_sweep(const char *root, double max_age_s, const char *const *keep)
{
    return sweep(root, max_age_s, keep, job_dir, NULL);
}

typedef struct path_test {
    int (*accept)(const char *path);
} path_test;

static int accepted_path(const char *name, const char *path, void *ctx)
{
    (void)name;
    return ((const path_test *)ctx)->accept(path);
}

int gi_batch_dir_sweep_where(const char *root, double max_age_s, int (*accept)(const char *path))
{
    path_test t = {accept};
    return sweep(root, max_age_s, NULL, accepted_path, &t);
}

static int of_job(const char *name, const char *path, void *ctx)
{
    (void)path;
    char prefix[32];
    int n = snprintf(prefix, sizeof prefix, "%llu-", (unsigned long long)*(const uint64_t *)ctx);
    return is_job_dir_name(name) && strncmp(name, prefix, (size_t)n) == 0;
}

int gi_batch_dir_remove_job(const char *root, uint64_t job_id)
{
    return sweep(root, -1e300, NULL, of_job, &job_id);
}
