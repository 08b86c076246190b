/* rad_relight: solutions for emission sets, and their outputs. */
#include "rad_relight.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_clock.h"
#include "gi_fs.h"
#include "gi_glb.h"
#include "gi_ply.h"

void gi_rad_solve_opts_default(gi_rad_solve_opts *o)
{
    o->solver = GI_RAD_SMW;
    o->tolerance = 1e-6;
    o->max_iterations = 10000;
    o->threads = 1;
}

int gi_rad_solve_emissions(const gi_rad_factor *f, const gi_rad_model *md,
                           const gi_rad_emissions *em, const gi_rad_solve_opts *o, float *E,
                           float *B, gi_rad_solve_info *info, gi_error *err)
{
    if (md->n != f->n)
        return gi_fail(err, GI_EINTERNAL, "radiosity: model and factor sizes differ");
    if (gi_rad_emissions_check(em, md, "emissions", err))
        return -1;
    size_t n3 = 3 * (size_t)f->n;
    float *e = gi_try_malloc(n3 * sizeof *e, err, "emission vector");
    if (!e)
        return -1;
    for (uint32_t i = 0; i < em->count; i++) {
        gi_rad_emission_vector(em, i, md, e);
        gi_rad_solve_info *in = &info[i];
        memset(in, 0, sizeof *in);
        double t0 = gi_now();
        int rc = o->solver == GI_RAD_NEUMANN
                     ? gi_rad_factor_neumann(f, e, B + i * n3, o->tolerance, o->max_iterations,
                                             o->threads, &in->iterations, &in->residual, err)
                     : gi_rad_factor_relight(f, e, B + i * n3, 1, o->threads, err);
        in->seconds = gi_now() - t0;
        if (rc) {
            free(e);
            return gi_error_prefix(err, "emission set \"%s\"", em->items[i].name);
        }
        if (E)
            memcpy(E + i * n3, e, n3 * sizeof *e);
    }
    free(e);
    return 0;
}

/* A vertex's normal: its elements are coplanar (gi_rad_vertices shares a
 * vertex only among them), so any one of them gives it. */
static gi_vec3 *vertex_normals(const gi_rad_vertices *v, uint32_t n, gi_error *err)
{
    gi_vec3 *nrm = gi_try_calloc(v->count, sizeof *nrm, err, "vertex normals");
    if (!nrm)
        return NULL;
    for (uint32_t e = 0; e < n; e++) {
        const uint32_t *c = &v->corner[3 * (size_t)e];
        gi_vec3 g = gi_triangle_normal(v->positions[c[0]], v->positions[c[1]],
                                       v->positions[c[2]]);
        for (int k = 0; k < 3; k++)
            if (gi_dot(nrm[c[k]], nrm[c[k]]) == 0.0f)
                nrm[c[k]] = g;
    }
    for (uint32_t i = 0; i < v->count; i++) /* only on elements without area */
        if (gi_dot(nrm[i], nrm[i]) == 0.0f)
            nrm[i] = gi_v3(0.0f, 1.0f, 0.0f);
    return nrm;
}

int gi_rad_vertex_output_write(const char *path, const char *kind, const gi_rad_model *md,
                               const float *B, double exposure, gi_error *err)
{
    const gi_rad_vertices *vx = &md->vertices;
    float *vv = gi_try_malloc(3 * (size_t)vx->count * sizeof *vv, err, "per-vertex output");
    if (!vv)
        return -1;
    int rc = gi_rad_vertex_values(vx, md->n, md->area, B, vv, err);
    if (rc == 0 && strcmp(kind, "ply") == 0) {
        rc = gi_ply_write(path, vx->count, vx->positions, vv, md->n, vx->corner, exposure, err)
                 ? -1
                 : 1;
    } else if (rc == 0) {
        gi_vec3 *nrm = vertex_normals(vx, md->n, err);
        const gi_vertex_bake bake = {vx->count, vx->positions, nrm,        vv,
                                     NULL,      md->n,         vx->corner, exposure};
        rc = nrm ? gi_glb_write_or_skip(path, &bake, err) : -1;
        free(nrm);
    }
    free(vv);
    return rc;
}

