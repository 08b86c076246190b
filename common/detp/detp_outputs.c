/* detp_outputs: what a detp job writes besides the image - per-vertex
 * radiance as PLY (vertex colours for engines and DCC tools) and as a
 * binary float file, and the JSON report (photons, rays, time per phase,
 * the estimator's statistics, the predicted relative error of eq. 3.46
 * and, if asked, the comparison with the path tracer). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp_method.h"
#include "gi_fs.h"
#include "gi_glb.h"
#include "gi_outputs.h"
#include "gi_ply.h"

/* The binary float file: a 24-byte header - "GIVTXF32", u32 version (1),
 * u32 vertex count, u32 floats per vertex (6), u32 zero - then per vertex,
 * little-endian float32: radiance R, G, B (reflected + emitted), then
 * irradiance R, G, B. Vertices are those of the PLY, in the same order. */
static int write_bin(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                     gi_error *err)
{
    const char *file = gi_job_output(job, "bin");
    if (!file)
        return 0;
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put(&b, "GIVTXF32", 8);
    gi_buf_put_u32(&b, 1);
    gi_buf_put_u32(&b, st->nv);
    gi_buf_put_u32(&b, 6);
    gi_buf_put_u32(&b, 0);
    for (uint32_t i = 0; i < st->nv; i++) {
        gi_buf_put_f32s(&b, &v->radiance[3 * (size_t)i], 3);
        gi_buf_put_f32s(&b, &v->irradiance[3 * (size_t)i], 3);
    }
    char *path = gi_job_output_path(job, file);
    int rc = gi_write_file_atomic(path, b.data, b.len, err);
    if (rc == 0)
        gi_job_note_output(job, "bin", path);
    free(path);
    gi_buf_free(&b);
    return rc;
}

static int write_ply(gi_job *job, const detp_vertex_data *v, gi_error *err)
{
    const char *file = gi_job_output(job, "ply");
    if (!file)
        return 0;
    const gi_scene *s = &job->scene;
    char *path = gi_job_output_path(job, file);
    int rc = gi_ply_write(path, s->vertex_count, s->positions, v->radiance, s->triangle_count,
                          s->indices, job->exposure, err);
    if (rc == 0)
        gi_job_note_output(job, "ply", path);
    free(path);
    return rc;
}

static int write_glb(gi_job *job, const detp_vertex_data *v, gi_error *err)
{
    const char *file = gi_job_output(job, "glb");
    if (!file)
        return 0;
    const gi_scene *s = &job->scene;
    const gi_vertex_bake bake = {s->vertex_count, s->positions, s->normals, v->radiance,
                                 v->irradiance,   s->triangle_count, s->indices, job->exposure};
    char *path = gi_job_output_path(job, file);
    int rc = gi_glb_write_or_skip(path, &bake, err);
    if (rc == 1)
        gi_job_note_output(job, "glb", path);
    free(path);
    return rc < 0 ? -1 : 0;
}

static void add_num(cJSON *o, const char *k, double v) { cJSON_AddNumberToObject(o, k, v); }

static cJSON *stats_json(const detp_state *st)
{
    const gi_detp_stats *s = &st->stats;
    cJSON *o = cJSON_CreateObject();
    add_num(o, "disc_tests", (double)s->disc_tests);
    add_num(o, "crossings", (double)s->crossings);
    add_num(o, "sphere_tests", (double)s->sphere_tests);
    add_num(o, "queries", (double)s->queries);
    add_num(o, "cache_faults", (double)s->faults);
    add_num(o, "faults_per_query", s->queries ? (double)s->faults / (double)s->queries : 0.0);
    add_num(o, "spheres_built", (double)s->spheres_built);
    add_num(o, "max_level", (double)s->max_level);
    add_num(o, "max_spheres_at_once", (double)s->max_spheres);
    add_num(o, "spheres_evicted", (double)s->evictions);
    add_num(o, "mean_rays_in_innermost_sphere",
            s->queries ? (double)s->inner_rays / (double)s->queries : 0.0);
    add_num(o, "octree_nodes_visited", (double)s->node_visits);
    add_num(o, "embree_candidates", (double)s->candidates);
    add_num(o, "photons_gathered", (double)s->photons_found);
    if (s->spheres_built) {
        /* Thesis Table 5.7: faults and mean rays per level. */
        cJSON *lv = cJSON_AddArrayToObject(o, "levels");
        for (uint64_t i = 1; i <= s->max_level && i < GI_DETP_MAX_LEVELS; i++) {
            cJSON *l = cJSON_CreateObject();
            add_num(l, "level", (double)i);
            add_num(l, "rebuilds", (double)s->level_faults[i]);
            add_num(l, "mean_rays",
                    s->level_faults[i] ? (double)s->level_rays[i] / (double)s->level_faults[i]
                                       : 0.0);
            cJSON_AddItemToArray(lv, l);
        }
    }
    return o;
}

