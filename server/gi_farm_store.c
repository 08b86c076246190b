/* gi_farm_store: the coordinator's content-addressed asset store.
 *
 * <state>/assets/<first two hex digits>/<BLAKE2b-256 hex>: the bytes of
 * every uploaded file and of every blob a job published (so published data
 * survives a restart with the checkpoint that refers to it). Uploads stream
 * into <state>/assets/tmp/ while being hashed and are renamed into place
 * only if the bytes match the name; a file in the store is never rewritten.
 * Names are hashes, so no request can name a path. A file goes when no job
 * names it any more: a purged job's uploads (unless another job uses the
 * same bytes), published data its newer checkpoint no longer needs. A file
 * found damaged when read (its bytes no longer hash to its name) is moved to
 * <state>/assets/damaged/. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_farm_impl.h"
#include "gi_fs.h"
#include "gi_log.h"

char *gi_farm_store_path(const gi_farm *f, const char *hash)
{
    size_t n = strlen(f->assets_dir) + 80;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/%.2s/%s", f->assets_dir, hash, hash);
    return p;
}

int gi_farm_store_has(const gi_farm *f, const char *hash, uint64_t *size)
{
    if (!gi_hash_is_valid(hash))
        return 0;
    char *p = gi_farm_store_path(f, hash);
    struct stat st;
    int ok = stat(p, &st) == 0 && S_ISREG(st.st_mode);
    free(p);
    if (ok && size)
        *size = (uint64_t)st.st_size;
    return ok;
}

/* A damaged file goes to <assets>/damaged/ (kept for the operator to look
 * at, outside the fan-out the store is read from), so that submitting the
 * job again finds the hash missing and uploads the bytes anew. Returns the
 * new path, or NULL if it could not be moved. Its bytes still count against
 * --max-store-bytes until gi-farmd restarts: they are still on the disk. */
static char *move_aside(const gi_farm *f, const char *hash, const char *path)
{
    size_t n = strlen(f->assets_dir) + 100;
    char *dir = gi_xmalloc(n), *to = gi_xmalloc(n);
    snprintf(dir, n, "%s/damaged", f->assets_dir);
    snprintf(to, n, "%s/%s", dir, hash);
    int ok = (mkdir(dir, 0700) == 0 || errno == EEXIST) && rename(path, to) == 0;
    if (ok)
        gi_warn("asset store: %s is damaged: moved to %s", hash, to);
    free(dir);
    if (!ok)
        free(to);
    return ok ? to : NULL;
}

int gi_farm_store_read(const gi_farm *f, const char *hash, gi_buf *out, gi_error *err)
{
    if (!gi_hash_is_valid(hash))
        return gi_fail(err, GI_EINVAL, "malformed asset hash");
    char *p = gi_farm_store_path(f, hash);
    int rc = gi_read_file(p, GI_ASSET_MAX_BYTES, out, err);
    if (rc == 0) {
        /* The name is the hash: a file damaged on disk (a bad sector, an
         * operator's edit) is caught here, naming it, rather than by every
         * worker it is sent to. GI_EINVAL: the job fails at once, and no
         * worker is blamed (blocklisted) for the coordinator's disk. */
        char hex[GI_HASH_HEX];
        size_t n = out->len;
        gi_hash_hex(out->data, n, hex);
        if (strcmp(hex, hash) != 0) {
            gi_buf_reset(out);
            char *aside = move_aside(f, hash, p);
            if (aside)
                rc = gi_fail(err, GI_EINVAL,
                             "asset store: %s is damaged (%s: its %zu bytes hash to %.16s...); "
                             "it was moved to %s: submit the job again to upload it anew",
                             hash, p, n, hex, aside);
            else
                rc = gi_fail(err, GI_EINVAL,
                             "asset store: %s is damaged (%s: its %zu bytes hash to %.16s...); "
                             "remove the file and submit the job again to upload it anew",
                             hash, p, n, hex);
            free(aside);
        }
    }
    free(p);
    return rc;
}

static int ensure_fanout(const gi_farm *f, const char *hash, gi_error *err)
{
    char d[4200];
    snprintf(d, sizeof d, "%s/%.2s", f->assets_dir, hash);
    if (mkdir(d, 0700) != 0 && errno != EEXIST)
        return gi_fail(err, GI_EIO, "%s: mkdir: %s", d, strerror(errno));
    return 0;
}

