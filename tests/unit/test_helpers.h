/* Helpers shared by unit tests that need scenes. */
#ifndef GI_TEST_HELPERS_H
#define GI_TEST_HELPERS_H

#include "gi_error.h"
#include "gi_scene.h"

/* Writes `text` to <tmpdir>/<name> and loads it as a scene. */
int gi_test_load_scene_text(const char *name, const char *text, gi_scene *out, gi_error *err);
/* Loads a scene from the source tree (path relative to the repository). */
int gi_test_load_scene_file(const char *path, gi_scene *out, gi_error *err);

#endif
