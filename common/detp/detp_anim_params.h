/* detp_anim_params: the "detp.animation" block of a job (docs/job-format.md,
 * "### animation"): which mobile object moves, over how many frames, and
 * its keyframed pose; parsed strictly, resolved against the scene, and
 * evaluated per frame as an affine matrix.
 *
 * A key's pose maps the object's as-loaded (refined) world-space vertices p
 * to  pivot + translate + R * (scale * (p - pivot)),  pivot = the centre of
 * the object's as-loaded bounding box, so rotate and scale act in place.
 * Between keys translate and scale are linear and R is the slerp of unit
 * quaternions (the short way); before the first key and after the last the
 * nearest key holds.
 *
 * Everything is stored inline (no heap): the detp method frees its params
 * with a plain free(), and every parse or resolve error path stays
 * leak-free without a destructor. */
#ifndef GI_DETP_ANIM_PARAMS_H
#define GI_DETP_ANIM_PARAMS_H

#include <stdint.h>

#include "gi_json.h"
#include "gi_math.h"
#include "gi_scene.h"

#define GI_DETP_ANIM_MAX_FRAMES 100000
#define GI_DETP_ANIM_MAX_KEYS 1024
#define GI_DETP_ANIM_NAME_MAX 256 /* object name, with its NUL */

/* How the mobile's own vertices are estimated each frame (thesis 1.12.4). */
typedef enum {
    GI_DETP_MOBILE_SPHERE_CACHE, /* Sphere Cache rooted at the mobile's bounding sphere */
    GI_DETP_MOBILE_EMBREE,       /* Disc Indexing (Embree) over the mobile's discs only */
    GI_DETP_MOBILE_LANES         /* every disc group near a segment, in vector lanes */
} gi_detp_mobile_estimator;

extern const char *const gi_detp_mobile_estimator_names[];

/* How a frame after the first is computed. Both trace the same paths; "full"
 * estimates every vertex from scratch over the frame's segments (for checks
 * and benchmarks: the incremental result must equal it bit for bit). */
typedef enum { GI_DETP_UPDATE_INCREMENTAL, GI_DETP_UPDATE_FULL } gi_detp_anim_update_mode;

extern const char *const gi_detp_anim_update_names[];

typedef struct gi_detp_anim_key {
    uint32_t frame;
    double translate[3];
    double rotation[4]; /* unit quaternion (w, x, y, z), w >= 0 */
    double scale;       /* uniform, > 0 */
} gi_detp_anim_key;

typedef struct gi_detp_anim_params {
    int enabled; /* the job has a detp.animation block */
    char object[GI_DETP_ANIM_NAME_MAX];
    uint32_t frames; /* frames 0 .. frames-1 */
    uint32_t key_count;
    gi_detp_anim_key keys[GI_DETP_ANIM_MAX_KEYS]; /* frames strictly increasing */
    gi_detp_mobile_estimator mobile_estimator;
    gi_detp_anim_update_mode update;

    /* Resolved against the (refined) scene by gi_detp_anim_resolve. */
    uint32_t object_index;
    double pivot[3]; /* centre of the object's as-loaded bounding box */
} gi_detp_anim_params;

/* Parses the "detp.animation" object `block` (NULL: no animation, enabled
 * = 0). Errors name the field path, e.g. "detp.animation.keyframes[2].frame". */
int gi_detp_anim_parse(gi_detp_anim_params *a, const cJSON *block, gi_jv *v);

/* Finds the object in the scene (it must exist, be "mobile": true and not
 * emissive) and takes the pivot from its current vertices. Call after any
 * refinement; errors are "<file>: detp.animation.object: ...". */
int gi_detp_anim_resolve(gi_detp_anim_params *a, const gi_scene *s, const char *file,
                         gi_error *err);

/* The object-to-pose matrix of `frame` (applied to the as-loaded world-space
 * vertices). At a key's frame it is exactly that key's pose; an all-default
 * pose is exactly the identity. Frames past the last key hold it. */
void gi_detp_anim_pose(const gi_detp_anim_params *a, uint32_t frame, gi_mat4 *out);
/* 1 if the mobile does not move into `frame` (>= 1): its pose is the very
 * same as at frame - 1 (a held shot, frames before the first key or after
 * the last, equal keys), so nothing of the frame before changes. */
int gi_detp_anim_still(const gi_detp_anim_params *a, uint32_t frame);
/* Warns (gi_warn) when a key puts the mobile (resolved) wholly outside the
 * box of the scene's other objects: most likely a slip, a translate in the
 * wrong units or with the wrong sign; not refused, since an object may fly
 * over an open scene. */
void gi_detp_anim_warn_keys(const gi_detp_anim_params *a, const gi_scene *s, const char *file);

/* The matrix of one pose given as translate, unit quaternion (w, x, y, z)
 * and scale about `pivot` (what gi_detp_anim_pose builds; for tests). */
gi_mat4 gi_detp_anim_matrix(const double pivot[3], const double translate[3],
                            const double q[4], double scale);

#endif
