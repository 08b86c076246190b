/* Tests for gi_image, gi_exr (OpenEXR C API) and gi_png (libpng).
 *
 * NaN handling: EXR files are lossless, so a NaN (with its payload bits)
 * round-trips bit-exactly like any other float; the PNG preview maps NaN to 0
 * (black), as it does negatives. */
#include <OpenEXR/openexr.h>
#include <dirent.h>
#include <float.h>
#include <libdeflate.h>
#include <malloc.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gi_buf.h"
#include "gi_fs.h"
#include "gi_image.h"
#include "gi_test.h"

/* ---- helpers ------------------------------------------------------------ */

static char *tpath(const char *name)
{
    return gi_path_join(gi_test_tmpdir(), name);
}

/* A fresh empty directory under the test tmpdir. */
static char *tdir(const char *name)
{
    char *d = tpath(name);
    mkdir(d, 0755);
    return d;
}

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float bitsf(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Deterministic test data (xorshift32). */
static uint32_t rng_next(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *s = x;
}

static void fill_pattern(gi_image *img, uint32_t seed)
{
    size_t n = (size_t)img->width * img->height * img->channels;
    for (size_t i = 0; i < n; i++)
        img->pixels[i] = (float)(rng_next(&seed) % 100000) * 1e-3f - 20.0f;
}

/* Every channel of `a` exists in `b` under the same name with bit-identical
 * values. Returns the number of mismatching samples. */
static long compare_by_name(const gi_image *a, const gi_image *b)
{
    if (a->width != b->width || a->height != b->height || a->channels != b->channels)
        return -1;
    long bad = 0;
    for (int c = 0; c < a->channels; c++) {
        int k = gi_image_channel(b, a->names[c]);
        if (k < 0)
            return -1;
        for (int y = 0; y < a->height; y++)
            for (int x = 0; x < a->width; x++)
                if (fbits(gi_image_at(a, x, y)[c]) != fbits(gi_image_at(b, x, y)[k]))
                    bad++;
    }
    return bad;
}

static int files_equal(const char *p, const char *q)
{
    gi_buf a, b;
    gi_buf_init(&a);
    gi_buf_init(&b);
    int eq = gi_read_file(p, 1 << 28, &a, NULL) == 0 && gi_read_file(q, 1 << 28, &b, NULL) == 0 &&
             a.len == b.len && memcmp(a.data, b.data, a.len) == 0;
    gi_buf_free(&a);
    gi_buf_free(&b);
    return eq;
}

/* Number of entries in dir (besides . and ..) whose name contains `part`. */
static int count_entries(const char *dir, const char *part)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strstr(e->d_name, part))
            n++;
    closedir(d);
    return n;
}

static int file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

/* Writes an EXR with OpenEXR's C API directly, for layouts gi_exr_write does
 * not produce (HALF/UINT channels, other compressions, tiled, multi-part).
 * `data` is interleaved per pixel in the order of `names`, elements of the
 * file's pixel type (HALF as raw 16-bit halves). Returns 0 on success. */
typedef struct exr_spec {
    exr_storage_t storage;
    int parts;
    exr_pixel_type_t type;
    exr_compression_t compression;
    int width, height, channels;
    const char *const *names;
    const void *data;
    int origin_x, origin_y; /* data window origin */
} exr_spec;

static int write_exr_core(const char *path, const exr_spec *s)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    size_t esz = s->type == EXR_PIXEL_HALF ? 2 : 4;
    exr_result_t r = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    for (int p = 0; p < s->parts && r == EXR_ERR_SUCCESS; p++) {
        char pname[16];
        snprintf(pname, sizeof pname, "part%d", p);
        int idx;
        r = exr_add_part(ctx, s->parts > 1 ? pname : NULL, s->storage, &idx);
        if (!r)
            r = exr_initialize_required_attr_simple(ctx, idx, s->width, s->height, s->compression);
        if (!r && (s->origin_x || s->origin_y)) {
            exr_attr_box2i_t dw;
            dw.min.x = s->origin_x;
            dw.min.y = s->origin_y;
            dw.max.x = s->origin_x + s->width - 1;
            dw.max.y = s->origin_y + s->height - 1;
            r = exr_set_data_window(ctx, idx, &dw);
        }
        if (!r && s->storage == EXR_STORAGE_TILED)
            r = exr_set_tile_descriptor(ctx, idx, 8, 8, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN);
        for (int c = 0; c < s->channels && !r; c++)
            r = exr_add_channel(ctx, idx, s->names[c], s->type, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    }
    if (!r)
        r = exr_write_header(ctx);
    for (int p = 0; p < s->parts && !r; p++) {
        exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
        int have = 0;
        int tiled = s->storage == EXR_STORAGE_TILED;
        int lines = 1;
        if (!tiled)
            r = exr_get_scanlines_per_chunk(ctx, p, &lines);
        int ny = tiled ? (s->height + 7) / 8 : (s->height + lines - 1) / lines;
        int nx = tiled ? (s->width + 7) / 8 : 1;
        for (int ty = 0; ty < ny && !r; ty++) {
            for (int tx = 0; tx < nx && !r; tx++) {
                exr_chunk_info_t ci;
                r = tiled ? exr_write_tile_chunk_info(ctx, p, tx, ty, 0, 0, &ci)
                          : exr_write_scanline_chunk_info(ctx, p, s->origin_y + ty * lines, &ci);
                if (!r)
                    r = have ? exr_encoding_update(ctx, p, &ci, &enc)
                             : exr_encoding_initialize(ctx, p, &ci, &enc);
                if (r)
                    break;
                for (int i = 0; i < enc.channel_count; i++) {
                    int k = 0;
                    while (strcmp(s->names[k], enc.channels[i].channel_name))
                        k++;
                    size_t row = (size_t)(ci.start_y - (tiled ? 0 : s->origin_y));
                    size_t col = (size_t)(ci.start_x - (tiled ? 0 : s->origin_x));
                    size_t off = ((row * s->width + col) * s->channels + k) * esz;
                    enc.channels[i].encode_from_ptr = (const uint8_t *)s->data + off;
                    enc.channels[i].user_pixel_stride = (int32_t)(s->channels * esz);
                    enc.channels[i].user_line_stride = (int32_t)(s->width * s->channels * esz);
                    enc.channels[i].user_bytes_per_element = (int16_t)esz;
                    enc.channels[i].user_data_type = (uint16_t)s->type;
                }
                if (!have)
                    r = exr_encoding_choose_default_routines(ctx, p, &enc);
                have = 1;
                if (!r)
                    r = exr_encoding_run(ctx, p, &enc);
            }
        }
        if (have)
            exr_encoding_destroy(ctx, &enc);
    }
    exr_result_t f = exr_finish(&ctx);
    return r ? (int)r : (int)f;
}

