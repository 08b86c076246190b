/* detp_params: parsing the "detp" block and resolving it against the scene. */
#include "detp_params.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "gi_log.h"

const char *const gi_detp_estimator_names[] = {"impact_count", "photon_map", "basic",
                                               "sphere_cache", "multilist",  "octree",
                                               "embree",       NULL};
const char *const gi_detp_mobile_estimator_names[] = {"sphere_cache", "embree", "lanes",
                                                       NULL};
const char *const gi_detp_anim_update_names[] = {"incremental", "full", NULL};

static const char *const artifact_names[] = {"none", "second_hit", "visible_area", NULL};
static const char *const order_names[] = {"none", "lebesgue", "hilbert", "shuffled", NULL};

/* A number in [lo, hi] (scene units), "N%" with N in (0, 100], or "auto"
 * when allow_auto. */
static int parse_len(gi_jv *v, const cJSON *obj, const char *key, double lo, double hi,
                     int allow_auto, gi_detp_len *out)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    char path[64];
    gi_json_path(path, sizeof path, "detp", key);
    if (!it)
        return 0;
    if (cJSON_IsNumber(it)) {
        out->kind = GI_DETP_LEN_UNITS;
        return gi_jv_value_number(v, it, path, lo, hi, &out->value);
    }
    if (cJSON_IsString(it)) {
        const char *s = it->valuestring;
        if (allow_auto && strcmp(s, "auto") == 0) {
            out->kind = GI_DETP_LEN_AUTO;
            out->value = 0;
            return 0;
        }
        char *end = NULL;
        double pct = strtod(s, &end);
        if (end != s && end && strcmp(end, "%") == 0 && isfinite(pct)) {
            if (pct == 0.0 && lo == 0.0) { /* "0%": off, like 0 */
                out->kind = GI_DETP_LEN_UNITS;
                out->value = 0;
                return 0;
            }
            if (pct > 0.0 && pct <= 100.0) {
                out->kind = GI_DETP_LEN_PERCENT;
                out->value = pct;
                return 0;
            }
            return gi_jv_fail(v, path, "\"%.40s\" is out of range: a percentage of the scene "
                              "size is in (0%%, 100%%]%s", s, lo == 0.0 ? ", or 0 for none" : "");
        }
    }
    return gi_jv_fail(v, path, "expected a length in scene units, a percentage of the scene "
                               "size such as \"2%%\"%s",
                      allow_auto ? ", or \"auto\"" : "");
}

static int parse_sphere_cache(gi_detp_params *p, const cJSON *b, gi_jv *v)
{
    static const char *const keys[] = {"q", "r_min", "max_levels", "order",
                                       "width", "sphere_limit", NULL};
    const char *path = "detp.sphere_cache";
    int64_t rmin = p->sc.r_min, levels = p->sc.max_levels, width = -1, limit = -1;
    int order = (int)p->sc.order;
    if (gi_jv_keys(v, b, path, keys) ||
        gi_jv_number(v, b, path, "q", 0, 0.05, 0.95, &p->sc.q) ||
        gi_jv_int(v, b, path, "r_min", 0, 1, 1 << 30, &rmin) ||
        gi_jv_int(v, b, path, "max_levels", 0, 1, GI_DETP_MAX_LEVELS - 1, &levels) ||
        gi_jv_enum(v, b, path, "order", 0, order_names, &order) ||
        gi_jv_int(v, b, path, "width", 0, 1, 1 << 16, &width) ||
        gi_jv_int(v, b, path, "sphere_limit", 0, 1, 1 << 24, &limit))
        return -1;
    if ((width > 0 || limit > 0) && p->estimator != GI_DETP_EST_MULTILIST)
        return gi_jv_fail(v, width > 0 ? "detp.sphere_cache.width" : "detp.sphere_cache.sphere_limit",
                          "only the \"multilist\" estimator keeps several spheres per level");
    if (width > 0 && limit > 0)
        return gi_jv_fail(v, "detp.sphere_cache", "give \"width\" or \"sphere_limit\", not both");
    p->sc.r_min = (uint32_t)rmin;
    p->sc.max_levels = (uint32_t)levels;
    p->sc.order = (gi_detp_order)order;
    if (width > 0)
        p->sc.width = (uint32_t)width;
    if (limit > 0) {
        p->sc.sphere_limit = (uint32_t)limit;
        p->sc.width = 0;
    }
    return 0;
}

