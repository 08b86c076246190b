/* Unit tests: every DETP estimator finds the same (segment, disc) pairs as
 * basic DETP, so disc energies agree - exactly, since each disc's sum is
 * taken in segment order whatever found the pairs. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp/detp.h"
#include "gi_rng.h"
#include "gi_test.h"

static gi_vec3 random_unit(gi_rng *r)
{
    float z = 2.0f * gi_rng_float(r) - 1.0f, phi = (float)(2.0 * GI_PI) * gi_rng_float(r);
    float s = sqrtf(gi_maxf(0.0f, 1.0f - z * z));
    return gi_v3(s * cosf(phi), s * sinf(phi), z);
}

static gi_vec3 random_point(gi_rng *r)
{
    return gi_v3(gi_rng_float(r), gi_rng_float(r), gi_rng_float(r));
}

/* n discs in the unit cube: most anywhere with any normal; a quarter on the
 * plane z = 0.5 facing +z, where a quarter of the segments end exactly (the
 * case the extent's margin is for). */
static void make_discs(gi_detp_discs *d, uint32_t n, float radius, uint64_t seed)
{
    gi_rng r;
    gi_rng_init(&r, seed, 1, 0);
    d->count = n;
    d->d = gi_xcalloc(n, sizeof *d->d);
    d->radius = radius;
    d->r2 = radius * radius;
    for (uint32_t i = 0; i < n; i++) {
        if (i % 4 == 0) {
            d->d[i].c = gi_v3(gi_rng_float(&r), gi_rng_float(&r), 0.5f);
            d->d[i].n = gi_v3(0, 0, 1);
        } else {
            d->d[i].c = random_point(&r);
            d->d[i].n = random_unit(&r);
        }
    }
}

static void make_segments(gi_detp_segments *s, uint32_t n, gi_detp_artifact ac, uint64_t seed)
{
    gi_rng r;
    gi_rng_init(&r, seed, 2, 0);
    gi_detp_segments_init(s);
    for (uint32_t i = 0; i < n; i++) {
        gi_detp_segment *g = gi_detp_segments_push(s);
        g->org = gi_add(gi_scale(random_point(&r), 1.4f), gi_v3(-0.2f, -0.2f, -0.2f));
        g->dir = random_unit(&r);
        g->photon = i;
        g->hit_tri = 0;
        g->energy = gi_v3(gi_rng_float(&r), gi_rng_float(&r), gi_rng_float(&r));
        int kind = (int)gi_rng_below(&r, 4);
        if (kind == 0) { /* ends on the plane z = 0.5, from above */
            g->org = gi_v3(gi_rng_float(&r), gi_rng_float(&r), 0.6f + 0.5f * gi_rng_float(&r));
            if (g->dir.z > 0.0f)
                g->dir.z = -g->dir.z;
            g->dir.z = gi_minf(g->dir.z, -0.2f);
            g->dir = gi_normalize(g->dir);
            g->t_hit = (0.5f - g->org.z) / g->dir.z;
            g->t_second = INFINITY;
        } else if (kind == 1) { /* escapes */
            g->t_hit = g->t_second = INFINITY;
            g->hit_tri = GI_DETP_NO_HIT;
        } else {
            g->t_hit = 1.5f * gi_rng_float(&r);
            g->t_second = kind == 2 ? g->t_hit + 0.3f * gi_rng_float(&r) : INFINITY;
        }
    }
    gi_detp_set_extent(s, ac, 1e-5f);
}

static int same_accum(const gi_detp_accum *a, const gi_detp_accum *b)
{
    return memcmp(a->energy, b->energy, (size_t)a->count * 3 * sizeof(double)) == 0 &&
           memcmp(a->hits, b->hits, (size_t)a->count * sizeof(uint32_t)) == 0;
}