int gi_farm_store_put(gi_farm *f, const char *hash, const void *data, size_t len, gi_error *err)
{
    if (gi_farm_store_has(f, hash, NULL))
        return 0;
    if (ensure_fanout(f, hash, err))
        return -1;
    char *p = gi_farm_store_path(f, hash);
    int rc = gi_write_file_atomic(p, data, len, err);
    free(p);
    if (rc == 0)
        f->store_bytes += len;
    return rc;
}

int gi_farm_store_room(const gi_farm *f, uint64_t more, gi_error *err)
{
    uint64_t used = f->store_bytes + f->upload_bytes;
    if (used + more <= f->cfg.max_store_bytes)
        return 0;
    return gi_fail(err, GI_ENOMEM,
                   "the asset store is full (%llu bytes, %llu of them uploads under way; limit "
                   "%llu): `gi purge` ended jobs to free their files",
                   (unsigned long long)used, (unsigned long long)f->upload_bytes,
                   (unsigned long long)f->cfg.max_store_bytes);
}

struct gi_farm_upload {
    gi_farm *f;
    char hash[GI_HASH_HEX];
    char *tmp;
    int fd;
    uint64_t bytes;
    crypto_generichash_state st;
};

gi_farm_upload *gi_farm_upload_begin(gi_farm *f, const char *hash, gi_error *err)
{
    if (!gi_hash_is_valid(hash)) {
        gi_fail(err, GI_EINVAL, "asset name must be 64 lower-case hex digits (BLAKE2b-256)");
        return NULL;
    }
    static unsigned counter;
    size_t n = strlen(f->assets_dir) + 64;
    gi_farm_upload *u = gi_xcalloc(1, sizeof *u);
    u->f = f;
    memcpy(u->hash, hash, GI_HASH_HEX);
    u->tmp = gi_xmalloc(n);
    snprintf(u->tmp, n, "%s/tmp/upload-%ld-%u", f->assets_dir, (long)getpid(), counter++);
    u->fd = open(u->tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (u->fd < 0) {
        gi_fail(err, GI_EIO, "%s: %s", u->tmp, strerror(errno));
        free(u->tmp);
        free(u);
        return NULL;
    }
    crypto_generichash_init(&u->st, NULL, 0, 32);
    return u;
}

int gi_farm_upload_write(gi_farm_upload *u, const void *data, size_t len, gi_error *err)
{
    /* Counted as they arrive: uploads at once, or sent chunked, would
     * otherwise fill the disk past the limit before the first finished. */
    if (gi_farm_store_room(u->f, len, err))
        return -1;
    crypto_generichash_update(&u->st, data, len);
    const uint8_t *p = data;
    while (len) {
        ssize_t w = write(u->fd, p, len);
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0)
            return gi_fail(err, GI_EIO, "%s: write: %s", u->tmp, strerror(errno));
        p += w;
        len -= (size_t)w;
        u->bytes += (uint64_t)w;
        u->f->upload_bytes += (uint64_t)w;
    }
    return 0;
}

void gi_farm_upload_abort(gi_farm_upload *u)
{
    if (!u)
        return;
    u->f->upload_bytes -= u->bytes;
    u->bytes = 0;
    if (u->fd >= 0)
        close(u->fd);
    unlink(u->tmp);
    free(u->tmp);
    free(u);
}