/* A block for an estimator the job does not use is a mistake worth naming. */
static int block_for(gi_jv *v, const gi_detp_params *p, const char *name, int ok)
{
    if (ok)
        return 0;
    char path[64];
    gi_json_path(path, sizeof path, "detp", name);
    return gi_jv_fail(v, path, "parameters for another estimator (this job's is \"%s\")",
                      gi_detp_estimator_names[p->estimator]);
}

/* What the incremental update (thesis 1.12) cannot keep exact: it adds and
 * subtracts per-segment disc contributions, so the estimator must be a sum
 * over segments (photon_map's k nearest hits and impact_count's per-triangle
 * counts are not kept per disc), the visible-area rule would need its
 * shadow rays re-cast against every pose, and the path-traced reference
 * would be one per frame. */
static int check_animation(const gi_detp_params *p, gi_jv *v)
{
    if (!gi_anim_moves_object(&p->anim)) /* a camera path alone: a still bake */
        return 0;
    if (p->artifact == GI_DETP_AC_VISIBLE_AREA)
        return gi_jv_fail(v, "detp.artifact_control",
                          "\"visible_area\" cannot be used with detp.animation (use "
                          "\"second_hit\" or \"none\")");
    if (p->estimator == GI_DETP_EST_IMPACT_COUNT || p->estimator == GI_DETP_EST_PHOTON_MAP)
        return gi_jv_fail(v, "detp.estimator",
                          "\"%s\" cannot be used with detp.animation (use a disc estimator: "
                          "embree, octree, sphere_cache, multilist or basic)",
                          gi_detp_estimator_names[p->estimator]);
    if (p->reference_spp > 0)
        return gi_jv_fail(v, "detp.reference",
                          "the path-traced reference cannot be used with detp.animation");
    return 0;
}

