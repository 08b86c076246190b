/* Helpers shared by unit tests that need scenes. */
#include "test_helpers.h"

#include <stdio.h>
#include <string.h>

#include "gi_assets.h"
#include "gi_fs.h"
#include "gi_test.h"

static int load_from(const char *root, const char *name, gi_scene *out, gi_error *err)
{
    gi_dir_source ds;
    gi_dir_source_init(&ds, root);
    gi_asset_source src = gi_dir_source_as_source(&ds);
    int rc = gi_scene_load(&src, name, out, err);
    gi_dir_source_free(&ds);
    return rc;
}

int gi_test_load_scene_text(const char *name, const char *text, gi_scene *out, gi_error *err)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", gi_test_tmpdir(), name);
    if (gi_write_file_atomic(path, text, strlen(text), err))
        return -1;
    return load_from(gi_test_tmpdir(), name, out, err);
}

int gi_test_load_scene_file(const char *path, gi_scene *out, gi_error *err)
{
    return load_from(gi_test_srcdir(), path, out, err);
}
