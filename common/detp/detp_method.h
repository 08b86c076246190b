/* detp_method: the detp method's internals shared by its coordinator side
 * (detp_method.c, detp_outputs.c) and its worker side (detp_worker.c):
 * task kinds and payloads, result encodings, the coordinator's state. */
#ifndef GI_DETP_METHOD_H
#define GI_DETP_METHOD_H

#include <stdint.h>

#include "detp.h"
#include "detp_params.h"
#include "gi_image.h"
#include "gi_job.h"
#include "gi_method.h"

/* Task kinds and their payloads. */
enum {
    DETP_TASK_BATCH = 1,      /* u64 first photon, u64 end photon */
    DETP_TASK_VISIBILITY = 2, /* u32 first vertex, u32 end vertex */
    DETP_TASK_REFERENCE = 3,  /* u32 first, u32 end reference index */
    DETP_TASK_TILE = 4        /* gi_tile, str hash of the published radiance */
};

#define DETP_VIS_PER_TASK 2048
#define DETP_REF_PER_TASK 16
/* Streams of gi_rng besides the photons' (detp.h): disjoint ranges. */
#define DETP_STREAM_REFERENCE (3ull << 61)

/* A batch's result: timings and statistics, then per vertex the irradiance
 * contribution (RGB; for DETP the disc energy over the disc area) and the
 * number of crossings, dense or sparse (index deltas as varints), whichever
 * is smaller. The frame layer zstd-compresses it. */
typedef struct detp_batch_result {
    uint64_t photons, segments, rays;
    double trace_seconds, build_seconds, estimate_seconds;
    gi_detp_stats stats;
} detp_batch_result;

void detp_encode_batch(const detp_batch_result *h, const gi_detp_accum *acc, double scale,
                       gi_buf *out);
/* Adds the result's per-vertex values into irr (3 per vertex) and hits. */
int detp_decode_batch(gi_reader *r, uint32_t vertex_count, detp_batch_result *h, double *irr,
                      uint64_t *hits, gi_error *err);

/* The vertex of reference sample j (of m, over n vertices): evenly spread. */
static inline uint32_t detp_reference_vertex(uint32_t j, uint32_t m, uint32_t n)
{
    return (uint32_t)(((uint64_t)2 * j + 1) * n / (2 * (uint64_t)m));
}

enum { DETP_PHASE_BAKE, DETP_PHASE_IMAGE, DETP_PHASE_DONE };

typedef struct detp_state {
    int phase;
    uint32_t nv;
    double *irr;     /* 3 per vertex: summed irradiance contributions */
    uint64_t *hits;  /* crossings per vertex */
    float *visible;  /* per vertex, artifact control rule 2 (else NULL) */
    uint32_t nref;   /* reference vertices */
    double *ref;     /* 4 per reference vertex: R, G, B sums and luminance^2 sum */
    uint64_t batches, photons, segments;
    uint64_t rays_trace, rays_visibility, rays_reference, rays_image;
    double sec_trace, sec_build, sec_estimate, sec_visibility, sec_reference, sec_image;
    gi_detp_stats stats;
    double wall_start, wall_bake, wall_image; /* coordinator clock, not checkpointed */
    char hash[GI_HASH_HEX];                   /* published radiance (image phase) */
    gi_image img;
} detp_state;

/* Per-vertex results computed from the state (finish). */
typedef struct detp_vertex_data {
    float *irradiance; /* E, 3 per vertex */
    float *reflected;  /* rho E / pi */
    float *radiance;   /* reflected + emission */
} detp_vertex_data;

int detp_vertex_data_compute(const gi_job *job, const detp_state *st, detp_vertex_data *out,
                             gi_error *err);
void detp_vertex_data_free(detp_vertex_data *v);

/* Outputs (detp_outputs.c): PLY, the binary float file, the report. */
int detp_write_outputs(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                       gi_error *err);

/* Worker side (detp_worker.c). */
int detp_run(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err);

double detp_now(void);

#endif
