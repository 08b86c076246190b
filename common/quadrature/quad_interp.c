/* quad_interp: the image-plane interpolant of a region (see quad_interp.h). */
#include "quad_interp.h"

#include <math.h>
#include <string.h>

/* Composite trapezoid weight of node i of n on [0,1]: what integrating the
 * piecewise-bilinear interpolant exactly amounts to. */
static double trap_w(int i, int n)
{
    return (i == 0 || i == n - 1 ? 0.5 : 1.0) / (double)(n - 1);
}

void gi_quad_interp_integral(const gi_quad_interp *g, const double *lo, const double *hi,
                             double *out)
{
    double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    int n = g->n, nc = g->channels;
    for (int c = 0; c < nc; c++) {
        double s = 0;
        for (int ix = 0; ix < n; ix++)
            for (int iy = 0; iy < n; iy++)
                s += trap_w(ix, n) * trap_w(iy, n) * g->v[(ix * n + iy) * nc + c];
        out[c] = area * s;
    }
}

static void build_boole(const gi_quad_rule *r, const gi_quad_analysis *a, const double *lo,
                        const double *hi, gi_quad_interp *g)
{
    int nc = r->channels;
    double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    memcpy(g->v, a->image, sizeof(double) * 25 * nc);
    double trap[GI_QUAD_MAX_CHANNELS];
    gi_quad_interp_integral(g, lo, hi, trap);
    for (int c = 0; c < nc; c++) {
        /* Light-integrated with positive weights, the grid of a non-negative
         * channel is non-negative. */
        if (a->nonneg[c] && trap[c] > 0.0) {
            double s = a->est[c] / trap[c];
            for (int k = 0; k < 25; k++)
                g->v[k * nc + c] *= s;
        } else if (area > 0.0) {
            double shift = (a->est[c] - trap[c]) / area;
            for (int k = 0; k < 25; k++)
                g->v[k * nc + c] += shift;
        }
    }
}

static void build_gm(const gi_quad_rule *r, const gi_quad_analysis *a, gi_quad_interp *g)
{
    int nc = r->channels;
    for (int c = 0; c < nc; c++) {
        double a0 = a->image[c], a1 = a->image[nc + c], a2 = a->image[2 * nc + c],
               a3 = a->image[3 * nc + c];
        /* At the corners |a1 X + a2 Y + a3 XY| <= |a1| + |a2| + |a3|. */
        double slope = fabs(a1) + fabs(a2) + fabs(a3), theta = 1.0;
        if (a->nonneg[c] && slope > a0)
            theta = a0 > 0.0 ? a0 / slope : 0.0;
        for (int ix = 0; ix < 2; ix++)
            for (int iy = 0; iy < 2; iy++) {
                double X = 2 * ix - 1, Y = 2 * iy - 1;
                g->v[(ix * 2 + iy) * nc + c] = a0 + theta * (a1 * X + a2 * Y + a3 * X * Y);
            }
    }
}

void gi_quad_interp_build(const gi_quad_rule *r, const gi_quad_analysis *a, const double *lo,
                          const double *hi, gi_quad_interp *out)
{
    memset(out, 0, sizeof *out);
    out->n = r->nodes;
    out->channels = r->channels;
    if (r->kind == GI_QUAD_BOOLE)
        build_boole(r, a, lo, hi, out);
    else
        build_gm(r, a, out);
}

void gi_quad_interp_eval(const gi_quad_interp *g, const double *lo, const double *hi, double x,
                         double y, double *out)
{
    int n = g->n, nc = g->channels;
    double sx = (x - lo[0]) / (hi[0] - lo[0]) * (n - 1);
    double sy = (y - lo[1]) / (hi[1] - lo[1]) * (n - 1);
    int ix = sx <= 0.0 ? 0 : sx >= n - 1 ? n - 2 : (int)sx;
    int iy = sy <= 0.0 ? 0 : sy >= n - 1 ? n - 2 : (int)sy;
    double fx = sx - ix, fy = sy - iy;
    fx = fx < 0.0 ? 0.0 : fx > 1.0 ? 1.0 : fx;
    fy = fy < 0.0 ? 0.0 : fy > 1.0 ? 1.0 : fy;
    const double *v00 = g->v + (ix * n + iy) * nc, *v01 = g->v + (ix * n + iy + 1) * nc;
    const double *v10 = g->v + ((ix + 1) * n + iy) * nc,
                 *v11 = g->v + ((ix + 1) * n + iy + 1) * nc;
    for (int c = 0; c < nc; c++)
        /* eq. 4.12 on the cell's unit square: c00 + c01 x + c10 y + c11 x y
         * with c00 = v00, c01 = v10 - v00, c10 = v01 - v00,
         * c11 = v11 - v10 - v01 + v00 (eq. 4.14 in closed form). */
        out[c] = (1 - fx) * ((1 - fy) * v00[c] + fy * v01[c]) +
                 fx * ((1 - fy) * v10[c] + fy * v11[c]);
}

void gi_quad_interp_coarse_diff(const gi_quad_interp *g, const double *lo, const double *hi,
                                gi_quad_interp *out)
{
    int n = g->n, nc = g->channels;
    *out = *g;
    double fine[GI_QUAD_MAX_CHANNELS], coarse[GI_QUAD_MAX_CHANNELS];
    gi_quad_interp_integral(g, lo, hi, fine);
    if (n == 2) {
        /* Genz-Malik: the patch minus its mean (a0). */
        double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        for (int c = 0; c < nc; c++)
            for (int k = 0; k < 4; k++)
                out->v[k * nc + c] -= area > 0 ? fine[c] / area : 0.0;
        return;
    }
    /* Boole: the 3 x 3 sub-grid (nodes 0, 2, 4), bilinear on its 2 x 2
     * cells, is also bilinear on each of the 4 x 4 fine cells: its values
     * at the fine nodes are averages of its own. */
    gi_quad_interp c3;
    memset(&c3, 0, sizeof c3);
    c3.n = 3;
    c3.channels = nc;
    for (int ix = 0; ix < 3; ix++)
        for (int iy = 0; iy < 3; iy++)
            memcpy(c3.v + (ix * 3 + iy) * nc, g->v + (2 * ix * n + 2 * iy) * nc,
                   sizeof(double) * nc);
    gi_quad_interp_integral(&c3, lo, hi, coarse);
    for (int ix = 0; ix < n; ix++)
        for (int iy = 0; iy < n; iy++) {
            int x0 = ix / 2, x1 = (ix + 1) / 2, y0 = iy / 2, y1 = (iy + 1) / 2;
            for (int c = 0; c < nc; c++) {
                double v = 0.25 * (c3.v[(x0 * 3 + y0) * nc + c] + c3.v[(x0 * 3 + y1) * nc + c] +
                                   c3.v[(x1 * 3 + y0) * nc + c] + c3.v[(x1 * 3 + y1) * nc + c]);
                /* Same integral as the fine one: scale (or shift). */
                if (coarse[c] != 0.0 && fine[c] / coarse[c] > 0.0)
                    v *= fine[c] / coarse[c];
                out->v[(ix * n + iy) * nc + c] -= v;
            }
        }
}
