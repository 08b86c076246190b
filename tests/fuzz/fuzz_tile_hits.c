/* fuzz_tile_hits: libFuzzer target for an animation tile's hits file
 * (gi_tile_hits.h). The input is written as the file of a fixed tile and
 * read back: it must read, with every hit a miss or on one of the scene's
 * triangles in front of the camera, or be "trace again" (0) with a reason;
 * never crash, leak, hang or report an I/O error. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "gi_checked_files.h"
#include "gi_fs.h"
#include "gi_tile_hits.h"

/* What the seed corpus was made with (tests/fuzz/corpus/tile_hits). */
#define SPP 2
#define TRIS 10
static const gi_tile TILE = {16, 8, 20, 11};
#define HITS (4 * 3 * SPP)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char dir[64], path[128];
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/fuzz_tile_hits.%ld", (long)getpid());
        snprintf(path, sizeof path, "%s/tile.16.8.20.11.2.hits", dir);
        gi_error e;
        if (gi_mkdirs(dir, &e))
            abort();
    }
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
        abort();
    gi_error err;
    gi_error_clear(&err);
    gi_file_forget_checked(); /* the same path rewritten in place */
    gi_tile_hit hits[HITS];
    int rc = gi_tile_hits_read(dir, &TILE, SPP, TRIS, hits, &err);
    if (rc == 1) {
        for (int i = 0; i < HITS; i++)
            if (hits[i].tri != GI_TILE_HIT_NONE &&
                (hits[i].tri >= TRIS || !(hits[i].t >= 0.0f) || !isfinite(hits[i].t)))
                abort();
    } else if (rc != 0 || !err.msg[0]) {
        abort();
    }
    unlink(path);
    return 0;
}
