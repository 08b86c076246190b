/* Unit tests: quasi-static animation (issue 7). A Cornell box with a mobile
 * sphere that moves over 5 frames: the incremental update (thesis Fig. 4.2)
 * against full recomputes in fixed point, its determinism whatever the
 * batch split, untouched paths, a fresh-ray check of every kept segment;
 * the mobile's own vertices; the batch store; a frame's image tiles traced
 * with the mobile alone. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "detp/detp_anim.h"
#include "detp/detp_sphere.h"
#include "gi_fs.h"
#include "gi_job.h"
#include "gi_rt.h"
#include "gi_test.h"
#include "gi_tiles.h"
#include "test_helpers.h"

#define FRAMES 5
#define PHOTONS 3000

typedef struct anim {
    gi_scene s;
    gi_rt rt;
    uint32_t mob;          /* the mobile's object index */
    gi_vec3 *base;         /* its as-loaded positions */
    float eps, radius;
    gi_vec3 step;          /* translation per frame */
    gi_detp_discs discs;   /* every vertex, frame 0 */
} anim;

/* Loads a scene with a mobile object "ball", refines it to max_edge. */
static int anim_load_text(anim *a, const char *name, const char *text, double max_edge,
                          float radius, gi_vec3 step, gi_error *err)
{
    memset(a, 0, sizeof *a);
    if (gi_test_load_scene_text(name, text, &a->s, err) ||
        gi_detp_refine_scene(&a->s, max_edge, err))
        return -1;
    int mob = gi_scene_find_object(&a->s, "ball");
    if (mob < 0 || !a->s.objects[mob].mobile)
        return gi_fail(err, GI_EINVAL, "no mobile ball");
    a->mob = (uint32_t)mob;
    const gi_object *o = &a->s.objects[a->mob];
    a->base = gi_xmalloc(o->vertex_count * sizeof *a->base);
    memcpy(a->base, a->s.positions + o->first_vertex, o->vertex_count * sizeof *a->base);
    a->eps = 1e-5f * (float)gi_detp_scene_size(&a->s);
    a->radius = radius;
    a->step = step;
    if (gi_detp_discs_from_scene(&a->s, a->radius, &a->discs, err))
        return -1;
    return gi_rt_create(&a->rt, &a->s, err);
}

/* The Cornell box with a sphere (radius 60) hanging above the tall block,
 * refined to 30 mm edges, moving by (-25, 0, -15) a frame. */
static int anim_load(anim *a, gi_error *err)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box/scene.json", gi_test_srcdir());
    gi_buf b;
    gi_buf_init(&b);
    if (gi_read_file(path, 1 << 20, &b, err))
        return -1;
    const char *mobile = "{\"name\": \"ball\", \"material\": \"white\", \"mobile\": true,"
                         " \"sphere\": {\"radius\": 60, \"subdivisions\": 2},"
                         " \"transform\": [{\"translate\": [278, 420, 280]}]},";
    const char *key = "\"objects\": [";
    char *at = memmem(b.data, b.len, key, strlen(key));
    if (!at) {
        gi_buf_free(&b);
        return gi_fail(err, GI_EINVAL, "no objects in the Cornell box");
    }
    char *text = gi_xmalloc(b.len + strlen(mobile) + 1);
    size_t head = (size_t)(at - (char *)b.data) + strlen(key);
    memcpy(text, b.data, head);
    strcpy(text + head, mobile);
    memcpy(text + head + strlen(mobile), b.data + head, b.len - head);
    text[b.len + strlen(mobile)] = 0;
    gi_buf_free(&b);
    int rc = anim_load_text(a, "cornell-ball.json", text, 30.0, 15.0f,
                            gi_v3(-25.0f, 0.0f, -15.0f), err);
    free(text);
    return rc;
}

/* A closed room 4 wide with a lamp under its ceiling, the ball (radius
 * 0.5) at (ball_x, -1, 0) moving by `step` a frame, and one static object
 * (JSON) besides. */
static int anim_load_room(anim *a, const char *name, float ball_x, const char *object,
                          gi_vec3 step, gi_error *err)
{
    char text[2048];
    snprintf(text, sizeof text,
             "{\"materials\": {\"w\": {\"diffuse\": [0.6, 0.6, 0.6]},"
             " \"l\": {\"diffuse\": [0, 0, 0], \"emission\": [4, 4, 4]}},"
             " \"objects\": ["
             "  {\"name\": \"ball\", \"material\": \"w\", \"mobile\": true,"
             "   \"sphere\": {\"radius\": 0.5, \"subdivisions\": 2},"
             "   \"transform\": [{\"translate\": [%g, -1, 0]}]},"
             "  {\"name\": \"room\", \"material\": \"w\","
             "   \"box\": {\"size\": [4, 4, 4], \"inward\": true}},"
             "  %s,"
             "  {\"name\": \"lamp\", \"material\": \"l\", \"quad\": {\"size\": [1, 1]},"
             "   \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}},"
             "                   {\"translate\": [0, 1.9, 0]}]}]}",
             (double)ball_x, object);
    return anim_load_text(a, name, text, 0.3, 0.15f, step, err);
}

/* A panel across the middle of the room and the ball moving under it:
 * segments that hit the panel keep their hit while the surface behind it
 * (rule 1's t_second) comes and goes. */
static int anim_load_panel(anim *a, gi_error *err)
{
    return anim_load_room(a, "panel-ball.json", -0.8f,
                          "{\"name\": \"panel\", \"material\": \"w\","
                          " \"quad\": {\"size\": [2.5, 2.5]}}",
                          gi_v3(0.3f, 0.0f, 0.1f), err);
}

/* The ball passing through a static plate (a mobile that cuts into the
 * static scene): rays that hit the ball at one pose may meet the plate
 * before the ball at the next, and the retrace's shortcut (the first hit
 * taken from the mobile alone) must see it. */
static int anim_load_plate(anim *a, gi_error *err)
{
    return anim_load_room(a, "plate-ball.json", -0.6f,
                          "{\"name\": \"plate\", \"material\": \"w\","
                          " \"quad\": {\"size\": [2, 2]},"
                          " \"transform\": [{\"rotate\": {\"axis\": [0, 0, 1], \"degrees\": 90}},"
                          " {\"translate\": [0, -1, 0]}]}",
                          gi_v3(0.25f, 0.0f, 0.05f), err);
}

