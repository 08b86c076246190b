/* rad_model: what relighting needs to know about the scene besides the
 * factorization: the materials and objects (emission overrides are given
 * by name), which of them each element belongs to, element areas, and the
 * shared vertices (per-vertex output). It travels in the factorization
 * file, so relighting needs neither the scene nor Embree. */
#ifndef GI_RAD_MODEL_H
#define GI_RAD_MODEL_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_scene.h"
#include "rad_mesh.h"
#include "rad_vertices.h"

typedef struct gi_rad_material {
    char *name;
    float rho[3];      /* diffuse reflectance */
    float emission[3]; /* emitted radiance (front faces) */
    int two_sided;     /* the scene's material emits from both faces: radiosity's
                        * elements cannot, so an emission set may not name it */
} gi_rad_material;

typedef struct gi_rad_model {
    uint32_t n;
    uint32_t material_count, object_count;
    gi_rad_material *materials;
    char **objects;
    uint32_t *elem_material, *elem_object; /* n each */
    double *area;                          /* n */
    gi_rad_vertices vertices;
} gi_rad_model;

int gi_rad_model_build(gi_rad_model *md, const gi_rad_mesh *m, const gi_scene *s, gi_error *err);
void gi_rad_model_free(gi_rad_model *md);

/* Reflectances per element and colour (n x 3). */
void gi_rad_model_reflectance(const gi_rad_model *md, float *rho);

int gi_rad_model_find_material(const gi_rad_model *md, const char *name);
int gi_rad_model_find_object(const gi_rad_model *md, const char *name);

#endif
