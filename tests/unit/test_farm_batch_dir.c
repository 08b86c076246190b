/* Unit tests: per-job batch directories (names, creation on first use,
 * removal without following links, the idle sweep). */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_batch_dir.h"
#include "gi_fs.h"
#include "gi_test.h"
#include "gi_worker_ctx.h"

static void put_file(const char *dir, const char *name)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "wb");
    if (f) {
        fputs("x", f);
        fclose(f);
    }
}

static void age(const char *path, time_t seconds)
{
    struct timespec t[2] = {{time(NULL) - seconds, 0}, {time(NULL) - seconds, 0}};
    utimensat(AT_FDCWD, path, t, 0);
}

GI_TEST(test_farm_batch_dir_lifetime)
{
    char root[512], outside[600];
    snprintf(root, sizeof root, "%s/batches", gi_test_tmpdir());
    snprintf(outside, sizeof outside, "%s/outside", gi_test_tmpdir());
    gi_error err;
    GI_REQUIRE_OK(gi_mkdirs(outside, &err));
    put_file(outside, "precious");

    /* Named by job id and the job text's hash: same job, same directory. */
    char *a = gi_batch_dir_path(root, 12, "{\"method\": \"detp\"}");
    char *a2 = gi_batch_dir_path(root, 12, "{\"method\": \"detp\"}");
    char *b = gi_batch_dir_path(root, 12, "{\"method\": \"pt\"}");
    GI_CHECK(strcmp(a, a2) == 0 && strcmp(a, b) != 0);
    GI_CHECK_MSG(strncmp(a + strlen(root), "/12-", 4) == 0 && strlen(a) == strlen(root) + 20, "%s",
                 a);

    /* Created on first use by the method's helper. */
    gi_worker_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.job_id = 12;
    const char *dir;
    GI_CHECK(gi_worker_batch_dir(&ctx, &dir, &err) != 0 && dir == NULL);
    GI_CHECK(strstr(err.msg, "no batch directory") != NULL);
    ctx.batch_dir = gi_xstrdup(a);
    GI_REQUIRE_OK(gi_worker_batch_dir(&ctx, &dir, &err));
    GI_CHECK(dir == ctx.batch_dir && access(a, W_OK) == 0);
    GI_REQUIRE_OK(gi_worker_batch_dir(&ctx, &dir, &err));
    free(ctx.batch_dir);

    /* Removal takes everything below, but never follows a link out. */
    char sub[700], link[800];
    snprintf(sub, sizeof sub, "%s/deep/er", a);
    GI_REQUIRE_OK(gi_mkdirs(sub, &err));
    put_file(sub, "batch-0.gids");
    put_file(a, "batch-1.gids");
    snprintf(link, sizeof link, "%s/escape", a);
    GI_REQUIRE(symlink(outside, link) == 0);
    GI_REQUIRE_OK(gi_batch_dir_remove(a, &err));
    GI_CHECK(access(a, F_OK) != 0);
    char precious[700];
    snprintf(precious, sizeof precious, "%s/precious", outside);
    GI_CHECK(access(precious, F_OK) == 0);
    GI_CHECK_OK(gi_batch_dir_remove(a, &err)); /* missing: fine */

    /* The sweep: idle job directories go, fresh or kept ones stay, and
     * names that are not job directories are never touched. */
    char *c = gi_batch_dir_path(root, 3, "c"), *d = gi_batch_dir_path(root, 4, "d");
    char other[600];
    snprintf(other, sizeof other, "%s/notes", root);
    GI_REQUIRE_OK(gi_mkdirs(a, &err));
    GI_REQUIRE_OK(gi_mkdirs(b, &err));
    GI_REQUIRE_OK(gi_mkdirs(c, &err));
    GI_REQUIRE_OK(gi_mkdirs(d, &err));
    GI_REQUIRE_OK(gi_mkdirs(other, &err));
    put_file(c, "f");
    age(a, 10 * 86400);
    age(c, 10 * 86400);
    age(d, 10 * 86400);
    age(other, 10 * 86400);
    const char *keep[] = {d, NULL};
    GI_CHECK(gi_batch_dir_sweep(root, GI_BATCH_DIR_MAX_AGE_S, keep) == 2);
    GI_CHECK(access(a, F_OK) != 0 && access(c, F_OK) != 0);
    GI_CHECK(access(b, F_OK) == 0 && access(d, F_OK) == 0 && access(other, F_OK) == 0);
    /* Touching marks a directory as in use. */
    gi_batch_dir_touch(d);
    GI_CHECK(gi_batch_dir_sweep(root, GI_BATCH_DIR_MAX_AGE_S, NULL) == 0);
    GI_CHECK(access(d, F_OK) == 0);

    /* A job that is over: all its directories, whatever their text and age,
     * and no other job's (12 is not 1 or 120). */
    char *e = gi_batch_dir_path(root, 1, "e"), *g = gi_batch_dir_path(root, 120, "g");
    GI_REQUIRE_OK(gi_mkdirs(a, &err));
    GI_REQUIRE_OK(gi_mkdirs(e, &err));
    GI_REQUIRE_OK(gi_mkdirs(g, &err));
    put_file(a, "batch-0.gids");
    GI_CHECK(gi_batch_dir_remove_job(root, 12) == 2);
    GI_CHECK(access(a, F_OK) != 0 && access(b, F_OK) != 0);
    GI_CHECK(access(e, F_OK) == 0 && access(g, F_OK) == 0 && access(d, F_OK) == 0 &&
             access(other, F_OK) == 0);
    GI_CHECK(gi_batch_dir_remove_job(root, 12) == 0);
    free(e);
    free(g);
    free(a);
    free(a2);
    free(b);
    free(c);
    free(d);
}