static void anim_free(anim *a)
{
    gi_rt_free(&a->rt);
    gi_detp_discs_free(&a->discs);
    free(a->base);
    gi_scene_free(&a->s);
}

/* Frame f's pose: the ball translated by f steps. */
static int anim_pose(anim *a, uint32_t f, gi_error *err)
{
    const gi_object *o = &a->s.objects[a->mob];
    gi_vec3 d = gi_scale(a->step, (float)f);
    for (uint32_t i = 0; i < o->vertex_count; i++)
        a->s.positions[o->first_vertex + i] = gi_add(a->base[i], d);
    if (gi_scene_update_derived(&a->s, err))
        return -1;
    return gi_rt_update_object(&a->rt, a->mob, err);
}

static void anim_tracer(anim *a, gi_detp_tracer *tr, uint32_t frame)
{
    gi_detp_tracer_init(tr, &a->rt, &a->s, 11, PHOTONS, -1, 1);
    tr->frame = frame;
}

/* Frame 0 of photons [p0, p1). */
static void trace_batch(anim *a, uint64_t p0, uint64_t p1, gi_detp_segments *out)
{
    gi_detp_tracer tr;
    anim_tracer(a, &tr, 0);
    for (uint64_t p = p0; p < p1; p++)
        gi_detp_trace_photon(&tr, p, out);
    gi_detp_set_extent(out, GI_DETP_AC_SECOND_HIT, a->eps);
}

/* Frame f from frame f-1's segments; the scene is already at pose f and
 * old_pose is the ball's sphere at f-1. */
static int update(anim *a, uint32_t f, gi_detp_mobile_pose old_pose,
                  const gi_detp_segments *prev, gi_detp_segments *next, gi_detp_segments *old_list,
                  gi_detp_segments *new_list, gi_detp_update_stats *st, gi_error *err)
{
    gi_detp_tracer tr;
    anim_tracer(a, &tr, f);
    const gi_object *o = &a->s.objects[a->mob];
    gi_detp_anim_update_in in = {prev->v, prev->count, &tr, o->first_triangle,
                                 o->triangle_count, old_pose,
                                 gi_detp_object_sphere(&a->s, a->mob),
                                 gi_rt_object_scene(&a->rt, a->mob, err),
                                 GI_DETP_AC_SECOND_HIT, a->eps, 0, 0};
    if (!in.mobile_scene)
        return -1;
    return gi_detp_anim_update(&in, next, old_list, new_list, st, err);
}

/* The whole chain for photons [p0, p1), frames 0 .. last, from pose 0
 * (what a worker does when a batch's store file is missing). */
static int chain(anim *a, uint64_t p0, uint64_t p1, uint32_t last, gi_detp_segments *out,
                 gi_error *err)
{
    if (anim_pose(a, 0, err))
        return -1;
    gi_detp_segments cur, next, o, n;
    gi_detp_segments_init(&cur);
    gi_detp_segments_init(&o);
    gi_detp_segments_init(&n);
    trace_batch(a, p0, p1, &cur);
    int rc = 0;
    for (uint32_t f = 1; f <= last && rc == 0; f++) {
        gi_detp_mobile_pose old_pose = gi_detp_object_sphere(&a->s, a->mob);
        gi_detp_update_stats st = {0};
        gi_detp_segments_init(&next);
        o.count = n.count = 0;
        rc = anim_pose(a, f, err) || update(a, f, old_pose, &cur, &next, &o, &n, &st, err);
        gi_detp_segments_free(&cur);
        cur = next;
    }
    for (size_t i = 0; i < cur.count; i++)
        *gi_detp_segments_push(out) = cur.v[i];
    gi_detp_segments_free(&cur);
    gi_detp_segments_free(&o);
    gi_detp_segments_free(&n);
    return rc ? -1 : 0;
}

static int is_mobile_vertex(const anim *a, uint32_t v)
{
    const gi_object *o = &a->s.objects[a->mob];
    return v - o->first_vertex < o->vertex_count;
}

static size_t seg_diff(const gi_detp_segments *x, const gi_detp_segments *y)
{
    if (x->count != y->count)
        return SIZE_MAX;
    size_t d = 0;
    for (size_t i = 0; i < x->count; i++)
        d += memcmp(&x->v[i], &y->v[i], sizeof x->v[i]) != 0;
    return d;
}

/* Fixed-point estimate of segs over every disc (Embree DI). */
static int scratch(anim *a, gi_detp_embree_index *x, double unit, const gi_detp_segments *segs,
                   gi_detp_accum *acc, gi_error *err)
{
    if (gi_detp_accum_init_fixed(acc, a->discs.count, unit, err))
        return -1;
    gi_detp_stats st = {0};
    gi_detp_embree_estimate(x, segs, acc, &st);
    return 0;
}

/* Frames 1 .. FRAMES of one batch, checked against recomputes; then the
 * chain regenerated in two half batches. */
