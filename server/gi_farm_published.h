/* gi_farm_published: the format of a farm job's <dir>/published file,
 * "HASH SIZE" lines: the data its method published for tasks that the
 * checkpoint on disk needs from the asset store, read back when gi-farmd
 * restarts so that the store keeps it (gi_farm_jobs.c reads and writes the
 * file). */
#ifndef GI_FARM_PUBLISHED_H
#define GI_FARM_PUBLISHED_H

#include <stddef.h>

#include "gi_assets.h"
#include "gi_buf.h"

/* Appends m's entries (their hashes and sizes), one line each. */
void gi_published_format(const gi_manifest *m, gi_buf *out);
/* Fills m, empty, with the entries of text[0..len), named by their hash
 * (of lines with equal hashes the last counts), in O(n log n). A line that
 * is not 64 lowercase hex digits, a space and a size (decimal digits, at
 * most GI_ASSET_MAX_BYTES) is skipped: at worst the store keeps a file
 * longer. Returns the number of lines skipped. */
size_t gi_published_parse(const char *text, size_t len, gi_manifest *m);

#endif
