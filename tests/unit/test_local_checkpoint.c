/* Unit tests: the batch root a `gi render` checkpoint names, and which
 * directories a render takes for its own batch root (it removes them, so a
 * damaged or hostile checkpoint must not name anything else). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gi_batch_dir.h"
#include "gi_batch_root.h"
#include "gi_buf.h"
#include "gi_fs.h"
#include "gi_local_checkpoint.h"
#include "gi_test.h"

/* A checkpoint's header as gi_local_checkpoint_write lays it out, then a
 * byte of the run's state. */
static void put_checkpoint(const char *path, uint32_t version, const char *root, size_t cut)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_u32(&b, 0x434C4947u);
    gi_buf_put_u32(&b, version);
    gi_buf_put_str(&b, "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef");
    if (root)
        gi_buf_put_str(&b, root);
    gi_buf_put_u8(&b, 1);
    gi_error err;
    GI_CHECK_OK(gi_write_file_atomic(path, b.data, cut ? cut : b.len, &err));
    gi_buf_free(&b);
}

GI_TEST(test_local_checkpoint_batch_root)
{
    char path[512];
    snprintf(path, sizeof path, "%s/.job.checkpoint", gi_test_tmpdir());
    put_checkpoint(path, 2, "/var/tmp/gi-render-abc123", 0);
    char *root = gi_local_checkpoint_batch_root(path);
    GI_CHECK_MSG(root && strcmp(root, "/var/tmp/gi-render-abc123") == 0, "%s",
                 root ? root : "(none)");
    free(root);
    put_checkpoint(path, 2, "", 0); /* none recorded */
    GI_CHECK(gi_local_checkpoint_batch_root(path) == NULL);
    put_checkpoint(path, 1, NULL, 0); /* before batch roots were recorded */
    GI_CHECK(gi_local_checkpoint_batch_root(path) == NULL);
    put_checkpoint(path, 2, "/var/tmp/gi-render-abc123", 80); /* torn in the root */
    GI_CHECK(gi_local_checkpoint_batch_root(path) == NULL);
    put_checkpoint(path, 3, "/var/tmp/gi-render-abc123", 0); /* a newer format */
    GI_CHECK(gi_local_checkpoint_batch_root(path) == NULL);
    unlink(path);
    GI_CHECK(gi_local_checkpoint_batch_root(path) == NULL);
}

GI_TEST(test_local_batch_root_ours)
{
    char base[512], dir[600], other[600], link[600], open_dir[600];
    if (!realpath(gi_test_tmpdir(), base)) {
        GI_CHECK_MSG(0, "realpath %s", gi_test_tmpdir());
        return;
    }
    snprintf(dir, sizeof dir, "%s/gi-render-Ab12Cd", base);
    snprintf(other, sizeof other, "%s/batches", base);
    snprintf(link, sizeof link, "%s/gi-render-link", base);
    snprintf(open_dir, sizeof open_dir, "%s/gi-render-open", base);
    GI_CHECK(mkdir(dir, 0700) == 0 && mkdir(other, 0700) == 0 && mkdir(open_dir, 0700) == 0);
    GI_CHECK(chmod(open_dir, 0755) == 0 && symlink(dir, link) == 0);

    GI_CHECK(gi_local_batch_root_ours(dir));
    GI_CHECK(!gi_local_batch_root_ours(other));    /* not a render's name */
    GI_CHECK(!gi_local_batch_root_ours(link));     /* a link, even to one */
    GI_CHECK(!gi_local_batch_root_ours(open_dir)); /* others may enter */
    GI_CHECK(!gi_local_batch_root_ours("/"));
    GI_CHECK(!gi_local_batch_root_ours("gi-render-Ab12Cd")); /* relative */
    GI_CHECK(!gi_local_batch_root_ours(NULL));
    char up[700];
    snprintf(up, sizeof up, "%s/gi-render-Ab12Cd/../gi-render-Ab12Cd", base);
    GI_CHECK(!gi_local_batch_root_ours(up));
    snprintf(up, sizeof up, "%s/gi-render-gone", base); /* missing */
    GI_CHECK(!gi_local_batch_root_ours(up));
    rmdir(dir);
    rmdir(other);
    rmdir(open_dir);
    unlink(link);
}

/* Makes root's owner record name a process that is gone (a child that
 * exited) and the checkpoint ckpt ("" for none). */
static void dead_owner(const char *root, const char *ckpt)
{
    pid_t pid = fork();
    if (pid == 0)
        _exit(0);
    waitpid(pid, NULL, 0);
    char rec[1200], path[700];
    snprintf(rec, sizeof rec, "gi-render-owner 1\n%ld 12345\n%s\n", (long)pid, ckpt);
    snprintf(path, sizeof path, "%s/.owner", root);
    gi_error err;
    GI_CHECK_OK(gi_write_file_atomic(path, rec, strlen(rec), &err));
}

/* The sweep a render starts with: roots whose render is alive stay; those
 * whose render is gone go, unless a checkpoint names them; those without
 * an owner record (an older gi's) wait for the age rule. */
