/* gi_json: strict JSON validation over cJSON. */
#include "gi_json.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Line and column (from 1) of text[off]. */
static void line_col(const char *text, size_t off, int *line, int *col)
{
    *line = 1;
    *col = 1;
    for (size_t i = 0; i < off; i++) {
        if (text[i] == '\n') {
            (*line)++;
            *col = 1;
        } else {
            (*col)++;
        }
    }
}

/* The offset of a NUL that a string of the document would hold (raw, or
 * written \u0000), or len if none: cJSON's C strings would end there, and
 * a name checked after it would not be the name given. */
static size_t string_nul(const char *text, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        if (text[i] == '\0')
            return i;
        if (text[i] != '\\' || i + 1 >= len)
            continue;
        if (text[i + 1] == 'u' && i + 5 < len && memcmp(text + i + 2, "0000", 4) == 0)
            return i;
        i++; /* the escaped character */
    }
    return len;
}

/* The scanner's states: before the '{' (a BOM, then spaces), then in turn
 * a key (or '}' after '{'), the key's bytes, its ':', its value, and after
 * the value's ',' the next key. */
enum { TK_BOM, TK_OPEN, TK_FIRST, TK_KEY, TK_COLON, TK_VALUE, TK_NEXT, TK_DONE, TK_FAILED };

void gi_json_top_keys_begin(gi_json_top_keys_scan *s, const char *const *keys)
{
    memset(s, 0, sizeof *s);
    s->keys = keys;
    s->state = TK_BOM;
}

static void key_ended(gi_json_top_keys_scan *s)
{
    for (unsigned k = 0; k < 32 && s->keys[k]; k++)
        if (s->key_len <= sizeof s->key && strlen(s->keys[k]) == s->key_len &&
            memcmp(s->key, s->keys[k], s->key_len) == 0)
            s->found |= 1u << k;
}

/* One byte; the state after it. As cJSON, every byte up to ' ' (control
 * characters too) is space. */
static int scan_byte(gi_json_top_keys_scan *s, unsigned char c)
{
    int space = c <= ' ';
    switch (s->state) {
    case TK_BOM: /* "\xef\xbb\xbf" at the start, as cJSON skips it; without one, c opens */
        if (c == (unsigned char)"\xef\xbb\xbf"[s->bom])
            return ++s->bom < 3 ? TK_BOM : TK_OPEN;
        if (s->bom > 0)
            return TK_FAILED;
        /* fall through */
    case TK_OPEN:
        return space ? TK_OPEN : c == '{' ? TK_FIRST : TK_FAILED;
    case TK_FIRST:
    case TK_NEXT:
        if (space)
            return s->state;
        if (c == '}' && s->state == TK_FIRST)
            return TK_DONE;
        s->key_len = 0;
        s->escape = 0;
        return c == '"' ? TK_KEY : TK_FAILED;
    case TK_KEY: /* its raw bytes: a key written with escapes matches none */
        if (!s->escape && c == '"') {
            key_ended(s);
            return TK_COLON;
        }
        s->escape = !s->escape && c == '\\';
        if (s->key_len < sizeof s->key)
            s->key[s->key_len] = (char)c;
        if (s->key_len <= sizeof s->key) /* one past: longer than any key */
            s->key_len++;
        return TK_KEY;
    case TK_COLON:
        if (space)
            return TK_COLON;
        s->depth = 0;
        return c == ':' ? TK_VALUE : TK_FAILED;
    case TK_VALUE: /* to the ',' or '}' outside any string or bracket */
        if (s->in_string) {
            if (s->escape)
                s->escape = 0;
            else if (c == '\\')
                s->escape = 1;
            else if (c == '"')
                s->in_string = 0;
            return TK_VALUE;
        }
        if (c == '"') {
            s->in_string = 1;
        } else if (c == '{' || c == '[') {
            s->depth++;
        } else if (c == '}' || c == ']') {
            if (s->depth == 0)
                return c == '}' ? TK_DONE : TK_FAILED;
            s->depth--;
        } else if (c == ',' && s->depth == 0) {
            return TK_NEXT;
        }
        return TK_VALUE;
    }
    return s->state; /* done or failed: what follows is not read */
}

int gi_json_top_keys_feed(gi_json_top_keys_scan *s, const char *text, size_t len)
{
    for (size_t i = 0; i < len && s->state != TK_DONE && s->state != TK_FAILED; i++)
        s->state = scan_byte(s, (unsigned char)text[i]);
    return s->state == TK_DONE ? 0 : s->state == TK_FAILED ? -1 : 1;
}

int gi_json_top_keys_end(const gi_json_top_keys_scan *s, unsigned *found)
{
    *found = s->found;
    return s->state == TK_DONE ? 0 : -1;
}

int gi_json_top_keys(const char *text, size_t len, const char *const *keys, unsigned *found)
{
    gi_json_top_keys_scan s;
    gi_json_top_keys_begin(&s, keys);
    gi_json_top_keys_feed(&s, text, len);
    return gi_json_top_keys_end(&s, found);
}

