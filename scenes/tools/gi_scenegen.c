/* gi_scenegen: procedural benchmark scenes (nothing downloaded).
 *
 *   gi_scenegen tree DIR [--seed N]
 *       A tree scene like the thesis's "Escena del Arbol" (App. A, 4.10): a
 *       1 x 1 floor of triangles about 2% of the scene across, a tree of
 *       about 67,000 triangles about 1-1.5% across (a branching trunk of
 *       cylinders and clusters of foliage blobs, bounding box about
 *       0.35 x 0.67 x 0.35 like the thesis's), 71,966 triangles in all, plus
 *       a 500-triangle torus as the mobile object. The thesis does not
 *       describe its lights; ours is a 0.3 x 0.3 white area light at
 *       height 1 facing down, so the scene's bounding box is the unit cube
 *       and "1%" means 0.01. Writes DIR/floor.obj, bark.obj, leaves.obj,
 *       mobile.obj and DIR/scene.json.
 *
 *   gi_scenegen cornell-mobile BASE.json OUT.json --radius F
 *       The Cornell box (BASE, e.g. scenes/cornell-box/scene.json) with a
 *       sphere mobile of radius F times the box's width (thesis Table A.14:
 *       1.25% to 50%). As in the thesis the sphere keeps its mesh resolution
 *       whatever its size (icosphere, 1280 triangles). Its centre,
 *       (150, 395, 150), is the point of the room farthest from the walls,
 *       the blocks, the ceiling and the open front all the way to
 *       (278, 395, 150): a sphere of radius up to 150 (27%) moved there
 *       along x touches nothing, so it is lit on every side and never partly
 *       inside a block (the room's middle is 12 mm from the tall block). A
 *       50% sphere is as wide as the box and is free nowhere.
 *
 *   gi_scenegen grid DIR --objects N [--mesh | --mesh-files]
 *       Many small objects: N cubes of side 0.5 in a square grid of unit
 *       cells on the floor of a closed room (an inward box), lit by a quad
 *       under its ceiling; four materials in turn. Each cube is a "box"
 *       object, or with --mesh a reference to DIR/cube.obj (whose material
 *       then becomes one scene material per object, as mesh files' do), or
 *       with --mesh-files to a file of its own, DIR/cubeI.obj (the same
 *       bytes: a scene of many distinct mesh files, each imported apart).
 *       Writes DIR/scene.json (and the OBJs). The scene that load and
 *       per-object costs are measured on (bench/many_objects.sh).
 *
 * Deterministic: the same arguments give the same bytes. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "gi_fs.h"
#include "gi_rng.h"

#define PI 3.14159265358979323846
#define TREE_TRIANGLES 71966 /* the thesis's Tree Scene, without its mobile */

typedef struct { double x, y, z; } v3;

static v3 V(double x, double y, double z) { v3 r = {x, y, z}; return r; }
static v3 add(v3 a, v3 b) { return V(a.x + b.x, a.y + b.y, a.z + b.z); }
static v3 sub(v3 a, v3 b) { return V(a.x - b.x, a.y - b.y, a.z - b.z); }
static v3 mul(v3 a, double s) { return V(a.x * s, a.y * s, a.z * s); }
static double dot(v3 a, v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static v3 cross(v3 a, v3 b)
{
    return V(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static v3 unit(v3 a) { return mul(a, 1.0 / sqrt(dot(a, a))); }

/* A mesh being written (vertices and triangles, OBJ numbering). */
typedef struct mesh {
    v3 *v;
    size_t nv, capv;
    unsigned *t;
    size_t nt, capt;
} mesh;

static size_t vert(mesh *m, v3 p)
{
    if (m->nv == m->capv) {
        m->capv = m->capv ? 2 * m->capv : 1024;
        m->v = realloc(m->v, m->capv * sizeof *m->v);
        if (!m->v)
            abort();
    }
    m->v[m->nv] = p;
    return m->nv++;
}

static void tri(mesh *m, size_t a, size_t b, size_t c)
{
    if (m->nt == m->capt) {
        m->capt = m->capt ? 2 * m->capt : 1024;
        m->t = realloc(m->t, m->capt * 3 * sizeof *m->t);
        if (!m->t)
            abort();
    }
    m->t[3 * m->nt] = (unsigned)a;
    m->t[3 * m->nt + 1] = (unsigned)b;
    m->t[3 * m->nt + 2] = (unsigned)c;
    m->nt++;
}

static int write_obj(const char *dir, const char *name, const mesh *m)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", path, strerror(errno));
        return -1;
    }
    fprintf(f, "# gi_scenegen: %zu vertices, %zu triangles\n", m->nv, m->nt);
    for (size_t i = 0; i < m->nv; i++)
        fprintf(f, "v %.6f %.6f %.6f\n", m->v[i].x, m->v[i].y, m->v[i].z);
    for (size_t i = 0; i < m->nt; i++)
        fprintf(f, "f %u %u %u\n", m->t[3 * i] + 1, m->t[3 * i + 1] + 1, m->t[3 * i + 2] + 1);
    if (fclose(f) != 0) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", path, strerror(errno));
        return -1;
    }
    return 0;
}

