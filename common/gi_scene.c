/* gi_scene: assembling scenes from meshes, checks, and derived data (bounds,
 * light distribution). The JSON reader is gi_scene_json.c. */
#include "gi_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_limits.h"
#include "gi_log.h"
#include "gi_mesh.h"
#include "gi_scene_build.h"


void gi_scene_free(gi_scene *s)
{
    if (!s)
        return;
    free(s->name);
    for (uint32_t i = 0; i < s->material_count; i++)
        free(s->materials[i].name);
    free(s->materials);
    gi_name_index_free(&s->material_names);
    gi_name_index_free(&s->object_names);
    for (uint32_t i = 0; i < s->object_count; i++)
        free(s->objects[i].name);
    free(s->objects);
    free(s->positions);
    free(s->normals);
    free(s->indices);
    free(s->tri_material);
    free(s->tri_object);
    free(s->tri_normal);
    free(s->tri_smooth);
    free(s->light_tris);
    free(s->light_geom);
    free(s->light_cdf);
    free(s->light_power);
    memset(s, 0, sizeof *s);
}

double gi_scene_triangle_area(const gi_scene *s, uint32_t t)
{
    gi_vec3 a, b, c;
    gi_scene_triangle(s, t, &a, &b, &c);
    /* In double: small triangles far from the origin lose too much in float. */
    double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
    double x = e1[1] * e2[2] - e1[2] * e2[1];
    double y = e1[2] * e2[0] - e1[0] * e2[2];
    double z = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(x * x + y * y + z * z);
}


int gi_scene_find_object(const gi_scene *s, const char *name)
{
    if (s->object_names.count == s->object_count)
        return (int)gi_name_index_find(&s->object_names, name);
    for (uint32_t i = 0; i < s->object_count; i++)
        if (strcmp(s->objects[i].name, name) == 0)
            return (int)i;
    return -1;
}

int gi_scene_material_index(const gi_scene *s, const char *name)
{
    if (s->material_names.count == s->material_count)
        return (int)gi_name_index_find(&s->material_names, name);
    for (uint32_t i = 0; i < s->material_count; i++)
        if (strcmp(s->materials[i].name, name) == 0)
            return (int)i;
    return -1;
}

/* The capacity for `need` elements: cap doubled as often as it takes, but
 * never over `most` (the most the scene's limits let it hold). */
static size_t grown(size_t cap, size_t need, size_t most)
{
    if (need <= cap)
        return cap;
    size_t c = cap ? cap : 64;
    while (c < need)
        c *= 2;
    return c < most ? c : need > most ? need : most;
}

void gi_scene_builder_init(gi_scene_builder *b, gi_scene *scene, const char *file)
{
    memset(scene, 0, sizeof *scene);
    scene->name = gi_xstrdup(file);
    memset(b, 0, sizeof *b);
    b->scene = scene;
    b->file = file;
}

int gi_scene_add_material(gi_scene_builder *b, const gi_material *m, gi_error *err)
{
    gi_scene *s = b->scene;
    if (gi_scene_material_index(s, m->name) >= 0)
        return gi_fail(err, GI_EINVAL, "%s: material \"%s\" is defined twice", b->file,
                       m->name);
    size_t cap = grown(b->material_cap, (size_t)s->material_count + 1, UINT32_MAX);
    if (cap != b->material_cap) {
        s->materials = gi_xrealloc(s->materials, cap * sizeof *s->materials);
        b->material_cap = cap;
    }
    gi_material *dst = &s->materials[s->material_count];
    *dst = *m;
    dst->name = gi_xstrdup(m->name);
    gi_name_index_add(&s->material_names, dst->name, s->material_count);
    return (int)s->material_count++;
}

static float clamp_channel(float v, float hi, int *changed)
{
    float c = isfinite(v) ? fminf(fmaxf(v, 0.0f), hi) : 0.0f;
    *changed |= c != v;
    return c;
}

gi_material gi_material_from_mesh(const gi_mesh_material *mm, const char *name,
                                  const char *file)
{
    gi_material m = {0};
    m.name = (char *)name;
    if (!mm) {
        m.diffuse = gi_v3(0.8f, 0.8f, 0.8f);
        return m;
    }
    int changed = 0;
    m.diffuse = gi_v3(clamp_channel(mm->diffuse.x, 1.0f, &changed),
                      clamp_channel(mm->diffuse.y, 1.0f, &changed),
                      clamp_channel(mm->diffuse.z, 1.0f, &changed));
    m.emission = gi_v3(clamp_channel(mm->emission.x, 1e30f, &changed),
                       clamp_channel(mm->emission.y, 1e30f, &changed),
                       clamp_channel(mm->emission.z, 1e30f, &changed));
    if (changed)
        gi_warn("%s: material \"%s\": reflectance clamped to [0, 1] and emission to >= 0",
                file, name);
    return m;
}

