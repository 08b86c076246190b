/* gi_batch_root: gi render's private batch roots and their owner records. */
#include "gi_batch_root.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_batch_dir.h"
#include "gi_fs.h"
#include "gi_local_checkpoint.h"
#include "gi_log.h"

#define OWNER_MAGIC "gi-render-owner 1"

/* The start time of process pid (clock ticks after boot, /proc/PID/stat's
 * 22nd field), or 0 if there is no such process. */
static unsigned long long process_start(long pid)
{
    char path[64], text[1024];
    snprintf(path, sizeof path, "/proc/%ld/stat", pid);
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    /* After the command name, which may hold spaces and parentheses. */
    const char *p = strrchr(text, ')');
    if (!p)
        return 0;
    unsigned long long start = 0;
    for (int field = 2; *p && field < 22; p++)
        if (*p == ' ')
            field++;
    if (sscanf(p, "%llu", &start) != 1)
        return 0;
    return start;
}

/* ckpt as an absolute path (its directory resolved), malloc'ed; NULL if
 * its directory does not exist. */
static char *absolute_file(const char *ckpt)
{
    char *dir = gi_dirname(ckpt);
    char *abs_dir = realpath(dir, NULL);
    free(dir);
    if (!abs_dir)
        return NULL;
    const char *base = strrchr(ckpt, '/') ? strrchr(ckpt, '/') + 1 : ckpt;
    char *out = gi_path_join(abs_dir, base);
    free(abs_dir);
    return out;
}

int gi_batch_root_owner_format(const gi_batch_root_owner *o, gi_buf *out)
{
    /* A newline would end the path early: the record would name another
     * checkpoint, and the root be removed while its checkpoint needs it. */
    if (o->pid <= 0 || (o->ckpt[0] && o->ckpt[0] != '/') || strchr(o->ckpt, '\n'))
        return -1;
    char head[64];
    int n = snprintf(head, sizeof head, OWNER_MAGIC "\n%ld %llu\n", o->pid, o->start);
    size_t len = strlen(o->ckpt);
    if ((size_t)n + len + 1 > GI_BATCH_ROOT_OWNER_MAX)
        return -1;
    gi_buf_put(out, head, (size_t)n);
    gi_buf_put(out, o->ckpt, len);
    gi_buf_put_u8(out, '\n');
    return 0;
}

/* A decimal number without sign or leading zeros, at most max; *s moves
 * past it. */
static int parse_decimal(const char **s, const char *end, unsigned long long max,
                         unsigned long long *out)
{
    const char *p = *s;
    unsigned long long v = 0;
    for (; p < end && *p >= '0' && *p <= '9'; p++) {
        unsigned d = (unsigned)(*p - '0');
        if ((p > *s && v == 0) || v > (max - d) / 10)
            return -1;
        v = v * 10 + d;
    }
    if (p == *s)
        return -1;
    *s = p;
    *out = v;
    return 0;
}

int gi_batch_root_owner_parse(const char *text, size_t len, const char *path,
                              gi_batch_root_owner *o, gi_error *err)
{
    o->ckpt = NULL;
    const char *s = text, *end = text + len;
    unsigned long long pid, start;
    if (len > GI_BATCH_ROOT_OWNER_MAX || len < sizeof OWNER_MAGIC ||
        memcmp(s, OWNER_MAGIC "\n", sizeof OWNER_MAGIC) != 0)
        return gi_fail(err, GI_EINVAL, "%s: not a gi render owner record", path);
    s += sizeof OWNER_MAGIC;
    if (parse_decimal(&s, end, LONG_MAX, &pid) || pid == 0 || s == end || *s++ != ' ' ||
        parse_decimal(&s, end, ULLONG_MAX, &start) || s == end || *s++ != '\n')
        return gi_fail(err, GI_EINVAL, "%s: line 2 is not \"PID START\"", path);
    const char *nl = memchr(s, '\n', (size_t)(end - s));
    if (!nl || nl + 1 != end)
        return gi_fail(err, GI_EINVAL, "%s: line 3 (the checkpoint) is not the last line",
                       path);
    if (memchr(s, '\0', (size_t)(nl - s)) || (nl > s && s[0] != '/'))
        return gi_fail(err, GI_EINVAL, "%s: line 3 is not an absolute path", path);
    o->pid = (long)pid;
    o->start = start;
    o->ckpt = gi_xmalloc((size_t)(nl - s) + 1);
    memcpy(o->ckpt, s, (size_t)(nl - s));
    o->ckpt[nl - s] = '\0';
    return 0;
}

