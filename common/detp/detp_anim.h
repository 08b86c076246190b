/* detp_anim: quasi-static animation (issue 7, thesis ch. 4).
 *
 * A batch's photon paths are traced once at frame 0 and then updated frame
 * by frame (thesis Fig. 4.2): only the paths that meet the mobile object at
 * its old or new pose are retraced. The segments a frame drops (old_list)
 * and adds (new_list) give the static vertices' change, summed in fixed
 * point (gi_detp_accum_init_fixed) so that frame 0 + all deltas equals a
 * recompute over the frame's segments bit for bit; the mobile's own
 * vertices are estimated from scratch each frame (thesis 4.5).
 *
 * Between frames a batch's segments live in the batch store: one file per
 * (batch, frame) in the worker's batch directory (detp_store.c). */
#ifndef GI_DETP_ANIM_H
#define GI_DETP_ANIM_H

#include <stddef.h>
#include <stdint.h>

#include "detp.h"
#include "detp_params.h"

/* ---- Batch store (detp_store.c) ------------------------------------- */

#define GI_DETP_STORE_MAGIC "GIDS"
#define GI_DETP_STORE_VERSION 2u /* 2: kind and prev_base */
#define GI_DETP_STORE_ENDIAN 0x01020304u /* written natively: a foreign host reads it swapped */

/* The file's first 64 bytes; the records (raw native gi_detp_segment,
 * 64 bytes each, path-ordered: photon ascending, bounce 0, 1, ... within a
 * path) follow. The caller fills p0, p1, frame; the writer the rest. */
typedef struct gi_detp_store_header {
    char magic[4];         /* "GIDS" */
    uint32_t version;      /* GI_DETP_STORE_VERSION */
    uint32_t endian;       /* GI_DETP_STORE_ENDIAN */
    uint32_t record_bytes; /* sizeof(gi_detp_segment) */
    uint64_t p0, p1;       /* the batch's photons [p0, p1) */
    uint64_t count;        /* segments */
    uint32_t frame;
    uint32_t kind;         /* GI_DETP_STORE_BASE or _DELTA (detp_batch.h) */
    uint32_t prev_base;    /* a base's previous base frame, or GI_DETP_STORE_NO_BASE */
    uint32_t records_crc;  /* CRC32C of the records */
    uint32_t header_crc;   /* CRC32C of the bytes before this field */
    uint32_t reserved;     /* zero */
} gi_detp_store_header;

enum { GI_DETP_STORE_BASE = 0, GI_DETP_STORE_DELTA = 1 };
#define GI_DETP_STORE_NO_BASE 0xFFFFFFFFu

typedef struct gi_detp_store_mapping {
    gi_detp_store_header header;
    const gi_detp_segment *seg; /* count records, read-only (mmap'ed) */
    size_t count;
    void *base; /* mapping (NULL if none) */
    size_t len;
    uint64_t dev, ino; /* the file mapped */
} gi_detp_store_mapping;

/* Writes the segments behind a header (temp name, rename: a reader sees
 * the old file, no file or the whole new one). The caller fills p0, p1,
 * frame, kind and prev_base. No fsync: the store is a cache, and a file a
 * crash tore reads as invalid (CRC), which means "regenerate". */
int gi_detp_store_write(const char *path, const gi_detp_store_header *h,
                        const gi_detp_segments *s, gi_error *err);
/* The records CRC a store file of these segments has. */
uint32_t gi_detp_store_records_crc(const gi_detp_segments *s);
/* Maps a store file. Returns 1 if it is valid (size, header, CRCs, records
 * path-ordered within [p0, p1) with finite origins, directions and
 * energies), 0 if it is missing, truncated or invalid (regenerate it; err
 * says why), -1 on an I/O error. The caller checks m->header's p0, p1,
 * frame against what it expects. */
int gi_detp_store_map(const char *path, gi_detp_store_mapping *m, gi_error *err);
void gi_detp_store_unmap(gi_detp_store_mapping *m);
/* A read-only gi_detp_segments view of a mapping (cap 0: never push). */
static inline gi_detp_segments gi_detp_store_view(const gi_detp_store_mapping *m)
{
    gi_detp_segments s = {(gi_detp_segment *)m->seg, m->count, 0};
    return s;
}

/* ---- Incremental update (detp_anim_update.c) ------------------------ */

/* Bounding sphere of the mobile at one pose. */
typedef struct gi_detp_mobile_pose {
    gi_vec3 c;
    float r;
} gi_detp_mobile_pose;

/* The bounding sphere of an object at its current positions: centre = the
 * centre of its vertices' box, radius = the largest distance to a vertex. */
gi_detp_mobile_pose gi_detp_object_sphere(const gi_scene *s, uint32_t object);

/* A radius about b.c (the object's sphere) that holds every point of every
 * disc of the object's vertices (radius `radius`, in each vertex's tangent
 * plane), with a margin for rounding: no segment that stays farther from
 * b.c can cross one. For a sphere mesh it is sqrt(R^2 + radius^2), not
 * R + radius. */
float gi_detp_object_disc_reach(const gi_scene *s, uint32_t object, gi_detp_mobile_pose b,
                                float radius);