int gi_detp_parse_params(gi_detp_params *p, const cJSON *b, gi_jv *v)
{
    memset(p, 0, sizeof *p);
    p->photons = 1000000;
    p->batch = 100000;
    p->radius.kind = GI_DETP_LEN_AUTO;
    p->subdivide.kind = GI_DETP_LEN_UNITS;
    p->estimator = GI_DETP_EST_EMBREE;
    p->artifact = GI_DETP_AC_SECOND_HIT;
    p->max_bounces = -1;
    p->sc.q = 2.0 / 3.0; /* the optimum of eqs. 3.84-3.86 */
    p->sc.r_min = 100;
    p->sc.max_levels = 60;
    p->sc.order = GI_DETP_ORDER_HILBERT;
    p->sc.width = 1;
    p->octree.max_depth = 0;
    p->octree.max_leaf = 20;
    p->pm_k = 20;
    p->pm_k_minus_one = 1;
    p->tile = 32;
    p->image_spp = 4;
    if (!b)
        return 0;
    static const char *const keys[] = {
        "photons", "relative_error", "batch", "radius", "subdivide", "estimator",
        "artifact_control", "max_bounces", "sphere_cache", "octree", "photon_map",
        "reference", "tile", "image_spp", "animation", NULL};
    if (gi_jv_keys(v, b, "detp", keys))
        return -1;
    int est = (int)p->estimator, ac = (int)p->artifact;
    int64_t batch = -1, maxb = p->max_bounces, tile = p->tile, ispp = p->image_spp;
    const cJSON *photons = cJSON_GetObjectItemCaseSensitive(b, "photons");
    if (photons && cJSON_IsString(photons) && strcmp(photons->valuestring, "auto") == 0) {
        p->photons = 0;
        if (gi_jv_number(v, b, "detp", "relative_error", 1, 1e-4, 1.0, &p->relative_error))
            return -1;
    } else {
        if (photons && !cJSON_IsNumber(photons))
            return gi_jv_fail(v, "detp.photons", "expected a number of photons or \"auto\"");
        if (gi_jv_int(v, b, "detp", "photons", 0, 1, GI_DETP_MAX_PHOTONS, &p->photons))
            return -1;
        if (cJSON_GetObjectItemCaseSensitive(b, "relative_error"))
            return gi_jv_fail(v, "detp.relative_error",
                              "only used with \"photons\": \"auto\"");
    }
    if (gi_jv_int(v, b, "detp", "batch", 0, 1, GI_DETP_MAX_BATCH, &batch) ||
        parse_len(v, b, "radius", 1e-30, 1e30, 1, &p->radius) ||
        parse_len(v, b, "subdivide", 0.0, 1e30, 0, &p->subdivide) ||
        gi_jv_enum(v, b, "detp", "estimator", 0, gi_detp_estimator_names, &est) ||
        gi_jv_enum(v, b, "detp", "artifact_control", 0, artifact_names, &ac) ||
        gi_jv_int(v, b, "detp", "max_bounces", 0, -1, GI_DETP_MAX_PATH - 1, &maxb) ||
        gi_jv_int(v, b, "detp", "tile", 0, 4, 4096, &tile) ||
        gi_jv_int(v, b, "detp", "image_spp", 0, 1, 4096, &ispp))
        return -1;
    p->estimator = (gi_detp_estimator)est;
    p->artifact = (gi_detp_artifact)ac;
    p->max_bounces = (int)maxb;
    p->tile = (int)tile;
    p->image_spp = (int)ispp;
    if (batch > 0)
        p->batch = batch;
    if (p->photons > 0 && p->batch > p->photons)
        p->batch = p->photons;

    const cJSON *sc, *oc, *pm, *ref, *anim;
    if (gi_jv_member_object(v, b, "detp", "sphere_cache", 0, &sc) ||
        gi_jv_member_object(v, b, "detp", "octree", 0, &oc) ||
        gi_jv_member_object(v, b, "detp", "photon_map", 0, &pm) ||
        gi_jv_member_object(v, b, "detp", "reference", 0, &ref) ||
        gi_jv_member_object(v, b, "detp", "animation", 0, &anim))
        return -1;
    if (p->estimator == GI_DETP_EST_MULTILIST)
        p->sc.width = 4;
    if (sc) {
        if (block_for(v, p, "sphere_cache",
                      p->estimator == GI_DETP_EST_SPHERE_CACHE ||
                          p->estimator == GI_DETP_EST_MULTILIST) ||
            parse_sphere_cache(p, sc, v))
            return -1;
    }
    if (oc) {
        static const char *const okeys[] = {"max_depth", "max_leaf", NULL};
        int64_t depth = 0, leaf = p->octree.max_leaf;
        const cJSON *d = cJSON_GetObjectItemCaseSensitive(oc, "max_depth");
        int auto_depth = d && cJSON_IsString(d) && strcmp(d->valuestring, "auto") == 0;
        if (block_for(v, p, "octree", p->estimator == GI_DETP_EST_OCTREE) ||
            gi_jv_keys(v, oc, "detp.octree", okeys) ||
            (!auto_depth && gi_jv_int(v, oc, "detp.octree", "max_depth", 0, 1, 16, &depth)) ||
            gi_jv_int(v, oc, "detp.octree", "max_leaf", 0, 1, 1 << 30, &leaf))
            return -1;
        p->octree.max_depth = (int)depth;
        p->octree.max_leaf = (uint32_t)leaf;
    }
    if (pm) {
        static const char *const pkeys[] = {"k", "correction", NULL};
        static const char *const corr[] = {"k-1", "k", NULL};
        int64_t k = p->pm_k;
        int c = 0;
        if (block_for(v, p, "photon_map", p->estimator == GI_DETP_EST_PHOTON_MAP) ||
            gi_jv_keys(v, pm, "detp.photon_map", pkeys) ||
            gi_jv_int(v, pm, "detp.photon_map", "k", 0, 2, 100000, &k) ||
            gi_jv_enum(v, pm, "detp.photon_map", "correction", 0, corr, &c))
            return -1;
        p->pm_k = (uint32_t)k;
        p->pm_k_minus_one = c == 0;
    }
    if (ref) {
        static const char *const rkeys[] = {"spp", "vertices", NULL};
        int64_t spp = 256, nv = 200;
        if (gi_jv_keys(v, ref, "detp.reference", rkeys) ||
            gi_jv_int(v, ref, "detp.reference", "spp", 0, 1, 1 << 24, &spp) ||
            gi_jv_int(v, ref, "detp.reference", "vertices", 0, 1, 1 << 24, &nv))
            return -1;
        p->reference_spp = (uint32_t)spp;
        p->reference_vertices = (uint32_t)nv;
    }
    static const char *const anim_keys[] = {"mobile_estimator", "update", NULL};
    int mest = GI_DETP_MOBILE_LANES, update = GI_DETP_UPDATE_INCREMENTAL;
    if (gi_anim_parse(&p->anim, anim, "detp.animation", anim_keys, GI_ANIM_CAMERA, v) ||
        (anim && (gi_jv_enum(v, anim, "detp.animation", "mobile_estimator", 0,
                             gi_detp_mobile_estimator_names, &mest) ||
                  gi_jv_enum(v, anim, "detp.animation", "update", 0, gi_detp_anim_update_names,
                             &update))))
        return -1;
    p->mobile_estimator = (gi_detp_mobile_estimator)mest;
    p->anim_update = (gi_detp_anim_update_mode)update;
    return check_animation(p, v);
}