static void check_animation(anim *a, const char *what)
{
    gi_error err;
    const gi_object *mo = &a->s.objects[a->mob];
    double unit = gi_detp_fixed_unit(a->s.total_power, PHOTONS);
    gi_detp_embree_index *x;
    GI_REQUIRE_OK(gi_detp_embree_build(a->rt.device, &a->discs, &x, &err));

    /* Frame 0, and its sums: the running static values. */
    gi_detp_segments cur;
    gi_detp_segments_init(&cur);
    trace_batch(a, 0, PHOTONS, &cur);
    gi_detp_accum run;
    GI_REQUIRE_OK(scratch(a, x, unit, &cur, &run, &err));
    gi_detp_stats est = {0};

    char store[1024];
    snprintf(store, sizeof store, "%s/batch0.gids", gi_test_tmpdir());
    size_t total_retraced = 0, total_paths = 0, kept_checked = 0, kept_bad = 0;
    size_t untouched_bad = 0, static_bad = 0, mobile_bad = 0, second_bad = 0;
    uint64_t second_changed = 0;
    size_t listed_old = 0;
    gi_detp_crossings rec[2];
    memset(rec, 0, sizeof rec);
    gi_detp_segments prev_new; /* the frame before's new segments (rec lists them) */
    gi_detp_segments_init(&prev_new);
    /* The mobile's orders at pose 0, reused at every later pose (as a
     * worker does), and one reversed: any order gives the same sums. */
    gi_detp_sc_params scp = {2.0 / 3.0, 20, 16, GI_DETP_ORDER_HILBERT, 1, 0};
    uint32_t *lanes0, *sc0, *reversed = gi_xmalloc((mo->vertex_count + 1) * sizeof *reversed);
    GI_REQUIRE_OK(gi_detp_anim_mobile_order(&a->s, a->mob, GI_DETP_MOBILE_LANES, NULL, &lanes0,
                                            &err));
    GI_REQUIRE_OK(gi_detp_anim_mobile_order(&a->s, a->mob, GI_DETP_MOBILE_SPHERE_CACHE, &scp,
                                            &sc0, &err));
    for (uint32_t i = 0; i < mo->vertex_count; i++)
        reversed[i] = lanes0[mo->vertex_count - 1 - i];
    for (uint32_t f = 1; f <= FRAMES; f++) {
        /* Through the store, as a worker does between frames. */
        gi_detp_store_header h = {.p0 = 0, .p1 = PHOTONS, .frame = f - 1};
        GI_REQUIRE_OK(gi_detp_store_write(store, &h, &cur, &err));
        gi_detp_store_mapping m;
        GI_REQUIRE(gi_detp_store_map(store, &m, &err) == 1);
        GI_CHECK(m.header.frame == f - 1 && m.count == cur.count);
        gi_detp_segments prev = gi_detp_store_view(&m);
        GI_CHECK(seg_diff(&prev, &cur) == 0);

        gi_detp_mobile_pose old_pose = gi_detp_object_sphere(&a->s, a->mob);
        GI_REQUIRE_OK(anim_pose(a, f, &err));
        gi_detp_segments next, o, n;
        gi_detp_segments_init(&next);
        gi_detp_segments_init(&o);
        gi_detp_segments_init(&n);
        gi_detp_update_stats st = {0};
        GI_REQUIRE_OK(update(a, f, old_pose, &prev, &next, &o, &n, &st, &err));
        GI_CHECK(next.count == prev.count - o.count + n.count);
        GI_CHECK(st.old_segments == o.count && st.new_segments == n.count);
        GI_CHECK_MSG(st.paths_retraced > 0 && st.paths_retraced < st.paths,
                     "frame %u: %llu of %llu paths retraced", f,
                     (unsigned long long)st.paths_retraced, (unsigned long long)st.paths);
        GI_CHECK(st.sphere_passes < st.segments / 2); /* the pre-test does cull */
        total_retraced += st.paths_retraced;
        second_changed += st.second_changed;
        if (getenv("GI_TEST_VERBOSE"))
            printf("%s frame %u: paths %llu retraced %llu, segments %llu: sphere passes %llu,"
                   " mobile hits %llu, old hits %llu, t_second %llu/%llu; old %zu new %zu\n",
                   what ? what : "cornell", f, (unsigned long long)st.paths,
                   (unsigned long long)st.paths_retraced, (unsigned long long)st.segments,
                   (unsigned long long)st.sphere_passes, (unsigned long long)st.mobile_hits,
                   (unsigned long long)st.old_hits, (unsigned long long)st.second_changed,
                   (unsigned long long)st.second_tests, o.count, n.count);
        total_paths += st.paths;

        /* Untouched paths: bit-identical; retraced ones: the same prefix. */
        size_t ip = 0, in_ = 0, io = 0;
        while (ip < prev.count) {
            uint64_t ph = prev.v[ip].photon;
            size_t ep = ip, en = in_;
            while (ep < prev.count && prev.v[ep].photon == ph)
                ep++;
            while (en < next.count && next.v[en].photon == ph)
                en++;
            int touched = io < o.count && o.v[io].photon == ph;
            while (io < o.count && o.v[io].photon == ph)
                io++;
            if (!touched) {
                gi_detp_segments pa = {prev.v + ip, ep - ip, 0}, na = {next.v + in_, en - in_, 0};
                untouched_bad += seg_diff(&pa, &na) != 0;
            }
            ip = ep;
            in_ = en;
        }
        GI_CHECK(in_ == next.count && io == o.count);

        /* Every segment of next against a fresh ray at the new pose: the
         * pre-tests missed nothing. */
        gi_detp_tracer tr;
        anim_tracer(a, &tr, f);
        for (size_t i = 0; i < next.count; i++) {
            const gi_detp_segment *g = &next.v[i];
            gi_hit hit;
            int got = gi_rt_intersect(&a->rt, g->org, g->dir, 0.0f, FLT_MAX, &hit);
            kept_checked++;
            if (got != (g->hit_tri != GI_DETP_NO_HIT) ||
                (got && (hit.tri != g->hit_tri || hit.t != g->t_hit))) {
                kept_bad++;
                continue;
            }
            if (!got)
                continue;
            /* t_second as the tracer computes it, at this pose. */
            float t2 = gi_detp_second_t(&tr, g->org, g->dir, g->t_hit, g->hit_tri);
            second_bad += !(t2 == g->t_second || (isinf(t2) && isinf(g->t_second)));
        }

        /* Static discs: running sums + new - old == recompute over next.
         * The new segments' crossings are listed; an old segment that the
         * frame before added takes back its listed crossings (as a worker
         * does), the others are searched. */
        run.sign = 1;
        gi_detp_embree_estimate_listed(x, &n, &run, &est, &rec[f & 1]);
        run.sign = -1;
        gi_detp_segments unlisted;
        gi_detp_segments_init(&unlisted);
        const gi_detp_crossings *was = &rec[(f - 1) & 1];
        for (size_t k = 0, j = 0; k < o.count; k++) {
            const gi_detp_segment *g = &o.v[k];
            while (j < prev_new.count && (prev_new.v[j].photon < g->photon ||
                                          (prev_new.v[j].photon == g->photon &&
                                           prev_new.v[j].bounce < g->bounce)))
                j++;
            if (f > 1 && j < prev_new.count && memcmp(&prev_new.v[j], g, sizeof *g) == 0) {
                gi_detp_crossings_apply(g, was->ids + was->off[j],
                                        was->off[j + 1] - was->off[j], &run, &est);
                listed_old++;
            } else {
                *gi_detp_segments_push(&unlisted) = *g;
            }
        }
        gi_detp_embree_estimate(x, &unlisted, &run, &est);
        gi_detp_segments_free(&unlisted);
        prev_new.count = 0;
        for (size_t k = 0; k < n.count; k++)
            *gi_detp_segments_push(&prev_new) = n.v[k];
        gi_detp_accum full;
        GI_REQUIRE_OK(scratch(a, x, unit, &next, &full, &err));
        for (uint32_t v = 0; v < a->discs.count; v++) {
            if (is_mobile_vertex(a, v))
                continue;
            static_bad += memcmp(&run.fixed[3 * (size_t)v], &full.fixed[3 * (size_t)v],
                                 3 * sizeof(int64_t)) != 0 ||
                          run.hits[v] != full.hits[v];
        }
        if (f == FRAMES) {
            /* And against basic DETP, another estimator: the same pairs. */
            gi_detp_accum basic;
            GI_REQUIRE_OK(gi_detp_accum_init_fixed(&basic, a->discs.count, unit, &err));
            gi_detp_basic(&a->discs, &next, &basic, &est);
            for (uint32_t v = 0; v < a->discs.count; v++)
                if (!is_mobile_vertex(a, v))
                    static_bad += memcmp(&run.fixed[3 * (size_t)v], &basic.fixed[3 * (size_t)v],
                                         3 * sizeof(int64_t)) != 0;
            gi_detp_accum_free(&basic);
        }
        gi_detp_accum_free(&full);

        /* The mobile's vertices from scratch at the new pose: Sphere Cache,
         * Embree DI and lanes of each width the CPU has against basic DETP
         * over discs of the ball. */
        gi_detp_discs md;
        GI_REQUIRE_OK(gi_detp_discs_from_scene(&a->s, a->radius, &md, &err));
        gi_detp_accum ref, sc, em, ln[3];
        GI_REQUIRE_OK(gi_detp_accum_init_fixed(&ref, md.count, unit, &err));
        GI_REQUIRE_OK(gi_detp_accum_init_fixed(&sc, md.count, unit, &err));
        GI_REQUIRE_OK(gi_detp_accum_init_fixed(&em, md.count, unit, &err));
        gi_detp_discs only = {mo->vertex_count, md.d + mo->first_vertex, md.radius, md.r2};
        gi_detp_accum refv = ref;
        refv.fixed += 3 * (size_t)mo->first_vertex;
        refv.hits += mo->first_vertex;
        gi_detp_basic(&only, &next, &refv, &est);
        /* The discs in 4, 8, 16 lanes (detp_lanes.c), in this pose's
         * order, pose 0's reversed and pose 0's. */
        const uint32_t *lane_order[3] = {NULL, reversed, lanes0};
        for (int w = 0; w < 3; w++) {
            GI_REQUIRE_OK(gi_detp_accum_init_fixed(&ln[w], md.count, unit, &err));
            gi_detp_accum lnv = ln[w];
            lnv.fixed += 3 * (size_t)mo->first_vertex;
            lnv.hits += mo->first_vertex;
            gi_detp_lanes_estimate_width(&only, lane_order[w], &next, &lnv, &est, 4u << w);
        }
        size_t other = 3 * (size_t)(md.count - 1); /* not the ball's: must stay */
        GI_REQUIRE(!is_mobile_vertex(a, md.count - 1));
        sc.fixed[other] = 12345;
        GI_REQUIRE_OK(gi_detp_anim_mobile_estimate(&a->s, a->mob, a->radius, &next,
                                                   GI_DETP_MOBILE_SPHERE_CACHE, &scp, sc0, NULL,
                                                   &sc, &est, &err));
        GI_REQUIRE_OK(gi_detp_anim_mobile_estimate(&a->s, a->mob, a->radius, &next,
                                                   GI_DETP_MOBILE_EMBREE, NULL, NULL,
                                                   a->rt.device, &em, &est, &err));
        uint64_t lit = 0;
        for (uint32_t v = mo->first_vertex; v < mo->first_vertex + mo->vertex_count; v++) {
            mobile_bad += memcmp(&ref.fixed[3 * (size_t)v], &sc.fixed[3 * (size_t)v], 24) != 0 ||
                          memcmp(&ref.fixed[3 * (size_t)v], &em.fixed[3 * (size_t)v], 24) != 0 ||
                          ref.hits[v] != sc.hits[v] || ref.hits[v] != em.hits[v];
            for (int w = 0; w < 3; w++)
                mobile_bad += memcmp(&ref.fixed[3 * (size_t)v], &ln[w].fixed[3 * (size_t)v],
                                     24) != 0 ||
                              ref.hits[v] != ln[w].hits[v];
            lit += ref.hits[v];
        }
        GI_CHECK(lit > 0 && sc.fixed[other] == 12345);
        gi_detp_accum_free(&ref);
        gi_detp_accum_free(&sc);
        gi_detp_accum_free(&em);
        for (int w = 0; w < 3; w++)
            gi_detp_accum_free(&ln[w]);
        gi_detp_discs_free(&md);

        gi_detp_store_unmap(&m);
        gi_detp_segments_free(&cur);
        gi_detp_segments_free(&o);
        gi_detp_segments_free(&n);
        cur = next;
    }
    GI_CHECK_MSG(untouched_bad == 0, "%zu untouched paths changed", untouched_bad);
    GI_CHECK_MSG(kept_bad == 0, "%zu of %zu segments disagree with a fresh ray", kept_bad,
                 kept_checked);
    GI_CHECK_MSG(second_bad == 0, "%zu segments have a stale t_second", second_bad);
    GI_CHECK_MSG(static_bad == 0, "%zu static discs differ from the recompute", static_bad);
    GI_CHECK_MSG(mobile_bad == 0, "%zu mobile discs differ from basic DETP", mobile_bad);
    GI_CHECK(total_retraced > 0 && total_retraced < total_paths);
    GI_CHECK_MSG(listed_old > 0, "no old segment took back listed crossings");
    gi_detp_crossings_free(&rec[0]);
    gi_detp_crossings_free(&rec[1]);
    gi_detp_segments_free(&prev_new);
    free(lanes0);
    free(sc0);
    free(reversed);

    /* Regenerated from frame 0, in two half batches: the same frame. */
    gi_detp_segments halves;
    gi_detp_segments_init(&halves);
    GI_REQUIRE_OK(chain(a, 0, PHOTONS / 2, FRAMES, &halves, &err));
    GI_REQUIRE_OK(chain(a, PHOTONS / 2, PHOTONS, FRAMES, &halves, &err));
    GI_CHECK_MSG(seg_diff(&halves, &cur) == 0, "regenerated halves differ: %zu",
                 seg_diff(&halves, &cur));

    gi_detp_segments_free(&halves);
    gi_detp_segments_free(&cur);
    gi_detp_accum_free(&run);
    gi_detp_embree_free(x);
    if (what && !second_changed)
        gi_test_failed(__FILE__, __LINE__, "%s: no t_second changed (not exercised)", what);
}