/* The floor: n x n quads over [0,1]^2 at y = 0, facing up. */
static void floor_grid(mesh *m, int n)
{
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++)
            vert(m, V((double)i / n, 0, (double)j / n));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            size_t a = (size_t)j * (n + 1) + i, b = a + 1, c = a + (n + 1), d = c + 1;
            tri(m, a, c, b); /* counter-clockwise seen from +y */
            tri(m, b, c, d);
        }
}

/* An open tube from p to q (radius r0 at p, r1 at q), `sides` around, rings
 * about `step` apart; outward faces. */
static void tube(mesh *m, v3 p, v3 q, double r0, double r1, int sides, double step)
{
    v3 axis = sub(q, p);
    double len = sqrt(dot(axis, axis));
    v3 w = mul(axis, 1.0 / len);
    v3 u = fabs(w.y) < 0.9 ? unit(cross(w, V(0, 1, 0))) : unit(cross(w, V(1, 0, 0)));
    v3 v = cross(w, u);
    int rings = (int)ceil(len / step);
    if (rings < 1)
        rings = 1;
    size_t first = m->nv;
    for (int k = 0; k <= rings; k++) {
        double s = (double)k / rings, r = r0 + (r1 - r0) * s;
        v3 c = add(p, mul(axis, s));
        for (int i = 0; i < sides; i++) {
            double a = 2 * PI * i / sides;
            vert(m, add(c, add(mul(u, r * cos(a)), mul(v, r * sin(a)))));
        }
    }
    for (int k = 0; k < rings; k++)
        for (int i = 0; i < sides; i++) {
            size_t a = first + (size_t)k * sides + i, b = first + (size_t)k * sides + (i + 1) % sides;
            size_t c = a + sides, d = b + sides;
            tri(m, a, b, d);
            tri(m, a, d, c);
        }
}

