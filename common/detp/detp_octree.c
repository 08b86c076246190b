/* detp_octree: Disc Indexing with an octree (thesis 1.9, Fig. 2.2).
 *
 * The loops are swapped: instead of looking for the segments near each
 * disc, every segment walks an octree over the discs and adds its energy
 * to each disc it crosses. Discs are stored in every leaf their bounding
 * box overlaps; a node with more than max_leaf discs is split until
 * max_depth (and not at all if every child would get every disc: large
 * overlapping discs, the thesis's out-of-memory case). Segments walk the
 * tree with the parametric algorithm of [Revelles 00] (mirror the ray so its
 * direction is positive, then visit children in the order the ray enters
 * them), clipped to [0, t_end]. A disc in several leaves along one segment
 * is tested once per segment (a mailbox per disc): the thesis leaves this
 * open.
 *
 * Tree traversal is conservative (boxes grown by a small margin, parameters
 * in double) and the final word is gi_detp_crosses, so the pairs found are
 * exactly basic DETP's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp.h"

#define LEAF 0xFFFFFFFFu
#define MAX_DEPTH 16
#define MAX_REFS ((uint64_t)1 << 29) /* 2 GiB of disc references */

typedef struct onode {
    uint32_t child;        /* first of 8 consecutive children, or LEAF */
    uint32_t start, count; /* a leaf's discs in refs[] */
} onode;

struct gi_detp_octree {
    const gi_detp_discs *discs;
    double lo[3], size; /* the root cube */
    double margin;      /* added to boxes and to parameter ranges */
    onode *nodes;
    uint32_t node_count, node_cap;
    uint32_t *refs;
    uint64_t ref_count, ref_cap;
    uint32_t *mail; /* per disc: the last segment that tested it */
    double *boxes;  /* per disc during the build: lo[3], hi[3] (grown by margin) */
    uint32_t stamp;
    int depth; /* deepest leaf */
    int max_depth;
    uint32_t max_leaf;
    /* During a query. */
    const gi_detp_segment *seg;
    gi_detp_accum *acc;
    gi_detp_stats *st;
    int mirror;
};

static uint32_t add_nodes(gi_detp_octree *o, uint32_t n)
{
    if (o->node_count + n > o->node_cap) {
        while (o->node_count + n > o->node_cap)
            o->node_cap = o->node_cap ? 2 * o->node_cap : 64;
        o->nodes = gi_xrealloc(o->nodes, o->node_cap * sizeof *o->nodes);
    }
    uint32_t first = o->node_count;
    o->node_count += n;
    return first;
}

/* Half extents of each disc's bounding box, per axis: r sqrt(1 - n_a^2). */
static void disc_box(const gi_detp_disc *D, float r, double margin, double lo[3], double hi[3])
{
    double n[3] = {D->n.x, D->n.y, D->n.z}, c[3] = {D->c.x, D->c.y, D->c.z};
    for (int a = 0; a < 3; a++) {
        double h = r * sqrt(fmax(0.0, 1.0 - n[a] * n[a])) + margin;
        lo[a] = c[a] - h;
        hi[a] = c[a] + h;
    }
}

static int build(gi_detp_octree *o, uint32_t node, const double lo[3], double size, int depth,
                 uint32_t *ids, uint32_t n, gi_error *err)
{
    if (depth > o->depth)
        o->depth = depth;
    if (n > o->max_leaf && depth < o->max_depth) {
        double half = 0.5 * size;
        uint32_t *kid_ids[8];
        uint32_t kid_n[8];
        int useful = 0;
        for (int k = 0; k < 8; k++) {
            double clo[3] = {lo[0] + ((k & 4) ? half : 0), lo[1] + ((k & 2) ? half : 0),
                             lo[2] + ((k & 1) ? half : 0)};
            kid_ids[k] = gi_try_malloc(((size_t)n + 1) * sizeof(uint32_t), err, "octree node");
            kid_n[k] = 0;
            if (!kid_ids[k]) {
                for (int j = 0; j < k; j++)
                    free(kid_ids[j]);
                return -1;
            }
            for (uint32_t i = 0; i < n; i++) {
                const double *blo = &o->boxes[6 * (size_t)ids[i]], *bhi = blo + 3;
                if (blo[0] <= clo[0] + half && bhi[0] >= clo[0] && blo[1] <= clo[1] + half &&
                    bhi[1] >= clo[1] && blo[2] <= clo[2] + half && bhi[2] >= clo[2])
                    kid_ids[k][kid_n[k]++] = ids[i];
            }
            useful |= kid_n[k] < n;
        }
        if (useful) {
            uint32_t first = add_nodes(o, 8);
            o->nodes[node].child = first;
            o->nodes[node].start = o->nodes[node].count = 0;
            int rc = 0;
            for (int k = 0; k < 8; k++) {
                double clo[3] = {lo[0] + ((k & 4) ? half : 0), lo[1] + ((k & 2) ? half : 0),
                                 lo[2] + ((k & 1) ? half : 0)};
                if (rc == 0)
                    rc = build(o, first + (uint32_t)k, clo, half, depth + 1, kid_ids[k],
                               kid_n[k], err);
                free(kid_ids[k]);
            }
            return rc;
        }
        for (int k = 0; k < 8; k++)
            free(kid_ids[k]);
    }
    /* A leaf. */
    if (o->ref_count + n > MAX_REFS)
        return gi_fail(err, GI_ENOMEM,
                       "disc octree: more than %llu disc references (discs too large for "
                       "the depth: lower octree.max_depth or raise octree.max_leaf)",
                       (unsigned long long)MAX_REFS);
    if (o->ref_count + n > o->ref_cap) {
        uint64_t cap = o->ref_cap ? o->ref_cap : 1024;
        while (cap < o->ref_count + n)
            cap *= 2;
        uint32_t *r = realloc(o->refs, cap * sizeof *r);
        if (!r)
            return gi_fail(err, GI_ENOMEM, "disc octree: out of memory");
        o->refs = r;
        o->ref_cap = cap;
    }
    o->nodes[node].child = LEAF;
    o->nodes[node].start = (uint32_t)o->ref_count;
    o->nodes[node].count = n;
    if (n) {
        memcpy(o->refs + o->ref_count, ids, (size_t)n * sizeof *ids);
        o->ref_count += n;
    }
    return 0;
}

