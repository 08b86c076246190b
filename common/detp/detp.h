/* detp: photon paths and Density Estimation on the Tangent Plane.
 *
 * R. J. Garcia Hernandez, "Estudio y desarrollo de tecnicas interactivas de
 * Iluminacion Global", PhD thesis, Univ. de Granada, 2009 (the "thesis";
 * equation numbers below are its own). Photons leave the emitters, bounce
 * diffusely and are stored as ray segments; every irradiance sample (a mesh
 * vertex) owns a disc in its tangent plane, and the irradiance there is the
 * power of the segments crossing the disc divided by the disc's area.
 *
 * This header holds what every part shares: the segment record, the discs,
 * the one ray-disc test all estimators use (so they agree on which pairs
 * cross, bit for bit), the accumulators and the estimators' statistics.
 * Each estimator, the photon tracer, the mesh refinement, the query orders
 * and the method glue live in files of their own (common/detp/). */
#ifndef GI_DETP_H
#define GI_DETP_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include <embree3/rtcore.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "gi_math.h"
#include "gi_method.h"
#include "gi_rt.h"
#include "gi_scene.h"

#define GI_DETP_NO_HIT 0xFFFFFFFFu

/* One straight piece of a photon path. A path is the run of segments with
 * the same photon index and bounces 0, 1, 2, ... (thesis 1.1; the stored
 * fields are those of Fig. 4.2's incremental recompute: origin, direction,
 * hit distance, hit triangle, energy). */
typedef struct gi_detp_segment {
    gi_vec3 org;      /* origin (moved off the surface it leaves) */
    gi_vec3 dir;      /* unit direction */
    float t_hit;      /* distance to the first scene hit; INFINITY if it escaped */
    float t_second;   /* distance to the next intersection beyond the first along the
                         same line (artifact control, thesis 1.5 rule 1); INFINITY if
                         none or not traced */
    float t_end;      /* extent tested against discs (set by gi_detp_set_extent) */
    gi_vec3 energy;   /* power carried, RGB (scene units) */
    uint32_t hit_tri; /* global triangle index of the first hit, or GI_DETP_NO_HIT */
    uint32_t bounce;  /* reflections before this segment (0: leaving the emitter) */
    uint64_t photon;  /* photon (path) index */
} gi_detp_segment;

typedef struct gi_detp_segments {
    gi_detp_segment *v;
    size_t count, cap;
} gi_detp_segments;

void gi_detp_segments_init(gi_detp_segments *s);
void gi_detp_segments_free(gi_detp_segments *s);
gi_detp_segment *gi_detp_segments_push(gi_detp_segments *s);

/* Artifact control (thesis 1.5): which part of a segment can feed a disc. */
typedef enum {
    GI_DETP_AC_NONE,         /* origin to the first hit */
    GI_DETP_AC_SECOND_HIT,   /* rule 1: strictly before the second intersection */
    GI_DETP_AC_VISIBLE_AREA  /* rule 2: origin to the first hit, and the energy is
                                divided by the disc's visible area (detp_visibility.c) */
} gi_detp_artifact;

/* Sets t_end of every segment: up to t_hit + eps (a crossing on the surface
 * the segment hits must count whatever the rounding), or t_second - eps for
 * rule 1 (the surface behind must not). eps is a length, e.g. 1e-5 of the
 * scene size. */
void gi_detp_set_extent(gi_detp_segments *s, gi_detp_artifact ac, float eps);

/* A disc: centre and unit normal; all discs of a job share one radius. */
typedef struct gi_detp_disc {
    gi_vec3 c, n;
} gi_detp_disc;

typedef struct gi_detp_discs {
    uint32_t count;
    gi_detp_disc *d;
    float radius, r2; /* r2 = radius^2 */
} gi_detp_discs;

void gi_detp_discs_free(gi_detp_discs *d);

/* THE ray-disc test, used by every DETP estimator (basic, Sphere Cache,
 * both Disc Indexings): the segment crosses the disc from the side its
 * normal faces (irradiance is defined over the front hemisphere: one-sided
 * discs are also what makes eq. 3.38's p = A_d / A_0 exact), at a distance
 * in (0, t_end), within the radius. The same float operations everywhere
 * make the estimators count exactly the same (segment, disc) pairs. */