/* An icosphere (subdivision 1: 80 triangles, 42 vertices), outward faces. */
static void blob(mesh *m, v3 c, double r)
{
    static const double t = 1.6180339887498949;
    v3 base[12] = {V(-1, t, 0), V(1, t, 0), V(-1, -t, 0), V(1, -t, 0), V(0, -1, t), V(0, 1, t),
                   V(0, -1, -t), V(0, 1, -t), V(t, 0, -1), V(t, 0, 1), V(-t, 0, -1), V(-t, 0, 1)};
    static const int f[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                 {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                 {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                 {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    size_t id[12];
    for (int i = 0; i < 12; i++)
        id[i] = vert(m, add(c, mul(unit(base[i]), r)));
    /* Edge midpoints, shared between the two faces of each edge. */
    size_t mid[12][12];
    memset(mid, 0xFF, sizeof mid);
    for (int k = 0; k < 20; k++)
        for (int e = 0; e < 3; e++) {
            int a = f[k][e], b = f[k][(e + 1) % 3];
            if (mid[a][b] == (size_t)-1) {
                v3 p = unit(add(unit(base[a]), unit(base[b])));
                mid[a][b] = mid[b][a] = vert(m, add(c, mul(p, r)));
            }
        }
    for (int k = 0; k < 20; k++) {
        int a = f[k][0], b = f[k][1], cc = f[k][2];
        size_t ab = mid[a][b], bc = mid[b][cc], ca = mid[cc][a];
        tri(m, id[a], ab, ca);
        tri(m, id[b], bc, ab);
        tri(m, id[cc], ca, bc);
        tri(m, ab, bc, ca);
    }
}

/* A direction at angle `tilt` from `w`, turned by `spin` around it. */
static v3 turn(v3 w, double tilt, double spin)
{
    v3 u = fabs(w.y) < 0.9 ? unit(cross(w, V(0, 1, 0))) : unit(cross(w, V(1, 0, 0)));
    v3 v = cross(w, u);
    v3 side = add(mul(u, cos(spin)), mul(v, sin(spin)));
    return unit(add(mul(w, cos(tilt)), mul(side, sin(tilt))));
}

typedef struct twig {
    v3 end, dir;
} twig;

static int tree(const char *dir, uint64_t seed)
{
    gi_rng r;
    gi_rng_init(&r, seed, 0x7EE, 0);
    mesh fl = {0}, bark = {0}, leaves = {0}, mob = {0};
    floor_grid(&fl, 50);
    /* Trunk and three levels of branches (5, then 4 per branch twice). */
    v3 base = V(0.5, 0, 0.5), top = V(0.5, 0.3, 0.5);
    tube(&bark, base, top, 0.02, 0.015, 12, 0.0125);
    twig ends[512];
    int nends = 0;
    twig level[128];
    int nlevel = 0;
    for (int i = 0; i < 5; i++) {
        v3 d = turn(V(0, 1, 0), 0.75 + 0.2 * gi_rng_double(&r),
                    2 * PI * (i + 0.3 * gi_rng_double(&r)) / 5);
        v3 e = add(top, mul(d, 0.13));
        tube(&bark, top, e, 0.012, 0.008, 6, 0.0125);
        level[nlevel++] = (twig){e, d};
    }
    static const double lens[2] = {0.07, 0.045}, rads[2][2] = {{0.008, 0.005}, {0.005, 0.003}};
    for (int depth = 0; depth < 2; depth++) {
        twig next[128];
        int nnext = 0;
        for (int b = 0; b < nlevel; b++)
            for (int k = 0; k < 4; k++) {
                v3 d = turn(level[b].dir, 0.45 + 0.25 * gi_rng_double(&r),
                            2 * PI * (k + 0.5 * gi_rng_double(&r)) / 4);
                d = unit(add(d, V(0, 0.25, 0))); /* towards the light */
                v3 e = add(level[b].end, mul(d, lens[depth]));
                tube(&bark, level[b].end, e, rads[depth][0], rads[depth][1], depth ? 4 : 5,
                     0.0125);
                if (depth == 0)
                    next[nnext++] = (twig){e, d};
                else if (nends < 512)
                    ends[nends++] = (twig){e, d};
            }
        memcpy(level, next, sizeof(twig) * (size_t)nnext);
        nlevel = nnext;
    }
    /* Foliage: blobs of 80 triangles around the twig ends, as many as keep
     * the scene at or just below the thesis's 71,966 triangles. */
    size_t have = fl.nt + bark.nt;
    size_t blobs = (TREE_TRIANGLES - have) / 80;
    for (size_t i = 0; i < blobs; i++) {
        const twig *t = &ends[i % (size_t)nends];
        v3 off = V(gi_rng_double(&r) - 0.5, gi_rng_double(&r) - 0.3, gi_rng_double(&r) - 0.5);
        v3 c = add(add(t->end, mul(t->dir, 0.02)), mul(off, 0.07));
        blob(&leaves, c, 0.02 + 0.01 * gi_rng_double(&r));
    }
    /* The mobile: a 25 x 10 torus (500 triangles) beside the tree. */
    {
        int nu = 25, nv = 10;
        double R = 0.05, rr = 0.015;
        v3 c = V(0.78, 0.12, 0.3);
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                double a = 2 * PI * i / nu, b = 2 * PI * j / nv;
                vert(&mob, V(c.x + (R + rr * cos(b)) * cos(a), c.y + rr * sin(b),
                             c.z + (R + rr * cos(b)) * sin(a)));
            }
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                size_t a = (size_t)i * nv + j, b = (size_t)((i + 1) % nu) * nv + j;
                size_t cc = (size_t)i * nv + (j + 1) % nv, d = (size_t)((i + 1) % nu) * nv + (j + 1) % nv;
                tri(&mob, a, cc, d);
                tri(&mob, a, d, b);
            }
    }
    if (write_obj(dir, "floor.obj", &fl) || write_obj(dir, "bark.obj", &bark) ||
        write_obj(dir, "leaves.obj", &leaves) || write_obj(dir, "mobile.obj", &mob))
        return 1;
    char path[4096];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", path, strerror(errno));
        return 1;
    }
    fprintf(f,
            "{\n"
            "  \"description\": \"Procedural tree scene (gi_scenegen tree, seed %llu): %zu floor, "
            "%zu bark and %zu foliage triangles (%zu in all, as the thesis's Tree Scene) and a "
            "%zu-triangle mobile torus; unit floor, light 0.3 x 0.3 at height 1.\",\n"
            "  \"camera\": {\"position\": [0.5, 0.45, 2.1], \"look_at\": [0.5, 0.3, 0.5], "
            "\"fov_y\": 40},\n"
            "  \"materials\": {\n"
            "    \"ground\": {\"diffuse\": [0.5, 0.5, 0.5]},\n"
            "    \"bark\": {\"diffuse\": [0.35, 0.25, 0.15]},\n"
            "    \"leaves\": {\"diffuse\": [0.25, 0.5, 0.15]},\n"
            "    \"mobile\": {\"diffuse\": [0.7, 0.7, 0.7]},\n"
            "    \"light\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [10, 10, 10]}\n"
            "  },\n"
            "  \"objects\": [\n"
            "    {\"name\": \"floor\", \"material\": \"ground\", \"mesh\": \"floor.obj\"},\n"
            "    {\"name\": \"bark\", \"material\": \"bark\", \"mesh\": \"bark.obj\"},\n"
            "    {\"name\": \"leaves\", \"material\": \"leaves\", \"mesh\": \"leaves.obj\"},\n"
            "    {\"name\": \"mobile\", \"material\": \"mobile\", \"mesh\": \"mobile.obj\", "
            "\"mobile\": true},\n"
            "    {\"name\": \"light\", \"material\": \"light\", \"quad\": {\"size\": [0.3, 0.3]},\n"
            "     \"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}}, "
            "{\"translate\": [0.5, 1, 0.5]}]}\n"
            "  ]\n"
            "}\n",
            (unsigned long long)seed, fl.nt, bark.nt, leaves.nt, fl.nt + bark.nt + leaves.nt, mob.nt);
    if (fclose(f) != 0) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", path, strerror(errno));
        return 1;
    }
    printf("%s: %zu + %zu + %zu = %zu triangles, %zu vertices; mobile %zu triangles\n", dir,
           fl.nt, bark.nt, leaves.nt, fl.nt + bark.nt + leaves.nt, fl.nv + bark.nv + leaves.nv,
           mob.nt);
    free(fl.v), free(fl.t), free(bark.v), free(bark.t), free(leaves.v), free(leaves.t);
    free(mob.v), free(mob.t);
    return 0;
}