int gi_farm_upload_finish(gi_farm *f, gi_farm_upload *u, gi_error *err)
{
    /* From here on its bytes are in the store, or gone. */
    uint64_t bytes = u->bytes;
    f->upload_bytes -= bytes;
    u->bytes = 0;
    uint8_t h[32];
    crypto_generichash_final(&u->st, h, sizeof h);
    char hex[GI_HASH_HEX];
    sodium_bin2hex(hex, sizeof hex, h, sizeof h);
    int rc = 0;
    if (strcmp(hex, u->hash) != 0) {
        rc = gi_fail(err, GI_EINVAL, "the %llu bytes uploaded hash to %.16s..., not %.16s...",
                     (unsigned long long)bytes, hex, u->hash);
    } else if (close(u->fd) != 0) {
        u->fd = -1;
        rc = gi_fail(err, GI_EIO, "%s: close: %s", u->tmp, strerror(errno));
    } else {
        u->fd = -1;
        uint64_t have;
        if (gi_farm_store_has(f, u->hash, &have)) {
            unlink(u->tmp); /* uploaded twice: the first copy stays */
        } else if (ensure_fanout(f, u->hash, err) == 0) {
            char *p = gi_farm_store_path(f, u->hash);
            rc = gi_commit_file(u->tmp, p, err);
            free(p);
            if (rc == 0) {
                f->store_bytes += bytes;
                f->m.assets_uploaded++;
                f->m.asset_bytes_uploaded += bytes;
            }
        } else {
            rc = -1;
        }
    }
    if (rc)
        gi_farm_upload_abort(u);
    else {
        free(u->tmp);
        free(u);
    }
    return rc;
}

static void count_bytes(void *ctx, const char *path, const char *name, const struct stat *st)
{
    *(uint64_t *)ctx += (uint64_t)st->st_size;
}

int gi_farm_store_scan(gi_farm *f, gi_error *err)
{
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s/tmp", f->assets_dir);
    if (gi_mkdirs(tmp, err))
        return -1;
    /* Uploads cut short by a crash: nothing refers to them. */
    DIR *d = opendir(tmp);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)))
            if (e->d_name[0] != '.') {
                char p[4500];
                snprintf(p, sizeof p, "%s/%s", tmp, e->d_name);
                unlink(p);
            }
        closedir(d);
    }
    f->store_bytes = 0;
    gi_fs_walk_fanout(f->assets_dir, count_bytes, &f->store_bytes);
    return 0;
}

void gi_farm_store_touch(const gi_farm *f, const char *hash)
{
    if (!gi_hash_is_valid(hash))
        return;
    char *p = gi_farm_store_path(f, hash);
    utimensat(AT_FDCWD, p, NULL, 0);
    free(p);
}

/* Some job of the farm names hash. */
static int named(const gi_farm *f, const char *hash)
{
    for (size_t i = 0; i < f->job_count; i++)
        if (gi_manifest_has_hash(&f->jobs[i]->manifest, hash) ||
            gi_manifest_has_hash(&f->jobs[i]->published, hash))
            return 1;
    return 0;
}

uint64_t gi_farm_store_release(gi_farm *f, const gi_manifest *m, int uploaded)
{
    uint64_t freed = 0;
    double now = gi_farm_wallnow();
    for (size_t i = 0; i < m->count; i++) {
        const char *hash = m->entries[i].hash;
        if (!gi_hash_is_valid(hash) || named(f, hash))
            continue;
        char *p = gi_farm_store_path(f, hash);
        struct stat st;
        if (stat(p, &st) == 0 && S_ISREG(st.st_mode) &&
            (!uploaded || now - (double)st.st_mtime >= GI_FARM_STORE_GRACE_S) && unlink(p) == 0) {
            freed += (uint64_t)st.st_size;
            f->store_bytes -= (uint64_t)st.st_size < f->store_bytes ? (uint64_t)st.st_size
                                                                     : f->store_bytes;
        }
        free(p);
    }
    return freed;
}

int gi_farm_asset_bytes(gi_farm *f, const char *hash, gi_buf *out, gi_error *err)
{
    for (size_t i = 0; i < f->job_count; i++) {
        gi_farm_job *j = f->jobs[i];
        /* A finishing job's data is its finish thread's (it may publish):
         * what its checkpoints need is in the store, and no task of it
         * runs any more. */
        if (!j->loaded || gi_jobrun_finishing(&j->jr) || !j->job.assets)
            continue;
        const gi_buf *b = gi_asset_store_get(j->job.assets, hash);
        if (b) {
            gi_buf_reset(out);
            gi_buf_put(out, b->data, b->len);
            return 0;
        }
    }
    if (!gi_farm_store_has(f, hash, NULL))
        return gi_fail(err, GI_EINVAL, "asset %.12s is unknown to the coordinator", hash);
    return gi_farm_store_read(f, hash, out, err);
}
