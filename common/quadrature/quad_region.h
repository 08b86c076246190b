/* quad_region: region records, and the engine that creates them.
 *
 * A region is an axis-aligned box of [0,1]^N (thesis sec. 5.2.1: start and
 * extent per axis) with its samples, its estimate, its error (eq. 4.4, and
 * eq. 4.5 as the priority), its split axis (eq. 4.8) and its image-plane
 * interpolant. Its summary is all of that but the samples: what the
 * coordinator keeps in its heap and what travels between coordinator and
 * workers (a worker evaluates a summary's samples again before refining it:
 * they are a pure function of the box).
 *
 * Boxes are dyadic (bisections of [0,1]), so coordinates are exact and a
 * region's id, a hash of its box, is the same wherever it is computed.
 *
 * Error: eq. 4.4 measures how well the rule pair agrees on the region's
 * integral, not on how the splat spreads it over pixels: a region with an
 * accurate total can still smear a sharp edge (the light's silhouette)
 * over the pixels it covers. Beyond the thesis, a region that spans more
 * than one pixel also counts its reconstruction error: the L1 norm over
 * pixels of its splat minus the splat of the next coarser reconstruction
 * of the same data (quad_interp.h), in integral units (pixel area 1/(W H)).
 *
 * The engine owns a slab of fixed-size records (samples included), recycled
 * through a free list (the thesis's object pool, sec. 5.3). */
#ifndef GI_QUAD_REGION_H
#define GI_QUAD_REGION_H

#include <stdint.h>

#include "gi_buf.h"
#include "quad_accum.h"
#include "quad_axis.h"
#include "quad_interp.h"
#include "quad_rule.h"

typedef struct gi_quad_summary {
    uint64_t id;
    double err;     /* eq. 4.5: err_raw weighted by image coverage, the heap key */
    double err_raw; /* eq. 4.4 || Q_high - Q_low ||_1, plus the reconstruction error */
    int32_t axis;   /* split axis; -1: cannot be split */
    double lo[GI_QUAD_MAX_DIMS], hi[GI_QUAD_MAX_DIMS];
    double est[GI_QUAD_MAX_CHANNELS];
    gi_quad_interp interp;
} gi_quad_summary;

/* The integrand: n points (n x dims, point-major) to n x channels values. */
typedef struct gi_quad_integrand {
    void (*eval)(void *user, size_t n, const double *pts, double *out);
    void *user;
} gi_quad_integrand;

typedef struct gi_quad_region {
    gi_quad_summary s;
    double *f; /* rule->points x channels samples */
    uint32_t slot;
    int live;
} gi_quad_region;

typedef struct gi_quad_engine {
    const gi_quad_rule *rule;
    gi_quad_axis_rule axis_rule;
    gi_quad_image image;
    gi_quad_integrand fn;
    uint64_t evals; /* integrand evaluations so far */
    /* Region slab: chunks of GI_QUAD_CHUNK records. */
    gi_quad_region **chunks;
    double **chunk_samples;
    uint32_t nchunks, used;
    uint32_t *free_slots;
    uint32_t nfree, live;
    /* Evaluation scratch. */
    double *pts, *vals;
    size_t *idx;
    /* Reconstruction errors are splatted here (image only). */
    gi_quad_accum scratch;
} gi_quad_engine;

#define GI_QUAD_CHUNK 64u

int gi_quad_engine_init(gi_quad_engine *e, const gi_quad_rule *rule, gi_quad_axis_rule axis_rule,
                        const gi_quad_image *image, const gi_quad_integrand *fn, gi_error *err);
void gi_quad_engine_free(gi_quad_engine *e);

/* A region on [lo, hi] with every sample evaluated. */
gi_quad_region *gi_quad_region_new(gi_quad_engine *e, const double *lo, const double *hi,
                                   gi_error *err);
/* Bisects r along r->s.axis into child[0] (lower half) and child[1]. The
 * children take what the rule lets them from r's samples; r is left as is. */
int gi_quad_region_split(gi_quad_engine *e, const gi_quad_region *r, gi_quad_region *child[2],
                         gi_error *err);
void gi_quad_region_release(gi_quad_engine *e, gi_quad_region *r);
static inline gi_quad_region *gi_quad_region_at(const gi_quad_engine *e, uint32_t slot)
{
    return &e->chunks[slot / GI_QUAD_CHUNK][slot % GI_QUAD_CHUNK];
}

/* A hash of the box: the region's id (heap tie-break, random stream). */
uint64_t gi_quad_box_id(const double *lo, const double *hi, int dims);

/* Summaries on the wire: the box, the id, errors, axis, estimate and
 * interpolant nodes, explicitly serialized. get checks the box (inside
 * [0,1], non-empty), that the id matches it, and that numbers are finite. */
void gi_quad_summary_put(gi_buf *b, const gi_quad_summary *s, const gi_quad_rule *rule);
int gi_quad_summary_get(gi_reader *r, const gi_quad_rule *rule, gi_quad_summary *s,
                        gi_error *err);
/* Bytes one summary takes on the wire. */
size_t gi_quad_summary_bytes(const gi_quad_rule *rule);

#endif