/* Edges used by more than two triangles of one object (by vertex index). */
typedef struct edge_key {
    uint32_t a, b;
} edge_key;

static int edge_cmp(const void *x, const void *y)
{
    const edge_key *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    if (p->b != q->b)
        return p->b < q->b ? -1 : 1;
    return 0;
}

static int find_non_manifold_edge(const gi_mesh_data *m, edge_key *bad)
{
    size_t n = (size_t)m->triangle_count * 3;
    edge_key *e = gi_xmalloc(n * sizeof *e);
    for (uint32_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = m->indices[3 * t + k], v = m->indices[3 * t + (k + 1) % 3];
            e[3 * t + k] = u < v ? (edge_key){u, v} : (edge_key){v, u};
        }
    qsort(e, n, sizeof *e, edge_cmp);
    int found = 0;
    for (size_t i = 0; i + 2 < n && !found; i++)
        if (edge_cmp(&e[i], &e[i + 2]) == 0) {
            *bad = e[i];
            found = 1;
        }
    free(e);
    return found;
}

int gi_scene_add_object(gi_scene_builder *b, const char *name, int mobile,
                        int allow_non_manifold, const gi_mat4 *transform,
                        gi_mesh_data *mesh, const uint32_t *material_map, gi_error *err)
{
    gi_scene *s = b->scene;
    if (gi_scene_find_object(s, name) >= 0)
        return gi_fail(err, GI_EINVAL, "%s: object \"%s\": the name is used twice", b->file,
                       name);
    if (mesh->triangle_count == 0 || mesh->vertex_count == 0)
        return gi_fail(err, GI_EINVAL, "%s: object \"%s\": empty mesh (no triangles)",
                       b->file, name);
    const gi_limits *lim = gi_limits_get();
    if ((uint64_t)mesh->vertex_count + s->vertex_count > lim->max_scene_vertices ||
        (uint64_t)mesh->triangle_count + s->triangle_count > lim->max_scene_triangles)
        return gi_fail(err, GI_EINVAL,
                       "%s: object \"%s\": the scene exceeds the limit of %u vertices / %u triangles",
                       b->file, name, lim->max_scene_vertices, lim->max_scene_triangles);
    for (uint32_t i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->indices[i] >= mesh->vertex_count)
            return gi_fail(err, GI_EINVAL,
                           "%s: object \"%s\": triangle %u uses vertex %u of %u", b->file,
                           name, i / 3, mesh->indices[i], mesh->vertex_count);
    gi_mat4 inv;
    if (gi_mat4_inverse(*transform, &inv))
        return gi_fail(err, GI_EINVAL, "%s: object \"%s\": the transform is singular",
                       b->file, name);

    /* Transform to world space, and check every coordinate is finite. */
    for (uint32_t i = 0; i < mesh->vertex_count; i++) {
        gi_vec3 p = mesh->positions[i];
        if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z))
            return gi_fail(err, GI_EINVAL, "%s: object \"%s\": vertex %u is not finite",
                           b->file, name, i);
        p = gi_mat4_point(transform, p);
        if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z) || fabsf(p.x) > 1e18f ||
            fabsf(p.y) > 1e18f || fabsf(p.z) > 1e18f)
            return gi_fail(err, GI_EINVAL,
                           "%s: object \"%s\": vertex %u is out of range after the transform",
                           b->file, name, i);
        mesh->positions[i] = p;
    }
    /* A mirroring transform (negative determinant) would turn every face's
     * front to its other side: the triangles are re-wound so that a
     * mirrored object faces, and emits, the way the original does. */
    const double(*m)[4] = transform->m;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (det < 0)
        for (uint32_t t = 0; t < mesh->triangle_count; t++) {
            uint32_t *ix = &mesh->indices[3 * t];
            uint32_t swap = ix[1];
            ix[1] = ix[2];
            ix[2] = swap;
        }
    if (mesh->normals) {
        for (uint32_t i = 0; i < mesh->vertex_count; i++) {
            gi_vec3 n = mesh->normals[i];
            if (!isfinite(n.x) || !isfinite(n.y) || !isfinite(n.z) || gi_length(n) == 0.0f) {
                /* A broken normal in the file: recompute them all rather than
                 * shade with garbage. */
                gi_warn("%s: object \"%s\": vertex %u has an invalid normal; recomputing normals",
                        b->file, name, i);
                free(mesh->normals);
                mesh->normals = NULL;
                break;
            }
            mesh->normals[i] = gi_mat4_normal(&inv, n);
        }
    }

    uint32_t with_area = 0;
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *ix = &mesh->indices[3 * t];
        gi_vec3 n = gi_triangle_normal(mesh->positions[ix[0]], mesh->positions[ix[1]],
                                       mesh->positions[ix[2]]);
        if (gi_length(n) > 0.0f)
            with_area++;
    }
    if (with_area == 0)
        return gi_fail(err, GI_EINVAL, "%s: object \"%s\": every triangle is degenerate (zero area)",
                       b->file, name);
    if (with_area < mesh->triangle_count)
        gi_info("%s: object \"%s\": %u degenerate triangles", b->file, name,
                mesh->triangle_count - with_area);
    edge_key bad;
    if (!allow_non_manifold && find_non_manifold_edge(mesh, &bad))
        return gi_fail(err, GI_EINVAL,
                       "%s: object \"%s\": non-manifold mesh: the edge between vertices %u "
                       "and %u belongs to more than two triangles (set \"allow_non_manifold\": "
                       "true to accept it)",
                       b->file, name, bad.a, bad.b);
    /* After the manifold check, which must see the file's own topology:
     * splitting vertices at hard edges makes boundary edges of them. */
    if (!mesh->normals) {
        gi_mesh_compute_normals(mesh);
        if ((uint64_t)mesh->vertex_count + s->vertex_count > lim->max_scene_vertices)
            return gi_fail(err, GI_EINVAL,
                           "%s: object \"%s\": the scene exceeds the limit of %u vertices "
                           "(%u after splitting the mesh's vertices at hard edges)",
                           b->file, name, lim->max_scene_vertices, mesh->vertex_count);
    }

    /* Append to the scene arrays. */
    uint32_t v0 = s->vertex_count, t0 = s->triangle_count;
    uint32_t nv = v0 + mesh->vertex_count, nt = t0 + mesh->triangle_count;
    size_t cap = grown(b->vertex_cap, (size_t)nv + 1, (size_t)lim->max_scene_vertices + 1);
    if (cap != b->vertex_cap) {
        s->positions = gi_xrealloc(s->positions, cap * sizeof *s->positions);
        s->normals = gi_xrealloc(s->normals, cap * sizeof *s->normals);
        b->vertex_cap = cap;
    }
    memcpy(s->positions + v0, mesh->positions, mesh->vertex_count * sizeof(gi_vec3));
    memcpy(s->normals + v0, mesh->normals, mesh->vertex_count * sizeof(gi_vec3));
    s->positions[nv] = s->normals[nv] = gi_v3(0, 0, 0); /* Embree's padded read */
    cap = grown(b->triangle_cap, nt, lim->max_scene_triangles);
    if (cap != b->triangle_cap) {
        s->indices = gi_xrealloc(s->indices, cap * 3 * sizeof *s->indices);
        s->tri_material = gi_xrealloc(s->tri_material, cap * sizeof *s->tri_material);
        s->tri_object = gi_xrealloc(s->tri_object, cap * sizeof *s->tri_object);
        b->triangle_cap = cap;
    }
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            s->indices[3 * (t0 + t) + k] = v0 + mesh->indices[3 * t + k];
        uint32_t mm = mesh->tri_material ? mesh->tri_material[t] : 0;
        s->tri_material[t0 + t] = material_map[mm < mesh->material_count ? mm : 0];
        s->tri_object[t0 + t] = s->object_count;
    }
    cap = grown(b->object_cap, (size_t)s->object_count + 1, UINT32_MAX);
    if (cap != b->object_cap) {
        s->objects = gi_xrealloc(s->objects, cap * sizeof *s->objects);
        b->object_cap = cap;
    }
    gi_object *o = &s->objects[s->object_count];
    o->name = gi_xstrdup(name);
    gi_name_index_add(&s->object_names, o->name, s->object_count++);
    o->mobile = mobile;
    o->first_vertex = v0;
    o->vertex_count = mesh->vertex_count;
    o->first_triangle = t0;
    o->triangle_count = mesh->triangle_count;
    o->transform = *transform;
    s->vertex_count = nv;
    s->triangle_count = nt;
    return 0;
}