/* ---- gi_image ------------------------------------------------------------ */

GI_TEST(image_init_checks_sizes_and_names)
{
    gi_error err;
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, 3, 2, 4, NULL, &err));
    GI_CHECK(strcmp(img.names[0], "R") == 0 && strcmp(img.names[3], "A") == 0);
    for (int i = 0; i < 3 * 2 * 4; i++)
        GI_CHECK(fbits(img.pixels[i]) == 0);
    GI_CHECK(gi_image_channel(&img, "B") == 2);
    GI_CHECK(gi_image_channel(&img, "Z") == -1);
    GI_CHECK(gi_image_at(&img, 2, 1) == img.pixels + (1 * 3 + 2) * 4);
    gi_image_free(&img);
    GI_CHECK(img.pixels == NULL && img.channels == 0);
    gi_image_free(&img); /* twice is fine */

    GI_REQUIRE_OK(gi_image_init(&img, 1, 1, 1, NULL, &err));
    GI_CHECK(strcmp(img.names[0], "Y") == 0);
    gi_image_free(&img);
    GI_REQUIRE_OK(gi_image_init(&img, 1, 1, 6, NULL, &err));
    GI_CHECK(strcmp(img.names[4], "c4") == 0 && strcmp(img.names[5], "c5") == 0);
    gi_image_free(&img);

    GI_CHECK(gi_image_init(&img, 0, 5, 3, NULL, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(img.pixels == NULL);
    GI_CHECK(gi_image_init(&img, 5, -1, 3, NULL, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(gi_image_init(&img, 65537, 1, 3, NULL, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(gi_image_init(&img, 1, 1, 0, NULL, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(gi_image_init(&img, 1, 1, 17, NULL, &err) == -1 && err.code == GI_EINVAL);
    /* 65536^2 x 1 float = 16 GiB: over the byte limit, refused before allocating. */
    GI_CHECK(gi_image_init(&img, 65536, 65536, 1, NULL, &err) == -1 && err.code == GI_ENOMEM);
    GI_CHECK(strstr(err.msg, "limit") != NULL);

    const char *dup[] = {"R", "G", "R"};
    GI_CHECK(gi_image_init(&img, 2, 2, 3, dup, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(strstr(err.msg, "twice") != NULL);
    const char *empty[] = {"R", ""};
    GI_CHECK(gi_image_init(&img, 2, 2, 2, empty, &err) == -1 && err.code == GI_EINVAL);
    const char *longn[] = {"this.name.is.thirty.two.bytes.xx"};
    GI_CHECK(gi_image_init(&img, 2, 2, 1, longn, &err) == -1 && err.code == GI_EINVAL);
    const char *ok31[] = {"this.name.is.thirty.one.bytes.x"};
    GI_CHECK_OK(gi_image_init(&img, 2, 2, 1, ok31, &err));
    gi_image_free(&img);
}

/* ---- EXR round trips ------------------------------------------------------- */

GI_TEST(exr_roundtrip_rgb_bit_exact)
{
    gi_error err;
    gi_image img, back;
    const char *rgb[] = {"R", "G", "B"};
    GI_REQUIRE_OK(gi_image_init(&img, 7, 5, 3, rgb, &err));
    fill_pattern(&img, 12345);
    char *p = tpath("rgb.exr");
    GI_REQUIRE_OK(gi_exr_write(p, &img, &err));
    GI_REQUIRE_OK(gi_exr_read(p, &back, &err));
    GI_CHECK(back.width == 7 && back.height == 5 && back.channels == 3);
    /* EXR sorts channels by name: B, G, R. */
    GI_CHECK(strcmp(back.names[0], "B") == 0 && strcmp(back.names[1], "G") == 0 &&
             strcmp(back.names[2], "R") == 0);
    GI_CHECK(compare_by_name(&img, &back) == 0);
    gi_image_free(&back);
    gi_image_free(&img);
    free(p);
}

/* A disk that takes no byte (RLIMIT_FSIZE 0 stands in for a full one: the
 * header write at offset 0 fails) fails the write with the reason; it
 * used to hang in the library's error handler. In a child, so that a hang
 * is an alarm and not a stuck test run. */
GI_TEST(exr_write_on_a_full_disk_fails_and_does_not_hang)
{
    gi_error err;
    gi_image img;
    const char *rgb[] = {"R", "G", "B"};
    GI_REQUIRE_OK(gi_image_init(&img, 64, 48, 3, rgb, &err));
    fill_pattern(&img, 7);
    char *p = tpath("full-disk.exr");
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        alarm(20);
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit rl = {0, 0};
        setrlimit(RLIMIT_FSIZE, &rl);
        int rc = gi_exr_write(p, &img, &err);
        int ok = rc != 0 && strstr(err.msg, "full-disk.exr") && strstr(err.msg, "File too large") &&
                 access(p, F_OK) != 0;
        if (!ok)
            fprintf(stderr, "rc %d: %s\n", rc, err.msg);
        _exit(ok ? 0 : 1);
    }
    int status = 0;
    GI_REQUIRE(pid > 0 && waitpid(pid, &status, 0) == pid);
    GI_CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "child status %#x%s", status,
                 WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM ? " (hung)" : "");
    gi_image_free(&img);
    free(p);
}

GI_TEST(exr_roundtrip_extra_channels_special_values)
{
    gi_error err;
    /* Deliberately unsorted, with names that sort differently from this order. */
    const char *names[] = {"R", "G", "B", "A", "var.R", "var.G", "var.B", "N.x", "albedo"};
    const int nch = (int)GI_ARRAY_LEN(names);
    const float special[] = {
        0.0f, -0.0f, 1.0f, -1.0f, 1e30f, -1e30f, FLT_MAX, -FLT_MAX, FLT_MIN,
        bitsf(0x00000001u),       /* smallest denormal */
        bitsf(0x807fffffu),       /* largest negative denormal */
        FLT_MIN / 3.0f, 3.14159265f, -2.5e-20f, INFINITY, -INFINITY,
        bitsf(0x7fc00000u),       /* quiet NaN */
        bitsf(0xffc01234u),       /* negative NaN with payload */
        bitsf(0x7f800001u),       /* signalling-NaN bit pattern */
    };
    const int ns = (int)GI_ARRAY_LEN(special);
    gi_image img, back;
    GI_REQUIRE_OK(gi_image_init(&img, 11, 6, nch, names, &err));
    size_t n = (size_t)img.width * img.height * img.channels;
    for (size_t i = 0; i < n; i++)
        img.pixels[i] = special[(i * 7 + i / 13) % (size_t)ns];
    char *p = tpath("extra.exr");
    GI_REQUIRE_OK(gi_exr_write(p, &img, &err));
    GI_REQUIRE_OK(gi_exr_read(p, &back, &err));
    GI_REQUIRE(back.channels == nch);
    /* File order is sorted by name (byte order). */
    for (int c = 1; c < back.channels; c++)
        GI_CHECK(strcmp(back.names[c - 1], back.names[c]) < 0);
    GI_CHECK(compare_by_name(&img, &back) == 0);
    GI_CHECK(compare_by_name(&back, &img) == 0);
    /* NaN payloads survive: the file is lossless. */
    int k = gi_image_channel(&back, "var.G");
    int found_nan = 0;
    for (int i = 0; i < back.width * back.height; i++)
        if (fbits(back.pixels[(size_t)i * back.channels + k]) == 0xffc01234u)
            found_nan = 1;
    GI_CHECK(found_nan);
    gi_image_free(&back);
    gi_image_free(&img);
    free(p);
}

/* Deflated size (libdeflate at GI_EXR_ZIP_LEVEL, as gi_exr) of a ZIP chunk:
 * OpenEXR reorders the bytes (even then odd) and delta-codes them before
 * deflating. */
static unsigned long zip_chunk_size(const unsigned char *packed, size_t n)
{
    unsigned char *s = malloc(n), *t1 = s, *t2 = s + (n + 1) / 2;
    for (size_t i = 0; i < n; i++)
        *(i % 2 ? t2++ : t1++) = packed[i];
    int p = s[0];
    for (size_t i = 1; i < n; i++) {
        int d = (int)s[i] - p + (128 + 256);
        p = s[i];
        s[i] = (unsigned char)d;
    }
    struct libdeflate_compressor *c = libdeflate_alloc_compressor(GI_EXR_ZIP_LEVEL);
    size_t cap = libdeflate_zlib_compress_bound(c, n);
    unsigned char *out = malloc(cap);
    unsigned long z = libdeflate_zlib_compress(c, s, n, out, cap);
    libdeflate_free_compressor(c);
    free(s);
    free(out);
    return z;
}

/* A chunk whose deflated size is exactly its raw size must be stored raw:
 * readers take a chunk as long as its raw size for raw data, so with
 * OpenEXRCore 3.1.5's compressor (which keeps such deflated bytes) it read
 * back as garbage (a quadrature image did). */
GI_TEST(exr_roundtrip_chunk_that_deflates_to_its_own_size)
{
    enum { W = 64, LINES = 16, BYTES = W * LINES * 4 };
    unsigned char packed[BYTES];
    int found = 0;
    /* The first r bytes random, the rest zero: the deflated size grows with
     * r; look for an r where it equals BYTES exactly. */
    for (uint64_t seed = 1; seed < 64 && !found; seed++) {
        uint64_t x = seed * 0x9E3779B97F4A7C15ull;
        for (size_t i = 0; i < BYTES; i++) {
            x = x * 6364136223846793005ull + 1442695040888963407ull;
            packed[i] = (unsigned char)(x >> 56);
            if (i % 4 == 3)
                packed[i] &= 0xBF; /* no NaN or infinity */
        }
        size_t lo = 0, hi = BYTES;
        unsigned char trial[BYTES];
        while (lo < hi && !found) {
            size_t r = (lo + hi) / 2;
            memcpy(trial, packed, r);
            memset(trial + r, 0, BYTES - r);
            unsigned long z = zip_chunk_size(trial, BYTES);
            if (z == BYTES) {
                memcpy(packed, trial, BYTES);
                found = 1;
            } else if (z < BYTES) {
                lo = r + 1;
            } else {
                hi = r;
            }
        }
    }
    GI_REQUIRE(found);
    gi_error err;
    gi_image a, b;
    static const char *const names[] = {"Y"};
    GI_REQUIRE_OK(gi_image_init(&a, W, 2 * LINES, 1, names, &err));
    /* Chunk 0 deflates well (a ramp); chunk 1 deflates to its own size. */
    for (int i = 0; i < W * LINES; i++)
        a.pixels[i] = (float)(i % W) / W;
    memcpy(a.pixels + W * LINES, packed, BYTES);
    char path[1024];
    snprintf(path, sizeof path, "%s/exact.exr", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_exr_write(path, &a, &err));
    GI_REQUIRE_OK(gi_exr_read(path, &b, &err));
    GI_REQUIRE(b.width == W && b.height == 2 * LINES && b.channels == 1);
    GI_CHECK_MSG(memcmp(a.pixels, b.pixels, sizeof(float) * W * 2 * LINES) == 0,
                 "the chunk came back changed");
    gi_image_free(&a);
    gi_image_free(&b);
}

GI_TEST(exr_shapes_1x1_nonsquare_multichunk)
{
    gi_error err;
    const int shapes[][3] = {{1, 1, 1}, {1, 40, 3}, {37, 3, 4}, {33, 50, 2}, {300, 17, 3}};
    for (size_t s = 0; s < GI_ARRAY_LEN(shapes); s++) {
        gi_image img, back;
        GI_REQUIRE_OK(gi_image_init(&img, shapes[s][0], shapes[s][1], shapes[s][2], NULL, &err));
        fill_pattern(&img, 99u + (uint32_t)s);
        char name[64];
        snprintf(name, sizeof name, "shape%zu.exr", s);
        char *p = tpath(name);
        GI_REQUIRE_OK(gi_exr_write(p, &img, &err));
        GI_REQUIRE_OK(gi_exr_read(p, &back, &err));
        GI_CHECK_MSG(compare_by_name(&img, &back) == 0, "shape %dx%dx%d differs", shapes[s][0],
                     shapes[s][1], shapes[s][2]);
        gi_image_free(&back);
        gi_image_free(&img);
        free(p);
    }
}

/* ---- EXR determinism ------------------------------------------------------ */

GI_TEST(exr_repeated_writes_are_byte_identical)
{
    gi_error err;
    const char *names[] = {"R", "G", "B", "var.R", "var.G", "var.B"};
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, 45, 38, 6, names, &err));
    fill_pattern(&img, 7);
    char *a = tpath("det_a.exr"), *b = tpath("det_b.exr"), *c = tpath("det_c.exr");
    /* Different fill bytes in freshly malloc'ed memory (glibc M_PERTURB;
     * ignored under ASan, which fills with its own pattern): any
     * uninitialised byte reaching the file would make the outputs differ. */
    mallopt(M_PERTURB, 0x5a);
    GI_REQUIRE_OK(gi_exr_write(a, &img, &err));
    mallopt(M_PERTURB, 0xa5);
    GI_REQUIRE_OK(gi_exr_write(b, &img, &err));
    mallopt(M_PERTURB, 0);
    GI_CHECK(files_equal(a, b));

    /* The same channels held in another order give the same file. */
    const char *perm[] = {"var.B", "G", "R", "var.R", "B", "var.G"};
    gi_image img2;
    GI_REQUIRE_OK(gi_image_init(&img2, 45, 38, 6, perm, &err));
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < img.width; x++)
            for (int ch = 0; ch < 6; ch++)
                gi_image_at(&img2, x, y)[gi_image_channel(&img2, names[ch])] =
                    gi_image_at(&img, x, y)[ch];
    GI_REQUIRE_OK(gi_exr_write(c, &img2, &err));
    GI_CHECK(files_equal(a, c));

    /* Overwriting an existing file also gives the same bytes. */
    GI_REQUIRE_OK(gi_exr_write(b, &img2, &err));
    GI_CHECK(files_equal(a, b));

    /* And a different image gives a different file (the check is not vacuous). */
    img2.pixels[17] += 1.0f;
    GI_REQUIRE_OK(gi_exr_write(c, &img2, &err));
    GI_CHECK(!files_equal(a, c));
    gi_image_free(&img2);
    gi_image_free(&img);
    free(a);
    free(b);
    free(c);
}

/* ---- EXR reading other layouts ---------------------------------------------- */

GI_TEST(exr_reads_half_and_other_compressions)
{
    gi_error err;
    const char *names[] = {"R", "G", "B"};
    /* Exact halves: 0.5, 1, 2, -3.25, 65504 (max half), 0, 2^-24 (denormal),
     * 0x3555 (nearest half to 1/3). */
    const uint16_t hv[] = {0x3800, 0x3C00, 0x4000, 0xC280, 0x7BFF, 0x0000, 0x0001, 0x3555};
    const float fv[] = {0.5f, 1.0f, 2.0f, -3.25f, 65504.0f, 0.0f, 5.9604645e-8f, 0.33325195f};
    enum { W = 9, H = 35, C = 3 };
    uint16_t half[W * H * C];
    float flt[W * H * C];
    for (int i = 0; i < W * H * C; i++) {
        half[i] = hv[i % 8];
        flt[i] = (float)(i % 977) * 0.125f - 17.0f;
    }
    const exr_compression_t comps[] = {EXR_COMPRESSION_NONE, EXR_COMPRESSION_RLE,
                                       EXR_COMPRESSION_ZIPS, EXR_COMPRESSION_ZIP,
                                       EXR_COMPRESSION_PIZ};
    for (size_t ci = 0; ci < GI_ARRAY_LEN(comps); ci++) {
        for (int t = 0; t < 2; t++) {
            exr_spec s = {.storage = EXR_STORAGE_SCANLINE, .parts = 1,
                          .type = t ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF,
                          .compression = comps[ci], .width = W, .height = H, .channels = C,
                          .names = names, .data = t ? (const void *)flt : (const void *)half};
            char name[64];
            snprintf(name, sizeof name, "core_%d_%d.exr", (int)comps[ci], t);
            char *p = tpath(name);
            int wr = write_exr_core(p, &s);
            GI_CHECK_MSG(wr == 0, "writing %s with the C API: %s", name,
                         exr_get_error_code_as_string(wr));
            gi_image back;
            if (wr == 0 && gi_exr_read(p, &back, &err) == 0) {
                GI_CHECK(back.width == W && back.height == H && back.channels == C);
                long bad = 0;
                for (int y = 0; y < H; y++)
                    for (int x = 0; x < W; x++)
                        for (int c = 0; c < C; c++) {
                            int i = (y * W + x) * C + c;
                            float want = t ? flt[i] : fv[i % 8];
                            float got = gi_image_at(&back, x, y)[gi_image_channel(&back, names[c])];
                            bad += fbits(want) != fbits(got);
                        }
                GI_CHECK_MSG(bad == 0, "%s: %ld samples differ", name, bad);
                gi_image_free(&back);
            } else if (wr == 0) {
                GI_CHECK_MSG(0, "reading %s: %s", name, err.msg);
            }
            free(p);
        }
    }
}

GI_TEST(exr_reads_offset_data_window)
{
    gi_error err;
    const char *names[] = {"Z", "Y"};
    enum { W = 6, H = 70, C = 2 };
    float data[W * H * C];
    for (int i = 0; i < W * H * C; i++)
        data[i] = (float)i * 0.5f;
    char *p = tpath("offset.exr");
    exr_spec s = {.storage = EXR_STORAGE_SCANLINE, .parts = 1, .type = EXR_PIXEL_FLOAT,
                  .compression = EXR_COMPRESSION_ZIP, .width = W, .height = H, .channels = C,
                  .names = names, .data = data, .origin_x = -3, .origin_y = 1000};
    gi_image back;
    int wr = write_exr_core(p, &s);
    GI_CHECK(wr == 0);
    if (wr != 0 || gi_exr_read(p, &back, &err) != 0) {
        GI_CHECK_MSG(0, "%s", wr ? exr_get_error_code_as_string(wr) : err.msg);
        free(p);
        return;
    }
    GI_CHECK(back.width == W && back.height == H);
    GI_CHECK(strcmp(back.names[0], "Y") == 0 && strcmp(back.names[1], "Z") == 0);
    long bad = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float *q = gi_image_at(&back, x, y);
            bad += q[0] != data[(y * W + x) * C + 1] || q[1] != data[(y * W + x) * C];
        }
    GI_CHECK(bad == 0);
    gi_image_free(&back);
    free(p);
}

GI_TEST(exr_refuses_tiled_multipart_uint)
{
    gi_error err;
    const char *names[] = {"G", "R"};
    float data[16 * 10 * 2] = {0};
    gi_image out;
    struct {
        exr_storage_t storage;
        int parts;
        exr_pixel_type_t type;
        const char *expect;
    } cases[] = {
        {EXR_STORAGE_TILED, 1, EXR_PIXEL_FLOAT, "tiled"},
        {EXR_STORAGE_SCANLINE, 2, EXR_PIXEL_FLOAT, "multi-part"},
        {EXR_STORAGE_SCANLINE, 1, EXR_PIXEL_UINT, "UINT"},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(cases); i++) {
        char name[32];
        snprintf(name, sizeof name, "refuse%zu.exr", i);
        char *p = tpath(name);
        exr_spec s = {.storage = cases[i].storage, .parts = cases[i].parts,
                      .type = cases[i].type, .compression = EXR_COMPRESSION_ZIP, .width = 16,
                      .height = 10, .channels = 2, .names = names, .data = data};
        int wr = write_exr_core(p, &s);
        GI_CHECK_MSG(wr == 0, "writing %s: %s", name, exr_get_error_code_as_string(wr));
        if (wr == 0) {
            GI_CHECK(gi_exr_read(p, &out, &err) == -1);
            GI_CHECK(err.code == GI_EINVAL);
            GI_CHECK_MSG(strstr(err.msg, cases[i].expect) && strstr(err.msg, p),
                         "message \"%s\" should name the file and say %s", err.msg,
                         cases[i].expect);
            GI_CHECK(out.pixels == NULL);
        }
        free(p);
    }
}

/* ---- EXR bad input ------------------------------------------------------- */

/* Plain write (no fsync: thousands of scratch files). */
static int put_file(const char *path, const void *bytes, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = fwrite(bytes, 1, len, f) == len;
    return fclose(f) == 0 && ok ? 0 : -1;
}

static int try_read(const char *path, const void *bytes, size_t len, gi_error *err)
{
    if (put_file(path, bytes, len) != 0)
        return -2;
    gi_image out;
    int rc = gi_exr_read(path, &out, err);
    if (rc == 0)
        gi_image_free(&out);
    else if (out.pixels != NULL)
        return -3; /* a failed read must leave the image empty */
    return rc;
}

GI_TEST(exr_read_garbage_fails_cleanly)
{
    gi_error err;
    gi_image out;
    char *p = tpath("garbage.exr");
    GI_CHECK(gi_exr_read(p, &out, &err) == -1 && err.code == GI_EINVAL); /* missing */
    GI_CHECK(strstr(err.msg, p) != NULL);
    GI_CHECK(try_read(p, "", 0, &err) == -1);
    GI_CHECK(strstr(err.msg, p) != NULL);
    const char text[] = "this is not an EXR file at all, just some text\n";
    GI_CHECK(try_read(p, text, sizeof text - 1, &err) == -1);
    const unsigned char magic_only[] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0};
    GI_CHECK(try_read(p, magic_only, sizeof magic_only, &err) == -1);
    uint8_t noise[4096];
    uint32_t seed = 4242;
    for (size_t i = 0; i < sizeof noise; i++)
        noise[i] = (uint8_t)rng_next(&seed);
    memcpy(noise, magic_only, sizeof magic_only);
    GI_CHECK(try_read(p, noise, sizeof noise, &err) == -1);
    char *dir = tdir("a_directory.exr");
    GI_CHECK(gi_exr_read(dir, &out, &err) == -1);
    free(dir);
    free(p);
}

/* Overwrites the dataWindow box of an EXR file in memory. */
static int patch_data_window(gi_buf *file, int32_t maxx, int32_t maxy)
{
    static const char key[] = "dataWindow\0box2i\0";
    for (size_t i = 0; i + sizeof key + 4 + 16 <= file->len; i++) {
        if (memcmp(file->data + i, key, sizeof key - 1) == 0) {
            uint8_t *box = file->data + i + (sizeof key - 1) + 4; /* after the size field */
            gi_le_put_u32(box + 8, (uint32_t)maxx);
            gi_le_put_u32(box + 12, (uint32_t)maxy);
            return 0;
        }
    }
    return -1;
}

GI_TEST(exr_read_checks_data_window_before_allocating)
{
    gi_error err;
    gi_image img, out;
    GI_REQUIRE_OK(gi_image_init(&img, 4, 4, 4, NULL, &err));
    char *p = tpath("window.exr"), *q = tpath("window_patched.exr");
    GI_REQUIRE_OK(gi_exr_write(p, &img, &err));
    gi_image_free(&img);
    gi_buf file;
    gi_buf_init(&file);
    GI_REQUIRE_OK(gi_read_file(p, 1 << 20, &file, &err));
    /* 65536 x 65536 x 4 floats = 64 GiB: each side is allowed, the total is not. */
    GI_REQUIRE(patch_data_window(&file, 65535, 65535) == 0);
    GI_REQUIRE(put_file(q, file.data, file.len) == 0);
    GI_CHECK(gi_exr_read(q, &out, &err) == -1 && out.pixels == NULL);
    GI_CHECK_MSG(err.code == GI_ENOMEM && strstr(err.msg, "limit") && strstr(err.msg, q),
                 "%s", err.msg);
    /* Over the per-side limit. */
    GI_REQUIRE(patch_data_window(&file, 3, 70000) == 0);
    GI_REQUIRE(put_file(q, file.data, file.len) == 0);
    GI_CHECK(gi_exr_read(q, &out, &err) == -1 && out.pixels == NULL);
    GI_CHECK_MSG(err.code == GI_EINVAL && strstr(err.msg, q), "%s", err.msg);
    /* Inverted window. */
    GI_REQUIRE(patch_data_window(&file, -5, 3) == 0);
    GI_REQUIRE(put_file(q, file.data, file.len) == 0);
    GI_CHECK(gi_exr_read(q, &out, &err) == -1 && out.pixels == NULL);
    GI_CHECK_MSG(err.code == GI_EINVAL && strstr(err.msg, q), "%s", err.msg);
    gi_buf_free(&file);
    free(p);
    free(q);
}

/* Truncates a valid file at every length and flips every byte (and some
 * random multi-byte damage): each read must fail with a message or succeed,
 * never crash or leak (run under ASan by `make test`). */
static void corrupt_all_ways(const char *src, const char *scratch)
{
    gi_error err;
    gi_buf file;
    gi_buf_init(&file);
    if (gi_read_file(src, 1 << 24, &file, &err) != 0) {
        GI_CHECK_MSG(0, "%s", err.msg);
        return;
    }
    uint8_t *copy = malloc(file.len);
    for (size_t len = 0; len < file.len; len++) {
        int rc = try_read(scratch, file.data, len, &err);
        GI_CHECK_MSG(rc == -1, "truncated at %zu of %zu bytes: rc %d", len, file.len, rc);
        if (rc == -1)
            GI_CHECK_MSG(strstr(err.msg, scratch) != NULL, "message does not name the file: %s",
                         err.msg);
    }
    long failed = 0, ok = 0;
    for (size_t i = 0; i < file.len; i++) {
        for (int v = 0; v < 2; v++) {
            memcpy(copy, file.data, file.len);
            copy[i] ^= v ? 0xff : 0x01;
            int rc = try_read(scratch, copy, file.len, &err);
            GI_CHECK_MSG(rc == 0 || rc == -1, "flip at %zu: rc %d", i, rc);
            rc ? failed++ : ok++;
        }
    }
    uint32_t seed = 777;
    for (int t = 0; t < 300; t++) {
        memcpy(copy, file.data, file.len);
        int n = 1 + (int)(rng_next(&seed) % 8);
        for (int j = 0; j < n; j++)
            copy[rng_next(&seed) % file.len] = (uint8_t)rng_next(&seed);
        int rc = try_read(scratch, copy, file.len, &err);
        GI_CHECK_MSG(rc == 0 || rc == -1, "random damage %d: rc %d", t, rc);
    }
    /* Flips in raw pixel data or in attributes we ignore can read fine; ones
     * in the magic, the channel list, offsets and compressed streams cannot. */
    GI_CHECK_MSG(failed > 0 && ok > 0, "%ld of %ld flipped files refused", failed, failed + ok);
    free(copy);
    gi_buf_free(&file);
}

GI_TEST(exr_read_truncated_and_flipped_fails_cleanly)
{
    gi_error err;
    const char *names[] = {"R", "G", "B", "var.R"};
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, 13, 21, 4, names, &err));
    /* Smooth values, so that zlib really compresses both chunks (an
     * incompressible chunk is stored raw). */
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < img.width; x++)
            for (int c = 0; c < img.channels; c++)
                gi_image_at(&img, x, y)[c] = (float)(x / 4) * 0.5f + (float)c;
    char *p = tpath("valid.exr"), *q = tpath("damaged.exr");
    GI_REQUIRE_OK(gi_exr_write(p, &img, &err));
    struct stat st;
    GI_REQUIRE(stat(p, &st) == 0);
    GI_CHECK_MSG((size_t)st.st_size < 13 * 21 * 4 * sizeof(float) / 2,
                 "%lld bytes: chunks are not compressed", (long long)st.st_size);
    corrupt_all_ways(p, q);
    gi_image_free(&img);
    free(p);
    free(q);
}

