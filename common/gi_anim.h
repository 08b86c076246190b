/* gi_anim: the "animation" block of a detp, pt or quadrature job
 * (docs/job-format.md, "### animation"): which mobile object moves, over
 * how many frames, its keyframed pose and the camera path; parsed
 * strictly, resolved against the scene, and evaluated per frame (the pose
 * as an affine matrix).
 *
 * A key's pose maps the object's as-loaded (refined) world-space vertices p
 * to  pivot + translate + R * (scale * (p - pivot)),  pivot = the centre of
 * the object's as-loaded bounding box, so rotate and scale act in place.
 * Between keys translate and scale are linear and R is the slerp of unit
 * quaternions (the short way); before the first key and after the last the
 * nearest key holds.
 *
 * Everything is stored inline (no heap): the methods free their params
 * with a plain free(), and every parse or resolve error path stays
 * leak-free without a destructor. */
#ifndef GI_ANIM_H
#define GI_ANIM_H

#include <stdint.h>

#include "gi_job.h"
#include "gi_json.h"
#include "gi_math.h"
#include "gi_scene.h"

#define GI_ANIM_MAX_FRAMES 100000
#define GI_ANIM_MAX_KEYS 1024
#define GI_ANIM_NAME_MAX 256 /* object name, with its NUL */
#define GI_ANIM_PATH_MAX 32  /* the block's path in the job, with its NUL */

typedef struct gi_anim_key {
    uint32_t frame;
    double translate[3];
    double rotation[4]; /* unit quaternion (w, x, y, z), w >= 0 */
    double scale;       /* uniform, > 0 */
} gi_anim_key;

typedef struct gi_anim_camera_key {
    uint32_t frame;
    gi_camera camera;
} gi_anim_camera_key;

typedef struct gi_anim {
    int enabled; /* the job has an animation block */
    char path[GI_ANIM_PATH_MAX]; /* "detp.animation": what errors name */
    char object[GI_ANIM_NAME_MAX]; /* "": no object moves (a camera path alone) */
    uint32_t frames; /* frames 0 .. frames-1 */
    uint32_t key_count;
    gi_anim_key keys[GI_ANIM_MAX_KEYS]; /* frames strictly increasing */
    /* The camera path (GI_ANIM_CAMERA): keys strictly increasing in frame;
     * none: the job's camera in every frame. */
    uint32_t camera_count;
    gi_anim_camera_key cameras[GI_ANIM_MAX_KEYS];

    /* Resolved against the (refined) scene by gi_anim_resolve. */
    uint32_t object_index;
    double pivot[3]; /* centre of the object's as-loaded bounding box */
} gi_anim;

/* gi_anim_parse's flags: the block may hold a camera path ("camera"), and
 * then the moving object is optional. */
#define GI_ANIM_CAMERA 1

/* Parses the animation object `block` found at `path` ("detp.animation";
 * NULL block: no animation, enabled = 0). The block may also hold the
 * method's own `extra_keys` (NULL-terminated, or NULL), which the method
 * parses. Errors name the field path, e.g. "detp.animation.keyframes[2].frame". */
int gi_anim_parse(gi_anim *a, const cJSON *block, const char *path,
                  const char *const *extra_keys, int flags, gi_jv *v);
/* 1 if an object moves (the block names one). */
static inline int gi_anim_moves_object(const gi_anim *a)
{
    return a->enabled && a->object[0] != '\0';
}
/* The camera of `frame`: the path's (positions, look_at points, up vectors
 * and fields of view linear between keys, held before the first and after
 * the last; exactly a key's at its frame), or *base without a path. */
void gi_anim_camera(const gi_anim *a, const gi_camera *base, uint32_t frame, gi_camera *out);

/* Finds the object in the scene (it must exist, be "mobile": true and not
 * emissive) and takes the pivot from its current vertices (nothing without
 * an object). Call after any refinement; errors are
 * "<file>: <path>.object: ...". */
int gi_anim_resolve(gi_anim *a, const gi_scene *s, const char *file, gi_error *err);

/* The object-to-pose matrix of `frame` (applied to the as-loaded world-space
 * vertices). At a key's frame it is exactly that key's pose; an all-default
 * pose is exactly the identity. Frames past the last key hold it. */
void gi_anim_pose(const gi_anim *a, uint32_t frame, gi_mat4 *out);
/* 1 if the mobile does not move into `frame` (>= 1): its pose is the very
 * same as at frame - 1 (a held shot, frames before the first key or after
 * the last, equal keys), so nothing of the frame before changes. */
int gi_anim_still(const gi_anim *a, uint32_t frame);
/* Warns (gi_warn) when a key puts the mobile (resolved) wholly outside the
 * box of the scene's other objects: most likely a slip, a translate in the
 * wrong units or with the wrong sign; not refused, since an object may fly
 * over an open scene. */
void gi_anim_warn_keys(const gi_anim *a, const gi_scene *s, const char *file);

/* ---- A method's animation, frame by frame (pt, quadrature, a detp camera path). ---- */

/* check_scene's part: resolves a against the job's scene (on the
 * coordinator and in every worker), sets the job's frame_count and, on the
 * coordinator, warns about its keys. */
int gi_anim_check_scene(gi_anim *a, gi_job *job, gi_error *err);
/* While a is enabled, the job's output paths name `frame` (NAME.0003.exr). */
void gi_anim_set_frame(const gi_anim *a, gi_job *job, uint32_t frame);
/* Writes the outputs of *frame with write(job, ctx, err), then those of the
 * frames after it whose pose is the very same (the same outputs, written
 * again), moving *frame along. 1: *frame is the next frame that moves (its
 * tasks to plan); 0: the last frame (or a still's outputs) is written; -1:
 * writing *frame failed. */
int gi_anim_write_frames(const gi_anim *a, gi_job *job, uint32_t *frame,
                         int (*write)(gi_job *job, void *ctx, gi_error *err), void *ctx,
                         gi_error *err);
/* The pose of `frame` for a report: the rows of the 3 x 4 matrix applied to
 * the mobile's vertices as loaded. */
cJSON *gi_anim_pose_json(const gi_anim *a, uint32_t frame);
/* With a camera path, adds the camera of `frame` to a report's object o
 * ("camera": position, look_at, up, fov_y); nothing without one. */
void gi_anim_report_camera(const gi_anim *a, const gi_camera *base, uint32_t frame, cJSON *o);

/* The matrix of one pose given as translate, unit quaternion (w, x, y, z)
 * and scale about `pivot` (what gi_anim_pose builds; for tests). */
gi_mat4 gi_anim_matrix(const double pivot[3], const double translate[3], const double q[4],
                       double scale);

#endif
