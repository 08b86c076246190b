/* Unit tests: scene files (JSON), assembly checks, lights, camera. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_buf.h"
#include "gi_camera.h"
#include "gi_fs.h"
#include "gi_light.h"
#include "gi_rng.h"
#include "gi_scene_build.h"
#include "gi_test.h"
#include "test_helpers.h"

GI_TEST(test_cornell_box_scene_matches_the_measured_data)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &s, &err));
    GI_CHECK(s.object_count == 8);
    GI_CHECK(s.triangle_count == 32);
    GI_CHECK(s.has_camera);
    GI_CHECK_NEAR(s.camera.fov_y_deg, 39.3, 1e-5);
    int light = gi_scene_find_object(&s, "light");
    GI_REQUIRE(light >= 0);
    GI_CHECK(s.light_count == 2);
    double area = 0;
    for (uint32_t i = 0; i < s.light_count; i++) {
        uint32_t t = s.light_tris[i];
        GI_CHECK(s.tri_object[t] == (uint32_t)light);
        area += gi_scene_triangle_area(&s, t);
        gi_vec3 n = gi_scene_triangle_normal(&s, t);
        /* The light faces down into the box. */
        GI_CHECK_NEAR(n.y, -1.0, 1e-6);
    }
    GI_CHECK_NEAR(area, 130.0 * 105.0, 1e-3);
    double lum = 0.2126 * 17 + 0.7152 * 12 + 0.0722 * 4;
    GI_CHECK_REL(s.total_power, GI_PI * area * lum, 1e-6);
    const gi_material *red = gi_scene_tri_material(&s, s.objects[gi_scene_find_object(&s, "left_wall")].first_triangle);
    GI_CHECK(strcmp(red->name, "red") == 0);
    GI_CHECK_NEAR(red->diffuse.y, 0.065, 1e-7);
    GI_CHECK_NEAR(s.bbox_max.x, 556.0, 1e-3);
    GI_CHECK_NEAR(s.bbox_max.y, 548.8, 1e-3);
    GI_CHECK_NEAR(s.bbox_max.z, 559.2, 1e-3);
    /* Image right is -x: the red wall (x ~ 550) is on the left. */
    gi_camera_frame f;
    gi_camera_frame_init(&f, &s.camera, 256, 256);
    GI_CHECK(gi_camera_dir(&f, 0.0f, 128.0f).x > 0.0f);
    GI_CHECK(gi_camera_dir(&f, 256.0f, 128.0f).x < 0.0f);
    GI_CHECK(gi_camera_dir(&f, 128.0f, 0.0f).y > 0.0f);
    gi_scene_free(&s);
}

GI_TEST(test_scene_shapes_transforms_and_mobile)
{
    gi_error err;
    gi_scene s;
    const char *text =
        "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]},"
        "                 \"l\": {\"emission\": [1, 1, 1], \"two_sided\": true}},"
        " \"objects\": ["
        "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [2, 3]},"
        "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 90}},"
        "                   {\"translate\": [0, 5, 0]}]},"
        "  {\"name\": \"ball\", \"material\": \"w\", \"mobile\": true,"
        "   \"sphere\": {\"radius\": 2, \"subdivisions\": 2},"
        "   \"transform\": [{\"scale\": 0.5}, {\"translate\": [10, 0, 0]}]},"
        "  {\"name\": \"room\", \"material\": \"w\", \"box\": {\"size\": [20, 20, 20], \"inward\": true}}"
        " ]}";
    GI_REQUIRE_OK(gi_test_load_scene_text("shapes.json", text, &s, &err));
    GI_CHECK(s.object_count == 3);
    GI_CHECK(!s.has_camera); /* a default camera is still provided */
    GI_CHECK(gi_length(gi_sub(s.camera.position, s.camera.look_at)) > 0);
    const gi_object *lamp = &s.objects[0], *ball = &s.objects[1];
    GI_CHECK(!lamp->mobile && ball->mobile);
    /* The lamp quad was rotated to face -z... or +z: normal along z, at y 5. */
    gi_vec3 n = gi_scene_triangle_normal(&s, lamp->first_triangle);
    GI_CHECK_NEAR(fabs(n.z), 1.0, 1e-5);
    for (uint32_t v = lamp->first_vertex; v < lamp->first_vertex + lamp->vertex_count; v++)
        GI_CHECK_NEAR(s.positions[v].y, 5.0, 1.6);
    /* Scale then translate: every ball vertex at distance 1 from (10, 0, 0). */
    for (uint32_t v = ball->first_vertex; v < ball->first_vertex + ball->vertex_count; v++) {
        GI_CHECK_NEAR(gi_length(gi_sub(s.positions[v], gi_v3(10, 0, 0))), 1.0, 1e-5);
        /* Normals point outwards after the transform. */
        GI_CHECK(gi_dot(s.normals[v], gi_sub(s.positions[v], gi_v3(10, 0, 0))) > 0.99f);
    }
    /* Two-sided emitter: twice the power of one face. */
    GI_CHECK_REL(s.total_power, 2.0 * GI_PI * 6.0, 1e-5);
    gi_scene_free(&s);
}

