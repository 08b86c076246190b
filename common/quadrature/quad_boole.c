/* quad_boole: the tensor Boole / Simpson pair (thesis sec. 4.1, 5.2).
 *
 * Samples sit on the 5^N grid of nodes lo + k (hi - lo) / 4, k = 0..4 per
 * axis, stored lexicographically with axis 0 slowest (so consecutive samples
 * share their image-plane coordinates: the integrand reuses its camera ray).
 * Every sum over the grid is done one axis at a time (iterated integration,
 * Fubini), which costs O(5^N) instead of O(N 5^N).
 *
 * Region boxes are dyadic (bisections of [0,1]), so a node's coordinate is
 * exact whichever box computes it: a child's copied samples are bit for bit
 * what evaluating the child afresh would give. */
#include <math.h>
#include <string.h>

#include "quad_rule.h"

/* Boole's rule on [0,1] with nodes k/4 (exact for degree <= 5), and
 * Simpson's rule on nodes 0, 2, 4 (degree <= 3), as 5-node weights. */
static const double boole_w[5] = {7.0 / 90, 32.0 / 90, 12.0 / 90, 32.0 / 90, 7.0 / 90};
static const double simpson_w[5] = {1.0 / 6, 0.0, 4.0 / 6, 0.0, 1.0 / 6};

/* Advances the node index tuple k (axis 0 slowest) to the next sample. */
static inline void odometer(int *k, int n)
{
    for (int d = n - 1; d >= 0; d--) {
        if (++k[d] < 5)
            return;
        k[d] = 0;
    }
}

void gi_quad_boole_points(const gi_quad_rule *r, const double *lo, const double *hi,
                          double *pts)
{
    int n = r->dims, k[GI_QUAD_MAX_DIMS] = {0};
    double step[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < n; d++)
        step[d] = (hi[d] - lo[d]) * 0.25;
    for (size_t i = 0; i < r->points; i++, odometer(k, n))
        for (int d = 0; d < n; d++)
            pts[i * n + d] = lo[d] + (double)k[d] * step[d];
}

size_t gi_quad_boole_child(const gi_quad_rule *r, const double *parent_f, int axis, int side,
                           const double *clo, const double *chi, double *child_f, double *pts,
                           size_t *idx)
{
    int n = r->dims, nc = r->channels, k[GI_QUAD_MAX_DIMS] = {0};
    size_t stride = r->pow5[n - 1 - axis], count = 0;
    double step[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < n; d++)
        step[d] = (chi[d] - clo[d]) * 0.25;
    for (size_t i = 0; i < r->points; i++, odometer(k, n)) {
        int ka = k[axis];
        if (ka % 2 == 0) {
            /* The child's nodes 0, 2, 4 are the parent's 0, 1, 2 (lower
             * half) or 2, 3, 4 (upper half). */
            int pk = 2 * side + ka / 2;
            size_t pi = i + ((size_t)pk - (size_t)ka) * stride;
            memcpy(child_f + i * nc, parent_f + pi * nc, sizeof(double) * nc);
            continue;
        }
        for (int d = 0; d < n; d++)
            pts[count * n + d] = clo[d] + (double)k[d] * step[d];
        idx[count++] = i;
    }
    return count;
}

/* src has shape (A, 5, B): dst (A, B) = sum_k w[k] src[a, k, b]. dst may be
 * src (each output is written after the inputs it needs and before any
 * later output's inputs are overwritten). */
static void collapse(const double *src, size_t A, size_t B, const double w[5], double *dst)
{
    for (size_t a = 0; a < A; a++) {
        const double *s = src + a * 5 * B;
        for (size_t b = 0; b < B; b++)
            dst[a * B + b] = w[0] * s[b] + w[1] * s[B + b] + w[2] * s[2 * B + b] +
                             w[3] * s[3 * B + b] + w[4] * s[4 * B + b];
    }
}

/* Fourth difference (eq. 4.6) of five values along an axis, at the
 * offsets that reuse Boole's nodes: alpha1 = 1 (the ends, +-v/2) and
 * alpha2 = 1/2 (nodes 1 and 3, +-v/4), so alpha1^2 / alpha2^2 = 4 (the
 * digest's note: with the printed alpha1 = 2 the points leave the region,
 * and a ratio of 16 on these nodes measures curvature instead). */
