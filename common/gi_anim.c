/* gi_anim: parsing, resolving and evaluating a job's "animation" block
 * (the keyframed pose of one mobile object, thesis 1.12). */
#include "gi_anim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gi_camera.h"
#include "gi_log.h"

/* Unit quaternion of a rotation by `degrees` about `axis` (not zero), as
 * written: (cos(h), sin(h) * axis / |axis|), h = degrees / 2 (w < 0 past
 * 180 degrees: 270 and -90 are one rotation but two spins). */
static void axis_angle_quat(const double axis[3], double degrees, double q[4])
{
    if (degrees == 0.0) {
        q[0] = 1.0;
        q[1] = q[2] = q[3] = 0.0;
        return;
    }
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double h = degrees * GI_PI / 360.0, s = sin(h) / n;
    q[0] = cos(h);
    q[1] = axis[0] * s;
    q[2] = axis[1] * s;
    q[3] = axis[2] * s;
}

/* The key's rotation from the quaternion as written, with w >= 0 so that
 * every rotation has one representative. */
static void set_rotation(gi_anim_key *k, const double written[4])
{
    double sign = written[0] < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 4; i++)
        k->rotation[i] = sign * written[i];
}

/* Two consecutive keys' rotations, as written, must be at most 180 degrees
 * apart: slerp takes the short way, so a 270-degree turn would play as 90
 * degrees the other way, and 0 to 360 as no turn at all. */
static int check_turn(const gi_anim *a, const double prev[4], const double cur[4], int i,
                      gi_jv *v)
{
    double d = prev[0] * cur[0] + prev[1] * cur[1] + prev[2] * cur[2] + prev[3] * cur[3];
    if (d >= 0.0)
        return 0;
    double apart = 360.0 / GI_PI * acos(d < -1.0 ? -1.0 : d);
    char kpath[64], path[96], rpath[128];
    snprintf(kpath, sizeof kpath, "%s.keyframes", a->path);
    gi_json_index_path(path, sizeof path, kpath, i);
    return gi_jv_fail(v, gi_json_path(rpath, sizeof rpath, path, "rotate"),
                      "%.1f degrees from keyframes[%d]'s rotation as written: the pose turns "
                      "the short way between keys, so it would turn %.1f degrees the other way; "
                      "add keys in between (at most 180 degrees apart)",
                      apart, i - 1, 360.0 - apart);
}

static int parse_rotate(gi_anim_key *k, double written[4], const cJSON *obj,
                        const char *path, gi_jv *v)
{
    static const char *const keys[] = {"axis", "degrees", NULL};
    const cJSON *rot;
    char rpath[160], apath[192];
    if (gi_jv_member_object(v, obj, path, "rotate", 0, &rot))
        return -1;
    if (!rot)
        return 0;
    gi_json_path(rpath, sizeof rpath, path, "rotate");
    double axis[3], degrees;
    if (gi_jv_keys(v, rot, rpath, keys) ||
        gi_jv_vec3d(v, rot, rpath, "axis", 1, -1e30, 1e30, axis) ||
        gi_jv_number(v, rot, rpath, "degrees", 1, -360.0, 360.0, &degrees))
        return -1;
    double n2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
    if (!(n2 > 0.0) || !isfinite(n2))
        return gi_jv_fail(v, gi_json_path(apath, sizeof apath, rpath, "axis"),
                          "the axis is zero (or its length is not finite)");
    axis_angle_quat(axis, degrees, written);
    set_rotation(k, written);
    return 0;
}

/* The frame of key i of the list `list` ("keyframes", "camera") at `path`:
 * given, below the animation's frames, and after the key before's (prev,
 * when i > 0). */
