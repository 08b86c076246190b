/* rad_emissions: parsing and applying emission sets. */
#include "rad_emissions.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > GI_RAD_EMISSION_NAME_MAX || s[0] == '.' || s[0] == '-')
        return 0;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
              *p == '.' || *p == '_' || *p == '-'))
            return 0;
    return 1;
}

static int parse_overrides(gi_jv *v, const cJSON *map, const char *path, uint32_t *count,
                           gi_rad_override **out)
{
    *count = 0;
    *out = NULL;
    if (!map)
        return 0;
    if (gi_jv_object(v, map, path))
        return -1;
    uint32_t n = 0;
    for (const cJSON *it = map->child; it; it = it->next)
        n++;
    if (n > 65536)
        return gi_jv_fail(v, path, "more than 65536 overrides");
    *out = gi_xcalloc(n ? n : 1, sizeof **out);
    for (const cJSON *it = map->child; it; it = it->next) {
        char p[512];
        gi_json_path(p, sizeof p, path, it->string);
        for (uint32_t i = 0; i < *count; i++)
            if (strcmp((*out)[i].name, it->string) == 0)
                return gi_jv_fail(v, p, "given twice");
        gi_rad_override *o = &(*out)[(*count)++];
        o->name = gi_xstrdup(it->string);
        if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
            return gi_jv_fail(v, p, "expected [r, g, b] emitted radiance");
        int c = 0;
        for (const cJSON *x = it->child; x; x = x->next, c++) {
            char pc[540];
            double d;
            if (gi_jv_value_number(v, x, gi_json_index_path(pc, sizeof pc, p, c), 0.0,
                                   GI_RAD_MAX_RADIANCE, &d))
                return -1;
            o->rgb[c] = (float)d;
        }
    }
    return 0;
}

int gi_rad_emissions_parse_json(gi_jv *v, const cJSON *list, const char *path,
                                gi_rad_emissions *out)
{
    memset(out, 0, sizeof *out);
    if (!cJSON_IsArray(list))
        return gi_jv_fail(v, path, "expected an array of emission sets");
    int n = cJSON_GetArraySize(list);
    if (n < 1 || n > GI_RAD_MAX_EMISSIONS)
        return gi_jv_fail(v, path, "expected 1 to %d emission sets, got %d", GI_RAD_MAX_EMISSIONS,
                          n);
    out->items = gi_xcalloc((size_t)n, sizeof *out->items);
    static const char *const keys[] = {"name", "base", "materials", "objects", "scale", NULL};
    static const char *const bases[] = {"scene", "none", NULL};
    int i = 0;
    for (const cJSON *it = list->child; it; it = it->next, i++) {
        char p[256], pm[300];
        gi_json_index_path(p, sizeof p, path, i);
        gi_rad_emission *em = &out->items[out->count++];
        em->scale = 1.0f;
        const char *name;
        int base = 0;
        double scale = 1.0;
        const cJSON *mats, *objs;
        if (gi_jv_object(v, it, p) || gi_jv_keys(v, it, p, keys) ||
            gi_jv_string(v, it, p, "name", 1, &name) ||
            gi_jv_enum(v, it, p, "base", 0, bases, &base) ||
            gi_jv_number(v, it, p, "scale", 0, 0.0, GI_RAD_MAX_RADIANCE, &scale) ||
            gi_jv_member_object(v, it, p, "materials", 0, &mats) ||
            gi_jv_member_object(v, it, p, "objects", 0, &objs))
            return -1;
        if (!valid_name(name))
            return gi_jv_fail(v, gi_json_path(pm, sizeof pm, p, "name"),
                              "must be 1-%d letters, digits, '.', '_' or '-' (not starting "
                              "with '.' or '-')",
                              GI_RAD_EMISSION_NAME_MAX);
        for (uint32_t j = 0; j + 1 < out->count; j++)
            if (strcmp(out->items[j].name, name) == 0)
                return gi_jv_fail(v, gi_json_path(pm, sizeof pm, p, "name"),
                                  "\"%s\" is already the name of set %u", name, j);
        em->name = gi_xstrdup(name);
        em->base_none = base == 1;
        em->scale = (float)scale;
        if (parse_overrides(v, mats, gi_json_path(pm, sizeof pm, p, "materials"),
                            &em->material_count, &em->materials) ||
            parse_overrides(v, objs, gi_json_path(pm, sizeof pm, p, "objects"), &em->object_count,
                            &em->objects))
            return -1;
    }
    return 0;
}