static inline int gi_detp_crosses(const gi_detp_disc *D, float r2, const gi_detp_segment *s)
{
    float denom = gi_dot(s->dir, D->n);
    if (!(denom < 0.0f))
        return 0;
    float t = gi_dot(gi_sub(D->c, s->org), D->n) / denom;
    if (!(t > 0.0f && t < s->t_end))
        return 0;
    gi_vec3 p = gi_sub(gi_madd(s->org, s->dir, t), D->c);
    return gi_dot(p, p) <= r2;
}

/* Per-disc sums: energy (RGB, double) and the number of crossings. Every
 * estimator adds a disc's contributions in segment order, so the sums are
 * bit-identical whichever estimator found the pairs.
 *
 * Fixed-point mode (animation, issue 7): `fixed` (3 int64 per disc) instead
 * of `energy`; each crossing adds sign * gi_detp_fixed_round(energy_c *
 * inv_unit). Integer sums do not depend on the order or the split of the
 * segments, so "frame 0 + new - old" equals a recompute over the final
 * segments bit for bit. `hits` then counts modulo 2^32 (a removal adds (uint32_t)-1). Only
 * the estimators that go through gi_detp_accum_add (basic, Sphere Cache,
 * multilist, octree, Embree DI) support it: impact count and the photon map
 * write irradiance to `energy` themselves. */
typedef struct gi_detp_accum {
    uint32_t count;
    double *energy; /* 3 per disc (double mode) */
    uint32_t *hits;
    int64_t *fixed;  /* 3 per disc (fixed-point mode), else NULL */
    double inv_unit; /* 1 / unit (fixed-point mode) */
    int sign;        /* +1 adds segments, -1 removes them (fixed-point mode) */
} gi_detp_accum;

int gi_detp_accum_init(gi_detp_accum *a, uint32_t count, gi_error *err);
/* A fixed-point accumulator (energy == NULL) of value unit per count,
 * sign +1. */
int gi_detp_accum_init_fixed(gi_detp_accum *a, uint32_t count, double unit, gi_error *err);
/* The animation's fixed-point unit: one photon's luminance power
 * (total_power / photons_total) times 2^-32. */
double gi_detp_fixed_unit(double total_power, uint64_t photons_total);
void gi_detp_accum_clear(gi_detp_accum *a);
void gi_detp_accum_free(gi_detp_accum *a);
/* A contribution in fixed-point units, rounded half away from zero: one
 * add and one truncating conversion (llround is a library call, and this
 * runs once per disc crossing). Segment energies are at most a few photon
 * powers, far below 2^53 units, so the conversion is exact and the same
 * on every host. */
static inline int64_t gi_detp_fixed_round(double x)
{
    return (int64_t)(x < 0.0 ? x - 0.5 : x + 0.5);
}

/* One segment's contribution in fixed-point units, for an estimator that
 * adds the same segment to many discs: gi_detp_accum_add's conversions
 * done once (the same values, so the same sums). Fixed-point mode only. */
typedef struct gi_detp_fixed_contrib {
    int64_t e[3];
    uint32_t hit;
} gi_detp_fixed_contrib;

static inline gi_detp_fixed_contrib gi_detp_fixed_contrib_of(const gi_detp_accum *a,
                                                             const gi_detp_segment *s)
{
    int64_t sg = a->sign;
    gi_detp_fixed_contrib c = {{sg * gi_detp_fixed_round((double)s->energy.x * a->inv_unit),
                                sg * gi_detp_fixed_round((double)s->energy.y * a->inv_unit),
                                sg * gi_detp_fixed_round((double)s->energy.z * a->inv_unit)},
                               (uint32_t)sg};
    return c;
}

static inline void gi_detp_accum_add_fixed(gi_detp_accum *a, uint32_t disc,
                                           const gi_detp_fixed_contrib *c)
{
    int64_t *f = &a->fixed[3 * (size_t)disc];
    f[0] += c->e[0];
    f[1] += c->e[1];
    f[2] += c->e[2];
    a->hits[disc] += c->hit;
}

