/* Unit tests: the radiosity factorization file and the emissions file. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_crc32c.h"
#include "gi_test.h"
#include "radiosity/rad.h"
#include "radiosity/rad_ff.h"
#include "radiosity/rad_file.h"
#include "radiosity/rad_patches.h"
#include "radiosity/rad_relight.h"

/* A small model and factor by hand: 2 materials, 2 objects, n = 6, k = 2. */
static void small(gi_rad_model *md, gi_rad_factor *f, gi_error *err)
{
    memset(md, 0, sizeof *md);
    md->n = 6;
    md->material_count = 2;
    md->materials = calloc(2, sizeof *md->materials);
    md->materials[0] = (gi_rad_material){strdup("white"), {0.5f, 0.5f, 0.5f}, {0, 0, 0}, 0};
    md->materials[1] = (gi_rad_material){strdup("lamp"), {0.8f, 0.7f, 0.6f}, {4, 3, 2}, 0};
    md->object_count = 2;
    md->objects = calloc(2, sizeof *md->objects);
    md->objects[0] = strdup("room");
    md->objects[1] = strdup("lamp");
    md->elem_material = calloc(6, sizeof(uint32_t));
    md->elem_object = calloc(6, sizeof(uint32_t));
    md->area = calloc(6, sizeof(double));
    md->vertices.count = 8;
    md->vertices.positions = calloc(8, sizeof(gi_vec3));
    md->vertices.corner = calloc(18, sizeof(uint32_t));
    for (uint32_t e = 0; e < 6; e++) {
        md->elem_material[e] = md->elem_object[e] = e >= 4;
        md->area[e] = 1.0 + e;
        for (int k = 0; k < 3; k++)
            md->vertices.corner[3 * e + k] = (e + (uint32_t)k) % 8;
    }
    for (uint32_t v = 0; v < 8; v++)
        md->vertices.positions[v] = gi_v3((float)v, 1.0f, -2.0f);
    gi_rad_factor_alloc(f, 6, 2, 16, err);
    for (uint32_t e = 0; e < 6; e++) {
        f->patch[e] = e / 3;
        f->hits[e * f->k_pad + 0] = (uint16_t)(e + 1);
        f->hits[e * f->k_pad + 1] = (uint16_t)(6 - e);
    }
    gi_rad_factor_finish(f, err);
    gi_rad_model_reflectance(md, f->rho);
    gi_rad_factor_prepare(f, err);
}

static const gi_rad_file_info small_info = {"2mf", 1, 2};

static void expect_bad(const uint8_t *data, size_t len, const char *what, int line);

GI_TEST(test_rad_factorization_file_round_trip)
{
    gi_error err;
    gi_rad_model md;
    gi_rad_factor f;
    small(&md, &f, &err);
    GI_REQUIRE(f.M != NULL);
    gi_buf a, b;
    gi_buf_init(&a);
    gi_buf_init(&b);
    gi_rad_file_encode(&small_info, &md, &f, &a);
    gi_rad_file_info info;
    gi_rad_model md2;
    gi_rad_factor f2;
    GI_REQUIRE_OK(gi_rad_file_decode(a.data, a.len, "t.fact", &info, &md2, &f2, &err));
    GI_CHECK(strcmp(info.method, "2mf") == 0 && info.levels == 1 && info.roots == 2);
    GI_CHECK(f2.n == 6 && f2.k == 2 && f2.rays == 16 && f2.patch_count[1] == 3);
    GI_CHECK(memcmp(f2.M, f.M, 3 * 4 * sizeof(float)) == 0);
    GI_CHECK(memcmp(f2.rho, f.rho, 18 * sizeof(float)) == 0);
    gi_rad_file_encode(&info, &md2, &f2, &b);
    GI_CHECK(a.len == b.len && memcmp(a.data, b.data, a.len) == 0);
    gi_rad_model_free(&md2);
    gi_rad_factor_free(&f2);
    /* Through the disk. */
    char path[1024];
    snprintf(path, sizeof path, "%s/small.factorization", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_rad_file_write(path, &small_info, &md, &f, &err));
    GI_REQUIRE_OK(gi_rad_file_read(path, &info, &md2, &f2, &err));
    gi_rad_model_free(&md2);
    gi_rad_factor_free(&f2);
    /* A white of albedo 1, which a scene allows, loads; above 1 does not. */
    md.materials[0].rho[1] = 1.0f;
    gi_buf_reset(&a);
    gi_rad_file_encode(&small_info, &md, &f, &a);
    GI_CHECK_OK(gi_rad_file_decode(a.data, a.len, "t.fact", &info, &md2, &f2, &err));
    gi_rad_model_free(&md2);
    gi_rad_factor_free(&f2);
    md.materials[0].rho[1] = 1.001f;
    gi_buf_reset(&a);
    gi_rad_file_encode(&small_info, &md, &f, &a);
    expect_bad(a.data, a.len, "reflectance outside [0, 1]", __LINE__);
    gi_buf_free(&a);
    gi_buf_free(&b);
    gi_rad_model_free(&md);
    gi_rad_factor_free(&f);
}

