/* gi_checked_files: the cache files this process has already checked whole
 * (CRCs, record order, values) or written itself: an animation's batch
 * store and grid files (detp_store.c, detp_grid.c), mapped every frame, and
 * its tiles' hits (gi_tile_hits.c), read every frame; checking them again
 * each time would cost a good part of the frame. Keyed by what a rewrite
 * changes (a temp file renamed into place is a new inode; size, mtime) and
 * the file's header CRC. One process, one thread. */
#ifndef GI_CHECKED_FILES_H
#define GI_CHECKED_FILES_H

#include <stdint.h>

struct stat;
int gi_file_was_checked(const struct stat *st, uint32_t header_crc);
void gi_file_note_checked(const struct stat *st, uint32_t header_crc);
/* Notes a file this process has just written whole and renamed into
 * place: the next frame need not read back what this one wrote. */
void gi_file_note_written(const char *path, uint32_t header_crc);
/* Forgets them (fuzzers rewrite one path in place thousands of times a
 * second). */
void gi_file_forget_checked(void);

#endif