int gi_rad_emissions_parse(const char *text, size_t len, const char *file, gi_rad_emissions *out,
                           gi_error *err)
{
    memset(out, 0, sizeof *out);
    cJSON *doc;
    if (gi_json_parse(text, len, file, &doc, err))
        return -1;
    gi_jv v = {file, err};
    static const char *const keys[] = {"emissions", "description", NULL};
    const cJSON *list;
    const char *desc;
    int rc = gi_jv_keys(&v, doc, "", keys) || gi_jv_string(&v, doc, "", "description", 0, &desc) ||
             gi_jv_member_array(&v, doc, "", "emissions", 1, &list) ||
             gi_rad_emissions_parse_json(&v, list, "emissions", out);
    cJSON_Delete(doc);
    if (rc) {
        gi_rad_emissions_free(out);
        return -1;
    }
    return 0;
}

static void free_overrides(gi_rad_override *o, uint32_t n)
{
    for (uint32_t i = 0; o && i < n; i++)
        free(o[i].name);
    free(o);
}

void gi_rad_emissions_free(gi_rad_emissions *em)
{
    for (uint32_t i = 0; em->items && i < em->count; i++) {
        free(em->items[i].name);
        free_overrides(em->items[i].materials, em->items[i].material_count);
        free_overrides(em->items[i].objects, em->items[i].object_count);
    }
    free(em->items);
    memset(em, 0, sizeof *em);
}

void gi_rad_emissions_scene(gi_rad_emissions *em)
{
    memset(em, 0, sizeof *em);
    em->count = 1;
    em->items = gi_xcalloc(1, sizeof *em->items);
    em->items[0].name = gi_xstrdup("scene");
    em->items[0].scale = 1.0f;
}

const char *gi_rad_name_list(char *buf, size_t cap, uint32_t count,
                             const char *(*name)(const void *ctx, uint32_t i), const void *ctx)
{
    size_t len = 0;
    buf[0] = '\0';
    for (uint32_t i = 0; i < count; i++) {
        const char *s = name(ctx, i);
        size_t need = strlen(s) + (i ? 2 : 0);
        if (len + need + 5 >= cap) { /* room for ", ..." */
            snprintf(buf + len, cap - len, "%s...", i ? ", " : "");
            break;
        }
        len += (size_t)snprintf(buf + len, cap - len, "%s%s", i ? ", " : "", s);
    }
    return buf;
}

static const char *material_name(const void *md, uint32_t i)
{
    return ((const gi_rad_model *)md)->materials[i].name;
}

static const char *object_name(const void *md, uint32_t i)
{
    return ((const gi_rad_model *)md)->objects[i];
}

int gi_rad_emissions_check(const gi_rad_emissions *em, const gi_rad_model *md, const char *file,
                           gi_error *err)
{
    char names[400];
    for (uint32_t i = 0; i < em->count; i++) {
        const gi_rad_emission *e = &em->items[i];
        for (uint32_t j = 0; j < e->material_count; j++) {
            int m = gi_rad_model_find_material(md, e->materials[j].name);
            if (m < 0)
                return gi_fail(err, GI_EINVAL,
                               "%s: emissions[%u] (\"%s\"): no material \"%s\" in the scene "
                               "(its materials: %s)",
                               file, i, e->name, e->materials[j].name,
                               gi_rad_name_list(names, sizeof names, md->material_count,
                                                material_name, md));
            if (md->materials[m].two_sided)
                return gi_fail(err, GI_EINVAL,
                               "%s: emissions[%u] (\"%s\"): material \"%s\" is two-sided, and "
                               "radiosity's elements emit from their front face only",
                               file, i, e->name, e->materials[j].name);
        }
        for (uint32_t j = 0; j < e->object_count; j++)
            if (gi_rad_model_find_object(md, e->objects[j].name) < 0)
                return gi_fail(err, GI_EINVAL,
                               "%s: emissions[%u] (\"%s\"): no object \"%s\" in the scene "
                               "(its objects: %s)",
                               file, i, e->name, e->objects[j].name,
                               gi_rad_name_list(names, sizeof names, md->object_count,
                                                object_name, md));
    }
    return 0;
}

