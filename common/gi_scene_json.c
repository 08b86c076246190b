/* gi_scene_json: the scene file format (docs/scene-format.md).
 *
 * { "camera": {...}, "materials": {"name": {...}, ...}, "objects": [...] }
 * Each object has exactly one geometry: "mesh" (a file), "polygons" (inline
 * vertices and faces), "quad", "box" or "sphere"; a "material" (optional for
 * mesh files, which carry their own); a "transform" (a list of steps); a
 * "name"; and "mobile". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_camera.h"
#include "gi_fs.h"
#include "gi_json.h"
#include "gi_mesh.h"
#include "gi_polygon.h"
#include "gi_scene_build.h"

#define MAX_COORD 1e12
#define MAX_INLINE_VERTICES 10000000
#define MAX_SPHERE_SUBDIVISIONS 8

static int parse_materials(gi_jv *v, gi_scene_builder *b, const cJSON *mats)
{
    if (gi_jv_object(v, mats, "materials"))
        return -1;
    static const char *const keys[] = {"diffuse", "emission", "two_sided", NULL};
    for (const cJSON *m = mats->child; m; m = m->next) {
        char path[512];
        gi_json_path(path, sizeof path, "materials", m->string);
        if (!m->string[0])
            return gi_jv_fail(v, "materials", "a material has an empty name");
        if (strlen(m->string) > GI_SCENE_NAME_MAX)
            return gi_jv_fail(v, "materials", "a material's name is %zu bytes long, over the "
                              "limit of %d", strlen(m->string), GI_SCENE_NAME_MAX);
        if (gi_jv_keys(v, m, path, keys))
            return -1;
        gi_material mat = {0};
        mat.name = m->string;
        if (gi_jv_vec3(v, m, path, "diffuse", 0, 0.0, 1.0, &mat.diffuse) ||
            gi_jv_vec3(v, m, path, "emission", 0, 0.0, 1e30, &mat.emission) ||
            gi_jv_bool(v, m, path, "two_sided", 0, &mat.two_sided))
            return -1;
        if (gi_scene_add_material(b, &mat, v->err) < 0)
            return -1;
    }
    return 0;
}

/* "transform": [ {"translate": [x,y,z]} | {"scale": s or [x,y,z]} |
 *                {"rotate": {"axis": [x,y,z], "degrees": d}} |
 *                {"matrix": [16 numbers, row-major]} , ... ]
 * Steps apply in the order listed (the first step acts on the object first). */
static int parse_transform(gi_jv *v, const cJSON *arr, const char *path, gi_mat4 *out)
{
    *out = gi_mat4_identity();
    if (!arr)
        return 0;
    int i = 0;
    for (const cJSON *st = arr->child; st; st = st->next, i++) {
        char p[600];
        gi_json_index_path(p, sizeof p, path, i);
        static const char *const keys[] = {"translate", "scale", "rotate", "matrix", NULL};
        if (gi_jv_keys(v, st, p, keys))
            return -1;
        if (cJSON_GetArraySize(st) != 1)
            return gi_jv_fail(v, p, "each step has exactly one of translate, scale, rotate, matrix");
        const cJSON *item = st->child;
        gi_mat4 m = gi_mat4_identity();
        char q[700];
        gi_json_path(q, sizeof q, p, item->string);
        if (strcmp(item->string, "translate") == 0) {
            double t[3];
            if (gi_jv_vec3d(v, st, p, "translate", 1, -MAX_COORD, MAX_COORD, t))
                return -1;
            m = gi_mat4_translate(t[0], t[1], t[2]);
        } else if (strcmp(item->string, "scale") == 0) {
            double s[3];
            if (cJSON_IsNumber(item)) {
                if (gi_jv_value_number(v, item, q, -1e9, 1e9, &s[0]))
                    return -1;
                s[1] = s[2] = s[0];
            } else if (gi_jv_vec3d(v, st, p, "scale", 1, -1e9, 1e9, s)) {
                return -1;
            }
            if (s[0] * s[1] * s[2] == 0.0)
                return gi_jv_fail(v, q, "a zero scale flattens the object");
            m = gi_mat4_scale(s[0], s[1], s[2]);
        } else if (strcmp(item->string, "rotate") == 0) {
            static const char *const rkeys[] = {"axis", "degrees", NULL};
            double axis[3], deg;
            if (gi_jv_keys(v, item, q, rkeys) ||
                gi_jv_vec3d(v, item, q, "axis", 1, -1e9, 1e9, axis) ||
                gi_jv_number(v, item, q, "degrees", 1, -1e6, 1e6, &deg))
                return -1;
            if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0)
                return gi_jv_fail(v, q, "the rotation axis is zero");
            m = gi_mat4_rotate(axis[0], axis[1], axis[2], deg);
        } else {
            if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 16)
                return gi_jv_fail(v, q, "expected an array of 16 numbers (row-major 4x4)");
            int k = 0;
            for (const cJSON *e = item->child; e; e = e->next, k++) {
                char r[720];
                if (gi_jv_value_number(v, e, gi_json_index_path(r, sizeof r, q, k), -1e12,
                                       1e12, &m.m[k / 4][k % 4]))
                    return -1;
            }
            if (m.m[3][0] != 0 || m.m[3][1] != 0 || m.m[3][2] != 0 || m.m[3][3] != 1)
                return gi_jv_fail(v, q, "the last row must be [0, 0, 0, 1] (affine)");
        }
        *out = gi_mat4_mul(m, *out);
    }
    return 0;
}