typedef struct gi_detp_anim_update_in {
    const gi_detp_segment *prev; /* the previous frame's segments, path-ordered */
    size_t prev_count;
    const gi_detp_tracer *tracer; /* rt at the NEW pose, frame = the new frame */
    uint32_t mobile_first_tri, mobile_tri_count; /* the mobile's global triangles */
    gi_detp_mobile_pose old_pose, new_pose;
    RTCScene mobile_scene; /* the mobile alone at the new pose (gi_rt_object_scene) */
    gi_detp_artifact artifact; /* for gi_detp_set_extent of new segments */
    float eps;
    /* Time tests and retraces apart (the stats' seconds_*): two clock
     * reads per retrace, about 1% of a small mobile's frame. */
    int timed;
    /* The mobile did not move (gi_anim_still): every segment stays. */
    int still;
} gi_detp_anim_update_in;

typedef struct gi_detp_update_stats {
    uint64_t paths;          /* paths seen */
    uint64_t segments;       /* segments tested */
    uint64_t sphere_passes;  /* bounding-sphere pre-tests passed (new pose, t < t_hit) */
    uint64_t mobile_tests;   /* exact rays against the mobile-only scene */
    uint64_t mobile_hits;    /* ... that hit it before t_hit */
    uint64_t old_hits;       /* segments whose old hit was on the mobile */
    uint64_t paths_retraced;
    uint64_t second_tests;   /* rule 1: t_second recomputed (one ray each) */
    uint64_t second_changed; /* ... and different */
    uint64_t old_segments, new_segments;
    double seconds_test;    /* pre-tests and mobile rays (if timed) */
    double seconds_retrace; /* retraced suffixes and t_second rays (if timed) */
} gi_detp_update_stats;

/* Thesis Fig. 4.2. Appends to `next` the frame's segments (path-ordered),
 * to old_list the segments dropped and to new_list those added (both
 * path-ordered, extents set). A path is retraced from its first segment
 * that hit the mobile at the old pose or meets it at the new pose strictly
 * before its stored hit; with rule 1 (tracer->second_hit), t_second is
 * recomputed where the mobile at either pose may lie in [t_hit, t_second].
 * Stats are added to *st. Returns 0, or -1 if prev is not path-ordered. */
int gi_detp_anim_update(const gi_detp_anim_update_in *in, gi_detp_segments *next,
                        gi_detp_segments *old_list, gi_detp_segments *new_list,
                        gi_detp_update_stats *st, gi_error *err);

/* The same for one path (its segments in bounce order): its segments for
 * the new frame go to `out` - all of them if keep_unchanged, else only if
 * the path changed (then its whole new run). Returns 1 if it changed. The
 * caller checks the order; seconds_test is left to the caller. */
int gi_detp_anim_update_path(const gi_detp_anim_update_in *in, const gi_detp_segment *path,
                             size_t n, int keep_unchanged, gi_detp_segments *out,
                             gi_detp_segments *old_list, gi_detp_segments *new_list,
                             gi_detp_update_stats *st);

/* The part [t0, t1] of org + t dir (unit dir; t1 may be infinite) may come
 * within the sphere. The radius is grown well beyond float error at the
 * scale of the ray and the sphere: a false pass only costs an exact test. */
int gi_detp_ray_may_meet(gi_vec3 org, gi_vec3 dir, float t0, float t1, gi_detp_mobile_pose m);

/* A superset of the segments the update retraces from: the first test of
 * gi_detp_anim_update_path without its exact ray (the stored hit is the
 * mobile's, triangles [m0, m0 + mn), or the segment comes near the mobile
 * at `pose` before its hit). */
int gi_detp_anim_may_retrace(const gi_detp_segment *g, uint32_t m0, uint32_t mn,
                             gi_detp_mobile_pose pose);

/* The mobile's vertices from scratch (thesis 4.5): one disc per vertex of
 * `object` at its current pose (radius `radius`), estimated against all of
 * `segs` as `how` says: the Sphere Cache rooted at the object's bounding
 * sphere grown by the radius (sc given; segments missing that sphere are
 * dropped first), Embree Disc Indexing over the discs (device given), or
 * the discs in lanes (gi_detp_lanes_estimate): the same pairs. The Sphere
 * Cache and the lanes visit the discs in `order` (the object's vertices,
 * 0-based; gi_detp_anim_mobile_order) or, if NULL, in one computed here.
 * acc is a fixed-point accumulator indexed by GLOBAL vertex: the object's
 * entries are cleared and then set; the others are untouched. */
int gi_detp_anim_mobile_estimate(const gi_scene *s, uint32_t object, float radius,
                                 const gi_detp_segments *segs, gi_detp_mobile_estimator how,
                                 const gi_detp_sc_params *sc, const uint32_t *order,
                                 RTCDevice device, gi_detp_accum *acc, gi_detp_stats *st,
                                 gi_error *err);

/* The order in which gi_detp_anim_mobile_estimate(how, sc) visits the
 * object's discs, from their current pose (malloc'ed; *out NULL for the
 * Embree estimator, which has none). The mobile is rigid: an order computed
 * at one pose serves every pose (thesis 4.6), and any order gives the same
 * sums. */
int gi_detp_anim_mobile_order(const gi_scene *s, uint32_t object, gi_detp_mobile_estimator how,
                              const gi_detp_sc_params *sc, uint32_t **out, gi_error *err);

#endif
