/* detp_basic: basic DETP (thesis 1.5): every disc against every segment,
 * T = n_P n_R u. The reference the faster estimators are tested against,
 * and fine for small runs. */
#include "detp.h"

void gi_detp_basic(const gi_detp_discs *d, const gi_detp_segments *s, gi_detp_accum *acc,
                   gi_detp_stats *st)
{
    uint64_t crossings = 0;
    for (uint32_t i = 0; i < d->count; i++) {
        const gi_detp_disc *D = &d->d[i];
        for (size_t j = 0; j < s->count; j++)
            if (gi_detp_crosses(D, d->r2, &s->v[j])) {
                gi_detp_accum_add(acc, i, &s->v[j]);
                crossings++;
            }
    }
    st->disc_tests += (uint64_t)d->count * s->count;
    st->crossings += crossings;
}
