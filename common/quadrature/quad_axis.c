/* quad_axis: region error and split axis (see quad_axis.h). */
#include "quad_axis.h"

#include <math.h>

void gi_quad_pixel_span(const gi_quad_image *im, const double *lo, const double *hi, int *px,
                        int *py)
{
    if (im->width <= 0) {
        *px = *py = 1;
        return;
    }
    double x0 = floor(lo[0] * im->width), x1 = ceil(hi[0] * im->width);
    double y0 = floor(lo[1] * im->height), y1 = ceil(hi[1] * im->height);
    *px = x1 - x0 >= 1.0 ? (int)(x1 - x0) : 1;
    *py = y1 - y0 >= 1.0 ? (int)(y1 - y0) : 1;
}

double gi_quad_region_error(const gi_quad_image *im, double err_raw, const double *lo,
                            const double *hi)
{
    if (im->width <= 0)
        return err_raw;
    int px, py;
    gi_quad_pixel_span(im, lo, hi, &px, &py);
    double total = (double)im->width * (double)im->height;
    return err_raw * (1.0 + (double)px * (double)py / total); /* eq. 4.5 */
}

int gi_quad_split_axis(const gi_quad_image *im, int dims, const gi_quad_analysis *a,
                       const double *lo, const double *hi)
{
    int px = 1, py = 1;
    if (im->width > 0)
        gi_quad_pixel_span(im, lo, hi, &px, &py);
    int best = -1;
    double best_c = 0, best_v = 0;
    for (int i = 0; i < dims; i++) {
        double v = hi[i] - lo[i];
        if (v < 2.0 * GI_QUAD_MIN_EXTENT)
            continue;
        double h = 1.0; /* eq. 4.7 */
        if (im->width > 0 && i == 0)
            h = 2.0 + (double)px / im->width;
        else if (im->width > 0 && i == 1)
            h = 2.0 + (double)py / im->height;
        double d = a->d4[i] <= 1e-12 * a->d4_scale[i] ? 0.0 : a->d4[i];
        double c = d * h; /* eq. 4.8 */
        if (best < 0 || c > best_c || (c == best_c && v > best_v)) {
            best = i;
            best_c = c;
            best_v = v;
        }
    }
    return best;
}
