/* Unit tests: an animation's camera path (gi_anim.h): keys parsed with
 * their checks, positions, look_at points, up vectors and fields of view
 * linear between keys and exactly a key's at its frame, held outside them,
 * held frames found, and refusals naming the field. */
#include <stdlib.h>
#include <string.h>

#include "gi_anim.h"
#include "gi_test.h"

static int parse(const char *text, int flags, gi_anim *a, gi_error *err)
{
    cJSON *root;
    if (gi_json_parse(text, strlen(text), "job.json", &root, err))
        return -1;
    gi_jv v = {"job.json", err};
    int rc = gi_anim_parse(a, root, "pt.animation", NULL, flags, &v);
    cJSON_Delete(root);
    return rc;
}

GI_TEST(test_anim_camera_path_interpolates_and_holds)
{
    gi_anim *a = gi_xcalloc(1, sizeof *a);
    gi_error err;
    GI_REQUIRE_OK(parse("{\"frames\": 8, \"camera\": ["
                        "{\"frame\": 2, \"position\": [0, 0, -10], \"look_at\": [0, 0, 0],"
                        " \"fov_y\": 40},"
                        "{\"frame\": 6, \"position\": [4, 0, -10], \"look_at\": [0, 2, 0],"
                        " \"up\": [0, 1, 0.5], \"fov_y\": 60}]}",
                        GI_ANIM_CAMERA, a, &err));
    GI_CHECK(a->enabled && !gi_anim_moves_object(a) && a->camera_count == 2);
    gi_camera base = {{9, 9, 9}, {9, 9, 10}, {0, 1, 0}, 10}, c;
    gi_anim_camera(a, &base, 0, &c); /* before the first key: held */
    GI_CHECK(c.position.z == -10.0f && c.fov_y_deg == 40.0f);
    gi_anim_camera(a, &base, 6, &c); /* a key's frame: exactly the key */
    GI_CHECK(memcmp(&c, &a->cameras[1].camera, sizeof c) == 0);
    gi_anim_camera(a, &base, 4, &c); /* halfway */
    GI_CHECK_NEAR(c.position.x, 2.0, 1e-6);
    GI_CHECK_NEAR(c.look_at.y, 1.0, 1e-6);
    GI_CHECK_NEAR(c.up.z, 0.25, 1e-6);
    GI_CHECK_NEAR(c.fov_y_deg, 50.0, 1e-5);
    GI_CHECK(c.position.z == -10.0f); /* equal ends stay exact */
    /* Held frames: before the first key and after the last. */
    GI_CHECK(!gi_anim_still(a, 0));
    GI_CHECK(gi_anim_still(a, 1) && gi_anim_still(a, 2) && gi_anim_still(a, 7));
    GI_CHECK(!gi_anim_still(a, 3) && !gi_anim_still(a, 6));
    /* No path: the base camera in every frame. */
    GI_REQUIRE_OK(parse("{\"frames\": 3, \"object\": \"ball\", \"keyframes\": [{\"frame\": 0}]}",
                        GI_ANIM_CAMERA, a, &err));
    gi_anim_camera(a, &base, 2, &c);
    GI_CHECK(memcmp(&c, &base, sizeof c) == 0);
    free(a);
}

GI_TEST(test_anim_camera_path_refusals_name_the_field)
{
    gi_anim *a = gi_xcalloc(1, sizeof *a);
    gi_error err;
    static const struct {
        const char *text;
        int flags;
        const char *msg;
    } bad[] = {
        {"{\"frames\": 4, \"camera\": [{\"frame\": 0, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 40}]}",
         0, "pt.animation.camera: unknown key"},
        {"{\"frames\": 4}", GI_ANIM_CAMERA, "pt.animation.object"},
        {"{\"frames\": 4, \"camera\": [], \"keyframes\": [{\"frame\": 0}]}", GI_ANIM_CAMERA,
         "pt.animation.camera: at least one key"},
        {"{\"frames\": 4, \"camera\": [{\"frame\": 0, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 40}], \"keyframes\": [{\"frame\": 0}]}",
         GI_ANIM_CAMERA, "pt.animation.keyframes: keys for no object"},
        {"{\"frames\": 4, \"camera\": [{\"frame\": 4, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 40}]}",
         GI_ANIM_CAMERA, "pt.animation.camera[0].frame: 4 is not less than pt.animation.frames"},
        {"{\"frames\": 4, \"camera\": [{\"frame\": 1, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 40}, {\"frame\": 1, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 40}]}",
         GI_ANIM_CAMERA, "pt.animation.camera[1].frame: 1 is not after camera[0].frame"},
        {"{\"frames\": 4, \"camera\": [{\"frame\": 0, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 400}]}",
         GI_ANIM_CAMERA, "pt.animation.camera[0].fov_y"},
        {"{\"frames\": 4, \"camera\": [{\"frame\": 0, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 10], \"fov_y\": 40}, {\"frame\": 2, \"position\": [0, 0, 20],"
         " \"look_at\": [0, 0, 10], \"fov_y\": 40}]}",
         GI_ANIM_CAMERA, "pt.animation.camera: at frame 1, between keys, the position meets"},
        {"{\"frames\": 4, \"camera\": [{\"frame\": 0, \"position\": [0, 0, 0],"
         " \"look_at\": [0, 0, 1], \"fov_y\": 40, \"roll\": 3}]}",
         GI_ANIM_CAMERA, "pt.animation.camera[0].roll: unknown key (expected one of: frame,"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        GI_CHECK_MSG(parse(bad[i].text, bad[i].flags, a, &err) != 0, "case %zu parsed", i);
        GI_CHECK_MSG(strstr(err.msg, bad[i].msg) != NULL, "case %zu: %s", i, err.msg);
    }
    free(a);
}
