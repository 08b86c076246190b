/* Unit tests: the detp.animation block (parse, refusals, resolve), the
 * per-frame pose (keys, interpolation, hold) and gi_scene_pose_object; the
 * detp block's lengths. */
#include <stdlib.h>
#include <string.h>

#include "detp/detp_params.h"
#include "gi_test.h"
#include "test_helpers.h"

/* Parses {"detp": <detp>} as job.json's detp block into *p. */
static int parse_detp(const char *detp, gi_detp_params *p, gi_error *err)
{
    char text[4096];
    snprintf(text, sizeof text, "{\"detp\": %s}", detp);
    cJSON *root;
    if (gi_json_parse(text, strlen(text), "job.json", &root, err))
        return -1;
    gi_jv v = {"job.json", err};
    int rc = gi_detp_parse_params(p, cJSON_GetObjectItemCaseSensitive(root, "detp"), &v);
    cJSON_Delete(root);
    return rc;
}

/* Lengths: units, a percentage of the scene's size, "auto"; a percentage
 * out of range says so, and "0%" is no subdivision, like 0. */
GI_TEST(test_detp_lengths)
{
    gi_detp_params *p = gi_xcalloc(1, sizeof *p);
    gi_error err;
    GI_REQUIRE_OK(parse_detp("{\"radius\": \"2.5%\", \"subdivide\": \"0%\"}", p, &err));
    GI_CHECK(p->radius.kind == GI_DETP_LEN_PERCENT && p->radius.value == 2.5);
    GI_CHECK(p->subdivide.kind == GI_DETP_LEN_UNITS && p->subdivide.value == 0);
    GI_CHECK(parse_detp("{\"radius\": \"200%\"}", p, &err) != 0);
    GI_CHECK_MSG(strstr(err.msg, "detp.radius: \"200%\" is out of range: a percentage of the "
                                 "scene size is in (0%, 100%]") != NULL, "%s", err.msg);
    GI_CHECK(parse_detp("{\"radius\": \"0%\"}", p, &err) != 0);
    GI_CHECK(strstr(err.msg, "is out of range") && !strstr(err.msg, "0 for none"));
    GI_CHECK(parse_detp("{\"subdivide\": \"-1%\"}", p, &err) != 0);
    GI_CHECK(strstr(err.msg, "(0%, 100%], or 0 for none") != NULL);
    GI_CHECK(parse_detp("{\"radius\": \"2 percent\"}", p, &err) != 0);
    GI_CHECK(strstr(err.msg, "expected a length in scene units") != NULL);
    free(p);
}

#define ANIM(body) "{\"animation\": {\"object\": \"ball\", \"frames\": 24, " body "}}"

GI_TEST(test_detp_anim_parse_good)
{
    gi_error err;
    gi_detp_params *p = gi_xcalloc(1, sizeof *p);
    GI_REQUIRE_OK(parse_detp("{\"photons\": 1000}", p, &err));
    GI_CHECK(!p->anim.enabled);
    GI_CHECK(p->anim.key_count == 0);

    GI_REQUIRE_OK(parse_detp(
        ANIM("\"keyframes\": [{\"frame\": 0},"
             " {\"frame\": 23, \"translate\": [100, 0, -5],"
             "  \"rotate\": {\"axis\": [0, 2, 0], \"degrees\": 90}, \"scale\": 1.5}],"
             " \"mobile_estimator\": \"embree\""),
        p, &err));
    GI_CHECK(p->anim.enabled);
    GI_CHECK(strcmp(p->anim.object, "ball") == 0);
    GI_CHECK(p->anim.frames == 24);
    GI_CHECK(p->mobile_estimator == GI_DETP_MOBILE_EMBREE);
    GI_REQUIRE(p->anim.key_count == 2);
    const gi_anim_key *k0 = &p->anim.keys[0], *k1 = &p->anim.keys[1];
    GI_CHECK(k0->frame == 0 && k1->frame == 23);
    GI_CHECK(k0->translate[0] == 0.0 && k0->scale == 1.0);
    GI_CHECK(k0->rotation[0] == 1.0 && k0->rotation[1] == 0.0 && k0->rotation[2] == 0.0 &&
             k0->rotation[3] == 0.0);
    GI_CHECK(k1->translate[0] == 100.0 && k1->translate[2] == -5.0);
    GI_CHECK(k1->scale == 1.5);
    /* 90 degrees about +y (the axis is normalized): (cos 45, 0, sin 45, 0). */
    GI_CHECK_NEAR(k1->rotation[0], sqrt(0.5), 1e-15);
    GI_CHECK_NEAR(k1->rotation[1], 0.0, 1e-15);
    GI_CHECK_NEAR(k1->rotation[2], sqrt(0.5), 1e-15);
    GI_CHECK_NEAR(k1->rotation[3], 0.0, 1e-15);

    /* The default mobile estimator, and a single key. */
    GI_REQUIRE_OK(parse_detp(ANIM("\"keyframes\": [{\"frame\": 5}]"), p, &err));
    GI_CHECK(p->mobile_estimator == GI_DETP_MOBILE_LANES);
    GI_CHECK(p->anim.key_count == 1);
    GI_REQUIRE_OK(parse_detp(
        ANIM("\"keyframes\": [{\"frame\": 0}], \"mobile_estimator\": \"sphere_cache\""), p,
        &err));
    GI_CHECK(p->mobile_estimator == GI_DETP_MOBILE_SPHERE_CACHE);
    free(p);
}