GI_TEST(test_detp_anim_incremental_update_is_exact)
{
    gi_error err;
    anim a;
    GI_REQUIRE_OK(anim_load(&a, &err));
    check_animation(&a, NULL);
    anim_free(&a);
    GI_REQUIRE_OK(anim_load_panel(&a, &err));
    check_animation(&a, "panel");
    anim_free(&a);
    GI_REQUIRE_OK(anim_load_plate(&a, &err));
    check_animation(&a, "plate");
    anim_free(&a);
}

/* A moved object's BVH is refit, not rebuilt (gi_rt.c): its hits at a pose
 * must not depend on the poses before, or workers that saw different frames
 * would trace different paths. Two ray tracers of one scene, one posed at
 * frames 1, 2, 3, 7 and 3 again, the other at 3 only: the same hits, bit for
 * bit, for rays aimed at the ball and at random. */
GI_TEST(test_detp_anim_moved_object_hits_do_not_depend_on_earlier_poses)
{
    gi_error err;
    anim a, b;
    GI_REQUIRE_OK(anim_load(&a, &err));
    GI_REQUIRE_OK(anim_load(&b, &err));
    const uint32_t path[] = {1, 2, 3, 7, 3};
    for (size_t i = 0; i < sizeof path / sizeof *path; i++)
        GI_REQUIRE_OK(anim_pose(&a, path[i], &err));
    GI_REQUIRE_OK(anim_pose(&b, 3, &err));
    gi_detp_mobile_pose ball = gi_detp_object_sphere(&b.s, b.mob);
    const gi_object *o = &b.s.objects[b.mob];
    gi_rng r;
    gi_rng_init(&r, 5, 77, 0);
    size_t differ = 0, on_ball = 0;
    for (int k = 0; k < 20000; k++) {
        gi_vec3 org = gi_v3(555.0f * gi_rng_float(&r), 548.0f * gi_rng_float(&r),
                            559.0f * gi_rng_float(&r));
        gi_vec3 aim = gi_v3(gi_rng_float(&r) - 0.5f, gi_rng_float(&r) - 0.5f,
                            gi_rng_float(&r) - 0.5f);
        aim = k % 2 ? gi_add(ball.c, gi_scale(aim, 2.0f * ball.r))
                    : gi_add(org, aim); /* towards the ball, or anywhere */
        gi_vec3 dir = gi_normalize(gi_sub(aim, org));
        gi_hit ha, hb;
        memset(&ha, 0, sizeof ha);
        memset(&hb, 0, sizeof hb);
        int got_a = gi_rt_intersect(&a.rt, org, dir, 0.0f, FLT_MAX, &ha);
        int got_b = gi_rt_intersect(&b.rt, org, dir, 0.0f, FLT_MAX, &hb);
        differ += got_a != got_b || (got_b && (memcmp(&ha.t, &hb.t, sizeof ha.t) != 0 ||
                                               ha.tri != hb.tri ||
                                               memcmp(&ha.u, &hb.u, sizeof ha.u) != 0 ||
                                               memcmp(&ha.v, &hb.v, sizeof ha.v) != 0));
        on_ball += got_b && hb.tri - o->first_triangle < o->triangle_count;
    }
    GI_CHECK_MSG(differ == 0, "%zu of 20000 rays differ", differ);
    GI_CHECK_MSG(on_ball > 5000, "only %zu rays hit the ball", on_ball);
    anim_free(&a);
    anim_free(&b);
}