int gi_json_parse(const char *text, size_t len, const char *file, cJSON **out,
                  gi_error *err)
{
    *out = NULL;
    int line, col;
    if (len == 0)
        return gi_fail(err, GI_EINVAL, "%s: empty file, expected a JSON object", file);
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (!root) {
        size_t off = end && end >= text ? (size_t)(end - text) : 0;
        if (off > len)
            off = len;
        line_col(text, off, &line, &col);
        return gi_fail(err, GI_EINVAL, "%s:%d:%d: invalid JSON", file, line, col);
    }
    /* Trailing garbage after the root value is an error too. */
    size_t used = len;
    if (end) {
        size_t off = (size_t)(end - text);
        used = off;
        /* Whitespace, and NULs (a terminator counted in len), may follow. */
        while (off < len && (text[off] == ' ' || text[off] == '\n' || text[off] == '\r' ||
                             text[off] == '\t' || text[off] == '\0'))
            off++;
        if (off < len) {
            cJSON_Delete(root);
            return gi_fail(err, GI_EINVAL, "%s: unexpected text after the JSON document",
                           file);
        }
    }
    size_t nul = string_nul(text, used);
    if (nul < used) {
        cJSON_Delete(root);
        line_col(text, nul, &line, &col);
        return gi_fail(err, GI_EINVAL, "%s:%d:%d: a string holds a NUL character (\\u0000)",
                       file, line, col);
    }
    if (!cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return gi_fail(err, GI_EINVAL, "%s: the document must be a JSON object", file);
    }
    *out = root;
    return 0;
}

const char *gi_json_path(char *buf, size_t n, const char *path, const char *key)
{
    if (path && path[0])
        snprintf(buf, n, "%s.%s", path, key);
    else
        snprintf(buf, n, "%s", key);
    return buf;
}

const char *gi_json_index_path(char *buf, size_t n, const char *path, int i)
{
    snprintf(buf, n, "%s[%d]", path, i);
    return buf;
}

int gi_jv_fail(gi_jv *v, const char *path, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (path && path[0])
        return gi_fail(v->err, GI_EINVAL, "%s: %s: %s", v->file, path, msg);
    return gi_fail(v->err, GI_EINVAL, "%s: %s", v->file, msg);
}

static const char *type_name(const cJSON *item)
{
    if (!item)
        return "nothing";
    if (cJSON_IsNumber(item))
        return "a number";
    if (cJSON_IsString(item))
        return "a string";
    if (cJSON_IsBool(item))
        return "a boolean";
    if (cJSON_IsNull(item))
        return "null";
    if (cJSON_IsArray(item))
        return "an array";
    if (cJSON_IsObject(item))
        return "an object";
    return "an invalid value";
}

static const cJSON *member(const cJSON *obj, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(obj, key);
}

/* Finds key in obj, with its path in p: 1 if present (*item set), 0 if
 * absent and optional, -1 (and the error) if absent and required. */
static int lookup(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
                  char p[512], const cJSON **item)
{
    gi_json_path(p, 512, path, key);
    *item = member(obj, key);
    if (*item)
        return 1;
    return required ? gi_jv_fail(v, p, "missing (required)") : 0;
}

/* "a, b, c" into buf. */
static const char *join_names(const char *const *names, char *buf, size_t n)
{
    size_t len = 0;
    buf[0] = '\0';
    for (int i = 0; names[i] && len + 64 < n; i++)
        len += (size_t)snprintf(buf + len, n - len, "%s%s", i ? ", " : "", names[i]);
    return buf;
}

int gi_jv_object(gi_jv *v, const cJSON *obj, const char *path)
{
    if (!cJSON_IsObject(obj))
        return gi_jv_fail(v, path, "expected an object, got %s", type_name(obj));
    return 0;
}

int gi_jv_keys(gi_jv *v, const cJSON *obj, const char *path, const char *const *allowed)
{
    if (gi_jv_object(v, obj, path))
        return -1;
    for (const cJSON *it = obj->child; it; it = it->next) {
        int known = 0;
        for (const char *const *a = allowed; *a; a++)
            if (it->string && strcmp(it->string, *a) == 0)
                known = 1;
        char p[512];
        if (!known) {
            char list[512];
            return gi_jv_fail(v, gi_json_path(p, sizeof p, path, it->string ? it->string : "?"),
                              "unknown key (expected one of: %s)",
                              join_names(allowed, list, sizeof list));
        }
        for (const cJSON *o = obj->child; o != it; o = o->next)
            if (strcmp(o->string, it->string) == 0)
                return gi_jv_fail(v, gi_json_path(p, sizeof p, path, it->string),
                                  "key appears twice");
    }
    return 0;
}


/* d with as few digits as give it back (%g alone rounds to 6: 1000001
 * would read "1e+06", inside a range it is said to be out of). */
static const char *fmt_number(char buf[32], double d)
{
    for (int digits = 6; digits < 17; digits++) {
        snprintf(buf, 32, "%.*g", digits, d);
        if (strtod(buf, NULL) == d)
            return buf;
    }
    snprintf(buf, 32, "%.17g", d);
    return buf;
}

