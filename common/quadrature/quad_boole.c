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

void gi_quad_boole_points(const gi_quad_rule *r, const double *lo, const double *hi,
                          double *pts)
{
    int n = r->dims;
    double step[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < n; d++)
        step[d] = (hi[d] - lo[d]) * 0.25;
    for (size_t i = 0; i < r->points; i++) {
        size_t rest = i;
        for (int d = n - 1; d >= 0; d--) {
            pts[i * n + d] = lo[d] + (double)(rest % 5) * step[d];
            rest /= 5;
        }
    }
}

size_t gi_quad_boole_child(const gi_quad_rule *r, const double *parent_f, int axis, int side,
                           const double *clo, const double *chi, double *child_f, double *pts,
                           size_t *idx)
{
    int n = r->dims, nc = r->channels;
    size_t stride = r->pow5[n - 1 - axis], count = 0;
    double step[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < n; d++)
        step[d] = (chi[d] - clo[d]) * 0.25;
    for (size_t i = 0; i < r->points; i++) {
        int k = (int)((i / stride) % 5);
        if (k % 2 == 0) {
            /* The child's nodes 0, 2, 4 are the parent's 0, 1, 2 (lower
             * half) or 2, 3, 4 (upper half). */
            int pk = 2 * side + k / 2;
            size_t pi = i + ((size_t)pk - (size_t)k) * stride;
            memcpy(child_f + i * nc, parent_f + pi * nc, sizeof(double) * nc);
            continue;
        }
        size_t rest = i;
        for (int d = n - 1; d >= 0; d--) {
            pts[count * n + d] = clo[d] + (double)(rest % 5) * step[d];
            rest /= 5;
        }
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

/* Integrates the samples over the axes [keep, N) (the slowest `keep` axes
 * stay) with weights w: out gets 5^keep * C values. */
static void collapse_tail(const gi_quad_rule *r, const double *f, int keep, const double w[5],
                          double *out)
{
    int n = r->dims, nc = r->channels;
    if (keep == n) {
        memcpy(out, f, sizeof(double) * r->points * nc);
        return;
    }
    collapse(f, r->pow5[n - 1], (size_t)nc, w, out);
    for (int m = n - 1; m > keep; m--)
        collapse(out, r->pow5[m - 1], (size_t)nc, w, out);
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
    /* Scratch for 5^(N-1) * C doubles: N <= GI_QUAD_BOOLE_MAX_DIMS keeps it
     * at 100 KB. */
    double buf[5 * 5 * 5 * 5 * 5 * GI_QUAD_MAX_CHANNELS];
    double vol = 1.0, light_vol = 1.0;
    for (int d = 0; d < n; d++) {
        vol *= hi[d] - lo[d];
        if (d >= 2)
            light_vol *= hi[d] - lo[d];
    }
    const double *src = f;
    /* Boole and Simpson estimates (iterated over every axis). */
    collapse_tail(r, src, 0, boole_w, buf);
    for (int c = 0; c < nc; c++)
        out->est[c] = vol * buf[c];
    collapse_tail(r, src, 0, simpson_w, buf);
    for (int c = 0; c < nc; c++)
        out->low[c] = vol * buf[c];

    /* Image plane: the 5 x 5 grid integrated over the other axes. */
    if (n >= 2) {
        collapse_tail(r, src, 2, boole_w, buf);
        for (size_t i = 0; i < 25 * (size_t)nc; i++)
            out->image[i] = light_vol * buf[i];
    }

    /* Fourth differences per axis. */
    for (int a = 0; a < n; a++) {
        double m[5 * GI_QUAD_MAX_CHANNELS];
        if (axis_rule == GI_QUAD_AXIS_CENTRE) {
            /* Point values on the line through the centre (eq. 4.6 as
             * printed): every other axis at node 2. */
            size_t base = 0;
            for (int d = 0; d < n; d++)
                if (d != a)
                    base += 2 * r->pow5[n - 1 - d];
            for (int k = 0; k < 5; k++)
                memcpy(m + k * nc, f + (base + (size_t)k * r->pow5[n - 1 - a]) * nc,
                       sizeof(double) * nc);
        } else {
            /* The mean over the other axes (Boole weights sum to 1): sees
             * features the centre line misses. */
            const double *mv = f;
            int front = a;
            if (a < n - 1) {
                collapse_tail(r, f, a + 1, boole_w, buf);
                mv = buf;
            } else if (a > 0) {
                /* The last axis: integrate axis 0 away straight from f. */
                collapse(f, 1, r->pow5[n - 1] * (size_t)nc, boole_w, buf);
                mv = buf;
                front = a - 1;
            }
            /* mv holds the axes a-front..a: integrate away the front ones,
             * each of shape (1, 5, 5^(rest) C). */
            for (int d = 0; d < front; d++)
                collapse(buf, 1, r->pow5[front - d] * (size_t)nc, boole_w, buf);
            memcpy(m, mv, sizeof(double) * 5 * nc);
        }
        fourth_difference(m, nc, &out->d4[a], &out->d4_scale[a]);
    }
}