static int cornell_mobile(const char *base, const char *out, double frac)
{
    FILE *f = fopen(base, "rb");
    if (!f) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", base, strerror(errno));
        return 1;
    }
    char *text = NULL;
    size_t len = 0, cap = 0, n;
    char buf[8192];
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
        if (len + n + 1 > cap) {
            cap = 2 * (len + n + 1);
            text = realloc(text, cap);
            if (!text)
                abort();
        }
        memcpy(text + len, buf, n);
        len += n;
    }
    fclose(f);
    cJSON *doc = text ? cJSON_ParseWithLength(text, len) : NULL;
    free(text);
    cJSON *objects = doc ? cJSON_GetObjectItemCaseSensitive(doc, "objects") : NULL;
    if (!cJSON_IsArray(objects)) {
        fprintf(stderr, "gi_scenegen: %s: not a scene with \"objects\"\n", base);
        cJSON_Delete(doc);
        return 1;
    }
    /* The box is 556 wide (x), 548.8 high, 559.2 deep; the centre: see the
     * header. */
    double width = 556.0, radius = frac * width;
    char obj[512];
    snprintf(obj, sizeof obj,
             "{\"name\": \"mobile\", \"material\": \"white\", \"mobile\": true,"
             " \"sphere\": {\"radius\": %.6g, \"subdivisions\": 3},"
             " \"transform\": [{\"translate\": [150, 395, 150]}]}",
             radius);
    cJSON_AddItemToArray(objects, cJSON_Parse(obj));
    char desc[512];
    snprintf(desc, sizeof desc,
             "The Cornell box with a sphere mobile of radius %.4g (%.4g%% of the box's width) "
             "at (150, 395, 150), clear of the walls and blocks up to (278, 395, 150) for radii "
             "up to 27%% of the width (gi_scenegen cornell-mobile).",
             radius, 100.0 * frac);
    cJSON_ReplaceItemInObjectCaseSensitive(doc, "description", cJSON_CreateString(desc));
    char *printed = cJSON_Print(doc);
    cJSON_Delete(doc);
    FILE *o = fopen(out, "w");
    if (!o || !printed || fprintf(o, "%s\n", printed) < 0 || fclose(o) != 0) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", out, strerror(errno));
        free(printed);
        return 1;
    }
    free(printed);
    return 0;
}