GI_TEST(test_batch_root_sweep_removes_what_cannot_be_resumed)
{
    char base[512], tmp[600], ckpt[700];
    GI_REQUIRE(realpath(gi_test_tmpdir(), base) != NULL);
    snprintf(tmp, sizeof tmp, "%s/roots", base);
    snprintf(ckpt, sizeof ckpt, "%s/.job.checkpoint", base);
    GI_REQUIRE(mkdir(tmp, 0700) == 0);
    gi_error err;
    char *live = gi_batch_root_make(tmp, NULL, &err), *named = gi_batch_root_make(tmp, ckpt, &err);
    char *orphan = gi_batch_root_make(tmp, NULL, &err), *bare = gi_batch_root_make(tmp, NULL, &err);
    GI_REQUIRE(live && named && orphan && bare);
    GI_CHECK(strncmp(live, tmp, strlen(tmp)) == 0 && gi_local_batch_root_ours(live));
    char path[700];
    snprintf(path, sizeof path, "%s/.owner", bare);
    GI_CHECK(unlink(path) == 0);
    dead_owner(named, ckpt);
    dead_owner(orphan, "");
    put_checkpoint(ckpt, 2, named, 0);
    GI_CHECK(gi_batch_root_sweep(tmp, GI_BATCH_DIR_MAX_AGE_S) == 1);
    GI_CHECK(access(orphan, F_OK) != 0);
    GI_CHECK(access(live, F_OK) == 0 && access(named, F_OK) == 0 && access(bare, F_OK) == 0);
    /* The checkpoint replaced by one of another render's: nothing can
     * resume that root any more. */
    put_checkpoint(ckpt, 2, "/var/tmp/gi-render-other", 0);
    GI_CHECK(gi_batch_root_sweep(tmp, GI_BATCH_DIR_MAX_AGE_S) == 1);
    GI_CHECK(access(named, F_OK) != 0 && access(live, F_OK) == 0 && access(bare, F_OK) == 0);
    /* A resumed render claims the root it reads: alive again, it stays. */
    dead_owner(live, "");
    gi_batch_root_claim(live, ckpt);
    GI_CHECK(gi_batch_root_sweep(tmp, GI_BATCH_DIR_MAX_AGE_S) == 0 && access(live, F_OK) == 0);
    GI_CHECK_OK(gi_batch_dir_remove(tmp, &err));
    free(live);
    free(named);
    free(orphan);
    free(bare);
}

/* The owner record reads back exactly what was written; anything else is
 * refused with a message (and the sweep then leaves the root to the age
 * rule, as if it had no record). */
GI_TEST(test_batch_root_owner_record)
{
    gi_batch_root_owner o = {4242, 987654321ull, "/var/tmp/job.checkpoint"}, back;
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE(gi_batch_root_owner_format(&o, &b) == 0);
    static const char want[] = "gi-render-owner 1\n4242 987654321\n/var/tmp/job.checkpoint\n";
    GI_CHECK(b.len == strlen(want) && memcmp(b.data, want, b.len) == 0);
    gi_error err;
    GI_REQUIRE(gi_batch_root_owner_parse((const char *)b.data, b.len, "r", &back, &err) == 0);
    GI_CHECK(back.pid == 4242 && back.start == 987654321ull &&
             strcmp(back.ckpt, o.ckpt) == 0);
    free(back.ckpt);
    GI_CHECK(gi_batch_root_owner_parse("gi-render-owner 1\n7 0\n\n", 23, "r", &back, &err) == 0 &&
             back.pid == 7 && back.ckpt[0] == '\0');
    free(back.ckpt);
    static const char *const bad[] = {
        "gi-render-owner 1\n-7 0\n\n",       /* sscanf took a sign */
        "gi-render-owner 1\n+7 0\n\n",
        "gi-render-owner 1\n0 0\n\n",        /* no process */
        "gi-render-owner 1\n7 0 junk\n\n",   /* sscanf ignored the rest */
        "gi-render-owner 1\n7 -1\n\n",       /* %llu took -1 as 2^64 - 1 */
        "gi-render-owner 1\n7 0\nrel/ckpt\n", /* not absolute */
        "gi-render-owner 1\n7 0\n/a\n/b\n",  /* a fourth line */
        "gi-render-owner 1\n7 0\n/a",        /* cut */
        "gi-render-owner 1\n99999999999999999999 0\n\n",
        "gi-render-owner 2\n7 0\n\n",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        gi_error_clear(&err);
        GI_CHECK_MSG(gi_batch_root_owner_parse(bad[i], strlen(bad[i]), "r", &back, &err) != 0 &&
                         err.code == GI_EINVAL && strncmp(err.msg, "r: ", 3) == 0,
                     "record %zu parsed", i);
    }
    /* A newline in the checkpoint's path cannot be written: the record
     * would name another file. */
    gi_buf_reset(&b);
    o.ckpt = "/var/tmp/a\nb.checkpoint";
    GI_CHECK(gi_batch_root_owner_format(&o, &b) != 0 && b.len == 0);
    o.ckpt = "job.checkpoint";
    GI_CHECK(gi_batch_root_owner_format(&o, &b) != 0 && b.len == 0);
    gi_buf_free(&b);
}

/* A render whose checkpoint's path has a newline gets a root without a
 * record: the sweep leaves it to the age rule instead of reading another
 * checkpoint's name from a cut path and removing it. */
GI_TEST(test_batch_root_newline_checkpoint_has_no_record)
{
    char base[512], ckpt[700], path[800];
    GI_REQUIRE(realpath(gi_test_tmpdir(), base) != NULL);
    snprintf(ckpt, sizeof ckpt, "%s/a\nb.checkpoint", base);
    gi_error err;
    char *root = gi_batch_root_make(base, ckpt, &err);
    GI_REQUIRE(root != NULL);
    snprintf(path, sizeof path, "%s/.owner", root);
    GI_CHECK(access(path, F_OK) != 0);
    GI_CHECK(gi_batch_root_sweep(base, GI_BATCH_DIR_MAX_AGE_S) == 0 && access(root, F_OK) == 0);
    GI_CHECK_OK(gi_batch_dir_remove(root, &err));
    free(root);
}