/* Rule 1's ray behind a hit on the mobile, traced against the mobile alone
 * when nothing else comes within its sphere (gi_detp_tracer.mobile_alone):
 * the same segments, bit for bit, as through the whole scene. The ball
 * hanging over the tall block is clear of it by 30 mm; grown by 40 it is
 * not, nor is the ball through the plate. */
GI_TEST(test_detp_anim_rays_behind_the_mobile_alone_are_the_scenes)
{
    gi_error err;
    anim a;
    GI_REQUIRE_OK(anim_load(&a, &err));
    const gi_object *o = &a.s.objects[a.mob];
    gi_detp_mobile_pose ball = gi_detp_object_sphere(&a.s, a.mob);
    GI_CHECK(!gi_rt_others_near(&a.rt, a.mob, ball.c, ball.r * 1.01f + 1.0f));
    GI_CHECK(gi_rt_others_near(&a.rt, a.mob, ball.c, ball.r + 40.0f));
    gi_detp_segments whole, alone;
    gi_detp_segments_init(&whole);
    gi_detp_segments_init(&alone);
    gi_detp_tracer tw, ta;
    anim_tracer(&a, &tw, 0);
    anim_tracer(&a, &ta, 0);
    ta.mobile_alone = gi_rt_object_scene(&a.rt, a.mob, &err);
    GI_REQUIRE(ta.mobile_alone != NULL);
    ta.mobile_first = o->first_triangle;
    ta.mobile_count = o->triangle_count;
    uint64_t rays0 = a.rt.rays;
    for (uint64_t p = 0; p < PHOTONS; p++)
        gi_detp_trace_photon(&tw, p, &whole);
    uint64_t rays_whole = a.rt.rays - rays0;
    for (uint64_t p = 0; p < PHOTONS; p++)
        gi_detp_trace_photon(&ta, p, &alone);
    uint64_t rays_alone = a.rt.rays - rays0 - rays_whole;
    size_t behind = 0;
    for (size_t i = 0; i < whole.count; i++)
        behind += whole.v[i].hit_tri - o->first_triangle < o->triangle_count &&
                  isfinite(whole.v[i].t_second);
    GI_CHECK_MSG(seg_diff(&whole, &alone) == 0, "%zu segments differ",
                 seg_diff(&whole, &alone));
    GI_CHECK_MSG(behind > 50 && rays_whole - rays_alone == behind,
                 "%zu rays behind the ball, %llu fewer through the scene", behind,
                 (unsigned long long)(rays_whole - rays_alone));
    gi_detp_segments_free(&whole);
    gi_detp_segments_free(&alone);
    anim_free(&a);

    GI_REQUIRE_OK(anim_load_plate(&a, &err));
    ball = gi_detp_object_sphere(&a.s, a.mob);
    GI_CHECK(!gi_rt_others_near(&a.rt, a.mob, ball.c, ball.r)); /* 0.1 short of it */
    GI_REQUIRE_OK(anim_pose(&a, 2, &err));                       /* through it */
    ball = gi_detp_object_sphere(&a.s, a.mob);
    GI_CHECK(gi_rt_others_near(&a.rt, a.mob, ball.c, ball.r));
    anim_free(&a);
}