/* A mirroring transform keeps each face's front where the original's was:
 * a mirrored ball still faces out, a quad mirrored through its plane
 * emits to the other side. */
GI_TEST(test_scene_mirroring_transform_keeps_front_faces)
{
    gi_error err;
    gi_scene s;
    const char *text =
        "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]},"
        "                 \"l\": {\"emission\": [1, 1, 1]}},"
        " \"objects\": ["
        "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [2, 3]},"
        "   \"transform\": [{\"scale\": [1, -1, 1]}, {\"translate\": [0, 5, 0]}]},"
        "  {\"name\": \"ball\", \"material\": \"w\", \"sphere\": {\"radius\": 2},"
        "   \"transform\": [{\"scale\": [-1, 1, 1]}, {\"translate\": [10, 0, 0]}]}"
        " ]}";
    GI_REQUIRE_OK(gi_test_load_scene_text("mirror.json", text, &s, &err));
    const gi_object *lamp = &s.objects[0], *ball = &s.objects[1];
    for (uint32_t t = lamp->first_triangle; t < lamp->first_triangle + lamp->triangle_count; t++)
        GI_CHECK_NEAR(gi_scene_triangle_normal(&s, t).y, -1.0, 1e-6);
    for (uint32_t t = ball->first_triangle; t < ball->first_triangle + ball->triangle_count; t++) {
        const uint32_t *ix = &s.indices[3 * t];
        gi_vec3 c = gi_scale(gi_add(gi_add(s.positions[ix[0]], s.positions[ix[1]]),
                                    s.positions[ix[2]]), 1.0f / 3.0f);
        GI_CHECK(gi_dot(gi_scene_triangle_normal(&s, t), gi_sub(c, gi_v3(10, 0, 0))) > 0.0f);
    }
    for (uint32_t v = ball->first_vertex; v < ball->first_vertex + ball->vertex_count; v++)
        GI_CHECK(gi_dot(s.normals[v], gi_sub(s.positions[v], gi_v3(10, 0, 0))) > 0.99f);
    gi_scene_free(&s);
}

/* Concave faces are cut into ears that cover the face once and face its
 * way (fanning from the first vertex made a backwards triangle outside
 * it); convex ones stay fans; faces whose edges cross are refused. */
