/* detp_params: the "detp" block of a job (docs/job-format.md), parsed and
 * validated strictly, and the values derived from the scene (automatic
 * radius and photon count). */
#ifndef GI_DETP_PARAMS_H
#define GI_DETP_PARAMS_H

#include <stdint.h>

#include "detp.h"
#include "detp_anim_params.h"
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
    gi_detp_anim_params anim; /* detp.animation; anim.enabled = 0 without one */

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
