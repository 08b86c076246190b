/* detp_auto: the theory the automatic parameters come from (thesis 1.13,
 * 3.6.1, 3.12). Under uniformly distributed lines through the convex hull
 * of area A_0, the number of rays crossing a (one-sided) disc of area A_d
 * is Binomial(n_R, A_d / A_0) (eqs. 3.38-3.41), so the estimate's relative
 * standard deviation is sqrt((A_0 - A_d) / (A_d n_R)) (eq. 3.46). The disc
 * radius that loses nothing the sampling has not already lost is the mean
 * sample spacing (Nyquist, thesis 3.12): gi_detp_mean_edge. */
#include <math.h>

#include "detp.h"

double gi_detp_predicted_error(double hull_area, double disc_area, double rays)
{
    if (!(disc_area > 0.0) || !(rays > 0.0) || !(hull_area > disc_area))
        return 0.0;
    return sqrt((hull_area - disc_area) / (disc_area * rays)); /* eq. 3.46 */
}

uint64_t gi_detp_rays_for_error(double hull_area, double disc_area, double e)
{
    if (!(disc_area > 0.0) || !(e > 0.0) || !(hull_area > disc_area))
        return 1;
    double n = ceil((hull_area - disc_area) / (disc_area * e * e)); /* eq. 3.46 for n_R */
    return n < 1.0 ? 1 : n > 9e18 ? (uint64_t)9e18 : (uint64_t)n;
}

double gi_detp_hull_area(const gi_scene *s)
{
    double x = (double)s->bbox_max.x - s->bbox_min.x, y = (double)s->bbox_max.y - s->bbox_min.y,
           z = (double)s->bbox_max.z - s->bbox_min.z;
    return 2.0 * (x * y + y * z + z * x);
}

double gi_detp_scene_size(const gi_scene *s)
{
    double x = (double)s->bbox_max.x - s->bbox_min.x, y = (double)s->bbox_max.y - s->bbox_min.y,
           z = (double)s->bbox_max.z - s->bbox_min.z;
    return fmax(x, fmax(y, z));
}
