/* Unit tests: radiosity meshes (compatible quadtree forests), shared
 * vertices, and 2MCE's patch selection. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_test.h"
#include "radiosity/rad.h"
#include "radiosity/rad_2mce.h"
#include "radiosity/rad_mesh.h"
#include "radiosity/rad_patches.h"
#include "radiosity/rad_vertices.h"
#include "test_helpers.h"

static double tri_area(gi_vec3 a, gi_vec3 b, gi_vec3 c)
{
    return 0.5 * gi_length(gi_cross(gi_sub(b, a), gi_sub(c, a)));
}

GI_TEST(test_rad_mesh_is_compatible_and_locates_points)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &s, &err));
    gi_rad_mesh m;
    double pa = gi_rad_patch_area(&s, 100);
    GI_REQUIRE_OK(gi_rad_mesh_build(&m, &s, pa, 2, &err));
    GI_CHECK(m.element_count == m.root_count * 16);
    /* Roots are no larger than the patch area and more than a quarter of it
     * unless their input triangle was smaller already. */
    int sizes_ok = 1;
    for (uint32_t r = 0; r < m.root_count; r++) {
        uint32_t t = m.root_tri[r];
        sizes_ok &=
            m.root_area[r] <= pa * (1 + 1e-9) && (m.root_area[r] > pa / 4 || m.tri_depth[t] == 0);
    }
    GI_CHECK(sizes_ok);
    /* Leaves of one tree have equal areas summing to the root's; every
     * element's centre locates back to it. */
    int areas_ok = 1, located = 1;
    double total = 0.0;
    for (uint32_t e = 0; e < m.element_count; e++) {
        gi_vec3 c[3];
        gi_rad_mesh_element_corners(&m, &s, e, c);
        double a = tri_area(c[0], c[1], c[2]);
        areas_ok &= fabs(a - gi_rad_mesh_element_area(&m, e)) <= 1e-3 * a;
        total += a;
        /* Barycentrics of the element centre in its input triangle. */
        uint32_t t = gi_rad_mesh_element_tri(&m, e);
        gi_vec3 A, B, C;
        gi_scene_triangle(&s, t, &A, &B, &C);
        gi_vec3 p = gi_scale(gi_add(gi_add(c[0], c[1]), c[2]), 1.0f / 3.0f);
        double at = tri_area(A, B, C);
        float u = (float)(tri_area(A, p, C) / at), v = (float)(tri_area(A, B, p) / at);
        float bary[3];
        located &= gi_rad_mesh_locate(&m, t, u, v, bary) == e;
        located &= fabsf(bary[0] - 1.0f / 3) < 1e-2f && fabsf(bary[1] - 1.0f / 3) < 1e-2f;
    }
    GI_CHECK(areas_ok);
    GI_CHECK(located);
    double scene_area = 0.0;
    for (uint32_t t = 0; t < s.triangle_count; t++)
        scene_area += gi_scene_triangle_area(&s, t);
    GI_CHECK_REL(total, scene_area, 1e-5);
    /* Limits are checked before allocating. */
    gi_rad_mesh big;
    GI_CHECK(gi_rad_mesh_build(&big, &s, pa / 1e6, 8, &err) == -1 && err.code == GI_EINVAL);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
}

GI_TEST(test_rad_vertices_weld_coplanar_surfaces_only)
{
    gi_error err;
    gi_scene s;
    /* A unit square (2 triangles) on the floor and one standing on its
     * edge: the square's corners weld across its diagonal into a
     * (2^L + 1)^2 grid; the crease keeps its own vertices. */
    GI_REQUIRE_OK(gi_test_load_scene_text(
        "weld.json",
        "{\"materials\": {\"m\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},"
        " \"objects\": [{\"name\": \"floor\", \"material\": \"m\", \"polygons\": {\"vertices\":"
        " [[0,0,0],[0,0,1],[1,0,1],[1,0,0]], \"faces\": [[0,1,2,3]]}},"
        " {\"name\": \"wall\", \"material\": \"m\", \"polygons\": {\"vertices\":"
        " [[0,0,0],[1,0,0],[1,1,0],[0,1,0]], \"faces\": [[0,1,2,3]]}}]}",
        &s, &err));
    gi_rad_mesh m;
    GI_REQUIRE_OK(gi_rad_mesh_build(&m, &s, 0.0, 3, &err));
    gi_rad_vertices v;
    GI_REQUIRE_OK(gi_rad_vertices_build(&v, &m, &s, &err));
    GI_CHECK(v.count == 2 * 81);
    /* A constant field stays constant; a field that differs between the
     * two squares does not bleed across the crease. */
    float *elem = malloc(3 * (size_t)m.element_count * sizeof *elem);
    float *vv = malloc(3 * (size_t)v.count * sizeof *vv);
    double *area = malloc(m.element_count * sizeof *area);
    for (uint32_t e = 0; e < m.element_count; e++) {
        area[e] = gi_rad_mesh_element_area(&m, e);
        for (int c = 0; c < 3; c++)
            elem[3 * e + c] = e < m.element_count / 2 ? 1.0f : 5.0f;
    }
    GI_REQUIRE_OK(gi_rad_vertex_values(&v, m.element_count, area, elem, vv, &err));
    int ok = 1;
    for (uint32_t e = 0; e < m.element_count; e++)
        for (int k = 0; k < 3; k++)
            ok &= vv[3 * v.corner[3 * e + k]] == elem[3 * e];
    GI_CHECK(ok);
    free(elem), free(vv), free(area);
    gi_rad_vertices_free(&v);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
}

