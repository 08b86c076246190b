/* small_jobs: the scene and the four small jobs (detp, a detp animation, pt,
 * radiosity) that fuzz_checkpoint and fuzz_result run in-process to record
 * their seeds and restore points. Their order is the selector byte's in
 * fuzz_checkpoint's corpus: append, never reorder. */
#ifndef GI_FUZZ_SMALL_JOBS_H
#define GI_FUZZ_SMALL_JOBS_H

static const char small_scene_text[] =
    "{\"camera\": {\"position\": [0, 0, -0.9], \"look_at\": [0, 0, 0], \"fov_y\": 60},"
    " \"materials\": {\"wall\": {\"diffuse\": [0.6, 0.6, 0.6]},"
    "  \"lamp\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [5, 5, 5]}},"
    " \"objects\": ["
    "  {\"name\": \"room\", \"material\": \"wall\","
    "   \"box\": {\"size\": [2, 2, 2], \"inward\": true}},"
    "  {\"name\": \"lamp\", \"material\": \"lamp\", \"quad\": {\"size\": [0.5, 0.5]},"
    "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
    "                   {\"translate\": [0, 0.99, 0]}]},"
    "  {\"name\": \"ball\", \"material\": \"wall\", \"mobile\": true,"
    "   \"sphere\": {\"radius\": 0.2, \"subdivisions\": 0}}]}";

#define SMALL_JOB_TEXTS \
    "{\"scene\": \"scene.json\", \"method\": \"detp\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"detp\": {\"photons\": 3000, \"batch\": 1000, \"tile\": 4, \"image_spp\": 1}," \
    " \"outputs\": {\"exr\": \"a.exr\", \"bin\": \"a.bin\", \"json\": \"a.json\"}}", \
    "{\"scene\": \"scene.json\", \"method\": \"detp\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"detp\": {\"photons\": 3000, \"batch\": 1000, \"tile\": 4, \"image_spp\": 1," \
    "  \"animation\": {\"object\": \"ball\", \"frames\": 3," \
    "   \"keyframes\": [{\"frame\": 0}, {\"frame\": 2, \"translate\": [0.2, 0, 0]}]}}," \
    " \"outputs\": {\"exr\": \"b.exr\", \"bin\": \"b.bin\", \"json\": \"b.json\"}}", \
    "{\"scene\": \"scene.json\", \"method\": \"pt\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"pt\": {\"spp\": 4, \"tile\": 4, \"pass_spp\": 1}," \
    " \"outputs\": {\"exr\": \"c.exr\"}}", \
    "{\"scene\": \"scene.json\", \"method\": \"radiosity\", \"seed\": 3," \
    " \"image\": {\"width\": 8, \"height\": 6}," \
    " \"radiosity\": {\"patches\": 4, \"levels\": 1, \"rays\": 16, \"task_elements\": 40}," \
    " \"outputs\": {\"exr\": \"d.exr\", \"report\": \"d.json\"}}"
#define SMALL_JOBS 4

#endif