static inline void gi_detp_accum_add(gi_detp_accum *a, uint32_t disc, const gi_detp_segment *s)
{
    if (__builtin_expect(a->fixed != NULL, 0)) {
        gi_detp_fixed_contrib c = gi_detp_fixed_contrib_of(a, s);
        gi_detp_accum_add_fixed(a, disc, &c);
        return;
    }
    double *e = &a->energy[3 * (size_t)disc];
    e[0] += s->energy.x;
    e[1] += s->energy.y;
    e[2] += s->energy.z;
    a->hits[disc]++;
}

/* What the estimators count (summed over batches for the report). */
#define GI_DETP_MAX_LEVELS 64
typedef struct gi_detp_stats {
    uint64_t disc_tests;    /* exact ray-disc tests (gi_detp_crosses) */
    uint64_t crossings;     /* (segment, disc) pairs counted */
    uint64_t sphere_tests;  /* Sphere Cache: segment-sphere tests */
    uint64_t queries;       /* Sphere Cache: discs queried */
    uint64_t faults;        /* Sphere Cache: cache misses (thesis Table 5.7) */
    uint64_t spheres_built; /* Sphere Cache: spheres (re)built */
    uint64_t max_level;     /* Sphere Cache: deepest level used */
    uint64_t max_spheres;   /* Sphere Cache: most spheres alive at once */
    uint64_t evictions;     /* multilist: spheres discarded */
    uint64_t inner_rays;    /* Sphere Cache: rays in the innermost sphere, summed over queries */
    uint64_t node_visits;   /* octree: nodes entered */
    uint64_t candidates;    /* Embree index: discs reported by traversal */
    uint64_t photons_found; /* photon map: photons gathered */
    uint64_t level_faults[GI_DETP_MAX_LEVELS];    /* misses that rebuilt level i */
    uint64_t level_rays[GI_DETP_MAX_LEVELS];      /* rays in level i's spheres, summed at rebuilds */
} gi_detp_stats;

void gi_detp_stats_add(gi_detp_stats *into, const gi_detp_stats *s);
void gi_detp_stats_encode(const gi_detp_stats *s, gi_buf *out);
void gi_detp_stats_decode(gi_reader *r, gi_detp_stats *s);

/* ---- Photon paths (detp_photons.c) ---------------------------------- */

typedef struct gi_detp_tracer {
    gi_rt *rt;
    const gi_scene *scene;
    uint64_t seed;          /* the job's seed */
    uint64_t photons_total; /* the job's photon count (each carries total power / this) */
    int max_bounces;        /* reflections per path; -1: until absorbed */
    int second_hit;         /* trace t_second (artifact control rule 1) */
    double select_shift;    /* Cranley-Patterson shift of the emitter selection */
    uint32_t frame;         /* animation frame (0: still jobs; set after init) */
    /* Optional (NULL after init): a mobile object, triangles [mobile_first,
     * + mobile_count), alone in this scene, when nothing else comes within
     * its bounding sphere (gi_rt_others_near). A ray from just behind a hit
     * on it stays in that sphere until it meets it again, so its first hit
     * there is the whole scene's, bit for bit (gi_rt.h): rule 1's second
     * ray is then traced against the mobile alone. */
    RTCScene mobile_alone;
    uint32_t mobile_first, mobile_count;
} gi_detp_tracer;

/* Random numbers of photon p at bounce b come from gi_rng (seed,
 * GI_DETP_STREAM_PHOTON + p, b): a path depends only on (job, p), and a
 * retrace from bounce b reuses the numbers of the bounces from b on.
 * Reflections traced at animation frame f > 0 draw from sample
 * (f << 13) | b instead (b < GI_DETP_MAX_PATH = 2^12): a suffix retraced
 * at frame f is new, but the same for every worker; frame 0 is the still
 * stream. Emission (b = 0) never depends on the frame. */
#define GI_DETP_STREAM_PHOTON (1ull << 62)
/* Paths are cut here even if never absorbed (reflectance < 1 makes this
 * unreachable in practice; it bounds a path's memory). */
#define GI_DETP_MAX_PATH 4096

void gi_detp_tracer_init(gi_detp_tracer *tr, gi_rt *rt, const gi_scene *scene, uint64_t seed,
                         uint64_t photons_total, int max_bounces, int second_hit);
/* t_second of a segment from org along dir that hit triangle hit_tri at
 * t_hit: where its line meets the next surface behind that hit, INFINITY
 * if none (the tracer and the incremental update share it, so that both
 * compute the same float). */