GI_TEST(test_detp_anim_parse_bad)
{
    static const struct {
        const char *detp, *expect;
    } cases[] = {
        {ANIM("\"keyframes\": [{\"frame\": 0}], \"fps\": 24"),
         "job.json: detp.animation.fps: unknown key"},
        {"{\"animation\": {\"frames\": 24, \"keyframes\": [{\"frame\": 0}]}}",
         "detp.animation.object: missing (required)"},
        {"{\"animation\": {\"object\": \"\", \"frames\": 24, \"keyframes\": [{\"frame\": 0}]}}",
         "detp.animation.object: the object name is empty"},
        {"{\"animation\": {\"object\": \"ball\", \"frames\": 0, \"keyframes\": [{\"frame\": 0}]}}",
         "detp.animation.frames: 0 is out of range"},
        {"{\"animation\": {\"object\": \"ball\", \"frames\": 100001, \"keyframes\": []}}",
         "detp.animation.frames: 100001 is out of range"},
        {"{\"animation\": {\"object\": \"ball\", \"keyframes\": [{\"frame\": 0}]}}",
         "detp.animation.frames: missing (required)"},
        {ANIM("\"keyframes\": []"), "detp.animation.keyframes: at least one key"},
        {ANIM("\"keyframes\": {}"), "detp.animation.keyframes: expected an array"},
        {ANIM("\"keyframes\": [3]"), "detp.animation.keyframes[0]: expected an object"},
        {ANIM("\"keyframes\": [{\"translate\": [0, 0, 0]}]"),
         "detp.animation.keyframes[0].frame: missing (required)"},
        {ANIM("\"keyframes\": [{\"frame\": 0}, {\"frame\": 5}, {\"frame\": 5}]"),
         "detp.animation.keyframes[2].frame: 5 is not after keyframes[1].frame (5)"},
        {ANIM("\"keyframes\": [{\"frame\": 7}, {\"frame\": 3}]"),
         "detp.animation.keyframes[1].frame: 3 is not after"},
        {ANIM("\"keyframes\": [{\"frame\": 0}, {\"frame\": 24}]"),
         "detp.animation.keyframes[1].frame: 24 is not less than detp.animation.frames (24)"},
        {ANIM("\"keyframes\": [{\"frame\": -1}]"), "keyframes[0].frame: -1 is out of range"},
        {ANIM("\"keyframes\": [{\"frame\": 1.5}]"), "keyframes[0].frame: expected an integer"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 0, 0], \"degrees\": 9}}]"),
         "detp.animation.keyframes[0].rotate.axis: the axis is zero"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 1e200, 1e200],"
              " \"degrees\": 9}}]"),
         "keyframes[0].rotate.axis[1]: 1e+200 is out of range"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 1, 0]}}]"),
         "keyframes[0].rotate.degrees: missing (required)"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 1, 0], \"degrees\": 400}}]"),
         "keyframes[0].rotate.degrees: 400 is out of range"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 1], \"degrees\": 4}}]"),
         "keyframes[0].rotate.axis: expected an array of 3 numbers"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 1, 0], \"degrees\": 4,"
              " \"angle\": 1}}]"),
         "keyframes[0].rotate.angle: unknown key"},
        {ANIM("\"keyframes\": [{\"frame\": 0}, {\"frame\": 1, \"scale\": 0}]"),
         "detp.animation.keyframes[1].scale: 0 is not > 0"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"scale\": -2}]"),
         "detp.animation.keyframes[0].scale: -2 is not > 0"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"scale\": [1, 2, 1]}]"),
         "keyframes[0].scale: expected a number"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"translate\": [0, \"x\", 0]}]"),
         "keyframes[0].translate"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"pivot\": [0, 0, 0]}]"),
         "detp.animation.keyframes[0].pivot: unknown key"},
        {ANIM("\"keyframes\": [{\"frame\": 0}], \"mobile_estimator\": \"octree\""),
         "detp.animation.mobile_estimator: \"octree\" is not one of"},
        {"{\"animation\": 3}", "detp.animation: expected an object"},
        /* Rotations as written more than 180 degrees apart: the pose would
         * turn the short way, not as written. */
        {ANIM("\"keyframes\": [{\"frame\": 0}, {\"frame\": 2, \"rotate\": {\"axis\": [0, 1, 0],"
              " \"degrees\": 270}}]"),
         "detp.animation.keyframes[1].rotate: 270.0 degrees from keyframes[0]'s rotation as "
         "written: the pose turns the short way between keys, so it would turn 90.0 degrees"},
        {ANIM("\"keyframes\": [{\"frame\": 0, \"rotate\": {\"axis\": [0, 0, 1], \"degrees\": -10}},"
              " {\"frame\": 5, \"rotate\": {\"axis\": [0, 0, 1], \"degrees\": 350}}]"),
         "keyframes[1].rotate: 360.0 degrees from keyframes[0]'s"},
        {ANIM("\"keyframes\": [{\"frame\": 0}, {\"frame\": 1, \"rotate\": {\"axis\": [0, 1, 0],"
              " \"degrees\": 90}}, {\"frame\": 2, \"rotate\": {\"axis\": [0, -1, 0], \"degrees\": 100}}]"),
         "keyframes[2].rotate: 190.0 degrees from keyframes[1]'s"},
        /* Combinations the incremental update refuses. */
        {"{\"estimator\": \"photon_map\", \"animation\": {\"object\": \"ball\", \"frames\": 2,"
         " \"keyframes\": [{\"frame\": 0}]}}",
         "detp.estimator: \"photon_map\" cannot be used with detp.animation"},
        {"{\"estimator\": \"impact_count\", \"animation\": {\"object\": \"ball\", \"frames\": 2,"
         " \"keyframes\": [{\"frame\": 0}]}}",
         "detp.estimator: \"impact_count\" cannot be used with detp.animation"},
        {"{\"artifact_control\": \"visible_area\", \"animation\": {\"object\": \"ball\","
         " \"frames\": 2, \"keyframes\": [{\"frame\": 0}]}}",
         "detp.artifact_control: \"visible_area\" cannot be used with detp.animation"},
        {"{\"reference\": {\"spp\": 4}, \"animation\": {\"object\": \"ball\", \"frames\": 2,"
         " \"keyframes\": [{\"frame\": 0}]}}",
         "detp.reference: the path-traced reference cannot be used with detp.animation"},
    };
    gi_detp_params *p = gi_xcalloc(1, sizeof *p);
    for (size_t i = 0; i < GI_ARRAY_LEN(cases); i++) {
        gi_error err;
        gi_error_clear(&err);
        int rc = parse_detp(cases[i].detp, p, &err);
        GI_CHECK_MSG(rc != 0, "case %zu accepted: %s", i, cases[i].detp);
        GI_CHECK_MSG(err.code == GI_EINVAL, "case %zu: code %d", i, err.code);
        GI_CHECK_MSG(strstr(err.msg, cases[i].expect) != NULL,
                     "case %zu: \"%s\" does not say \"%s\"", i, err.msg, cases[i].expect);
        GI_CHECK_MSG(!strchr(err.msg, '\n'), "case %zu: message is not one line", i);
    }
    free(p);
}