/* Decoding must fail with GI_EINVAL and a message containing `what`. */
static void expect_bad(const uint8_t *data, size_t len, const char *what, int line)
{
    gi_error err;
    gi_rad_file_info info;
    gi_rad_model md;
    gi_rad_factor f;
    gi_error_clear(&err);
    int rc = gi_rad_file_decode(data, len, "bad.fact", &info, &md, &f, &err);
    if (rc != -1 || err.code != GI_EINVAL || !strstr(err.msg, what) || !strstr(err.msg, "bad.fact"))
        gi_test_failed(__FILE__, line, "expected \"%s\", got rc %d: %s", what, rc, err.msg);
    if (rc == 0) {
        gi_rad_model_free(&md);
        gi_rad_factor_free(&f);
    }
}

/* Re-seals the payload's checksum after an edit. */
static void reseal(gi_buf *b)
{
    gi_le_put_u32(b->data + 24,
                  gi_crc32c(0, b->data + GI_RAD_FILE_HEADER, b->len - GI_RAD_FILE_HEADER));
}

GI_TEST(test_rad_factorization_file_refuses_damage)
{
    gi_error err;
    gi_rad_model md;
    gi_rad_factor f;
    small(&md, &f, &err);
    gi_buf a;
    gi_buf_init(&a);
    gi_rad_file_encode(&small_info, &md, &f, &a);
    expect_bad(a.data, 10, "header", __LINE__);
    expect_bad(a.data, a.len - 1, "length", __LINE__);
    a.data[a.len - 3] ^= 1;
    expect_bad(a.data, a.len, "checksum", __LINE__);
    a.data[a.len - 3] ^= 1;
    a.data[0] = 'X';
    expect_bad(a.data, a.len, "header", __LINE__);
    a.data[0] = 'G';
    gi_le_put_u32(a.data + 8, 99);
    expect_bad(a.data, a.len, "version 99", __LINE__);
    gi_le_put_u32(a.data + 8, GI_RAD_FILE_VERSION);
    /* Valid checksums over bad contents. Offsets: method str (4 + 3), then
     * n at 7, k at 11, rays at 15 (payload-relative). */
    size_t P = GI_RAD_FILE_HEADER;
    gi_le_put_u32(a.data + P + 11, 7); /* k > n */
    reseal(&a);
    expect_bad(a.data, a.len, "sizes out of range", __LINE__);
    gi_le_put_u32(a.data + P + 11, 2);
    gi_le_put_u32(a.data + P + 7, 4000000); /* n far beyond the bytes */
    reseal(&a);
    expect_bad(a.data, a.len, "truncated", __LINE__);
    gi_le_put_u32(a.data + P + 7, 6);
    /* The last element's patch index (before the 6 x 2 hits and the 3 x 4
     * matrix floats). */
    size_t patch_last = a.len - 3 * 4 * 4 - 6 * 2 * 2 - 4;
    gi_le_put_u32(a.data + patch_last, 5);
    reseal(&a);
    expect_bad(a.data, a.len, "patch 5", __LINE__);
    gi_le_put_u32(a.data + patch_last, 0); /* patch 1 keeps 2 elements */
    reseal(&a);
    gi_rad_file_info info;
    gi_rad_model md2;
    gi_rad_factor f2;
    GI_CHECK(gi_rad_file_decode(a.data, a.len, "ok.fact", &info, &md2, &f2, &err) == 0);
    gi_rad_model_free(&md2);
    gi_rad_factor_free(&f2);
    /* A row with more hits than rays (16). */
    size_t hits0 = a.len - 3 * 4 * 4 - 6 * 2 * 2;
    gi_le_put_u16(a.data + hits0, 40);
    reseal(&a);
    expect_bad(a.data, a.len, "more hits than rays", __LINE__);
    gi_buf_free(&a);
    /* A missing file is an I/O error naming it. */
    char path[1024];
    snprintf(path, sizeof path, "%s/none.factorization", gi_test_tmpdir());
    GI_CHECK(gi_rad_file_read(path, &info, &md2, &f2, &err) == -1 && strstr(err.msg, "none"));
    gi_rad_model_free(&md);
    gi_rad_factor_free(&f);
}