int gi_detp_octree_build(const gi_detp_discs *d, const gi_detp_octree_params *p,
                         gi_detp_octree **out, gi_error *err)
{
    *out = NULL;
    gi_detp_octree *o = gi_xcalloc(1, sizeof *o);
    o->discs = d;
    o->max_leaf = p->max_leaf ? p->max_leaf : 1;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < d->count; i++) {
        double blo[3], bhi[3];
        disc_box(&d->d[i], d->radius, 0.0, blo, bhi);
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], blo[a]);
            hi[a] = fmax(hi[a], bhi[a]);
        }
    }
    if (d->count == 0)
        lo[0] = lo[1] = lo[2] = hi[0] = hi[1] = hi[2] = 0.0;
    double size = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (!(size > 0.0))
        size = 1.0;
    o->margin = 1e-5 * size;
    o->size = size + 4.0 * o->margin;
    for (int a = 0; a < 3; a++)
        o->lo[a] = lo[a] - 2.0 * o->margin;
    /* Automatic depth: voxels about the disc diameter (thesis 3.11), one
     * level deeper (the thesis's measurements favour depth 8 at 1%). */
    int depth = p->max_depth;
    if (depth <= 0) {
        double v = d->radius > 0.0f ? o->size / (2.0 * d->radius) : 1.0;
        depth = v > 1.0 ? (int)ceil(log2(v)) + 1 : 1;
    }
    o->max_depth = depth < MAX_DEPTH ? depth : MAX_DEPTH;
    o->mail = gi_try_calloc((size_t)d->count + 1, sizeof *o->mail, err, "octree mailboxes");
    uint32_t *all = gi_try_malloc(((size_t)d->count + 1) * sizeof *all, err, "octree root");
    o->boxes = gi_try_malloc(((size_t)d->count + 1) * 6 * sizeof *o->boxes, err, "octree boxes");
    int rc = (o->mail && all && o->boxes) ? 0 : -1;
    if (rc == 0) {
        for (uint32_t i = 0; i < d->count; i++) {
            all[i] = i;
            disc_box(&d->d[i], d->radius, o->margin, &o->boxes[6 * (size_t)i],
                     &o->boxes[6 * (size_t)i + 3]);
        }
        add_nodes(o, 1);
        rc = build(o, 0, o->lo, o->size, 0, all, d->count, err);
    }
    free(all);
    free(o->boxes);
    o->boxes = NULL;
    if (rc) {
        gi_detp_octree_free(o);
        return -1;
    }
    *out = o;
    return 0;
}

void gi_detp_octree_free(gi_detp_octree *o)
{
    if (!o)
        return;
    free(o->nodes);
    free(o->refs);
    free(o->mail);
    free(o);
}

void gi_detp_octree_shape(const gi_detp_octree *o, int *depth, uint64_t *nodes,
                          uint64_t *leaves, uint64_t *refs)
{
    uint64_t nl = 0;
    for (uint32_t i = 0; i < o->node_count; i++)
        nl += o->nodes[i].child == LEAF;
    *depth = o->depth;
    *nodes = o->node_count;
    *leaves = nl;
    *refs = o->ref_count;
}

static void visit_leaf(gi_detp_octree *o, const onode *n)
{
    const gi_detp_discs *d = o->discs;
    const gi_detp_segment *g = o->seg;
    for (uint32_t k = 0; k < n->count; k++) {
        uint32_t i = o->refs[n->start + k];
        if (o->mail[i] == o->stamp)
            continue;
        o->mail[i] = o->stamp;
        o->st->disc_tests++;
        if (gi_detp_crosses(&d->d[i], d->r2, g)) {
            gi_detp_accum_add(o->acc, i, g);
            o->st->crossings++;
        }
    }
}