GI_TEST(test_detp_estimators_agree_with_basic_detp)
{
    gi_error err;
    const uint32_t nd = 2000, ns = 2500;
    gi_detp_artifact modes[2] = {GI_DETP_AC_NONE, GI_DETP_AC_SECOND_HIT};
    for (int mi = 0; mi < 2; mi++) {
        gi_detp_discs d;
        make_discs(&d, nd, 0.05f, 10 + (uint64_t)mi);
        gi_detp_segments s;
        make_segments(&s, ns, modes[mi], 20 + (uint64_t)mi);
        gi_detp_accum ref, acc;
        GI_REQUIRE_OK(gi_detp_accum_init(&ref, nd, &err));
        GI_REQUIRE_OK(gi_detp_accum_init(&acc, nd, &err));
        gi_detp_stats st;
        memset(&st, 0, sizeof st);
        gi_detp_basic(&d, &s, &ref, &st);
        /* Enough crossings, and on the plane too, for the check to bite. */
        GI_CHECK_MSG(st.crossings > 3000, "only %llu crossings",
                     (unsigned long long)st.crossings);
        uint64_t on_plane = 0;
        for (uint32_t i = 0; i < nd; i += 4)
            on_plane += ref.hits[i];
        GI_CHECK(on_plane > 100);
        uint64_t want = st.crossings;
        gi_vec3 lo = gi_v3(0, 0, 0), hi = gi_v3(1, 1, 1);

        /* Sphere Cache, every query order; small r_min for deep stacks. */
        for (int o = 0; o < 4; o++) {
            gi_detp_sc_params p = {2.0 / 3.0, 20, 60, (gi_detp_order)o, 1, 0};
            uint32_t *order = gi_detp_query_order(&d, p.order, 5, &err);
            GI_REQUIRE(order);
            gi_detp_accum_clear(&acc);
            memset(&st, 0, sizeof st);
            GI_CHECK_OK(gi_detp_sphere_cache(&d, order, &s, &p, lo, hi, &acc, &st, &err));
            GI_CHECK_MSG(same_accum(&acc, &ref), "sphere cache (order %d, mode %d) differs", o,
                         mi);
            GI_CHECK(st.crossings == want && st.max_level >= 2);
            /* Multilist: width 1 is the plain cache, fault for fault (in
             * mesh order, which is random here, and along the curve). */
            gi_detp_stats st1 = st;
            for (int v = 0; v < 3 && (o == 0 || o == 2); v++) {
                gi_detp_sc_params pm = p;
                pm.width = v == 0 ? 1 : v == 1 ? 3 : 0;
                pm.sphere_limit = v == 2 ? 12 : 0;
                gi_detp_accum_clear(&acc);
                memset(&st, 0, sizeof st);
                GI_CHECK_OK(gi_detp_multilist(&d, order, &s, &pm, lo, hi, &acc, &st, &err));
                GI_CHECK_MSG(same_accum(&acc, &ref), "multilist %d (order %d) differs", v, o);
                if (v == 0)
                    GI_CHECK_MSG(st.faults == st1.faults && st.sphere_tests == st1.sphere_tests,
                                 "multilist width 1: %llu faults vs %llu",
                                 (unsigned long long)st.faults,
                                 (unsigned long long)st1.faults);
                if (v == 2)
                    GI_CHECK(st.max_spheres <= 13 && st.evictions > 0);
            }
            free(order);
        }

        /* Octree: automatic depth, and a deep one with tiny leaves (discs
         * in many leaves: the mailbox must count each once). */
        gi_detp_octree_params op[2] = {{0, 20}, {7, 2}};
        for (int k = 0; k < 2; k++) {
            gi_detp_octree *oct;
            GI_REQUIRE_OK(gi_detp_octree_build(&d, &op[k], &oct, &err));
            gi_detp_accum_clear(&acc);
            memset(&st, 0, sizeof st);
            gi_detp_octree_estimate(oct, &s, &acc, &st);
            GI_CHECK_MSG(same_accum(&acc, &ref), "octree %d (mode %d) differs", k, mi);
            GI_CHECK(st.disc_tests < (uint64_t)nd * ns / 4);
            int depth;
            uint64_t nodes, leaves, refs;
            gi_detp_octree_shape(oct, &depth, &nodes, &leaves, &refs);
            GI_CHECK(depth >= 3 && refs > nd);
            gi_detp_octree_free(oct);
        }

        /* Lanes (the animation's mobile discs), every width the CPU has:
         * the segments ending on the plane of discs are where a fused
         * multiply-add would round otherwise than basic DETP. */
        for (unsigned w = 4; w <= 16; w *= 2) {
            gi_detp_accum_clear(&acc);
            memset(&st, 0, sizeof st);
            gi_detp_lanes_estimate_width(&d, NULL, &s, &acc, &st, w);
            GI_CHECK_MSG(same_accum(&acc, &ref), "lanes of %u (mode %d) differ", w, mi);
            GI_CHECK(st.crossings == want);
        }

        /* Embree. */
        RTCDevice dev = rtcNewDevice("threads=1");
        GI_REQUIRE(dev);
        gi_detp_embree_index *x;
        GI_REQUIRE_OK(gi_detp_embree_build(dev, &d, &x, &err));
        gi_detp_accum_clear(&acc);
        memset(&st, 0, sizeof st);
        gi_detp_embree_estimate(x, &s, &acc, &st);
        GI_CHECK_MSG(same_accum(&acc, &ref), "Embree index (mode %d) differs", mi);
        GI_CHECK(st.candidates >= want && st.candidates < (uint64_t)nd * ns / 4);
        gi_detp_embree_free(x);
        rtcReleaseDevice(dev);

        gi_detp_accum_free(&ref);
        gi_detp_accum_free(&acc);
        gi_detp_segments_free(&s);
        gi_detp_discs_free(&d);
    }
}

