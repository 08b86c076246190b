/* quad_params: the "quadrature" block of a job, validated strictly (every
 * key, type and range; docs/job-format.md). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "quadrature.h"

#define MAX_INITIAL_REGIONS (1 << 20)

void gi_quad_params_default(gi_quad_params *p)
{
    memset(p, 0, sizeof *p);
    p->dims = 4;
    p->rule = GI_QUAD_BOOLE;
    p->axis_rule = GI_QUAD_AXIS_MARGINAL;
    p->heap = GI_QHEAP_BUCKETED;
    p->threshold = 0.0;
    p->tolerance = 0.0;
    p->max_evals = 4000000;
    p->initial[0] = p->initial[1] = 1; /* parse picks them from the image size */
    p->initial_path = 1;
    p->round_tasks = 16;
    p->task_regions = 8;
    p->task_splits = 64;
    p->hybrid = 0;
    p->mc_spp = 8;
    p->max_bounces = -1;
    p->rr_depth = 3;
    snprintf(p->anim.path, sizeof p->anim.path, "quadrature.animation");
}

static int power_of_two(int64_t v) { return v > 0 && (v & (v - 1)) == 0; }

/* Initial tiles per image axis: at least 16 (regions that start as a large
 * part of the scene can miss what falls between all their samples - a
 * penumbra sliver at the edge of the floor: a region whose samples are all
 * zero has no error estimate and is never refined), and tiles of at most 8
 * pixels (5 Boole nodes per 8 pixels); a power of two, at most 1024 and not
 * much finer than the pixels. */
static int auto_initial(int side)
{
    int n = 1;
    while (n < 1024 && (n < 16 || side > 8 * n) && n < side)
        n *= 2;
    return n;
}