/* A pixel's "radiance" is the hit itself (triangle, u, v): any difference
 * in the hits shows. */
static gi_vec3 hit_shader(void *user, const gi_hit *h, gi_vec3 p, gi_vec3 wo)
{
    (void)user;
    (void)p;
    (void)wo;
    return gi_v3((float)h->tri, h->u, h->v);
}

/* An animation frame's tiles split at the mobile (gi_tile_render_split):
 * the rest's hits traced at frame 0 and reused at frames 1-4 give, frame
 * for frame, the pixels of tiles traced through the whole scene, bit for
 * bit, with the ball in view, moving and partly hidden, and later frames
 * trace only the rays that come near the ball. */
GI_TEST(test_detp_anim_tiles_split_at_the_mobile_are_the_whole_scenes)
{
    gi_error err;
    anim a;
    GI_REQUIRE_OK(anim_load(&a, &err));
    /* Down through the frames until it sinks into the floor: part of the
     * ball hides behind the floor. */
    a.step = gi_v3(0.0f, -100.0f, 0.0f);
    const gi_object *o = &a.s.objects[a.mob];
    gi_job job;
    memset(&job, 0, sizeof job);
    job.scene = a.s; /* borrowed: not freed through job */
    job.width = 48;
    job.height = 32;
    job.seed = 5;
    enum { SPP = 2, TILE = 16 };
    size_t npix = (size_t)job.width * job.height;
    gi_tile_hit *rest = gi_xcalloc(npix * SPP, sizeof *rest);
    float *prev = gi_xcalloc(npix * 3, sizeof *prev);
    size_t differing = 0, changed_by_moving = 0, ball_pixels = 0;
    uint64_t split_rays = 0;
    for (uint32_t f = 0; f < FRAMES; f++) {
        GI_REQUIRE_OK(anim_pose(&a, f, &err));
        gi_detp_mobile_pose ball = gi_detp_object_sphere(&a.s, a.mob);
        size_t at = 0;
        for (int y0 = 0; y0 < job.height; y0 += TILE)
            for (int x0 = 0; x0 < job.width; x0 += TILE) {
                gi_tile t = {(uint32_t)x0, (uint32_t)y0, (uint32_t)(x0 + TILE),
                             (uint32_t)(y0 + TILE)};
                gi_buf whole, split;
                gi_buf_init(&whole);
                gi_buf_init(&split);
                const gi_camera *cam = gi_job_camera(&job);
                GI_REQUIRE_OK(gi_tile_render(&a.rt, &job, cam, &t, SPP, hit_shader, NULL, &whole,
                                             &err));
                uint64_t r0 = a.rt.rays;
                GI_REQUIRE_OK(gi_tile_render_split(&a.rt, &job, cam, &t, SPP, a.mob, ball.c, ball.r,
                                                   rest + at, f > 0, hit_shader, NULL, &split,
                                                   &err));
                if (f > 0)
                    split_rays += a.rt.rays - r0;
                /* Any sphere that holds the ball will do; a loose one
                 * sends rays that pass the ball's hit on to the ball. */
                gi_buf loose;
                gi_buf_init(&loose);
                GI_REQUIRE_OK(gi_tile_render_split(&a.rt, &job, cam, &t, SPP, a.mob, ball.c,
                                                   8.0f * ball.r, rest + at, 1, hit_shader, NULL,
                                                   &loose, &err));
                at += (size_t)TILE * TILE * SPP;
                GI_REQUIRE(whole.len == split.len && whole.len == loose.len);
                differing += memcmp(whole.data, split.data, whole.len) != 0;
                differing += memcmp(whole.data, loose.data, whole.len) != 0;
                gi_buf_free(&loose);
                const float *px = (const float *)split.data;
                for (int k = 0; k < TILE * TILE; k++) {
                    size_t i = (size_t)(y0 + k / TILE) * job.width + (size_t)(x0 + k % TILE);
                    float tri = px[3 * k];
                    ball_pixels += tri >= (float)o->first_triangle &&
                                   tri < (float)(o->first_triangle + o->triangle_count);
                    changed_by_moving += f > 0 && memcmp(&prev[3 * i], &px[3 * k], 12) != 0;
                    memcpy(&prev[3 * i], &px[3 * k], 12);
                }
                gi_buf_free(&whole);
                gi_buf_free(&split);
            }
    }
    GI_CHECK_MSG(differing == 0, "%zu tiles differ", differing);
    GI_CHECK_MSG(ball_pixels > 100 && changed_by_moving > 50, "ball in %zu pixels, %zu changed",
                 ball_pixels, changed_by_moving);
    GI_CHECK_MSG(split_rays > 0 && split_rays < npix * SPP * (FRAMES - 1) / 4,
                 "%llu rays in frames 1-4", (unsigned long long)split_rays);
    free(rest);
    free(prev);
    anim_free(&a);
}

