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

static void write_owner(const char *root, const char *ckpt)
{
    char *abs = ckpt ? absolute_file(ckpt) : NULL;
    long pid = (long)getpid();
    char rec[PATH_MAX + 128];
    int n = snprintf(rec, sizeof rec, OWNER_MAGIC "\n%ld %llu\n%s\n", pid, process_start(pid),
                     abs ? abs : "");
    free(abs);
    char *path = gi_path_join(root, ".owner");
    gi_error err;
    if (n > 0 && (size_t)n < sizeof rec && gi_write_file_atomic(path, rec, (size_t)n, &err))
        gi_debug("%s", err.msg); /* without it the root waits for the age rule */
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
    int rc = gi_read_file(path, PATH_MAX + 128, &b, &err);
    free(path);
    if (rc) {
        gi_buf_free(&b);
        return 0;
    }
    gi_buf_put(&b, "", 1); /* a C string */
    char *text = (char *)b.data, *line2 = strchr(text, '\n'), *line3 = NULL;
    long pid = 0;
    unsigned long long start = 0;
    int ok = line2 && strncmp(text, OWNER_MAGIC "\n", sizeof OWNER_MAGIC) == 0 &&
             sscanf(line2 + 1, "%ld %llu", &pid, &start) == 2 && pid > 0 &&
             (line3 = strchr(line2 + 1, '\n')) != NULL;
    int orphan = 0;
    if (ok && (start == 0 || process_start(pid) != start)) {
        char *end = strchr(line3 + 1, '\n');
        if (end)
            *end = '\0';
        char *named = line3[1] ? gi_local_checkpoint_batch_root(line3 + 1) : NULL;
        orphan = !named || strcmp(named, root) != 0;
        free(named);
    }
    gi_buf_free(&b);
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
