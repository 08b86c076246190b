/* gi_mesh_precheck: checks a mesh file's declared sizes before assimp sees
 * it. assimp trusts counts in headers (a PLY header declaring 10^8
 * vertices makes it allocate gigabytes for a 100-byte file, and it leaks
 * that on the error path): a header whose elements cannot fit in the bytes
 * that follow it is refused here, as bad input. Likewise an OBJ face that
 * names a vertex, texture coordinate or normal the file does not have
 * (assimp refuses it, but leaks the meshes it has built when the file has
 * more than one; found by fuzz_mesh), with the line it is on, an OBJ
 * vertex that is not a finite point, a material name assimp would drop,
 * and what assimp mis-reads (line continuations it reads past the line
 * with, corners of more than three indices). The OBJ checks read the lines
 * as assimp does ("OBJ: the lines as assimp reads them"). */
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

/* ---- OBJ: the lines as assimp reads them ---------------------------------
 * The checks must see the lines assimp's OBJ parser sees, or they pass
 * faces it reads and refuse faces it never reads. What assimp 5.2.5 (Debian
 * 12) does, from its ObjFileParser and IOStreamBuffer and checked by
 * importing small files (test_mesh.c, mesh_precheck_obj_*):
 * - a line ends at \n, \r, \f or NUL;
 * - a '\' before a line end joins the next line: all up to and including
 *   the next \n is skipped, and the byte after that is taken whatever it
 *   is (refused here when it is a line end or another '\': assimp's
 *   parsers then read past the line); a '\' that is the file's last byte
 *   ends the line;
 * - the first byte says what a line is: 'f', 'l', 'p' start a face, line
 *   or point whatever word they begin ("fo 1 2 3" is a face, "lod 1" a
 *   line); "v" and a space or tab a vertex if the line has 3, 4 or 6
 *   numeric words, and nothing otherwise; "vt..." a texture coordinate,
 *   "vn..." a normal; an indented line is nothing; lines from "cstype" to
 *   "end" are skipped; a UTF-8 byte order mark is not skipped;
 * - a face's indices are read with atoi from every byte that is not a
 *   space, tab or '/', stepping over as many bytes as the number has
 *   digits ("007" is 7, 7, 7); a word that is no number fails the import;
 * - a file is read in blocks of OBJ_BLOCK bytes: a continuation that
 *   reaches over the end of a block is read from stale memory or past the
 *   cache (refused here; in a smaller file, past the data it reads 
);
 *   in a file of more than one block, a last line without a line end is
 *   dropped. */

#define OBJ_BLOCK ((size_t)4096 * 4096) /* IOStreamBuffer's default cache */

static int obj_line_end(uint8_t c) { return c == '\n' || c == '\r' || c == '\f' || c == '\0'; }

typedef struct obj_reader {
    const uint8_t *data;
    size_t len, at;
    size_t line; /* the line number (\n, \r\n or a lone \r end one) at `at`, from 1 */
    gi_buf text; /* the current line, continuations joined */
} obj_reader;

/* A line as assimp reads it, without its line end. */
typedef struct obj_line {
    const char *p, *end;
    size_t number; /* where it starts */
} obj_line;

static size_t obj_count_lines(const uint8_t *d, size_t len, size_t from, size_t to)
{
    size_t n = 0;
    for (size_t i = from; i < to; i++)
        n += d[i] == '\n' || (d[i] == '\r' && (i + 1 >= len || d[i + 1] != '\n'));
    return n;
}

/* How far assimp may read from pos: to the end of pos's block, and past
 * the data of a file smaller than a block, over the cache's \n filling. */
static size_t obj_readable_end(const obj_reader *r, size_t pos)
{
    if (r->len < OBJ_BLOCK)
        return OBJ_BLOCK;
    size_t e = (pos / OBJ_BLOCK + 1) * OBJ_BLOCK;
    return e < r->len ? e : r->len;
}

static int obj_refuse_continuation(const obj_reader *r, const char *name, size_t bs,
                                   const char *why, gi_error *err)
{
    return gi_fail(err, GI_EINVAL,
                   "%s: line %zu: the '\\' (a line continuation) at byte %zu %s, which the "
                   "importer (assimp) mis-reads",
                   name, r->line + obj_count_lines(r->data, r->len, r->at, bs), bs, why);
}

/* A '\' at bs: where the line goes on (bs + 1 for a '\' inside the line;
 * after a continuation, the byte after the next \n, or past the data), or
 * -1 (refused) where assimp would read outside what obj_readable_end
 * allows, or take a line end or a '\' as the line's next byte. */