/* pivot + t + R (s (p - pivot)), composed from gi_math's own builders. */
static gi_mat4 expected_pose(const double pivot[3], double tx, double ty, double tz,
                             double ax, double ay, double az, double deg, double s)
{
    gi_mat4 m = gi_mat4_translate(-pivot[0], -pivot[1], -pivot[2]);
    m = gi_mat4_mul(gi_mat4_scale(s, s, s), m);
    m = gi_mat4_mul(gi_mat4_rotate(ax, ay, az, deg), m);
    return gi_mat4_mul(gi_mat4_translate(pivot[0] + tx, pivot[1] + ty, pivot[2] + tz), m);
}

static double mat_diff(const gi_mat4 *a, const gi_mat4 *b)
{
    double d = 0.0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            d = fmax(d, fabs(a->m[i][j] - b->m[i][j]));
    return d;
}

GI_TEST(test_detp_anim_pose_keys_interpolation_and_hold)
{
    gi_error err;
    gi_detp_params *p = gi_xcalloc(1, sizeof *p);
    GI_REQUIRE_OK(parse_detp(
        "{\"animation\": {\"object\": \"ball\", \"frames\": 30, \"keyframes\": ["
        " {\"frame\": 4, \"translate\": [10, 0, 0]},"
        " {\"frame\": 14, \"translate\": [30, 4, -2], \"scale\": 2,"
        "  \"rotate\": {\"axis\": [0, 1, 0], \"degrees\": 90}},"
        " {\"frame\": 20, \"rotate\": {\"axis\": [0, 1, 0], \"degrees\": 170}},"
        " {\"frame\": 24, \"rotate\": {\"axis\": [0, 3, 0], \"degrees\": 190}}]}}",
        p, &err));
    gi_anim *a = &p->anim;
    a->pivot[0] = 100.0, a->pivot[1] = 50.0, a->pivot[2] = -20.0;
    gi_mat4 m, want;

    /* At the keys: the keys' poses. */
    gi_anim_pose(a, 4, &m);
    want = expected_pose(a->pivot, 10, 0, 0, 0, 1, 0, 0, 1);
    GI_CHECK_NEAR(mat_diff(&m, &want), 0.0, 1e-12);
    gi_anim_pose(a, 14, &m);
    want = expected_pose(a->pivot, 30, 4, -2, 0, 1, 0, 90, 2);
    GI_CHECK_NEAR(mat_diff(&m, &want), 0.0, 1e-12);
    /* The pivot stays where the key's translate puts it. */
    gi_vec3 c = gi_mat4_point(&m, gi_v3(100.0f, 50.0f, -20.0f));
    GI_CHECK_NEAR(c.x, 130.0, 1e-4);
    GI_CHECK_NEAR(c.y, 54.0, 1e-4);
    GI_CHECK_NEAR(c.z, -22.0, 1e-4);

    /* Halfway between frames 4 and 14 (frame 9): translate (20, 2, -1),
     * scale 1.5, and the slerp of 0 and 90 degrees is 45 degrees. */
    gi_anim_pose(a, 9, &m);
    want = expected_pose(a->pivot, 20, 2, -1, 0, 1, 0, 45, 1.5);
    GI_CHECK_NEAR(mat_diff(&m, &want), 0.0, 1e-12);
    /* By hand: x' = pivot + t + 1.5 R45 (p - pivot) for p - pivot = (1, 0, 0):
     * R_y(45) (1, 0, 0) = (cos 45, 0, -sin 45). */
    gi_vec3 q = gi_mat4_point(&m, gi_v3(101.0f, 50.0f, -20.0f));
    GI_CHECK_NEAR(q.x, 120.0 + 1.5 * sqrt(0.5), 1e-4);
    GI_CHECK_NEAR(q.y, 52.0, 1e-4);
    GI_CHECK_NEAR(q.z, -21.0 - 1.5 * sqrt(0.5), 1e-4);
    /* A quarter of the way (not a key): frame 6.5 does not exist, frame 6
     * is t = 0.2: 18 degrees. */
    gi_anim_pose(a, 6, &m);
    want = expected_pose(a->pivot, 14, 0.8, -0.4, 0, 1, 0, 18, 1.2);
    GI_CHECK_NEAR(mat_diff(&m, &want), 0.0, 1e-12);

    /* 170 degrees to 190 (-170) about y: through 180, not back through 0
     * (written as 170 about -y, the keys would be 340 degrees apart as
     * written: refused, see test_detp_anim_parse_bad). */
    gi_anim_pose(a, 22, &m);
    want = expected_pose(a->pivot, 0, 0, 0, 0, 1, 0, 180, 1);
    GI_CHECK_NEAR(mat_diff(&m, &want), 0.0, 1e-12);

    /* Hold before the first key and after the last. */
    gi_mat4 first, last;
    gi_anim_pose(a, 4, &first);
    gi_anim_pose(a, 24, &last);
    gi_anim_pose(a, 0, &m);
    GI_CHECK(memcmp(&m, &first, sizeof m) == 0);
    gi_anim_pose(a, 3, &m);
    GI_CHECK(memcmp(&m, &first, sizeof m) == 0);
    gi_anim_pose(a, 29, &m);
    GI_CHECK(memcmp(&m, &last, sizeof m) == 0);
    want = expected_pose(a->pivot, 0, 0, 0, 0, 1, 0, -170, 1);
    GI_CHECK_NEAR(mat_diff(&m, &want), 0.0, 1e-12);

    /* Between keys with the same rotation, only the translation moves: the
     * 3x3 part stays exactly the identity. */
    GI_REQUIRE_OK(parse_detp(ANIM("\"keyframes\": [{\"frame\": 0},"
                                  " {\"frame\": 7, \"translate\": [7, -3.5, 1]}]"),
                             p, &err));
    a->pivot[0] = 3.25, a->pivot[1] = -1.0, a->pivot[2] = 0.5;
    gi_anim_pose(a, 3, &m);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            GI_CHECK(m.m[i][j] == (i == j ? 1.0 : 0.0));
    GI_CHECK_NEAR(m.m[0][3], 3.0, 1e-12);
    GI_CHECK_NEAR(m.m[1][3], -1.5, 1e-12);
    GI_CHECK_NEAR(m.m[2][3], 3.0 / 7.0, 1e-12);

    /* A default key is exactly the identity, whatever the pivot. */
    GI_REQUIRE_OK(parse_detp(ANIM("\"keyframes\": [{\"frame\": 3}, {\"frame\": 9,"
                                  " \"rotate\": {\"axis\": [1, 1, 0], \"degrees\": 0}}]"),
                             p, &err));
    a->pivot[0] = 278.25, a->pivot[1] = 0.1, a->pivot[2] = -1e-3;
    gi_mat4 id = gi_mat4_identity();
    for (uint32_t f = 0; f < 24; f++) {
        gi_anim_pose(a, f, &m);
        GI_CHECK_MSG(memcmp(&m, &id, sizeof m) == 0, "frame %u is not the identity", f);
    }

    /* Still frames: held before the first key, between equal keys (the
     * translation mixed exactly) and after the last; moving between them. */
    GI_REQUIRE_OK(parse_detp(ANIM("\"keyframes\": [{\"frame\": 2, \"translate\": [0.1, 0.2, 0.3]},"
                                  " {\"frame\": 9, \"translate\": [0.1, 0.2, 0.3], \"scale\": 1.1},"
                                  " {\"frame\": 12, \"translate\": [0.1, 0.2, 0.3], \"scale\": 1.1},"
                                  " {\"frame\": 15, \"translate\": [0.7, 0.2, 0.3], \"scale\": 1.1}]"),
                             p, &err));
    a->pivot[0] = 1.0 / 3.0, a->pivot[1] = 0.7, a->pivot[2] = -0.1;
    for (uint32_t f = 1; f < 24; f++) {
        int want_still = f <= 2 || (f > 9 && f <= 12) || f > 15;
        GI_CHECK_MSG(gi_anim_still(a, f) == want_still, "frame %u: still %d", f,
                     gi_anim_still(a, f));
    }
    GI_CHECK(!gi_anim_still(a, 0));
    free(p);
}

