/* quad_hybrid: Monte Carlo on top of the quadrature, with each region's
 * interpolant as a control variate (thesis sec. 4.6, eqs. 4.16-4.17):
 *   I_R = int_R g + int_R (f - g),
 * the first term exact (the region's splat), the second estimated with
 * n_R uniform samples in R:  (|R| / n_R) sum_j (f(U_j, xi_j) - g(U_j)),
 * each sample's residual going to the pixel its image coordinates fall in.
 * f is the full integrand: coordinates below N from U_j, the rest of the
 * path from the random stream xi_j (quad_path.h). g is the region's
 * image-plane interpolant divided by the region's extent over the path
 * axes, so int_R g is exactly the splatted value. Every final region gets
 * it - closed ones when they close, open ones in the last round - so the
 * image is an unbiased estimate of the full path integral, whatever the
 * quadrature did: the quadrature only decides the variance.
 *
 * n_R = ceil(mc_spp x the region's footprint in pixels): mc_spp samples per
 * pixel on average, at least one per region. Random numbers are keyed by
 * (seed, region id, sample index): independent of task and worker.
 *
 * Why the thesis saw bias (Figs. 6.4-6.5), and what this avoids:
 *   1. The residual f - g is signed. Mitsuba, where the thesis ran,
 *      refuses image samples with a negative channel (ImageBlock::put /
 *      putSample: "returns false if the sample contains invalid values
 *      (negative/NaN)", with an "Invalid sample value" warning), so the
 *      negative half of the residuals is dropped and the image is biased up
 *      wherever g overshoots f (edges, shadow boundaries). Here residuals
 *      are added, signed, into a double accumulator.
 *   2. The control variate's integral and its point values must come from
 *      the same function: a Boole estimate as int g with a bilinear
 *      (trapezoid) g pointwise is off by Q_Boole - Q_trapezoid per region.
 *      Here both are the interpolant (quad_interp.h), made to integrate to
 *      Q_Boole.
 *   3. Regions that got no Monte Carlo (closed ones, in the thesis's
 *      description only regions still above the threshold get it) keep
 *      their quadrature error, a bias; so do coordinates cut beyond N.
 *      Here every final region gets samples of the full path.
 * tests/unit/test_quad_hybrid.c shows 1 and 2 bias a toy problem and this
 * estimator does not; tests/integration/quadrature_hybrid_unbiased.sh
 * checks the Cornell box against the path tracer over 64 seeds. */
#ifndef GI_QUAD_HYBRID_H
#define GI_QUAD_HYBRID_H

#include <stdint.h>

#include "gi_rng.h"
#include "quad_accum.h"
#include "quad_region.h"

/* The full integrand at u (dims coordinates) with the rest of the path
 * drawn from rng; writes channels values. */
typedef void (*gi_quad_mc_fn)(void *user, const double *u, gi_rng *rng, double *out);

/* Samples in region s for mc_spp samples per pixel (image width x height). */
uint64_t gi_quad_hybrid_samples(const gi_quad_summary *s, int width, int height, int mc_spp);

/* Adds the region's Monte Carlo residual estimate to the pixels of acc,
 * and its integral (per channel) to *total; returns the number of samples
 * taken. */
uint64_t gi_quad_hybrid_region(gi_quad_mc_fn fn, void *user, uint64_t seed,
                               const gi_quad_summary *s, int dims, int mc_spp,
                               gi_quad_accum *acc, double *total);

#endif
