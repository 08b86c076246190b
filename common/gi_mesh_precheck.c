/* gi_mesh_precheck: checks a mesh file's declared sizes before assimp sees
 * it. assimp trusts counts in headers (a PLY header declaring 10^8
 * vertices makes it allocate gigabytes for a 100-byte file, and it leaks
 * that on the error path): a header whose elements cannot fit in the bytes
 * that follow it is refused here, as bad input. Likewise an OBJ face that
 * names a vertex, texture coordinate or normal the file does not have
 * (assimp refuses it, but leaks the meshes it has built when the file has
 * more than one; found by fuzz_mesh), with the line it is on, and an OBJ
 * vertex that is not a finite point. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

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
    /* Word by word, whatever the spacing: the precheck only bounds sizes, so
     * it errs towards ASCII (no size to check); assimp itself refuses a
     * "format  ascii 1.0" line. */
    int ascii = 0;
    for (const char *s = strstr(hdr, "format"); s; s = strstr(s + 1, "format")) {
        char w1[64], w2[64];
        if ((s == hdr || s[-1] == '\n' || s[-1] == '\r') &&
            sscanf(s, "%63s %63s", w1, w2) == 2 && strcmp(w1, "format") == 0)
            ascii = strcmp(w2, "ascii") == 0;
    }
    double need = 0.0, count = 0.0, elem_bytes = 0.0;
    int rc = 0;
    for (char *line = strtok(hdr, "\r\n"); line && rc == 0; line = strtok(NULL, "\r\n")) {
        char w1[64], w2[64], w3[64], w4[64];
        int n = sscanf(line, "%63s %63s %63s %63s", w1, w2, w3, w4);
        if (n >= 3 && strcmp(w1, "element") == 0) {
            need += count * elem_bytes;
            char *end;
            count = strtod(w3, &end);
            /* Negated: "nan" is a number to strtod, and no count. */
            if (*end || !(count >= 0 && count <= 2147483647.0))
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
    char num[32];
    if (need > have)
        return gi_fail(err, GI_EINVAL,
                       "%s: the PLY header declares at least %s bytes of elements, but the "
                       "file has %zu after its header (truncated or corrupt)",
                       name, gi_fmt_count(num, need), len - hdr_end);
    return 0;
}

/* An OBJ line: its keyword (the first word) and where its arguments start. */
typedef struct obj_line {
    const char *p, *end; /* the line, without its newline */
    size_t number;       /* from 1 */
} obj_line;

static int obj_next_line(const uint8_t *data, size_t len, size_t *at, obj_line *l)
{
    if (*at >= len)
        return 0;
    const char *s = (const char *)data + *at, *e = memchr(s, '\n', len - *at);
    if (!e)
        e = (const char *)data + len;
    *at = (size_t)(e - (const char *)data) + 1;
    l->p = s;
    l->end = e;
    l->number++;
    return 1;
}

/* The line's keyword: "v", "vt", "vn", "f", "l", "p" -> 0..5, else -1;
 * *args after it. Only at the start of the line: assimp skips an indented
 * line whatever it holds ("  v 1 1 0" defines no vertex, "  f 1 2 9" no
 * face; found while writing fuzz_mesh's seeds), so counting those would
 * pass faces that name vertices assimp never read, and refuse faces it
 * never reads. */
static int obj_keyword(const obj_line *l, const char **args)
{
    static const char *const words[] = {"v", "vt", "vn", "f", "l", "p"};
    const char *w = l->p, *s = w;
    while (s < l->end && !isspace((unsigned char)*s))
        s++;
    *args = s;
    for (int k = 0; k < 6; k++)
        if ((size_t)(s - w) == strlen(words[k]) && memcmp(w, words[k], (size_t)(s - w)) == 0)
            return k;
    return -1;
}

/* Every index of a face, line or point element (v, v/vt, v//vn, v/vt/vn;
 * negative: relative to the elements defined so far) must name one the
 * file defines. Tokens that are not plain integers are left to assimp. */
static int obj_check_refs(const char *name, const obj_line *l, const char *s,
                          const uint64_t total[3], const uint64_t sofar[3], gi_error *err)
{
    static const char *const what[] = {"vertex", "texture coordinate", "normal"};
    while (s < l->end) {
        while (s < l->end && isspace((unsigned char)*s))
            s++;
        for (int k = 0; k < 3 && s < l->end && !isspace((unsigned char)*s); k++) {
            if (*s == '/') { /* an empty slot: v//vn */
                s++;
                continue;
            }
            char buf[32];
            size_t n = 0;
            while (s < l->end && !isspace((unsigned char)*s) && *s != '/' && n + 1 < sizeof buf)
                buf[n++] = *s++;
            buf[n] = '\0';
            char *end;
            errno = 0;
            long long v = strtoll(buf, &end, 10);
            if (end == buf || *end || errno)
                return 0; /* not an integer: assimp decides */
            uint64_t mag = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
            if (v == 0 || (v > 0 && mag > total[k]) || (v < 0 && mag > sofar[k]))
                return gi_fail(err, GI_EINVAL,
                               "%s: line %zu: %s index %lld is out of range (%llu defined%s)",
                               name, l->number, what[k], v,
                               (unsigned long long)(v < 0 ? sofar[k] : total[k]),
                               v < 0 ? " before it" : "");
            if (s < l->end && *s == '/')
                s++;
        }
        while (s < l->end && !isspace((unsigned char)*s))
            s++;
    }
    return 0;
}

/* A vertex's coordinates must be finite ("v nan 0 0", "v 1e999 0 0" are
 * taken by assimp); said here with the line. Words that are not numbers are
 * left to assimp. */
static int obj_check_point(const char *name, const obj_line *l, const char *s, gi_error *err)
{
    for (int k = 0; k < 3; k++) {
        while (s < l->end && isspace((unsigned char)*s))
            s++;
        const char *w = s;
        while (s < l->end && !isspace((unsigned char)*s))
            s++;
        char buf[64];
        size_t n = (size_t)(s - w);
        if (n == 0 || n >= sizeof buf)
            return 0;
        memcpy(buf, w, n);
        buf[n] = '\0';
        char *end;
        double v = strtod(buf, &end);
        if (end == buf)
            return 0;
        if (!isfinite(v))
            return gi_fail(err, GI_EINVAL,
                           "%s: line %zu: vertex coordinate \"%s\" is not a finite number", name,
                           l->number, buf);
    }
    return 0;
}

static int obj_precheck(const char *name, const uint8_t *data, size_t len, gi_error *err)
{
    uint64_t total[3] = {0, 0, 0}, sofar[3] = {0, 0, 0};
    obj_line l = {0};
    size_t at = 0;
    const char *args;
    while (obj_next_line(data, len, &at, &l)) {
        int k = obj_keyword(&l, &args);
        if (k >= 0 && k < 3)
            total[k]++;
    }
    memset(&l, 0, sizeof l);
    at = 0;
    while (obj_next_line(data, len, &at, &l)) {
        int k = obj_keyword(&l, &args);
        if (k == 0 && obj_check_point(name, &l, args, err))
            return -1;
        if (k >= 0 && k < 3)
            sofar[k]++;
        else if (k >= 3 && obj_check_refs(name, &l, args, total, sofar, err))
            return -1;
    }
    return 0;
}

static int has_extension(const char *name, const char *ext)
{
    size_t n = strlen(name), e = strlen(ext);
    return n > e && strcasecmp(name + n - e, ext) == 0;
}

int gi_mesh_precheck(const char *name, const uint8_t *data, size_t len, gi_error *err)
{
    /* assimp picks the OBJ importer by the name first; otherwise its PLY
     * importer takes any file whose first line starts with "ply" or "PLY"
     * whatever follows ("ply ", "ply\t", "Ply\r"), so the check does too. */
    if (has_extension(name, ".obj"))
        return obj_precheck(name, data, len, err);
    if (len >= 3 && strncasecmp((const char *)data, "ply", 3) == 0)
        return ply_precheck(name, data, len, err);
    return 0;
}