/* Every segment that crosses one of the mobile's discs comes within
 * gi_detp_object_disc_reach of its centre: lines shot at the ball with
 * discs nearly its size (where the reach is well under R + radius, and
 * segments that miss the ball still cross discs that stick out of it)
 * count the same pairs whether or not the far ones are dropped. */
GI_TEST(test_detp_anim_disc_reach_holds_every_crossing)
{
    gi_error err;
    anim a;
    GI_REQUIRE_OK(anim_load(&a, &err));
    const gi_object *mo = &a.s.objects[a.mob];
    float radius = 50.0f;
    gi_detp_mobile_pose b = gi_detp_object_sphere(&a.s, a.mob);
    float reach = gi_detp_object_disc_reach(&a.s, a.mob, b, radius);
    float tangent = sqrtf(b.r * b.r + radius * radius);
    GI_CHECK_MSG(reach >= tangent * 0.999f && reach < tangent * 1.01f && reach < b.r + radius,
                 "reach %g: a sphere of radius %g with discs of %g", reach, b.r, radius);
    gi_detp_discs md;
    GI_REQUIRE_OK(gi_detp_discs_from_scene(&a.s, radius, &md, &err));
    gi_detp_discs only = {mo->vertex_count, md.d + mo->first_vertex, md.radius, md.r2};
    gi_detp_segments all, near;
    gi_detp_segments_init(&all);
    gi_detp_segments_init(&near);
    gi_rng r;
    gi_rng_init(&r, 17, 0, 0);
    for (int k = 0; k < 20000; k++) {
        /* From a sphere of 4R towards a point within 1.5 reach of the centre. */
        gi_vec3 from = gi_test_random_dir(&r), to = gi_test_random_dir(&r);
        gi_detp_segment *g = gi_detp_segments_push(&all);
        memset(g, 0, sizeof *g);
        g->org = gi_madd(b.c, from, 4.0f * b.r);
        gi_vec3 aim = gi_madd(b.c, to, 1.5f * reach * gi_rng_float(&r));
        g->dir = gi_normalize(gi_sub(aim, g->org));
        g->t_hit = g->t_second = g->t_end = 8.0f * b.r;
        g->energy = gi_v3(1.0f, 0.5f, 0.25f);
        g->hit_tri = GI_DETP_NO_HIT;
        g->photon = (uint64_t)k;
    }
    float rr = reach + gi_detp_sphere_slack(reach);
    size_t outside = 0; /* crossing segments that miss the ball's sphere */
    for (size_t j = 0; j < all.count; j++) {
        if (gi_detp_segment_meets_sphere(&all.v[j], b.c, rr * rr))
            *gi_detp_segments_push(&near) = all.v[j];
        if (gi_detp_segment_meets_sphere(&all.v[j], b.c, b.r * b.r))
            continue;
        for (uint32_t i = 0; i < only.count; i++)
            if (gi_detp_crosses(&only.d[i], only.r2, &all.v[j])) {
                outside++;
                break;
            }
    }
    gi_detp_accum ref, cut;
    double unit = gi_detp_fixed_unit(1e4, 1000);
    GI_REQUIRE_OK(gi_detp_accum_init_fixed(&ref, only.count, unit, &err));
    GI_REQUIRE_OK(gi_detp_accum_init_fixed(&cut, only.count, unit, &err));
    gi_detp_stats st;
    memset(&st, 0, sizeof st);
    gi_detp_basic(&only, &all, &ref, &st);
    uint64_t crossings = st.crossings;
    gi_detp_basic(&only, &near, &cut, &st);
    GI_CHECK_MSG(outside > 100 && near.count < all.count, "%zu outside, %zu of %zu near",
                 outside, near.count, all.count);
    GI_CHECK(crossings > 0 && st.crossings == 2 * crossings);
    GI_CHECK(memcmp(ref.fixed, cut.fixed, 3 * (size_t)only.count * sizeof *ref.fixed) == 0 &&
             memcmp(ref.hits, cut.hits, (size_t)only.count * sizeof *ref.hits) == 0);
    gi_detp_accum_free(&ref);
    gi_detp_accum_free(&cut);
    gi_detp_segments_free(&all);
    gi_detp_segments_free(&near);
    gi_detp_discs_free(&md);
    anim_free(&a);
}