static int parse_key_frame(const gi_anim *a, const cJSON *obj, const char *path,
                           const char *list, int i, uint32_t prev, uint32_t *out, gi_jv *v)
{
    char fpath[128];
    gi_json_path(fpath, sizeof fpath, path, "frame");
    int64_t frame = 0;
    if (gi_jv_int(v, obj, path, "frame", 1, 0, GI_ANIM_MAX_FRAMES - 1, &frame))
        return -1;
    if (frame >= (int64_t)a->frames)
        return gi_jv_fail(v, fpath, "%lld is not less than %s.frames (%u)", (long long)frame,
                          a->path, a->frames);
    if (i > 0 && frame <= (int64_t)prev)
        return gi_jv_fail(v, fpath,
                          "%lld is not after %s[%d].frame (%u): key frames must be strictly "
                          "increasing",
                          (long long)frame, list, i - 1, prev);
    *out = (uint32_t)frame;
    return 0;
}

/* Key i; written: its rotation as written (the identity without one). */
static int parse_key(gi_anim *a, int i, const cJSON *obj, double written[4], gi_jv *v)
{
    static const char *const keys[] = {"frame", "translate", "rotate", "scale", NULL};
    gi_anim_key *k = &a->keys[i];
    char kpath[64], path[96];
    snprintf(kpath, sizeof kpath, "%s.keyframes", a->path);
    gi_json_index_path(path, sizeof path, kpath, i);
    memset(k, 0, sizeof *k);
    k->rotation[0] = 1.0;
    written[0] = 1.0;
    written[1] = written[2] = written[3] = 0.0;
    k->scale = 1.0;
    if (gi_jv_object(v, obj, path) || gi_jv_keys(v, obj, path, keys) ||
        parse_key_frame(a, obj, path, "keyframes", i, i > 0 ? a->keys[i - 1].frame : 0,
                        &k->frame, v))
        return -1;
    char spath[128];
    gi_json_path(spath, sizeof spath, path, "scale");
    if (gi_jv_vec3d(v, obj, path, "translate", 0, -1e15, 1e15, k->translate) ||
        parse_rotate(k, written, obj, path, v) ||
        gi_jv_number(v, obj, path, "scale", 0, -INFINITY, 1e6, &k->scale))
        return -1;
    if (!(k->scale > 0.0))
        return gi_jv_fail(v, spath, "%g is not > 0 (a uniform scale factor)", k->scale);
    if (k->scale < 1e-6)
        return gi_jv_fail(v, spath, "%g is below 1e-6", k->scale);
    return 0;
}

/* Camera key i of `arr`: {"frame", "position", "look_at", "up", "fov_y"}
 * (gi_camera_parse's keys and checks, plus the frame). */
static int parse_camera_key(gi_anim *a, int i, const cJSON *obj, gi_jv *v)
{
    char kpath[64], path[96];
    snprintf(kpath, sizeof kpath, "%s.camera", a->path);
    gi_json_index_path(path, sizeof path, kpath, i);
    static const char *const keys[] = {"frame", "position", "look_at", "up", "fov_y", NULL};
    if (gi_jv_object(v, obj, path) || gi_jv_keys(v, obj, path, keys) ||
        parse_key_frame(a, obj, path, "camera", i, i > 0 ? a->cameras[i - 1].frame : 0,
                        &a->cameras[i].frame, v))
        return -1;
    cJSON *rest = cJSON_Duplicate(obj, 1);
    cJSON_DeleteItemFromObjectCaseSensitive(rest, "frame");
    int rc = gi_camera_parse(v, rest, path, &a->cameras[i].camera);
    cJSON_Delete(rest);
    return rc;
}

/* A key list's length at `path`: 1 to GI_ANIM_MAX_KEYS. */
static int check_key_count(const char *path, int n, gi_jv *v)
{
    if (n < 1)
        return gi_jv_fail(v, path, "at least one key is needed");
    if (n > GI_ANIM_MAX_KEYS)
        return gi_jv_fail(v, path, "%d keys (at most %d)", n, GI_ANIM_MAX_KEYS);
    return 0;
}

/* The camera path, and every frame's camera along it a camera: its
 * position off its look_at point, its up off the view direction. */