static int by_id(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* Segment j's pairs in c, sorted into out (room for n). */
static uint32_t sorted_pairs(const gi_detp_crossings *c, size_t j, uint32_t *out)
{
    uint32_t n = c->off[j + 1] - c->off[j];
    memcpy(out, c->ids + c->off[j], n * sizeof *out);
    qsort(out, n, sizeof *out, by_id);
    return n;
}

/* A segment on a twin's line (the animation's retraced first segments and
 * repaired ones): the twin's list plus a search beyond its end finds
 * exactly a whole search's pairs, whether the segment is shorter, longer,
 * endless, or ends just past a disc the twin ends just short of. */
GI_TEST(test_detp_embree_twin_finds_a_whole_search_pairs)
{
    gi_error err;
    const uint32_t nd = 2000, ns = 1500;
    gi_detp_discs d;
    make_discs(&d, nd, 0.05f, 31);
    gi_detp_segments twins, segs;
    make_segments(&twins, ns, GI_DETP_AC_SECOND_HIT, 32);
    gi_detp_segments_init(&segs);
    gi_rng r;
    gi_rng_init(&r, 33, 3, 0);
    size_t at_disc = 0;
    for (uint32_t i = 0; i < ns; i++) {
        gi_detp_segment *t = &twins.v[i], *g = gi_detp_segments_push(&segs);
        *g = *t;
        g->energy = gi_v3(gi_rng_float(&r), 1.0f, 0.5f); /* another photon state */
        switch (i % 6) {
        case 0: g->t_end = t->t_end * 0.5f; break;
        case 1: g->t_end = isfinite(t->t_end) ? t->t_end * 1.7f + 0.2f : 0.8f; break;
        case 2: g->t_end = INFINITY; break;
        case 3: break; /* the same extent */
        default: {
            /* The twin ends exactly at a disc's crossing, the segment one
             * float past it: only the search beyond the twin finds it. Or
             * the twin ends one float past it and the segment goes on: the
             * search beyond the twin starts a little before its end, and
             * must not count that disc again. */
            for (uint32_t k = 0; k < nd; k++) {
                const gi_detp_disc *D = &d.d[(k + i) % nd];
                float denom = gi_dot(g->dir, D->n);
                if (!(denom < 0.0f))
                    continue;
                float tc = gi_dot(gi_sub(D->c, g->org), D->n) / denom;
                gi_detp_segment probe = *g;
                probe.t_end = INFINITY;
                if (tc > 0.0f && gi_detp_crosses(D, d.r2, &probe)) {
                    if (i % 6 == 4) {
                        t->t_end = tc;
                        g->t_end = nextafterf(tc, INFINITY);
                    } else {
                        t->t_end = nextafterf(tc, INFINITY);
                        g->t_end = 1.5f * tc + 0.1f;
                    }
                    at_disc++;
                    break;
                }
            }
        }
        }
    }
    GI_CHECK_MSG(at_disc > ns / 8, "only %zu twins end at a disc", at_disc);
    RTCDevice dev = rtcNewDevice("threads=1");
    GI_REQUIRE(dev);
    gi_detp_embree_index *x;
    GI_REQUIRE_OK(gi_detp_embree_build(dev, &d, &x, &err));
    double unit = 1e-9;
    gi_detp_accum whole, derived;
    GI_REQUIRE_OK(gi_detp_accum_init_fixed(&whole, nd, unit, &err));
    GI_REQUIRE_OK(gi_detp_accum_init_fixed(&derived, nd, unit, &err));
    gi_detp_stats st = {0};
    gi_detp_crossings tw = {0}, a = {0}, b = {0};
    gi_detp_accum scratch;
    GI_REQUIRE_OK(gi_detp_accum_init_fixed(&scratch, nd, unit, &err));
    gi_detp_embree_estimate_listed(x, &twins, &scratch, &st, &tw);
    gi_detp_embree_estimate_listed(x, &segs, &whole, &st, &a);
    gi_detp_crossings_reset(&b);
    for (uint32_t i = 0; i < ns; i++)
        gi_detp_embree_estimate_twin(x, &segs.v[i], &twins.v[i], tw.ids + tw.off[i],
                                     tw.off[i + 1] - tw.off[i], &derived, &st, &b);
    GI_REQUIRE(b.segments == ns && a.segments == ns);
    size_t bad = 0, crossings = 0;
    uint32_t *pa = gi_xmalloc(nd * sizeof *pa), *pb = gi_xmalloc(nd * sizeof *pb);
    for (uint32_t i = 0; i < ns; i++) {
        uint32_t na = sorted_pairs(&a, i, pa), nb = sorted_pairs(&b, i, pb);
        bad += na != nb || memcmp(pa, pb, na * sizeof *pa) != 0;
        crossings += na;
    }
    GI_CHECK_MSG(bad == 0, "%zu of %u segments: other pairs than a whole search", bad, ns);
    GI_CHECK(crossings > 1000);
    GI_CHECK(memcmp(whole.fixed, derived.fixed, 3 * (size_t)nd * sizeof *whole.fixed) == 0 &&
             memcmp(whole.hits, derived.hits, nd * sizeof *whole.hits) == 0);
    free(pa);
    free(pb);
    gi_detp_crossings_free(&tw);
    gi_detp_crossings_free(&a);
    gi_detp_crossings_free(&b);
    gi_detp_accum_free(&scratch);
    gi_detp_accum_free(&whole);
    gi_detp_accum_free(&derived);
    gi_detp_embree_free(x);
    rtcReleaseDevice(dev);
    gi_detp_segments_free(&twins);
    gi_detp_segments_free(&segs);
    gi_detp_discs_free(&d);
}

/* Lanes against basic DETP where rounding decides: segments that end
 * exactly at a tilted disc's plane (t_end = its t: not crossed) or one
 * float past it (crossed). A fused multiply-add, or any other order of
 * operations, computes another t and flips some of them. */
GI_TEST(test_detp_lanes_round_like_basic_detp_at_the_edge)
{
    gi_error err;
    const uint32_t nd = 64, ns = 4000;
    gi_detp_discs d;
    make_discs(&d, nd, 0.3f, 41);
    gi_detp_segments s;
    gi_detp_segments_init(&s);
    gi_rng r;
    gi_rng_init(&r, 42, 4, 0);
    for (uint32_t i = 0; i < ns; i++) {
        const gi_detp_disc *D = &d.d[i % nd];
        gi_detp_segment *g = gi_detp_segments_push(&s);
        memset(g, 0, sizeof *g);
        g->photon = i;
        g->energy = gi_v3(1, 1, 1);
        /* From the front of the disc towards a point near its centre. */
        gi_vec3 aim = gi_add(D->c, gi_scale(random_unit(&r), 0.1f));
        g->org = gi_add(aim, gi_scale(gi_add(D->n, gi_scale(random_unit(&r), 0.5f)),
                                      0.5f + gi_rng_float(&r)));
        g->dir = gi_normalize(gi_sub(aim, g->org));
        float denom = gi_dot(g->dir, D->n);
        float t = gi_dot(gi_sub(D->c, g->org), D->n) / denom;
        g->t_hit = g->t_second = g->t_end = i % 2 ? nextafterf(t, INFINITY) : t;
    }
    gi_detp_accum ref, acc;
    GI_REQUIRE_OK(gi_detp_accum_init(&ref, nd, &err));
    GI_REQUIRE_OK(gi_detp_accum_init(&acc, nd, &err));
    gi_detp_stats st = {0};
    gi_detp_basic(&d, &s, &ref, &st);
    GI_CHECK(st.crossings > ns / 4);
    for (unsigned w = 4; w <= 16; w *= 2) {
        gi_detp_accum_clear(&acc);
        gi_detp_lanes_estimate_width(&d, NULL, &s, &acc, &st, w);
        GI_CHECK_MSG(same_accum(&acc, &ref), "lanes of %u differ from basic DETP", w);
    }
    gi_detp_accum_free(&ref);
    gi_detp_accum_free(&acc);
    gi_detp_segments_free(&s);
    gi_detp_discs_free(&d);
}

GI_TEST(test_detp_disc_test_is_one_sided_and_respects_the_extent)
{
    gi_detp_disc D = {{0, 0, 0}, {0, 0, 1}};
    gi_detp_segment g;
    memset(&g, 0, sizeof g);
    g.org = gi_v3(0.05f, 0, 1);
    g.dir = gi_v3(0, 0, -1);
    g.t_hit = g.t_end = 2.0f;
    GI_CHECK(gi_detp_crosses(&D, 0.01f, &g));
    g.t_end = 0.999f; /* stops short */
    GI_CHECK(!gi_detp_crosses(&D, 0.01f, &g));
    g.t_end = 2.0f;
    g.org = gi_v3(0.2f, 0, 1); /* outside the radius 0.1 */
    GI_CHECK(!gi_detp_crosses(&D, 0.01f, &g));
    g.org = gi_v3(0, 0, -1); /* from behind */
    g.dir = gi_v3(0, 0, 1);
    GI_CHECK(!gi_detp_crosses(&D, 0.01f, &g));
    /* Extents: rule 1 reaches up to (not onto) the surface behind. */
    gi_detp_segments s;
    gi_detp_segments_init(&s);
    gi_detp_segment *p = gi_detp_segments_push(&s);
    p->t_hit = 1.0f;
    p->t_second = 3.0f;
    gi_detp_set_extent(&s, GI_DETP_AC_NONE, 0.01f);
    GI_CHECK_NEAR(p->t_end, 1.01, 1e-6);
    gi_detp_set_extent(&s, GI_DETP_AC_SECOND_HIT, 0.01f);
    GI_CHECK_NEAR(p->t_end, 2.99, 1e-6);
    p->t_second = 1.005f; /* closer than the margin: never short of the hit */
    gi_detp_set_extent(&s, GI_DETP_AC_SECOND_HIT, 0.01f);
    GI_CHECK_NEAR(p->t_end, 1.01, 1e-6);
    gi_detp_segments_free(&s);
}

GI_TEST(test_detp_space_filling_orders)
{
    /* The Hilbert curve visits the 8^3 cells of an aligned cube one after
     * another, each sharing a face with the previous one. */
    uint64_t keys[512];
    uint32_t cells[512];
    for (uint32_t i = 0; i < 512; i++) {
        keys[i] = gi_detp_hilbert_key(i >> 6, (i >> 3) & 7, i & 7);
        cells[i] = i;
    }
    for (int i = 1; i < 512; i++) /* insertion sort by key */
        for (int j = i; j > 0 && keys[cells[j - 1]] > keys[cells[j]]; j--) {
            uint32_t t = cells[j];
            cells[j] = cells[j - 1];
            cells[j - 1] = t;
        }
    int bad = 0;
    for (int i = 1; i < 512; i++) {
        uint32_t a = cells[i - 1], b = cells[i];
        int dx = abs((int)(a >> 6) - (int)(b >> 6)), dy = abs((int)((a >> 3) & 7) - (int)((b >> 3) & 7)),
            dz = abs((int)(a & 7) - (int)(b & 7));
        bad += dx + dy + dz != 1;
        bad += keys[a] == keys[b];
    }
    GI_CHECK_MSG(bad == 0, "%d steps of the Hilbert order are not to a face neighbour", bad);
    /* Morton interleaves x, y, z from the most significant bit. */
    GI_CHECK(gi_detp_morton_key(1u << 15, 0, 0) == 1ull << 47);
    GI_CHECK(gi_detp_morton_key(0, 1u << 15, 0) == 1ull << 46);
    GI_CHECK(gi_detp_morton_key(0, 0, 1) == 1ull);
    GI_CHECK(gi_detp_morton_key(1, 1, 1) == 7ull);
    /* Orders are permutations; the shuffle depends on the seed. */
    gi_error err;
    gi_detp_discs d;
    make_discs(&d, 1000, 0.01f, 3);
    uint32_t *o[4];
    for (int k = 0; k < 4; k++) {
        o[k] = gi_detp_query_order(&d, (gi_detp_order)k, 9, &err);
        GI_REQUIRE(o[k]);
        uint8_t seen[1000] = {0};
        int dup = 0;
        for (uint32_t i = 0; i < 1000; i++)
            dup += seen[o[k][i]]++ != 0;
        GI_CHECK(dup == 0);
    }
    GI_CHECK(memcmp(o[1], o[2], 4000) != 0 && memcmp(o[0], o[3], 4000) != 0);
    /* Along a sorted order consecutive discs are close: the mean step is
     * far below a random order's. */
    double step[4] = {0, 0, 0, 0};
    for (int k = 0; k < 4; k++)
        for (uint32_t i = 1; i < 1000; i++)
            step[k] += gi_length(gi_sub(d.d[o[k][i]].c, d.d[o[k][i - 1]].c));
    GI_CHECK(step[1] < 0.4 * step[3] && step[2] < 0.4 * step[3]);
    for (int k = 0; k < 4; k++)
        free(o[k]);
    gi_detp_discs_free(&d);
}