int gi_quad_params_parse(gi_quad_params *p, const cJSON *params, int width, int height,
                         gi_jv *v)
{
    gi_quad_params_default(p);
    p->initial[0] = auto_initial(width);
    p->initial[1] = auto_initial(height);
    /* 100 evaluations per pixel (a few bisections each past the initial
     * regions' ~10), at least 4 million. */
    double evals = 100.0 * width * height;
    p->max_evals = evals > 4e6 ? (uint64_t)evals : 4000000;
    if (!params)
        return 0;
    static const char *const keys[] = {"dims", "rule", "axis", "heap", "threshold", "tolerance",
                                       "max_evals", "initial", "initial_path", "round_tasks",
                                       "task_regions", "task_splits", "hybrid", "mc_spp",
                                       "max_bounces", "rr_depth", "animation", NULL};
    static const char *const rules[] = {"boole", "genz-malik", NULL};
    static const char *const axes[] = {"marginal", "centre", NULL};
    static const char *const heaps[] = {"bucketed", "binary", "pairing", NULL};
    int64_t dims = p->dims, max_evals = (int64_t)p->max_evals, ipath = p->initial_path,
            rtasks = p->round_tasks, tregions = p->task_regions, tsplits = p->task_splits,
            spp = -1, maxb = p->max_bounces, rr = -1;
    int rule = (int)p->rule, axis = (int)p->axis_rule, heap = (int)p->heap;
    const cJSON *initial = NULL, *anim = NULL;
    if (gi_jv_keys(v, params, "quadrature", keys) ||
        gi_jv_int(v, params, "quadrature", "dims", 0, 4, GI_QUAD_MAX_DIMS, &dims) ||
        gi_jv_enum(v, params, "quadrature", "rule", 0, rules, &rule) ||
        gi_jv_enum(v, params, "quadrature", "axis", 0, axes, &axis) ||
        gi_jv_enum(v, params, "quadrature", "heap", 0, heaps, &heap) ||
        gi_jv_number(v, params, "quadrature", "threshold", 0, 0.0, 1.0, &p->threshold) ||
        gi_jv_number(v, params, "quadrature", "tolerance", 0, 0.0, 1.0, &p->tolerance) ||
        gi_jv_int(v, params, "quadrature", "max_evals", 0, 1, (int64_t)1 << 50, &max_evals) ||
        gi_jv_member_array(v, params, "quadrature", "initial", 0, &initial) ||
        gi_jv_int(v, params, "quadrature", "initial_path", 0, 1, 16, &ipath) ||
        gi_jv_int(v, params, "quadrature", "round_tasks", 0, 1, 4096, &rtasks) ||
        gi_jv_int(v, params, "quadrature", "task_regions", 0, 1, 4096, &tregions) ||
        gi_jv_int(v, params, "quadrature", "task_splits", 0, 1, 1 << 20, &tsplits) ||
        gi_jv_bool(v, params, "quadrature", "hybrid", 0, &p->hybrid) ||
        gi_jv_int(v, params, "quadrature", "mc_spp", 0, 1, 1 << 16, &spp) ||
        gi_jv_int(v, params, "quadrature", "max_bounces", 0, -1, 100000, &maxb) ||
        gi_jv_int(v, params, "quadrature", "rr_depth", 0, 0, 100000, &rr) ||
        gi_jv_member_object(v, params, "quadrature", "animation", 0, &anim) ||
        gi_anim_parse(&p->anim, anim, "quadrature.animation", NULL, GI_ANIM_CAMERA, v))
        return -1;
    if (dims % 2)
        return gi_jv_fail(v, "quadrature.dims",
                          "%lld is odd (the path uses coordinates in pairs)", (long long)dims);
    if (rule == GI_QUAD_BOOLE && dims > GI_QUAD_BOOLE_MAX_DIMS)
        return gi_jv_fail(v, "quadrature.dims",
                          "%lld is too many for the Boole rule (5^N samples per region; at most "
                          "%d, or use \"rule\": \"genz-malik\")",
                          (long long)dims, GI_QUAD_BOOLE_MAX_DIMS);
    if (initial) {
        if (cJSON_GetArraySize(initial) != 2)
            return gi_jv_fail(v, "quadrature.initial", "expected [x, y], got %d numbers",
                              cJSON_GetArraySize(initial));
        for (int i = 0; i < 2; i++) {
            char path[64];
            double d;
            gi_json_index_path(path, sizeof path, "quadrature.initial", i);
            if (gi_jv_value_number(v, cJSON_GetArrayItem(initial, i), path, 1, 1024, &d))
                return -1;
            if (d != (double)(int64_t)d || !power_of_two((int64_t)d))
                return gi_jv_fail(v, path, "%g is not a power of two (regions are dyadic)", d);
            p->initial[i] = (int)d;
        }
    }
    if (!power_of_two(ipath))
        return gi_jv_fail(v, "quadrature.initial_path",
                          "%lld is not a power of two (regions are dyadic)", (long long)ipath);
    double count = (double)p->initial[0] * p->initial[1] * pow((double)ipath, (double)(dims - 2));
    char num[32];
    if (count > MAX_INITIAL_REGIONS)
        return gi_jv_fail(v, "quadrature.initial_path", "%s initial regions (at most %d)",
                          gi_fmt_count(num, count), MAX_INITIAL_REGIONS);
    if (!p->hybrid && spp >= 0)
        return gi_jv_fail(v, "quadrature.mc_spp", "only with \"hybrid\": true");
    if (!p->hybrid && rr >= 0)
        return gi_jv_fail(v, "quadrature.rr_depth", "only with \"hybrid\": true");
    p->dims = (int)dims;
    p->rule = (gi_quad_rule_kind)rule;
    p->axis_rule = (gi_quad_axis_rule)axis;
    p->heap = (gi_qheap_kind)heap;
    p->max_evals = (uint64_t)max_evals;
    p->initial_path = (int)ipath;
    p->round_tasks = (int)rtasks;
    p->task_regions = (int)tregions;
    p->task_splits = (int)tsplits;
    if (spp >= 0)
        p->mc_spp = (int)spp;
    p->max_bounces = (int)maxb;
    if (rr >= 0)
        p->rr_depth = (int)rr;
    return 0;
}