/* "polygons": {"vertices": [[x,y,z], ...], "faces": [[i,j,k,...], ...]}
 * Faces are simple polygons: convex ones are fanned into triangles from
 * their first vertex, concave ones cut into ears (gi_polygon.h). */
static int parse_polygons(gi_jv *v, const cJSON *poly, const char *path, gi_mesh_data *m)
{
    static const char *const keys[] = {"vertices", "faces", NULL};
    const cJSON *verts, *faces;
    if (gi_jv_keys(v, poly, path, keys) ||
        gi_jv_member_array(v, poly, path, "vertices", 1, &verts) ||
        gi_jv_member_array(v, poly, path, "faces", 1, &faces))
        return -1;
    int nv = cJSON_GetArraySize(verts);
    if (nv > MAX_INLINE_VERTICES)
        return gi_jv_fail(v, path, "too many inline vertices (%d, limit %d)", nv,
                          MAX_INLINE_VERTICES);
    m->vertex_count = (uint32_t)nv;
    m->positions = gi_xmalloc(((size_t)nv + 1) * sizeof *m->positions);
    char p[600], q[700];
    gi_json_path(p, sizeof p, path, "vertices");
    int i = 0;
    for (const cJSON *e = verts->child; e; e = e->next, i++) {
        gi_json_index_path(q, sizeof q, p, i);
        if (!cJSON_IsArray(e) || cJSON_GetArraySize(e) != 3)
            return gi_jv_fail(v, q, "expected [x, y, z]");
        double c[3];
        int k = 0;
        for (const cJSON *x = e->child; x; x = x->next, k++) {
            char r[720];
            if (gi_jv_value_number(v, x, gi_json_index_path(r, sizeof r, q, k), -MAX_COORD,
                                   MAX_COORD, &c[k]))
                return -1;
        }
        m->positions[i] = gi_v3((float)c[0], (float)c[1], (float)c[2]);
    }
    gi_json_path(p, sizeof p, path, "faces");
    size_t cap = 0;
    i = 0;
    for (const cJSON *f = faces->child; f; f = f->next, i++) {
        gi_json_index_path(q, sizeof q, p, i);
        int n = cJSON_IsArray(f) ? cJSON_GetArraySize(f) : 0;
        if (n < 3)
            return gi_jv_fail(v, q, "a face needs an array of at least 3 vertex indices");
        uint32_t *ix = gi_xmalloc((size_t)n * sizeof *ix);
        int k = 0;
        for (const cJSON *x = f->child; x; x = x->next, k++) {
            char r[720];
            double d;
            if (gi_jv_value_number(v, x, gi_json_index_path(r, sizeof r, q, k), 0,
                                   (double)nv - 1, &d) ||
                (d != floor(d) && gi_jv_fail(v, r, "a vertex index must be an integer"))) {
                free(ix);
                return -1;
            }
            ix[k] = (uint32_t)d;
        }
        while (m->triangle_count + (size_t)n - 2 > cap) {
            cap = cap ? 2 * cap : 16;
            m->indices = gi_xrealloc(m->indices, cap * 3 * sizeof *m->indices);
        }
        int made = gi_polygon_triangulate(m->positions, ix, n, &m->indices[3 * m->triangle_count]);
        free(ix);
        if (made < 0 && n > GI_POLYGON_MAX_CONCAVE)
            return gi_jv_fail(v, q, "a concave face of more than %d vertices: split it",
                              GI_POLYGON_MAX_CONCAVE);
        if (made < 0)
            return gi_jv_fail(v, q, "its edges cross (not a simple polygon): split it into "
                              "simple ones");
        m->triangle_count += (uint32_t)made;
    }
    if (nv == 0 || m->triangle_count == 0)
        return gi_jv_fail(v, path, "empty mesh: no vertices or no faces");
    m->tri_material = gi_xcalloc(m->triangle_count, sizeof *m->tri_material);
    m->material_count = 1;
    m->materials = gi_xcalloc(1, sizeof *m->materials);
    m->materials[0].name = gi_xstrdup("default");
    return 0;
}

