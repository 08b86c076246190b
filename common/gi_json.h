/* gi_json: strict reading of JSON documents (jobs, scenes, API requests).
 *
 * cJSON parses; these helpers validate. Every check names the file and the
 * field path ("scene.json: objects[2].transform[0].rotate.degrees: ...") and
 * says what was expected and what was found. Unknown and duplicate keys are
 * errors, numbers must be finite and inside their range, and integers must
 * be integral. */
#ifndef GI_JSON_H
#define GI_JSON_H

#include <stdint.h>
#include <stdio.h>

#include <cjson/cJSON.h>

#include "gi_error.h"
#include "gi_math.h"

typedef struct gi_jv {
    const char *file; /* named in every message */
    gi_error *err;
} gi_jv;

/* o as one line of JSON on out (flushed: a program reads it as it comes);
 * takes o over. */
void gi_json_print_line(FILE *out, cJSON *o);

/* Parses text (not necessarily NUL-terminated) and reports the line and
 * column of a syntax error. The root must be an object. */
int gi_json_parse(const char *text, size_t len, const char *file, cJSON **out,
                  gi_error *err);

/* Which of `keys` (NULL-terminated, at most 32, plain ASCII, each at most
 * 64 bytes) the top-level object of text names, as bit i of *found, without
 * parsing it: strings and nested values are skipped by their brackets and
 * quotes, in one pass with nothing allocated, so that a file can be told
 * apart (gi validate: a job, a scene or an emissions file) before its size
 * is checked against its kind's limit. It does not validate (the kind's own
 * parser does); a key written with escapes is not recognised. -1 if text is
 * not an object as far as it reads. */
int gi_json_top_keys(const char *text, size_t len, const char *const *keys, unsigned *found);

/* The same, fed in pieces (a file read as it comes, which a map would not
 * survive being truncated under it): begin, feed each piece in order (1:
 * more wanted; 0: the object has closed and *found is final; -1: not an
 * object of this form), then end, which says 0 only if the object closed. */
typedef struct gi_json_top_keys_scan {
    const char *const *keys;
    int state, escape, in_string;
    unsigned bom, found;
    size_t depth, key_len;
    char key[64];
} gi_json_top_keys_scan;
void gi_json_top_keys_begin(gi_json_top_keys_scan *s, const char *const *keys);
int gi_json_top_keys_feed(gi_json_top_keys_scan *s, const char *text, size_t len);
int gi_json_top_keys_end(const gi_json_top_keys_scan *s, unsigned *found);

/* "path.key" (or "key" when path is empty) into buf. */
const char *gi_json_path(char *buf, size_t n, const char *path, const char *key);
/* "path[i]" into buf. */
const char *gi_json_index_path(char *buf, size_t n, const char *path, int i);

/* Fails with "<file>: <path>: <message>". */
int gi_jv_fail(gi_jv *v, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* obj must be an object whose keys are all in `allowed` (NULL-terminated),
 * each at most once. */
int gi_jv_keys(gi_jv *v, const cJSON *obj, const char *path, const char *const *allowed);
/* Requires obj to be an object (path names it). */
int gi_jv_object(gi_jv *v, const cJSON *obj, const char *path);

/* Member lookups. `required` members that are absent fail; optional absent
 * members leave *out at the default the caller put there and return 0. */
int gi_jv_number(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                 int required, double lo, double hi, double *out);
int gi_jv_int(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
              int64_t lo, int64_t hi, int64_t *out);
int gi_jv_bool(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
               int *out);
/* *out points into the cJSON tree. */
int gi_jv_string(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                 int required, const char **out);
/* The string must be one of `choices`; *out is its index. */
int gi_jv_enum(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
               const char *const *choices, int *out);
/* Array of 3 finite numbers in [lo, hi]. */
int gi_jv_vec3(gi_jv *v, const cJSON *obj, const char *path, const char *key, int required,
               double lo, double hi, gi_vec3 *out);
/* Array of 3 finite numbers as doubles. */
int gi_jv_vec3d(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                int required, double lo, double hi, double out[3]);
/* A member that must be an object / array if present; NULL if absent. */
int gi_jv_member_object(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                        int required, const cJSON **out);
int gi_jv_member_array(gi_jv *v, const cJSON *obj, const char *path, const char *key,
                       int required, const cJSON **out);

/* A value (not a member) that must be a finite number in [lo, hi]. */
int gi_jv_value_number(gi_jv *v, const cJSON *item, const char *path, double lo,
                       double hi, double *out);

#endif