float gi_detp_second_t(const gi_detp_tracer *tr, gi_vec3 org, gi_vec3 dir, float t_hit,
                       uint32_t hit_tri);
/* Appends the segments of photon `photon`'s path. */
void gi_detp_trace_photon(const gi_detp_tracer *tr, uint64_t photon, gi_detp_segments *out);
/* Continues a path from a segment (origin, direction, energy) at `bounce`:
 * what an incremental recompute calls to retrace a suffix. */
void gi_detp_trace_from(const gi_detp_tracer *tr, uint64_t photon, uint32_t bounce,
                        gi_vec3 org, gi_vec3 dir, gi_vec3 energy, gi_detp_segments *out);
/* The same with the first segment's closest hit already known (`first`,
 * exactly what the ray would find), or NULL. */
void gi_detp_trace_from_hit(const gi_detp_tracer *tr, uint64_t photon, uint32_t bounce,
                            gi_vec3 org, gi_vec3 dir, gi_vec3 energy, const gi_hit *first,
                            gi_detp_segments *out);

/* ---- Irradiance points (detp_points.c) ------------------------------ */

/* Splits triangles until no edge is longer than max_edge. Edges are split at
 * their midpoints, globally: an edge is split from both of its triangles or
 * from neither, and the midpoint vertex is shared through an edge -> vertex
 * map, so the refined mesh has no T-junctions and per-vertex values
 * interpolate continuously. Objects keep their contiguous vertex and
 * triangle ranges; derived data is recomputed. Fails if the result would
 * exceed the scene limits. */
int gi_detp_refine_scene(gi_scene *s, double max_edge, gi_error *err);
/* Mean length of the mesh's edges (each shared edge once): the mean sample
 * spacing d_P of thesis 3.12. */
double gi_detp_mean_edge(const gi_scene *s);
/* One disc per vertex: centre = position, normal = vertex normal. */
int gi_detp_discs_from_scene(const gi_scene *s, float radius, gi_detp_discs *out,
                             gi_error *err);
/* Per-vertex reflectance and emission: area-weighted means over the
 * triangles around each vertex (3 floats per vertex each). */
void gi_detp_vertex_materials(const gi_scene *s, float *rho, float *emission);

/* ---- Query orders (detp_order.c) ----------------------------------- */

typedef enum {
    GI_DETP_ORDER_NONE,     /* mesh order */
    GI_DETP_ORDER_LEBESGUE, /* Morton / Z-order, 16 bits per axis (thesis 1.7) */
    GI_DETP_ORDER_HILBERT,  /* 3-D Hilbert curve, 16 bits per axis */
    GI_DETP_ORDER_SHUFFLED  /* random permutation (DETP_UnsortQueries) */
} gi_detp_order;

uint64_t gi_detp_morton_key(uint32_t x, uint32_t y, uint32_t z);
uint64_t gi_detp_hilbert_key(uint32_t x, uint32_t y, uint32_t z);
/* The permutation of disc indices to query in (malloc'ed). */
uint32_t *gi_detp_query_order(const gi_detp_discs *d, gi_detp_order order, uint64_t seed,
                              gi_error *err);

/* ---- Estimators ------------------------------------------------------ */

/* Basic DETP (detp_basic.c): every disc against every segment, O(n_R n_P). */
void gi_detp_basic(const gi_detp_discs *d, const gi_detp_segments *s, gi_detp_accum *acc,
                   gi_detp_stats *st);
/* The same pairs, the discs 16 (AVX-512), 8 (AVX2) or 4 at a time
 * (detp_lanes.c): faster than an index when a segment crosses most of the
 * discs (a small mobile's). The discs are grouped in `order` (a
 * permutation of their indices; NULL: their Hilbert order, computed here);
 * any order gives the same sums, a compact one fewer tests, so a rigid
 * mobile's order can be computed once and reused at every pose (thesis
 * 4.6). _width: at most `lanes` at a time (4, 8 or 16, as far as the CPU
 * goes; the tests check each). */
void gi_detp_lanes_estimate(const gi_detp_discs *d, const uint32_t *order,
                            const gi_detp_segments *s, gi_detp_accum *acc, gi_detp_stats *st);
