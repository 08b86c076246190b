/* quad_gm: Genz and Malik's embedded degree-7 / degree-5 rule (A. C. Genz,
 * A. A. Malik, "An adaptive algorithm for numerical integration over an
 * N-dimensional rectangular region", J. Comput. Appl. Math. 6, 1980).
 *
 * On [-1,1]^N, with weights normalised to sum to 1 (integral = volume x
 * weighted mean):
 *   centre                              w7 = (12824 - 9120N + 400N^2)/19683,
 *                                        w5 = (729 - 950N + 50N^2)/729
 *   +-lambda2 e_i        (2N points)    w7 = 980/6561,   w5 = 245/486
 *   +-lambda3 e_i        (2N points)    w7 = (1820 - 400N)/19683,
 *                                        w5 = (265 - 100N)/1458
 *   lambda4 (+-e_i +-e_j), i < j        w7 = 200/19683,  w5 = 25/729
 *   lambda5 (+-1, ..., +-1) (2^N pts)   w7 = 6859/19683/2^N, w5 = 0
 * with lambda2^2 = 9/70, lambda3^2 = lambda4^2 = 9/10, lambda5^2 = 9/19.
 * The degree-7 rule integrates every polynomial of total degree <= 7
 * exactly, the embedded one degree <= 5.
 *
 * The split axis uses the same fourth difference as eq. 4.6 (from Berntsen,
 * Espelid and Genz 1991) at the rule's own axis points: alpha1 = lambda2,
 * alpha2 = lambda3, so alpha1^2 / alpha2^2 = 1/7, and no extra samples.
 *
 * The template is sorted by its first two coordinates so that points on
 * the same image position are evaluated one after the other. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "quad_rule.h"

typedef struct tpl_point {
    double t[GI_QUAD_MAX_DIMS];
    double w7, w5;
    size_t order; /* creation order: sort tie-break */
} tpl_point;

static int tpl_cmp(const void *pa, const void *pb)
{
    const tpl_point *a = pa, *b = pb;
    for (int d = 0; d < 2; d++)
        if (a->t[d] != b->t[d])
            return a->t[d] < b->t[d] ? -1 : 1;
    return a->order < b->order ? -1 : a->order > b->order;
}

int gi_quad_gm_init(gi_quad_rule *r, gi_error *err)
{
    int n = r->dims;
    size_t count = ((size_t)1 << n) + 2 * (size_t)n * n + 2 * (size_t)n + 1;
    tpl_point *p = gi_try_calloc(count, sizeof *p, err, "Genz-Malik template");
    if (!p)
        return -1;
    const double l2 = sqrt(9.0 / 70.0), l3 = sqrt(9.0 / 10.0), l4 = sqrt(9.0 / 10.0),
                 l5 = sqrt(9.0 / 19.0), N = n;
    size_t k = 0;
    /* Centre. */
    p[k].w7 = (12824.0 - 9120.0 * N + 400.0 * N * N) / 19683.0;
    p[k].w5 = (729.0 - 950.0 * N + 50.0 * N * N) / 729.0;
    k++;
    for (int i = 0; i < n; i++)
        for (int s = -1; s <= 1; s += 2) {
            p[k].t[i] = s * l2;
            p[k].w7 = 980.0 / 6561.0;
            p[k].w5 = 245.0 / 486.0;
            k++;
            p[k].t[i] = s * l3;
            p[k].w7 = (1820.0 - 400.0 * N) / 19683.0;
            p[k].w5 = (265.0 - 100.0 * N) / 1458.0;
            k++;
        }
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            for (int s = 0; s < 4; s++) {
                p[k].t[i] = (s & 1) ? -l4 : l4;
                p[k].t[j] = (s & 2) ? -l4 : l4;
                p[k].w7 = 200.0 / 19683.0;
                p[k].w5 = 25.0 / 729.0;
                k++;
            }
    for (size_t m = 0; m < ((size_t)1 << n); m++) {
        for (int i = 0; i < n; i++)
            p[k].t[i] = (m >> i) & 1 ? -l5 : l5;
        p[k].w7 = 6859.0 / 19683.0 / (double)((size_t)1 << n);
        p[k].w5 = 0.0;
        k++;
    }
    for (size_t i = 0; i < count; i++)
        p[i].order = i;
    qsort(p, count, sizeof *p, tpl_cmp);

    r->points = r->child_new = count;
    r->tpl = gi_try_calloc(count * (size_t)n, sizeof(double), err, "Genz-Malik template");
    r->w7 = gi_try_calloc(count, sizeof(double), err, "Genz-Malik weights");
    r->w5 = gi_try_calloc(count, sizeof(double), err, "Genz-Malik weights");
    if (!r->tpl || !r->w7 || !r->w5) {
        free(p);
        return -1;
    }
    for (size_t i = 0; i < count; i++) {
        memcpy(r->tpl + i * n, p[i].t, sizeof(double) * n);
        r->w7[i] = p[i].w7;
        r->w5[i] = p[i].w5;
        /* Creation order above: centre 0, then per axis i the points
         * -l2, -l3, +l2, +l3 at 1 + 4i .. 4 + 4i. */
        size_t o = p[i].order;
        if (o == 0)
            r->center = i;
        else if (o <= 4 * (size_t)n) {
            size_t axis = (o - 1) / 4, which = (o - 1) % 4;
            /* axis_pts: +l2, -l2, +l3, -l3 */
            static const int slot[4] = {1, 3, 0, 2};
            r->axis_pts[axis][slot[which]] = i;
        }
    }
    free(p);
    return 0;
}