static cJSON *rgb(const double v[3])
{
    double a[3] = {v[0], v[1], v[2]};
    return cJSON_CreateDoubleArray(a, 3);
}

cJSON *gi_rad_solution_report(const gi_rad_model *md, const char *name, const float *E,
                              const float *B, const gi_rad_solve_info *info)
{
    double flux[3] = {0, 0, 0}, mean[3] = {0, 0, 0}, max[3] = {0, 0, 0}, area = 0.0;
    for (uint32_t e = 0; e < md->n; e++) {
        area += md->area[e];
        for (int c = 0; c < 3; c++) {
            /* Radiance to flux: pi A L for a Lambertian emitter. */
            flux[c] += M_PI * md->area[e] * E[3 * (size_t)e + c];
            mean[c] += md->area[e] * B[3 * (size_t)e + c];
            if (B[3 * (size_t)e + c] > max[c])
                max[c] = B[3 * (size_t)e + c];
        }
    }
    for (int c = 0; c < 3; c++)
        mean[c] = area > 0 ? mean[c] / area : 0.0;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "name", name);
    cJSON_AddItemToObject(o, "emitted_flux", rgb(flux));
    cJSON_AddItemToObject(o, "mean_radiance", rgb(mean));
    cJSON_AddItemToObject(o, "max_radiance", rgb(max));
    cJSON_AddNumberToObject(o, "solve_ms", info->seconds * 1e3);
    if (info->iterations) {
        cJSON_AddNumberToObject(o, "iterations", info->iterations);
        cJSON_AddNumberToObject(o, "residual", info->residual);
    }
    return o;
}

cJSON *gi_rad_report_new(const gi_rad_file_info *info, const gi_rad_factor *f)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "method", "radiosity");
    cJSON_AddStringToObject(o, "factorization", info->method);
    cJSON_AddNumberToObject(o, "elements", f->n);
    cJSON_AddNumberToObject(o, "patches", f->k);
    cJSON_AddNumberToObject(o, "level0_patches", info->roots);
    cJSON_AddNumberToObject(o, "levels", info->levels);
    cJSON_AddNumberToObject(o, "rays_per_element", f->rays);
    return o;
}

void gi_rad_report_add_solutions(cJSON *doc, const gi_rad_model *md, const gi_rad_emissions *em,
                                 const float *E, const float *B, const gi_rad_solve_info *info)
{
    cJSON *sols = cJSON_AddArrayToObject(doc, "emissions");
    size_t n3 = 3 * (size_t)md->n;
    for (uint32_t i = 0; i < em->count; i++)
        cJSON_AddItemToArray(
            sols, gi_rad_solution_report(md, em->items[i].name, E + i * n3, B + i * n3, &info[i]));
}

int gi_rad_write_json(const char *path, const cJSON *doc, gi_error *err)
{
    char *text = cJSON_Print(doc);
    if (!text)
        return gi_fail(err, GI_ENOMEM, "%s: cannot format the report", path);
    size_t len = strlen(text);
    text[len] = '\n'; /* replaces the NUL: the file ends with a newline */
    int rc = gi_write_file_atomic(path, text, len + 1, err);
    cJSON_free(text);
    return rc;
}

char *gi_rad_output_name(const char *file, const char *emission)
{
    const char *dot = strrchr(file, '.');
    size_t stem = dot && dot != file ? (size_t)(dot - file) : strlen(file);
    size_t len = strlen(file) + strlen(emission) + 2;
    char *out = gi_xmalloc(len);
    snprintf(out, len, "%.*s-%s%s", (int)stem, file, emission, file + stem);
    return out;
}

typedef struct written_name {
    char *file;
    const char *kind, *set; /* set: NULL for a file written once */
} written_name;