GI_TEST(exr_read_damaged_other_compressions_fails_cleanly)
{
    /* The decompressors we do not write ourselves (PIZ's Huffman/wavelet,
     * RLE, HALF conversion) get the same treatment. */
    const char *names[] = {"B", "G", "R"};
    enum { W = 10, H = 9, C = 3 };
    uint16_t half[W * H * C];
    uint32_t seed = 5;
    for (int i = 0; i < W * H * C; i++)
        half[i] = (uint16_t)(0x3000 + rng_next(&seed) % 0x1000);
    const exr_compression_t comps[] = {EXR_COMPRESSION_RLE, EXR_COMPRESSION_PIZ};
    for (size_t i = 0; i < GI_ARRAY_LEN(comps); i++) {
        char *p = tpath("other_valid.exr"), *q = tpath("other_damaged.exr");
        exr_spec s = {.storage = EXR_STORAGE_SCANLINE, .parts = 1, .type = EXR_PIXEL_HALF,
                      .compression = comps[i], .width = W, .height = H, .channels = C,
                      .names = names, .data = half};
        GI_CHECK(write_exr_core(p, &s) == 0);
        corrupt_all_ways(p, q);
        free(p);
        free(q);
    }
}

/* ---- atomic writes ---------------------------------------------------------- */

