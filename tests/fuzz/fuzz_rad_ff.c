/* fuzz_rad_ff: libFuzzer target for gi_rad_ff_decode, the coordinator's
 * reading of a radiosity form-factor task's result (a worker's row block).
 *
 * Layout: u8 elements in the block (% 9), u8 first element, u16 tracked
 * nodes (% 512 + 1), u16 rays per element (% 1024 + 1), then the rows.
 *
 * Any input must decode or fail with GI_EPROTO and a one-line message;
 * decoded rows must be what the format promises: every hit on a node
 * below the count, in increasing node order within a row, nonzero and at
 * most the ray count, each row's hits, escaped and back-face rays adding
 * up to the rays cast, and its d2 at most its sum of squared hits (so the
 * block's sums cannot overflow). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "radiosity/rad_ff.h"

typedef struct sink {
    uint32_t e0, e1, nodes, rays;
    uint32_t last_e, last_node;
    int any;
    uint64_t row_hits[9];
} sink;

static void on_hit(void *user, uint32_t e, uint32_t node, uint32_t hits)
{
    sink *s = user;
    if (e < s->e0 || e >= s->e1 || node >= s->nodes || hits == 0 || hits > s->rays)
        abort();
    if (s->any && (e < s->last_e || (e == s->last_e && node <= s->last_node)))
        abort();
    s->any = 1;
    s->last_e = e;
    s->last_node = node;
    s->row_hits[e - s->e0] += hits;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 6)
        return 0;
    sink s;
    memset(&s, 0, sizeof s);
    s.e0 = data[1];
    s.e1 = s.e0 + data[0] % 9;
    s.nodes = (uint32_t)(data[2] | data[3] << 8) % 512 + 1;
    s.rays = (uint32_t)(data[4] | data[5] << 8) % 1024 + 1;
    gi_rad_ff_stats st;
    memset(&st, 0, sizeof st);
    gi_error err;
    gi_error_clear(&err);
    int rc = gi_rad_ff_decode(data + 6, size - 6, s.e0, s.e1, s.nodes, s.rays, on_hit, &s, &st,
                              &err);
    if (rc) {
        if (err.code != GI_EPROTO || strchr(err.msg, '\n') || !err.msg[0])
            abort();
        return 0;
    }
    /* Every ray of every row is a hit, an escape or a back face. */
    uint64_t hits = 0;
    for (uint32_t e = 0; e < s.e1 - s.e0; e++) {
        if (s.row_hits[e] > s.rays)
            abort();
        hits += s.row_hits[e];
    }
    if (hits + st.escaped + st.backface != (uint64_t)s.rays * (s.e1 - s.e0) || st.d2 > st.h2)
        abort();
    return 0;
}