GI_TEST(test_scene_concave_polygons)
{
    gi_error err;
    gi_scene s;
    /* An arrow in the y = 0 plane, counter-clockwise seen from +y (front +y),
     * its notch at vertex 0, the second of the face: area 4 * 4 - 4 * 2 / 2
     * = 12 (the fan from (0, 0, 4) made the notch a backwards triangle). */
    const char *text =
        "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},"
        " \"objects\": [{\"name\": \"arrow\", \"material\": \"w\", \"polygons\": {"
        "   \"vertices\": [[2, 0, 2], [0, 0, 4], [0, 0, 0], [4, 0, 0], [4, 0, 4]],"
        "   \"faces\": [[1, 0, 4, 3, 2]]}},"
        "  {\"name\": \"square\", \"material\": \"w\", \"polygons\": {"
        "   \"vertices\": [[0, 1, 0], [0, 1, 1], [1, 1, 1], [1, 1, 0]],"
        "   \"faces\": [[0, 1, 2, 3]]}}]}";
    GI_REQUIRE_OK(gi_test_load_scene_text("arrow.json", text, &s, &err));
    const gi_object *arrow = &s.objects[0];
    GI_REQUIRE(arrow->triangle_count == 3);
    double area = 0;
    for (uint32_t t = arrow->first_triangle; t < arrow->first_triangle + 3; t++) {
        area += gi_scene_triangle_area(&s, t);
        GI_CHECK_NEAR(gi_scene_triangle_normal(&s, t).y, 1.0, 1e-6);
    }
    GI_CHECK_NEAR(area, 12.0, 1e-5);
    /* The square: the fan (0 1 2), (0 2 3), as before. */
    const uint32_t *sq = &s.indices[3 * s.objects[1].first_triangle];
    uint32_t v0 = s.objects[1].first_vertex;
    GI_CHECK(sq[0] == v0 && sq[1] == v0 + 1 && sq[2] == v0 + 2 && sq[3] == v0 && sq[4] == v0 + 2 &&
             sq[5] == v0 + 3);
    gi_scene_free(&s);

    /* A bowtie; a pentagram (every corner turns the same way, but twice
     * around). */
    static const char *const crossing[] = {
        "[[0, 0, 0], [2, 0, 2], [2, 0, 0], [0, 0, 2], [1, 0, 3]]",
        "[[0, 0, 10], [6, 0, -8], [-9.5, 0, 3], [9.5, 0, 3], [-6, 0, -8]]"};
    for (int i = 0; i < 2; i++) {
        char bad[512];
        snprintf(bad, sizeof bad,
                 "{\"materials\": {\"w\": {\"emission\": [1, 1, 1]}},"
                 " \"objects\": [{\"name\": \"x\", \"material\": \"w\", \"polygons\": {"
                 "   \"vertices\": %s, \"faces\": [[0, 1, 2, 3, 4]]}}]}",
                 crossing[i]);
        GI_CHECK(gi_test_load_scene_text("crossing.json", bad, &s, &err) != 0);
        GI_CHECK_MSG(strstr(err.msg, "faces[0]: its edges cross") != NULL, "%s", err.msg);
    }
}

GI_TEST(test_scene_of_meshes_needs_no_materials_block)
{
    gi_error err;
    gi_scene s;
    char text[1200];
    snprintf(text, sizeof text,
             "{\"objects\": [{\"name\": \"m\", \"mesh\": \"%s/tests/data/meshes/two_materials.obj\"}]}",
             gi_test_srcdir());
    GI_REQUIRE_OK(gi_test_load_scene_text("meshes.json", text, &s, &err));
    GI_CHECK(s.object_count == 1 && s.material_count == 2 && s.total_power > 0);
    gi_scene_free(&s);
}

/* A mesh file's materials are the scene's "<object>/<material>" in full:
 * two names that differ only after 500 bytes stay two materials (they
 * were cut to 511 bytes and became one, with the first one's colours). */
GI_TEST(test_scene_mesh_material_names_are_kept_whole)
{
    char base[601];
    memset(base, 'm', 600);
    base[600] = '\0';
    char obj[1600], mtl[1600], text[600];
    snprintf(obj, sizeof obj,
             "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
             "usemtl %s1\nf 1 2 3\nusemtl %s2\nf 2 4 3\n",
             base, base);
    snprintf(mtl, sizeof mtl, "newmtl %s1\nKd 0.5 0.5 0.5\nnewmtl %s2\nKd 0 0 0\nKe 1 1 1\n",
             base, base);
    char *po = gi_path_join(gi_test_tmpdir(), "two.obj");
    char *pm = gi_path_join(gi_test_tmpdir(), "two.mtl");
    gi_error err;
    GI_REQUIRE_OK(gi_write_file_atomic(po, obj, strlen(obj), &err));
    GI_REQUIRE_OK(gi_write_file_atomic(pm, mtl, strlen(mtl), &err));
    free(po);
    free(pm);
    char object[301];
    memset(object, 'o', 300);
    object[300] = '\0';
    snprintf(text, sizeof text, "{\"objects\": [{\"name\": \"%s\", \"mesh\": \"two.obj\"}]}",
             object);
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_text("names.json", text, &s, &err));
    GI_CHECK(s.material_count == 2);
    for (int k = 1; k <= 2; k++) {
        char full[1000];
        snprintf(full, sizeof full, "%s/%s%d", object, base, k);
        int m = gi_scene_material_index(&s, full);
        GI_CHECK_MSG(m >= 0, "material %d is missing", k);
        if (m >= 0)
            GI_CHECK(gi_is_black(s.materials[m].emission) == (k == 1));
    }
    gi_scene_free(&s);
}