GI_TEST(image_writes_are_atomic)
{
    gi_error err;
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, 8, 4, 3, NULL, &err));
    fill_pattern(&img, 1);
    char *dir = tdir("atomic");
    char *exr = gi_path_join(dir, "out.exr"), *png = gi_path_join(dir, "out.png");
    GI_REQUIRE_OK(gi_exr_write(exr, &img, &err));
    GI_REQUIRE_OK(gi_png_write(png, &img, 0.0, &err));
    GI_REQUIRE_OK(gi_exr_write(exr, &img, &err)); /* overwrite */
    GI_CHECK(count_entries(dir, "") == 2);
    GI_CHECK(count_entries(dir, ".tmp") == 0);

    /* Missing directory: error naming the path, nothing created. */
    char *missing = gi_path_join(dir, "no/such/dir/out.exr");
    GI_CHECK(gi_exr_write(missing, &img, &err) == -1 && err.code == GI_EIO);
    GI_CHECK(strstr(err.msg, missing) != NULL);
    GI_CHECK(gi_png_write(missing, &img, 0.0, &err) == -1 && err.code == GI_EIO);
    GI_CHECK(!file_exists(missing));

    /* The final rename fails (the target is a directory): the temp file is
     * removed and the target is untouched. */
    char *blocked = gi_path_join(dir, "blocked");
    mkdir(blocked, 0755);
    GI_CHECK(gi_exr_write(blocked, &img, &err) == -1);
    GI_CHECK(gi_png_write(blocked, &img, 0.0, &err) == -1);
    struct stat st;
    GI_CHECK(stat(blocked, &st) == 0 && S_ISDIR(st.st_mode));
    GI_CHECK(count_entries(dir, ".tmp") == 0);
    GI_CHECK(count_entries(dir, "") == 3);

    /* Invalid images are refused before anything is created. */
    gi_image empty = {0};
    char *never = gi_path_join(dir, "never.exr");
    GI_CHECK(gi_exr_write(never, &empty, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(gi_png_write(never, &empty, 0.0, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(gi_png_write(never, &img, NAN, &err) == -1 && err.code == GI_EINVAL);
    GI_CHECK(!file_exists(never));
    GI_CHECK(count_entries(dir, "") == 3);

    gi_image_free(&img);
    free(never);
    free(blocked);
    free(missing);
    free(exr);
    free(png);
    free(dir);
}

/* ---- PNG ----------------------------------------------------------------- */

GI_TEST(png_srgb_transfer_exact)
{
    /* Expected codes from s = 12.92 v (v <= 0.0031308) else 1.055 v^(1/2.4) - 0.055,
     * round(255 s), computed independently in double precision. */
    GI_CHECK(gi_srgb8_from_linear(0.0) == 0);
    GI_CHECK(gi_srgb8_from_linear(0.0001) == 0);   /* 0.329 */
    GI_CHECK(gi_srgb8_from_linear(0.001) == 3);    /* 3.295 */
    GI_CHECK(gi_srgb8_from_linear(0.0031308) == 10); /* 10.315: end of the linear segment */
    GI_CHECK(gi_srgb8_from_linear(0.01) == 25);    /* 25.462 */
    GI_CHECK(gi_srgb8_from_linear(0.18) == 118);   /* 117.646 */
    GI_CHECK(gi_srgb8_from_linear(0.25) == 137);   /* 136.960 */
    GI_CHECK(gi_srgb8_from_linear(0.5) == 188);    /* 187.516 */
    GI_CHECK(gi_srgb8_from_linear(0.9) == 243);    /* 243.445 */
    GI_CHECK(gi_srgb8_from_linear(1.0) == 255);
    GI_CHECK(gi_srgb8_from_linear(1e30) == 255);
    GI_CHECK(gi_srgb8_from_linear(INFINITY) == 255);
    GI_CHECK(gi_srgb8_from_linear(-0.5) == 0);
    GI_CHECK(gi_srgb8_from_linear(-INFINITY) == 0);
    GI_CHECK(gi_srgb8_from_linear(NAN) == 0);
    /* Monotone over the whole range, and the two segments meet without a jump. */
    int prev = 0, mono = 1;
    for (int i = 0; i <= 100000; i++) {
        int v = gi_srgb8_from_linear(i / 100000.0);
        mono &= v >= prev;
        prev = v;
    }
    GI_CHECK(mono && prev == 255);
}

/* The sRGB formula, as the test computes it. */
static int srgb8_reference(double v)
{
    if (!(v > 0.0))
        return 0;
    if (v >= 1.0)
        return 255;
    double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (int)floor(s * 255.0 + 0.5);
}

/* gi_srgb8_from_linear looks codes up among thresholds instead of calling
 * pow: it must agree with the formula everywhere, in particular on both
 * sides of every code's boundary (found here by bisection over doubles)
 * and on a million values spread over the range in log scale. */
GI_TEST(png_srgb_lookup_matches_the_formula)
{
    size_t wrong = 0;
    for (int k = 1; k < 256; k++) {
        double lo = 0.0, hi = 1.0;
        for (int i = 0; i < 200 && nextafter(lo, 2.0) < hi; i++) {
            double mid = 0.5 * (lo + hi);
            if (mid <= lo || mid >= hi)
                break;
            *(srgb8_reference(mid) >= k ? &hi : &lo) = mid;
        }
        double at[4] = {nextafter(lo, 0.0), lo, hi, nextafter(hi, 2.0)};
        for (int j = 0; j < 4; j++)
            wrong += gi_srgb8_from_linear(at[j]) != srgb8_reference(at[j]);
    }
    uint64_t x = 12345;
    for (int i = 0; i < 1000000; i++) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        double v = pow(10.0, -8.0 + 8.5 * (double)(x >> 11) / 9007199254740992.0);
        wrong += gi_srgb8_from_linear(v) != srgb8_reference(v);
    }
    GI_CHECK_MSG(wrong == 0, "%zu values encode otherwise than the formula", wrong);
}

GI_TEST(png_roundtrip_known_values_and_exposure)
{
    gi_error err;
    const float vals[] = {0.5f, 0.0031308f, 0.18f, 1.0f, 2.0f, -1.0f, NAN, 0.0f, 0.25f, 0.01f};
    const unsigned char want[] = {188, 10, 118, 255, 255, 0, 0, 0, 137, 25};
    const int n = (int)GI_ARRAY_LEN(vals);
    /* Channels named so that R,G,B are not the first three. */
    const char *names[] = {"var.R", "B", "G", "R"};
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, n, 3, 4, names, &err));
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < n; x++) {
            float *px = gi_image_at(&img, x, y);
            px[0] = 0.5f;        /* var.R: must not be shown */
            px[3] = vals[x];     /* R */
            px[2] = vals[(x + y) % n]; /* G */
            px[1] = vals[(x + 2 * y) % n]; /* B */
        }
    char *p = tpath("known.png");
    GI_REQUIRE_OK(gi_png_write(p, &img, 0.0, &err));
    int w, h;
    unsigned char *rgb = NULL;
    GI_REQUIRE_OK(gi_png_read(p, &w, &h, &rgb, &err));
    GI_REQUIRE(w == n && h == 3);
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < n; x++) {
            const unsigned char *q = rgb + ((size_t)y * w + x) * 3;
            GI_CHECK_MSG(q[0] == want[x] && q[1] == want[(x + y) % n] &&
                             q[2] == want[(x + 2 * y) % n],
                         "pixel (%d,%d) = %d,%d,%d", x, y, q[0], q[1], q[2]);
        }
    free(rgb);

    /* +1 stop doubles: 0.25 -> 0.5 -> 188, 0.5 -> 1.0 -> 255. */
    GI_REQUIRE_OK(gi_png_write(p, &img, 1.0, &err));
    GI_REQUIRE_OK(gi_png_read(p, &w, &h, &rgb, &err));
    GI_CHECK(rgb[8 * 3] == 188); /* x = 8 holds R = 0.25 */
    GI_CHECK(rgb[0] == 255);     /* x = 0 holds R = 0.5 */
    free(rgb);
    /* -1 stop halves: 1.0 -> 0.5 -> 188. */
    GI_REQUIRE_OK(gi_png_write(p, &img, -1.0, &err));
    GI_REQUIRE_OK(gi_png_read(p, &w, &h, &rgb, &err));
    GI_CHECK(rgb[3 * 3] == 188); /* x = 3 holds R = 1.0 */
    free(rgb);

    /* Same image, same bytes. */
    char *p2 = tpath("known2.png");
    GI_REQUIRE_OK(gi_png_write(p2, &img, -1.0, &err));
    GI_CHECK(files_equal(p, p2));
    gi_image_free(&img);
    free(p);
    free(p2);
}