static int by_file(const void *a, const void *b)
{
    return strcmp(((const written_name *)a)->file, ((const written_name *)b)->file);
}

static void describe(const written_name *w, char *out, size_t len)
{
    if (w->set)
        snprintf(out, len, "set %s's %s output", w->set, w->kind);
    else
        snprintf(out, len, "the %s output", w->kind);
}

int gi_rad_outputs_distinct(const gi_rad_output_file *outs, int count, const gi_rad_emissions *em,
                            char *msg, size_t msg_len)
{
    size_t n = 0, cap = 0;
    for (int i = 0; i < count; i++)
        cap += outs[i].per_set ? em->count : 1;
    written_name *w = gi_xcalloc(cap ? cap : 1, sizeof *w);
    for (int i = 0; i < count; i++) {
        if (!outs[i].per_set) {
            w[n].file = outs[i].as ? gi_rad_output_name(outs[i].file, outs[i].as)
                                   : gi_xstrdup(outs[i].file);
            w[n++].kind = outs[i].kind;
            continue;
        }
        for (uint32_t k = 0; k < em->count; k++, n++) {
            w[n].file = gi_rad_output_name(outs[i].file, em->items[k].name);
            w[n].kind = outs[i].kind;
            w[n].set = em->items[k].name;
        }
    }
    qsort(w, n, sizeof *w, by_file);
    int rc = 0;
    for (size_t i = 1; i < n && !rc; i++)
        if (strcmp(w[i - 1].file, w[i].file) == 0) {
            char a[160], b[160];
            describe(&w[i - 1], a, sizeof a);
            describe(&w[i], b, sizeof b);
            snprintf(msg, msg_len, "\"%s\" is both %s and %s", w[i].file, a, b);
            rc = -1;
        }
    for (size_t i = 0; i < n; i++)
        free(w[i].file);
    free(w);
    return rc;
}

int gi_rad_relight_write(const char *dir, const char *ply, const char *glb, const char *report,
                         const char *job, double exposure, const gi_rad_file_info *info, const gi_rad_model *md,
                         const gi_rad_factor *f, const gi_rad_emissions *em, const float *E,
                         const float *B, const gi_rad_solve_info *si,
                         void (*note)(void *user, const char *kind, const char *path), void *user,
                         gi_error *err)
{
    gi_rad_output_file outs[3];
    int count = 0;
    if (ply)
        outs[count++] = (gi_rad_output_file){"ply", ply, NULL, 1};
    if (glb)
        outs[count++] = (gi_rad_output_file){"glb", glb, NULL, 1};
    if (report)
        outs[count++] = (gi_rad_output_file){"report", report, "relight", 0};
    char msg[512];
    if (gi_rad_outputs_distinct(outs, count, em, msg, sizeof msg))
        return gi_fail(err, GI_EINVAL, "%s: %s", dir, msg);
    size_t n3 = 3 * (size_t)f->n;
    for (int o = 0; o < count; o++)
        for (uint32_t i = 0; outs[o].per_set && i < em->count; i++) {
            char *name = gi_rad_output_name(outs[o].file, em->items[i].name);
            char *path = gi_path_join(dir, name);
            int rc = gi_rad_vertex_output_write(path, outs[o].kind, md, B + i * n3, exposure,
                                                err);
            if (rc == 1 && note)
                note(user, outs[o].kind, path);
            free(name);
            free(path);
            if (rc < 0)
                return -1;
        }
    if (!report)
        return 0;
    cJSON *doc = gi_rad_report_new(info, f);
    cJSON_AddStringToObject(doc, "job", job);
    gi_rad_report_add_solutions(doc, md, em, E, B, si);
    char *name = gi_rad_output_name(report, "relight");
    char *path = gi_path_join(dir, name);
    int rc = gi_rad_write_json(path, doc, err);
    if (rc == 0 && note)
        note(user, "report", path);
    cJSON_Delete(doc);
    free(name);
    free(path);
    return rc;
}