void gi_quad_gm_points(const gi_quad_rule *r, const double *lo, const double *hi, double *pts)
{
    int n = r->dims;
    double c[GI_QUAD_MAX_DIMS], h[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < n; d++) {
        c[d] = 0.5 * (lo[d] + hi[d]);
        h[d] = 0.5 * (hi[d] - lo[d]);
    }
    for (size_t i = 0; i < r->points; i++)
        for (int d = 0; d < n; d++)
            pts[i * n + d] = c[d] + h[d] * r->tpl[i * n + d];
}

void gi_quad_gm_analyse(const gi_quad_rule *r, const double *f, const double *lo,
                        const double *hi, gi_quad_analysis *out)
{
    int n = r->dims, nc = r->channels;
    double vol = 1.0, light_vol = 1.0;
    for (int d = 0; d < n; d++) {
        vol *= hi[d] - lo[d];
        if (d >= 2)
            light_vol *= hi[d] - lo[d];
    }
    double s7[GI_QUAD_MAX_CHANNELS] = {0}, s5[GI_QUAD_MAX_CHANNELS] = {0};
    double mx[GI_QUAD_MAX_CHANNELS] = {0}, my[GI_QUAD_MAX_CHANNELS] = {0},
           mxy[GI_QUAD_MAX_CHANNELS] = {0};
    for (size_t i = 0; i < r->points; i++) {
        const double *v = f + i * nc, *t = r->tpl + i * n;
        for (int c = 0; c < nc; c++) {
            double a = r->w7[i] * v[c];
            s7[c] += a;
            s5[c] += r->w5[i] * v[c];
            mx[c] += a * t[0];
            my[c] += a * t[1];
            mxy[c] += a * t[0] * t[1];
        }
    }
    for (int c = 0; c < nc; c++) {
        out->est[c] = vol * s7[c];
        out->low[c] = vol * s5[c];
        /* Legendre moments on the footprint, X and Y in [-1,1]: the mean,
         * then 3 <G X>, 3 <G Y>, 9 <G X Y> (P1 has norm 1/3 on [-1,1]
         * under the uniform mean). The rule is exact for f t of degree
         * <= 7 (f of degree <= 5 for the xy term). */
        out->image[0 * nc + c] = light_vol * s7[c];
        out->image[1 * nc + c] = light_vol * 3.0 * mx[c];
        out->image[2 * nc + c] = light_vol * 3.0 * my[c];
        out->image[3 * nc + c] = light_vol * 9.0 * mxy[c];
    }
    const double ratio = (9.0 / 70.0) / (9.0 / 10.0); /* alpha1^2 / alpha2^2 = 1/7 */
    for (int a = 0; a < n; a++) {
        const double *fc = f + r->center * nc;
        const double *p2 = f + r->axis_pts[a][0] * nc, *m2 = f + r->axis_pts[a][1] * nc;
        const double *p3 = f + r->axis_pts[a][2] * nc, *m3 = f + r->axis_pts[a][3] * nc;
        double d = 0, s = 0;
        for (int c = 0; c < nc; c++) {
            d += fabs((p2[c] + m2[c] - 2.0 * fc[c]) - ratio * (p3[c] + m3[c] - 2.0 * fc[c]));
            s += fabs(fc[c]) + fabs(p2[c]) + fabs(m2[c]) + fabs(p3[c]) + fabs(m3[c]);
        }
        out->d4[a] = d;
        out->d4_scale[a] = s;
    }
}
