/* detp_multilist: the multilist Sphere Cache (thesis 1.8). Spheres built on a
 * miss are kept: each sphere may have several children, and a query walks
 * down from S_0 through children that hold its disc, building new children
 * (centred on the disc, by the plain Sphere Cache's rules) where none does.
 *
 * Size control, the two options of the thesis:
 *  - width z: at most z children per sphere; a new one replaces the least
 *    recently used child (and its subtree). z = 1 is the plain Sphere Cache.
 *  - sphere limit M_S: any number of children, at most M_S spheres besides
 *    S_0; a new one first evicts the least recently used leaf sphere that is
 *    not on the current path.
 * The thesis names FIFO, LRU and "highest priority" for eviction (digest
 * erratum 12); we use least recently used: a sphere nobody has walked
 * through for longest is the one least likely to hold the next discs. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp.h"
#include "detp_sphere.h"

#define NONE 0xFFFFFFFFu

typedef struct node {
    gi_vec3 c;
    float r;
    uint32_t level;
    uint32_t parent;
    uint32_t *rays; /* NULL at the root: every segment */
    size_t n;
    uint32_t *kids;
    uint32_t nkids, capkids;
    uint64_t used; /* query stamp of the last walk through it */
    int alive;
} node;

typedef struct forest {
    node *v;
    uint32_t count, cap;
    uint32_t free_head; /* dead nodes chained through .parent */
    uint32_t alive;     /* spheres besides the root */
} forest;

static uint32_t node_new(forest *f)
{
    uint32_t id;
    if (f->free_head != NONE) {
        id = f->free_head;
        f->free_head = f->v[id].parent;
    } else {
        if (f->count == f->cap) {
            f->cap = f->cap ? 2 * f->cap : 64;
            f->v = gi_xrealloc(f->v, f->cap * sizeof *f->v);
        }
        id = f->count++;
    }
    memset(&f->v[id], 0, sizeof f->v[id]);
    f->v[id].alive = 1;
    return id;
}

static void unlink_child(forest *f, uint32_t parent, uint32_t child)
{
    node *p = &f->v[parent];
    for (uint32_t i = 0; i < p->nkids; i++)
        if (p->kids[i] == child) {
            p->kids[i] = p->kids[--p->nkids];
            return;
        }
}

/* Frees a sphere and its subtree (the caller unlinks it from its parent). */
static void drop(forest *f, uint32_t id, gi_detp_stats *st)
{
    node *x = &f->v[id];
    for (uint32_t i = 0; i < x->nkids; i++)
        drop(f, f->v[id].kids[i], st);
    x = &f->v[id];
    free(x->rays);
    free(x->kids);
    x->rays = x->kids = NULL;
    x->alive = 0;
    x->parent = f->free_head;
    f->free_head = id;
    f->alive--;
    st->evictions++;
}

/* The least recently used leaf that is not `keep` (the sphere the query
 * stands in; its ancestors have children, so they are not leaves). */
static uint32_t lru_leaf(const forest *f, uint32_t keep)
{
    uint32_t best = NONE;
    for (uint32_t i = 1; i < f->count; i++) {
        const node *x = &f->v[i];
        if (!x->alive || x->nkids || i == keep)
            continue;
        if (best == NONE || x->used < f->v[best].used)
            best = i;
    }
    return best;
}