/* Revelles' first_node / new_node. */
static int first_node(double tx0, double ty0, double tz0, double txm, double tym, double tzm)
{
    int a = 0;
    if (tx0 > ty0 && tx0 > tz0) { /* entry plane YZ */
        a |= (tym < tx0) ? 2 : 0;
        a |= (tzm < tx0) ? 1 : 0;
    } else if (ty0 > tz0) { /* XZ */
        a |= (txm < ty0) ? 4 : 0;
        a |= (tzm < ty0) ? 1 : 0;
    } else { /* XY */
        a |= (txm < tz0) ? 4 : 0;
        a |= (tym < tz0) ? 2 : 0;
    }
    return a;
}

static int new_node(double tx, int x, double ty, int y, double tz, int z)
{
    if (tx < ty)
        return tx < tz ? x : z;
    return ty < tz ? y : z;
}

static void proc_subtree(gi_detp_octree *o, uint32_t ni, double tx0, double ty0, double tz0,
                         double tx1, double ty1, double tz1)
{
    double m = o->margin;
    if (tx1 < -m || ty1 < -m || tz1 < -m)
        return; /* behind the origin */
    if (fmax(tx0, fmax(ty0, tz0)) > (double)o->seg->t_end + m)
        return; /* past the end of the segment */
    const onode *n = &o->nodes[ni];
    o->st->node_visits++;
    if (n->child == LEAF) {
        visit_leaf(o, n);
        return;
    }
    double txm = 0.5 * (tx0 + tx1), tym = 0.5 * (ty0 + ty1), tzm = 0.5 * (tz0 + tz1);
    int a = o->mirror;
    uint32_t c = n->child;
    int cur = first_node(tx0, ty0, tz0, txm, tym, tzm);
    while (cur < 8) {
        switch (cur) {
        case 0:
            proc_subtree(o, c + (uint32_t)a, tx0, ty0, tz0, txm, tym, tzm);
            cur = new_node(txm, 4, tym, 2, tzm, 1);
            break;
        case 1:
            proc_subtree(o, c + (uint32_t)(1 ^ a), tx0, ty0, tzm, txm, tym, tz1);
            cur = new_node(txm, 5, tym, 3, tz1, 8);
            break;
        case 2:
            proc_subtree(o, c + (uint32_t)(2 ^ a), tx0, tym, tz0, txm, ty1, tzm);
            cur = new_node(txm, 6, ty1, 8, tzm, 3);
            break;
        case 3:
            proc_subtree(o, c + (uint32_t)(3 ^ a), tx0, tym, tzm, txm, ty1, tz1);
            cur = new_node(txm, 7, ty1, 8, tz1, 8);
            break;
        case 4:
            proc_subtree(o, c + (uint32_t)(4 ^ a), txm, ty0, tz0, tx1, tym, tzm);
            cur = new_node(tx1, 8, tym, 6, tzm, 5);
            break;
        case 5:
            proc_subtree(o, c + (uint32_t)(5 ^ a), txm, ty0, tzm, tx1, tym, tz1);
            cur = new_node(tx1, 8, tym, 7, tz1, 8);
            break;
        case 6:
            proc_subtree(o, c + (uint32_t)(6 ^ a), txm, tym, tz0, tx1, ty1, tzm);
            cur = new_node(tx1, 8, ty1, 8, tzm, 7);
            break;
        default:
            proc_subtree(o, c + (uint32_t)(7 ^ a), txm, tym, tzm, tx1, ty1, tz1);
            cur = 8;
            break;
        }
    }
}

void gi_detp_octree_estimate(gi_detp_octree *o, const gi_detp_segments *s, gi_detp_accum *acc,
                             gi_detp_stats *st)
{
    o->acc = acc;
    o->st = st;
    for (size_t j = 0; j < s->count; j++) {
        const gi_detp_segment *g = &s->v[j];
        if (++o->stamp == 0) { /* wrapped: forget every mailbox */
            memset(o->mail, 0, (size_t)o->discs->count * sizeof *o->mail);
            o->stamp = 1;
        }
        o->seg = g;
        double org[3] = {g->org.x, g->org.y, g->org.z}, dir[3] = {g->dir.x, g->dir.y, g->dir.z};
        double t0[3], t1[3];
        int a = 0;
        for (int k = 0; k < 3; k++) {
            double lo = o->lo[k], hi = o->lo[k] + o->size;
            if (dir[k] < 0.0) {
                org[k] = lo + hi - org[k];
                dir[k] = -dir[k];
                a |= 4 >> k;
            }
            /* A zero component: parameters become huge but finite, with
             * the right signs (no 0 * inf). */
            double dk = dir[k] > 1e-30 ? dir[k] : 1e-30;
            t0[k] = (lo - org[k]) / dk;
            t1[k] = (hi - org[k]) / dk;
        }
        o->mirror = a;
        double tmin = fmax(t0[0], fmax(t0[1], t0[2])), tmax = fmin(t1[0], fmin(t1[1], t1[2]));
        if (tmin < tmax)
            proc_subtree(o, 0, t0[0], t0[1], t0[2], t1[0], t1[1], t1[2]);
    }
}
