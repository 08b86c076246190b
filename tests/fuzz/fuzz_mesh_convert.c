/* fuzz_mesh_convert: libFuzzer target for gi_mesh_from_assimp, the part of
 * a mesh import that is ours, in-process and without assimp's importers
 * (those run in a child, out of reach of coverage: fuzz_mesh). The input
 * is an aiScene as assimp would hand it over, built from the bytes: the
 * structure well-formed (arrays as long as their counts), every value the
 * fuzzer's (counts, face sizes and indices, material indices, coordinates,
 * normals, material names and colours, the .mtl bytes read beside an OBJ).
 *
 * Layout, read front to back (missing bytes read as 0):
 *   u8 flags: bit 0 OBJ (else glTF), bits 1-2 material libraries (0-3)
 *   per library: u16 length, the bytes
 *   u8 materials (% 5); per material: u8 properties (bit 0 name, 1 the
 *     default name, 2 diffuse, 3 emissive, 4 base colour, 5 emissive
 *     intensity, 6 a long name: its bytes repeated to 8 times their
 *     length, at most the 1023 an aiString holds), u8 name length + name,
 *     3 f32 per colour, f32 intensity
 *   u8 meshes (% 5); per mesh: u8 vertices, u8 faces, u8 material index,
 *     u8 flags (bit 0 normals), then f32 x, y, z per vertex, then normals,
 *     then per face u8 corner count (% 4 + 1) and a u8 index per corner
 *
 * Any input must convert or fail with a one-line message naming the file;
 * a mesh that converts must hold exactly the scene's triangles, in range,
 * finite, with unique material names, and reach the parent: what
 * gi_mesh_encode makes of it, gi_mesh_decode takes back unchanged. */
#include <assimp/material.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_log.h"
#include "gi_mesh_convert.h"
#include "gi_mesh_wire.h"
#include "gi_scene.h"
#include "gi_scene_build.h"

typedef struct bytes {
    const uint8_t *p;
    size_t left;
} bytes;

static uint8_t get_u8(bytes *b)
{
    if (!b->left)
        return 0;
    b->left--;
    return *b->p++;
}

