/* gi_anim_pose: a worker's scene and ray tracer posed for an animation's
 * frame (gi_anim.h): the mobile's vertices as loaded, kept at first use, and
 * the frame they are posed for, so that the tasks of one frame pose once.
 * Every frame is posed from the vertices as loaded, so its geometry (and
 * the ray tracer's hits, gi_rt_update_object) does not depend on the frames
 * posed before. Worker side: calls Embree. */
#ifndef GI_ANIM_POSE_H
#define GI_ANIM_POSE_H

#include <stdint.h>

#include "gi_anim.h"
#include "gi_rt.h"

typedef struct gi_anim_poser {
    gi_vec3 *base_pos, *base_nrm; /* the mobile as loaded (NULL until first posed) */
    int posed;                    /* 0: as loaded */
    uint32_t frame;               /* the frame posed for, when posed */
} gi_anim_poser;

/* Poses a's (resolved) mobile in scene and rt for `frame`; nothing if it is
 * posed for that frame already. scene must be rt's and as loaded at the
 * first call. On error the poser is left unposed (the next call poses
 * again). */
int gi_anim_poser_pose(gi_anim_poser *ps, const gi_anim *a, gi_scene *scene, gi_rt *rt,
                       uint32_t frame, gi_error *err);
void gi_anim_poser_free(gi_anim_poser *ps);

#endif