GI_TEST(png_channel_selection_grey_and_first_three)
{
    gi_error err;
    gi_image img;
    int w, h;
    unsigned char *rgb = NULL;
    char *p = tpath("sel.png");

    /* One channel: grey. */
    GI_REQUIRE_OK(gi_image_init(&img, 2, 1, 1, NULL, &err));
    img.pixels[0] = 0.5f;
    img.pixels[1] = 0.01f;
    GI_REQUIRE_OK(gi_png_write(p, &img, 0.0, &err));
    gi_image_free(&img);
    GI_REQUIRE_OK(gi_png_read(p, &w, &h, &rgb, &err));
    GI_CHECK(w == 2 && h == 1);
    GI_CHECK(rgb[0] == 188 && rgb[1] == 188 && rgb[2] == 188);
    GI_CHECK(rgb[3] == 25 && rgb[4] == 25 && rgb[5] == 25);
    free(rgb);

    /* No R,G,B names: the first three channels. */
    const char *xyz[] = {"X", "Y", "Z", "W"};
    GI_REQUIRE_OK(gi_image_init(&img, 1, 1, 4, xyz, &err));
    img.pixels[0] = 0.5f, img.pixels[1] = 0.18f, img.pixels[2] = 0.01f, img.pixels[3] = 1.0f;
    GI_REQUIRE_OK(gi_png_write(p, &img, 0.0, &err));
    gi_image_free(&img);
    GI_REQUIRE_OK(gi_png_read(p, &w, &h, &rgb, &err));
    GI_CHECK(rgb[0] == 188 && rgb[1] == 118 && rgb[2] == 25);
    free(rgb);
    free(p);
}

