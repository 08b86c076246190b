/* Unit tests: gi_frame_cache (ASSET_PUT frames kept for the next host). */
#include <string.h>

#include "gi_frame_cache.h"
#include "gi_test.h"

static void put(gi_frame_cache *c, const char *hash, size_t len, uint8_t fill)
{
    gi_buf b;
    gi_buf_init(&b);
    for (size_t i = 0; i < len; i++)
        gi_buf_put(&b, &fill, 1);
    gi_frame_cache_put(c, hash, &b);
    gi_buf_free(&b);
}

static int holds(gi_frame_cache *c, const char *hash, size_t len, uint8_t fill)
{
    const gi_buf *b = gi_frame_cache_get(c, hash);
    if (!b || b->len != len)
        return 0;
    for (size_t i = 0; i < len; i++)
        if (b->data[i] != fill)
            return 0;
    return 1;
}

GI_TEST(test_frame_cache_keeps_frames_and_drops_the_least_recently_used)
{
    gi_frame_cache c;
    gi_frame_cache_init(&c, 1000);
    GI_CHECK(gi_frame_cache_get(&c, "aa") == NULL);
    put(&c, "aa", 200, 1);
    put(&c, "bb", 200, 2);
    put(&c, "cc", 200, 3);
    GI_CHECK(holds(&c, "aa", 200, 1) && holds(&c, "bb", 200, 2) && holds(&c, "cc", 200, 3));
    /* The same hash again keeps the first frame (content-addressed bytes). */
    put(&c, "bb", 10, 9);
    GI_CHECK(holds(&c, "bb", 200, 2));
    /* Larger than a quarter of the limit: not kept. */
    put(&c, "big", 251, 4);
    GI_CHECK(gi_frame_cache_get(&c, "big") == NULL);
    /* Used order is aa, cc, bb (bb last, by the check above): dd fits,
     * ee takes aa's room. */
    GI_CHECK(holds(&c, "aa", 200, 1) && holds(&c, "cc", 200, 3) && holds(&c, "bb", 200, 2));
    put(&c, "dd", 250, 5);
    put(&c, "ee", 250, 6);
    GI_CHECK(gi_frame_cache_get(&c, "aa") == NULL);
    GI_CHECK(c.bytes == 900);
    /* cc is now the least recently used: ff takes its room. */
    GI_CHECK(holds(&c, "bb", 200, 2) && holds(&c, "dd", 250, 5) && holds(&c, "ee", 250, 6));
    put(&c, "ff", 250, 7);
    GI_CHECK(gi_frame_cache_get(&c, "cc") == NULL);
    GI_CHECK(holds(&c, "ff", 250, 7) && holds(&c, "bb", 200, 2));
    GI_CHECK(c.bytes == 950 && c.bytes <= c.max_bytes);
    gi_frame_cache_free(&c);
}