static float get_f32(bytes *b)
{
    uint32_t u = 0;
    for (int i = 0; i < 4; i++)
        u |= (uint32_t)get_u8(b) << (8 * i);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static void add_prop(struct aiMaterial *m, const char *key, unsigned semantic, unsigned index,
                     enum aiPropertyTypeInfo type, const void *data, unsigned len)
{
    struct aiMaterialProperty *p = calloc(1, sizeof *p);
    p->mKey.length = (uint32_t)strlen(key);
    memcpy(p->mKey.data, key, p->mKey.length + 1);
    p->mSemantic = semantic;
    p->mIndex = index;
    p->mType = type;
    p->mDataLength = len;
    p->mData = malloc(len);
    memcpy(p->mData, data, len);
    m->mProperties[m->mNumProperties++] = p;
}

/* A string property as assimp stores one: u32 length, the characters, NUL. */
static void add_name(struct aiMaterial *m, const char *s, uint32_t n)
{
    char buf[4 + MAXLEN];
    memcpy(buf, &n, 4);
    memcpy(buf + 4, s, n);
    buf[4 + n] = '\0';
    add_prop(m, AI_MATKEY_NAME, aiPTI_String, buf, 4 + n + 1);
}

static struct aiMaterial *make_material(bytes *b)
{
    struct aiMaterial *m = calloc(1, sizeof *m);
    m->mNumAllocated = 6;
    m->mProperties = calloc(m->mNumAllocated, sizeof *m->mProperties);
    uint8_t which = get_u8(b);
    unsigned n = get_u8(b);
    char name[MAXLEN];
    for (unsigned i = 0; i < n; i++)
        name[i] = (char)get_u8(b);
    if (which & 64) { /* around the conversion's limit, which is under assimp's */
        unsigned n0 = n, want = 8 * n0 < MAXLEN - 1 ? 8 * n0 : MAXLEN - 1;
        for (; n < want; n++)
            name[n] = name[n % n0];
    }
    if (which & 1)
        add_name(m, name, n);
    else if (which & 2)
        add_name(m, AI_DEFAULT_MATERIAL_NAME, (uint32_t)strlen(AI_DEFAULT_MATERIAL_NAME));
    float c[3];
    if (which & 4) {
        for (int k = 0; k < 3; k++)
            c[k] = get_f32(b);
        add_prop(m, AI_MATKEY_COLOR_DIFFUSE, aiPTI_Float, c, sizeof c);
    }
    if (which & 8) {
        for (int k = 0; k < 3; k++)
            c[k] = get_f32(b);
        add_prop(m, AI_MATKEY_COLOR_EMISSIVE, aiPTI_Float, c, sizeof c);
    }
    if (which & 16) {
        for (int k = 0; k < 3; k++)
            c[k] = get_f32(b);
        add_prop(m, AI_MATKEY_BASE_COLOR, aiPTI_Float, c, sizeof c);
    }
    if (which & 32) {
        float s = get_f32(b);
        add_prop(m, AI_MATKEY_EMISSIVE_INTENSITY, aiPTI_Float, &s, sizeof s);
    }
    return m;
}

static void free_material(struct aiMaterial *m)
{
    for (unsigned i = 0; i < m->mNumProperties; i++) {
        free(m->mProperties[i]->mData);
        free(m->mProperties[i]);
    }
    free(m->mProperties);
    free(m);
}

static struct aiMesh *make_mesh(bytes *b)
{
    struct aiMesh *m = calloc(1, sizeof *m);
    m->mNumVertices = get_u8(b);
    m->mNumFaces = get_u8(b);
    m->mMaterialIndex = get_u8(b);
    int normals = get_u8(b) & 1;
    m->mVertices = calloc(m->mNumVertices + 1, sizeof *m->mVertices);
    for (unsigned v = 0; v < m->mNumVertices; v++) {
        m->mVertices[v].x = get_f32(b);
        m->mVertices[v].y = get_f32(b);
        m->mVertices[v].z = get_f32(b);
    }
    if (normals) {
        m->mNormals = calloc(m->mNumVertices + 1, sizeof *m->mNormals);
        for (unsigned v = 0; v < m->mNumVertices; v++) {
            m->mNormals[v].x = get_f32(b);
            m->mNormals[v].y = get_f32(b);
            m->mNormals[v].z = get_f32(b);
        }
    }
    m->mFaces = calloc(m->mNumFaces + 1, sizeof *m->mFaces);
    for (unsigned f = 0; f < m->mNumFaces; f++) {
        struct aiFace *face = &m->mFaces[f];
        face->mNumIndices = get_u8(b) % 4 + 1;
        face->mIndices = calloc(face->mNumIndices, sizeof *face->mIndices);
        for (unsigned k = 0; k < face->mNumIndices; k++)
            face->mIndices[k] = get_u8(b);
    }
    return m;
}

static void free_mesh(struct aiMesh *m)
{
    for (unsigned f = 0; f < m->mNumFaces; f++)
        free(m->mFaces[f].mIndices);
    free(m->mFaces);
    free(m->mVertices);
    free(m->mNormals);
    free(m);
}

static int finite3(gi_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* What a converted mesh must be, given the scene it came from. */
static void check_mesh(const struct aiScene *sc, const gi_mesh_data *m)
{
    uint64_t nv = 0, nt = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        uint64_t t = 0;
        for (unsigned f = 0; f < sc->mMeshes[i]->mNumFaces; f++)
            t += sc->mMeshes[i]->mFaces[f].mNumIndices == 3;
        nv += t ? sc->mMeshes[i]->mNumVertices : 0;
        nt += t;
    }
    if (m->vertex_count != nv || m->triangle_count != nt || nt == 0 || m->material_count == 0)
        abort();
    for (uint64_t i = 0; i < 3 * nt; i++)
        if (m->indices[i] >= m->vertex_count)
            abort();
    for (uint32_t t = 0; t < m->triangle_count; t++)
        if (m->tri_material[t] >= m->material_count)
            abort();
    for (uint32_t v = 0; v < m->vertex_count; v++)
        if (!finite3(m->positions[v]) || (m->normals && !finite3(m->normals[v])))
            abort();
    for (uint32_t i = 0; i < m->material_count; i++) {
        if (!m->materials[i].name)
            abort();
        for (uint32_t j = 0; j < i; j++)
            if (strcmp(m->materials[i].name, m->materials[j].name) == 0)
                abort();
        /* What the scene makes of it: colours it can render. */
        gi_material g = gi_material_from_mesh(&m->materials[i], m->materials[i].name, "fuzz");
        if (!finite3(g.diffuse) || !finite3(g.emission))
            abort();
    }
}

/* The parent takes the mesh back as it was converted. */
static void check_wire(const gi_mesh_data *m)
{
    gi_buf b, again;
    gi_buf_init(&b);
    gi_buf_init(&again);
    gi_mesh_encode(&b, m);
    gi_mesh_data d;
    gi_mesh_data_init(&d);
    gi_error err;
    if (gi_mesh_decode(b.data, b.len, "fuzz", &d, &err) != 0)
        abort();
    gi_mesh_encode(&again, &d);
    if (again.len != b.len || memcmp(again.data, b.data, b.len) != 0)
        abort();
    gi_mesh_data_free(&d);
    gi_buf_free(&again);
    gi_buf_free(&b);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    gi_log_set_level(GI_LOG_ERROR); /* dropped normals, undefined materials are warned about */
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    bytes b = {data, size};
    uint8_t flags = get_u8(&b);
    const char *name = flags & 1 ? "fuzz.obj" : "fuzz.gltf";
    gi_buf libs[3];
    const gi_buf *lib_ptrs[3];
    size_t nlibs = (flags >> 1) & 3;
    for (size_t i = 0; i < nlibs; i++) {
        gi_buf_init(&libs[i]);
        size_t n = get_u8(&b);
        n |= (size_t)get_u8(&b) << 8;
        n = n < b.left ? n : b.left;
        gi_buf_put(&libs[i], b.p, n);
        b.p += n;
        b.left -= n;
        lib_ptrs[i] = &libs[i];
    }

    struct aiScene sc;
    memset(&sc, 0, sizeof sc);
    sc.mNumMaterials = get_u8(&b) % 5;
    sc.mMaterials = calloc(sc.mNumMaterials + 1, sizeof *sc.mMaterials);
    for (unsigned i = 0; i < sc.mNumMaterials; i++)
        sc.mMaterials[i] = make_material(&b);
    sc.mNumMeshes = get_u8(&b) % 5;
    sc.mMeshes = calloc(sc.mNumMeshes + 1, sizeof *sc.mMeshes);
    for (unsigned i = 0; i < sc.mNumMeshes; i++)
        sc.mMeshes[i] = make_mesh(&b);

    gi_mesh_data m;
    gi_mesh_data_init(&m);
    gi_error err;
    gi_error_clear(&err);
    if (gi_mesh_from_assimp(&sc, lib_ptrs, nlibs, name, &m, &err) == 0) {
        check_mesh(&sc, &m);
        check_wire(&m);
    } else if (strchr(err.msg, '\n') || !strstr(err.msg, name))
        abort();
    gi_mesh_data_free(&m);

    for (unsigned i = 0; i < sc.mNumMeshes; i++)
        free_mesh(sc.mMeshes[i]);
    free(sc.mMeshes);
    for (unsigned i = 0; i < sc.mNumMaterials; i++)
        free_material(sc.mMaterials[i]);
    free(sc.mMaterials);
    for (size_t i = 0; i < nlibs; i++)
        gi_buf_free(&libs[i]);
    return 0;
}
