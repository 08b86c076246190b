/* gi_polygon: fan or ear-clip a planar polygon into triangles. */
#include "gi_polygon.h"

#include <math.h>
#include <stdlib.h>

#include "gi_error.h"

typedef struct {
    double u, v;
} pt2;

/* Twice the signed area of (a, b, c), positive counter-clockwise. */
static double cross2(pt2 a, pt2 b, pt2 c)
{
    return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
}

/* Segments ab and cd cross at a point inside both. */
static int segments_cross(pt2 a, pt2 b, pt2 c, pt2 d)
{
    double d1 = cross2(a, b, c), d2 = cross2(a, b, d), d3 = cross2(c, d, a),
           d4 = cross2(c, d, b);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

/* Some two edges that share no vertex cross. */
static int edges_cross(const pt2 *p, int n)
{
    for (int i = 0; i < n; i++)
        for (int j = i + 2; j < n; j++) {
            if (i == 0 && j == n - 1)
                continue; /* neighbours through the closing edge */
            if (segments_cross(p[i], p[i + 1], p[j], p[(j + 1) % n]))
                return 1;
        }
    return 0;
}

/* The boundary turns once around: with every corner convex, the polygon is
 * convex and not a star (which turns twice). */
static int turns_once(const pt2 *p, int n)
{
    double total = 0;
    for (int i = 0; i < n; i++) {
        pt2 a = p[(i + n - 1) % n], b = p[i], c = p[(i + 1) % n];
        double in = atan2(b.v - a.v, b.u - a.u), out = atan2(c.v - b.v, c.u - b.u);
        double turn = out - in;
        while (turn > M_PI)
            turn -= 2 * M_PI;
        while (turn < -M_PI)
            turn += 2 * M_PI;
        total += turn;
    }
    return fabs(total) < 3 * M_PI;
}

static void emit(uint32_t *tri, uint32_t a, uint32_t b, uint32_t c)
{
    tri[0] = a;
    tri[1] = b;
    tri[2] = c;
}

int gi_polygon_triangulate(const gi_vec3 *pos, const uint32_t *ix, int n, uint32_t *tris)
{
    /* Newell's normal: the polygon's orientation, also when it is not quite
     * planar (measured data such as the Cornell box's walls). */
    double nrm[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        gi_vec3 a = pos[ix[i]], b = pos[ix[(i + 1) % n]];
        nrm[0] += ((double)a.y - b.y) * ((double)a.z + b.z);
        nrm[1] += ((double)a.z - b.z) * ((double)a.x + b.x);
        nrm[2] += ((double)a.x - b.x) * ((double)a.y + b.y);
    }
    int k = fabs(nrm[0]) >= fabs(nrm[1]) ? 0 : 1;
    if (fabs(nrm[2]) > fabs(nrm[k]))
        k = 2;
    pt2 *p = gi_xmalloc((size_t)n * sizeof *p);
    double s = nrm[k] >= 0 ? 1.0 : -1.0; /* counter-clockwise seen along the normal */
    for (int i = 0; i < n; i++) {
        const float *c = &pos[ix[i]].x;
        p[i] = (pt2){c[(k + 1) % 3], s * c[(k + 2) % 3]};
    }
    /* Convex (or without area: its degenerate triangles are counted, as
     * before, by the scene's checks): the fan from the first vertex. A
     * quadrilateral whose corners all turn one way is convex; from five
     * corners on, a star turns them all one way too. */
    int convex = 1;
    for (int i = 0; i < n && convex; i++)
        convex = cross2(p[(i + n - 1) % n], p[i], p[(i + 1) % n]) >= 0;
    if (nrm[k] == 0 || (convex && (n < 5 || turns_once(p, n)))) {
        for (int t = 1; t + 1 < n; t++)
            emit(&tris[3 * (t - 1)], ix[0], ix[t], ix[t + 1]);
        free(p);
        return n - 2;
    }
    if (n > GI_POLYGON_MAX_CONCAVE || edges_cross(p, n)) {
        free(p);
        return -1;
    }
    /* Ear clipping, from the second vertex on (a convex run is cut like
     * the fan): an ear is a convex corner whose triangle holds no other
     * vertex of what is left. */
    int *next = gi_xmalloc((size_t)n * sizeof *next), *prev = gi_xmalloc((size_t)n * sizeof *prev);
    for (int i = 0; i < n; i++) {
        next[i] = (i + 1) % n;
        prev[i] = (i + n - 1) % n;
    }
    int left = n, out = 0, i = 1, tried = 0, rc = n - 2;
    while (left > 3) {
        int a = prev[i], c = next[i];
        int ear = cross2(p[a], p[i], p[c]) > 0;
        for (int j = next[c]; ear && j != a; j = next[j])
            ear = !(cross2(p[a], p[i], p[j]) > 0 && cross2(p[i], p[c], p[j]) > 0 &&
                    cross2(p[c], p[a], p[j]) > 0);
        if (!ear) {
            i = c;
            if (++tried > left) { /* a whole turn without an ear: edges cross */
                rc = -1;
                break;
            }
            continue;
        }
        emit(&tris[3 * out++], ix[a], ix[i], ix[c]);
        next[a] = c;
        prev[c] = a;
        left--;
        i = c;
        tried = 0;
    }
    if (rc >= 0)
        emit(&tris[3 * out], ix[prev[i]], ix[i], ix[next[i]]);
    free(next);
    free(prev);
    free(p);
    return rc;
}