void gi_scene_update_bbox(gi_scene *s)
{
    gi_vec3 lo = gi_v3(INFINITY, INFINITY, INFINITY), hi = gi_scale(lo, -1.0f);
    for (uint32_t i = 0; i < s->vertex_count; i++) {
        lo = gi_min_v3(lo, s->positions[i]);
        hi = gi_max_v3(hi, s->positions[i]);
    }
    s->bbox_min = lo;
    s->bbox_max = hi;
}

void gi_scene_update_triangles(gi_scene *s, uint32_t first, uint32_t count)
{
    for (uint32_t t = first; t < first + count; t++) {
        gi_vec3 a, b, c;
        gi_scene_triangle(s, t, &a, &b, &c);
        gi_vec3 n = gi_triangle_normal(a, b, c);
        s->tri_normal[t] = n;
        const uint32_t *ix = &s->indices[3 * t];
        int smooth = 0;
        for (int k = 0; k < 3; k++)
            smooth |= gi_dot(s->normals[ix[k]], n) < 0.999999f;
        s->tri_smooth[t] = (uint8_t)smooth;
    }
}

int gi_scene_update_derived(gi_scene *s, gi_error *err)
{
    gi_scene_update_bbox(s);
    free(s->tri_normal);
    free(s->tri_smooth);
    s->tri_normal = gi_xmalloc(((size_t)s->triangle_count + 1) * sizeof *s->tri_normal);
    s->tri_smooth = gi_xmalloc((size_t)s->triangle_count + 1);
    gi_scene_update_triangles(s, 0, s->triangle_count);

    free(s->light_tris);
    free(s->light_cdf);
    free(s->light_power);
    s->light_count = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++)
        if (!gi_is_black(gi_scene_tri_material(s, t)->emission) &&
            gi_scene_triangle_area(s, t) > 0.0)
            s->light_count++;
    s->light_tris = gi_xmalloc((s->light_count + 1) * sizeof *s->light_tris);
    s->light_cdf = gi_xmalloc((s->light_count + 1) * sizeof *s->light_cdf);
    s->light_power = gi_xmalloc((s->light_count + 1) * sizeof *s->light_power);
    uint32_t k = 0;
    double total = 0.0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const gi_material *m = gi_scene_tri_material(s, t);
        double area = gi_scene_triangle_area(s, t);
        if (gi_is_black(m->emission) || !(area > 0.0))
            continue;
        /* Power of a Lambertian emitter: pi * A * L per face. */
        double p = GI_PI * area * gi_luminance(m->emission) * (m->two_sided ? 2.0 : 1.0);
        s->light_tris[k] = t;
        s->light_power[k] = p;
        s->light_cdf[k] = total;
        total += p;
        k++;
    }
    s->light_cdf[k] = total;
    s->total_power = total;
    if (total > 0.0)
        for (uint32_t i = 0; i <= k; i++)
            s->light_cdf[i] /= total;
    if (s->light_count)
        s->light_cdf[k] = 1.0;
    free(s->light_geom);
    s->light_geom = gi_xmalloc((s->light_count + 1) * sizeof *s->light_geom);
    for (uint32_t i = 0; i < s->light_count; i++) {
        uint32_t t = s->light_tris[i];
        gi_vec3 a, b, c;
        gi_scene_triangle(s, t, &a, &b, &c);
        gi_light_tri *L = &s->light_geom[i];
        L->a = a;
        L->e1 = gi_sub(b, a);
        L->e2 = gi_sub(c, a);
        L->n = s->tri_normal[t];
        L->pdf_area = (float)(s->light_power[i] / total / gi_scene_triangle_area(s, t));
        L->tri = t;
    }
    if (!isfinite(total))
        return gi_fail(err, GI_EINVAL, "%s: total emitted power is not finite", s->name);
    return 0;
}