static int parse_cameras(gi_anim *a, const cJSON *arr, gi_jv *v)
{
    char cpath[GI_ANIM_PATH_MAX + 16];
    snprintf(cpath, sizeof cpath, "%s.camera", a->path);
    if (check_key_count(cpath, cJSON_GetArraySize(arr), v))
        return -1;
    int i = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, arr)
    {
        if (parse_camera_key(a, i, it, v))
            return -1;
        a->camera_count = (uint32_t)++i;
    }
    for (uint32_t f = 0; f < a->frames; f++) {
        gi_camera c;
        gi_anim_camera(a, &c, f, &c);
        gi_vec3 dir = gi_sub(c.look_at, c.position);
        if (!(gi_length(dir) > 0.0f) ||
            !(gi_length(gi_cross(gi_normalize(dir), gi_normalize(c.up))) >= 1e-6f))
            return gi_jv_fail(v, cpath,
                              "at frame %u, between keys, the position meets the look_at point "
                              "or the up vector lies along the view: add a key in between",
                              f);
    }
    return 0;
}

int gi_anim_parse(gi_anim *a, const cJSON *b, const char *path, const char *const *extra_keys,
                  int flags, gi_jv *v)
{
    memset(a, 0, sizeof *a);
    snprintf(a->path, sizeof a->path, "%s", path);
    if (!b)
        return 0;
    const char *keys[16] = {"object", "frames", "keyframes"};
    size_t nk = 3;
    if (flags & GI_ANIM_CAMERA)
        keys[nk++] = "camera";
    for (size_t i = 0; extra_keys && extra_keys[i] && nk + 1 < sizeof keys / sizeof *keys; i++)
        keys[nk++] = extra_keys[i];
    keys[nk] = NULL;
    const char *object = NULL;
    int64_t frames = 0;
    const cJSON *arr = NULL, *cams = NULL;
    char opath[GI_ANIM_PATH_MAX + 16], kpath[GI_ANIM_PATH_MAX + 16];
    snprintf(opath, sizeof opath, "%s.object", a->path);
    snprintf(kpath, sizeof kpath, "%s.keyframes", a->path);
    /* The object is optional only beside a camera path. */
    int camera = flags & GI_ANIM_CAMERA;
    if (gi_jv_object(v, b, a->path) || gi_jv_keys(v, b, a->path, keys) ||
        (camera && gi_jv_member_array(v, b, a->path, "camera", 0, &cams)) ||
        gi_jv_string(v, b, a->path, "object", !cams, &object) ||
        gi_jv_int(v, b, a->path, "frames", 1, 1, GI_ANIM_MAX_FRAMES, &frames))
        return -1;
    a->frames = (uint32_t)frames;
    if (cams && parse_cameras(a, cams, v))
        return -1;
    if (!object) {
        if (cJSON_GetObjectItemCaseSensitive(b, "keyframes"))
            return gi_jv_fail(v, kpath, "keys for no object: give %s.object too", a->path);
        a->enabled = 1;
        return 0;
    }
    if (!object[0])
        return gi_jv_fail(v, opath, "the object name is empty");
    if (strlen(object) >= GI_ANIM_NAME_MAX)
        return gi_jv_fail(v, opath, "the name is longer than %d bytes", GI_ANIM_NAME_MAX - 1);
    if (gi_jv_member_array(v, b, a->path, "keyframes", 1, &arr))
        return -1;
    strcpy(a->object, object);
    int n = cJSON_GetArraySize(arr);
    if (check_key_count(kpath, n, v))
        return -1;
    int i = 0;
    const cJSON *it;
    double prev[4] = {1.0, 0.0, 0.0, 0.0}, cur[4];
    cJSON_ArrayForEach(it, arr)
    {
        if (parse_key(a, i, it, cur, v) || (i > 0 && check_turn(a, prev, cur, i, v)))
            return -1;
        memcpy(prev, cur, sizeof prev);
        i++;
    }
    a->key_count = (uint32_t)n;
    a->enabled = 1;
    return 0;
}

