/* detp_photon_map: photon maps [Jensen 95/96] as density estimation at the
 * discs' centres (thesis 1.4, 3.5).
 *
 * The hits (segment ends) go into a balanced kd-tree; at each sample the k
 * nearest hits arriving on its front side are found, and the estimate is
 *     g(R) = (k - 1) phi / (pi R^2)       (eq. 3.20)
 * with R the distance to the k-th: the energy of the k-1 nearest over the
 * area of the circle through the k-th. This is unbiased on a constant
 * density (eqs. 3.15-3.21); summing all k, as the literature does,
 * over-estimates by k / (k - 1) (kept as an option to show it).
 *
 * In a farm each batch is its own photon map: the k-1 estimate of a batch
 * is unbiased for that batch's share of the power, so the batches' sum is
 * an unbiased estimate of the whole (with the larger radius of fewer
 * photons). A sample with fewer than k photons in a batch gets nothing
 * from it. */
#include <math.h>
#include <stdlib.h>

#include "detp.h"

typedef struct kd {
    const gi_detp_segments *s;
    uint32_t *idx; /* hits; the tree is implicit: node = middle of its range */
    gi_vec3 *pos;  /* hit point of idx[i] */
    uint8_t *axis; /* split axis of the node at each position */
    uint32_t n;
} kd;

static float coord(gi_vec3 p, int a) { return a == 0 ? p.x : a == 1 ? p.y : p.z; }

/* Puts the k-th smallest (by axis a) of [lo, hi) at position k, smaller
 * ones before it and larger ones after (Wirth's selection). */
static void swap_hits(kd *t, int64_t i, int64_t j)
{
    gi_vec3 p = t->pos[i];
    t->pos[i] = t->pos[j];
    t->pos[j] = p;
    uint32_t x = t->idx[i];
    t->idx[i] = t->idx[j];
    t->idx[j] = x;
}

static void select_kth(kd *t, uint32_t lo_u, uint32_t hi_u, uint32_t k_u, int a)
{
    int64_t lo = lo_u, hi = (int64_t)hi_u - 1, k = k_u;
    while (lo < hi) {
        float pivot = coord(t->pos[k], a);
        int64_t i = lo, j = hi;
        do {
            while (coord(t->pos[i], a) < pivot)
                i++;
            while (pivot < coord(t->pos[j], a))
                j--;
            if (i <= j) {
                swap_hits(t, i, j);
                i++;
                j--;
            }
        } while (i <= j);
        if (j < k)
            lo = i;
        if (k < i)
            hi = j;
    }
}

static void build(kd *t, uint32_t lo, uint32_t hi)
{
    if (hi - lo < 2) {
        if (hi > lo)
            t->axis[lo] = 0;
        return;
    }
    gi_vec3 mn = t->pos[lo], mx = mn;
    for (uint32_t i = lo + 1; i < hi; i++) {
        mn = gi_min_v3(mn, t->pos[i]);
        mx = gi_max_v3(mx, t->pos[i]);
    }
    gi_vec3 e = gi_sub(mx, mn);
    int a = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
    uint32_t mid = lo + (hi - lo) / 2;
    select_kth(t, lo, hi, mid, a);
    t->axis[mid] = (uint8_t)a;
    build(t, lo, mid);
    build(t, mid + 1, hi);
}

/* k nearest as a max-heap on squared distance. */
typedef struct heap {
    float *d2;
    uint32_t *id;
    uint32_t n, k;
} heap;

static void heap_push(heap *h, float d2, uint32_t id)
{
    if (h->n < h->k) {
        uint32_t i = h->n++;
        while (i > 0) {
            uint32_t p = (i - 1) / 2;
            if (h->d2[p] >= d2)
                break;
            h->d2[i] = h->d2[p];
            h->id[i] = h->id[p];
            i = p;
        }
        h->d2[i] = d2;
        h->id[i] = id;
        return;
    }
    if (d2 >= h->d2[0])
        return;
    uint32_t i = 0;
    for (;;) { /* sift the new value down from the root */
        uint32_t l = 2 * i + 1, r = l + 1, m = i;
        float mv = d2;
        if (l < h->n && h->d2[l] > mv) {
            m = l;
            mv = h->d2[l];
        }
        if (r < h->n && h->d2[r] > mv)
            m = r;
        if (m == i)
            break;
        h->d2[i] = h->d2[m];
        h->id[i] = h->id[m];
        i = m;
    }
    h->d2[i] = d2;
    h->id[i] = id;
}