/* Gives back the room left for growth (up to half of each array). */
static void trim(gi_scene_builder *b)
{
    gi_scene *s = b->scene;
    size_t nv = (size_t)s->vertex_count + 1, nt = s->triangle_count ? s->triangle_count : 1;
    s->positions = gi_xrealloc(s->positions, nv * sizeof *s->positions);
    s->normals = gi_xrealloc(s->normals, nv * sizeof *s->normals);
    s->indices = gi_xrealloc(s->indices, nt * 3 * sizeof *s->indices);
    s->tri_material = gi_xrealloc(s->tri_material, nt * sizeof *s->tri_material);
    s->tri_object = gi_xrealloc(s->tri_object, nt * sizeof *s->tri_object);
    size_t no = s->object_count ? s->object_count : 1;
    size_t nm = s->material_count ? s->material_count : 1;
    s->objects = gi_xrealloc(s->objects, no * sizeof *s->objects);
    s->materials = gi_xrealloc(s->materials, nm * sizeof *s->materials);
    b->vertex_cap = nv;
    b->triangle_cap = nt;
    b->object_cap = no;
    b->material_cap = nm;
}

int gi_scene_builder_finish(gi_scene_builder *b, gi_error *err)
{
    gi_scene *s = b->scene;
    if (s->object_count == 0)
        return gi_fail(err, GI_EINVAL, "%s: the scene has no objects", b->file);
    trim(b);
    if (gi_scene_update_derived(s, err))
        return -1;
    if (s->light_count == 0)
        return gi_fail(err, GI_EINVAL,
                       "%s: the scene has no light (no triangle with an emissive material)",
                       b->file);
    if (!s->has_camera) {
        /* No camera given (e.g. a bare OBJ): look at the bounding box from +z,
         * far enough that its bounding sphere fits a 40 degree view. */
        gi_vec3 c = gi_scale(gi_add(s->bbox_min, s->bbox_max), 0.5f);
        float r = 0.5f * gi_length(gi_sub(s->bbox_max, s->bbox_min));
        s->camera.fov_y_deg = 40.0f;
        s->camera.look_at = c;
        s->camera.up = gi_v3(0, 1, 0);
        s->camera.position = gi_add(c, gi_v3(0, 0, 1.05f * r / sinf(20.0f * (float)GI_PI / 180.0f)));
    }
    return 0;
}

