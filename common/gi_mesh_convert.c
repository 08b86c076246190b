/* gi_mesh_convert: assimp's scene -> gi_mesh_data (materials, vertices,
 * triangles), refusing what cannot be rendered. assimp vouches for the
 * structure (every array as long as its count); the values are the file's:
 * counts, face indices, material indices, coordinates and colours are
 * checked here, and the length of material names (fuzz_mesh_convert builds
 * such scenes from fuzz bytes). */
#include "gi_mesh_convert.h"

#include <assimp/material.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "gi_log.h"

/* More would not fit the uint32 indices with room for the rest of a scene. */
#define MAX_MESH_VERTICES ((uint64_t)1 << 31)
#define MAX_MESH_TRIANGLES ((uint64_t)1 << 31)

/* What assimp puts where a file gives no material: its
 * AI_DEFAULT_MATERIAL_NAME (OBJ without usemtl), or an unnamed plain white
 * one (PLY; glTF's spec default for a primitive without material). A white
 * reflectance of 1 is not physical anyway, so an unnamed white material the
 * file did give is treated the same. */
static int is_stand_in(const struct aiMaterial *am)
{
    struct aiString name;
    if (aiGetMaterialString(am, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS)
        return strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) == 0;
    struct aiColor4D c;
    if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS &&
        (c.r != 0 || c.g != 0 || c.b != 0))
        return 0;
    return aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) != aiReturn_SUCCESS ||
           (c.r == 1 && c.g == 1 && c.b == 1);
}

/* Whether a "newmtl <name>" line in one of the material libraries read
 * for an OBJ defines `mat`. assimp gives a material that usemtl names but
 * no library defines (or whose library is missing) its own grey; we want
 * the default material there, and assimp does not say which case it was. */
