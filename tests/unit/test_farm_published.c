/* Unit tests: a farm job's published file (gi_farm_published.h), read back
 * when gi-farmd restarts. */
#include <string.h>

#include "gi_farm_published.h"
#include "gi_test.h"

#define H1 "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef"
#define H2 "fedcba9876543210fedcba9876543210fedcba9876543210fedcba9876543210"

GI_TEST(test_farm_published_round_trip)
{
    gi_manifest m, back;
    gi_manifest_init(&m);
    gi_manifest_init(&back);
    gi_manifest_put(&m, H1, H1, 12);
    gi_manifest_put(&m, H2, H2, 0);
    gi_buf b;
    gi_buf_init(&b);
    gi_published_format(&m, &b);
    static const char want[] = H1 " 12\n" H2 " 0\n";
    GI_CHECK(b.len == strlen(want) && memcmp(b.data, want, b.len) == 0);
    GI_CHECK(gi_published_parse((const char *)b.data, b.len, &back) == 0);
    GI_REQUIRE(back.count == 2);
    GI_CHECK(strcmp(back.entries[0].hash, H1) == 0 && back.entries[0].size == 12);
    GI_CHECK(strcmp(back.entries[1].hash, H2) == 0 && back.entries[1].size == 0);
    gi_buf_free(&b);
    gi_manifest_free(&m);
    gi_manifest_free(&back);
    GI_CHECK(gi_published_parse("", 0, &back) == 0 && back.count == 0); /* an empty file */
}

/* Damaged lines are skipped and counted, the others kept: what sscanf let
 * through before (a sign, a size past any asset, bytes after the size, a
 * NUL that hid the rest of the file) is a damaged line now. */
GI_TEST(test_farm_published_skips_damaged_lines)
{
    static const char text[] = H1 " -1\n"                   /* %llu: 2^64 - 1 */
                               H1 " 12 extra\n"
                               H1 " 99999999999\n"          /* past GI_ASSET_MAX_BYTES */
                               H1 " 012\n"
                               "0123 12\n"
                               "\n"
                               H1 " 5\0\n"                  /* a NUL in the line */
                               H2 " 7";                     /* no newline: still a line */
    gi_manifest m;
    gi_manifest_init(&m);
    GI_CHECK(gi_published_parse(text, sizeof text - 1, &m) == 6);
    GI_REQUIRE(m.count == 1);
    GI_CHECK(strcmp(m.entries[0].hash, H2) == 0 && m.entries[0].size == 7);
    gi_manifest_free(&m);
}

/* A hash on several lines is one entry, at its first line's place, with
 * its last line's size (what adding the lines one by one would make). */
GI_TEST(test_farm_published_repeated_hash)
{
    static const char text[] = H1 " 5\n" H2 " 7\n" H1 " 9\n";
    gi_manifest m;
    gi_manifest_init(&m);
    GI_CHECK(gi_published_parse(text, sizeof text - 1, &m) == 0);
    GI_REQUIRE(m.count == 2);
    GI_CHECK(strcmp(m.entries[0].hash, H1) == 0 && m.entries[0].size == 9);
    GI_CHECK(strcmp(m.entries[1].hash, H2) == 0 && m.entries[1].size == 7);
    gi_manifest_free(&m);
}
