/* quad_splat: exact pixel integrals of piecewise-bilinear interpolants (see
 * quad_splat.h). */
#include "quad_splat.h"

#include <math.h>
#include <stdlib.h>

/* Integrals over the pixels overlapping [c0, c1] (pixel units, at most
 * `limit` pixels wide image) of the two hat functions of the interval:
 * phi0 = (c1 - x)/(c1 - c0), phi1 = (x - c0)/(c1 - c0). Returns the first
 * pixel and the count. */
static int hat_integrals(double c0, double c1, int limit, double *phi0, double *phi1, int *first)
{
    int p0 = (int)floor(c0), p1 = (int)ceil(c1);
    if (p0 < 0)
        p0 = 0;
    if (p1 > limit)
        p1 = limit;
    double w = c1 - c0;
    int n = 0;
    for (int p = p0; p < p1; p++) {
        double a = c0 > p ? c0 : p, b = c1 < p + 1 ? c1 : p + 1;
        if (!(b > a) || !(w > 0.0)) {
            phi0[n] = phi1[n] = 0.0;
        } else {
            /* int_a^b (x - c0)/w dx = (b - a)(a + b - 2 c0) / (2 w) */
            phi1[n] = (b - a) * ((a - c0) + (b - c0)) / (2.0 * w);
            phi0[n] = (b - a) - phi1[n];
        }
        n++;
    }
    *first = p0;
    return n;
}

void gi_quad_splat(const gi_quad_interp *g, const double *lo, const double *hi, double scale,
                   gi_quad_accum *acc)
{
    int n = g->n, nc = g->channels, W = acc->width, H = acc->height;
    double x0 = lo[0] * W, x1 = hi[0] * W, y0 = lo[1] * H, y1 = hi[1] * H;
    double dx = (x1 - x0) / (n - 1), dy = (y1 - y0) / (n - 1);
    /* A cell spans at most ceil(W / (n - 1)) + 1 pixels per axis. */
    int maxw = W + 2, maxh = H + 2;
    double stack[4 * 512];
    double *buf = maxw + maxh <= 1024 ? stack : gi_xmalloc(sizeof(double) * 2 * (maxw + maxh));
    double *fx0 = buf, *fx1 = buf + maxw, *fy0 = buf + 2 * maxw, *fy1 = fy0 + maxh;
    for (int ix = 0; ix < n - 1; ix++) {
        double cx0 = x0 + ix * dx, cx1 = ix == n - 2 ? x1 : x0 + (ix + 1) * dx;
        int px0, nx = hat_integrals(cx0, cx1, W, fx0, fx1, &px0);
        for (int iy = 0; iy < n - 1; iy++) {
            double cy0 = y0 + iy * dy, cy1 = iy == n - 2 ? y1 : y0 + (iy + 1) * dy;
            int py0, ny = hat_integrals(cy0, cy1, H, fy0, fy1, &py0);
            const double *v00 = g->v + (ix * n + iy) * nc, *v01 = g->v + (ix * n + iy + 1) * nc;
            const double *v10 = g->v + ((ix + 1) * n + iy) * nc,
                         *v11 = g->v + ((ix + 1) * n + iy + 1) * nc;
            for (int j = 0; j < ny; j++)
                for (int i = 0; i < nx; i++) {
                    double w00 = fx0[i] * fy0[j], w01 = fx0[i] * fy1[j], w10 = fx1[i] * fy0[j],
                           w11 = fx1[i] * fy1[j];
                    if (w00 == 0.0 && w01 == 0.0 && w10 == 0.0 && w11 == 0.0)
                        continue;
                    double v[GI_QUAD_MAX_CHANNELS];
                    for (int c = 0; c < nc; c++)
                        v[c] = w00 * v00[c] + w01 * v01[c] + w10 * v10[c] + w11 * v11[c];
                    gi_quad_accum_add(acc, (uint32_t)((size_t)(py0 + j) * W + (px0 + i)), v,
                                      scale);
                }
        }
    }
    if (buf != stack)
        free(buf);
}