/* The path tracer's irradiance at the reference vertices against ours. */
static cJSON *reference_json(const gi_job *job, const detp_state *st, const detp_vertex_data *v)
{
    const gi_detp_params *p = job->params;
    cJSON *o = cJSON_CreateObject();
    add_num(o, "spp", p->reference_spp);
    add_num(o, "vertices", st->nref);
    cJSON *list = cJSON_CreateArray();
    double abs_sum = 0, sq_sum = 0, se_sum = 0, sum_detp = 0, sum_pt = 0, dev_sum = 0;
    uint32_t used = 0;
    for (uint32_t j = 0; j < st->nref; j++) {
        uint32_t vi = detp_reference_vertex(j, st->nref, st->nv);
        const double *r = &st->ref[4 * (size_t)j];
        double inv = 1.0 / p->reference_spp;
        gi_vec3 E = gi_v3((float)(r[0] * inv), (float)(r[1] * inv), (float)(r[2] * inv));
        double pt = gi_luminance(E);
        const float *e = &v->irradiance[3 * (size_t)vi];
        double ours = gi_luminance(gi_v3(e[0], e[1], e[2]));
        double var = r[3] * inv - pt * pt;
        double se = p->reference_spp > 1 && var > 0 ? sqrt(var / (p->reference_spp - 1)) : 0;
        cJSON *x = cJSON_CreateObject();
        add_num(x, "vertex", vi);
        add_num(x, "detp", ours);
        add_num(x, "pt", pt);
        add_num(x, "pt_stderr", se);
        cJSON_AddItemToArray(list, x);
        sum_detp += ours;
        sum_pt += pt;
        dev_sum += fabs(ours - pt);
        if (pt > 0) {
            double rel = (ours - pt) / pt;
            abs_sum += fabs(rel);
            sq_sum += rel * rel;
            se_sum += se / pt;
            used++;
        }
    }
    /* Mean |E_detp - E_pt| over the mean E_pt: robust to vertices the path
     * tracer finds almost dark (under the blocks), whose own relative
     * errors are huge and say little. */
    add_num(o, "mean_abs_error_over_mean", sum_pt > 0 ? dev_sum / sum_pt : 0.0);
    add_num(o, "mean_abs_relative_error", used ? abs_sum / used : 0.0);
    add_num(o, "rms_relative_error", used ? sqrt(sq_sum / used) : 0.0);
    add_num(o, "pt_mean_relative_stderr", used ? se_sum / used : 0.0);
    add_num(o, "relative_error_of_mean", sum_pt > 0 ? sum_detp / sum_pt - 1.0 : 0.0);
    cJSON_AddItemToObject(o, "per_vertex", list);
    return o;
}

