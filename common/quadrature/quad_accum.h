/* quad_accum: an additive image delta (what one task adds to the image).
 *
 * A dense double buffer for cheap random access, plus the list of pixels
 * touched, so that only those travel back to the coordinator: a task's
 * regions may be anywhere in the image, and their footprints are small.
 * Serialized as u32 count, then per pixel (in increasing index order) u32
 * index and C f64 values. */
#ifndef GI_QUAD_ACCUM_H
#define GI_QUAD_ACCUM_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

typedef struct gi_quad_accum {
    int width, height, channels;
    double *px;        /* width * height * channels */
    uint8_t *mark;     /* touched since the last reset */
    uint32_t *touched; /* their indices, first-touch order */
    size_t count;
} gi_quad_accum;

int gi_quad_accum_init(gi_quad_accum *a, int width, int height, int channels, gi_error *err);
void gi_quad_accum_free(gi_quad_accum *a);

static inline void gi_quad_accum_add(gi_quad_accum *a, uint32_t pixel, const double *v,
                                     double scale)
{
    if (!a->mark[pixel]) {
        a->mark[pixel] = 1;
        a->touched[a->count++] = pixel;
    }
    double *p = a->px + (size_t)pixel * a->channels;
    for (int c = 0; c < a->channels; c++)
        p[c] += scale * v[c];
}

/* The L1 norm (over pixels and channels) of what was added; resets. */
double gi_quad_accum_take_l1(gi_quad_accum *a);

/* Serializes the touched pixels (sorted) and resets the accumulator. */
void gi_quad_accum_emit(gi_quad_accum *a, gi_buf *out);

/* A serialized delta fits a width x height image: a pixel count the bytes
 * hold, indices in range and increasing, finite values of magnitude at most
 * bound (delta unmoved). */
int gi_quad_accum_check(const gi_reader *delta, int width, int height, int channels,
                        double bound, gi_error *err);
/* Adds a serialized delta to a dense image of width * height * channels
 * (coordinator side) after gi_quad_accum_check with the same bound. */
int gi_quad_accum_apply(gi_reader *r, int width, int height, int channels, double bound,
                        double *image, gi_error *err);
/* The adding half of gi_quad_accum_apply, for a delta already checked. */
void gi_quad_accum_add_delta(gi_reader *r, int channels, double *image);

#endif