void gi_detp_lanes_estimate_width(const gi_detp_discs *d, const uint32_t *order,
                                  const gi_detp_segments *s, gi_detp_accum *acc,
                                  gi_detp_stats *st, unsigned lanes);

/* Sphere Cache (detp_sphere_cache.c), thesis 1.6. */
typedef struct gi_detp_sc_params {
    double q;            /* radius factor Q */
    uint32_t r_min;      /* a sphere with fewer rays gets no child */
    uint32_t max_levels; /* deepest level */
    gi_detp_order order;
    /* Multilist (thesis 1.8): width > 1 keeps up to `width` children per
     * sphere; sphere_limit > 0 keeps any number of children but at most
     * sphere_limit spheres in all. Both evict the least recently used. */
    uint32_t width;
    uint32_t sphere_limit;
} gi_detp_sc_params;

/* The cache over one set of segments; the root sphere S_0 encloses the box
 * [lo, hi] grown by the disc radius (every disc lies inside it). */
int gi_detp_sphere_cache(const gi_detp_discs *d, const uint32_t *order,
                         const gi_detp_segments *s, const gi_detp_sc_params *p, gi_vec3 lo,
                         gi_vec3 hi, gi_detp_accum *acc, gi_detp_stats *st, gi_error *err);
/* The same with the root sphere given (it must hold every disc whole): the
 * animation roots a mobile's cache at its bounding sphere (thesis 4.7). */
int gi_detp_sphere_cache_root(const gi_detp_discs *d, const uint32_t *order,
                              const gi_detp_segments *s, const gi_detp_sc_params *p,
                              gi_vec3 c0, float r0, gi_detp_accum *acc, gi_detp_stats *st,
                              gi_error *err);
int gi_detp_multilist(const gi_detp_discs *d, const uint32_t *order, const gi_detp_segments *s,
                      const gi_detp_sc_params *p, gi_vec3 lo, gi_vec3 hi, gi_detp_accum *acc,
                      gi_detp_stats *st, gi_error *err);

/* Disc Indexing with an octree (detp_octree.c), thesis 1.9. */
typedef struct gi_detp_octree gi_detp_octree;
typedef struct gi_detp_octree_params {
    int max_depth;     /* 0: automatic (voxel side about the disc diameter, thesis 3.11) */
    uint32_t max_leaf; /* a node with more discs is split */
} gi_detp_octree_params;
int gi_detp_octree_build(const gi_detp_discs *d, const gi_detp_octree_params *p,
                         gi_detp_octree **out, gi_error *err);
void gi_detp_octree_estimate(gi_detp_octree *o, const gi_detp_segments *s, gi_detp_accum *acc,
                             gi_detp_stats *st);
void gi_detp_octree_free(gi_detp_octree *o);
/* Depth, nodes, leaves, disc references (for reports and benchmarks). */
void gi_detp_octree_shape(const gi_detp_octree *o, int *depth, uint64_t *nodes,
                          uint64_t *leaves, uint64_t *refs);

/* Disc Indexing with Embree (detp_embree_index.c): the discs as
 * RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT; a filter function (on occlusion
 * queries) applies gi_detp_crosses to every disc a segment meets and
 * rejects the hit, so traversal goes on to the next. */
typedef struct gi_detp_embree_index gi_detp_embree_index;
int gi_detp_embree_build(RTCDevice device, const gi_detp_discs *d, gi_detp_embree_index **out,
                         gi_error *err);
void gi_detp_embree_estimate(gi_detp_embree_index *x, const gi_detp_segments *s,
                             gi_detp_accum *acc, gi_detp_stats *st);
void gi_detp_embree_free(gi_detp_embree_index *x);

/* The (segment, disc) pairs an estimate found, per segment: the discs of
 * segment j are ids[off[j] .. off[j + 1]) (in the order found). */
typedef struct gi_detp_crossings {
    uint32_t *off; /* segments + 1 */
    uint32_t *ids;
    size_t segments, pairs, off_cap, ids_cap;
} gi_detp_crossings;
void gi_detp_crossings_free(gi_detp_crossings *c);
/* gi_detp_embree_estimate that also lists each segment's discs into rec
 * (replacing what it held). */
