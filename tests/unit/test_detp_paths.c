/* Unit tests: photon paths (determinism per photon index, retracing a
 * suffix, the segment encoding, absorb-or-reflect energy), the mesh
 * refinement behind the irradiance points, and the visible disc area. */
#include <stdlib.h>
#include <string.h>

#include "detp/detp.h"
#include "gi_rt.h"
#include "gi_test.h"
#include "test_helpers.h"

static int same_segment(const gi_detp_segment *a, const gi_detp_segment *b)
{
    return memcmp(&a->org, &b->org, sizeof a->org) == 0 &&
           memcmp(&a->dir, &b->dir, sizeof a->dir) == 0 &&
           memcmp(&a->energy, &b->energy, sizeof a->energy) == 0 &&
           (a->t_hit == b->t_hit || (isinf(a->t_hit) && isinf(b->t_hit))) &&
           (a->t_second == b->t_second || (isinf(a->t_second) && isinf(b->t_second))) &&
           a->hit_tri == b->hit_tri && a->bounce == b->bounce && a->photon == b->photon;
}

GI_TEST(test_detp_paths_depend_only_on_the_photon_index)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    gi_detp_tracer tr;
    gi_detp_tracer_init(&tr, &rt, &s, 7, 1000, -1, 1);
    /* A batch [100, 300) against photon-by-photon traces, in reverse. */
    gi_detp_segments batch, one;
    gi_detp_segments_init(&batch);
    gi_detp_segments_init(&one);
    for (uint64_t p = 100; p < 300; p++)
        gi_detp_trace_photon(&tr, p, &batch);
    size_t end = batch.count, mismatches = 0, checked = 0;
    for (uint64_t p = 299; p >= 100; p--) {
        one.count = 0;
        gi_detp_trace_photon(&tr, p, &one);
        size_t first = end - one.count;
        for (size_t k = 0; k < one.count; k++, checked++)
            mismatches += !same_segment(&one.v[k], &batch.v[first + k]);
        end = first;
        /* Retracing from any segment of the path gives the same suffix. */
        if (one.count > 2) {
            gi_detp_segments suffix;
            gi_detp_segments_init(&suffix);
            const gi_detp_segment *g = &one.v[1];
            gi_detp_trace_from(&tr, p, g->bounce, g->org, g->dir, g->energy, &suffix);
            GI_CHECK(suffix.count == one.count - 1);
            for (size_t k = 0; k < suffix.count && k + 1 < one.count; k++)
                mismatches += !same_segment(&suffix.v[k], &one.v[k + 1]);
            gi_detp_segments_free(&suffix);
        }
    }
    GI_CHECK(end == 0 && checked == batch.count && mismatches == 0);
    /* Another seed, other paths. */
    gi_detp_tracer tr2;
    gi_detp_tracer_init(&tr2, &rt, &s, 8, 1000, -1, 1);
    one.count = 0;
    gi_detp_trace_photon(&tr2, 100, &one);
    GI_CHECK(!same_segment(&one.v[0], &batch.v[0]));

    gi_detp_segments_free(&batch);
    gi_detp_segments_free(&one);
    gi_rt_free(&rt);
    gi_scene_free(&s);
}

/* A closed room lit from inside: every segment hits something. */
static const char *room(const char *rho)
{
    static char text[1024];
    snprintf(text, sizeof text,
             "{\"materials\": {\"w\": {\"diffuse\": %s},"
             " \"l\": {\"diffuse\": %s, \"emission\": [1, 2, 3]}},"
             " \"objects\": [{\"name\": \"room\", \"material\": \"w\","
             "   \"box\": {\"size\": [2, 2, 2], \"inward\": true}},"
             "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [0.4, 0.4]},"
             "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
             "                   {\"translate\": [0, 0.9, 0]}]}]}",
             rho, rho);
    return text;
}

/* Rule 1's extension behind a thin wall stops short of the floor there,
 * wherever the room is: the second ray used to start off the wall along
 * its normal, by an offset that grows with the distance from the origin,
 * and its hit lay past where the segment's line crosses the floor (a room
 * moved by its own width put 18% of the lit side's light on the dark
 * side's floor). */
