/* rad_file: factorization files. */
#include "rad_file.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_crc32c.h"
#include "gi_fs.h"
#include "rad_kernel.h"
#include "rad_mesh.h"
#include "rad_rays.h"

#define MAX_NAMES (1u << 20)
#define MAX_NAME 4096
/* Every name a scene may hold is read back: "<object>/<material>#<index>". */
_Static_assert(MAX_NAME > 2 * GI_SCENE_NAME_MAX + 32, "a scene's names fit a factorization");

void gi_rad_file_encode(const gi_rad_file_info *info, const gi_rad_model *md,
                        const gi_rad_factor *f, gi_buf *out)
{
    gi_buf p;
    gi_buf_init(&p);
    gi_buf_put_str(&p, info->method);
    gi_buf_put_u32(&p, f->n);
    gi_buf_put_u32(&p, f->k);
    gi_buf_put_u32(&p, f->rays);
    gi_buf_put_u32(&p, info->levels);
    gi_buf_put_u32(&p, info->roots);
    gi_buf_put_u32(&p, md->material_count);
    for (uint32_t i = 0; i < md->material_count; i++) {
        gi_buf_put_str(&p, md->materials[i].name);
        gi_buf_put_f32s(&p, md->materials[i].rho, 3);
        gi_buf_put_f32s(&p, md->materials[i].emission, 3);
        gi_buf_put_u32(&p, md->materials[i].two_sided ? GI_RAD_MATERIAL_TWO_SIDED : 0);
    }
    gi_buf_put_u32(&p, md->object_count);
    for (uint32_t i = 0; i < md->object_count; i++)
        gi_buf_put_str(&p, md->objects[i]);
    for (uint32_t e = 0; e < md->n; e++) {
        gi_buf_put_u32(&p, md->elem_material[e]);
        gi_buf_put_u32(&p, md->elem_object[e]);
        gi_buf_put_f64(&p, md->area[e]);
    }
    gi_buf_put_u32(&p, md->vertices.count);
    for (uint32_t v = 0; v < md->vertices.count; v++) {
        gi_buf_put_f32(&p, md->vertices.positions[v].x);
        gi_buf_put_f32(&p, md->vertices.positions[v].y);
        gi_buf_put_f32(&p, md->vertices.positions[v].z);
    }
    for (size_t i = 0; i < 3 * (size_t)md->n; i++)
        gi_buf_put_u32(&p, md->vertices.corner[i]);
    for (uint32_t e = 0; e < f->n; e++)
        gi_buf_put_u32(&p, f->patch[e]);
    for (uint32_t e = 0; e < f->n; e++) {
        const uint16_t *h = f->hits + (size_t)e * f->k_pad;
        uint8_t *dst = gi_buf_grow(&p, 2 * (size_t)f->k);
        for (uint32_t q = 0; q < f->k; q++)
            gi_le_put_u16(dst + 2 * q, h[q]);
    }
    gi_buf_put_f32s(&p, f->M, 3 * (size_t)f->k * f->k);

    gi_buf_put(out, GI_RAD_FILE_MAGIC, 8);
    gi_buf_put_u32(out, GI_RAD_FILE_VERSION);
    gi_buf_put_u32(out, 0);
    gi_buf_put_u64(out, p.len);
    gi_buf_put_u32(out, gi_crc32c(0, p.data, p.len));
    gi_buf_put(out, p.data, p.len);
    gi_buf_free(&p);
}

int gi_rad_file_write(const char *path, const gi_rad_file_info *info, const gi_rad_model *md,
                      const gi_rad_factor *f, gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_rad_file_encode(info, md, f, &b);
    int rc = gi_write_file_atomic(path, b.data, b.len, err);
    gi_buf_free(&b);
    return rc;
}

static int bad(gi_error *err, const char *name, const char *what)
{
    return gi_fail(err, GI_EINVAL, "%s: not a valid factorization file: %s", name, what);
}

static int finite3(const float *v)
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

/* The body, after the header checks; outputs are freed by the caller on
 * failure. */