static int parse_shape(gi_jv *v, const cJSON *obj, const char *path, const char *kind,
                       gi_mesh_data *m)
{
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(obj, kind);
    char p[600];
    gi_json_path(p, sizeof p, path, kind);
    if (strcmp(kind, "quad") == 0) {
        static const char *const keys[] = {"size", NULL};
        const cJSON *size;
        double d[2];
        if (gi_jv_keys(v, s, p, keys) || gi_jv_member_array(v, s, p, "size", 1, &size))
            return -1;
        char q[700];
        gi_json_path(q, sizeof q, p, "size");
        if (cJSON_GetArraySize(size) != 2)
            return gi_jv_fail(v, q, "expected [size_x, size_z]");
        if (gi_jv_value_number(v, size->child, q, 1e-9, MAX_COORD, &d[0]) ||
            gi_jv_value_number(v, size->child->next, q, 1e-9, MAX_COORD, &d[1]))
            return -1;
        gi_mesh_quad(m, d[0], d[1]);
    } else if (strcmp(kind, "box") == 0) {
        static const char *const keys[] = {"size", "inward", NULL};
        double d[3];
        int inward = 0;
        if (gi_jv_keys(v, s, p, keys) || gi_jv_vec3d(v, s, p, "size", 1, 1e-9, MAX_COORD, d) ||
            gi_jv_bool(v, s, p, "inward", 0, &inward))
            return -1;
        gi_mesh_box(m, d[0], d[1], d[2], inward);
    } else if (strcmp(kind, "sphere") == 0) {
        static const char *const keys[] = {"radius", "subdivisions", NULL};
        double r = 0;
        int64_t sub = 3;
        if (gi_jv_keys(v, s, p, keys) || gi_jv_number(v, s, p, "radius", 1, 1e-9, MAX_COORD, &r) ||
            gi_jv_int(v, s, p, "subdivisions", 0, 0, MAX_SPHERE_SUBDIVISIONS, &sub))
            return -1;
        gi_mesh_sphere(m, r, (int)sub);
    } else {
        return parse_polygons(v, s, p, m);
    }
    return 0;
}

/* Mesh files that several objects name are imported once per load (an
 * import costs a few milliseconds even for a tiny file: 1,000 instances of
 * one mesh took 18 s when each object imported it, each import in a process
 * of its own). A mesh is kept only while objects still to come name it, and
 * the last of them takes it over. */
typedef struct mesh_ref {
    char *path;         /* normalized, as imported */
    uint32_t uses_left; /* objects still to come that name it */
    int loaded;
    gi_mesh_data mesh;
} mesh_ref;

typedef struct mesh_cache {
    const gi_asset_source *src;
    gi_mesh_importer *importer; /* one importer process for the load's files */
    mesh_ref *refs;
    size_t count, cap;
    gi_name_index index; /* path -> refs[] */
} mesh_cache;

static char *mesh_path(const char *scene_dir, const char *file)
{
    char *joined = gi_path_join(scene_dir, file);
    char *norm = gi_path_normalize(joined);
    free(joined);
    return norm;
}

/* Counts how many objects name each mesh file (what parse_object will find
 * wrong in them is its to say). */