int gi_anim_resolve(gi_anim *a, const gi_scene *s, const char *file, gi_error *err)
{
    if (!gi_anim_moves_object(a))
        return 0;
    int idx = gi_scene_find_object(s, a->object);
    if (idx < 0)
        return gi_fail(err, GI_EINVAL, "%s: %s.object: no object \"%s\" in the scene", file,
                       a->path, a->object);
    const gi_object *o = &s->objects[idx];
    if (!o->mobile)
        return gi_fail(err, GI_EINVAL,
                       "%s: %s.object: object \"%s\" is not mobile (give it "
                       "\"mobile\": true in the scene)",
                       file, a->path, a->object);
    for (uint32_t t = o->first_triangle; t < o->first_triangle + o->triangle_count; t++)
        if (!gi_is_black(gi_scene_tri_material(s, t)->emission))
            return gi_fail(err, GI_EINVAL,
                           "%s: %s.object: object \"%s\" is emissive (moving "
                           "lights are not supported)",
                           file, a->path, a->object);
    gi_vec3 lo = s->positions[o->first_vertex], hi = lo;
    for (uint32_t i = 1; i < o->vertex_count; i++) {
        lo = gi_min_v3(lo, s->positions[o->first_vertex + i]);
        hi = gi_max_v3(hi, s->positions[o->first_vertex + i]);
    }
    a->object_index = (uint32_t)idx;
    a->pivot[0] = 0.5 * ((double)lo.x + (double)hi.x);
    a->pivot[1] = 0.5 * ((double)lo.y + (double)hi.y);
    a->pivot[2] = 0.5 * ((double)lo.z + (double)hi.z);
    return 0;
}

gi_mat4 gi_anim_matrix(const double pivot[3], const double translate[3], const double q[4],
                       double scale)
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double r[3][3] = {
        {1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)},
        {2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)},
        {2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)},
    };
    gi_mat4 m = gi_mat4_identity();
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            m.m[i][j] = scale * r[i][j];
        /* p' = M3 p + (pivot + translate - M3 pivot); the identity pose
         * gives pivot - pivot = 0 exactly. */
        double mp = m.m[i][0] * pivot[0] + m.m[i][1] * pivot[1] + m.m[i][2] * pivot[2];
        m.m[i][3] = (pivot[i] + translate[i]) - mp;
    }
    return m;
}

/* Spherical linear interpolation of unit quaternions, the short way (q and
 * -q are the same rotation). Nearly parallel keys use the normalized lerp,
 * where slerp's 1/sin(theta) loses precision. */
static void slerp(const double a[4], const double b[4], double t, double out[4])
{
    if (memcmp(a, b, 4 * sizeof *a) == 0) {
        /* Equal keys (e.g. a translation only): keep the rotation exact. */
        memcpy(out, a, 4 * sizeof *a);
        return;
    }
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    double sb = 1.0;
    if (d < 0.0) {
        d = -d;
        sb = -1.0;
    }
    double wa = 1.0 - t, wb = t;
    if (d < 0.9995) {
        double th = acos(d), s = sin(th);
        wa = sin((1.0 - t) * th) / s;
        wb = sin(t * th) / s;
    }
    double n2 = 0.0;
    for (int i = 0; i < 4; i++) {
        out[i] = wa * a[i] + wb * sb * b[i];
        n2 += out[i] * out[i];
    }
    double inv = 1.0 / sqrt(n2);
    for (int i = 0; i < 4; i++)
        out[i] *= inv;
}

/* (1 - t) a + t b, not a + t (b - a): exact at both ends; and a itself
 * when a == b, so that a pose held between equal keys is the very same
 * pose (a frame that does not move changes nothing, gi_anim_still). */
static double mix(double a, double b, double t)
{
    return a == b ? a : (1.0 - t) * a + t * b;
}

static uint32_t key_frame(const void *keys, size_t stride, uint32_t i)
{
    uint32_t f;
    memcpy(&f, (const char *)keys + (size_t)i * stride, sizeof f);
    return f;
}

/* Where `frame` falls among n >= 1 keys (each holding its frame first,
 * `stride` bytes apart, frames strictly increasing): 1 with *lo the key
 * that holds it (at or before the first key, at a key, at or after the
 * last); 0 with key *lo's frame < frame < key *lo + 1's and *t the
 * fraction of the way. */