void gi_detp_embree_estimate_listed(gi_detp_embree_index *x, const gi_detp_segments *s,
                                    gi_detp_accum *acc, gi_detp_stats *st,
                                    gi_detp_crossings *rec);
/* Empties c for segments appended one by one. */
void gi_detp_crossings_reset(gi_detp_crossings *c);
/* Appends to rec the crossings of a segment whose line (origin and
 * direction, bit for bit) is that of twin, whose crossings are ids[0..n):
 * those of them within seg's extent, and if seg reaches past twin's end,
 * the discs found searching only beyond it. The same pairs and sums as
 * searching seg whole (the filter is gi_detp_crosses either way). */
void gi_detp_embree_estimate_twin(gi_detp_embree_index *x, const gi_detp_segment *seg,
                                  const gi_detp_segment *twin, const uint32_t *ids, uint32_t n,
                                  gi_detp_accum *acc, gi_detp_stats *st,
                                  gi_detp_crossings *rec);
/* Appends to rec the crossings of seg, searched whole. */
void gi_detp_embree_estimate_one(gi_detp_embree_index *x, const gi_detp_segment *seg,
                                 gi_detp_accum *acc, gi_detp_stats *st,
                                 gi_detp_crossings *rec);
/* The contributions of listed pairs without searching: segment j to each
 * disc of its list (the same gi_detp_accum_add calls as the estimate that
 * listed them made, in acc's current sign). */
void gi_detp_crossings_apply(const gi_detp_segment *seg, const uint32_t *ids, uint32_t n,
                             gi_detp_accum *acc, gi_detp_stats *st);

/* Impact count (detp_impact.c), eqs. 3.6-3.8: each hit's energy goes to
 * the triangle it hits; a triangle's irradiance is its energy over its
 * area, and a vertex takes the mean of its triangles. Adds IRRADIANCE
 * (energy / area) per vertex to acc. Hits on the back of a triangle (the
 * side its vertex normals turn away from) do not count, like the discs. */
int gi_detp_impact_count(const gi_scene *scene, const gi_detp_segments *s, gi_detp_accum *acc,
                         gi_detp_stats *st, gi_error *err);

/* Photon map (detp_photon_map.c), thesis 1.4 and eqs. 3.15-3.21: the k
 * hits nearest to each disc centre (arriving on its front side); the
 * energy of the nearest k-1 (or k, the literature's biased form) over the
 * area of the circle through the k-th. Adds IRRADIANCE per disc to acc. */
int gi_detp_photon_map(const gi_detp_discs *d, const gi_detp_segments *s, uint32_t k,
                       int k_minus_one, gi_detp_accum *acc, gi_detp_stats *st, gi_error *err);

/* ---- Visible disc area (detp_visibility.c), artifact control rule 2 --- */

/* Per vertex, a unit vector in its tangent plane pointing into its own
 * triangles (zero if none). */
void gi_detp_inward_dirs(const gi_scene *s, gi_vec3 *out);
/* The fraction of the disc reachable from its centre without crossing the
 * scene: k / GI_DETP_VIS_RAYS for the k of its shadow rays that are free,
 * so 0 or at least 1 / GI_DETP_VIS_RAYS (irradiance is divided by it). */
#define GI_DETP_VIS_RAYS 64
float gi_detp_visible_fraction(gi_rt *rt, const gi_detp_disc *D, float radius, gi_vec3 inward);

/* ---- Theory (detp_auto.c), thesis 1.13 ------------------------------- */

/* Relative error of the estimate under uniformly distributed lines:
 * sqrt((A_0 - A_d) / (A_d n_R)) (eq. 3.46). */
double gi_detp_predicted_error(double hull_area, double disc_area, double rays);
/* Rays needed for a relative error e (eq. 3.46 solved for n_R). */
uint64_t gi_detp_rays_for_error(double hull_area, double disc_area, double e);
/* The area A_0 that random lines hit: the surface of the scene's bounding
 * box (it contains the convex hull, so the predicted error and the photon
 * count are on the safe side). */
double gi_detp_hull_area(const gi_scene *s);
/* Largest edge of the scene's bounding box: what radii "in %" refer to. */
double gi_detp_scene_size(const gi_scene *s);

/* The method (detp_method.c): docs/job-format.md, section detp. */
extern const gi_method gi_method_detp;

#endif