static int parse(const char *text, gi_rad_emissions *em, gi_error *err)
{
    return gi_rad_emissions_parse(text, strlen(text), "em.json", em, err);
}

/* Payload offsets of small()'s two material flags: the method (4 + 3), five
 * sizes (20) and the count (4), then per material its name (4 + length),
 * rho and emission (24). */
#define FLAGS_WHITE (31 + 4 + 5 + 24)
#define FLAGS_LAMP (FLAGS_WHITE + 4 + 4 + 4 + 24)

GI_TEST(test_rad_factorization_file_keeps_two_sidedness)
{
    gi_error err;
    gi_rad_model md, md2;
    gi_rad_factor f, f2;
    gi_rad_file_info info;
    small(&md, &f, &err);
    md.materials[1].two_sided = 1;
    gi_buf a;
    gi_buf_init(&a);
    gi_rad_file_encode(&small_info, &md, &f, &a);
    size_t P = GI_RAD_FILE_HEADER;
    GI_REQUIRE(gi_le_get_u32(a.data + P + FLAGS_WHITE) == 0);
    GI_REQUIRE(gi_le_get_u32(a.data + P + FLAGS_LAMP) == GI_RAD_MATERIAL_TWO_SIDED);
    GI_REQUIRE_OK(gi_rad_file_decode(a.data, a.len, "t.fact", &info, &md2, &f2, &err));
    GI_CHECK(!md2.materials[0].two_sided && md2.materials[1].two_sided);
    /* An emission set may light the one-sided material, not the two-sided. */
    gi_rad_emissions em;
    GI_REQUIRE_OK(parse("{\"emissions\": [{\"name\": \"w\", \"materials\": "
                        "{\"white\": [1, 1, 1]}}]}",
                        &em, &err));
    GI_CHECK_OK(gi_rad_emissions_check(&em, &md2, "em.json", &err));
    gi_rad_emissions_free(&em);
    GI_REQUIRE_OK(parse("{\"emissions\": [{\"name\": \"w\"}, {\"name\": \"l\", "
                        "\"materials\": {\"lamp\": [1, 1, 1]}}]}",
                        &em, &err));
    GI_CHECK(gi_rad_emissions_check(&em, &md2, "em.json", &err) == -1 &&
             strstr(err.msg, "em.json: emissions[1] (\"l\"): material \"lamp\" is two-sided"));
    gi_rad_emissions_free(&em);
    gi_rad_model_free(&md2);
    gi_rad_factor_free(&f2);
    /* Flags this version does not know are refused. */
    gi_le_put_u32(a.data + P + FLAGS_WHITE, 2);
    reseal(&a);
    expect_bad(a.data, a.len, "unknown material flags", __LINE__);
    /* A version 1 file (no flags) still loads, its materials one-sided. */
    gi_buf v1;
    gi_buf_init(&v1);
    gi_buf_put(&v1, a.data, P + FLAGS_WHITE);
    gi_buf_put(&v1, a.data + P + FLAGS_WHITE + 4, FLAGS_LAMP - FLAGS_WHITE - 4);
    gi_buf_put(&v1, a.data + P + FLAGS_LAMP + 4, a.len - P - FLAGS_LAMP - 4);
    gi_le_put_u32(v1.data + 8, 1);
    gi_le_put_u64(v1.data + 16, v1.len - P);
    reseal(&v1);
    GI_REQUIRE_OK(gi_rad_file_decode(v1.data, v1.len, "v1.fact", &info, &md2, &f2, &err));
    GI_CHECK(!md2.materials[0].two_sided && !md2.materials[1].two_sided);
    GI_CHECK(memcmp(f2.M, f.M, 3 * 4 * sizeof(float)) == 0);
    gi_rad_model_free(&md2);
    gi_rad_factor_free(&f2);
    gi_le_put_u32(v1.data + 8, 0);
    expect_bad(v1.data, v1.len, "version 0 (this gi reads 1 to 2)", __LINE__);
    gi_buf_free(&v1);
    gi_buf_free(&a);
    gi_rad_model_free(&md);
    gi_rad_factor_free(&f);
}

