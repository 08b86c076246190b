/* rad_file: the factorization file a radiosity job leaves behind, so that
 * relighting (`gi relight`, the farm's API) needs neither the scene, the
 * form factors nor Embree. Format (little-endian, docs/job-format.md,
 * "Factorization file"):
 *
 *   "GIRADFAC" | u32 version (2) | u32 flags (0) | u64 payload bytes |
 *   u32 CRC-32C of the payload | payload
 *
 *   payload:
 *     str method ("2mf" / "2mce")            (str: u32 length + bytes)
 *     u32 n, k, rays, levels, roots
 *     u32 materials; each: str name, f32 rho[3], f32 emission[3],
 *                          u32 flags (bit 0: two-sided; version 2 on)
 *     u32 objects; each: str name
 *     n x (u32 material, u32 object, f64 area)
 *     u32 vertices; each f32 x, y, z;  n x 3 u32 corner vertex ids
 *     n x u32 patch P(e)                      (V, eq. 3.54)
 *     n x k u16 hit counts                    (U = hits / (rays c_p), eq. 3.53)
 *     3 x k x k f32 M_c                       (eq. 3.33)
 *
 * Every count is checked against the bytes left before anything is
 * allocated, every index against its range, every float for finiteness; a
 * bad file fails with GI_EINVAL and a one-line message naming it. */
#ifndef GI_RAD_FILE_H
#define GI_RAD_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "rad_factor.h"
#include "rad_model.h"

#define GI_RAD_FILE_MAGIC "GIRADFAC"
#define GI_RAD_FILE_VERSION 2u
#define GI_RAD_FILE_OLDEST_VERSION 1u /* still read: see decode_payload */
#define GI_RAD_MATERIAL_TWO_SIDED 1u
#define GI_RAD_FILE_HEADER 28u
#define GI_RAD_FILE_MAX_BYTES ((size_t)16 << 30)

typedef struct gi_rad_file_info {
    char method[8]; /* "2mf" or "2mce" */
    uint32_t levels, roots;
} gi_rad_file_info;

/* Serializes (M must be prepared). */
void gi_rad_file_encode(const gi_rad_file_info *info, const gi_rad_model *md,
                        const gi_rad_factor *f, gi_buf *out);
int gi_rad_file_write(const char *path, const gi_rad_file_info *info, const gi_rad_model *md,
                      const gi_rad_factor *f, gi_error *err);

/* Parses a whole file image; `name` is used in messages. On failure the
 * outputs are left empty. */
int gi_rad_file_decode(const uint8_t *data, size_t len, const char *name, gi_rad_file_info *info,
                       gi_rad_model *md, gi_rad_factor *f, gi_error *err);
int gi_rad_file_read(const char *path, gi_rad_file_info *info, gi_rad_model *md, gi_rad_factor *f,
                     gi_error *err);

#endif
