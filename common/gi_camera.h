/* gi_camera: the pinhole camera (JSON form and ray generation).
 *
 * Image rows go top to bottom; the camera's right is cross(forward, up), so
 * with the Cornell box camera (looking +z, up +y) image right is -x. */
#ifndef GI_CAMERA_H
#define GI_CAMERA_H

#include <cjson/cJSON.h>

#include "gi_json.h"
#include "gi_scene.h"

/* {"position": [..], "look_at": [..], "up": [..] (default [0,1,0]), "fov_y": deg} */
int gi_camera_parse(gi_jv *v, const cJSON *obj, const char *path, gi_camera *out);

typedef struct gi_camera_frame {
    gi_vec3 origin;
    gi_vec3 forward, right, up; /* right and up scaled to the image plane at distance 1 */
    int width, height;
} gi_camera_frame;

void gi_camera_frame_init(gi_camera_frame *f, const gi_camera *c, int width, int height);

/* Unit direction through image point (px, py) in pixel units (0..width,
 * 0..height from the top-left corner). */
static inline gi_vec3 gi_camera_dir(const gi_camera_frame *f, float px, float py)
{
    float sx = 2.0f * px / (float)f->width - 1.0f;
    float sy = 1.0f - 2.0f * py / (float)f->height;
    return gi_normalize(gi_add(f->forward, gi_add(gi_scale(f->right, sx), gi_scale(f->up, sy))));
}

#endif