static const char *pose_scene =
    "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]}, \"l\": {\"emission\": [1, 1, 1]}},"
    " \"objects\": ["
    "  {\"name\": \"floor\", \"material\": \"w\", \"quad\": {\"size\": [4, 4]}},"
    "  {\"name\": \"box\", \"material\": \"w\", \"mobile\": true, \"box\": {\"size\": [1, 2, 1]},"
    "   \"transform\": [{\"translate\": [0.5, 1, -0.25]}]},"
    "  {\"name\": \"ball\", \"material\": \"w\", \"mobile\": true,"
    "   \"sphere\": {\"radius\": 0.3, \"subdivisions\": 1},"
    "   \"transform\": [{\"translate\": [-1, 0.3, 0]}]},"
    "  {\"name\": \"lamp\", \"material\": \"l\", \"mobile\": true, \"quad\": {\"size\": [1, 1]},"
    "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
    "                   {\"translate\": [0, 3, 0]}]}]}";

GI_TEST(test_detp_anim_resolve_against_the_scene)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_text("pose.json", pose_scene, &s, &err));
    gi_detp_params *p = gi_xcalloc(1, sizeof *p);
    GI_REQUIRE_OK(parse_detp(ANIM("\"keyframes\": [{\"frame\": 0}]"), p, &err));
    GI_REQUIRE_OK(gi_anim_resolve(&p->anim, &s, "job.json", &err));
    GI_CHECK(p->anim.object_index == (uint32_t)gi_scene_find_object(&s, "ball"));
    GI_CHECK_NEAR(p->anim.pivot[0], -1.0, 1e-6);
    GI_CHECK_NEAR(p->anim.pivot[1], 0.3, 1e-6);
    GI_CHECK_NEAR(p->anim.pivot[2], 0.0, 1e-6);

    strcpy(p->anim.object, "cube");
    GI_CHECK(gi_anim_resolve(&p->anim, &s, "job.json", &err) != 0);
    GI_CHECK(strstr(err.msg, "job.json: detp.animation.object: no object \"cube\"") != NULL);
    strcpy(p->anim.object, "floor");
    GI_CHECK(gi_anim_resolve(&p->anim, &s, "job.json", &err) != 0);
    GI_CHECK(strstr(err.msg, "detp.animation.object: object \"floor\" is not mobile") != NULL);
    strcpy(p->anim.object, "lamp");
    GI_CHECK(gi_anim_resolve(&p->anim, &s, "job.json", &err) != 0);
    GI_CHECK(strstr(err.msg, "detp.animation.object: object \"lamp\" is emissive") != NULL);

    /* Through gi_detp_resolve_params, after refinement: the pivot of the
     * refined box is still its centre. */
    GI_REQUIRE_OK(parse_detp("{\"subdivide\": 0.3, \"animation\": {\"object\": \"box\","
                             " \"frames\": 3, \"keyframes\": [{\"frame\": 0}]}}",
                             p, &err));
    uint32_t nv = s.vertex_count;
    GI_REQUIRE_OK(gi_detp_resolve_params(p, &s, "job.json", &err));
    GI_CHECK(s.vertex_count > nv);
    GI_CHECK(p->anim.object_index == (uint32_t)gi_scene_find_object(&s, "box"));
    GI_CHECK_NEAR(p->anim.pivot[0], 0.5, 1e-6);
    GI_CHECK_NEAR(p->anim.pivot[1], 1.0, 1e-6);
    GI_CHECK_NEAR(p->anim.pivot[2], -0.25, 1e-6);
    /* And a job without animation resolves as before. */
    GI_REQUIRE_OK(parse_detp("{\"photons\": 10}", p, &err));
    GI_CHECK_OK(gi_detp_resolve_params(p, &s, "job.json", &err));
    free(p);
    gi_scene_free(&s);
}