static int obj_backslash(const obj_reader *r, const char *name, size_t bs, size_t *next,
                         gi_error *err)
{
    const uint8_t *d = r->data;
    size_t len = r->len, lim = obj_readable_end(r, bs);
    if (bs + 1 >= lim)
        return obj_refuse_continuation(r, name, bs, "ends a 16 MiB block of the file", err);
    if (bs + 1 < len && !obj_line_end(d[bs + 1])) {
        *next = bs + 1;
        return 0;
    }
    const uint8_t *nl = bs + 1 < len ? memchr(d + bs + 1, '\n', len - bs - 1) : NULL;
    size_t after = (nl ? (size_t)(nl - d) : len) + 1; /* past the data: the filling's \n */
    if (after >= lim)
        return obj_refuse_continuation(r, name, bs,
                                       "joins a line that reaches over the end of the file "
                                       "or of a 16 MiB block of it",
                                       err);
    if (after < len && (obj_line_end(d[after]) || d[after] == '\\'))
        return obj_refuse_continuation(r, name, bs,
                                       d[after] == '\\' ? "joins a line that starts with "
                                                          "another '\\'"
                                                        : "joins an empty line",
                                       err);
    *next = after;
    return 0;
}

/* The next line into l: 1, 0 at the end, -1 when refused. */
static int obj_next_line(obj_reader *r, const char *name, obj_line *l, gi_error *err)
{
    const uint8_t *d = r->data;
    size_t len = r->len, at = r->at;
    if (at >= len)
        return 0;
    gi_buf_reset(&r->text);
    int ended = 0; /* by a line end, not by the end of the data */
    while (at < len) {
        size_t s = at;
        while (at < len && !obj_line_end(d[at]) && d[at] != '\\')
            at++;
        gi_buf_put(&r->text, d + s, at - s);
        if (at >= len)
            break;
        if (d[at] != '\\') {
            ended = 1;
            at++;
            break;
        }
        size_t next = at;
        if (obj_backslash(r, name, at, &next, err))
            return -1;
        if (next == at + 1)
            gi_buf_put(&r->text, d + at, 1);
        at = next < len ? next : len;
    }
    /* Read in blocks, a last line that does not end is dropped. */
    if (!ended && len > OBJ_BLOCK)
        gi_buf_reset(&r->text);
    l->p = r->text.len ? (const char *)r->text.data : "";
    l->end = l->p + r->text.len;
    l->number = r->line;
    r->line += obj_count_lines(d, len, r->at, at);
    r->at = at;
    return 1;
}

enum { OBJ_NONE, OBJ_V, OBJ_VT, OBJ_VN, OBJ_FACE, OBJ_USEMTL, OBJ_CSTYPE, OBJ_END };

static int obj_space(char c) { return c == ' ' || c == '\t'; }

/* Whether the line's first word (up to a space or tab) is w. */
static int obj_first_word(const obj_line *l, const char *w)
{
    size_t n = strlen(w);
    return (size_t)(l->end - l->p) >= n && memcmp(l->p, w, n) == 0 &&
           (l->p + n == l->end || obj_space(l->p[n]));
}

/* Words that start like a number (digit, sign, "nan", "inf"): how assimp
 * tells how many coordinates a "v" line gives. */
static int obj_numeric_words(const char *s, const char *end)
{
    int n = 0;
    for (;;) {
        while (s < end && obj_space(*s))
            s++;
        if (s >= end)
            return n;
        n += isdigit((unsigned char)*s) || *s == '-' || *s == '+' ||
             (end - s >= 3 && (strncasecmp(s, "nan", 3) == 0 || strncasecmp(s, "inf", 3) == 0));
        while (s < end && !obj_space(*s))
            s++;
    }
}

/* What the line is to assimp; *words: a vertex's numeric words. */
static int obj_kind(const obj_line *l, int *words)
{
    size_t n = (size_t)(l->end - l->p);
    if (n == 0)
        return OBJ_NONE;
    switch (l->p[0]) {
    case 'v':
        if (n >= 2 && obj_space(l->p[1])) {
            *words = obj_numeric_words(l->p + 1, l->end);
            return *words == 3 || *words == 4 || *words == 6 ? OBJ_V : OBJ_NONE;
        }
        return n >= 2 && l->p[1] == 't' ? OBJ_VT : n >= 2 && l->p[1] == 'n' ? OBJ_VN : OBJ_NONE;
    case 'f':
    case 'l':
    case 'p': return OBJ_FACE;
    case 'u': return obj_first_word(l, "usemtl") ? OBJ_USEMTL : OBJ_NONE;
    case 'c': return obj_first_word(l, "cstype") ? OBJ_CSTYPE : OBJ_NONE;
    case 'e': return obj_first_word(l, "end") ? OBJ_END : OBJ_NONE;
    default: return OBJ_NONE;
    }
}

/* Each index of a face, line or point element, as assimp reads them (v,
 * v/vt, v//vn, v/vt/vn; negative: relative to the elements defined so
 * far), must name one the file defines. Returns 1 when assimp fails the
 * import on the line anyway (a word that is no number), -1 if refused. */
