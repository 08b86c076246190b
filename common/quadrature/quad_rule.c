/* quad_rule: choosing between the two rule pairs (see quad_rule.h). */
#include "quad_rule.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int gi_quad_rule_init(gi_quad_rule *r, gi_quad_rule_kind kind, int dims, int channels,
                      gi_error *err)
{
    memset(r, 0, sizeof *r);
    if (dims < 1 || dims > GI_QUAD_MAX_DIMS || channels < 1 || channels > GI_QUAD_MAX_CHANNELS)
        return gi_fail(err, GI_EINVAL, "quadrature rule: %d dimensions, %d channels", dims,
                       channels);
    r->kind = kind;
    r->dims = dims;
    r->channels = channels;
    if (kind == GI_QUAD_BOOLE) {
        /* 5^N samples per region: at N = 7 a region holds 78,125 points
         * (1.9 MB of RGB), beyond what a heap of them can afford. */
        if (dims > GI_QUAD_BOOLE_MAX_DIMS)
            return gi_fail(err, GI_EINVAL, "Boole rule: %d dimensions (at most %d)", dims,
                           GI_QUAD_BOOLE_MAX_DIMS);
        r->pow5[0] = 1;
        for (int d = 1; d <= dims; d++)
            r->pow5[d] = r->pow5[d - 1] * 5;
        r->points = r->pow5[dims];
        r->child_new = 2 * r->pow5[dims - 1];
        r->nodes = 5;
        return 0;
    }
    if (dims < 2)
        return gi_fail(err, GI_EINVAL, "Genz-Malik rule: needs at least 2 dimensions");
    r->nodes = 2;
    return gi_quad_gm_init(r, err);
}

void gi_quad_rule_free(gi_quad_rule *r)
{
    free(r->tpl);
    free(r->w7);
    free(r->w5);
    memset(r, 0, sizeof *r);
}

void gi_quad_rule_points(const gi_quad_rule *r, const double *lo, const double *hi, double *pts)
{
    if (r->kind == GI_QUAD_BOOLE)
        gi_quad_boole_points(r, lo, hi, pts);
    else
        gi_quad_gm_points(r, lo, hi, pts);
}

size_t gi_quad_rule_child(const gi_quad_rule *r, const double *parent_f, int axis, int side,
                          const double *clo, const double *chi, double *child_f, double *pts,
                          size_t *idx)
{
    if (r->kind == GI_QUAD_BOOLE)
        return gi_quad_boole_child(r, parent_f, axis, side, clo, chi, child_f, pts, idx);
    /* The Genz-Malik points of a child share nothing with its parent's. */
    gi_quad_gm_points(r, clo, chi, pts);
    for (size_t i = 0; i < r->points; i++)
        idx[i] = i;
    return r->points;
}

void gi_quad_rule_analyse(const gi_quad_rule *r, gi_quad_axis_rule axis_rule, const double *f,
                          const double *lo, const double *hi, gi_quad_analysis *out)
{
    memset(out, 0, sizeof *out);
    if (r->kind == GI_QUAD_BOOLE)
        gi_quad_boole_analyse(r, axis_rule, f, lo, hi, out);
    else
        gi_quad_gm_analyse(r, f, lo, hi, out);
    double e = 0;
    for (int c = 0; c < r->channels; c++) {
        e += fabs(out->est[c] - out->low[c]); /* eq. 4.4 */
        out->nonneg[c] = 1;
    }
    out->err_raw = e;
    for (size_t i = 0; i < r->points; i++)
        for (int c = 0; c < r->channels; c++)
            out->nonneg[c] &= f[i * r->channels + c] >= 0.0;
}