GI_TEST(test_rad_emissions_apply_overrides_in_order)
{
    gi_error err;
    gi_rad_model md;
    gi_rad_factor f;
    small(&md, &f, &err);
    gi_rad_emissions em;
    GI_REQUIRE_OK(
        parse("{\"description\": \"x\", \"emissions\": ["
              " {\"name\": \"scene\"},"
              " {\"name\": \"warm\", \"materials\": {\"white\": [1, 0, 0]}},"
              " {\"name\": \"obj\", \"base\": \"none\", \"materials\": {\"white\": [1, 1, 1]},"
              "  \"objects\": {\"room\": [0, 2, 0]}, \"scale\": 0.5}]}",
              &em, &err));
    GI_REQUIRE(em.count == 3);
    GI_REQUIRE_OK(gi_rad_emissions_check(&em, &md, "em.json", &err));
    float E[18];
    gi_rad_emission_vector(&em, 0, &md, E);
    GI_CHECK(E[0] == 0 && E[3 * 4] == 4 && E[3 * 5 + 2] == 2); /* the lamp's own */
    gi_rad_emission_vector(&em, 1, &md, E);
    GI_CHECK(E[0] == 1 && E[1] == 0 && E[3 * 4] == 4);
    gi_rad_emission_vector(&em, 2, &md, E);
    /* Object override wins over the material; "none" turns the lamp off. */
    GI_CHECK(E[0] == 0 && E[1] == 1 && E[2] == 0 && E[3 * 4] == 0);
    gi_rad_emissions_free(&em);
    /* Names that the scene lacks fail the check. */
    GI_REQUIRE_OK(
        parse("{\"emissions\": [{\"name\": \"a\", \"objects\": {\"sofa\": [1,1,1]}}]}", &em, &err));
    GI_CHECK(gi_rad_emissions_check(&em, &md, "em.json", &err) == -1 && strstr(err.msg, "sofa"));
    gi_rad_emissions_free(&em);
    gi_rad_model_free(&md);
    gi_rad_factor_free(&f);
}

GI_TEST(test_rad_emissions_refuse_bad_input)
{
    static const struct {
        const char *text, *what;
    } cases[] = {
        {"", "empty"},
        {"[1]", "object"},
        {"{\"emissions\": []}", "1 to"},
        {"{\"emission\": [{\"name\": \"a\"}]}", "emission"},
        {"{\"emissions\": [{}]}", "name"},
        {"{\"emissions\": [{\"name\": \"a b\"}]}", "letters"},
        {"{\"emissions\": [{\"name\": \"a\"}, {\"name\": \"a\"}]}", "already"},
        {"{\"emissions\": [{\"name\": \"a\", \"colour\": 1}]}", "colour"},
        {"{\"emissions\": [{\"name\": \"a\", \"base\": \"dark\"}]}", "base"},
        {"{\"emissions\": [{\"name\": \"a\", \"scale\": -1}]}", "scale"},
        {"{\"emissions\": [{\"name\": \"a\", \"materials\": {\"m\": [1, 2]}}]}", "[r, g, b]"},
        {"{\"emissions\": [{\"name\": \"a\", \"materials\": {\"m\": [1, -2, 0]}}]}",
         "materials.m[1]"},
        {"{\"emissions\": [{\"name\": \"a\", \"objects\": {\"o\": [1, 1, 1], \"o\": [2, 2, 2]}}]}",
         "twice"},
        {"{\"emissions\": [{\"name\": \"a\", \"objects\": [1]}]}", "objects"},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(cases); i++) {
        gi_error err;
        gi_error_clear(&err);
        gi_rad_emissions em;
        int rc = parse(cases[i].text, &em, &err);
        GI_CHECK_MSG(rc == -1 && err.code == GI_EINVAL && strstr(err.msg, "em.json") &&
                         strstr(err.msg, cases[i].what) && !strchr(err.msg, '\n'),
                     "case %zu: rc %d: %s", i, rc, err.msg);
        gi_rad_emissions_free(&em);
    }
}

static const char *nth_name(const void *ctx, uint32_t i)
{
    return ((const char *const *)ctx)[i];
}

GI_TEST(test_rad_name_list_fits_its_buffer)
{
    const char *names[] = {"white", "red", "green", "light"};
    char buf[32];
    GI_CHECK(strcmp(gi_rad_name_list(buf, sizeof buf, 4, nth_name, names),
                    "white, red, green, light") == 0);
    GI_CHECK(strcmp(gi_rad_name_list(buf, sizeof buf, 0, nth_name, names), "") == 0);
    /* Too many for the buffer: as many as fit, then "...". */
    char small[20];
    GI_CHECK_MSG(strcmp(gi_rad_name_list(small, sizeof small, 4, nth_name, names),
                        "white, red, ...") == 0,
                 "got \"%s\"", small);
    const char *long_one[] = {"a-name-longer-than-the-buffer-itself"};
    GI_CHECK(strcmp(gi_rad_name_list(small, sizeof small, 1, nth_name, long_one), "...") == 0);
}