GI_TEST(test_detp_extension_stops_before_the_surface_behind_a_wall)
{
    static const double offsets[] = {0, 4, 20, 100};
    for (int k = 0; k < 4; k++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "{\"materials\": {\"w\": {\"diffuse\": [0.7, 0.7, 0.7]},"
                 " \"L\": {\"emission\": [10, 10, 10]}}, \"objects\": ["
                 " {\"name\": \"room\", \"material\": \"w\", \"box\": {\"size\": [4, 4, 4],"
                 "  \"inward\": true}, \"transform\": [{\"translate\": [%g, 0, 0]}]},"
                 " {\"name\": \"lamp\", \"material\": \"L\", \"quad\": {\"size\": [1, 1]},"
                 "  \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
                 "  {\"translate\": [%g, 1.9, 0]}]},"
                 " {\"name\": \"wall\", \"material\": \"w\", \"quad\": {\"size\": [4, 4]},"
                 "  \"transform\": [{\"rotate\": {\"axis\": [0, 0, 1], \"degrees\": 90}},"
                 "  {\"translate\": [%g, 0, 0]}]}]}",
                 offsets[k], offsets[k] + 1, offsets[k]);
        gi_error err;
        gi_scene s;
        GI_REQUIRE_OK(gi_test_load_scene_text("wall.json", text, &s, &err));
        gi_rt rt;
        GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
        gi_detp_tracer tr;
        gi_detp_tracer_init(&tr, &rt, &s, 5, 20000, -1, 1);
        gi_detp_segments segs;
        gi_detp_segments_init(&segs);
        for (uint64_t p = 0; p < 20000; p++)
            gi_detp_trace_photon(&tr, p, &segs);
        gi_detp_set_extent(&segs, GI_DETP_AC_SECOND_HIT, (float)(1e-5 * 4));
        size_t behind = 0, below = 0;
        for (size_t i = 0; i < segs.count; i++) {
            const gi_detp_segment *g = &segs.v[i];
            if (!(g->t_end > g->t_hit) || !isfinite(g->t_end))
                continue;
            gi_vec3 hit = gi_madd(g->org, g->dir, g->t_hit);
            gi_vec3 end = gi_madd(g->org, g->dir, g->t_end);
            if (fabs(hit.x - offsets[k]) < 1e-3 && end.x < offsets[k]) {
                behind++; /* an extension through the wall into the dark side */
                below += end.y < -2.0f;
            }
        }
        GI_CHECK(behind > 100);
        GI_CHECK_MSG(below == 0, "room at x = %g: %zu of %zu extensions behind the wall reach "
                                 "below the floor", offsets[k], below, behind);
        gi_detp_segments_free(&segs);
        gi_rt_free(&rt);
        gi_scene_free(&s);
    }
}

GI_TEST(test_detp_absorb_or_reflect_keeps_photons_equal_and_unbiased)
{
    gi_error err;
    const uint64_t N = 20000;
    for (int colored = 0; colored < 2; colored++) {
        gi_scene s;
        GI_REQUIRE_OK(gi_test_load_scene_text("room.json", room(colored ? "[0.8, 0.4, 0.2]"
                                                                        : "[0.6, 0.6, 0.6]"),
                                              &s, &err));
        gi_rt rt;
        GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
        gi_detp_tracer tr;
        gi_detp_tracer_init(&tr, &rt, &s, 3, N, -1, 0);
        gi_detp_segments seg;
        gi_detp_segments_init(&seg);
        for (uint64_t p = 0; p < N; p++)
            gi_detp_trace_photon(&tr, p, &seg);
        /* Emitted power: Phi_T / N each, in luminance; the emitter's colour. */
        double lum0 = s.total_power / (double)N, escaped = 0, bad_lum = 0;
        double e1[3] = {0, 0, 0}, e0[3] = {0, 0, 0};
        for (size_t k = 0; k < seg.count; k++) {
            const gi_detp_segment *g = &seg.v[k];
            escaped += g->hit_tri == GI_DETP_NO_HIT;
            bad_lum += fabs(gi_luminance(g->energy) / lum0 - 1.0) > 1e-4;
            double *e = g->bounce == 0 ? e0 : g->bounce == 1 ? e1 : NULL;
            if (e) {
                e[0] += g->energy.x;
                e[1] += g->energy.y;
                e[2] += g->energy.z;
            }
        }
        GI_CHECK(escaped < 1e-3 * (double)seg.count && bad_lum == 0);
        GI_CHECK_REL(e0[1] / e0[0], 2.0, 1e-5);
        GI_CHECK_REL(e0[2] / e0[0], 3.0, 1e-5);
        if (!colored) {
            /* Survival rho = 0.6 per bounce: 1 / (1 - rho) = 2.5 segments. */
            GI_CHECK_REL((double)seg.count / N, 2.5, 0.02);
        } else {
            /* After one bounce the expected power is rho times the
             * emitted one, per channel. */
            double rho[3] = {0.8, 0.4, 0.2};
            for (int c = 0; c < 3; c++)
                GI_CHECK_REL(e1[c] / e0[c], rho[c], 0.03);
        }
        gi_detp_segments_free(&seg);
        gi_rt_free(&rt);
        gi_scene_free(&s);
    }
}

/* Edges as (lo, hi) vertex pairs with their use counts. */
static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