enum { GRID_BOXES, GRID_ONE_MESH, GRID_MESH_FILES };

static int grid(const char *dir, long n, int kind)
{
    long side = (long)ceil(sqrt((double)n));
    double w = (double)side + 2.0, h = fmax(3.0, 0.5 * w);
    char *path = gi_path_join(dir, "scene.json");
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "gi_scenegen: %s: %s\n", path, strerror(errno));
        free(path);
        return 1;
    }
    fprintf(f, "{\n\"description\": \"%ld cubes on the floor of a closed room lit by a "
               "ceiling quad (gi_scenegen grid%s)\",\n",
            n, kind == GRID_ONE_MESH ? ", --mesh" : kind == GRID_MESH_FILES ? ", --mesh-files"
                                                                              : "");
    fprintf(f, "\"camera\": {\"position\": [%.6g, %.6g, %.6g], \"look_at\": [%.6g, 0, %.6g], "
               "\"up\": [0, 1, 0], \"fov_y\": 60},\n",
            0.5 * w, 0.8 * h, 0.05 * w, 0.5 * w, 0.5 * w);
    fprintf(f, "\"materials\": {\n"
               "  \"wall\": {\"diffuse\": [0.7, 0.7, 0.7]},\n"
               "  \"light\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [10, 10, 10]},\n"
               "  \"m0\": {\"diffuse\": [0.7, 0.2, 0.2]}, \"m1\": {\"diffuse\": [0.2, 0.7, 0.2]},\n"
               "  \"m2\": {\"diffuse\": [0.2, 0.2, 0.7]}, \"m3\": {\"diffuse\": [0.6, 0.6, 0.3]}\n"
               "},\n\"objects\": [\n");
    fprintf(f, "{\"name\": \"room\", \"material\": \"wall\", \"box\": {\"size\": [%.6g, %.6g, "
               "%.6g], \"inward\": true}, \"transform\": [{\"translate\": [%.6g, %.6g, %.6g]}]},\n",
            w, h, w, 0.5 * w, 0.5 * h, 0.5 * w);
    fprintf(f, "{\"name\": \"light\", \"material\": \"light\", \"quad\": {\"size\": [%.6g, %.6g]}, "
               "\"transform\": [{\"rotate\": {\"axis\": [1, 0, 0], \"degrees\": 180}}, "
               "{\"translate\": [%.6g, %.6g, %.6g]}]}",
            0.25 * w, 0.25 * w, 0.5 * w, 0.999 * h, 0.5 * w);
    for (long i = 0; i < n; i++) {
        double x = 1.5 + (double)(i % side), z = 1.5 + (double)(i / side);
        fprintf(f, ",\n{\"name\": \"cube%ld\", ", i);
        if (kind == GRID_ONE_MESH)
            fprintf(f, "\"mesh\": \"cube.obj\", ");
        else if (kind == GRID_MESH_FILES)
            fprintf(f, "\"mesh\": \"cube%ld.obj\", ", i);
        else
            fprintf(f, "\"material\": \"m%ld\", \"box\": {\"size\": [0.5, 0.5, 0.5]}, ", i % 4);
        fprintf(f, "\"transform\": [{\"translate\": [%.6g, 0.25, %.6g]}]}", x, z);
    }
    int bad = fprintf(f, "\n]\n}\n") < 0;
    bad |= fclose(f) != 0;
    if (bad)
        fprintf(stderr, "gi_scenegen: %s: %s\n", path, strerror(errno));
    free(path);
    if (bad || kind == GRID_BOXES)
        return bad;
    /* A 0.5 cube about the origin, outward faces, one material of its own. */
    mesh m = {0};
    for (int k = 0; k < 8; k++)
        vert(&m, V(k & 1 ? 0.25 : -0.25, k & 2 ? 0.25 : -0.25, k & 4 ? 0.25 : -0.25));
    static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int q = 0; q < 6; q++) {
        tri(&m, (size_t)quads[q][0], (size_t)quads[q][1], (size_t)quads[q][2]);
        tri(&m, (size_t)quads[q][0], (size_t)quads[q][2], (size_t)quads[q][3]);
    }
    int rc = write_obj(dir, "cube.obj", &m) ? 1 : 0;
    for (long i = 0; kind == GRID_MESH_FILES && i < n && rc == 0; i++) {
        char name[40];
        snprintf(name, sizeof name, "cube%ld.obj", i);
        rc = write_obj(dir, name, &m) ? 1 : 0;
    }
    free(m.v);
    free(m.t);
    return rc;
}