/* A mesh file without normals is split at its hard edges: the cube of 8
 * shared vertices gets 24, each with its face's normal (as the built-in box
 * has), not corner normals pointing diagonally out; still manifold (its
 * crease edges become boundary edges), also when mobile and transformed.
 * A gentle fold (30 degrees) stays one smooth vertex row. */
GI_TEST(test_scene_mesh_without_normals_is_split_at_hard_edges)
{
    gi_error err;
    gi_scene s;
    char text[1600];
    snprintf(text, sizeof text,
             "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]},"
             "                 \"l\": {\"emission\": [1, 1, 1]}},"
             " \"objects\": ["
             "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [1, 1]},"
             "   \"transform\": [{\"translate\": [0, 9, 0]}]},"
             "  {\"name\": \"cube\", \"mesh\": \"%s/tests/data/meshes/cube_shared.obj\","
             "   \"material\": \"w\", \"mobile\": true,"
             "   \"transform\": [{\"scale\": [60, 30, 60]},"
             "                   {\"rotate\": {\"axis\": [0, 1, 0], \"degrees\": 30}}]},"
             "  {\"name\": \"fold\", \"material\": \"w\", \"polygons\": {"
             "   \"vertices\": [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0],"
             "                  [2, 0.57735, 0], [2, 0.57735, 1]],"
             "   \"faces\": [[0, 1, 2, 3], [3, 2, 5, 4]]}}"
             " ]}",
             gi_test_srcdir());
    GI_REQUIRE_OK(gi_test_load_scene_text("cube.json", text, &s, &err));
    const gi_object *cube = &s.objects[1], *fold = &s.objects[2];
    GI_CHECK(cube->triangle_count == 12 && cube->vertex_count == 24);
    GI_CHECK(cube->mobile);
    for (uint32_t t = cube->first_triangle; t < cube->first_triangle + 12; t++) {
        gi_vec3 fn = gi_scene_triangle_normal(&s, t);
        for (int k = 0; k < 3; k++) {
            uint32_t v = s.indices[3 * t + k];
            GI_CHECK(v >= cube->first_vertex && v < cube->first_vertex + 24);
            GI_CHECK_MSG(gi_dot(s.normals[v], fn) > 1.0f - 1e-6f,
                         "triangle %u vertex %u: normal (%g %g %g), face (%g %g %g)", t, v,
                         s.normals[v].x, s.normals[v].y, s.normals[v].z, fn.x, fn.y, fn.z);
        }
        GI_CHECK(!s.tri_smooth[t]);
    }
    /* The fold's middle row is shared, its normal between the two faces. */
    GI_CHECK(fold->vertex_count == 6);
    gi_vec3 mid = s.normals[fold->first_vertex + 3];
    GI_CHECK(mid.y > 0.85f && mid.y < 0.999f && mid.x < -0.1f);
    gi_scene_free(&s);
}

/* Far from unit scale, face normals are computed in double: at 1e9 mm a
 * wall's float cross product (~1e47) overflowed to a NaN normal and every
 * method rendered black; a sphere scaled by 1e-20 underflowed to "every
 * triangle is degenerate", and its normals' inverse transform overflowed. */
GI_TEST(test_scene_normals_far_from_unit_scale)
{
    gi_error err;
    gi_scene s;
    const char *text =
        "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]},"
        "                 \"l\": {\"emission\": [1, 1, 1]}},"
        " \"objects\": ["
        "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [130, 105]},"
        "   \"transform\": [{\"scale\": [1, -1, 1]}, {\"translate\": [0, 548, 0]},"
        "                   {\"scale\": 1e9}]},"
        "  {\"name\": \"room\", \"material\": \"w\", \"box\": {\"size\": [556, 549, 559],"
        "   \"inward\": true}, \"transform\": [{\"translate\": [0, 274, 0]}, {\"scale\": 1e9}]},"
        "  {\"name\": \"dust\", \"material\": \"w\", \"sphere\": {\"radius\": 1},"
        "   \"transform\": [{\"scale\": 1e-20}]}"
        " ]}";
    GI_REQUIRE_OK(gi_test_load_scene_text("huge.json", text, &s, &err));
    for (uint32_t t = 0; t < s.triangle_count; t++)
        GI_CHECK_MSG(fabs(gi_length(gi_scene_triangle_normal(&s, t)) - 1.0) < 1e-6,
                     "triangle %u (object %u)", t, s.tri_object[t]);
    for (uint32_t v = 0; v < s.vertex_count; v++)
        GI_CHECK_MSG(fabs(gi_length(s.normals[v]) - 1.0) < 1e-6, "vertex %u", v);
    GI_CHECK_NEAR(gi_scene_triangle_normal(&s, s.objects[0].first_triangle).y, -1.0, 1e-6);
    GI_CHECK(s.light_count == 2 && isfinite(s.total_power) && s.total_power > 0);
    for (uint32_t i = 0; i < s.light_count; i++)
        GI_CHECK(isfinite(s.light_geom[i].pdf_area) && s.light_geom[i].pdf_area > 0 &&
                 s.light_geom[i].n.y < -0.999f);
    gi_scene_free(&s);
}

