/* quad_splat: a region's interpolant into pixels (eqs. 4.13, 4.15).
 *
 * Dimensions 0 and 1 span the whole image, so pixel (i, j) is the square
 * [i, i+1] x [j, j+1] in pixel units x = u0 W, y = u1 H, of area 1/(W H)
 * in unit coordinates. A pixel's value is the mean radiance over it (a box
 * filter, as the path tracer's jittered samples): W H times the integral
 * over it in unit coordinates, i.e. the interpolant's integral over the
 * pixel in pixel units. Each bilinear patch is integrated exactly over
 * its overlap with each pixel (the antiderivative of eq. 4.13 evaluated at
 * the overlap's corners, written as products of 1-D integrals of the hat
 * functions), so the pixel values of a region times the pixel area add up
 * to the interpolant's integral, which is the region's estimate
 * (quad_interp.h). */
#ifndef GI_QUAD_SPLAT_H
#define GI_QUAD_SPLAT_H

#include "quad_accum.h"
#include "quad_interp.h"

/* Adds scale x the region's contribution to every pixel it overlaps. */
void gi_quad_splat(const gi_quad_interp *g, const double *lo, const double *hi, double scale,
                   gi_quad_accum *acc);

#endif
