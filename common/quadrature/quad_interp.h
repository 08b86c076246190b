/* quad_interp: a region's interpolant on the image plane.
 *
 * The region's samples, integrated over every axis but the image's, give
 * a function G(x, y) on the region's footprint whose integral is the
 * region's estimate. G is represented piecewise bilinearly on an
 * (n-1) x (n-1) grid of cells over the footprint (nodes at the rule's image
 * positions). It is what gets splatted into pixels (quad_splat.h) and what
 * the hybrid's control variate evaluates (quad_hybrid.h), so the two are
 * the same function by construction.
 *
 *   - Boole (n = 5): the thesis's 16 bilinear patches (eqs. 4.12-4.15) on
 *     the 5 x 5 grid of light-integrated samples. Integrated exactly, such
 *     patches give the composite trapezoid rule (weights 1,2,2,2,1 / 8 per
 *     axis), not Boole's: the digest's note that the splatted value is not
 *     the estimate whose error was measured. To make them agree, each
 *     channel is scaled by Q_Boole / Q_trapezoid when its samples are
 *     non-negative (radiance always is; Boole's weights are positive, so
 *     the ratio lies in [0.28, 2.03] and zeros stay zeros), else shifted by
 *     the constant (Q_Boole - Q_trapezoid) / area. Either way the
 *     interpolant integrates to Q_Boole, up to rounding.
 *   - Genz-Malik (n = 2): one bilinear patch, the L2 projection of G onto
 *     {1, X, Y, XY} computed by the degree-7 rule, its non-constant part
 *     scaled down, for a channel whose samples are non-negative, just enough
 *     that no corner is negative (a slope limiter; the non-constant part
 *     integrates to 0, so the integral is unchanged).
 *
 * Node values are stored x-major: v[(ix * n + iy) * C + c]. */
#ifndef GI_QUAD_INTERP_H
#define GI_QUAD_INTERP_H

#include "quad_rule.h"

typedef struct gi_quad_interp {
    int n; /* nodes per axis */
    int channels;
    double v[GI_QUAD_MAX_NODES * GI_QUAD_MAX_NODES * GI_QUAD_MAX_CHANNELS];
} gi_quad_interp;

/* Builds the interpolant of a region from its analysis (footprint
 * [lo0,hi0] x [lo1,hi1] in [0,1]^2). */
void gi_quad_interp_build(const gi_quad_rule *r, const gi_quad_analysis *a, const double *lo,
                          const double *hi, gi_quad_interp *out);

/* The interpolant minus the next coarser reconstruction of the same data,
 * scaled to the same integral (so the difference is only in how the
 * region's integral is spread over its footprint): Boole's 5 x 5 grid
 * minus its 3 x 3 sub-grid (the nodes Simpson's rule uses), Genz-Malik's
 * bilinear patch minus its mean. Splatted, its L1 norm over the pixels is
 * the region's reconstruction error (quad_region.h). Written on g's node
 * grid. */
void gi_quad_interp_coarse_diff(const gi_quad_interp *g, const double *lo, const double *hi,
                                gi_quad_interp *out);

/* The exact integral of the interpolant over its footprint (unit coords). */
void gi_quad_interp_integral(const gi_quad_interp *g, const double *lo, const double *hi,
                             double *out);

/* G at (x, y) in the footprint (unit coordinates). */
void gi_quad_interp_eval(const gi_quad_interp *g, const double *lo, const double *hi, double x,
                         double y, double *out);

#endif
