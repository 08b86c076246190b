/* gi_math: affine transforms, triangle normals. */
#include "gi_math.h"

#include <math.h>
#include <string.h>

gi_mat4 gi_mat4_identity(void)
{
    gi_mat4 r;
    memset(&r, 0, sizeof r);
    for (int i = 0; i < 4; i++)
        r.m[i][i] = 1.0;
    return r;
}

gi_mat4 gi_mat4_mul(gi_mat4 a, gi_mat4 b)
{
    gi_mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++)
                s += a.m[i][k] * b.m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

gi_mat4 gi_mat4_translate(double x, double y, double z)
{
    gi_mat4 r = gi_mat4_identity();
    r.m[0][3] = x;
    r.m[1][3] = y;
    r.m[2][3] = z;
    return r;
}

gi_mat4 gi_mat4_scale(double x, double y, double z)
{
    gi_mat4 r = gi_mat4_identity();
    r.m[0][0] = x;
    r.m[1][1] = y;
    r.m[2][2] = z;
    return r;
}

gi_mat4 gi_mat4_rotate(double ax, double ay, double az, double degrees)
{
    double len = sqrt(ax * ax + ay * ay + az * az);
    gi_mat4 r = gi_mat4_identity();
    if (len == 0.0)
        return r;
    ax /= len;
    ay /= len;
    az /= len;
    double t = degrees * GI_PI / 180.0, c = cos(t), s = sin(t), k = 1.0 - c;
    /* Rodrigues' rotation formula. */
    r.m[0][0] = c + ax * ax * k;
    r.m[0][1] = ax * ay * k - az * s;
    r.m[0][2] = ax * az * k + ay * s;
    r.m[1][0] = ay * ax * k + az * s;
    r.m[1][1] = c + ay * ay * k;
    r.m[1][2] = ay * az * k - ax * s;
    r.m[2][0] = az * ax * k - ay * s;
    r.m[2][1] = az * ay * k + ax * s;
    r.m[2][2] = c + az * az * k;
    return r;
}

int gi_mat4_inverse(gi_mat4 a, gi_mat4 *out)
{
    /* Affine: invert the 3x3 block, then the translation. */
    double (*m)[4] = a.m;
    double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    if (!(fabs(det) > 1e-300) || !isfinite(det))
        return -1;
    double id = 1.0 / det;
    gi_mat4 r = gi_mat4_identity();
    r.m[0][0] = c00 * id;
    r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * id;
    r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * id;
    r.m[1][0] = c01 * id;
    r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * id;
    r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * id;
    r.m[2][0] = c02 * id;
    r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * id;
    r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * id;
    for (int i = 0; i < 3; i++)
        r.m[i][3] = -(r.m[i][0] * m[0][3] + r.m[i][1] * m[1][3] + r.m[i][2] * m[2][3]);
    *out = r;
    return 0;
}

gi_vec3 gi_mat4_point(const gi_mat4 *m, gi_vec3 p)
{
    const double (*a)[4] = m->m;
    return gi_v3((float)(a[0][0] * p.x + a[0][1] * p.y + a[0][2] * p.z + a[0][3]),
                 (float)(a[1][0] * p.x + a[1][1] * p.y + a[1][2] * p.z + a[1][3]),
                 (float)(a[2][0] * p.x + a[2][1] * p.y + a[2][2] * p.z + a[2][3]));
}

gi_vec3 gi_mat4_vector(const gi_mat4 *m, gi_vec3 v)
{
    const double (*a)[4] = m->m;
    return gi_v3((float)(a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z),
                 (float)(a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z),
                 (float)(a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z));
}

gi_vec3 gi_mat4_normal(const gi_mat4 *inv, gi_vec3 n)
{
    const double (*a)[4] = inv->m;
    /* Normalized in double: under a tiny scale (1e-20) the inverse's
     * entries are so large that the float length would overflow. */
    double r[3] = {a[0][0] * n.x + a[1][0] * n.y + a[2][0] * n.z,
                   a[0][1] * n.x + a[1][1] * n.y + a[2][1] * n.z,
                   a[0][2] * n.x + a[1][2] * n.y + a[2][2] * n.z};
    double len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(len > 0.0) || !isfinite(len))
        return gi_v3((float)r[0], (float)r[1], (float)r[2]);
    return gi_v3((float)(r[0] / len), (float)(r[1] / len), (float)(r[2] / len));
}

gi_vec3 gi_triangle_normal(gi_vec3 a, gi_vec3 b, gi_vec3 c)
{
    double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0) || !isfinite(len))
        return gi_v3(0.0f, 0.0f, 0.0f);
    return gi_v3((float)(n[0] / len), (float)(n[1] / len), (float)(n[2] / len));
}