static const char *scene_material(const void *s, uint32_t i)
{
    return ((const gi_scene *)s)->materials[i].name;
}

static const char *scene_object(const void *s, uint32_t i)
{
    return ((const gi_scene *)s)->objects[i].name;
}

int gi_rad_emissions_check_scene(const gi_rad_emissions *em, const gi_scene *s, const char *file,
                                 const char *list, gi_error *err)
{
    char names[400];
    for (uint32_t i = 0; i < em->count; i++) {
        const gi_rad_emission *e = &em->items[i];
        for (uint32_t j = 0; j < e->material_count; j++) {
            int m = gi_scene_material_index(s, e->materials[j].name);
            if (m < 0)
                return gi_fail(err, GI_EINVAL,
                               "%s: %s[%u].materials: no material \"%s\" in the scene (its "
                               "materials: %s)",
                               file, list, i, e->materials[j].name,
                               gi_rad_name_list(names, sizeof names, s->material_count,
                                                scene_material, s));
            if (s->materials[m].two_sided)
                return gi_fail(err, GI_EINVAL,
                               "%s: %s[%u].materials: \"%s\" is two-sided, and radiosity's "
                               "elements emit from their front face only",
                               file, list, i, e->materials[j].name);
        }
        for (uint32_t j = 0; j < e->object_count; j++)
            if (gi_scene_find_object(s, e->objects[j].name) < 0)
                return gi_fail(err, GI_EINVAL,
                               "%s: %s[%u].objects: no object \"%s\" in the scene (its objects: "
                               "%s)",
                               file, list, i, e->objects[j].name,
                               gi_rad_name_list(names, sizeof names, s->object_count,
                                                scene_object, s));
    }
    return 0;
}

void gi_rad_emission_vector(const gi_rad_emissions *em, uint32_t i, const gi_rad_model *md,
                            float *E)
{
    const gi_rad_emission *set = &em->items[i];
    /* Per material and per object radiance, then per element. */
    float *mat = gi_xcalloc((size_t)md->material_count * 3 + 3, sizeof *mat);
    float *obj = gi_xcalloc((size_t)md->object_count * 3 + 3, sizeof *obj);
    uint8_t *obj_set = gi_xcalloc((size_t)md->object_count + 1, 1);
    for (uint32_t m = 0; m < md->material_count; m++)
        if (!set->base_none)
            memcpy(&mat[3 * m], md->materials[m].emission, 3 * sizeof *mat);
    for (uint32_t j = 0; j < set->material_count; j++) {
        int m = gi_rad_model_find_material(md, set->materials[j].name);
        if (m >= 0)
            memcpy(&mat[3 * m], set->materials[j].rgb, 3 * sizeof *mat);
    }
    for (uint32_t j = 0; j < set->object_count; j++) {
        int o = gi_rad_model_find_object(md, set->objects[j].name);
        if (o >= 0) {
            memcpy(&obj[3 * o], set->objects[j].rgb, 3 * sizeof *obj);
            obj_set[o] = 1;
        }
    }
    for (uint32_t e = 0; e < md->n; e++) {
        uint32_t o = md->elem_object[e];
        const float *src = obj_set[o] ? &obj[3 * o] : &mat[3 * md->elem_material[e]];
        for (int c = 0; c < 3; c++)
            E[3 * (size_t)e + c] = src[c] * set->scale;
    }
    free(mat);
    free(obj);
    free(obj_set);
}