static double len_value(const gi_detp_len *l, double scene_size)
{
    return l->kind == GI_DETP_LEN_PERCENT ? l->value * 0.01 * scene_size : l->value;
}

int gi_detp_resolve_params(gi_detp_params *p, gi_scene *scene, const char *file, gi_error *err)
{
    p->scene_size = gi_detp_scene_size(scene);
    if (!(p->scene_size > 0.0))
        return gi_fail(err, GI_EINVAL, "%s: the scene has no extent", file);
    double sub = len_value(&p->subdivide, p->scene_size);
    if (sub > 0.0) {
        if (sub < 1e-4 * p->scene_size)
            return gi_fail(err, GI_EINVAL,
                           "%s: detp.subdivide: %g is below 1e-4 of the scene size (%g)", file,
                           sub, p->scene_size);
        if (gi_detp_refine_scene(scene, sub, err))
            return gi_error_prefix(err, "%s: detp.subdivide", file);
    }
    p->mean_spacing = gi_detp_mean_edge(scene);
    p->hull_area = gi_detp_hull_area(scene);
    double r = p->radius.kind == GI_DETP_LEN_AUTO ? p->mean_spacing
                                                   : len_value(&p->radius, p->scene_size);
    if (!(r > 1e-6 * p->scene_size) || !(r <= p->scene_size))
        return gi_fail(err, GI_EINVAL,
                       "%s: detp.radius: %g is not between 1e-6 of the scene size and the "
                       "scene size (%g)",
                       file, r, p->scene_size);
    p->disc_radius = (float)r;
    double disc_area = GI_PI * r * r;
    if (p->photons == 0) {
        uint64_t n = gi_detp_rays_for_error(p->hull_area, disc_area, p->relative_error);
        if (n > (uint64_t)GI_DETP_MAX_PHOTONS)
            return gi_fail(err, GI_EINVAL,
                           "%s: detp.relative_error: %g needs %llu photons (limit %lld)", file,
                           p->relative_error, (unsigned long long)n,
                           (long long)GI_DETP_MAX_PHOTONS);
        p->photon_count = n;
        if ((uint64_t)p->batch > n)
            p->batch = (int64_t)n;
        gi_jv v = {file, err};
        if (gi_job_check_tasks(&v, "detp.batch", ceil((double)n / (double)p->batch),
                               "detp.relative_error %g needs %llu photons: in batches of %lld, "
                               "they",
                               p->relative_error, (unsigned long long)n, (long long)p->batch))
            return -1;
    } else {
        p->photon_count = (uint64_t)p->photons;
    }
    p->extent_eps = (float)(1e-5 * p->scene_size);
    /* After refinement: the pivot is the refined mobile's bounding-box centre. */
    return gi_anim_resolve(&p->anim, scene, file, err);
}
