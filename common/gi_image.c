/* gi_image: the float image struct (allocation, channel names, lookup).
 * File formats live in gi_exr.c and gi_png.c. */
#include "gi_image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void default_name(int channels, int i, char out[32])
{
    static const char *const rgba[] = {"R", "G", "B", "A"};
    if (channels == 1)
        snprintf(out, 32, "Y");
    else if (i < 4)
        snprintf(out, 32, "%s", rgba[i]);
    else
        snprintf(out, 32, "c%d", i);
}

int gi_image_init(gi_image *img, int width, int height, int channels,
                  const char *const *names, gi_error *err)
{
    memset(img, 0, sizeof *img);
    if (width < 1 || width > GI_IMAGE_MAX_SIDE || height < 1 || height > GI_IMAGE_MAX_SIDE)
        return gi_fail(err, GI_EINVAL, "image: size %dx%d is outside 1..%d per side", width,
                       height, GI_IMAGE_MAX_SIDE);
    if (channels < 1 || channels > GI_IMAGE_MAX_CHANNELS)
        return gi_fail(err, GI_EINVAL, "image: %d channels is outside 1..%d", channels,
                       GI_IMAGE_MAX_CHANNELS);
    /* Sides are <= 2^16 and channels <= 16, so this product fits in 64 bits. */
    size_t count = (size_t)width * (size_t)height * (size_t)channels;
    if (count > GI_IMAGE_MAX_BYTES / sizeof(float))
        return gi_fail(err, GI_ENOMEM,
                       "image: %dx%d with %d channels is %zu bytes, over the limit of %zu",
                       width, height, channels, count * sizeof(float), GI_IMAGE_MAX_BYTES);
    char tmp[GI_IMAGE_MAX_CHANNELS][32];
    for (int i = 0; i < channels; i++) {
        if (!names) {
            default_name(channels, i, tmp[i]);
            continue;
        }
        const char *n = names[i];
        if (!n || !n[0])
            return gi_fail(err, GI_EINVAL, "image: channel %d has an empty name", i);
        if (strlen(n) > GI_IMAGE_NAME_MAX)
            return gi_fail(err, GI_EINVAL, "image: channel name \"%.40s...\" is over %d bytes",
                           n, GI_IMAGE_NAME_MAX);
        memcpy(tmp[i], n, strlen(n) + 1);
        for (int j = 0; j < i; j++)
            if (strcmp(tmp[j], tmp[i]) == 0)
                return gi_fail(err, GI_EINVAL, "image: channel name \"%s\" appears twice", n);
    }
    float *px = gi_try_calloc(count, sizeof(float), err, "image pixels");
    if (!px)
        return -1;
    img->width = width;
    img->height = height;
    img->channels = channels;
    memcpy(img->names, tmp, sizeof(tmp[0]) * (size_t)channels);
    img->pixels = px;
    return 0;
}

void gi_image_free(gi_image *img)
{
    if (!img)
        return;
    free(img->pixels);
    memset(img, 0, sizeof *img);
}

int gi_image_channel(const gi_image *img, const char *name)
{
    for (int i = 0; i < img->channels; i++)
        if (strcmp(img->names[i], name) == 0)
            return i;
    return -1;
}

int gi_image_check_finite(const gi_image *img, const char *what, gi_error *err)
{
    size_t n = (size_t)img->width * (size_t)img->height * (size_t)img->channels;
    for (size_t i = 0; i < n; i++) {
        if (isfinite(img->pixels[i]))
            continue;
        size_t px = i / (size_t)img->channels;
        return gi_fail(err, GI_EINTERNAL,
                       "%s: pixel (%zu, %zu)'s %s is %g: an image output is never written "
                       "with a non-finite value",
                       what, px % (size_t)img->width, px / (size_t)img->width,
                       img->names[i % (size_t)img->channels], (double)img->pixels[i]);
    }
    return 0;
}
