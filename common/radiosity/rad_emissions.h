/* rad_emissions: emission sets for relighting (docs/job-format.md,
 * "Emissions file").
 *
 *   {"emissions": [
 *     {"name": "scene"},
 *     {"name": "blue", "materials": {"light": [2, 4, 17]}},
 *     {"name": "lamp", "base": "none", "objects": {"tall_block": [5, 5, 5]}, "scale": 2}
 *   ]}
 *
 * Each set starts from the scene's own emission ("base": "scene", the
 * default) or from darkness ("none"), replaces the emitted radiance of the
 * named materials, then of the named objects (an object override wins over
 * its material's), then multiplies by "scale". A job may give the same list
 * inline as "radiosity.emissions". */
#ifndef GI_RAD_EMISSIONS_H
#define GI_RAD_EMISSIONS_H

#include <stdint.h>

#include <cjson/cJSON.h>

#include "gi_error.h"
#include "gi_json.h"
#include "gi_scene.h"
#include "rad_model.h"

#define GI_RAD_MAX_EMISSIONS 1024
#define GI_RAD_EMISSION_NAME_MAX 64
#define GI_RAD_MAX_RADIANCE 1e12

typedef struct gi_rad_override {
    char *name;
    float rgb[3];
} gi_rad_override;

typedef struct gi_rad_emission {
    char *name;
    int base_none; /* start from darkness instead of the scene's emission */
    float scale;
    uint32_t material_count, object_count;
    gi_rad_override *materials, *objects;
} gi_rad_emission;

typedef struct gi_rad_emissions {
    uint32_t count;
    gi_rad_emission *items;
} gi_rad_emissions;

/* An emissions file: a JSON object {"emissions": [...]}. Bad input fails
 * with GI_EINVAL and a message naming the file and field. */
int gi_rad_emissions_parse(const char *text, size_t len, const char *file, gi_rad_emissions *out,
                           gi_error *err);
/* The list itself (a job's inline "emissions"); path names it in messages. */
int gi_rad_emissions_parse_json(gi_jv *v, const cJSON *list, const char *path,
                                gi_rad_emissions *out);
void gi_rad_emissions_free(gi_rad_emissions *em);

/* The set with only the scene's emission, named "scene". */
void gi_rad_emissions_scene(gi_rad_emissions *em);

/* "a, b, c": the names an unknown one was meant to be, for an error
 * message, cut with "..." to fit cap (a mesh file may bring hundreds). */
const char *gi_rad_name_list(char *buf, size_t cap, uint32_t count,
                             const char *(*name)(const void *ctx, uint32_t i), const void *ctx);
/* Checks that every material and object named exists in the model, and
 * that no named material is two-sided (as gi_rad_emissions_check_scene;
 * GI_EINVAL naming `file`, the set and the name). */
int gi_rad_emissions_check(const gi_rad_emissions *em, const gi_rad_model *md, const char *file,
                           gi_error *err);
/* Checks that every material and object named exists in the scene, and
 * that no named material is two-sided (radiosity's elements emit from
 * their front face only: half its light would be lost). GI_EINVAL naming
 * `file` and the field, `list` being the list's own: "radiosity.emissions"
 * in a job, "emissions" in an emissions file. */
int gi_rad_emissions_check_scene(const gi_rad_emissions *em, const gi_scene *s, const char *file,
                                 const char *list, gi_error *err);
/* The emission vector of set i: n x 3 radiance per element. */
void gi_rad_emission_vector(const gi_rad_emissions *em, uint32_t i, const gi_rad_model *md,
                            float *E);

#endif