GI_TEST(test_detp_anim_fixed_point_and_frame_streams)
{
    /* Fixed-point sums cancel exactly whatever the order. */
    gi_error err;
    gi_detp_accum a;
    GI_REQUIRE_OK(gi_detp_accum_init_fixed(&a, 2, gi_detp_fixed_unit(10.0, 1000), &err));
    GI_CHECK(a.inv_unit == ldexp(100.0, 32));
    gi_detp_segment s[3];
    memset(s, 0, sizeof s);
    s[0].energy = gi_v3(0.01f, 0.02f, 0.003f);
    s[1].energy = gi_v3(0.0123f, 1e-9f, 0.5f);
    s[2].energy = gi_v3(7.0f, 0.0f, 0.25f);
    for (int k = 0; k < 3; k++)
        gi_detp_accum_add(&a, 1, &s[k]);
    GI_CHECK(a.hits[1] == 3 && a.fixed[3] == llround(0.01f * ldexp(100.0, 32)) +
                                                 llround(0.0123f * ldexp(100.0, 32)) +
                                                 llround(7.0f * ldexp(100.0, 32)));
    a.sign = -1;
    gi_detp_accum_add(&a, 1, &s[1]);
    gi_detp_accum_add(&a, 1, &s[2]);
    gi_detp_accum_add(&a, 1, &s[0]);
    GI_CHECK(a.hits[1] == 0 && a.fixed[3] == 0 && a.fixed[4] == 0 && a.fixed[5] == 0);
    GI_CHECK(a.energy == NULL && a.fixed[0] == 0 && a.hits[0] == 0);
    gi_detp_accum_free(&a);

    /* Frame 0 is the still stream; another frame changes reflections but
     * not emission. */
    anim m;
    GI_REQUIRE_OK(anim_load(&m, &err));
    gi_detp_tracer t0, t1, t2;
    gi_detp_tracer_init(&t0, &m.rt, &m.s, 11, PHOTONS, -1, 1);
    anim_tracer(&m, &t1, 0);
    anim_tracer(&m, &t2, 3);
    gi_detp_segments p0, p1, p2;
    gi_detp_segments_init(&p0);
    gi_detp_segments_init(&p1);
    gi_detp_segments_init(&p2);
    size_t first_same = 0, later_differ = 0;
    for (uint64_t p = 0; p < 200; p++) {
        p0.count = p1.count = p2.count = 0;
        gi_detp_trace_photon(&t0, p, &p0);
        gi_detp_trace_photon(&t1, p, &p1);
        gi_detp_trace_photon(&t2, p, &p2);
        GI_CHECK(seg_diff(&p0, &p1) == 0);
        first_same += memcmp(&p0.v[0], &p2.v[0], sizeof p0.v[0]) == 0;
        later_differ += seg_diff(&p0, &p2) != 0;
    }
    GI_CHECK(first_same == 200 && later_differ > 50);
    gi_detp_segments_free(&p0);
    gi_detp_segments_free(&p1);
    gi_detp_segments_free(&p2);
    anim_free(&m);
}

/* A damaged file: plain write, no fsync (hundreds of them). */
static int put_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int rc = fwrite(data, 1, len, f) != len;
    return fclose(f) || rc ? -1 : 0;
}

GI_TEST(test_detp_anim_store_round_trip_and_damage)
{
    gi_error err;
    gi_detp_segments s;
    gi_detp_segments_init(&s);
    for (uint64_t p = 100; p < 140; p++)
        for (uint32_t b = 0; b < 1 + p % 4; b++) {
            gi_detp_segment *g = gi_detp_segments_push(&s);
            g->org = gi_v3((float)p, (float)b, 1.0f);
            g->dir = gi_v3(0, 1, 0);
            g->t_hit = b == p % 4 ? INFINITY : 2.0f + (float)b;
            g->t_second = g->t_end = g->t_hit;
            g->energy = gi_v3(0.5f, 0.25f, 0.125f);
            g->hit_tri = b == p % 4 ? GI_DETP_NO_HIT : (uint32_t)(p + b);
            g->bounce = b;
            g->photon = p;
        }
    char path[1024];
    snprintf(path, sizeof path, "%s/b.gids", gi_test_tmpdir());
    gi_detp_store_header h = {.p0 = 100, .p1 = 140, .frame = 7};
    GI_REQUIRE_OK(gi_detp_store_write(path, &h, &s, &err));
    gi_detp_store_mapping m;
    GI_REQUIRE(gi_detp_store_map(path, &m, &err) == 1);
    GI_CHECK(m.header.p0 == 100 && m.header.p1 == 140 && m.header.frame == 7 &&
             m.count == s.count);
    GI_CHECK(memcmp(m.seg, s.v, s.count * sizeof *s.v) == 0);
    gi_detp_store_unmap(&m);

    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(path, 1 << 24, &b, &err));
    GI_CHECK(b.len == 64 + 64 * s.count);
    char bad[1024];
    snprintf(bad, sizeof bad, "%s/bad.gids", gi_test_tmpdir());
    /* Every byte flipped in turn (header and a sample of the records),
     * then every truncation: all "missing", none mapped. */
    size_t mapped = 0, io_errors = 0, tried = 0;
    for (size_t i = 0; i < b.len; i += i < 64 ? 1 : 61) {
        b.data[i] ^= 0x10;
        GI_REQUIRE(put_file(bad, b.data, b.len) == 0);
        b.data[i] ^= 0x10;
        int rc = gi_detp_store_map(bad, &m, &err);
        mapped += rc == 1;
        io_errors += rc < 0;
        tried++;
        if (rc == 1)
            gi_detp_store_unmap(&m);
    }
    for (size_t len = 0; len < b.len; len += len < 70 ? 1 : 37) {
        GI_REQUIRE(put_file(bad, b.data, len) == 0);
        int rc = gi_detp_store_map(bad, &m, &err);
        mapped += rc == 1;
        io_errors += rc < 0;
        tried++;
        if (rc == 1)
            gi_detp_store_unmap(&m);
    }
    GI_CHECK_MSG(mapped == 0 && io_errors == 0, "%zu of %zu damaged files mapped, %zu errors",
                 mapped, tried, io_errors);
    /* Missing; valid CRCs but records out of path order or outside the
     * batch. */
    snprintf(bad, sizeof bad, "%s/none.gids", gi_test_tmpdir());
    GI_CHECK(gi_detp_store_map(bad, &m, &err) == 0);
    gi_detp_segment t = s.v[1];
    s.v[1] = s.v[2];
    s.v[2] = t;
    GI_REQUIRE_OK(gi_detp_store_write(path, &h, &s, &err));
    GI_CHECK(gi_detp_store_map(path, &m, &err) == 0);
    s.v[2] = s.v[1];
    s.v[1] = t;
    h.p1 = 120;
    GI_REQUIRE_OK(gi_detp_store_write(path, &h, &s, &err));
    GI_CHECK(gi_detp_store_map(path, &m, &err) == 0);
    /* An empty batch is valid. */
    s.count = 0;
    GI_REQUIRE_OK(gi_detp_store_write(path, &h, &s, &err));
    GI_CHECK(gi_detp_store_map(path, &m, &err) == 1 && m.count == 0);
    gi_detp_store_unmap(&m);
    gi_buf_free(&b);
    gi_detp_segments_free(&s);
}