static int has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

/* A bare mesh file as a whole scene: one object, the file's materials. */
static int load_bare_mesh(const gi_asset_source *src, const char *name, gi_scene *out,
                          gi_error *err)
{
    gi_mesh_data mesh;
    gi_mesh_data_init(&mesh);
    if (gi_mesh_import(src, name, &mesh, err))
        return -1;
    gi_scene_builder b;
    gi_scene_builder_init(&b, out, name);
    uint32_t *map = gi_xcalloc(mesh.material_count ? mesh.material_count : 1, sizeof *map);
    int rc = 0;
    for (uint32_t i = 0; i < mesh.material_count && rc == 0; i++) {
        gi_material m = gi_material_from_mesh(&mesh.materials[i], mesh.materials[i].name, name);
        int idx = gi_scene_material_index(out, m.name);
        if (idx < 0)
            idx = gi_scene_add_material(&b, &m, err);
        if (idx < 0)
            rc = -1;
        map[i] = (uint32_t)idx;
    }
    if (rc == 0 && mesh.material_count == 0) {
        gi_material m = {.name = "default", .diffuse = gi_v3(0.8f, 0.8f, 0.8f)};
        map[0] = (uint32_t)gi_scene_add_material(&b, &m, err);
    }
    const char *base = strrchr(name, '/');
    gi_mat4 id = gi_mat4_identity();
    if (rc == 0)
        rc = gi_scene_add_object(&b, base ? base + 1 : name, 0, 1, &id, &mesh, map, err);
    free(map);
    gi_mesh_data_free(&mesh);
    if (rc == 0)
        rc = gi_scene_builder_finish(&b, err);
    if (rc)
        gi_scene_free(out);
    return rc;
}

int gi_scene_load(const gi_asset_source *src, const char *name, gi_scene *out,
                  gi_error *err)
{
    memset(out, 0, sizeof *out);
    if (!has_suffix(name, ".json"))
        return load_bare_mesh(src, name, out, err);
    gi_buf text;
    gi_buf_init(&text);
    if (gi_asset_read(src, name, &text, err)) {
        gi_buf_free(&text);
        return -1;
    }
    int rc = gi_scene_load_json(src, name, (const char *)text.data, text.len, out, err);
    gi_buf_free(&text);
    return rc;
}
