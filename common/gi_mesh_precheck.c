/* gi_mesh_precheck: checks a mesh file's declared sizes before assimp sees
 * it. assimp trusts counts in headers (a PLY header declaring 10^8
 * vertices makes it allocate gigabytes for a 100-byte file, and it leaks
 * that on the error path): a header whose elements cannot fit in the bytes
 * that follow it is refused here, as bad input. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_mesh.h"

static int ply_type_size(const char *t)
{
    static const struct {
        const char *name;
        int size;
    } types[] = {{"char", 1},   {"uchar", 1},  {"int8", 1},    {"uint8", 1},  {"short", 2},
                 {"ushort", 2}, {"int16", 2},  {"uint16", 2},  {"int", 4},    {"uint", 4},
                 {"int32", 4},  {"uint32", 4}, {"float", 4},   {"float32", 4}, {"double", 8},
                 {"float64", 8}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (strcmp(t, types[i].name) == 0)
            return types[i].size;
    return -1;
}

/* Every element must take at least this many bytes in the body: binary, the
 * sum of its property sizes (a list at least its count field); ASCII, two
 * characters per property ("0 "). */
static int ply_precheck(const char *name, const uint8_t *data, size_t len, gi_error *err)
{
    size_t hdr_end = 0;
    for (size_t i = 0; i + 10 <= len && i < 65536; i++)
        if (memcmp(data + i, "end_header", 10) == 0) {
            hdr_end = i + 10;
            while (hdr_end < len && data[hdr_end] != '\n')
                hdr_end++;
            if (hdr_end < len)
                hdr_end++;
            break;
        }
    if (!hdr_end)
        return gi_fail(err, GI_EINVAL, "%s: PLY header has no end_header line", name);
    char *hdr = gi_xmalloc(hdr_end + 1);
    memcpy(hdr, data, hdr_end);
    hdr[hdr_end] = '\0';
    int ascii = strstr(hdr, "format ascii") != NULL;
    double need = 0.0, count = 0.0, elem_bytes = 0.0;
    int rc = 0;
    for (char *line = strtok(hdr, "\r\n"); line && rc == 0; line = strtok(NULL, "\r\n")) {
        char w1[64], w2[64], w3[64], w4[64];
        int n = sscanf(line, "%63s %63s %63s %63s", w1, w2, w3, w4);
        if (n >= 3 && strcmp(w1, "element") == 0) {
            need += count * elem_bytes;
            char *end;
            count = strtod(w3, &end);
            if (*end || count < 0 || count > 2147483647.0)
                rc = gi_fail(err, GI_EINVAL, "%s: PLY element \"%s\" has a bad count \"%s\"", name,
                             w2, w3);
            elem_bytes = 0.0;
        } else if (n >= 3 && strcmp(w1, "property") == 0) {
            const char *t = strcmp(w2, "list") == 0 ? w3 : w2;
            int size = ply_type_size(t);
            if (size < 0)
                rc = gi_fail(err, GI_EINVAL, "%s: PLY property type \"%s\" is unknown", name, t);
            elem_bytes += ascii ? 2.0 : (double)size;
        }
    }
    need += count * elem_bytes;
    free(hdr);
    if (rc)
        return -1;
    /* The last ASCII value needs no separator after it. */
    double have = (double)(len - hdr_end) + (ascii ? 1.0 : 0.0);
    if (need > have)
        return gi_fail(err, GI_EINVAL,
                       "%s: the PLY header declares at least %.0f bytes of elements, but the "
                       "file has %zu after its header (truncated or corrupt)",
                       name, need, len - hdr_end);
    return 0;
}

int gi_mesh_precheck(const char *name, const uint8_t *data, size_t len, gi_error *err)
{
    if (len >= 4 && memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r'))
        return ply_precheck(name, data, len, err);
    return 0;
}