static cJSON *report(const gi_job *job, const detp_state *st, const detp_vertex_data *v)
{
    const gi_detp_params *p = job->params;
    static const char *const ac_names[] = {"none", "second_hit", "visible_area"};
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "method", "detp");
    cJSON_AddStringToObject(o, "estimator", gi_detp_estimator_names[p->estimator]);
    cJSON_AddStringToObject(o, "artifact_control", ac_names[p->artifact]);
    add_num(o, "photons", (double)st->photons);
    add_num(o, "batches", (double)st->batches);
    add_num(o, "segments", (double)st->segments);
    add_num(o, "segments_per_photon", st->photons ? (double)st->segments / st->photons : 0.0);
    add_num(o, "vertices", st->nv);
    add_num(o, "triangles", job->scene.triangle_count);
    add_num(o, "scene_size", p->scene_size);
    add_num(o, "mean_sample_spacing", p->mean_spacing);
    add_num(o, "disc_radius", p->disc_radius);
    double ad = GI_PI * (double)p->disc_radius * p->disc_radius;
    add_num(o, "disc_area", ad);
    add_num(o, "hull_area", p->hull_area);
    cJSON *pred = cJSON_AddObjectToObject(o, "predicted_relative_error");
    cJSON_AddStringToObject(pred, "formula", "sqrt((A_0 - A_d) / (A_d n_R)), eq. 3.46");
    add_num(pred, "n_R_photons", gi_detp_predicted_error(p->hull_area, ad, (double)st->photons));
    add_num(pred, "n_R_segments",
            gi_detp_predicted_error(p->hull_area, ad, (double)st->segments));
    /* Crossings per disc are Poisson-like: 1/sqrt(hits) is each disc's own
     * relative error; their mean over discs that got any. */
    double poisson = 0, lum = 0, lmin = INFINITY, lmax = 0;
    uint64_t with = 0, without = 0;
    for (uint32_t i = 0; i < st->nv; i++) {
        if (st->hits[i]) {
            poisson += 1.0 / sqrt((double)st->hits[i]);
            with++;
        } else {
            without++;
        }
        const float *e = &v->irradiance[3 * (size_t)i];
        double l = gi_luminance(gi_v3(e[0], e[1], e[2]));
        lum += l;
        lmin = fmin(lmin, l);
        lmax = fmax(lmax, l);
    }
    add_num(o, "mean_poisson_relative_error", with ? poisson / (double)with : 0.0);
    add_num(o, "vertices_without_hits", (double)without);
    cJSON *irr = cJSON_AddObjectToObject(o, "irradiance_luminance");
    add_num(irr, "mean", st->nv ? lum / st->nv : 0.0);
    add_num(irr, "min", st->nv ? lmin : 0.0);
    add_num(irr, "max", lmax);
    cJSON *rays = cJSON_AddObjectToObject(o, "rays");
    add_num(rays, "photon_paths", (double)st->rays_trace);
    add_num(rays, "visible_area", (double)st->rays_visibility);
    add_num(rays, "reference", (double)st->rays_reference);
    add_num(rays, "image", (double)st->rays_image);
    cJSON *sec = cJSON_AddObjectToObject(o, "seconds");
    add_num(sec, "photon_tracing", st->sec_trace);
    add_num(sec, "index_build", st->sec_build);
    add_num(sec, "density_estimation", st->sec_estimate);
    add_num(sec, "visible_area", st->sec_visibility);
    add_num(sec, "reference", st->sec_reference);
    add_num(sec, "image", st->sec_image);
    add_num(sec, "wall_bake", st->wall_bake);
    add_num(sec, "wall_image", st->wall_image);
    cJSON_AddItemToObject(o, "estimator_stats", stats_json(st));
    if (st->nref)
        cJSON_AddItemToObject(o, "reference", reference_json(job, st, v));
    if (st->anim) {
        cJSON_AddItemToObject(o, "animation", detp_anim_report(job, st));
    } else if (p->anim.enabled) { /* a camera path alone: the frame and its camera */
        cJSON *a = cJSON_AddObjectToObject(o, "animation");
        add_num(a, "frame", job->frame);
        add_num(a, "frames", p->anim.frames);
        gi_anim_report_camera(&p->anim, gi_job_camera(job), job->frame, a);
    }
    return o;
}

int detp_write_vertex_outputs(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                              gi_error *err)
{
    return write_ply(job, v, err) || write_glb(job, v, err) || write_bin(job, st, v, err) ? -1
                                                                                          : 0;
}

int detp_write_outputs(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                       gi_error *err)
{
    if (detp_write_vertex_outputs(job, st, v, err))
        return -1;
    return detp_write_report(job, st, v, err);
}

int detp_write_report(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                      gi_error *err)
{
    if (!gi_job_output(job, "json"))
        return 0;
    cJSON *doc = report(job, st, v);
    int rc = gi_write_json_output(job, "json", doc, err);
    cJSON_Delete(doc);
    return rc;
}
