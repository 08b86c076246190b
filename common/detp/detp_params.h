/* detp_params: the "detp" block of a job (docs/job-format.md), parsed and
 * validated strictly, and the values derived from the scene (automatic
 * radius and photon count). */
#ifndef GI_DETP_PARAMS_H
#define GI_DETP_PARAMS_H

#include <stdint.h>

#include "detp.h"
#include "gi_anim.h"
#include "gi_json.h"

typedef enum {
    GI_DETP_EST_IMPACT_COUNT,
    GI_DETP_EST_PHOTON_MAP,
    GI_DETP_EST_BASIC,
    GI_DETP_EST_SPHERE_CACHE,
    GI_DETP_EST_MULTILIST,
    GI_DETP_EST_OCTREE,
    GI_DETP_EST_EMBREE
} gi_detp_estimator;

extern const char *const gi_detp_estimator_names[];

/* How the mobile's own vertices are estimated each frame (thesis 1.12.4). */
typedef enum {
    GI_DETP_MOBILE_SPHERE_CACHE, /* Sphere Cache rooted at the mobile's bounding sphere */
    GI_DETP_MOBILE_EMBREE,       /* Disc Indexing (Embree) over the mobile's discs only */
    GI_DETP_MOBILE_LANES         /* every disc group near a segment, in vector lanes */
} gi_detp_mobile_estimator;

extern const char *const gi_detp_mobile_estimator_names[];

/* How a frame after the first is computed. Both trace the same paths; "full"
 * estimates every vertex from scratch over the frame's segments (for checks
 * and benchmarks: the incremental result must equal it bit for bit). */
typedef enum { GI_DETP_UPDATE_INCREMENTAL, GI_DETP_UPDATE_FULL } gi_detp_anim_update_mode;

extern const char *const gi_detp_anim_update_names[];

/* A length given as scene units, as a percentage of the scene size ("2%"),
 * or "auto". */
typedef enum { GI_DETP_LEN_UNITS, GI_DETP_LEN_PERCENT, GI_DETP_LEN_AUTO } gi_detp_len_kind;
typedef struct gi_detp_len {
    gi_detp_len_kind kind;
    double value;
} gi_detp_len;

#define GI_DETP_MAX_PHOTONS ((int64_t)1 << 40)
#define GI_DETP_MAX_BATCH ((int64_t)1 << 24)

typedef struct gi_detp_params {
    /* As given. */
    int64_t photons;       /* 0: automatic from relative_error */
    double relative_error; /* target of eq. 3.46 when photons is "auto" */
    int64_t batch;         /* photons per task */
    gi_detp_len radius;
    gi_detp_len subdivide; /* value 0: no refinement */
    gi_detp_estimator estimator;
    gi_detp_artifact artifact;
    int max_bounces;
    gi_detp_sc_params sc;
    gi_detp_octree_params octree;
    uint32_t pm_k;
    int pm_k_minus_one;
    uint32_t reference_spp;      /* 0: no path-traced reference */
    uint32_t reference_vertices; /* how many vertices get one (evenly spread) */
    int tile, image_spp;
    gi_anim anim; /* detp.animation; anim.enabled = 0 without one */
    gi_detp_mobile_estimator mobile_estimator; /* detp.animation's */
    gi_detp_anim_update_mode anim_update;      /* detp.animation.update */

    /* Derived from the (refined) scene in check_scene: the same on the
     * coordinator and on every worker. */
    double scene_size;   /* largest bounding box edge */
    double mean_spacing; /* mean edge length d_P */
    double hull_area;    /* A_0 */
    float disc_radius;   /* d */
    uint64_t photon_count;
    float extent_eps; /* see gi_detp_set_extent */
} gi_detp_params;

int gi_detp_parse_params(gi_detp_params *p, const cJSON *block, gi_jv *v);
/* Refines the scene if asked and resolves the derived values. */
int gi_detp_resolve_params(gi_detp_params *p, gi_scene *scene, const char *file,
                           gi_error *err);

#endif
