/* quad_path: the path-space integrand (see quad_path.h). */
#include "quad_path.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_light.h"
#include "quad_light_map.h"

int gi_quad_path_init(gi_quad_path *p, gi_rt *rt, const gi_scene *s, const gi_camera *cam,
                      int width, int height, int dims, int max_bounces, int rr_depth,
                      gi_error *err)
{
    memset(p, 0, sizeof *p);
    if (dims < 4 || dims % 2)
        return gi_fail(err, GI_EINVAL, "quadrature path: %d dimensions (even, >= 4)", dims);
    p->rt = rt;
    p->scene = s;
    gi_camera_frame_init(&p->cam, cam, width, height);
    p->width = width;
    p->height = height;
    p->dims = dims;
    p->max_bounces = max_bounces;
    p->rr_depth = rr_depth;
    p->light_area = gi_try_calloc(s->light_count ? s->light_count : 1, sizeof(double), err,
                                  "emitter areas");
    if (!p->light_area)
        return -1;
    for (uint32_t k = 0; k < s->light_count; k++)
        p->light_area[k] = gi_scene_triangle_area(s, s->light_tris[k]);
    return 0;
}

void gi_quad_path_free(gi_quad_path *p)
{
    free(p->light_area);
    memset(p, 0, sizeof *p);
}

/* Next-event estimate at x towards the emitter point of coordinates (s, t):
 * f_r Le cos_s |cos_l| / d^2 V dA/du (quad_path.h). */
static gi_vec3 next_event(const gi_quad_path *p, gi_vec3 x, gi_vec3 ng_f, const gi_bsdf *bsdf,
                          double s, double t)
{
    const gi_scene *sc = p->scene;
    gi_quad_light_point lp;
    gi_quad_light_map(sc, p->light_area, s, t, &lp);
    gi_vec3 d = gi_sub(lp.p, x);
    float dist2 = gi_dot(d, d);
    if (!(dist2 > 0.0f) || !(lp.weight > 0.0))
        return gi_v3(0, 0, 0);
    float dist = sqrtf(dist2);
    gi_vec3 wi = gi_scale(d, 1.0f / dist);
    float cos_s = gi_dot(bsdf->n, wi);
    if (cos_s <= 0.0f || gi_dot(ng_f, wi) <= 0.0f)
        return gi_v3(0, 0, 0);
    const gi_material *lm = gi_scene_tri_material(sc, lp.tri);
    float cos_l = -gi_dot(lp.n, wi);
    if (cos_l == 0.0f || (cos_l < 0.0f && !lm->two_sided))
        return gi_v3(0, 0, 0);
    float abs_cos_l = fabsf(cos_l);
    gi_vec3 org;
    float tfar;
    if (!gi_rt_shadow_segment(x, ng_f, lp.p, dist, 1.0f / abs_cos_l, &org, &tfar))
        return gi_v3(0, 0, 0);
    if (gi_rt_occluded(p->rt, org, wi, 0.0f, tfar))
        return gi_v3(0, 0, 0);
    gi_vec3 fl = gi_mul(gi_bsdf_eval(bsdf, wi), lm->emission);
    return gi_scale(fl, (float)(cos_s * abs_cos_l / dist2 * lp.weight));
}

/* The radiance of the path of coordinates u (and rng beyond N, or cut if
 * rng is NULL). */
