/* pt: the reference path tracer (unbiased; the ground truth the other
 * methods are compared against).
 *
 * Estimator: paths from the camera; at each diffuse vertex, next-event
 * estimation on the emissive triangles and BSDF sampling, combined with
 * multiple importance sampling (power heuristic, Veach 1997); Russian
 * roulette after rr_depth bounces. Random numbers are keyed by (seed, pixel,
 * sample), so the image does not depend on tiles, passes or workers. */
#ifndef GI_PT_H
#define GI_PT_H

#include <stdint.h>

#include "gi_method.h"
#include "gi_rng.h"
#include "gi_rt.h"
#include "gi_scene.h"

typedef enum {
    GI_PT_MIS,   /* light + BSDF sampling, power heuristic (default) */
    GI_PT_BSDF,  /* BSDF sampling only: emission found by hitting it */
    GI_PT_LIGHT  /* next-event estimation only */
} gi_pt_strategy;

typedef struct gi_pt_params {
    int spp;          /* samples per pixel */
    int max_bounces;  /* -1: unlimited (Russian roulette decides) */
    int rr_depth;     /* bounces before Russian roulette starts */
    int tile;         /* task tile side, pixels */
    int pass_spp;     /* samples per pixel per task */
    gi_pt_strategy strategy;
} gi_pt_params;

/* For benchmarks: sees every ray the tracer casts. */
typedef struct gi_pt_ray_log {
    void (*ray)(void *user, gi_vec3 org, gi_vec3 dir, float tnear, float tfar, int occlusion);
    void *user;
} gi_pt_ray_log;

typedef struct gi_pt_tracer {
    gi_rt *rt;
    const gi_scene *scene;
    const gi_pt_params *params;
    const gi_pt_ray_log *log; /* NULL normally */
} gi_pt_tracer;

/* Radiance arriving at org from direction -dir (dir unit). */
gi_vec3 gi_pt_radiance(const gi_pt_tracer *tr, gi_vec3 org, gi_vec3 dir, gi_rng *rng);
/* Irradiance at surface point p over the hemisphere of unit normal n
 * (direct and indirect; emission of the surface at p itself excluded):
 * what a per-vertex method's irradiance is checked against. p is counted
 * as the first scattering vertex for max_bounces and rr_depth. */
gi_vec3 gi_pt_irradiance(const gi_pt_tracer *tr, gi_vec3 p, gi_vec3 n, gi_rng *rng);

/* The estimator one vertex at a time, so many paths can advance together
 * (gi_pt_trace_paths) with the very same arithmetic as gi_pt_radiance. */
typedef struct gi_pt_path {
    gi_vec3 org, dir; /* the ray to trace next */
    gi_vec3 beta;     /* throughput */
    gi_vec3 L;        /* radiance gathered so far */
    float prev_pdf;   /* BSDF density of the current ray (for MIS) */
    int bounce;
    gi_rng rng;
} gi_pt_path;

/* A next-event estimation shadow ray: contrib is added to the path's L if
 * nothing blocks org + t dir for t in [0, tfar]. */
typedef struct gi_pt_shadow {
    gi_vec3 org, dir, contrib;
    float tfar;
} gi_pt_shadow;

#define GI_PT_SHADOW 1   /* *sh holds a shadow ray to test */
#define GI_PT_CONTINUE 2 /* the path has a next ray */

void gi_pt_path_start(gi_pt_path *P, gi_vec3 org, gi_vec3 dir, const gi_rng *rng);
/* Handles the vertex where the path's ray hit (h): emission, next-event
 * estimation, the next ray. Returns GI_PT_SHADOW | GI_PT_CONTINUE flags. */
int gi_pt_vertex(const gi_pt_tracer *tr, gi_pt_path *P, const gi_hit *h, gi_pt_shadow *sh);
/* The scratch arrays of gi_pt_trace_paths, kept from one call to the next:
 * allocated afresh for every task they were megabytes that glibc handed back
 * to the kernel and faulted in again, page by page (~8% of a pt render). */
typedef struct gi_pt_wavefront {
    size_t cap;
    uint32_t *live, *owner;
    gi_hit *hits;
    uint8_t *hit_ok;
    gi_pt_shadow *sh;
} gi_pt_wavefront; /* zero-initialized is empty */

void gi_pt_wavefront_free(gi_pt_wavefront *wf);

/* Advances n paths to their ends breadth first: all rays of a bounce, then
 * all shading (a batch of vertices at a time, stage by stage), then all
 * shadow rays. Same result bits as gi_pt_radiance per path; independent
 * paths give the CPU room to overlap their latencies. wf grows to n. */
void gi_pt_trace_paths(const gi_pt_tracer *tr, gi_pt_wavefront *wf, gi_pt_path *paths,
                       size_t n);

void gi_pt_params_default(gi_pt_params *p);

extern const gi_method gi_method_pt;

#endif