/* One input triangle as one root, levels 2, max_level 2: metrics set by
 * hand to exercise HalloParches' branches. */
static void one_tree(gi_rad_mesh *m, gi_rad_2mce *c)
{
    memset(m, 0, sizeof *m);
    m->levels = 2;
    m->root_count = 1;
    m->element_count = 16;
    memset(c, 0, sizeof *c);
    c->max_level = 2;
    c->roots = 1;
    c->level_offset = calloc(3, sizeof *c->level_offset);
    c->level_offset[1] = 1;
    c->level_offset[2] = 5;
    c->metric = calloc(5, sizeof *c->metric); /* root, then its 4 children */
}

GI_TEST(test_rad_2mce_marks_split_nodes_and_applies_the_sibling_rule)
{
    gi_error err;
    gi_rad_mesh m;
    gi_rad_2mce c;
    one_tree(&m, &c);
    gi_rad_patches pt;
    /* Everything coherent: the root is the only patch. */
    GI_REQUIRE_OK(gi_rad_2mce_select(&c, &m, 1.0, &pt, &err));
    GI_CHECK(pt.k == 1 && pt.p[0].level == 0);
    gi_rad_patches_free(&pt);
    /* Child 2 incoherent: its 4 children become patches, its 3 siblings too
     * (sibling rule), and the root - marked because child 2 now contains
     * patches - does not (the pseudocode's omission would add it, on top
     * of them). */
    c.metric[1 + 2] = 5.0;
    GI_REQUIRE_OK(gi_rad_2mce_select(&c, &m, 1.0, &pt, &err));
    GI_CHECK(pt.k == 7);
    int l1 = 0, l2 = 0;
    for (uint32_t i = 0; i < pt.k; i++) {
        l1 += pt.p[i].level == 1;
        l2 += pt.p[i].level == 2 && pt.p[i].node / 4 == 2;
    }
    GI_CHECK(l1 == 3 && l2 == 4);
    gi_rad_patches_free(&pt);
    /* Only the root incoherent: its 4 children. */
    c.metric[1 + 2] = 0.0;
    c.metric[0] = 5.0;
    GI_REQUIRE_OK(gi_rad_2mce_select(&c, &m, 1.0, &pt, &err));
    GI_CHECK(pt.k == 4 && pt.p[0].level == 1);
    gi_rad_patches_free(&pt);
    /* Tuning for a target finds the closest count. */
    c.metric[1 + 2] = 5.0;
    c.metric[1 + 0] = 3.0;
    double th;
    GI_REQUIRE_OK(gi_rad_2mce_tune(&c, &m, 10, &th, &pt, &err));
    GI_CHECK(pt.k == 10 && th >= 0.0 && th < 3.0); /* splits the nodes above 0 */
    gi_rad_patches_free(&pt);
    GI_REQUIRE_OK(gi_rad_2mce_tune(&c, &m, 100, &th, &pt, &err));
    GI_CHECK(pt.k == 16);
    gi_rad_patches_free(&pt);
    gi_rad_2mce_free(&c);
}

GI_TEST(test_rad_2mce_metric_is_zero_for_coherent_rows)
{
    gi_error err;
    gi_rad_mesh m;
    gi_rad_2mce c;
    one_tree(&m, &c);
    free(c.metric);
    free(c.level_offset);
    /* Counts at level 2 (16 nodes): uniform rows are perfectly coherent;
     * one row that sees only node 0 makes every ancestor of node 0
     * incoherent. */
    uint16_t counts[16 * 16];
    for (int i = 0; i < 16 * 16; i++)
        counts[i] = 4;
    GI_REQUIRE_OK(gi_rad_2mce_metrics(&c, &m, counts, 16, 2, 64, &err));
    for (int i = 0; i < 5; i++)
        GI_CHECK(c.metric[i] == 0.0);
    gi_rad_2mce_free(&c);
    memset(counts, 0, 16 * sizeof *counts);
    counts[0] = 64;
    GI_REQUIRE_OK(gi_rad_2mce_metrics(&c, &m, counts, 16, 2, 64, &err));
    GI_CHECK(c.metric[0] > 0.0 && c.metric[1] > 0.0);
    GI_CHECK(c.metric[2] == 0.0 && c.metric[3] == 0.0 && c.metric[4] == 0.0);
    gi_rad_2mce_free(&c);
}