static void knn(const kd *t, uint32_t lo, uint32_t hi, gi_vec3 q, gi_vec3 n, heap *h,
                uint64_t *visited)
{
    while (hi > lo) {
        uint32_t mid = lo + (hi - lo) / 2;
        gi_vec3 p = t->pos[mid];
        const gi_detp_segment *g = &t->s->v[t->idx[mid]];
        (*visited)++;
        if (gi_dot(g->dir, n) < 0.0f) { /* arrives on the front side */
            gi_vec3 d = gi_sub(p, q);
            heap_push(h, gi_dot(d, d), t->idx[mid]);
        }
        int a = t->axis[mid];
        float delta = coord(q, a) - coord(p, a);
        uint32_t near_lo = delta < 0.0f ? lo : mid + 1, near_hi = delta < 0.0f ? mid : hi;
        uint32_t far_lo = delta < 0.0f ? mid + 1 : lo, far_hi = delta < 0.0f ? hi : mid;
        knn(t, near_lo, near_hi, q, n, h, visited);
        if (h->n == h->k && delta * delta >= h->d2[0])
            return;
        lo = far_lo;
        hi = far_hi;
    }
}

int gi_detp_photon_map(const gi_detp_discs *d, const gi_detp_segments *s, uint32_t k,
                       int k_minus_one, gi_detp_accum *acc, gi_detp_stats *st, gi_error *err)
{
    if (k < 2)
        return gi_fail(err, GI_EINVAL, "photon map: k must be at least 2");
    kd t = {s, NULL, NULL, NULL, 0};
    uint32_t hits = 0;
    for (size_t j = 0; j < s->count; j++)
        hits += s->v[j].hit_tri != GI_DETP_NO_HIT;
    t.idx = gi_try_malloc(((size_t)hits + 1) * sizeof *t.idx, err, "photon map");
    t.pos = gi_try_malloc(((size_t)hits + 1) * sizeof *t.pos, err, "photon map");
    t.axis = gi_try_malloc((size_t)hits + 1, err, "photon map");
    heap h = {gi_xmalloc(k * sizeof(float)), gi_xmalloc(k * sizeof(uint32_t)), 0, k};
    int rc = (t.idx && t.pos && t.axis) ? 0 : -1;
    if (rc == 0) {
        for (size_t j = 0; j < s->count; j++) {
            const gi_detp_segment *g = &s->v[j];
            if (g->hit_tri == GI_DETP_NO_HIT)
                continue;
            t.idx[t.n] = (uint32_t)j;
            t.pos[t.n++] = gi_madd(g->org, g->dir, g->t_hit);
        }
        build(&t, 0, t.n);
        uint32_t used = k_minus_one ? k - 1 : k;
        for (uint32_t i = 0; i < d->count; i++) {
            h.n = 0;
            uint64_t visited = 0;
            knn(&t, 0, t.n, d->d[i].c, d->d[i].n, &h, &visited);
            st->disc_tests += visited;
            if (h.n < k || !(h.d2[0] > 0.0f))
                continue;
            /* The heap's root is the k-th nearest; sum the others (and the
             * root too in the k version). */
            double e[3] = {0, 0, 0};
            for (uint32_t m = 0; m < h.n; m++) {
                if (m == 0 && k_minus_one)
                    continue;
                const gi_detp_segment *g = &s->v[h.id[m]];
                e[0] += g->energy.x;
                e[1] += g->energy.y;
                e[2] += g->energy.z;
            }
            double area = GI_PI * (double)h.d2[0]; /* eq. 3.20 */
            for (int c = 0; c < 3; c++)
                acc->energy[3 * (size_t)i + c] += e[c] / area;
            acc->hits[i] += used;
            st->photons_found += used;
            st->crossings += used;
        }
    }
    free(t.idx);
    free(t.pos);
    free(t.axis);
    free(h.d2);
    free(h.id);
    return rc;
}