typedef struct bad_case {
    const char *text, *expect;
} bad_case;

GI_TEST(test_bad_scenes_are_refused_with_a_clear_message)
{
    static const bad_case cases[] = {
        {"{\"materials\": {}, \"objects\": []}", "no objects"},
        {"{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]}}, \"objects\": [{\"material\": "
         "\"w\", \"quad\": {\"size\": [1, 1]}}]}",
         "no light"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"x\", "
         "\"quad\": {\"size\": [1, 1]}}]}",
         "material \"x\" is not defined"},
        {"{\"materials\": {\"l\": {\"diffuse\": [1.5, 0, 0]}}, \"objects\": []}",
         "materials.l.diffuse[0]: 1.5 is out of range"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"polygons\": {\"vertices\": [], \"faces\": []}}]}",
         "empty mesh"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"polygons\": {\"vertices\": [[0,0,0],[1,0,0],[0,1,0]], \"faces\": [[0,1,3]]}}]}",
         "faces[0][2]: 3 is out of range"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"polygons\": {\"vertices\": [[0,0,0],[1,0,0],[0,1,0],[0,0,1],[0,-1,0]], "
         "\"faces\": [[0,1,2],[0,1,3],[0,1,4]]}}]}",
         "non-manifold"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"polygons\": {\"vertices\": [[0,0,0],[1,0,0],[2,0,0]], \"faces\": [[0,1,2]]}}]}",
         "degenerate"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"quad\": {\"size\": [1, 1]}, \"transform\": [{\"scale\": 0}]}]}",
         "zero scale"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"quad\": {\"size\": [1, 1]}, \"box\": {\"size\": [1, 1, 1]}}]}",
         "one geometry per object"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"quad\": {\"size\": [1, 1e999]}}]}",
         "not finite"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"material\": \"l\", "
         "\"mesh\": \"nowhere.obj\"}]}",
         "nowhere.obj"},
        {"{\"camera\": {\"position\": [0,0,0], \"look_at\": [0,0,0], \"fov_y\": 40}, "
         "\"materials\": {}, \"objects\": []}",
         "same point"},
        {"{\"materials\": {\"l\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"name\": \"a\", "
         "\"material\": \"l\", \"quad\": {\"size\": [1, 1]}}, {\"name\": \"a\", \"material\": "
         "\"l\", \"quad\": {\"size\": [1, 1]}}]}",
         "used twice"},
        {"{\"materials\": {}, \"objects\": [], \"lights\": []}", "lights: unknown key"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        gi_error err;
        gi_error_clear(&err);
        gi_scene s;
        int rc = gi_test_load_scene_text("bad.json", cases[i].text, &s, &err);
        GI_CHECK_MSG(rc == -1, "case %zu loaded", i);
        GI_CHECK_MSG(err.code == GI_EINVAL, "case %zu: code %d (%s)", i, err.code, err.msg);
        GI_CHECK_MSG(strstr(err.msg, cases[i].expect) != NULL && strstr(err.msg, "bad.json"),
                     "case %zu: \"%s\" does not say \"%s\"", i, err.msg, cases[i].expect);
        if (rc == 0)
            gi_scene_free(&s);
    }
}

/* A scene of 5,000 objects (loading once grew every array per object and
 * scanned every name): 4,900 boxes over 1,000 materials and 100 instances
 * of one mesh file (imported once, each instance a copy with materials of
 * its own). Every object is found by name at its place with its own
 * geometry, and a name repeated by a last object is still refused. */
#define MANY_OBJECTS 5000
#define MANY_MATERIALS 1000
static int is_instance(int i) { return i % 50 == 49; }

static void many_objects_text(gi_buf *b, const char *extra)
{
    gi_buf_printf(b, "{\"materials\": {");
    for (int k = 0; k < MANY_MATERIALS; k++)
        gi_buf_printf(b, "%s\"m%d\": {\"diffuse\": [0.5, 0.5, %g]}", k ? ", " : "", k, k / 2000.0);
    gi_buf_printf(b, "}, \"objects\": [");
    for (int i = 0; i < MANY_OBJECTS; i++) {
        if (is_instance(i))
            gi_buf_printf(b, "%s{\"name\": \"inst%d\", \"mesh\": \"%s/tests/data/meshes/"
                        "two_materials.obj\", ", i ? ", " : "", i, gi_test_srcdir());
        else
            gi_buf_printf(b, "%s{\"name\": \"cube%d\", \"material\": \"m%d\", \"box\": {\"size\": "
                        "[0.5, 0.5, 0.5]}, ", i ? ", " : "", i, i % MANY_MATERIALS);
        gi_buf_printf(b, "\"transform\": [{\"translate\": [%d, 0, 0]}]}", i);
    }
    gi_buf_printf(b, "%s]}", extra);
    gi_buf_put_u8(b, 0);
}

GI_TEST(test_scene_with_many_objects)
{
    gi_error err;
    gi_scene ref, s;
    char text[600];
    snprintf(text, sizeof text,
             "{\"objects\": [{\"name\": \"m\", \"mesh\": "
             "\"%s/tests/data/meshes/two_materials.obj\"}]}",
             gi_test_srcdir());
    GI_REQUIRE_OK(gi_test_load_scene_text("one.json", text, &ref, &err));
    gi_buf b;
    gi_buf_init(&b);
    many_objects_text(&b, "");
    GI_REQUIRE_OK(gi_test_load_scene_text("many.json", (const char *)b.data, &s, &err));
    GI_CHECK(s.object_count == MANY_OBJECTS);
    GI_CHECK(s.material_count == MANY_MATERIALS + 2 * (MANY_OBJECTS / 50));
    uint32_t nv = 0, nt = 0, bad = 0;
    for (int i = 0; i < MANY_OBJECTS && bad < 5; i++) {
        char name[32], mat[32];
        snprintf(name, sizeof name, is_instance(i) ? "inst%d" : "cube%d", i);
        const gi_object *o = &s.objects[i];
        int ok = gi_scene_find_object(&s, name) == i && strcmp(o->name, name) == 0 &&
                 o->first_vertex == nv && o->first_triangle == nt &&
                 s.tri_object[nt] == (uint32_t)i && s.tri_object[nt + o->triangle_count - 1] ==
                 (uint32_t)i;
        if (is_instance(i)) {
            ok &= o->vertex_count == ref.vertex_count && o->triangle_count == ref.triangle_count;
            for (uint32_t j = 0; ok && j < o->vertex_count; j++) {
                gi_vec3 p = s.positions[nv + j], q = ref.positions[j];
                ok &= p.x == q.x + (float)i && p.y == q.y && p.z == q.z;
            }
            for (uint32_t t = 0; ok && t < o->triangle_count; t++) {
                const char *rm = ref.materials[ref.tri_material[t]].name; /* "m/<material>" */
                char full[64];
                snprintf(full, sizeof full, "%s%s", name, rm + 1);
                ok &= s.tri_material[nt + t] == (uint32_t)gi_scene_material_index(&s, full) &&
                      strcmp(s.materials[s.tri_material[nt + t]].name, full) == 0;
            }
        } else {
            snprintf(mat, sizeof mat, "m%d", i % MANY_MATERIALS);
            ok &= o->vertex_count == 24 && o->triangle_count == 12 &&
                  gi_scene_material_index(&s, mat) == i % MANY_MATERIALS &&
                  s.tri_material[nt] == (uint32_t)(i % MANY_MATERIALS) &&
                  s.positions[nv].x >= (float)i - 0.25f && s.positions[nv].x <= (float)i + 0.25f;
        }
        GI_CHECK_MSG(ok, "object %d (%s) is not as written", i, name);
        bad += !ok;
        nv += o->vertex_count;
        nt += o->triangle_count;
    }
    GI_CHECK(s.vertex_count == nv && s.triangle_count == nt);
    GI_CHECK(nv == (MANY_OBJECTS - 100) * 24 + 100 * ref.vertex_count);
    GI_CHECK(nt == (MANY_OBJECTS - 100) * 12 + 100 * ref.triangle_count);
    /* Embree reads past the last vertex: the padding element is there. */
    GI_CHECK(s.positions[nv].x == 0 && s.positions[nv].y == 0 && s.positions[nv].z == 0);
    GI_CHECK(s.light_count == 100 * ref.light_count);
    GI_CHECK(gi_scene_find_object(&s, "cube49") == -1 && gi_scene_find_object(&s, "m") == -1);
    GI_CHECK(gi_scene_material_index(&s, "m1000") == -1);
    gi_scene_free(&s);
    gi_scene_free(&ref);

    gi_buf_reset(&b);
    many_objects_text(&b, ", {\"name\": \"cube0\", \"material\": \"m1\", \"quad\": {\"size\": "
                          "[1, 1]}}");
    gi_error_clear(&err);
    GI_CHECK(gi_test_load_scene_text("dup.json", (const char *)b.data, &s, &err) == -1);
    GI_CHECK_MSG(strstr(err.msg, "dup.json: object \"cube0\": the name is used twice"),
                 "%s", err.msg);
    gi_buf_free(&b);
}

/* Names longer than output files carry (a radiosity factorization reads
 * "<object>/<material>" back) are refused at the scene, before any work. */
GI_TEST(test_scene_names_over_the_limit_are_refused)
{
    char name[GI_SCENE_NAME_MAX + 2];
    for (int over = 0; over <= 1; over++) {
        memset(name, 'n', sizeof name);
        name[GI_SCENE_NAME_MAX + over] = 0;
        for (int in_materials = 0; in_materials <= 1; in_materials++) {
            char text[3 * GI_SCENE_NAME_MAX + 256];
            snprintf(text, sizeof text,
                     "{\"materials\": {\"%s\": {\"emission\": [1, 1, 1]}}, \"objects\": "
                     "[{\"name\": \"%s\", \"material\": \"%s\", "
                     "\"quad\": {\"size\": [1, 1]}}]}",
                     in_materials ? name : "l", in_materials ? "o" : name,
                     in_materials ? name : "l");
            gi_error err;
            gi_error_clear(&err);
            gi_scene s;
            int rc = gi_test_load_scene_text("names.json", text, &s, &err);
            if (!over) {
                GI_CHECK_MSG(rc == 0, "%s", err.msg);
                if (rc == 0)
                    gi_scene_free(&s);
                continue;
            }
            GI_CHECK(rc == -1 && err.code == GI_EINVAL);
            GI_CHECK_MSG(strstr(err.msg, "names.json") &&
                             strstr(err.msg, in_materials ? "materials" : "objects[0]") &&
                             strstr(err.msg, "1001 bytes long, over the limit of 1000"),
                         "%s", err.msg);
        }
    }
}

GI_TEST(test_light_sampling_is_proportional_to_power)
{
    gi_error err;
    gi_scene s;
    const char *text =
        "{\"materials\": {\"a\": {\"emission\": [1, 1, 1]}, \"b\": {\"emission\": [3, 3, 3]}},"
        " \"objects\": [{\"name\": \"a\", \"material\": \"a\", \"quad\": {\"size\": [1, 1]}},"
        "  {\"name\": \"b\", \"material\": \"b\", \"quad\": {\"size\": [2, 1]},"
        "   \"transform\": [{\"translate\": [5, 0, 0]}]}]}";
    GI_REQUIRE_OK(gi_test_load_scene_text("lights.json", text, &s, &err));
    /* Powers 1 and 6: b is picked 6/7 of the time; pdf_area matches. */
    gi_rng rng;
    gi_rng_init(&rng, 3, 0, 0);
    int nb = 0, n = 200000;
    for (int i = 0; i < n; i++) {
        gi_light_sample ls;
        gi_light_sample_point(&s, gi_rng_double(&rng), gi_rng_float(&rng), gi_rng_float(&rng), &ls);
        int is_b = ls.p.x > 2.0f;
        nb += is_b;
        GI_CHECK_NEAR(ls.pdf_area, is_b ? (6.0 / 7.0) / 2.0 : (1.0 / 7.0) / 1.0, 1e-6);
    }
    GI_CHECK_NEAR((double)nb / n, 6.0 / 7.0, 0.005);
    gi_scene_free(&s);
}
