/* quad_axis: a region's error with the image-space weight (eq. 4.5) and the
 * choice of the axis it is bisected along (eqs. 4.6-4.8).
 *
 * Axes 0 and 1 of the domain are the image plane (the whole image is
 * [0,1]^2). A region's footprint spans pixelsX x pixelsY pixels; both
 * weights favour regions that cover much of the image. Without an image
 * (width 0: Genz tests) both weights are 1. */
#ifndef GI_QUAD_AXIS_H
#define GI_QUAD_AXIS_H

#include "quad_rule.h"

/* Extents below this are not split further: nodes of dyadic boxes stay
 * exact in double down to ~2^-50, and nothing real needs finer. */
#define GI_QUAD_MIN_EXTENT (1.0 / 1099511627776.0) /* 2^-40 */

typedef struct gi_quad_image {
    int width, height; /* 0: the domain has no image plane */
} gi_quad_image;

/* Pixel columns (*px) and rows (*py) the footprint [lo0,hi0] x [lo1,hi1]
 * overlaps (1 x 1 without an image). */
void gi_quad_pixel_span(const gi_quad_image *im, const double *lo, const double *hi, int *px,
                        int *py);

/* eq. 4.5: err_raw * (1 + nPixels / totalPixels). */
double gi_quad_region_error(const gi_quad_image *im, double err_raw, const double *lo,
                            const double *hi);

/* eq. 4.8: the axis maximising D_i H(i) (eq. 4.7), ties to the longer
 * side, then the lower axis; fourth differences within 1e-12 of the
 * magnitude of the values they came from count as 0 (thesis sec. 5.6: "errors
 * close to zero"), so a region that is polynomial enough along every axis
 * is split along its longest side. Returns -1 if no axis can be split
 * (every side at GI_QUAD_MIN_EXTENT). */
int gi_quad_split_axis(const gi_quad_image *im, int dims, const gi_quad_analysis *a,
                       const double *lo, const double *hi);

#endif