int gi_detp_multilist(const gi_detp_discs *d, const uint32_t *order, const gi_detp_segments *s,
                      const gi_detp_sc_params *p, gi_vec3 lo, gi_vec3 hi, gi_detp_accum *acc,
                      gi_detp_stats *st, gi_error *err)
{
    uint32_t max_levels = p->max_levels < GI_DETP_MAX_LEVELS - 1 ? p->max_levels
                                                                  : GI_DETP_MAX_LEVELS - 1;
    forest f = {NULL, 0, 0, NONE, 0};
    uint32_t root = node_new(&f);
    gi_detp_sphere_root(lo, hi, d->radius, &f.v[root].c, &f.v[root].r);
    f.v[root].n = s->count;
    float slack = gi_detp_sphere_slack(f.v[root].r);
    int rc = 0;
    for (uint32_t q = 0; q < d->count && rc == 0; q++) {
        uint32_t i = order ? order[q] : q;
        const gi_detp_disc *D = &d->d[i];
        uint64_t stamp = q + 1;
        uint32_t at = root;
        int missed = 0;
        st->queries++;
        for (;;) {
            node *x = &f.v[at];
            x->used = stamp;
            uint32_t next = NONE;
            for (uint32_t k = 0; k < x->nkids; k++) {
                const node *c = &f.v[x->kids[k]];
                if (gi_detp_sphere_holds(c->c, c->r, D->c, d->radius)) {
                    next = x->kids[k];
                    break;
                }
            }
            if (next != NONE) {
                at = next;
                continue;
            }
            float r = x->r * (float)p->q;
            if (x->level >= max_levels || r < d->radius || x->n < p->r_min)
                break;
            /* Make room for a new child of `at`. */
            if (p->sphere_limit > 0) {
                if (f.alive >= p->sphere_limit) {
                    uint32_t victim = lru_leaf(&f, at);
                    if (victim == NONE)
                        break;
                    unlink_child(&f, f.v[victim].parent, victim);
                    drop(&f, victim, st);
                }
            } else if (x->nkids >= (p->width ? p->width : 1)) {
                uint32_t victim = x->kids[0];
                for (uint32_t k = 1; k < x->nkids; k++)
                    if (f.v[x->kids[k]].used < f.v[victim].used)
                        victim = x->kids[k];
                unlink_child(&f, at, victim);
                drop(&f, victim, st);
            }
            uint32_t id = node_new(&f);
            x = &f.v[at]; /* node_new may have moved the array */
            node *c = &f.v[id];
            c->rays = malloc((x->n ? x->n : 1) * sizeof *c->rays);
            if (!c->rays) {
                c->alive = 0;
                rc = gi_fail(err, GI_ENOMEM, "multilist sphere cache: out of memory");
                break;
            }
            c->c = D->c;
            c->r = r;
            c->level = x->level + 1;
            c->parent = at;
            c->used = stamp;
            float rr = (r + slack) * (r + slack);
            for (size_t j = 0; j < x->n; j++) {
                uint32_t g = x->rays ? x->rays[j] : (uint32_t)j;
                if (gi_detp_segment_meets_sphere(&s->v[g], c->c, rr))
                    c->rays[c->n++] = g;
            }
            if (x->nkids == x->capkids) {
                x->capkids = x->capkids ? 2 * x->capkids : 4;
                x->kids = gi_xrealloc(x->kids, x->capkids * sizeof *x->kids);
            }
            x->kids[x->nkids++] = id;
            f.alive++;
            st->sphere_tests += x->n;
            st->spheres_built++;
            st->level_faults[c->level]++;
            st->level_rays[c->level] += c->n;
            if (c->level > st->max_level)
                st->max_level = c->level;
            if ((uint64_t)f.alive + 1 > st->max_spheres)
                st->max_spheres = (uint64_t)f.alive + 1;
            missed = 1;
            at = id;
        }
        if (rc)
            break;
        st->faults += (uint64_t)missed;
        const node *in = &f.v[at];
        st->inner_rays += in->n;
        st->disc_tests += in->n;
        for (size_t j = 0; j < in->n; j++) {
            const gi_detp_segment *g = &s->v[in->rays ? in->rays[j] : (uint32_t)j];
            if (gi_detp_crosses(D, d->r2, g)) {
                gi_detp_accum_add(acc, i, g);
                st->crossings++;
            }
        }
    }
    for (uint32_t k = 0; k < f.count; k++)
        if (f.v[k].alive) {
            free(f.v[k].rays);
            free(f.v[k].kids);
        }
    free(f.v);
    return rc;
}