static int key_find(const void *keys, size_t stride, uint32_t n, uint32_t frame, uint32_t *lo,
                    double *t)
{
    if (frame <= key_frame(keys, stride, 0)) {
        *lo = 0;
        return 1;
    }
    uint32_t l = 0, h = n - 1;
    if (frame >= key_frame(keys, stride, h)) {
        *lo = h;
        return 1;
    }
    while (h - l > 1) { /* key l's frame <= frame < key h's */
        uint32_t mid = l + (h - l) / 2;
        if (key_frame(keys, stride, mid) <= frame)
            l = mid;
        else
            h = mid;
    }
    *lo = l;
    uint32_t f0 = key_frame(keys, stride, l), f1 = key_frame(keys, stride, h);
    *t = (double)(frame - f0) / (double)(f1 - f0);
    return f0 == frame;
}

static gi_mat4 key_matrix(const gi_anim *a, const gi_anim_key *k)
{
    return gi_anim_matrix(a->pivot, k->translate, k->rotation, k->scale);
}

void gi_anim_pose(const gi_anim *a, uint32_t frame, gi_mat4 *out)
{
    if (!a->enabled || a->key_count == 0) {
        *out = gi_mat4_identity();
        return;
    }
    const gi_anim_key *k = a->keys;
    uint32_t lo;
    double t;
    if (key_find(k, sizeof *k, a->key_count, frame, &lo, &t)) {
        *out = key_matrix(a, &k[lo]);
        return;
    }
    const gi_anim_key *k0 = &k[lo], *k1 = &k[lo + 1];
    double tr[3], q[4];
    for (int i = 0; i < 3; i++)
        tr[i] = mix(k0->translate[i], k1->translate[i], t);
    double s = mix(k0->scale, k1->scale, t);
    slerp(k0->rotation, k1->rotation, t, q);
    *out = gi_anim_matrix(a->pivot, tr, q, s);
}

int gi_anim_still(const gi_anim *a, uint32_t frame)
{
    if (frame == 0)
        return 0;
    gi_mat4 before, now;
    gi_anim_pose(a, frame - 1, &before);
    gi_anim_pose(a, frame, &now);
    gi_camera cb, cn, base;
    memset(&base, 0, sizeof base);
    gi_anim_camera(a, &base, frame - 1, &cb);
    gi_anim_camera(a, &base, frame, &cn);
    return memcmp(&before, &now, sizeof now) == 0 &&
           memcmp(&cb.position, &cn.position, sizeof cn.position) == 0 &&
           memcmp(&cb.look_at, &cn.look_at, sizeof cn.look_at) == 0 &&
           memcmp(&cb.up, &cn.up, sizeof cn.up) == 0 && cb.fov_y_deg == cn.fov_y_deg;
}

static float mixf(float a, float b, double t)
{
    return a == b ? a : (float)((1.0 - t) * (double)a + t * (double)b);
}

static gi_vec3 mix3(gi_vec3 a, gi_vec3 b, double t)
{
    return gi_v3(mixf(a.x, b.x, t), mixf(a.y, b.y, t), mixf(a.z, b.z, t));
}

void gi_anim_camera(const gi_anim *a, const gi_camera *base, uint32_t frame, gi_camera *out)
{
    const gi_anim_camera_key *k = a->cameras;
    uint32_t lo;
    double t;
    if (a->camera_count == 0) {
        *out = *base;
        return;
    }
    if (key_find(k, sizeof *k, a->camera_count, frame, &lo, &t)) {
        *out = k[lo].camera;
        return;
    }
    const gi_camera *c0 = &k[lo].camera, *c1 = &k[lo + 1].camera;
    out->position = mix3(c0->position, c1->position, t);
    out->look_at = mix3(c0->look_at, c1->look_at, t);
    out->up = mix3(c0->up, c1->up, t);
    out->fov_y_deg = mixf(c0->fov_y_deg, c1->fov_y_deg, t);
}