static void write_owner(const char *root, const char *ckpt)
{
    char *abs = ckpt ? absolute_file(ckpt) : NULL;
    long pid = (long)getpid();
    gi_batch_root_owner o = {pid, process_start(pid), abs ? abs : ""};
    gi_buf rec;
    gi_buf_init(&rec);
    char *path = gi_path_join(root, ".owner");
    gi_error err;
    /* Without a record the root waits for the age rule. */
    if (gi_batch_root_owner_format(&o, &rec))
        gi_debug("%s: no owner record: the checkpoint's path cannot be written in one", root);
    else if (gi_write_file_atomic(path, rec.data, rec.len, &err))
        gi_debug("%s", err.msg);
    gi_buf_free(&rec);
    free(abs);
    free(path);
}

char *gi_batch_root_make(const char *tmp, const char *ckpt, gi_error *err)
{
    size_t n = strlen(tmp) + 32;
    char *root = gi_xmalloc(n);
    snprintf(root, n, "%s/gi-render-XXXXXX", tmp);
    if (!mkdtemp(root)) {
        gi_fail(err, GI_EIO, "%s: cannot create a temporary directory for batch files: %s "
                "(set TMPDIR to a writable directory)", root, strerror(errno));
        free(root);
        return NULL;
    }
    char *abs = realpath(root, NULL);
    if (abs) {
        free(root);
        root = abs;
    }
    write_owner(root, ckpt);
    return root;
}

void gi_batch_root_claim(const char *root, const char *ckpt)
{
    write_owner(root, ckpt);
}

/* 1 if root is of no use: its owner record names a process that is gone
 * and a checkpoint that does not name root. Roots without a record are
 * left to the age rule. */
static int orphaned(const char *root)
{
    char *path = gi_path_join(root, ".owner");
    gi_buf b;
    gi_buf_init(&b);
    gi_error err;
    gi_batch_root_owner o;
    /* No record, or a damaged one: left to the age rule. */
    int rc = gi_read_file(path, GI_BATCH_ROOT_OWNER_MAX, &b, &err);
    if (rc == 0 && gi_batch_root_owner_parse((const char *)b.data, b.len, path, &o, &err)) {
        gi_debug("%s", err.msg);
        rc = -1;
    }
    gi_buf_free(&b);
    free(path);
    if (rc)
        return 0;
    int orphan = 0;
    if (o.start == 0 || process_start(o.pid) != o.start) {
        char *named = o.ckpt[0] ? gi_local_checkpoint_batch_root(o.ckpt) : NULL;
        orphan = !named || strcmp(named, root) != 0;
        free(named);
    }
    free(o.ckpt);
    return orphan;
}

/* A root that is ours and of no use: removed whatever its age. */
static int ours_and_orphaned(const char *root)
{
    return gi_local_batch_root_ours(root) && orphaned(root);
}

int gi_batch_root_sweep(const char *tmp, double max_age_s)
{
    char *abs_tmp = realpath(tmp, NULL); /* roots are named by absolute paths */
    if (!abs_tmp)
        return 0;
    int removed = gi_batch_dir_sweep_where(abs_tmp, -1e300, ours_and_orphaned) +
                  gi_batch_dir_sweep_where(abs_tmp, max_age_s, gi_local_batch_root_ours);
    free(abs_tmp);
    return removed;
}
