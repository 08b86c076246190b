/* quad_hybrid: Monte Carlo with the interpolant as control variate (see
 * quad_hybrid.h). */
#include "quad_hybrid.h"

#include <math.h>

uint64_t gi_quad_hybrid_samples(const gi_quad_summary *s, int width, int height, int mc_spp)
{
    double px = (s->hi[0] - s->lo[0]) * width * (s->hi[1] - s->lo[1]) * height;
    double n = ceil(mc_spp * px);
    return n < 1.0 ? 1 : n > 4294967295.0 ? 4294967295u : (uint64_t)n;
}

uint64_t gi_quad_hybrid_region(gi_quad_mc_fn fn, void *user, uint64_t seed,
                               const gi_quad_summary *s, int dims, int mc_spp,
                               gi_quad_accum *acc, double *total)
{
    int W = acc->width, H = acc->height, nc = acc->channels;
    uint64_t n = gi_quad_hybrid_samples(s, W, H, mc_spp);
    double vol = 1.0, light_vol = 1.0;
    for (int d = 0; d < dims; d++) {
        vol *= s->hi[d] - s->lo[d];
        if (d >= 2)
            light_vol *= s->hi[d] - s->lo[d];
    }
    /* Pixel value = W H x the integral over the pixel's slab (quad_splat.h). */
    double scale = vol * (double)W * (double)H / (double)n;
    double u[GI_QUAD_MAX_DIMS], f[GI_QUAD_MAX_CHANNELS], g[GI_QUAD_MAX_CHANNELS];
    for (uint64_t j = 0; j < n; j++) {
        gi_rng rng;
        gi_rng_init(&rng, seed, s->id, (uint32_t)j);
        for (int d = 0; d < dims; d++)
            u[d] = s->lo[d] + (s->hi[d] - s->lo[d]) * gi_rng_double(&rng);
        fn(user, u, &rng, f);
        gi_quad_interp_eval(&s->interp, s->lo, s->hi, u[0], u[1], g);
        for (int c = 0; c < nc; c++) {
            f[c] -= g[c] / light_vol; /* eq. 4.17: f - g */
            total[c] += f[c] * (vol / (double)n);
        }
        int px = (int)(u[0] * W), py = (int)(u[1] * H);
        px = px < 0 ? 0 : px >= W ? W - 1 : px;
        py = py < 0 ? 0 : py >= H ? H - 1 : py;
        gi_quad_accum_add(acc, (uint32_t)((size_t)py * W + px), f, scale);
    }
    return n;
}
