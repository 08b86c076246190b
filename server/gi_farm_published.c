/* gi_farm_published: a farm job's published file, "HASH SIZE" lines. */
#include "gi_farm_published.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void gi_published_format(const gi_manifest *m, gi_buf *out)
{
    for (size_t i = 0; i < m->count; i++) {
        char line[GI_HASH_HEX + 32];
        int n = snprintf(line, sizeof line, "%s %llu\n", m->entries[i].hash,
                         (unsigned long long)m->entries[i].size);
        gi_buf_put(out, line, (size_t)n);
    }
}

/* One line (without its newline), exactly as gi_published_format writes it:
 * no sign, no spaces around, no trailing bytes (sscanf took all three). */
static int parse_line(const char *s, size_t n, char hash[GI_HASH_HEX], uint64_t *size)
{
    if (n < GI_HASH_HEX + 1 || s[GI_HASH_HEX - 1] != ' ')
        return -1;
    memcpy(hash, s, GI_HASH_HEX - 1);
    hash[GI_HASH_HEX - 1] = '\0';
    if (!gi_hash_is_valid(hash))
        return -1;
    const char *d = s + GI_HASH_HEX, *end = s + n;
    if (end - d > 20 || (end - d > 1 && d[0] == '0'))
        return -1;
    uint64_t v = 0;
    for (; d < end; d++) {
        if (*d < '0' || *d > '9' || v > (GI_ASSET_MAX_BYTES - (uint64_t)(*d - '0')) / 10)
            return -1;
        v = v * 10 + (uint64_t)(*d - '0');
    }
    *size = v;
    return 0;
}

typedef struct line_entry {
    char hash[GI_HASH_HEX];
    uint64_t size;
    size_t line;
} line_entry;

static int by_hash_then_line(const void *a, const void *b)
{
    const line_entry *x = a, *y = b;
    int c = strcmp(x->hash, y->hash);
    return c ? c : (x->line > y->line) - (x->line < y->line);
}

static int by_line(const void *a, const void *b)
{
    const line_entry *x = a, *y = b;
    return (x->line > y->line) - (x->line < y->line);
}

size_t gi_published_parse(const char *text, size_t len, gi_manifest *m)
{
    /* Sorted, not gi_manifest_put line by line: that looks each hash up in
     * the entries so far, and a damaged file of 16 MiB (200k lines) would
     * hold up gi-farmd's restart for hours. */
    line_entry *e = NULL;
    size_t n = 0, cap = 0, skipped = 0;
    for (size_t pos = 0, line = 0; pos < len; line++) {
        const char *nl = memchr(text + pos, '\n', len - pos);
        size_t k = nl ? (size_t)(nl - (text + pos)) : len - pos;
        if (n == cap) {
            cap = cap ? 2 * cap : 16;
            e = gi_xrealloc(e, cap * sizeof *e);
        }
        if (parse_line(text + pos, k, e[n].hash, &e[n].size) == 0)
            e[n++].line = line;
        else if (k > 0)
            skipped++;
        pos += k + 1;
    }
    if (n == 0) { /* qsort takes no NULL array, even of 0 elements */
        free(e);
        return skipped;
    }
    /* Equal hashes: the last line's size, at the first line's place (what
     * gi_manifest_put would make of them). */
    qsort(e, n, sizeof *e, by_hash_then_line);
    size_t u = 0;
    for (size_t i = 0; i < n; i++) {
        if (u > 0 && strcmp(e[u - 1].hash, e[i].hash) == 0) {
            e[u - 1].size = e[i].size;
            continue;
        }
        e[u++] = e[i];
    }
    qsort(e, u, sizeof *e, by_line);
    for (size_t i = 0; i < u; i++)
        gi_manifest_append(m, e[i].hash, e[i].hash, e[i].size);
    free(e);
    return skipped;
}
