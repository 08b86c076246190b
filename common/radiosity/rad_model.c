/* rad_model: scene facts kept for relighting. */
#include "rad_model.h"

#include <stdlib.h>
#include <string.h>

int gi_rad_model_build(gi_rad_model *md, const gi_rad_mesh *m, const gi_scene *s, gi_error *err)
{
    memset(md, 0, sizeof *md);
    md->n = m->element_count;
    md->material_count = s->material_count;
    md->object_count = s->object_count;
    md->materials = gi_xcalloc(s->material_count ? s->material_count : 1, sizeof *md->materials);
    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *mt = &s->materials[i];
        md->materials[i].name = gi_xstrdup(mt->name);
        md->materials[i].rho[0] = mt->diffuse.x;
        md->materials[i].rho[1] = mt->diffuse.y;
        md->materials[i].rho[2] = mt->diffuse.z;
        md->materials[i].emission[0] = mt->emission.x;
        md->materials[i].emission[1] = mt->emission.y;
        md->materials[i].emission[2] = mt->emission.z;
        md->materials[i].two_sided = mt->two_sided;
    }
    md->objects = gi_xcalloc(s->object_count ? s->object_count : 1, sizeof *md->objects);
    for (uint32_t i = 0; i < s->object_count; i++)
        md->objects[i] = gi_xstrdup(s->objects[i].name);
    md->elem_material =
        gi_try_malloc((size_t)md->n * sizeof *md->elem_material, err, "radiosity model");
    md->elem_object =
        gi_try_malloc((size_t)md->n * sizeof *md->elem_object, err, "radiosity model");
    md->area = gi_try_malloc((size_t)md->n * sizeof *md->area, err, "radiosity model");
    if (!md->elem_material || !md->elem_object || !md->area) {
        gi_rad_model_free(md);
        return -1;
    }
    for (uint32_t e = 0; e < md->n; e++) {
        uint32_t t = gi_rad_mesh_element_tri(m, e);
        md->elem_material[e] = s->tri_material[t];
        md->elem_object[e] = s->tri_object[t];
        md->area[e] = gi_rad_mesh_element_area(m, e);
    }
    if (gi_rad_vertices_build(&md->vertices, m, s, err)) {
        gi_rad_model_free(md);
        return -1;
    }
    return 0;
}

void gi_rad_model_free(gi_rad_model *md)
{
    for (uint32_t i = 0; md->materials && i < md->material_count; i++)
        free(md->materials[i].name);
    free(md->materials);
    for (uint32_t i = 0; md->objects && i < md->object_count; i++)
        free(md->objects[i]);
    free(md->objects);
    free(md->elem_material);
    free(md->elem_object);
    free(md->area);
    gi_rad_vertices_free(&md->vertices);
    memset(md, 0, sizeof *md);
}

void gi_rad_model_reflectance(const gi_rad_model *md, float *rho)
{
    for (uint32_t e = 0; e < md->n; e++)
        memcpy(&rho[3 * (size_t)e], md->materials[md->elem_material[e]].rho, 3 * sizeof *rho);
}

int gi_rad_model_find_material(const gi_rad_model *md, const char *name)
{
    for (uint32_t i = 0; i < md->material_count; i++)
        if (strcmp(md->materials[i].name, name) == 0)
            return (int)i;
    return -1;
}

int gi_rad_model_find_object(const gi_rad_model *md, const char *name)
{
    for (uint32_t i = 0; i < md->object_count; i++)
        if (strcmp(md->objects[i], name) == 0)
            return (int)i;
    return -1;
}
