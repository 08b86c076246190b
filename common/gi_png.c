/* gi_png: 8-bit sRGB PNG previews through libpng, and a reader for tests.
 *
 * libpng reports errors by longjmp from its error callback. Our callbacks
 * copy the message into a png_msg and jump back to the setjmp in the caller;
 * everything the error path touches is either set before setjmp and never
 * changed afterwards, or declared volatile (C11 7.13.2.1: non-volatile locals
 * changed after setjmp are indeterminate after the longjmp). */
#include "gi_image.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

#include "gi_fs.h"
#include "gi_log.h"

typedef struct png_msg {
    const char *path;
    gi_errcode code; /* GI_EINVAL unless set before png_error() */
    char text[256];
} png_msg;

static void png_on_error(png_structp png, png_const_charp msg)
{
    png_msg *m = png_get_error_ptr(png);
    snprintf(m->text, sizeof m->text, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

static void png_on_warning(png_structp png, png_const_charp msg)
{
    png_msg *m = png_get_error_ptr(png);
    gi_debug("%s: libpng warning: %s", m->path, msg ? msg : "");
}

/* IEC 61966-2-1 sRGB encoding (linear -> non-linear) of v in (0, 1), to 8
 * bits. */
static unsigned char srgb8_formula(double v)
{
    double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (unsigned char)floor(s * 255.0 + 0.5);
}

static double as_double(uint64_t bits)
{
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

/* threshold[k], k = 1..255: the least double v with srgb8_formula(v) >= k
 * (positive doubles order as their bits do); threshold[256] stops the
 * search. first[b]: the code of b / BUCKETS, where a search for v in
 * [b / BUCKETS, (b + 1) / BUCKETS) starts (a bucket holds at most a couple
 * of thresholds). A PNG converts millions of values: this is exact and
 * several times cheaper than pow. */
#define BUCKETS 4096
static double threshold[257];
static unsigned char first[BUCKETS];
static pthread_once_t thresholds_once = PTHREAD_ONCE_INIT;

static void thresholds_init(void)
{
    uint64_t one;
    double d = 1.0;
    memcpy(&one, &d, sizeof one);
    for (int k = 1; k < 256; k++) {
        uint64_t lo = 0, hi = one; /* formula(lo) < k <= formula(hi) */
        while (hi - lo > 1) {
            uint64_t mid = lo + (hi - lo) / 2;
            if (srgb8_formula(as_double(mid)) >= k)
                hi = mid;
            else
                lo = mid;
        }
        threshold[k] = as_double(hi);
    }
    threshold[256] = INFINITY;
    int k = 0;
    for (int b = 0; b < BUCKETS; b++) {
        double v = (double)b / BUCKETS;
        while (threshold[k + 1] <= v)
            k++;
        first[b] = (unsigned char)k;
    }
}

unsigned char gi_srgb8_from_linear(double v)
{
    if (!(v > 0.0)) /* NaN and negatives */
        return 0;
    if (v >= 1.0)
        return 255;
    pthread_once(&thresholds_once, thresholds_init); /* PNGs are written on threads */
    int k = first[(int)(v * BUCKETS)];
    while (threshold[k + 1] <= v)
        k++;
    return (unsigned char)k;
}

/* ---- writing ---------------------------------------------------------- */

/* The whole libpng part of a write, so that setjmp sits in a function whose
 * locals are all fixed before it. */
static int png_encode(FILE *fp, png_msg *m, const gi_image *img, const int src[3], int grey,
                      double scale, unsigned char *row)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, m, png_on_error,
                                              png_on_warning);
    if (!png) {
        snprintf(m->text, sizeof m->text, "cannot create the libpng write struct");
        m->code = GI_ENOMEM;
        return -1;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, NULL);
        snprintf(m->text, sizeof m->text, "cannot create the libpng info struct");
        m->code = GI_ENOMEM;
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)img->width, (png_uint_32)img->height, 8,
                 grey ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* sRGB + matching gAMA/cHRM chunks, so viewers do not re-gamma. No tIME
     * chunk: the same image gives the same file. */
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    /* A preview written every frame of an animation: deflate level 1 and
     * the Up filter alone, 3x faster than libpng's defaults (level 6, every
     * filter tried per row) for files ~40% larger (bench/image_write: a
     * 1080p frame 0.32 -> 0.10 s, 0.50 -> 0.69 MB). */
    png_set_compression_level(png, 1);
    png_set_filter(png, 0, PNG_FILTER_UP);
    png_write_info(png, info);
    const int n = grey ? 1 : 3;
    for (int y = 0; y < img->height; y++) {
        for (int x = 0; x < img->width; x++) {
            const float *p = gi_image_at(img, x, y);
            for (int c = 0; c < n; c++)
                row[(size_t)x * (size_t)n + (size_t)c] =
                    gi_srgb8_from_linear((double)p[src[c]] * scale);
        }
        png_write_row(png, row);
    }
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return 0;
}