static void mesh_cache_init(mesh_cache *c, const gi_asset_source *src, const char *scene_dir,
                            const cJSON *objs)
{
    memset(c, 0, sizeof *c);
    c->src = src;
    for (const cJSON *o = objs ? objs->child : NULL; o; o = o->next) {
        const cJSON *file = cJSON_IsObject(o) ? cJSON_GetObjectItemCaseSensitive(o, "mesh") : NULL;
        if (!cJSON_IsString(file))
            continue;
        char *path = mesh_path(scene_dir, file->valuestring);
        int64_t i = gi_name_index_find(&c->index, path);
        if (i >= 0) {
            c->refs[i].uses_left++;
            free(path);
            continue;
        }
        if (c->count == c->cap) {
            c->cap = c->cap ? 2 * c->cap : 16;
            c->refs = gi_xrealloc(c->refs, c->cap * sizeof *c->refs);
        }
        mesh_ref *r = &c->refs[c->count];
        memset(r, 0, sizeof *r);
        r->path = path;
        r->uses_left = 1;
        gi_name_index_add(&c->index, path, (uint32_t)c->count++);
    }
}

static void mesh_cache_free(mesh_cache *c)
{
    for (size_t i = 0; i < c->count; i++) {
        free(c->refs[i].path);
        gi_mesh_data_free(&c->refs[i].mesh);
    }
    free(c->refs);
    gi_name_index_free(&c->index);
    gi_mesh_importer_free(c->importer);
}

static int mesh_cache_load(mesh_cache *c, const char *path, gi_mesh_data *out, gi_error *err)
{
    if (!c->importer)
        c->importer = gi_mesh_importer_new(c->src);
    return gi_mesh_importer_run(c->importer, path, out, err);
}

/* The import of `path` (normalized), through the cache. */
static int mesh_cache_import(mesh_cache *c, const char *path, gi_mesh_data *out, gi_error *err)
{
    int64_t i = gi_name_index_find(&c->index, path);
    mesh_ref *r = i >= 0 ? &c->refs[i] : NULL;
    if (!r || (!r->loaded && r->uses_left <= 1)) {
        if (r)
            r->uses_left = 0;
        return mesh_cache_load(c, path, out, err);
    }
    if (!r->loaded) {
        if (mesh_cache_load(c, path, &r->mesh, err))
            return -1;
        r->loaded = 1;
    }
    if (--r->uses_left > 0) {
        gi_mesh_data_copy(out, &r->mesh);
        return 0;
    }
    *out = r->mesh;
    gi_mesh_data_init(&r->mesh);
    r->loaded = 0;
    return 0;
}

static int parse_object(gi_jv *v, gi_scene_builder *b, mesh_cache *meshes,
                        const char *scene_dir, const cJSON *obj, int index)
{
    char path[64];
    snprintf(path, sizeof path, "objects[%d]", index);
    static const char *const keys[] = {"name", "mesh", "polygons", "quad", "box", "sphere",
                                       "material", "transform", "mobile",
                                       "allow_non_manifold", NULL};
    static const char *const kinds[] = {"mesh", "polygons", "quad", "box", "sphere", NULL};
    if (gi_jv_keys(v, obj, path, keys))
        return -1;
    const char *name = NULL, *material = NULL, *kind = NULL;
    int mobile = 0, allow_nm = 0;
    const cJSON *transform;
    if (gi_jv_string(v, obj, path, "name", 0, &name) ||
        gi_jv_string(v, obj, path, "material", 0, &material) ||
        gi_jv_bool(v, obj, path, "mobile", 0, &mobile) ||
        gi_jv_bool(v, obj, path, "allow_non_manifold", 0, &allow_nm) ||
        gi_jv_member_array(v, obj, path, "transform", 0, &transform))
        return -1;
    for (int k = 0; kinds[k]; k++)
        if (cJSON_GetObjectItemCaseSensitive(obj, kinds[k])) {
            if (kind)
                return gi_jv_fail(v, path, "has both \"%s\" and \"%s\" (one geometry per object)",
                                  kind, kinds[k]);
            kind = kinds[k];
        }
    if (!kind)
        return gi_jv_fail(v, path, "no geometry: give one of mesh, polygons, quad, box, sphere");
    char autoname[64];
    if (!name) {
        snprintf(autoname, sizeof autoname, "object%d", index);
        name = autoname;
    } else if (!name[0]) {
        return gi_jv_fail(v, path, "name is empty");
    } else if (strlen(name) > GI_SCENE_NAME_MAX) {
        return gi_jv_fail(v, path, "name is %zu bytes long, over the limit of %d", strlen(name),
                          GI_SCENE_NAME_MAX);
    }
    int mat_index = -1;
    if (material) {
        mat_index = gi_scene_material_index(b->scene, material);
        if (mat_index < 0)
            return gi_jv_fail(v, path, "material \"%s\" is not defined in \"materials\"",
                              material);
    } else if (strcmp(kind, "mesh") != 0) {
        return gi_jv_fail(v, path, "missing \"material\" (required for %s)", kind);
    }
    gi_mat4 xf;
    char tpath[128];
    gi_json_path(tpath, sizeof tpath, path, "transform");
    if (parse_transform(v, transform, tpath, &xf))
        return -1;

    gi_mesh_data mesh;
    gi_mesh_data_init(&mesh);
    int rc = 0;
    if (strcmp(kind, "mesh") == 0) {
        const char *file = NULL;
        rc = gi_jv_string(v, obj, path, "mesh", 1, &file);
        if (rc == 0) {
            char *norm = mesh_path(scene_dir, file);
            rc = mesh_cache_import(meshes, norm, &mesh, v->err);
            if (rc)
                gi_error_prefix(v->err, "%s: %s.mesh", v->file, path);
            free(norm);
        }
    } else {
        rc = parse_shape(v, obj, path, kind, &mesh);
    }
    uint32_t *map = NULL;
    if (rc == 0) {
        uint32_t nm = mesh.material_count ? mesh.material_count : 1;
        map = gi_xcalloc(nm, sizeof *map);
        for (uint32_t i = 0; i < nm && rc == 0; i++) {
            if (mat_index >= 0) {
                map[i] = (uint32_t)mat_index;
                continue;
            }
            /* The file's own materials, named "<object>/<material>" in
             * full: two names cut to one length would be one material. */
            const gi_mesh_material *mm = mesh.material_count ? &mesh.materials[i] : NULL;
            const char *mat = mm && mm->name ? mm->name : "default";
            size_t len = strlen(name) + 1 + strlen(mat) + 1;
            char *mname = gi_xmalloc(len);
            snprintf(mname, len, "%s/%s", name, mat);
            int idx = gi_scene_material_index(b->scene, mname);
            if (idx < 0) {
                gi_material m = gi_material_from_mesh(mm, mname, v->file);
                idx = gi_scene_add_material(b, &m, v->err);
            }
            free(mname);
            if (idx < 0)
                rc = -1;
            else
                map[i] = (uint32_t)idx;
        }
    }
    if (rc == 0)
        rc = gi_scene_add_object(b, name, mobile, allow_nm, &xf, &mesh, map, v->err);
    free(map);
    gi_mesh_data_free(&mesh);
    return rc;
}

