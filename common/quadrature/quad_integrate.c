/* quad_integrate: adaptive cubature on the unit cube (see quad_integrate.h). */
#include "quad_integrate.h"

#include <math.h>
#include <string.h>

#include "quad_refine.h"

typedef struct totals {
    gi_quad_engine *e;
    const gi_quad_opts *o;
    int channels;
    /* Running sums over the leaves (open and closed), updated per split;
     * exact sums are taken again whenever they claim convergence. */
    double err, est[GI_QUAD_MAX_CHANNELS];
    double closed_err, closed_est[GI_QUAD_MAX_CHANNELS];
    uint64_t closed;
    int converged;
} totals;

static void on_split(void *user, const gi_quad_region *p, gi_quad_region *const c[2])
{
    totals *t = user;
    t->err += c[0]->s.err_raw + c[1]->s.err_raw - p->s.err_raw;
    for (int k = 0; k < t->channels; k++)
        t->est[k] += c[0]->s.est[k] + c[1]->s.est[k] - p->s.est[k];
}

static void on_close(void *user, gi_quad_region *r)
{
    totals *t = user;
    t->closed_err += r->s.err_raw;
    for (int k = 0; k < t->channels; k++)
        t->closed_est[k] += r->s.est[k];
    t->closed++;
}

static int tolerance_met(const totals *t, double err, const double *est)
{
    double l1 = 0;
    for (int k = 0; k < t->channels; k++)
        l1 += fabs(est[k]);
    double tol = t->o->abs_tol > t->o->rel_tol * l1 ? t->o->abs_tol : t->o->rel_tol * l1;
    return err <= tol;
}

/* Exact sums over the open leaves (live regions) plus the closed ones. */
static void exact_sums(const totals *t, double *err, double *est)
{
    *err = t->closed_err;
    memcpy(est, t->closed_est, sizeof(double) * t->channels);
    for (uint32_t s = 0; s < t->e->used; s++) {
        const gi_quad_region *r = gi_quad_region_at(t->e, s);
        if (!r->live)
            continue;
        *err += r->s.err_raw;
        for (int k = 0; k < t->channels; k++)
            est[k] += r->s.est[k];
    }
}

static int stop(void *user)
{
    totals *t = user;
    if (t->e->evals + 2 * t->e->rule->child_new > t->o->max_evals)
        return 1;
    if (!tolerance_met(t, t->err, t->est))
        return 0;
    double est[GI_QUAD_MAX_CHANNELS];
    exact_sums(t, &t->err, est);
    memcpy(t->est, est, sizeof est);
    t->converged = tolerance_met(t, t->err, t->est);
    return t->converged;
}

int gi_quad_integrate(int dims, int channels, const gi_quad_integrand *fn,
                      const gi_quad_opts *opts, gi_quad_result *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_quad_rule rule;
    if (gi_quad_rule_init(&rule, opts->rule, dims, channels, err))
        return -1;
    gi_quad_engine e;
    gi_quad_image noimage = {0, 0};
    if (gi_quad_engine_init(&e, &rule, opts->axis_rule, &noimage, fn, err)) {
        gi_quad_rule_free(&rule);
        return -1;
    }
    gi_qheap *heap = gi_qheap_create(opts->heap);
    totals t;
    memset(&t, 0, sizeof t);
    t.e = &e;
    t.o = opts;
    t.channels = channels;
    double lo[GI_QUAD_MAX_DIMS] = {0}, hi[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < dims; d++)
        hi[d] = 1.0;
    int rc = -1;
    gi_quad_region *root = gi_quad_region_new(&e, lo, hi, err);
    if (root) {
        t.err = root->s.err_raw;
        memcpy(t.est, root->s.est, sizeof(double) * channels);
        gi_quad_refine_cb cb = {on_split, on_close, stop, &t};
        gi_quad_refine_offer(&e, heap, root, 0.0, &cb);
        uint64_t splits = 0;
        rc = gi_quad_refine(&e, heap, 0.0, UINT64_MAX, &cb, &splits, err);
        exact_sums(&t, &out->err, out->est);
        out->converged = tolerance_met(&t, out->err, out->est);
        out->evals = e.evals;
        out->splits = splits;
        out->regions = e.live + t.closed;
    }
    gi_qheap_free(heap);
    gi_quad_engine_free(&e);
    gi_quad_rule_free(&rule);
    return rc;
}
