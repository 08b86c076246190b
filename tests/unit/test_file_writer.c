/* Unit tests: gi_file_writer (a file written on a thread of its own). */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "gi_file_writer.h"
#include "gi_fs.h"
#include "gi_test.h"

GI_TEST(test_file_writer_writes_in_the_background)
{
    char path[512];
    snprintf(path, sizeof path, "%s/written", gi_test_tmpdir());
    gi_buf b;
    gi_buf_init(&b);
    for (int i = 0; i < 1 << 20; i++)
        gi_buf_put_u32(&b, (uint32_t)i * 2654435761u);
    gi_buf want;
    gi_buf_init(&want);
    gi_buf_put(&want, b.data, b.len);
    gi_file_writer *w = gi_file_writer_start(path, &b);
    GI_CHECK(b.len == 0 && b.data == NULL); /* taken over */
    while (!gi_file_writer_done(w))
        usleep(1000);
    gi_error err;
    double seconds = -1.0;
    GI_CHECK_OK(gi_file_writer_finish(w, &seconds, &err));
    GI_CHECK(seconds >= 0.0);
    gi_buf got;
    gi_buf_init(&got);
    GI_CHECK_OK(gi_read_file(path, 1 << 30, &got, &err));
    GI_CHECK(got.len == want.len && memcmp(got.data, want.data, want.len) == 0);
    gi_buf_free(&got);
    gi_buf_free(&want);

    /* A write that cannot be made: finish says why, nothing is left behind. */
    snprintf(path, sizeof path, "%s/no-such-dir/file", gi_test_tmpdir());
    gi_buf_put_u32(&b, 7);
    w = gi_file_writer_start(path, &b);
    GI_CHECK(gi_file_writer_finish(w, NULL, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "no-such-dir") != NULL, "%s", err.msg);
    GI_CHECK(access(path, F_OK) != 0);
}