static int decode_payload(gi_reader *r, uint32_t version, const char *name,
                          gi_rad_file_info *info, gi_rad_model *md, gi_rad_factor *f,
                          gi_error *err)
{
    char *method = gi_get_str(r, 7);
    if (!method)
        return bad(err, name, "truncated header");
    int known = strcmp(method, "2mf") == 0 || strcmp(method, "2mce") == 0;
    if (known)
        strcpy(info->method, method);
    free(method);
    if (!known)
        return bad(err, name, "unknown factorization method");
    uint32_t n = gi_get_u32(r), k = gi_get_u32(r), rays = gi_get_u32(r);
    info->levels = gi_get_u32(r);
    info->roots = gi_get_u32(r);
    if (r->failed)
        return bad(err, name, "truncated header");
    if (n == 0 || n > GI_RAD_MAX_ELEMENTS || k == 0 || k > n || k > GI_RAD_MAX_PATCHES ||
        rays == 0 || rays > GI_RAD_MAX_RAYS || info->levels > GI_RAD_MAX_LEVELS ||
        info->roots == 0 || info->roots > n)
        return bad(err, name, "sizes out of range");
    /* Fixed-size sections must fit in what is left, before allocating. */
    uint64_t fixed = (uint64_t)n * (16 + 12 + 4) + (uint64_t)n * k * 2 + 3ull * k * k * 4;
    if (fixed > r->left)
        return bad(err, name, "truncated (sizes larger than the file)");

    md->n = n;
    md->material_count = gi_get_u32(r);
    if (r->failed || md->material_count == 0 || md->material_count > MAX_NAMES ||
        md->material_count > r->left / 28)
        return bad(err, name, "bad material count");
    md->materials = gi_xcalloc(md->material_count, sizeof *md->materials);
    for (uint32_t i = 0; i < md->material_count; i++) {
        gi_rad_material *mt = &md->materials[i];
        mt->name = gi_get_str(r, MAX_NAME);
        gi_get_f32s(r, mt->rho, 3);
        gi_get_f32s(r, mt->emission, 3);
        /* Version 1 did not record two-sidedness: its materials read as
         * one-sided, as that version's relighting treated them. */
        uint32_t flags = version >= 2 ? gi_get_u32(r) : 0;
        if (r->failed || !mt->name)
            return bad(err, name, "truncated material table");
        if (flags & ~GI_RAD_MATERIAL_TWO_SIDED)
            return bad(err, name, "unknown material flags");
        mt->two_sided = (flags & GI_RAD_MATERIAL_TWO_SIDED) != 0;
        if (!finite3(mt->rho) || !finite3(mt->emission))
            return bad(err, name, "non-finite material value");
        for (int c = 0; c < 3; c++)
            if (mt->rho[c] < 0.0f || mt->rho[c] > 1.0f || mt->emission[c] < 0.0f)
                return bad(err, name, "material reflectance outside [0, 1] or negative emission");
    }
    md->object_count = gi_get_u32(r);
    if (r->failed || md->object_count == 0 || md->object_count > MAX_NAMES ||
        md->object_count > r->left / 4)
        return bad(err, name, "bad object count");
    md->objects = gi_xcalloc(md->object_count, sizeof *md->objects);
    for (uint32_t i = 0; i < md->object_count; i++)
        if (!(md->objects[i] = gi_get_str(r, MAX_NAME)))
            return bad(err, name, "truncated object table");
    if ((uint64_t)n * 16 > r->left)
        return bad(err, name, "truncated element table");
    md->elem_material = gi_try_malloc((size_t)n * sizeof *md->elem_material, err, name);
    md->elem_object = gi_try_malloc((size_t)n * sizeof *md->elem_object, err, name);
    md->area = gi_try_malloc((size_t)n * sizeof *md->area, err, name);
    if (!md->elem_material || !md->elem_object || !md->area)
        return -1;
    for (uint32_t e = 0; e < n; e++) {
        md->elem_material[e] = gi_get_u32(r);
        md->elem_object[e] = gi_get_u32(r);
        md->area[e] = gi_get_f64(r);
        if (md->elem_material[e] >= md->material_count || md->elem_object[e] >= md->object_count)
            return bad(err, name, "element material or object out of range");
        if (!(md->area[e] > 0.0) || !isfinite(md->area[e]))
            return bad(err, name, "element area not positive");
    }
    uint32_t nv = gi_get_u32(r);
    if (r->failed || nv == 0 || nv > 3 * n || (uint64_t)nv * 12 + (uint64_t)n * 12 > r->left)
        return bad(err, name, "bad vertex count");
    md->vertices.count = nv;
    md->vertices.positions = gi_try_malloc((size_t)nv * sizeof *md->vertices.positions, err, name);
    md->vertices.corner = gi_try_malloc(3 * (size_t)n * sizeof *md->vertices.corner, err, name);
    if (!md->vertices.positions || !md->vertices.corner)
        return -1;
    for (uint32_t v = 0; v < nv; v++) {
        float xyz[3];
        gi_get_f32s(r, xyz, 3);
        if (!finite3(xyz))
            return bad(err, name, "non-finite vertex");
        md->vertices.positions[v] = gi_v3(xyz[0], xyz[1], xyz[2]);
    }
    for (size_t i = 0; i < 3 * (size_t)n; i++)
        if ((md->vertices.corner[i] = gi_get_u32(r)) >= nv)
            return bad(err, name, "corner vertex out of range");

    if (gi_rad_factor_alloc(f, n, k, rays, err))
        return -1;
    if ((uint64_t)n * 4 + (uint64_t)n * k * 2 + 3ull * k * k * 4 != r->left)
        return bad(err, name, "factor sections do not match the sizes");
    for (uint32_t e = 0; e < n; e++)
        f->patch[e] = gi_get_u32(r);
    if (gi_rad_factor_finish(f, err)) /* patch range, no empty patch */
        return gi_error_prefix(err, "%s", name);
    for (uint32_t e = 0; e < n; e++) {
        uint16_t *h = f->hits + (size_t)e * f->k_pad;
        gi_get(r, h, 2 * (size_t)k); /* little-endian on disk */
        uint32_t sum = 0;
        for (uint32_t q = 0; q < k; q++) {
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
            h[q] = (uint16_t)((h[q] >> 8) | (h[q] << 8));
#endif
            sum += h[q];
        }
        if (sum > rays)
            return bad(err, name, "a row has more hits than rays");
    }
    size_t kk = (size_t)k * k;
    f->M = gi_try_malloc(3 * kk * sizeof *f->M, err, name);
    if (!f->M)
        return -1;
    gi_get_f32s(r, f->M, 3 * kk);
    for (size_t i = 0; i < 3 * kk; i++)
        if (!isfinite(f->M[i]))
            return bad(err, name, "non-finite SMW matrix");
    gi_rad_model_reflectance(md, f->rho);
    if (r->failed || r->left)
        return bad(err, name, "trailing or missing bytes");
    return gi_rad_factor_pack(f, err);
}