static void fourth_difference(const double *m, int nc, double *d4, double *scale)
{
    double d = 0, s = 0;
    for (int c = 0; c < nc; c++) {
        double v0 = m[c], v1 = m[nc + c], v2 = m[2 * nc + c], v3 = m[3 * nc + c],
               v4 = m[4 * nc + c];
        d += fabs((v0 + v4 - 2.0 * v2) - 4.0 * (v1 + v3 - 2.0 * v2));
        s += fabs(v0) + fabs(v1) + fabs(v2) + fabs(v3) + fabs(v4);
    }
    *d4 = d;
    *scale = s;
}

void gi_quad_boole_analyse(const gi_quad_rule *r, gi_quad_axis_rule axis_rule, const double *f,
                           const double *lo, const double *hi, gi_quad_analysis *out)
{
    int n = r->dims, nc = r->channels;
    /* tail[k]: the samples integrated over axes k..N-1 with Boole's weights
     * (5^k x C values; tail[N] is f), computed as one chain: every sum below
     * starts from one of them. Sizes add up to < 1.25 x 5^(N-1) C. */
    double chain[5 * 5 * 5 * 5 * 5 * GI_QUAD_MAX_CHANNELS * 5 / 4 + 8];
    double tmp[5 * 5 * 5 * 5 * 5 * GI_QUAD_MAX_CHANNELS];
    const double *tail[GI_QUAD_MAX_DIMS + 1];
    double vol = 1.0, light_vol = 1.0;
    for (int d = 0; d < n; d++) {
        vol *= hi[d] - lo[d];
        if (d >= 2)
            light_vol *= hi[d] - lo[d];
    }
    tail[n] = f;
    double *next = chain;
    for (int k = n - 1; k >= 0; k--) {
        collapse(tail[k + 1], r->pow5[k], (size_t)nc, boole_w, next);
        tail[k] = next;
        next += r->pow5[k] * (size_t)nc;
    }
    for (int c = 0; c < nc; c++)
        out->est[c] = vol * tail[0][c];
    /* Image plane: the 5 x 5 grid integrated over the other axes. */
    if (n >= 2)
        for (size_t i = 0; i < 25 * (size_t)nc; i++)
            out->image[i] = light_vol * tail[2][i];
    /* Simpson: its own chain, in place. */
    collapse(f, r->pow5[n - 1], (size_t)nc, simpson_w, tmp);
    for (int k = n - 2; k >= 0; k--)
        collapse(tmp, r->pow5[k], (size_t)nc, simpson_w, tmp);
    for (int c = 0; c < nc; c++)
        out->low[c] = vol * tmp[c];

    /* Fourth differences per axis. */
    for (int a = 0; a < n; a++) {
        const double *m;
        if (axis_rule == GI_QUAD_AXIS_CENTRE) {
            /* Point values on the line through the centre (eq. 4.6 as
             * printed): every other axis at node 2. */
            size_t base = 0;
            for (int d = 0; d < n; d++)
                if (d != a)
                    base += 2 * r->pow5[n - 1 - d];
            for (int k = 0; k < 5; k++)
                memcpy(tmp + k * nc, f + (base + (size_t)k * r->pow5[n - 1 - a]) * nc,
                       sizeof(double) * nc);
            m = tmp;
        } else if (a == 0) {
            /* The mean over the other axes (Boole weights sum to 1): sees
             * features the centre line misses. tail[1] is axis 0's. */
            m = tail[1];
        } else {
            /* tail[a+1] holds axes 0..a: integrate away the front ones,
             * axis d having shape (1, 5, 5^(a-d) C). */
            collapse(tail[a + 1], 1, r->pow5[a] * (size_t)nc, boole_w, tmp);
            for (int d = 1; d < a; d++)
                collapse(tmp, 1, r->pow5[a - d] * (size_t)nc, boole_w, tmp);
            m = tmp;
        }
        fourth_difference(m, nc, &out->d4[a], &out->d4_scale[a]);
    }
}
