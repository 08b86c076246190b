/* gi_camera: camera parsing and frames. */
#include "gi_camera.h"

#include <math.h>

#define MAX_COORD 1e12

int gi_camera_parse(gi_jv *v, const cJSON *cam, const char *path, gi_camera *c)
{
    static const char *const keys[] = {"position", "look_at", "up", "fov_y", NULL};
    if (gi_jv_keys(v, cam, path, keys))
        return -1;
    double fov = 0;
    c->up = gi_v3(0, 1, 0);
    if (gi_jv_vec3(v, cam, path, "position", 1, -MAX_COORD, MAX_COORD, &c->position) ||
        gi_jv_vec3(v, cam, path, "look_at", 1, -MAX_COORD, MAX_COORD, &c->look_at) ||
        gi_jv_vec3(v, cam, path, "up", 0, -MAX_COORD, MAX_COORD, &c->up) ||
        gi_jv_number(v, cam, path, "fov_y", 1, 1e-3, 179.0, &fov))
        return -1;
    c->fov_y_deg = (float)fov;
    gi_vec3 dir = gi_sub(c->look_at, c->position);
    if (gi_length(dir) == 0.0f)
        return gi_jv_fail(v, path, "position and look_at are the same point");
    if (gi_length(gi_cross(gi_normalize(dir), gi_normalize(c->up))) < 1e-6f) {
        char p[512];
        return gi_jv_fail(v, gi_json_path(p, sizeof p, path, "up"),
                          "is zero or parallel to the view direction");
    }
    return 0;
}

void gi_camera_frame_init(gi_camera_frame *f, const gi_camera *c, int width, int height)
{
    f->origin = c->position;
    f->forward = gi_normalize(gi_sub(c->look_at, c->position));
    gi_vec3 right = gi_normalize(gi_cross(f->forward, c->up));
    gi_vec3 up = gi_cross(right, f->forward);
    float th = tanf(0.5f * c->fov_y_deg * (float)GI_PI / 180.0f);
    float aspect = (float)width / (float)height;
    f->right = gi_scale(right, th * aspect);
    f->up = gi_scale(up, th);
    f->width = width;
    f->height = height;
}