static int usage(void)
{
    fprintf(stderr, "usage: gi_scenegen tree DIR [--seed N]\n"
                    "       gi_scenegen cornell-mobile BASE.json OUT.json --radius FRACTION\n"
                    "       gi_scenegen grid DIR --objects N [--mesh | --mesh-files]\n");
    return 2;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "tree") == 0) {
        uint64_t seed = 1;
        if (argc == 5 && strcmp(argv[3], "--seed") == 0)
            seed = strtoull(argv[4], NULL, 10);
        else if (argc != 3)
            return usage();
        gi_error err;
        if (gi_mkdirs(argv[2], &err)) {
            fprintf(stderr, "gi_scenegen: %s\n", err.msg);
            return 1;
        }
        return tree(argv[2], seed);
    }
    if (argc == 6 && strcmp(argv[1], "cornell-mobile") == 0 && strcmp(argv[4], "--radius") == 0) {
        char *end;
        double frac = strtod(argv[5], &end);
        if (*end || !(frac > 0.0 && frac <= 0.5)) {
            fprintf(stderr, "gi_scenegen: --radius: expected a fraction in (0, 0.5]\n");
            return 2;
        }
        return cornell_mobile(argv[2], argv[3], frac);
    }
    if ((argc == 5 || argc == 6) && strcmp(argv[1], "grid") == 0 &&
        strcmp(argv[3], "--objects") == 0) {
        char *end;
        long n = strtol(argv[4], &end, 10);
        int kind = argc == 5                         ? GRID_BOXES
                   : strcmp(argv[5], "--mesh") == 0       ? GRID_ONE_MESH
                   : strcmp(argv[5], "--mesh-files") == 0 ? GRID_MESH_FILES
                                                          : -1;
        if (*end || n < 0 || n > 10000000 || kind < 0)
            return usage();
        gi_error err;
        if (gi_mkdirs(argv[2], &err)) {
            fprintf(stderr, "gi_scenegen: %s\n", err.msg);
            return 1;
        }
        return grid(argv[2], n, kind);
    }
    return usage();
}