GI_TEST(png_read_garbage_fails_cleanly)
{
    gi_error err;
    int w = 1, h = 1;
    unsigned char *rgb = (unsigned char *)"x";
    char *p = tpath("garbage.png");
    GI_CHECK(gi_png_read(p, &w, &h, &rgb, &err) == -1 && rgb == NULL);
    GI_CHECK(strstr(err.msg, p) != NULL);
    GI_REQUIRE_OK(gi_write_file_atomic(p, "not a png", 9, &err));
    GI_CHECK(gi_png_read(p, &w, &h, &rgb, &err) == -1 && rgb == NULL);
    GI_CHECK(strstr(err.msg, p) != NULL);

    /* A valid PNG truncated at every length, and with flipped bytes. */
    gi_image img;
    GI_REQUIRE_OK(gi_image_init(&img, 9, 7, 3, NULL, &err));
    fill_pattern(&img, 3);
    char *v = tpath("valid.png");
    GI_REQUIRE_OK(gi_png_write(v, &img, 0.0, &err));
    gi_image_free(&img);
    gi_buf file;
    gi_buf_init(&file);
    GI_REQUIRE_OK(gi_read_file(v, 1 << 20, &file, &err));
    for (size_t len = 0; len < file.len; len++) {
        GI_REQUIRE(put_file(p, file.data, len) == 0);
        int rc = gi_png_read(p, &w, &h, &rgb, &err);
        GI_CHECK_MSG(rc == -1 && rgb == NULL, "truncated PNG at %zu read", len);
        free(rgb);
    }
    for (size_t i = 0; i < file.len; i++) {
        file.data[i] ^= 0x10;
        GI_REQUIRE(put_file(p, file.data, file.len) == 0);
        int rc = gi_png_read(p, &w, &h, &rgb, &err);
        GI_CHECK(rc == 0 || (rc == -1 && rgb == NULL));
        free(rgb);
        file.data[i] ^= 0x10;
    }
    gi_buf_free(&file);
    free(v);
    free(p);
}
