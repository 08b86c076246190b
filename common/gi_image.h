/* gi_image: a float image with named channels, and its file formats.
 *
 * Every output image of the farm is a gi_image: linear radiance (and extra
 * channels such as per-pixel variance "var.R") as 32-bit floats, channels
 * interleaved per pixel, rows top to bottom. Files:
 *   - EXR (gi_exr.c, OpenEXR's C API): the lossless output. Single-part
 *     scanline, FLOAT channels, ZIP compression. The same image always gives
 *     byte-identical files, so determinism tests can `cmp` outputs.
 *   - PNG (gi_png.c, libpng): an 8-bit sRGB preview.
 * Writers go through gi_temp_path + gi_commit_file: a failed write never
 * leaves a partial file under the final name. */
#ifndef GI_IMAGE_H
#define GI_IMAGE_H

#include <stddef.h>

#include "gi_error.h"

#define GI_IMAGE_MAX_CHANNELS 16
#define GI_IMAGE_MAX_SIDE 65536
/* Limit on width * height * channels * sizeof(float): bounds what a file
 * header (or a job) can make us allocate. */
#define GI_IMAGE_MAX_BYTES ((size_t)4 << 30)
/* Channel names are stored in a char[32]; EXR without long names allows 31. */
#define GI_IMAGE_NAME_MAX 31

typedef struct gi_image {
    int width, height, channels;
    char names[GI_IMAGE_MAX_CHANNELS][32]; /* channel names, e.g. "R","G","B","A","var.R" */
    float *pixels;                         /* channels interleaved per pixel, rows top to bottom */
} gi_image;

/* Allocates a zeroed width x height image. `names` has `channels` entries
 * (non-empty, at most 31 bytes, distinct); NULL gives "Y" for one channel,
 * else "R","G","B","A" then "c4","c5",... Bad sizes or names -> GI_EINVAL;
 * over GI_IMAGE_MAX_BYTES or out of memory -> GI_ENOMEM. On failure *img is
 * left empty (safe to gi_image_free). */
int gi_image_init(gi_image *img, int width, int height, int channels,
                  const char *const *names, gi_error *err);
/* Frees the pixels and empties the struct; safe on an empty or freed image. */
void gi_image_free(gi_image *img);
/* Index of the channel called `name`, or -1. */
int gi_image_channel(const gi_image *img, const char *name);

/* 0 if every value of img is finite; else fails (GI_EINTERNAL, prefixed
 * with `what`, an output's path) naming the first pixel and channel that
 * is not. A job's image outputs are checked with it before anything is
 * written (gi_outputs.c, radiosity's images): they never hold Inf or NaN.
 * The methods' checks keep non-finite values out of their sums and bound
 * them so that none arises (e.g. quad_farm.h's gi_quad_pixel_delta_max),
 * so one found here is a bug: the job fails naming the file (a frame's,
 * for an animation) and the pixel, rather than write it clamped, or as
 * Inf or NaN, which compositing would spread. (The writers themselves
 * keep what they are given: gi_exr_write stores Inf and NaN as EXR can.) */
int gi_image_check_finite(const gi_image *img, const char *what, gi_error *err);

/* Pixel (x, y)'s first channel; the other channels follow it. */
static inline float *gi_image_at(const gi_image *img, int x, int y)
{
    return img->pixels + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
}

/* Writes a single-part scanline EXR: FLOAT channels sorted by name (as EXR
 * requires; the image may hold them in any order), ZIP compression
 * (libdeflate at GI_EXR_ZIP_LEVEL), INCREASING_Y, data window = display
 * window = (0,0)-(w-1,h-1). */
/* Fixed, so the bytes do not depend on any library's default. Level 1:
 * radiance floats deflate to within 0.02% of level 6's size, 20% sooner
 * (bench/image_write). */
#define GI_EXR_ZIP_LEVEL 1
int gi_exr_write(const char *path, const gi_image *img, gi_error *err);
/* Reads a single-part scanline EXR with HALF or FLOAT channels (converted to
 * float), any compression. Channels come back in the file's order (sorted
 * by name) with their names; the data window's origin is dropped. Tiled,
 * deep, multi-part, subsampled or UINT files are refused (GI_EINVAL), as are
 * truncated or corrupt ones. `out` is initialised by the call (freed by the
 * caller with gi_image_free, also empty after a failure). */
int gi_exr_read(const char *path, gi_image *out, gi_error *err);

/* Writes an 8-bit RGB PNG preview: channels R,G,B if the image has all three,
 * else its first three, else (one or two channels) channel 0 as grey; each
 * value is scaled by 2^exposure_stops, encoded with the sRGB transfer
 * function and rounded to nearest (NaN and negatives -> 0, >= 1 -> 255). */
int gi_png_write(const char *path, const gi_image *img, double exposure_stops, gi_error *err);
/* Reads a PNG (any bit depth / colour type; alpha dropped, grey expanded,
 * 16-bit reduced) into malloc'ed 8-bit RGB rows, top to bottom. For tests
 * and tools. */
int gi_png_read(const char *path, int *width, int *height, unsigned char **rgb8, gi_error *err);

/* The 8-bit sRGB code of a linear value (what gi_png_write stores):
 * IEC 61966-2-1, s = 12.92 v for v <= 0.0031308, else 1.055 v^(1/2.4) - 0.055. */
unsigned char gi_srgb8_from_linear(double v);

#endif