int gi_rad_file_decode(const uint8_t *data, size_t len, const char *name, gi_rad_file_info *info,
                       gi_rad_model *md, gi_rad_factor *f, gi_error *err)
{
    memset(info, 0, sizeof *info);
    memset(md, 0, sizeof *md);
    memset(f, 0, sizeof *f);
    if (len < GI_RAD_FILE_HEADER || memcmp(data, GI_RAD_FILE_MAGIC, 8) != 0)
        return bad(err, name, "no GIRADFAC header");
    uint32_t version = gi_le_get_u32(data + 8), flags = gi_le_get_u32(data + 12);
    uint64_t plen = gi_le_get_u64(data + 16);
    uint32_t crc = gi_le_get_u32(data + 24);
    if (version < GI_RAD_FILE_OLDEST_VERSION || version > GI_RAD_FILE_VERSION)
        return gi_fail(err, GI_EINVAL,
                       "%s: factorization file version %u (this gi reads %u to %u)", name,
                       version, GI_RAD_FILE_OLDEST_VERSION, GI_RAD_FILE_VERSION);
    if (flags != 0)
        return bad(err, name, "unknown flags");
    if (plen != len - GI_RAD_FILE_HEADER)
        return bad(err, name, "payload length does not match the file size (truncated?)");
    if (gi_crc32c(0, data + GI_RAD_FILE_HEADER, plen) != crc)
        return bad(err, name, "checksum mismatch (corrupted)");
    gi_reader r;
    gi_reader_init(&r, data + GI_RAD_FILE_HEADER, plen, name);
    if (decode_payload(&r, version, name, info, md, f, err)) {
        gi_rad_model_free(md);
        gi_rad_factor_free(f);
        return -1;
    }
    return 0;
}

int gi_rad_file_read(const char *path, gi_rad_file_info *info, gi_rad_model *md, gi_rad_factor *f,
                     gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    if (gi_read_file(path, GI_RAD_FILE_MAX_BYTES, &b, err)) {
        gi_buf_free(&b);
        memset(info, 0, sizeof *info);
        memset(md, 0, sizeof *md);
        memset(f, 0, sizeof *f);
        return -1;
    }
    int rc = gi_rad_file_decode(b.data, b.len, path, info, md, f, err);
    gi_buf_free(&b);
    return rc;
}