GI_TEST(test_detp_refinement_is_conforming_and_keeps_the_surface)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_text(
        "ball.json",
        "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]}, \"l\": {\"emission\": [1, 1, 1]}},"
        " \"objects\": [{\"name\": \"ball\", \"material\": \"w\","
        "   \"sphere\": {\"radius\": 1, \"subdivisions\": 1}},"
        "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [3, 0.5]},"
        "   \"transform\": [{\"translate\": [0, 2, 0]}]}]}",
        &s, &err));
    double area0 = 0;
    for (uint32_t t = 0; t < s.triangle_count; t++)
        area0 += gi_scene_triangle_area(&s, t);
    uint32_t ball_t0 = s.objects[0].triangle_count;
    const double L = 0.13;
    GI_REQUIRE_OK(gi_detp_refine_scene(&s, L, &err));
    GI_CHECK(s.objects[0].triangle_count > 10 * ball_t0);
    double area = 0, longest = 0;
    for (uint32_t t = 0; t < s.triangle_count; t++) {
        area += gi_scene_triangle_area(&s, t);
        for (int k = 0; k < 3; k++) {
            gi_vec3 a = s.positions[s.indices[3 * t + k]], b = s.positions[s.indices[3 * t + (k + 1) % 3]];
            longest = fmax(longest, gi_length(gi_sub(a, b)));
        }
        /* Orientation kept: the face normal agrees with its vertices'. */
        const uint32_t *ix = &s.indices[3 * t];
        gi_vec3 nv = gi_add(gi_add(s.normals[ix[0]], s.normals[ix[1]]), s.normals[ix[2]]);
        GI_CHECK(gi_dot(s.tri_normal[t], gi_normalize(nv)) > 0.9f);
    }
    GI_CHECK(longest <= L);
    GI_CHECK_REL(area, area0, 1e-5);
    /* The ball is still closed: every edge in exactly two triangles (a
     * T-junction would leave edges used once), and V - E + F = 2. */
    const gi_object *o = &s.objects[0];
    uint64_t *e = malloc((size_t)o->triangle_count * 3 * sizeof *e);
    for (uint32_t t = 0; t < o->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = s.indices[3 * (o->first_triangle + t) + k],
                     b = s.indices[3 * (o->first_triangle + t) + (k + 1) % 3];
            e[3 * t + k] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
    size_t ne = (size_t)o->triangle_count * 3;
    qsort(e, ne, sizeof *e, cmp_u64);
    size_t unique = 0, bad = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i;
        while (j < ne && e[j] == e[i])
            j++;
        bad += j - i != 2;
        unique++;
        i = j;
    }
    free(e);
    GI_CHECK_MSG(bad == 0, "%zu edges are not shared by exactly two triangles", bad);
    GI_CHECK((int64_t)o->vertex_count - (int64_t)unique + (int64_t)o->triangle_count == 2);
    /* Light sampling follows the refined emitter. */
    GI_CHECK(s.light_count > 2);
    double spacing = gi_detp_mean_edge(&s);
    GI_CHECK(spacing > 0.3 * L && spacing <= L);
    gi_scene_free(&s);
}

GI_TEST(test_detp_visible_fraction_of_discs_at_walls)
{
    gi_error err;
    gi_scene s;
    /* A floor, a wall standing on it along x = 0, a box standing on it. */
    GI_REQUIRE_OK(gi_test_load_scene_text(
        "walls.json",
        "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5]}, \"l\": {\"emission\": [1, 1, 1]}},"
        " \"objects\": [{\"name\": \"floor\", \"material\": \"w\", \"quad\": {\"size\": [8, 8]}},"
        "  {\"name\": \"wall\", \"material\": \"w\", \"polygons\": {\"vertices\":"
        "   [[0, 0, -4], [0, 0, 4], [0, 2, 4], [0, 2, -4]], \"faces\": [[0, 1, 2, 3]]}},"
        "  {\"name\": \"box\", \"material\": \"w\", \"box\": {\"size\": [1, 1, 1]},"
        "   \"transform\": [{\"translate\": [2, 0.5, 2]}]},"
        "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [1, 1]},"
        "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
        "                   {\"translate\": [1, 3, 0]}]}]}",
        &s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    gi_vec3 up = gi_v3(0, 1, 0);
    gi_detp_disc open = {{2, 0, -2}, up}, at_wall = {{0, 0, 0}, up},
                 near_wall = {{0.25f, 0, 1}, up}, at_box = {{1.5f, 0, 2}, up};
    float f_open = gi_detp_visible_fraction(&rt, &open, 0.5f, gi_v3(1, 0, 0));
    float f_wall = gi_detp_visible_fraction(&rt, &at_wall, 0.5f, gi_v3(1, 0, 0));
    float f_near = gi_detp_visible_fraction(&rt, &near_wall, 0.5f, gi_v3(1, 0, 0));
    float f_box = gi_detp_visible_fraction(&rt, &at_box, 0.5f, gi_v3(-1, 0, 0));
    GI_CHECK(f_open == 1.0f);
    GI_CHECK_NEAR(f_wall, 0.5, 3.0 / 64.0);
    /* Beyond the wall: the circular segment past x = 0 (d/r = 0.5: 19.6%). */
    GI_CHECK_NEAR(f_near, 1.0 - 0.196, 4.0 / 64.0);
    GI_CHECK_NEAR(f_box, 0.5, 3.0 / 64.0);
    gi_rt_free(&rt);
    gi_scene_free(&s);
}
