/* fuzz_detp_grid: libFuzzer target for the animation's path grids
 * (detp_grid.h). The input is written as a grid file and mapped for a
 * fixed batch, base and spec: it must map, with every path start and list
 * entry in range, or be "missing" (0); never crash, leak, hang or report an
 * I/O error. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "detp/detp_grid.h"
#include "gi_checked_files.h"

/* What the seed corpus was made with (tests/fuzz/corpus/detp_grid). */
#define P0 10
#define P1 14
#define RECORDS 6
#define BASE_CRC 0x1234u

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char path[64];
    if (!path[0])
        snprintf(path, sizeof path, "/tmp/fuzz_detp_grid.%ld", (long)getpid());
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
        abort();
    detp_grid_spec spec;
    detp_grid_spec_make(gi_v3(0, 0, 0), gi_v3(4, 4, 4), 1.0f, &spec);
    gi_error err;
    gi_error_clear(&err);
    gi_file_forget_checked();
    detp_grid g;
    int rc = detp_grid_map(path, &spec, P0, P1, 2, RECORDS, BASE_CRC, &g, &err);
    if (rc == 1) {
        uint8_t mark[P1 - P0] = {0};
        detp_grid_mark(&g, gi_v3(2, 2, 2), 4.0f, mark);
        for (uint32_t i = 0; i < g.paths; i++)
            if (g.path_start[i] > g.path_start[i + 1] || g.path_start[i + 1] > RECORDS)
                abort();
        detp_grid_unmap(&g);
    } else if (rc != 0 || !err.msg[0]) {
        abort();
    }
    unlink(path);
    return 0;
}