int gi_scene_load_json(const gi_asset_source *src, const char *name, const char *text,
                       size_t len, gi_scene *out, gi_error *err)
{
    cJSON *root;
    if (gi_json_parse(text, len, name, &root, err))
        return -1;
    gi_jv v = {name, err};
    gi_scene_builder b;
    gi_scene_builder_init(&b, out, name);
    char *dir = gi_dirname(name);
    static const char *const keys[] = {"camera", "materials", "objects", "units",
                                       "description", NULL};
    const cJSON *cam = NULL, *mats = NULL, *objs = NULL;
    const char *units = NULL, *desc = NULL;
    int rc = gi_jv_keys(&v, root, "", keys);
    if (rc == 0)
        rc = gi_jv_member_object(&v, root, "", "camera", 0, &cam) ||
             gi_jv_member_object(&v, root, "", "materials", 0, &mats) ||
             gi_jv_member_array(&v, root, "", "objects", 1, &objs) ||
             gi_jv_string(&v, root, "", "units", 0, &units) ||
             gi_jv_string(&v, root, "", "description", 0, &desc);
    if (rc == 0 && cam) {
        rc = gi_camera_parse(&v, cam, "camera", &out->camera);
        out->has_camera = rc == 0;
    }
    if (rc == 0 && mats) /* none: every object's mesh brings its own */
        rc = parse_materials(&v, &b, mats);
    if (rc == 0 && cJSON_GetArraySize(objs) == 0)
        rc = gi_jv_fail(&v, "objects", "the scene has no objects");
    mesh_cache meshes;
    mesh_cache_init(&meshes, src, dir, rc == 0 ? objs : NULL);
    int i = 0;
    for (const cJSON *o = objs ? objs->child : NULL; o && rc == 0; o = o->next, i++)
        rc = parse_object(&v, &b, &meshes, dir, o, i);
    mesh_cache_free(&meshes);
    if (rc == 0)
        rc = gi_scene_builder_finish(&b, err);
    free(dir);
    cJSON_Delete(root);
    if (rc)
        gi_scene_free(out);
    return rc ? -1 : 0;
}