static void radiance(gi_quad_path *p, const double *u, gi_rng *rng, double *rgb)
{
    const gi_scene *sc = p->scene;
    int n = p->dims;
    gi_hit h;
    gi_vec3 dir;
    int hit;
    if (!rng && p->cache_valid && p->cache_u0 == u[0] && p->cache_u1 == u[1]) {
        hit = p->cache_hit;
        h = p->cache_h;
        dir = p->cache_dir;
    } else {
        dir = gi_camera_dir(&p->cam, (float)(u[0] * p->width), (float)(u[1] * p->height));
        hit = gi_rt_intersect(p->rt, p->cam.origin, dir, 0.0f, FLT_MAX, &h);
        if (!rng) {
            p->cache_valid = 1;
            p->cache_u0 = u[0];
            p->cache_u1 = u[1];
            p->cache_hit = hit;
            p->cache_h = h;
            p->cache_dir = dir;
        }
    }
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!hit)
        return;
    gi_vec3 org = p->cam.origin, beta = gi_v3(1, 1, 1);
    double L[3] = {0, 0, 0};
    /* The last light pair below N, reused by cut vertices beyond it. */
    int last_light = 2 + 4 * ((n - 4) / 4);
    for (int k = 1;; k++) {
        const gi_material *m = gi_scene_tri_material(sc, h.tri);
        gi_vec3 ng = sc->tri_normal[h.tri];
        gi_vec3 x = gi_madd(org, dir, h.t);
        gi_vec3 wo = gi_neg(dir);
        gi_vec3 ng_f = gi_dot(ng, wo) >= 0.0f ? ng : gi_neg(ng);
        if (k == 1) {
            gi_vec3 le = gi_light_emitted(m, ng, wo);
            L[0] += le.x;
            L[1] += le.y;
            L[2] += le.z;
        }
        if (p->max_bounces >= 0 && k > p->max_bounces)
            break;
        if (gi_is_black(m->diffuse))
            break;
        gi_bsdf bsdf = gi_bsdf_at(m, gi_scene_shading_normal(sc, h.tri, h.u, h.v, ng_f));
        int li = 2 + 4 * (k - 1), bi = li + 2;
        double ls, lt;
        if (li + 1 < n) {
            ls = u[li];
            lt = u[li + 1];
        } else if (rng) {
            ls = gi_rng_double(rng);
            lt = gi_rng_double(rng);
        } else {
            ls = u[last_light];
            lt = u[last_light + 1];
        }
        gi_vec3 e = gi_mul(beta, next_event(p, x, ng_f, &bsdf, ls, lt));
        L[0] += e.x;
        L[1] += e.y;
        L[2] += e.z;
        /* Emission met later is not counted (quad_path.h): a path that may
         * not scatter again ends here. */
        if (p->max_bounces >= 0 && k >= p->max_bounces)
            break;
        float b1, b2;
        int random_part = bi + 1 >= n;
        if (!random_part) {
            b1 = (float)u[bi];
            b2 = (float)u[bi + 1];
        } else if (rng) {
            b1 = gi_rng_float(rng);
            b2 = gi_rng_float(rng);
        } else {
            break;
        }
        gi_vec3 wi = gi_sample_cosine(bsdf.n, b1, b2);
        if (!(gi_dot(wi, ng_f) > 0.0f) || !(gi_bsdf_pdf(&bsdf, wi) > 0.0f))
            break;
        beta = gi_mul(beta, bsdf.rho); /* f cos / pdf of cosine sampling */
        if (random_part && k >= p->rr_depth) {
            float q = gi_rr_survival(beta);
            if (!(gi_rng_float(rng) < q) || (p->max_bounces < 0 && k >= GI_RR_MAX_PATH))
                break;
            beta = gi_scale(beta, 1.0f / q);
        }
        org = gi_rt_offset(x, ng_f, wi);
        dir = wi;
        if (!gi_rt_intersect(p->rt, org, dir, 0.0f, FLT_MAX, &h))
            break;
    }
    for (int c = 0; c < 3; c++)
        rgb[c] = L[c];
}

static void sanitize(gi_quad_path *p, double *rgb)
{
    for (int c = 0; c < 3; c++)
        if (!isfinite(rgb[c])) {
            rgb[c] = 0.0;
            p->nonfinite++;
        }
}

void gi_quad_path_eval(void *user, size_t n, const double *pts, double *out)
{
    gi_quad_path *p = user;
    for (size_t i = 0; i < n; i++) {
        radiance(p, pts + i * p->dims, NULL, out + 3 * i);
        sanitize(p, out + 3 * i);
    }
}

void gi_quad_path_eval_mc(gi_quad_path *p, const double *u, gi_rng *rng, double *rgb)
{
    radiance(p, u, rng, rgb);
    sanitize(p, rgb);
}
