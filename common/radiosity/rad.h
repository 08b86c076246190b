/* rad: the `radiosity` method - low-rank radiosity with fast relighting
 * (Fernandez 2010, digests/lowrank-radiosity-thesis-001.md).
 *
 * A job meshes the scene into n equal-area elements grouped into k patches
 * (rad_mesh, rad_patches, rad_2mce), estimates the form factors F_ep by
 * ray casting on the farm (rad_rays, rad_ff: a task is a block of elements,
 * its result their rows), places the rows into U (2MF / 2MCE, eq. 3.53),
 * precomputes the k x k SMW matrices (rad_factor, eq. 3.33) and solves
 * every emission set (rad_relight). It writes the factorization (rad_file)
 * so that `gi relight` can answer new emissions in milliseconds, the
 * per-vertex radiosity (PLY), camera images (tile tasks, Gouraud
 * interpolation in the elements; with a camera path, each frame's image
 * from its camera) and a JSON report.
 *
 * Validation pieces, not used by jobs: truncated SVD, CUR and ACA
 * (rad_lowrank.h), the dense reference solve, the moving-object update
 * (rad_dynamic.h). */
#ifndef GI_RAD_H
#define GI_RAD_H

#include <stdint.h>

#include "gi_anim.h"
#include "gi_method.h"
#include "rad_emissions.h"
#include "rad_factor.h"
#include "rad_file.h"
#include "rad_model.h"
#include "rad_relight.h"

typedef enum { GI_RAD_2MF = 0, GI_RAD_2MCE = 1 } gi_rad_method_kind;

typedef struct gi_rad_params {
    gi_rad_method_kind factorization;
    uint32_t patches;        /* target level-0 patch count */
    uint32_t levels;         /* levels from the roots to the elements */
    uint32_t patch_level;    /* 2MF: level of the patches */
    uint32_t max_level;      /* 2MCE: maxnivel */
    uint32_t target_patches; /* 2MCE: tune the threshold for this k (0: see docs) */
    double threshold;        /* 2MCE: or use this threshold (eq. 3.61) */
    int has_threshold;
    uint32_t rays;          /* per element */
    uint32_t task_elements; /* 0: automatic */
    gi_rad_solve_opts solve;
    gi_rad_emissions emissions; /* the job's sets (or the scene's own) */
    int has_emissions;          /* given in the job */
    int image_spp, tile;
    /* radiosity.animation: a camera path only (anim.enabled = 0 without
     * one); the solution, view-independent, is computed once. */
    gi_anim anim;

    /* Relight mode (`gi relight --images`): a loaded factorization and the
     * emission sets to render; the job then plans only image tiles. Owned
     * by the caller. */
    const gi_rad_file_info *relight_info;
    const gi_rad_model *relight_model;
    const gi_rad_factor *relight_factor;
    const gi_rad_emissions *relight_emissions;
} gi_rad_params;

extern const gi_method gi_method_radiosity;

/* Scene elements per level-0 patch target: patch_area = total / patches. */
double gi_rad_patch_area(const gi_scene *s, uint32_t patches);

#endif