void gi_anim_warn_keys(const gi_anim *a, const gi_scene *s, const char *file)
{
    if (!gi_anim_moves_object(a))
        return;
    const gi_object *mob = &s->objects[a->object_index];
    gi_vec3 lo = s->positions[mob->first_vertex], hi = lo;
    gi_vec3 slo = {INFINITY, INFINITY, INFINITY}, shi = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *ob = &s->objects[o];
        for (uint32_t i = ob->first_vertex; i < ob->first_vertex + ob->vertex_count; i++) {
            gi_vec3 *l = o == a->object_index ? &lo : &slo, *h = o == a->object_index ? &hi : &shi;
            *l = gi_min_v3(*l, s->positions[i]);
            *h = gi_max_v3(*h, s->positions[i]);
        }
    }
    if (!(slo.x <= shi.x))
        return; /* nothing else in the scene */
    for (uint32_t k = 0; k < a->key_count; k++) {
        gi_mat4 m = key_matrix(a, &a->keys[k]);
        gi_vec3 plo = {INFINITY, INFINITY, INFINITY}, phi = {-INFINITY, -INFINITY, -INFINITY};
        for (int c = 0; c < 8; c++) {
            gi_vec3 corner = {c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
            gi_vec3 p = gi_mat4_point(&m, corner);
            plo = gi_min_v3(plo, p);
            phi = gi_max_v3(phi, p);
        }
        if (phi.x < slo.x || plo.x > shi.x || phi.y < slo.y || plo.y > shi.y || phi.z < slo.z ||
            plo.z > shi.z) {
            gi_warn("%s: %s.keyframes[%u]: at frame %u the mobile lies wholly "
                    "outside the box of the scene's other objects ([%g, %g, %g] to [%g, %g, %g])",
                    file, a->path, k, a->keys[k].frame, slo.x, slo.y, slo.z, shi.x, shi.y, shi.z);
            return; /* one is enough to look at the keys again */
        }
    }
}

int gi_anim_check_scene(gi_anim *a, gi_job *job, gi_error *err)
{
    if (gi_anim_resolve(a, &job->scene, job->file, err))
        return -1;
    if (a->enabled)
        job->frame_count = a->frames; /* gi validate says how many */
    if (!job->on_worker)
        gi_anim_warn_keys(a, &job->scene, job->file);
    return 0;
}

void gi_anim_set_frame(const gi_anim *a, gi_job *job, uint32_t frame)
{
    if (!a->enabled)
        return;
    job->in_frame = 1;
    job->frame = frame;
    job->frame_count = a->frames;
}

int gi_anim_write_frames(const gi_anim *a, gi_job *job, uint32_t *frame,
                         int (*write)(gi_job *job, void *ctx, gi_error *err), void *ctx,
                         gi_error *err)
{
    for (;;) {
        gi_anim_set_frame(a, job, *frame);
        if (write(job, ctx, err))
            return -1;
        if (!a->enabled || *frame + 1 >= a->frames) {
            job->in_frame = 0;
            return 0;
        }
        ++*frame;
        if (!gi_anim_still(a, *frame)) {
            gi_anim_set_frame(a, job, *frame);
            return 1;
        }
    }
}

cJSON *gi_anim_pose_json(const gi_anim *a, uint32_t frame)
{
    gi_mat4 m;
    gi_anim_pose(a, frame, &m);
    cJSON *pose = cJSON_CreateArray();
    for (int r = 0; r < 3; r++)
        cJSON_AddItemToArray(pose, cJSON_CreateDoubleArray(m.m[r], 4));
    return pose;
}

void gi_anim_report_camera(const gi_anim *a, const gi_camera *base, uint32_t frame, cJSON *o)
{
    if (!a->camera_count)
        return;
    gi_camera c;
    gi_anim_camera(a, base, frame, &c);
    cJSON *cam = cJSON_AddObjectToObject(o, "camera");
    float v[3][3] = {{c.position.x, c.position.y, c.position.z},
                     {c.look_at.x, c.look_at.y, c.look_at.z},
                     {c.up.x, c.up.y, c.up.z}};
    static const char *const vecs[] = {"position", "look_at", "up"};
    for (int i = 0; i < 3; i++)
        cJSON_AddItemToObject(cam, vecs[i], cJSON_CreateFloatArray(v[i], 3));
    cJSON_AddNumberToObject(cam, "fov_y", c.fov_y_deg);
}