static int mtl_defines(const gi_buf *const *libs, size_t count, const char *mat)
{
    size_t ml = strlen(mat);
    for (size_t i = 0; i < count; i++) {
        if (libs[i]->len == 0)
            continue;
        const char *p = (const char *)libs[i]->data;
        const char *end = p + libs[i]->len;
        while (p < end) {
            const char *eol = memchr(p, '\n', (size_t)(end - p));
            if (!eol)
                eol = end;
            const char *b = p;
            while (b < eol && (*b == ' ' || *b == '\t'))
                b++;
            if (eol - b > 7 && strncasecmp(b, "newmtl", 6) == 0 &&
                (b[6] == ' ' || b[6] == '\t')) {
                b += 7;
                while (b < eol && (*b == ' ' || *b == '\t'))
                    b++;
                const char *e = eol;
                while (e > b && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r'))
                    e--;
                if ((size_t)(e - b) == ml && memcmp(b, mat, ml) == 0)
                    return 1;
            }
            p = eol + 1;
        }
    }
    return 0;
}

static void default_material(gi_mesh_material *m)
{
    m->name = gi_xstrdup("default");
    m->diffuse = gi_v3(0.8f, 0.8f, 0.8f);
    m->emission = gi_v3(0.0f, 0.0f, 0.0f);
}

/* A name at assimp's limit may be one it cut (glTF; an OBJ's is dropped
 * whole, gi_mesh_precheck says so with its line): refused like one over
 * ours, as it is not the name the file gives. */
static int read_material(const struct aiMaterial *am, uint32_t index, const char *file,
                         gi_mesh_material *m, gi_error *err)
{
    if (is_stand_in(am)) {
        default_material(m);
        return 0;
    }
    struct aiString name;
    if (aiGetMaterialString(am, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && name.data[0]) {
        size_t n = strlen(name.data);
        if (n > GI_MESH_NAME_MAX)
            return gi_fail(err, GI_EINVAL,
                           "%s: material %u: its name (\"%.24s...\") is %s%zu bytes long, over "
                           "the limit of %d",
                           file, index, name.data, n + 1 >= MAXLEN ? "at least " : "", n,
                           GI_MESH_NAME_MAX);
        m->name = gi_xstrdup(name.data);
    } else {
        char buf[32];
        snprintf(buf, sizeof buf, "material%u", index);
        m->name = gi_xstrdup(buf);
    }
    /* OBJ Kd and glTF's base colour factor both land in COLOR_DIFFUSE
     * (assimp 5.2 also copies the latter to BASE_COLOR). */
    struct aiColor4D c;
    m->diffuse = gi_v3(0.8f, 0.8f, 0.8f);
    if (aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS ||
        aiGetMaterialColor(am, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS)
        m->diffuse = gi_v3(c.r, c.g, c.b);
    m->emission = gi_v3(0.0f, 0.0f, 0.0f);
    if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS)
        m->emission = gi_v3(c.r, c.g, c.b);
    /* An emissive intensity scales the emissive colour (glTF's
     * KHR_materials_emissive_strength semantics) where an importer sets it. */
    float strength;
    unsigned int one = 1;
    if (aiGetMaterialFloatArray(am, AI_MATKEY_EMISSIVE_INTENSITY, &strength, &one) ==
            aiReturn_SUCCESS &&
        one == 1)
        m->emission = gi_scale(m->emission, strength);
    return 0;
}

/* Material names must be unique within a mesh (the scene looks them up by
 * name): a repeated name gets "#<file index>" appended. */
static void make_names_unique(gi_mesh_data *out, const uint32_t *file_index)
{
    for (uint32_t i = 1; i < out->material_count; i++)
        for (uint32_t j = 0; j < i; j++)
            if (strcmp(out->materials[i].name, out->materials[j].name) == 0) {
                size_t n = strlen(out->materials[i].name) + 16;
                char *s = gi_xmalloc(n);
                snprintf(s, n, "%s#%u", out->materials[i].name, file_index[i]);
                free(out->materials[i].name);
                out->materials[i].name = s;
                j = (uint32_t)-1; /* check the new name from the start */
            }
}

static int finite_vec(const struct aiVector3D *v)
{
    return isfinite(v->x) && isfinite(v->y) && isfinite(v->z);
}

/* All of a mesh's normals are finite numbers. */
static int normals_finite(const struct aiMesh *am)
{
    for (unsigned v = 0; v < am->mNumVertices; v++)
        if (!finite_vec(&am->mNormals[v]))
            return 0;
    return 1;
}

static uint32_t mesh_triangles(const struct aiMesh *am)
{
    uint32_t n = 0;
    for (unsigned f = 0; f < am->mNumFaces; f++)
        n += am->mFaces[f].mNumIndices == 3;
    return n;
}

int gi_mesh_from_assimp(const struct aiScene *sc, const gi_buf *const *mtl_libs,
                        size_t mtl_count, const char *name, gi_mesh_data *out, gi_error *err)
{
    uint64_t nv = 0, nt = 0;
    int all_normals = 1;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        uint32_t t = mesh_triangles(am);
        if (t == 0)
            continue;
        nv += am->mNumVertices;
        nt += t;
        all_normals &= am->mNormals != NULL;
        /* NaN positions cannot be rendered: refused, naming the vertex
         * (OBJ "v nan 0 0"; assimp takes it). Bad normals are only
         * dropped: the scene computes its own then. */
        for (unsigned v = 0; v < am->mNumVertices; v++)
            if (!finite_vec(&am->mVertices[v]))
                return gi_fail(err, GI_EINVAL,
                               "%s: mesh %u vertex %u is not a finite point (%g %g %g)", name, i,
                               v, (double)am->mVertices[v].x, (double)am->mVertices[v].y,
                               (double)am->mVertices[v].z);
        if (all_normals && !normals_finite(am)) {
            gi_warn("%s: mesh %u has normals that are not finite; using computed normals",
                    name, i);
            all_normals = 0;
        }
        if (sc->mNumMaterials && am->mMaterialIndex >= sc->mNumMaterials)
            return gi_fail(err, GI_EINVAL, "%s: mesh %u uses material %u of %u", name, i,
                           am->mMaterialIndex, sc->mNumMaterials);
    }
    if (nt == 0)
        return gi_fail(err, GI_EINVAL, "%s: no triangles", name);
    if (nv > MAX_MESH_VERTICES || nt > MAX_MESH_TRIANGLES)
        return gi_fail(err, GI_ENOMEM,
                       "%s: %llu vertices and %llu triangles, over the limit of 2^31 each",
                       name, (unsigned long long)nv, (unsigned long long)nt);

    /* Only materials some triangle uses, in the file's order (assimp adds
     * unused ones: the OBJ stand-in, glTF's default). */
    uint32_t nm = sc->mNumMaterials;
    uint32_t *map = gi_xcalloc((size_t)nm + 1, sizeof *map);
    uint32_t *file_index = gi_xcalloc((size_t)nm + 1, sizeof *file_index);
    for (unsigned i = 0; i < sc->mNumMeshes; i++)
        if (nm && mesh_triangles(sc->mMeshes[i]))
            map[sc->mMeshes[i]->mMaterialIndex] = 1;
    uint32_t used = 0;
    for (uint32_t i = 0; i < nm; i++)
        if (map[i]) {
            file_index[used] = i;
            map[i] = used++;
        }

    out->positions = gi_try_malloc((size_t)(nv + 1) * sizeof *out->positions, err, name);
    out->normals = all_normals
                       ? gi_try_malloc((size_t)(nv + 1) * sizeof *out->normals, err, name)
                       : NULL;
    out->indices = gi_try_malloc((size_t)(3 * nt) * sizeof *out->indices, err, name);
    out->tri_material = gi_try_malloc((size_t)nt * sizeof *out->tri_material, err, name);
    if (!out->positions || (all_normals && !out->normals) || !out->indices ||
        !out->tri_material) {
        free(map);
        free(file_index);
        return -1;
    }
    out->material_count = used ? used : 1;
    out->materials = gi_xcalloc(out->material_count, sizeof *out->materials);
    if (used == 0)
        default_material(&out->materials[0]);
    size_t nl = strlen(name);
    int is_obj = nl >= 4 && strcasecmp(name + nl - 4, ".obj") == 0;
    for (uint32_t i = 0; i < used; i++) {
        gi_mesh_material *m = &out->materials[i];
        if (read_material(sc->mMaterials[file_index[i]], file_index[i], name, m, err)) {
            free(map);
            free(file_index);
            return -1;
        }
        if (is_obj && strcmp(m->name, "default") != 0 &&
            !mtl_defines(mtl_libs, mtl_count, m->name)) {
            gi_warn("%s: material \"%s\" is not defined by any material library read; "
                    "using the default material's colours",
                    name, m->name);
            m->diffuse = gi_v3(0.8f, 0.8f, 0.8f);
            m->emission = gi_v3(0.0f, 0.0f, 0.0f);
        }
    }
    make_names_unique(out, file_index);

    uint32_t v0 = 0, t0 = 0;
    int rc = 0;
    for (unsigned i = 0; i < sc->mNumMeshes && rc == 0; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (mesh_triangles(am) == 0)
            continue;
        for (unsigned v = 0; v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            out->positions[v0 + v] = gi_v3(p->x, p->y, p->z);
            if (all_normals) {
                const struct aiVector3D *n = &am->mNormals[v];
                out->normals[v0 + v] = gi_v3(n->x, n->y, n->z);
            }
        }
        uint32_t mat = nm ? map[am->mMaterialIndex] : 0;
        for (unsigned f = 0; f < am->mNumFaces && rc == 0; f++) {
            const struct aiFace *face = &am->mFaces[f];
            if (face->mNumIndices != 3)
                continue;
            for (int k = 0; k < 3; k++) {
                if (face->mIndices[k] >= am->mNumVertices) {
                    rc = gi_fail(err, GI_EINVAL, "%s: mesh %u face %u uses vertex %u of %u",
                                 name, i, f, face->mIndices[k], am->mNumVertices);
                    break;
                }
                out->indices[3 * (size_t)t0 + k] = v0 + face->mIndices[k];
            }
            out->tri_material[t0++] = mat;
        }
        v0 += am->mNumVertices;
    }
    free(map);
    free(file_index);
    if (rc)
        return -1;
    out->vertex_count = v0;
    out->triangle_count = t0;
    return 0;
}

