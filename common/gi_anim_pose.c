/* gi_anim_pose: posing a worker's scene and ray tracer per frame (see
 * gi_anim_pose.h). */
#include "gi_anim_pose.h"

#include <stdlib.h>
#include <string.h>

int gi_anim_poser_pose(gi_anim_poser *ps, const gi_anim *a, gi_scene *scene, gi_rt *rt,
                       uint32_t frame, gi_error *err)
{
    if (!gi_anim_moves_object(a) || (ps->posed && ps->frame == frame))
        return 0;
    if (!ps->base_pos &&
        gi_scene_object_copy_base(scene, a->object_index, &ps->base_pos, &ps->base_nrm, err))
        return -1;
    gi_mat4 m;
    gi_anim_pose(a, frame, &m);
    ps->posed = 0;
    if (gi_scene_pose_object(scene, a->object_index, ps->base_pos, ps->base_nrm, &m, err) ||
        gi_rt_update_object(rt, a->object_index, err))
        return -1;
    ps->posed = 1;
    ps->frame = frame;
    return 0;
}

void gi_anim_poser_free(gi_anim_poser *ps)
{
    free(ps->base_pos);
    free(ps->base_nrm);
    memset(ps, 0, sizeof *ps);
}