int gi_png_write(const char *path, const gi_image *img, double exposure_stops, gi_error *err)
{
    if (!img || !img->pixels || img->width < 1 || img->height < 1 || img->channels < 1 ||
        img->channels > GI_IMAGE_MAX_CHANNELS)
        return gi_fail(err, GI_EINVAL, "%s: PNG write: empty or invalid image", path);
    if (!isfinite(exposure_stops))
        return gi_fail(err, GI_EINVAL, "%s: PNG write: exposure %g stops is not finite", path,
                       exposure_stops);
    int src[3], grey = 0;
    int r = gi_image_channel(img, "R"), g = gi_image_channel(img, "G"),
        b = gi_image_channel(img, "B");
    if (r >= 0 && g >= 0 && b >= 0) {
        src[0] = r, src[1] = g, src[2] = b;
    } else if (img->channels >= 3) {
        src[0] = 0, src[1] = 1, src[2] = 2;
    } else {
        src[0] = src[1] = src[2] = 0;
        grey = 1;
    }
    double scale = exp2(exposure_stops);

    unsigned char *row = gi_try_malloc((size_t)img->width * 3, err, "PNG row");
    if (!row)
        return gi_error_prefix(err, "%s", path);
    char *tmp = gi_temp_path(path);
    FILE *fp = fopen(tmp, "wbxe"); /* x: O_EXCL, e: O_CLOEXEC (glibc) */
    if (!fp) {
        int e = errno;
        free(tmp);
        free(row);
        return gi_fail(err, GI_EIO, "%s: cannot create temporary file: %s", path, strerror(e));
    }
    png_msg m = {.path = path, .code = GI_EINVAL};
    int rc = png_encode(fp, &m, img, src, grey, scale, row);
    free(row);
    if (rc != 0) {
        /* Our own pixels cannot be invalid, so a libpng failure while writing
         * is an I/O problem (or out of memory when m.code says so). */
        gi_fail(err, m.code == GI_ENOMEM ? GI_ENOMEM : GI_EIO, "%s: PNG write: %s", path, m.text);
        fclose(fp);
    } else if (fflush(fp) != 0 || ferror(fp)) {
        rc = gi_fail(err, GI_EIO, "%s: PNG write: %s", path, strerror(errno));
        fclose(fp);
    } else if (fclose(fp) != 0) {
        rc = gi_fail(err, GI_EIO, "%s: PNG close: %s", path, strerror(errno));
    }
    rc = gi_temp_finish(tmp, path, rc, err);
    free(tmp);
    return rc;
}

/* ---- reading ---------------------------------------------------------- */

static int png_decode(FILE *fp, png_msg *m, int *width, int *height, unsigned char **rgb8)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, m, png_on_error,
                                             png_on_warning);
    if (!png) {
        snprintf(m->text, sizeof m->text, "cannot create the libpng read struct");
        m->code = GI_ENOMEM;
        return -1;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_read_struct(&png, NULL, NULL);
        snprintf(m->text, sizeof m->text, "cannot create the libpng info struct");
        m->code = GI_ENOMEM;
        return -1;
    }
    /* Allocated after setjmp and freed on the error path: volatile. */
    unsigned char *volatile pixels = NULL;
    png_bytep *volatile rows = NULL;
    if (setjmp(png_jmpbuf(png))) {
        free(pixels);
        free(rows);
        png_destroy_read_struct(&png, &info, NULL);
        return -1;
    }
    png_init_io(png, fp);
    png_set_user_limits(png, GI_IMAGE_MAX_SIDE, GI_IMAGE_MAX_SIDE);
    png_read_info(png, info);
    png_uint_32 w = 0, h = 0;
    int depth = 0, ctype = 0;
    png_get_IHDR(png, info, &w, &h, &depth, &ctype, NULL, NULL, NULL);
    /* Everything becomes 8-bit RGB: palette and low-depth grey expanded,
     * 16-bit reduced, alpha dropped, grey replicated. */
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_strip_alpha(png);
    if (!(ctype & PNG_COLOR_MASK_COLOR))
        png_set_gray_to_rgb(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    if (png_get_rowbytes(png, info) != (size_t)w * 3)
        png_error(png, "unexpected row size after conversion to 8-bit RGB");
    if ((uint64_t)w * h * 3 > GI_IMAGE_MAX_BYTES) {
        m->code = GI_ENOMEM;
        png_error(png, "image is over the size limit");
    }
    pixels = malloc((size_t)w * h * 3);
    rows = malloc((size_t)h * sizeof(png_bytep));
    if (!pixels || !rows) {
        m->code = GI_ENOMEM;
        png_error(png, "out of memory");
    }
    for (png_uint_32 y = 0; y < h; y++)
        rows[y] = pixels + (size_t)y * w * 3;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    png_destroy_read_struct(&png, &info, NULL);
    free(rows);
    *width = (int)w;
    *height = (int)h;
    *rgb8 = pixels;
    return 0;
}

int gi_png_read(const char *path, int *width, int *height, unsigned char **rgb8, gi_error *err)
{
    *rgb8 = NULL;
    *width = *height = 0;
    int fd = gi_open_regular(path, O_RDONLY, NULL, err);
    if (fd < 0)
        return -1;
    FILE *fp = fdopen(fd, "rb");
    if (!fp) {
        close(fd);
        return gi_fail(err, GI_EIO, "%s: %s", path, strerror(errno));
    }
    png_msg m = {.path = path, .code = GI_EINVAL};
    int rc = png_decode(fp, &m, width, height, rgb8);
    fclose(fp);
    if (rc != 0)
        return gi_fail(err, m.code, "%s: PNG read: %s", path, m.text);
    return 0;
}
