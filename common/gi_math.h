/* gi_math: small-vector math for geometry and shading (single precision, as
 * Embree), and 4x4 affine transforms (double, applied once at load time). */
#ifndef GI_MATH_H
#define GI_MATH_H

#include <math.h>

#define GI_PI 3.14159265358979323846
#define GI_INV_PI 0.31830988618379067154

/* min/max without fminf's NaN rules, so they compile to one instruction
 * (fminf/fmaxf are library calls at -O2 on x86-64). */
static inline float gi_minf(float a, float b) { return a < b ? a : b; }
static inline float gi_maxf(float a, float b) { return a > b ? a : b; }

typedef struct gi_vec3 {
    float x, y, z;
} gi_vec3;

static inline gi_vec3 gi_v3(float x, float y, float z)
{
    gi_vec3 v = {x, y, z};
    return v;
}
static inline gi_vec3 gi_add(gi_vec3 a, gi_vec3 b) { return gi_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline gi_vec3 gi_sub(gi_vec3 a, gi_vec3 b) { return gi_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline gi_vec3 gi_mul(gi_vec3 a, gi_vec3 b) { return gi_v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline gi_vec3 gi_scale(gi_vec3 a, float s) { return gi_v3(a.x * s, a.y * s, a.z * s); }
static inline gi_vec3 gi_madd(gi_vec3 a, gi_vec3 b, float s)
{
    return gi_v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
static inline float gi_dot(gi_vec3 a, gi_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline gi_vec3 gi_cross(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float gi_length(gi_vec3 a) { return sqrtf(gi_dot(a, a)); }
static inline gi_vec3 gi_normalize(gi_vec3 a)
{
    float l = gi_length(a);
    return l > 0.0f ? gi_scale(a, 1.0f / l) : a;
}
static inline gi_vec3 gi_neg(gi_vec3 a) { return gi_v3(-a.x, -a.y, -a.z); }
static inline float gi_max3(gi_vec3 a) { return gi_maxf(a.x, gi_maxf(a.y, a.z)); }
static inline float gi_luminance(gi_vec3 c)
{
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
static inline int gi_is_black(gi_vec3 c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }
/* Per-component min/max for bounding boxes, lo = gi_min_v3(lo, p): a NaN
 * in b is passed over (like fminf), in one instruction per component
 * (fminf is a library call at -O2: 2% of a small animation frame). */
static inline gi_vec3 gi_min_v3(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(gi_minf(b.x, a.x), gi_minf(b.y, a.y), gi_minf(b.z, a.z));
}
static inline gi_vec3 gi_max_v3(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(gi_maxf(b.x, a.x), gi_maxf(b.y, a.y), gi_maxf(b.z, a.z));
}
static inline float gi_v3_get(gi_vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }

/* An orthonormal basis (t, b, n) around unit n (Duff et al. 2017, branchless). */
static inline void gi_onb(gi_vec3 n, gi_vec3 *t, gi_vec3 *b)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = gi_v3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = gi_v3(c, sign + n.y * n.y * a, -n.y);
}

/* Affine transform, row-major: p' = M * (p, 1). */
typedef struct gi_mat4 {
    double m[4][4];
} gi_mat4;

gi_mat4 gi_mat4_identity(void);
gi_mat4 gi_mat4_mul(gi_mat4 a, gi_mat4 b); /* a * b: b applied first */
gi_mat4 gi_mat4_translate(double x, double y, double z);
gi_mat4 gi_mat4_scale(double x, double y, double z);
gi_mat4 gi_mat4_rotate(double axis_x, double axis_y, double axis_z, double degrees);
/* Inverse of an affine matrix; returns 0, or -1 if singular. */
int gi_mat4_inverse(gi_mat4 a, gi_mat4 *out);
gi_vec3 gi_mat4_point(const gi_mat4 *m, gi_vec3 p);
gi_vec3 gi_mat4_vector(const gi_mat4 *m, gi_vec3 v);
/* Normals transform by the inverse transpose; `inv` is the inverse of m. */
gi_vec3 gi_mat4_normal(const gi_mat4 *inv, gi_vec3 n);
/* The unit normal of triangle (a, b, c), counter-clockwise seen from its
 * front, or (0, 0, 0) if it has no area. In double: the float cross product
 * of edges longer than ~1e9 overflows, of edges under ~1e-19 underflows. */
gi_vec3 gi_triangle_normal(gi_vec3 a, gi_vec3 b, gi_vec3 c);

#endif
