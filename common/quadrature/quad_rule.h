/* quad_rule: the embedded cubature rule pairs a region is integrated with.
 *
 * A rule places `points` samples in an axis-aligned box of [0,1]^N and
 * gives, from their values, a high-order estimate of the box's integral, a
 * low-order one (their difference is the error estimate, eq. 4.3-4.4), a
 * fourth difference per axis (the split-axis criterion, eq. 4.6), and the
 * image-plane data the region's interpolant is built from (quad_interp.h).
 *
 * Two rules:
 *   - GI_QUAD_BOOLE: the thesis's tensor pair (sec. 4.1): Boole's 5-point
 *     rule in every axis (5^N samples, exact for degree <= 5 per axis) and
 *     Simpson's rule on 3 of the 5 nodes (exact for degree <= 3). When a
 *     region is bisected each child takes 3 of its 5 planes along the split
 *     axis from the parent (nodes 0,1,2 or 2,3,4 become the child's 0,2,4),
 *     so a child costs 2*5^(N-1) new samples (quad_boole.c).
 *   - GI_QUAD_GM: Genz and Malik's (1980) fully symmetric degree-7 rule with
 *     its embedded degree-5 rule, 2^N + 2N^2 + 2N + 1 samples (quad_gm.c):
 *     not in the thesis; it keeps N >= 4 affordable.
 *
 * Samples are stored point-major, `channels` doubles per point. */
#ifndef GI_QUAD_RULE_H
#define GI_QUAD_RULE_H

#include <stddef.h>

#include "gi_error.h"

#define GI_QUAD_MAX_DIMS 16
#define GI_QUAD_MAX_CHANNELS 4
/* 5^N samples per region: N = 7 would hold 78,125 points (1.9 MB of RGB). */
#define GI_QUAD_BOOLE_MAX_DIMS 6
/* Interpolant nodes per image axis: 5 (Boole's grid) or 2 (Genz-Malik). */
#define GI_QUAD_MAX_NODES 5

typedef enum { GI_QUAD_BOOLE, GI_QUAD_GM } gi_quad_rule_kind;

typedef struct gi_quad_rule {
    gi_quad_rule_kind kind;
    int dims, channels;
    size_t points;      /* samples of a fresh region */
    size_t child_new;   /* samples a child needs beyond what it takes from its parent */
    int nodes;          /* interpolant nodes per image axis */
    /* Boole: 5^d for d = 0..N (stride of axis a is pow5[N-1-a]). */
    size_t pow5[GI_QUAD_MAX_DIMS + 1];
    /* Genz-Malik: the point template in [-1,1]^N (points x N), its degree-7
     * and degree-5 weights (each set sums to 1), and for each axis the
     * template indices of c, c +- lambda2 e_i, c +- lambda3 e_i. */
    double *tpl, *w7, *w5;
    size_t center, axis_pts[GI_QUAD_MAX_DIMS][4];
} gi_quad_rule;

/* What a region's samples say (gi_quad_rule_analyse). */
typedef struct gi_quad_analysis {
    double est[GI_QUAD_MAX_CHANNELS];  /* high-order estimate */
    double low[GI_QUAD_MAX_CHANNELS];  /* embedded low-order estimate */
    double err_raw;                    /* || est - low ||_1, eq. 4.4 */
    double d4[GI_QUAD_MAX_DIMS];       /* fourth difference per axis, eq. 4.6 */
    double d4_scale[GI_QUAD_MAX_DIMS]; /* magnitude of the values it came from */
    int nonneg[GI_QUAD_MAX_CHANNELS];  /* no sample of the channel is negative */
    /* Image-plane data for the interpolant. Boole: the nodes x nodes grid of
     * the samples integrated over the other axes (times their extent).
     * Genz-Malik: Legendre moments a0, a1 (x), a2 (y), a3 (xy) of the same
     * light-integrated function over the region's image footprint. */
    double image[GI_QUAD_MAX_NODES * GI_QUAD_MAX_NODES * GI_QUAD_MAX_CHANNELS];
} gi_quad_analysis;

/* Axis split rule for Boole's fourth differences (ambiguity 4 of the
 * digest): through the region's centre (eq. 4.6 as printed), or on the
 * marginal (the samples integrated over the other axes). Genz-Malik always
 * uses its own axis points through the centre. */
typedef enum { GI_QUAD_AXIS_MARGINAL, GI_QUAD_AXIS_CENTRE } gi_quad_axis_rule;

int gi_quad_rule_init(gi_quad_rule *r, gi_quad_rule_kind kind, int dims, int channels,
                      gi_error *err);
void gi_quad_rule_free(gi_quad_rule *r);

/* Coordinates (points x N) of every sample of a fresh region [lo, hi]. */
void gi_quad_rule_points(const gi_quad_rule *r, const double *lo, const double *hi, double *pts);

/* A child of a region bisected along `axis` (side 0: lower half): takes
 * what it can from the parent's samples into child_f, writes the missing
 * points' coordinates to pts and their sample indices to idx, and returns
 * how many there are (r->child_new). clo/chi is the child's box. */
size_t gi_quad_rule_child(const gi_quad_rule *r, const double *parent_f, int axis, int side,
                          const double *clo, const double *chi, double *child_f, double *pts,
                          size_t *idx);

/* Estimates, error and fourth differences of a region's samples. */
void gi_quad_rule_analyse(const gi_quad_rule *r, gi_quad_axis_rule axis_rule, const double *f,
                          const double *lo, const double *hi, gi_quad_analysis *out);

/* Rule internals, one per file. */
void gi_quad_boole_points(const gi_quad_rule *r, const double *lo, const double *hi,
                          double *pts);
size_t gi_quad_boole_child(const gi_quad_rule *r, const double *parent_f, int axis, int side,
                           const double *clo, const double *chi, double *child_f, double *pts,
                           size_t *idx);
void gi_quad_boole_analyse(const gi_quad_rule *r, gi_quad_axis_rule axis_rule, const double *f,
                           const double *lo, const double *hi, gi_quad_analysis *out);
int gi_quad_gm_init(gi_quad_rule *r, gi_error *err);
void gi_quad_gm_points(const gi_quad_rule *r, const double *lo, const double *hi, double *pts);
void gi_quad_gm_analyse(const gi_quad_rule *r, const double *f, const double *lo,
                        const double *hi, gi_quad_analysis *out);

#endif