int gi_jv_value_number(gi_jv *v, const cJSON *item, const char *path, double lo,
                       double hi, double *out)
{
    if (!cJSON_IsNumber(item))
        return gi_jv_fail(v, path, "expected a number, got %s", type_name(item));
    double d = item->valuedouble;
    if (!isfinite(d))
        return gi_jv_fail(v, path, "number is not finite");
    char num[32];
    if (d < lo || d > hi)
        return gi_jv_fail(v, path, "%s is out of range [%g, %g]", fmt_number(num, d), lo, hi);
    *out = d;
    return 0;
}

int gi_jv_number(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                 int required, double lo, double hi, double *out)
{
    char p[512];
    const cJSON *item;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    return gi_jv_value_number(v, item, p, lo, hi, out);
}

int gi_jv_int(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
              int64_t lo, int64_t hi, int64_t *out)
{
    char p[512];
    const cJSON *item;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    if (!cJSON_IsNumber(item))
        return gi_jv_fail(v, p, "expected an integer, got %s", type_name(item));
    double d = item->valuedouble;
    if (!isfinite(d) || d != floor(d))
        return gi_jv_fail(v, p, "expected an integer, got %g", d);
    /* From 2^53 on the double is not the integer written (2^53 + 1 reads
     * as 2^53): echoing it would name a number the user did not write. */
    if (fabs(d) >= 9007199254740992.0 && (d < (double)lo || d > (double)hi))
        return gi_jv_fail(v, p, "out of range [%lld, %lld] (and integers of 2^53 or more are "
                          "not exact in JSON)", (long long)lo, (long long)hi);
    char num[32];
    if (d < (double)lo || d > (double)hi)
        return gi_jv_fail(v, p, "%s is out of range [%lld, %lld]", gi_fmt_count(num, d),
                          (long long)lo, (long long)hi);
    *out = (int64_t)d;
    return 0;
}

int gi_jv_bool(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
               int *out)
{
    char p[512];
    const cJSON *item;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    if (!cJSON_IsBool(item))
        return gi_jv_fail(v, p, "expected true or false, got %s", type_name(item));
    *out = cJSON_IsTrue(item);
    return 0;
}

int gi_jv_string(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                 int required, const char **out)
{
    char p[512];
    const cJSON *item;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    if (!cJSON_IsString(item) || !item->valuestring)
        return gi_jv_fail(v, p, "expected a string, got %s", type_name(item));
    *out = item->valuestring;
    return 0;
}

int gi_jv_enum(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
               const char *const *choices, int *out)
{
    const char *s = NULL;
    if (gi_jv_string(v, obj, path, key, required, &s))
        return -1;
    if (!s)
        return 0;
    for (int i = 0; choices[i]; i++)
        if (strcmp(s, choices[i]) == 0) {
            *out = i;
            return 0;
        }
    char list[512], p[512];
    return gi_jv_fail(v, gi_json_path(p, sizeof p, path, key), "\"%s\" is not one of: %s", s,
                      join_names(choices, list, sizeof list));
}

int gi_jv_vec3d(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                int required, double lo, double hi, double out[3])
{
    char p[512];
    const cJSON *item;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return gi_jv_fail(v, p, "expected an array of 3 numbers, got %s",
                          cJSON_IsArray(item) ? "an array of another length" : type_name(item));
    int i = 0;
    for (const cJSON *e = item->child; e; e = e->next, i++) {
        char q[540];
        if (gi_jv_value_number(v, e, gi_json_index_path(q, sizeof q, p, i), lo, hi, &out[i]))
            return -1;
    }
    return 0;
}

int gi_jv_vec3(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
               double lo, double hi, gi_vec3 *out)
{
    double d[3];
    if (!member(obj, key))
        return gi_jv_vec3d(v, obj, path, key, required, lo, hi, d);
    if (gi_jv_vec3d(v, obj, path, key, required, lo, hi, d))
        return -1;
    *out = gi_v3((float)d[0], (float)d[1], (float)d[2]);
    return 0;
}

int gi_jv_member_object(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                        int required, const cJSON **out)
{
    char p[512];
    const cJSON *item;
    *out = NULL;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    if (!cJSON_IsObject(item))
        return gi_jv_fail(v, p, "expected an object, got %s", type_name(item));
    *out = item;
    return 0;
}

int gi_jv_member_array(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                       int required, const cJSON **out)
{
    char p[512];
    const cJSON *item;
    *out = NULL;
    int got = lookup(v, obj, path, key, required, p, &item);
    if (got <= 0)
        return got;
    if (!cJSON_IsArray(item))
        return gi_jv_fail(v, p, "expected an array, got %s", type_name(item));
    *out = item;
    return 0;
}

void gi_json_print_line(FILE *out, cJSON *o)
{
    char *text = cJSON_PrintUnformatted(o);
    if (text)
        fprintf(out, "%s\n", text);
    fflush(out);
    cJSON_free(text);
    cJSON_Delete(o);
}