GI_TEST(test_rad_output_names_of_several_sets_must_not_meet)
{
    gi_error err;
    gi_rad_emissions em;
    GI_REQUIRE_OK(parse("{\"emissions\": [{\"name\": \"a\"}, {\"name\": \"relight\"}]}", &em,
                        &err));
    char msg[512];
    gi_rad_output_file ok[] = {{"ply", "r.ply", NULL, 1},
                               {"exr", "r.exr", NULL, 1},
                               {"report", "r.json", NULL, 0},
                               {"factorization", "r-a.fact", NULL, 0}};
    GI_CHECK(gi_rad_outputs_distinct(ok, 4, &em, msg, sizeof msg) == 0);
    /* A fixed name that a set's file takes. */
    gi_rad_output_file fixed[] = {{"ply", "r.ply", NULL, 1}, {"report", "r-a.ply", NULL, 0}};
    GI_CHECK(gi_rad_outputs_distinct(fixed, 2, &em, msg, sizeof msg) == -1);
    GI_CHECK_MSG(strstr(msg, "\"r-a.ply\"") && strstr(msg, "set a's ply output") &&
                     strstr(msg, "the report output"),
                 "%s", msg);
    /* Two per-set outputs: set b's ply and set a-b's png are both x-a-b.ply. */
    gi_rad_output_file sets[] = {{"ply", "x-a.ply", NULL, 1}, {"png", "x.ply", NULL, 1}};
    gi_rad_emissions_free(&em);
    GI_REQUIRE_OK(parse("{\"emissions\": [{\"name\": \"a-b\"}, {\"name\": \"b\"}]}", &em,
                        &err));
    GI_CHECK(gi_rad_outputs_distinct(sets, 2, &em, msg, sizeof msg) == -1 &&
             strstr(msg, "\"x-a-b.ply\""));
    /* A relight's report, named after "relight", against a set of that name. */
    gi_rad_emissions_free(&em);
    GI_REQUIRE_OK(parse("{\"emissions\": [{\"name\": \"relight\"}]}", &em, &err));
    gi_rad_output_file relit[] = {{"ply", "r.json", NULL, 1}, {"report", "r.json", "relight", 0}};
    GI_CHECK(gi_rad_outputs_distinct(relit, 2, &em, msg, sizeof msg) == -1 &&
             strstr(msg, "r-relight.json"));
    gi_rad_emissions_free(&em);
}

static void nothing(void *user, uint32_t e, uint32_t node, uint32_t hits) {}

/* A form-factor row as a worker sends it (rad_ff.h). */
static void put_row(gi_buf *b, uint32_t nnz, uint32_t escaped, uint32_t backface,
                    const uint32_t *pairs)
{
    gi_buf_put_u32(b, nnz);
    gi_buf_put_u32(b, escaped);
    gi_buf_put_u32(b, backface);
    gi_buf_put_u64(b, 0);
    for (uint32_t i = 0; i < 2 * nnz; i++)
        gi_buf_put_u32(b, pairs[i]);
}

GI_TEST(test_rad_form_factor_rows_are_checked_on_merge)
{
    static const struct {
        uint32_t nnz, escaped, backface, pairs[6];
        int ok;
    } rows[] = {
        {2, 1, 1, {0, 10, 3, 4}, 1}, /* 10 + 4 + 1 + 1 = 16 rays */
        {2, 0, 0, {0, 10, 3, 4}, 0}, /* accounts for 14 */
        {2, 1, 1, {3, 10, 0, 4}, 0}, /* nodes out of order */
        {2, 1, 1, {0, 10, 9, 4}, 0}, /* node 9 of 8 */
        {2, 10, 1, {0, 0, 3, 5}, 0}, /* a zero count */
        {3, 0, 0, {0, 17, 1, 0, 2, 0}, 0},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(rows); i++) {
        gi_buf b;
        gi_buf_init(&b);
        put_row(&b, rows[i].nnz, rows[i].escaped, rows[i].backface, rows[i].pairs);
        gi_error err;
        gi_error_clear(&err);
        gi_rad_ff_stats st = {0};
        int rc = gi_rad_ff_decode(b.data, b.len, 5, 6, 8, 16, nothing, NULL, &st, &err);
        GI_CHECK_MSG(rows[i].ok ? rc == 0 : rc == -1 && err.code == GI_EPROTO, "row %zu: %s", i,
                     err.msg);
        /* Trailing bytes are refused too. */
        if (rows[i].ok) {
            gi_buf_put_u8(&b, 0);
            GI_CHECK(gi_rad_ff_decode(b.data, b.len, 5, 6, 8, 16, nothing, NULL, &st, &err) == -1);
        }
        gi_buf_free(&b);
    }
}