GI_TEST(test_scene_pose_object_moves_one_object)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_text("pose.json", pose_scene, &s, &err));
    int obj = gi_scene_find_object(&s, "box");
    GI_REQUIRE(obj >= 0);
    const gi_object *o = &s.objects[obj];
    uint32_t nv = s.vertex_count, nt = s.triangle_count;

    /* Snapshots of everything posing may touch. */
    gi_vec3 *pos0 = gi_xmalloc(nv * sizeof *pos0), *nrm0 = gi_xmalloc(nv * sizeof *nrm0);
    gi_vec3 *tn0 = gi_xmalloc(nt * sizeof *tn0);
    uint8_t *sm0 = gi_xmalloc(nt);
    memcpy(pos0, s.positions, nv * sizeof *pos0);
    memcpy(nrm0, s.normals, nv * sizeof *nrm0);
    memcpy(tn0, s.tri_normal, nt * sizeof *tn0);
    memcpy(sm0, s.tri_smooth, nt);
    gi_vec3 bmin0 = s.bbox_min, bmax0 = s.bbox_max;
    double power0 = s.total_power;

    gi_vec3 *bp, *bn;
    GI_REQUIRE_OK(gi_scene_object_copy_base(&s, (uint32_t)obj, &bp, &bn, &err));
    GI_CHECK(memcmp(bp, s.positions + o->first_vertex, o->vertex_count * sizeof *bp) == 0);

    /* 90 degrees about y around the box's centre (0.5, 1, -0.25), then 10
     * along x. R_y(90) maps +x to -z and +z to +x. */
    double pivot[3] = {0.5, 1.0, -0.25}, tr[3] = {10, 0, 0};
    double q[4] = {sqrt(0.5), 0, sqrt(0.5), 0};
    gi_mat4 m = gi_anim_matrix(pivot, tr, q, 1.0);
    GI_REQUIRE_OK(gi_scene_pose_object(&s, (uint32_t)obj, bp, bn, &m, &err));
    for (uint32_t i = 0; i < o->vertex_count; i++) {
        gi_vec3 b = bp[i], p = s.positions[o->first_vertex + i];
        /* By hand: (x, y, z) -> (0.5 + 10 + (z + 0.25), y, -0.25 - (x - 0.5)). */
        GI_CHECK_NEAR(p.x, 10.5 + (b.z + 0.25), 1e-5);
        GI_CHECK_NEAR(p.y, b.y, 1e-6);
        GI_CHECK_NEAR(p.z, -0.25 - (b.x - 0.5), 1e-5);
        gi_vec3 n = s.normals[o->first_vertex + i], n0 = bn[i];
        GI_CHECK_NEAR(n.x, n0.z, 1e-6);
        GI_CHECK_NEAR(n.y, n0.y, 1e-6);
        GI_CHECK_NEAR(n.z, -n0.x, 1e-6);
        GI_CHECK_NEAR(gi_length(n), 1.0, 1e-6);
    }
    for (uint32_t t = o->first_triangle; t < o->first_triangle + o->triangle_count; t++) {
        gi_vec3 a, b, c;
        gi_scene_triangle(&s, t, &a, &b, &c);
        gi_vec3 n = gi_normalize(gi_cross(gi_sub(b, a), gi_sub(c, a)));
        GI_CHECK_NEAR(gi_dot(n, s.tri_normal[t]), 1.0, 1e-6);
        gi_vec3 n0 = tn0[t];
        GI_CHECK_NEAR(s.tri_normal[t].x, n0.z, 1e-6);
        GI_CHECK_NEAR(s.tri_normal[t].z, -n0.x, 1e-6);
        GI_CHECK(s.tri_smooth[t] == sm0[t]); /* a box stays flat */
    }
    /* The box (1 x 2 x 1 around its centre) now spans x in [10, 11]. */
    GI_CHECK_NEAR(s.bbox_max.x, 11.0, 1e-5);
    GI_CHECK(s.bbox_min.x == bmin0.x && s.bbox_min.y == bmin0.y && s.bbox_max.y == bmax0.y);
    /* Other objects and the lights are untouched. */
    GI_CHECK(memcmp(s.positions, pos0, o->first_vertex * sizeof *pos0) == 0);
    uint32_t after = o->first_vertex + o->vertex_count;
    GI_CHECK(memcmp(s.positions + after, pos0 + after, (nv - after) * sizeof *pos0) == 0);
    GI_CHECK(s.total_power == power0);

    /* Deterministic: the same pose again gives the same bits. */
    gi_vec3 *pos1 = gi_xmalloc(nv * sizeof *pos1);
    memcpy(pos1, s.positions, nv * sizeof *pos1);
    GI_REQUIRE_OK(gi_scene_pose_object(&s, (uint32_t)obj, bp, bn, &m, &err));
    GI_CHECK(memcmp(pos1, s.positions, nv * sizeof *pos1) == 0);

    /* A singular pose and an emissive object are refused, the scene kept. */
    gi_mat4 flat = gi_mat4_scale(1, 0, 1);
    GI_CHECK(gi_scene_pose_object(&s, (uint32_t)obj, bp, bn, &flat, &err) != 0);
    GI_CHECK(strstr(err.msg, "singular") != NULL);
    gi_mat4 far = gi_mat4_translate(1e30, 0, 0);
    GI_CHECK(gi_scene_pose_object(&s, (uint32_t)obj, bp, bn, &far, &err) != 0);
    GI_CHECK(strstr(err.msg, "out of range") != NULL);
    GI_CHECK(memcmp(pos1, s.positions, nv * sizeof *pos1) == 0);
    int lamp = gi_scene_find_object(&s, "lamp");
    gi_vec3 *lp, *ln;
    GI_REQUIRE_OK(gi_scene_object_copy_base(&s, (uint32_t)lamp, &lp, &ln, &err));
    gi_mat4 up = gi_mat4_translate(0, 1, 0);
    GI_CHECK(gi_scene_pose_object(&s, (uint32_t)lamp, lp, ln, &up, &err) != 0);
    GI_CHECK(strstr(err.msg, "emissive") != NULL);
    free(lp);
    free(ln);

    /* Posing back with the identity restores every bit. */
    gi_mat4 id = gi_mat4_identity();
    GI_REQUIRE_OK(gi_scene_pose_object(&s, (uint32_t)obj, bp, bn, &id, &err));
    GI_CHECK(memcmp(s.positions, pos0, nv * sizeof *pos0) == 0);
    GI_CHECK(memcmp(s.normals, nrm0, nv * sizeof *nrm0) == 0);
    GI_CHECK(memcmp(s.tri_normal, tn0, nt * sizeof *tn0) == 0);
    GI_CHECK(memcmp(s.tri_smooth, sm0, nt) == 0);
    GI_CHECK(memcmp(&s.bbox_min, &bmin0, sizeof bmin0) == 0);
    GI_CHECK(memcmp(&s.bbox_max, &bmax0, sizeof bmax0) == 0);

    /* A smooth sphere: a rotation keeps its normals unit and its smooth
     * flags; the identity restores it too. */
    int ball = gi_scene_find_object(&s, "ball");
    gi_vec3 *sp, *sn;
    GI_REQUIRE_OK(gi_scene_object_copy_base(&s, (uint32_t)ball, &sp, &sn, &err));
    double piv[3] = {-1, 0.3, 0}, zero[3] = {0, 0, 0};
    double q2[4] = {cos(0.3), sin(0.3) * 0.6, 0, sin(0.3) * 0.8};
    gi_mat4 r = gi_anim_matrix(piv, zero, q2, 0.5);
    GI_REQUIRE_OK(gi_scene_pose_object(&s, (uint32_t)ball, sp, sn, &r, &err));
    const gi_object *ob = &s.objects[ball];
    for (uint32_t i = 0; i < ob->vertex_count; i++) {
        gi_vec3 p = s.positions[ob->first_vertex + i];
        /* Scale 0.5 about the centre: the radius 0.3 becomes 0.15. */
        GI_CHECK_NEAR(gi_length(gi_sub(p, gi_v3(-1, 0.3f, 0))), 0.15, 2e-3);
        GI_CHECK_NEAR(gi_length(s.normals[ob->first_vertex + i]), 1.0, 1e-6);
    }
    GI_REQUIRE_OK(gi_scene_pose_object(&s, (uint32_t)ball, sp, sn, &id, &err));
    GI_CHECK(memcmp(s.positions, pos0, nv * sizeof *pos0) == 0);
    GI_CHECK(memcmp(s.normals, nrm0, nv * sizeof *nrm0) == 0);
    GI_CHECK(memcmp(s.tri_normal, tn0, nt * sizeof *tn0) == 0);
    GI_CHECK(memcmp(s.tri_smooth, sm0, nt) == 0);

    free(sp);
    free(sn);
    free(bp);
    free(bn);
    free(pos0);
    free(pos1);
    free(nrm0);
    free(tn0);
    free(sm0);
    gi_scene_free(&s);
}
