/* fuzz_detp_store: libFuzzer target for the animation's batch store. The
 * input is written as a store file and mapped: it must map (and then hold
 * path-ordered records of its batch) or be "missing" (0); never crash,
 * leak, hang or report an I/O error. For inputs whose first byte is odd the
 * header's magic, count and CRCs are made right first: a mutated file almost
 * never passes its CRCs, and the record checks behind them would go
 * unfuzzed. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "detp/detp_anim.h"
#include "gi_checked_files.h"
#include "gi_crc32c.h"

/* data as a store file whose header agrees with its records. */
static uint8_t *repaired(const uint8_t *data, size_t *size)
{
    uint8_t *d = malloc(*size ? *size : 1);
    memcpy(d, data, *size);
    gi_detp_store_header h;
    if (*size < sizeof h)
        return d;
    memcpy(&h, d, sizeof h);
    memcpy(h.magic, GI_DETP_STORE_MAGIC, 4);
    size_t records = (*size - sizeof h) / sizeof(gi_detp_segment);
    h.count = records;
    *size = sizeof h + records * sizeof(gi_detp_segment);
    h.records_crc = gi_crc32c(0, d + sizeof h, records * sizeof(gi_detp_segment));
    h.header_crc = gi_crc32c(0, &h, offsetof(gi_detp_store_header, header_crc));
    memcpy(d, &h, sizeof h);
    return d;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char path[64];
    if (!path[0])
        snprintf(path, sizeof path, "/tmp/fuzz_detp_store.%ld", (long)getpid());
    gi_error err;
    gi_error_clear(&err);
    uint8_t *own = size && (data[0] & 1) ? repaired(data, &size) : NULL;
    if (own)
        data = own;
    FILE *f = fopen(path, "wb"); /* no fsync: thousands of runs a second */
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
        abort();
    gi_detp_store_mapping m;
    gi_file_forget_checked();
    int rc = gi_detp_store_map(path, &m, &err);
    if (rc == 1) {
        if (m.count * sizeof(gi_detp_segment) + sizeof m.header != size)
            abort();
        for (size_t i = 0; i < m.count; i++)
            if (m.seg[i].photon < m.header.p0 || m.seg[i].photon >= m.header.p1 ||
                (i > 0 && m.seg[i].photon == m.seg[i - 1].photon &&
                 m.seg[i].bounce != m.seg[i - 1].bounce + 1))
                abort();
        gi_detp_store_unmap(&m);
    } else if (rc != 0 || !err.msg[0]) {
        abort();
    }
    unlink(path);
    free(own);
    return 0;
}