static int obj_check_refs(const char *name, const obj_line *l, const uint64_t total[3],
                          const uint64_t sofar[3], gi_error *err)
{
    static const char *const what[] = {"vertex", "texture coordinate", "normal"};
    const char *s = l->p, *end = l->end;
    while (s < end && !obj_space(*s)) /* the keyword, whatever word it is */
        s++;
    int slot = 0;
    while (s < end) {
        if (*s == '/' || obj_space(*s)) {
            slot = *s == '/' ? slot + 1 : 0;
            s++;
            continue;
        }
        /* atoi: white space (here only \v), a sign, digits. */
        const char *t = s;
        while (t < end && isspace((unsigned char)*t))
            t++;
        int neg = t < end && *t == '-';
        t += t < end && (*t == '-' || *t == '+');
        uint64_t mag = 0;
        int digits = 0;
        for (; t < end && isdigit((unsigned char)*t); t++, digits++)
            mag = mag > UINT64_MAX / 16 ? UINT64_MAX / 16 : mag * 10 + (uint64_t)(*t - '0');
        if (digits == 0)
            return 1;
        if (slot == 1 && sofar[1] == 0 && sofar[2] > 0)
            slot = 2; /* v//vn written v/vn: assimp reads a normal */
        if (slot > 2)
            return gi_fail(err, GI_EINVAL,
                           "%s: line %zu: a corner has more than three indices "
                           "(vertex/texture coordinate/normal)",
                           name, l->number);
        if (mag == 0 || (!neg && mag > total[slot]) || (neg && mag > sofar[slot]))
            return gi_fail(err, GI_EINVAL,
                           "%s: line %zu: %s index %s%llu is out of range (%llu defined%s)",
                           name, l->number, what[slot], neg ? "-" : "",
                           (unsigned long long)mag,
                           (unsigned long long)(neg ? sofar[slot] : total[slot]),
                           neg ? " before it" : "");
        /* In range, the number fits an int: assimp steps over its digits
         * (and the minus sign), not over leading zeros or a plus sign. */
        int step = 1 + neg;
        for (uint64_t m = mag; m >= 10; m /= 10)
            step++;
        s += step;
    }
    return 0;
}

/* A vertex's coordinates (the first three words; a fourth, the homogeneous
 * w) must be finite ("v nan 0 0", "v 1e999 0 0" are taken by assimp; "v 1 2
 * 3 nan" becomes another vertex); said here with the line. Words that are
 * not numbers are left to assimp. */
static int obj_check_point(const char *name, const obj_line *l, int words, gi_error *err)
{
    const char *s = l->p + 1;
    for (int k = 0; k < (words == 4 ? 4 : 3); k++) {
        while (s < l->end && obj_space(*s))
            s++;
        const char *w = s;
        while (s < l->end && !obj_space(*s))
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

/* A material name assimp would drop (over its 1023 bytes) or we refuse
 * (over GI_MESH_NAME_MAX): said with the line. assimp takes the rest of
 * the line, trimmed. */
static int obj_check_usemtl(const char *name, const obj_line *l, gi_error *err)
{
    const char *s = l->p + 6, *e = l->end;
    while (s < e && isspace((unsigned char)*s))
        s++;
    while (e > s && isspace((unsigned char)e[-1]))
        e--;
    if ((size_t)(e - s) > GI_MESH_NAME_MAX)
        return gi_fail(err, GI_EINVAL,
                       "%s: line %zu: usemtl: the material's name (\"%.24s...\") is %zu bytes "
                       "long, over the limit of %d",
                       name, l->number, s, (size_t)(e - s), GI_MESH_NAME_MAX);
    return 0;
}

/* Runs over the lines assimp reads as data (not those of a cstype
 * section): pass 0 counts the vertices, texture coordinates and normals,
 * pass 1 checks the lines against them. */
static int obj_pass(const char *name, const uint8_t *data, size_t len, int check,
                    uint64_t total[3], gi_error *err)
{
    obj_reader r = {data, len, 0, 1, {0}};
    gi_buf_init(&r.text);
    uint64_t sofar[3] = {0, 0, 0};
    int in_cstype = 0, rc = 0, got = 0;
    obj_line l;
    while (rc == 0 && (got = obj_next_line(&r, name, &l, err)) == 1) {
        int words = 0, kind = obj_kind(&l, &words);
        if (in_cstype) {
            in_cstype = kind != OBJ_END;
            continue;
        }
        in_cstype = kind == OBJ_CSTYPE;
        if (kind == OBJ_V || kind == OBJ_VT || kind == OBJ_VN) {
            if (check && kind == OBJ_V && obj_check_point(name, &l, words, err))
                rc = -1;
            sofar[kind - OBJ_V]++;
        } else if (check && kind == OBJ_FACE) {
            rc = obj_check_refs(name, &l, total, sofar, err);
        } else if (check && kind == OBJ_USEMTL) {
            rc = obj_check_usemtl(name, &l, err);
        }
    }
    gi_buf_free(&r.text);
    if (got < 0)
        return -1;
    if (!check)
        memcpy(total, sofar, sizeof sofar);
    return rc < 0 ? -1 : 0;
}

static int obj_precheck(const char *name, const uint8_t *data, size_t len, gi_error *err)
{
    uint64_t total[3] = {0, 0, 0};
    return obj_pass(name, data, len, 0, total, err) || obj_pass(name, data, len, 1, total, err)
               ? -1
               : 0;
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
