/* rad_method: low-rank radiosity as a farm method.
 *
 * Tasks: first blocks of elements (kind FF: their form-factor rows, counted
 * at the tracked level), merged in task order into the count matrix; then,
 * once every row is in, the coordinator builds the factorization (2MF or
 * 2MCE), the SMW matrices and the solutions, and plans image tiles (kind
 * TILE: camera rays on workers, radiosity interpolated in the elements);
 * the last finish writes the outputs. The coordinator never calls Embree. */
#include <cblas.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "gi_clock.h"
#include "gi_log.h"
#include "gi_published.h"
#include "gi_tiles.h"
#include "gi_worker_ctx.h"
#include "rad.h"
#include "rad_2mce.h"
#include "rad_ff.h"
#include "rad_mesh.h"
#include "rad_patches.h"
#include "rad_rays.h"
#include "rad_task.h"
#include "rad_vertices.h"


/* Rays per form-factor task when task_elements is automatic. */
#define RAD_RAYS_PER_TASK (1u << 18)

enum { PHASE_FF, PHASE_IMAGES, PHASE_DONE };

typedef struct rad_state {
    int phase;
    gi_rad_mesh mesh;
    uint32_t tracked_level, tracked_nodes;
    size_t stride;
    uint16_t *counts; /* n x stride hits at the tracked level (NULL in relight mode) */
    gi_rad_ff_stats ff;

    /* Built when every row is in (or given, in relight mode). */
    int built;
    gi_rad_file_info info;
    gi_rad_model model;
    gi_rad_factor factor;
    const gi_rad_model *md; /* &model, or the relight model */
    const gi_rad_factor *f;
    const gi_rad_emissions *em;
    double threshold; /* 2MCE */
    uint32_t level_histogram[GI_RAD_MAX_LEVELS + 1];
    double build_seconds, prepare_seconds;
    float *E, *B; /* count x n x 3 */
    gi_rad_solve_info *solve;
    gi_image *images; /* image_count (= emission sets), when images are wanted */
    uint32_t image_count;
    char (*blob)[GI_HASH_HEX];
} rad_state;

double gi_rad_patch_area(const gi_scene *s, uint32_t patches)
{
    double total = 0.0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        double a = gi_scene_triangle_area(s, t);
        if (a > 0.0 && isfinite(a))
            total += a;
    }
    return patches ? total / patches : 0.0;
}

/* ------------------------------------------------------------------------ */
/* Parameters */

/* Several emission sets put their names into the files of the ply, exr
 * and png outputs (output_path): none may land on another output's file. */
static int check_output_names(const gi_job *job, gi_jv *v)
{
    const gi_rad_params *p = job->params;
    static const char *const kinds[] = {"factorization", "ply", "glb", "exr", "png", "report"};
    gi_rad_output_file outs[6];
    int n = 0;
    for (int k = 0; k < 6; k++) {
        const char *file = gi_job_output(job, kinds[k]);
        if (file)
            outs[n++] = (gi_rad_output_file){kinds[k], file, NULL, k >= 1 && k <= 4};
    }
    char msg[512];
    if (gi_rad_outputs_distinct(outs, n, &p->emissions, msg, sizeof msg))
        return gi_jv_fail(v, "outputs", "%s", msg);
    return 0;
}

/* radiosity.animation: a camera path, nothing else (the solution does not
 * depend on the camera: it is computed once, and each frame is its images
 * from the frame's camera). */
static int parse_camera_path(const gi_job *job, gi_rad_params *p, const cJSON *anim, gi_jv *v)
{
    if (!anim)
        return 0;
    static const char *const moving[] = {"object", "keyframes"};
    for (int i = 0; i < 2; i++)
        if (cJSON_IsObject(anim) && cJSON_GetObjectItemCaseSensitive(anim, moving[i])) {
            char path[64];
            snprintf(path, sizeof path, "radiosity.animation.%s", moving[i]);
            return gi_jv_fail(v, path,
                              "radiosity jobs take a camera path only (a moving object: detp, "
                              "pt or quadrature)");
        }
    if (cJSON_IsObject(anim) && !cJSON_GetObjectItemCaseSensitive(anim, "camera"))
        return gi_jv_fail(v, "radiosity.animation.camera", "missing (required)");
    if (gi_anim_parse(&p->anim, anim, "radiosity.animation", NULL, GI_ANIM_CAMERA, v))
        return -1;
    if (!gi_job_output(job, "exr") && !gi_job_output(job, "png"))
        return gi_jv_fail(v, "radiosity.animation.camera",
                          "a camera path needs an image output (\"exr\" or \"png\")");
    return 0;
}

static int rad_parse(gi_job *job, const cJSON *params, gi_jv *v)
{
    gi_rad_params *p = gi_xcalloc(1, sizeof *p);
    job->params = p;
    p->factorization = GI_RAD_2MF;
    p->patches = 256;
    p->levels = 2;
    p->patch_level = 0;
    p->max_level = 1;
    p->rays = 1024;
    p->image_spp = 16;
    p->tile = 32;
    gi_rad_solve_opts_default(&p->solve);
    if (!params) {
        gi_rad_emissions_scene(&p->emissions);
        return 0;
    }
    static const char *const keys[] = {
        "factorization", "patches",   "levels",        "patch_level", "max_level", "target_patches",
        "threshold",     "rays",      "task_elements", "solver",      "tolerance", "max_iterations",
        "emissions",     "image_spp", "tile",          "animation", NULL};
    static const char *const kinds[] = {"2mf", "2mce", NULL};
    static const char *const solvers[] = {"smw", "neumann", NULL};
    int kind = 0, solver = 0;
    int64_t patches = p->patches, levels = p->levels, patch_level = -1, max_level = -1, target = 0,
            rays = p->rays, task_elements = 0, max_it = p->solve.max_iterations, spp = p->image_spp,
            tile = p->tile;
    double threshold = -1.0;
    const cJSON *emissions = NULL, *anim = NULL;
    if (gi_jv_keys(v, params, "radiosity", keys) ||
        gi_jv_enum(v, params, "radiosity", "factorization", 0, kinds, &kind) ||
        gi_jv_int(v, params, "radiosity", "patches", 0, 1, 1 << 20, &patches) ||
        gi_jv_int(v, params, "radiosity", "levels", 0, 0, GI_RAD_MAX_LEVELS, &levels) ||
        gi_jv_int(v, params, "radiosity", "patch_level", 0, 0, GI_RAD_MAX_LEVELS, &patch_level) ||
        gi_jv_int(v, params, "radiosity", "max_level", 0, 0, GI_RAD_MAX_LEVELS, &max_level) ||
        gi_jv_int(v, params, "radiosity", "target_patches", 0, 1, GI_RAD_MAX_PATCHES, &target) ||
        gi_jv_number(v, params, "radiosity", "threshold", 0, 0.0, 1e30, &threshold) ||
        gi_jv_int(v, params, "radiosity", "rays", 0, 1, GI_RAD_MAX_RAYS, &rays) ||
        gi_jv_int(v, params, "radiosity", "task_elements", 0, 1, GI_RAD_MAX_ELEMENTS,
                  &task_elements) ||
        gi_jv_enum(v, params, "radiosity", "solver", 0, solvers, &solver) ||
        gi_jv_number(v, params, "radiosity", "tolerance", 0, 1e-12, 0.1, &p->solve.tolerance) ||
        gi_jv_int(v, params, "radiosity", "max_iterations", 0, 1, 1000000, &max_it) ||
        gi_jv_int(v, params, "radiosity", "image_spp", 0, 1, 4096, &spp) ||
        gi_jv_int(v, params, "radiosity", "tile", 0, 4, 4096, &tile) ||
        gi_jv_member_object(v, params, "radiosity", "animation", 0, &anim) ||
        parse_camera_path(job, p, anim, v))
        return -1;
    p->factorization = (gi_rad_method_kind)kind;
    p->patches = (uint32_t)patches;
    p->levels = (uint32_t)levels;
    p->rays = (uint32_t)rays;
    p->task_elements = (uint32_t)task_elements;
    p->solve.solver = (gi_rad_solver)solver;
    p->solve.max_iterations = (int)max_it;
    p->image_spp = (int)spp;
    p->tile = (int)tile;
    if (gi_job_check_tasks(v, "radiosity.tile", gi_tiles_count(job->width, job->height, p->tile),
                           "%d x %d pixels in tiles of %d", job->width, job->height, p->tile))
        return -1;
    if (!gi_rad_rays_valid(p->rays))
        return gi_jv_fail(v, "radiosity.rays",
                          "%u is not a perfect square (rays are stratified on an m x m grid: "
                          "e.g. 256, 1024, 4096)",
                          p->rays);
    if (patch_level >= 0 && kind != GI_RAD_2MF)
        return gi_jv_fail(v, "radiosity.patch_level", "only for \"factorization\": \"2mf\"");
    if ((max_level >= 0 || target > 0 || threshold >= 0.0) && kind != GI_RAD_2MCE)
        return gi_jv_fail(v, "radiosity",
                          "max_level, target_patches and threshold are for "
                          "\"factorization\": \"2mce\"");
    if (target > 0 && threshold >= 0.0)
        return gi_jv_fail(v, "radiosity.threshold", "give either target_patches or threshold");
    if (patch_level > (int64_t)p->levels)
        return gi_jv_fail(v, "radiosity.patch_level", "%lld is below the elements (levels = %u)",
                          (long long)patch_level, p->levels);
    if (max_level > (int64_t)p->levels)
        return gi_jv_fail(v, "radiosity.max_level", "%lld is below the elements (levels = %u)",
                          (long long)max_level, p->levels);
    if (patch_level >= 0)
        p->patch_level = (uint32_t)patch_level;
    if (max_level >= 0)
        p->max_level = (uint32_t)max_level;
    else if (p->max_level > p->levels)
        p->max_level = p->levels;
    p->target_patches = (uint32_t)target;
    p->has_threshold = threshold >= 0.0;
    p->threshold = threshold;
    if (gi_jv_member_array(v, params, "radiosity", "emissions", 0, &emissions))
        return -1;
    if (emissions) {
        p->has_emissions = 1;
        if (gi_rad_emissions_parse_json(v, emissions, "radiosity.emissions", &p->emissions))
            return -1;
        return check_output_names(job, v);
    }
    gi_rad_emissions_scene(&p->emissions);
    return 0;
}

static uint32_t tracked_level(const gi_rad_params *p)
{
    return p->factorization == GI_RAD_2MF ? p->patch_level : p->max_level;
}

static int rad_check_scene(gi_job *job, gi_error *err)
{
    gi_rad_params *p = job->params;
    const gi_scene *s = &job->scene;
    if (gi_anim_check_scene(&p->anim, job, err))
        return -1;
    /* Elements emit from their front face only: a two-sided emitter would
     * silently lose half its light (and its back would stay dark). */
    for (uint32_t m = 0; m < s->material_count; m++)
        if (s->materials[m].two_sided && !gi_is_black(s->materials[m].emission))
            return gi_fail(err, GI_EINVAL,
                           "%s: material \"%s\" is a two-sided emitter, and radiosity's "
                           "elements emit from their front face only: make the emitter two "
                           "one-sided faces back to back, or render with another method",
                           job->file, s->materials[m].name);
    if (gi_rad_emissions_check_scene(&p->emissions, s, job->file, "radiosity.emissions", err))
        return -1;
    /* The sizes, before any work: n, and k (2MF) or its bound (2MCE). */
    gi_rad_mesh m;
    if (gi_rad_mesh_build(&m, s, gi_rad_patch_area(s, p->patches), p->levels, err))
        return gi_error_prefix(err, "%s", job->file);
    uint64_t nodes = gi_rad_mesh_nodes(&m, tracked_level(p));
    uint32_t roots = m.root_count, n = m.element_count;
    gi_rad_mesh_free(&m);
    if (p->factorization == GI_RAD_2MF && nodes > GI_RAD_MAX_PATCHES)
        return gi_fail(err, GI_EINVAL,
                       "%s: radiosity: %llu patches at patch_level %u (limit %u): fewer "
                       "\"patches\" or a lower patch_level",
                       job->file, (unsigned long long)nodes, p->patch_level, GI_RAD_MAX_PATCHES);
    if (p->factorization == GI_RAD_2MCE && roots > GI_RAD_MAX_PATCHES)
        return gi_fail(err, GI_EINVAL, "%s: radiosity: %u level-0 patches (limit %u)", job->file,
                       roots, GI_RAD_MAX_PATCHES);
    /* The coordinator holds n x (nodes at the tracked level) 16-bit counts. */
    if ((uint64_t)n * nodes > ((uint64_t)1 << 31))
        return gi_fail(err, GI_EINVAL,
                       "%s: radiosity: %u elements x %llu tracked patches is more than 2^31 "
                       "form-factor counts (fewer patches, levels or a lower %s)",
                       job->file, n, (unsigned long long)nodes,
                       p->factorization == GI_RAD_2MF ? "patch_level" : "max_level");
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Coordinator: state */

static int images_wanted(const gi_job *job)
{
    return gi_job_output(job, "exr") || gi_job_output(job, "png");
}

static void state_free(rad_state *st)
{
    if (!st)
        return;
    gi_rad_mesh_free(&st->mesh);
    free(st->counts);
    gi_rad_model_free(&st->model);
    gi_rad_factor_free(&st->factor);
    free(st->E);
    free(st->B);
    free(st->solve);
    for (uint32_t i = 0; i < st->image_count; i++)
        gi_image_free(&st->images[i]);
    free(st->images);
    free(st->blob);
    free(st);
}

static rad_state *state_new(gi_job *job, gi_error *err)
{
    const gi_rad_params *p = job->params;
    rad_state *st = gi_xcalloc(1, sizeof *st);
    if (gi_rad_mesh_build(&st->mesh, &job->scene, gi_rad_patch_area(&job->scene, p->patches),
                          p->levels, err)) {
        free(st);
        return NULL;
    }
    if (p->relight_factor)
        return st;
    st->tracked_level = tracked_level(p);
    st->tracked_nodes = gi_rad_mesh_nodes(&st->mesh, st->tracked_level);
    st->stride = (st->tracked_nodes + 7) & ~(size_t)7;
    st->counts = gi_try_calloc((size_t)st->mesh.element_count * st->stride, sizeof *st->counts, err,
                               "radiosity form-factor counts");
    if (!st->counts) {
        state_free(st);
        return NULL;
    }
    return st;
}

/* The factorization (from the counts), the SMW matrices and the solution
 * of every emission set. Deterministic: a restored checkpoint rebuilds
 * exactly the same bits. */
static int build(gi_job *job, rad_state *st, gi_error *err)
{
    const gi_rad_params *p = job->params;
    /* One BLAS thread: LAPACK's results then do not depend on the core
     * count of the coordinator (the pool uses the cores anyway). */
    openblas_set_num_threads(1);
    double t0 = gi_now();
    if (p->relight_factor) {
        st->info = *p->relight_info;
        st->md = p->relight_model;
        st->f = p->relight_factor;
        st->em = p->relight_emissions;
        /* The images interpolate per element of this scene's mesh: it must
         * be the mesh the factorization was built on (same elements, same
         * vertices where they are). */
        gi_rad_vertices v;
        memset(&v, 0, sizeof v);
        if (st->md->n == st->mesh.element_count &&
            gi_rad_vertices_build(&v, &st->mesh, &job->scene, err))
            return -1;
        int same = st->md->n == st->mesh.element_count && v.count == st->md->vertices.count &&
                   memcmp(v.positions, st->md->vertices.positions,
                          (size_t)v.count * sizeof *v.positions) == 0 &&
                   memcmp(v.corner, st->md->vertices.corner,
                          3 * (size_t)st->md->n * sizeof *v.corner) == 0;
        gi_rad_vertices_free(&v);
        if (!same)
            return gi_fail(err, GI_EINVAL,
                           "%s: the factorization was not built on this scene's mesh (%u "
                           "elements there, %u here): was the scene or the job changed?",
                           job->file, st->md->n, st->mesh.element_count);
    } else {
        gi_rad_patches pt;
        if (p->factorization == GI_RAD_2MF) {
            gi_rad_2mf_patches(&st->mesh, p->patch_level, &pt);
        } else {
            gi_rad_2mce c;
            if (gi_rad_2mce_metrics(&c, &st->mesh, st->counts, st->stride, p->max_level, p->rays,
                                    err))
                return -1;
            int rc;
            if (p->has_threshold) {
                st->threshold = p->threshold;
                rc = gi_rad_2mce_select(&c, &st->mesh, p->threshold, &pt, err);
            } else {
                uint32_t target = p->target_patches ? p->target_patches : 2 * st->mesh.root_count;
                if (target > GI_RAD_MAX_PATCHES)
                    target = GI_RAD_MAX_PATCHES;
                rc = gi_rad_2mce_tune(&c, &st->mesh, target, &st->threshold, &pt, err);
            }
            gi_rad_2mce_free(&c);
            if (rc)
                return -1;
            if (pt.k > GI_RAD_MAX_PATCHES) {
                gi_rad_patches_free(&pt);
                return gi_fail(err, GI_EINVAL,
                               "%s: 2mce chose more than %u patches: raise the "
                               "threshold or lower target_patches",
                               job->file, GI_RAD_MAX_PATCHES);
            }
        }
        for (uint32_t i = 0; i < pt.k; i++)
            st->level_histogram[pt.p[i].level]++;
        int rc = gi_rad_factor_from_counts(&st->factor, &st->mesh, st->counts, st->stride, p->rays,
                                           &pt, err);
        gi_rad_patches_free(&pt);
        if (rc || gi_rad_model_build(&st->model, &st->mesh, &job->scene, err))
            return -1;
        gi_rad_model_reflectance(&st->model, st->factor.rho);
        st->build_seconds = gi_now() - t0;
        t0 = gi_now();
        if (gi_rad_factor_prepare(&st->factor, err))
            return gi_error_prefix(err, "%s", job->file);
        st->prepare_seconds = gi_now() - t0;
        snprintf(st->info.method, sizeof st->info.method, "%s",
                 p->factorization == GI_RAD_2MF ? "2mf" : "2mce");
        st->info.levels = st->mesh.levels;
        st->info.roots = st->mesh.root_count;
        st->md = &st->model;
        st->f = &st->factor;
        st->em = &p->emissions;
    }
    size_t n3 = 3 * (size_t)st->f->n, count = st->em->count;
    st->E = gi_try_malloc(count * n3 * sizeof *st->E, err, "radiosity solutions");
    st->B = gi_try_malloc(count * n3 * sizeof *st->B, err, "radiosity solutions");
    st->solve = gi_xcalloc(count, sizeof *st->solve);
    if (!st->E || !st->B)
        return -1;
    gi_rad_solve_opts so = p->solve;
    if (p->relight_factor)
        so.solver = GI_RAD_SMW; /* relighting is the direct solve */
    if (gi_rad_solve_emissions(st->f, st->md, st->em, &so, st->E, st->B, st->solve, err))
        return gi_error_prefix(err, "%s", job->file);
    st->built = 1;
    return 0;
}

/* Per-corner radiance of emission i (Gouraud data for the image tiles):
 * published, fetched by workers by hash. */
static int publish(gi_job *job, rad_state *st, gi_error *err)
{
    const gi_rad_model *md = st->md;
    size_t n3 = 3 * (size_t)md->n;
    st->blob = gi_xcalloc(st->em->count, sizeof *st->blob);
    float *vv = gi_try_malloc(3 * (size_t)md->vertices.count * sizeof *vv, err, "image data");
    float *corner = gi_try_malloc(3 * n3 * sizeof *corner, err, "image data");
    if (!vv || !corner) {
        free(vv);
        free(corner);
        return -1;
    }
    int rc = 0;
    for (uint32_t i = 0; i < st->em->count && rc == 0; i++) {
        rc = gi_rad_vertex_values(&md->vertices, md->n, md->area, st->B + i * n3, vv, err);
        if (rc)
            break;
        for (size_t c = 0; c < n3; c++)
            memcpy(&corner[3 * c], &vv[3 * (size_t)md->vertices.corner[c]], 3 * sizeof *vv);
        gi_buf b;
        gi_buf_init(&b);
        gi_buf_put_f32s(&b, corner, 3 * n3);
        /* What the workers would refuse fails the job here, naming it. */
        char hash[GI_HASH_HEX];
        gi_hash_hex(b.data, b.len, hash);
        float *checked = gi_rad_corners_decode(&b, hash, md->n, err);
        if (checked)
            gi_job_publish(job, b.data, b.len, st->blob[i]);
        else
            rc = gi_error_prefix(err, "%s: emission set %u", job->file, i);
        free(checked);
        gi_buf_free(&b);
    }
    free(vv);
    free(corner);
    return rc;
}

static int alloc_images(gi_job *job, rad_state *st, gi_error *err)
{
    st->images = gi_xcalloc(st->em->count, sizeof *st->images);
    st->image_count = st->em->count;
    for (uint32_t i = 0; i < st->em->count; i++)
        if (gi_image_init(&st->images[i], job->width, job->height, 3, NULL, err))
            return -1;
    return 0;
}

static void plan_tiles(gi_job *job, rad_state *st, gi_task_queue *q)
{
    const gi_rad_params *p = job->params;
    gi_buf extra;
    gi_buf_init(&extra);
    for (uint32_t i = 0; i < st->em->count; i++) {
        gi_buf_reset(&extra);
        gi_buf_put_u32(&extra, i);
        gi_buf_put_str(&extra, st->blob[i]);
        if (p->anim.enabled) /* the frame's camera */
            gi_buf_put_u32(&extra, job->frame);
        gi_tiles_plan(q, RAD_TASK_TILE, job->width, job->height, p->tile, p->image_spp, &extra);
    }
    gi_buf_free(&extra);
}

/* ------------------------------------------------------------------------ */
/* Coordinator: plan, merge, finish */

static int rad_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    const gi_rad_params *p = job->params;
    rad_state *st = state_new(job, err);
    if (!st)
        return gi_error_prefix(err, "%s", job->file);
    job->state = st;
    gi_anim_set_frame(&p->anim, job, 0); /* a camera path's: its images name the frame */
    if (p->relight_factor) {
        /* Relight mode: the factorization exists; only images are left. */
        if (build(job, st, err))
            return -1;
        if (!images_wanted(job)) {
            st->phase = PHASE_DONE;
            return gi_fail(err, GI_EINVAL,
                           "%s: relight with images, but the job asks for no "
                           "\"exr\" or \"png\" output",
                           job->file);
        }
        if (publish(job, st, err) || alloc_images(job, st, err))
            return -1;
        plan_tiles(job, st, q);
        st->phase = PHASE_IMAGES;
        return 0;
    }
    uint32_t n = st->mesh.element_count;
    uint32_t block = p->task_elements ? p->task_elements : RAD_RAYS_PER_TASK / p->rays;
    if (block == 0)
        block = 1;
    for (uint32_t e0 = 0; e0 < n; e0 += block) {
        uint32_t e1 = n - e0 < block ? n : e0 + block;
        gi_task *t = gi_task_queue_add(q, RAD_TASK_FF, (double)(e1 - e0) * p->rays);
        gi_buf_put_u32(&t->payload, e0);
        gi_buf_put_u32(&t->payload, e1);
    }
    gi_info("%s: radiosity: %u elements in %u level-0 patches, %u rays each, %zu tasks", job->name,
            n, st->mesh.root_count, p->rays, q->count);
    return 0;
}

int gi_rad_task_block_decode(const gi_task *t, uint32_t n, uint32_t *e0, uint32_t *e1,
                             gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, t->payload.data, t->payload.len, "radiosity task");
    *e0 = gi_get_u32(&r);
    *e1 = gi_get_u32(&r);
    if (gi_reader_finish(&r, err))
        return -1;
    if (*e0 >= *e1 || *e1 > n)
        return gi_fail(err, GI_EPROTO, "radiosity task %llu: element block out of range",
                       (unsigned long long)t->id);
    return 0;
}

int gi_rad_task_tile_decode(const gi_job *job, const gi_task *t, uint32_t emissions,
                            gi_rad_tile_task *tt, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, t->payload.data, t->payload.len, "radiosity tile task");
    if (gi_tile_read(&r, job->width, job->height, &tt->tile, err))
        return -1;
    const gi_rad_params *p = job->params;
    tt->emission = gi_get_u32(&r);
    char *hash = gi_get_str(&r, GI_HASH_HEX - 1);
    tt->frame = p->anim.enabled ? gi_get_u32(&r) : 0;
    if (gi_reader_finish(&r, err)) {
        free(hash);
        return -1;
    }
    if (p->anim.enabled && tt->frame >= p->anim.frames) {
        free(hash);
        return gi_fail(err, GI_EPROTO, "radiosity tile task %llu: frame %u of %u",
                       (unsigned long long)t->id, tt->frame, p->anim.frames);
    }
    int ok = hash && gi_hash_is_valid(hash) && tt->emission < emissions;
    if (ok)
        memcpy(tt->hash, hash, GI_HASH_HEX);
    free(hash);
    if (!ok)
        return gi_fail(err, GI_EPROTO, "radiosity tile task %llu: bad emission or data hash",
                       (unsigned long long)t->id);
    return 0;
}

static void put_hits(void *user, uint32_t e, uint32_t node, uint32_t hits)
{
    rad_state *st = user;
    st->counts[(size_t)e * st->stride + node] = (uint16_t)hits;
}

static void ignore_hits(void *user, uint32_t e, uint32_t node, uint32_t hits)
{
    (void)user;
    (void)e;
    (void)node;
    (void)hits;
}

/* Whatever rad_merge would refuse is refused here, as the result arrives:
 * a result that does not decode then fails its task's run, which is retried,
 * instead of failing the whole job at merge (and merge never stops half way
 * through a block's rows). */
static int rad_check_result(const gi_job *job, const gi_task *t, const gi_buf *result,
                            gi_buf *decoded, gi_error *err)
{
    (void)decoded; /* no merge_decoded */
    const gi_rad_params *p = job->params;
    const rad_state *st = job->state;
    if (t->kind == RAD_TASK_FF && st->counts) {
        uint32_t e0, e1;
        gi_rad_ff_stats scratch = {0};
        if (gi_rad_task_block_decode(t, st->mesh.element_count, &e0, &e1, err))
            return -1;
        return gi_rad_ff_decode(result->data, result->len, e0, e1, st->tracked_nodes, p->rays,
                                ignore_hits, NULL, &scratch, err);
    }
    gi_rad_tile_task tt;
    if (t->kind != RAD_TASK_TILE || !st->images)
        return 0;
    if (gi_rad_task_tile_decode(job, t, st->em->count, &tt, err))
        return -1;
    return gi_tile_check_result(&tt.tile, result->data, result->len, err);
}

/* Tests only (gi_method.h): form-factor rows hold counts, summed (the
 * first row's d2, after u32 nnz, escaped and backface); tiles, pixels. */
static int rad_damage_result(const gi_job *job, const gi_task *t, gi_buf *result,
                             gi_damage how)
{
    (void)job;
    if (t->kind == RAD_TASK_FF) {
        if (how != GI_DAMAGE_HUGE || result->len < 20)
            return 1;
        gi_le_put_u64(result->data + 12, UINT64_MAX);
        return 0;
    }
    if (how != GI_DAMAGE_NAN || result->len < 4)
        return 1;
    float v = NAN;
    memcpy(result->data, &v, 4);
    return 0;
}

static int rad_merge(gi_job *job, const gi_task *t, const gi_buf *result, gi_task_queue *fq,
                     gi_error *err)
{
    const gi_rad_params *p = job->params;
    rad_state *st = job->state;
    if (t->kind == RAD_TASK_FF && st->counts) {
        uint32_t e0, e1;
        if (gi_rad_task_block_decode(t, st->mesh.element_count, &e0, &e1, err))
            return -1;
        return gi_rad_ff_decode(result->data, result->len, e0, e1, st->tracked_nodes, p->rays,
                                put_hits, st, &st->ff, err);
    }
    if (t->kind == RAD_TASK_TILE && st->images) {
        gi_rad_tile_task tt;
        if (gi_rad_task_tile_decode(job, t, st->em->count, &tt, err))
            return -1;
        return gi_tile_merge(&st->images[tt.emission], &tt.tile, result, err);
    }
    return gi_fail(err, GI_EPROTO, "radiosity: unexpected result for task %llu (kind %u)",
                   (unsigned long long)t->id, t->kind);
}

static cJSON *report(const gi_job *job, const rad_state *st)
{
    const gi_rad_params *p = job->params;
    const gi_rad_factor *f = st->f;
    cJSON *o = gi_rad_report_new(&st->info, f);
    cJSON_AddStringToObject(o, "job", job->name);
    if (!p->relight_factor) {
        if (p->factorization == GI_RAD_2MCE) {
            cJSON *c = cJSON_AddObjectToObject(o, "2mce");
            cJSON_AddNumberToObject(c, "max_level", p->max_level);
            cJSON_AddNumberToObject(c, "threshold", st->threshold);
            cJSON *h = cJSON_AddArrayToObject(c, "patches_per_level");
            for (uint32_t l = 0; l <= p->max_level; l++)
                cJSON_AddItemToArray(h, cJSON_CreateNumber(st->level_histogram[l]));
        }
        double rays = (double)f->n * f->rays;
        cJSON *ff = cJSON_AddObjectToObject(o, "form_factors");
        cJSON_AddNumberToObject(ff, "rays", rays);
        cJSON_AddNumberToObject(ff, "escaped_fraction", (double)st->ff.escaped / rays);
        cJSON_AddNumberToObject(ff, "backface_fraction", (double)st->ff.backface / rays);
        /* Mean row sum of F: 1 in a closed scene. */
        cJSON_AddNumberToObject(ff, "mean_row_sum",
                                1.0 - (double)(st->ff.escaped + st->ff.backface) / rays);
        /* Relative Frobenius error of the sampled F at the tracked level
         * (rad_ff.h: from the even/odd halves of every element's rays). */
        cJSON_AddNumberToObject(ff, "relative_error_estimate",
                                st->ff.h2 ? sqrt((double)st->ff.d2 / (double)st->ff.h2) : 0.0);
        cJSON *tm = cJSON_AddObjectToObject(o, "timings_ms");
        cJSON_AddNumberToObject(tm, "factorization", st->build_seconds * 1e3);
        cJSON_AddNumberToObject(tm, "smw_matrices", st->prepare_seconds * 1e3);
    }
    gi_rad_report_add_solutions(o, st->md, st->em, st->E, st->B, st->solve);
    return o;
}

/* Output file of `kind` for emission i: the job's name, or with the
 * emission's name inserted when there are several sets (or a relight). */
static char *output_path(const gi_job *job, const rad_state *st, const char *kind, uint32_t i)
{
    const gi_rad_params *p = job->params;
    const char *file = gi_job_output(job, kind);
    if (!file)
        return NULL;
    char *name = p->has_emissions || p->relight_factor
                     ? gi_rad_output_name(file, st->em->items[i].name)
                     : gi_xstrdup(file);
    char *path = gi_job_output_path(job, name);
    free(name);
    return path;
}

/* The solution's outputs: the factorization, and per emission set the
 * per-vertex radiosity (PLY, glTF). */
static int write_solution(gi_job *job, rad_state *st, gi_error *err)
{
    const gi_rad_params *p = job->params;
    const char *ff = gi_job_output(job, "factorization");
    if (ff && !p->relight_factor) {
        char *path = gi_job_output_path(job, ff);
        int rc = gi_rad_file_write(path, &st->info, st->md, st->f, err);
        if (rc == 0)
            gi_job_note_output(job, "factorization", path);
        free(path);
        if (rc)
            return -1;
    }
    size_t n3 = 3 * (size_t)st->f->n;
    for (uint32_t i = 0; i < st->em->count; i++) {
        static const char *const vertex_kinds[] = {"ply", "glb"};
        for (int k = 0; k < 2; k++) {
            char *path = output_path(job, st, vertex_kinds[k], i);
            if (!path)
                continue;
            int rc = gi_rad_vertex_output_write(path, vertex_kinds[k], st->md, st->B + i * n3,
                                                job->exposure, err);
            if (rc == 1)
                gi_job_note_output(job, vertex_kinds[k], path);
            free(path);
            if (rc < 0)
                return -1;
        }
    }
    return 0;
}

/* Per emission set, the camera images (if the job wants them). */
static int write_images(gi_job *job, rad_state *st, gi_error *err)
{
    for (uint32_t i = 0; st->images && i < st->em->count; i++) {
        static const char *const kinds[] = {"exr", "png"};
        for (int k = 0; k < 2; k++) {
            char *path = output_path(job, st, kinds[k], i);
            if (!path)
                continue;
            int rc = gi_image_check_finite(&st->images[i], path, err);
            if (rc == 0)
                rc = k == 0 ? gi_exr_write(path, &st->images[i], err)
                            : gi_png_write(path, &st->images[i], job->exposure, err);
            if (rc == 0)
                gi_job_note_output(job, kinds[k], path);
            free(path);
            if (rc)
                return -1;
        }
    }
    return 0;
}

static int write_report(gi_job *job, rad_state *st, gi_error *err)
{
    const gi_rad_params *p = job->params;
    const char *rep = gi_job_output(job, "report");
    if (rep) {
        cJSON *doc = report(job, st);
        char *path;
        if (p->relight_factor) {
            char *name = gi_rad_output_name(rep, "relight");
            path = gi_job_output_path(job, name);
            free(name);
        } else {
            path = gi_job_output_path(job, rep);
        }
        int rc = gi_rad_write_json(path, doc, err);
        cJSON_Delete(doc);
        if (rc == 0)
            gi_job_note_output(job, "report", path);
        free(path);
        if (rc)
            return -1;
    }
    return 0;
}

static int write_outputs(gi_job *job, rad_state *st, gi_error *err)
{
    if (write_solution(job, st, err) || write_images(job, st, err))
        return -1;
    return write_report(job, st, err);
}

/* A camera path's frame: its images, and with frame 0 the solution's
 * outputs and the report, once and under their own names (no frame
 * number: the solution is the same in every frame); then the frames after
 * it whose camera holds, written again; then the next frame whose camera
 * moves gets its tiles. A failed write keeps the frame, its images and the
 * phase, to be written again. */
static int write_camera_frame(gi_job *job, void *ctx, gi_error *err)
{
    rad_state *st = ctx;
    if (job->frame == 0) {
        job->in_frame = 0;
        int rc = write_solution(job, st, err) || write_report(job, st, err);
        job->in_frame = 1;
        if (rc)
            return -1;
    }
    return write_images(job, st, err);
}

static int write_camera_frames(gi_job *job, rad_state *st, gi_task_queue *fq, gi_error *err)
{
    const gi_rad_params *p = job->params;
    uint32_t frame = job->frame;
    int rc = gi_anim_write_frames(&p->anim, job, &frame, write_camera_frame, st, err);
    if (rc <= 0) {
        if (rc == 0)
            st->phase = PHASE_DONE;
        return rc;
    }
    plan_tiles(job, st, fq);
    return 0;
}

static int rad_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    const gi_rad_params *p = job->params;
    rad_state *st = job->state;
    if (st->phase == PHASE_FF) {
        if (!st->built && build(job, st, err))
            return -1;
        gi_info("%s: radiosity: %s factorization, n = %u, k = %u", job->name, st->info.method,
                st->f->n, st->f->k);
        if (images_wanted(job)) {
            if (publish(job, st, err) || alloc_images(job, st, err))
                return -1;
            plan_tiles(job, st, fq);
            st->phase = PHASE_IMAGES;
            return 0;
        }
    }
    if (st->phase == PHASE_IMAGES && p->anim.enabled)
        return write_camera_frames(job, st, fq, err);
    if (st->phase != PHASE_DONE) {
        if (write_outputs(job, st, err))
            return -1;
        st->phase = PHASE_DONE;
    }
    return 0;
}

/* A failed write leaves the phase as it was: finish builds (from the counts)
 * and writes again. */
static int rad_can_finish_again(const gi_job *job)
{
    const rad_state *st = job->state;
    return st->phase != PHASE_DONE;
}

/* The image tiles the form factors are followed by, before they are planned. */
static void rad_progress(const gi_job *job, gi_job_progress *out)
{
    const gi_rad_params *p = job->params;
    const rad_state *st = job->state;
    double images = p->emissions.count * gi_tiles_cost(job->width, job->height, p->image_spp);
    out->cost_unplanned = st->phase == PHASE_FF && images_wanted(job) ? images : 0;
    if (p->anim.enabled) { /* a camera path: the solution once, then images each frame */
        out->frame = job->frame;
        out->frames = p->anim.frames;
        out->first_frame_cost = (double)st->mesh.element_count * p->rays + images;
        out->later_frame_cost = images;
    }
}

/* ------------------------------------------------------------------------ */
/* Checkpoints: the counts (everything else is rebuilt from them, bit for
 * bit), and the image tiles merged so far. */

static int rad_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    const rad_state *st = job->state;
    gi_buf_put_u32(out, (uint32_t)st->phase);
    gi_buf_put_u32(out, st->mesh.element_count);
    gi_buf_put_u64(out, st->counts ? st->stride : 0);
    if (st->counts) {
        size_t cells = (size_t)st->mesh.element_count * st->stride;
        uint8_t *dst = gi_buf_grow(out, 2 * cells);
        for (size_t i = 0; i < cells; i++)
            gi_le_put_u16(dst + 2 * i, st->counts[i]);
    }
    gi_buf_put_u64(out, st->ff.escaped);
    gi_buf_put_u64(out, st->ff.backface);
    gi_buf_put_u64(out, st->ff.d2);
    gi_buf_put_u64(out, st->ff.h2);
    if (st->phase == PHASE_IMAGES)
        for (uint32_t i = 0; i < st->em->count; i++)
            gi_buf_put_f32s(out, st->images[i].pixels, (size_t)job->width * job->height * 3);
    const gi_rad_params *p = job->params;
    if (p->anim.enabled) /* a camera path's frame (its images above) */
        gi_buf_put_u32(out, job->frame);
    return 0;
}

static int rad_load(gi_job *job, gi_reader *in, gi_error *err)
{
    rad_state *st = state_new(job, err);
    if (!st)
        return -1;
    job->state = st;
    uint32_t phase = gi_get_u32(in), n = gi_get_u32(in);
    uint64_t stride = gi_get_u64(in);
    if (in->failed || phase > PHASE_DONE || n != st->mesh.element_count ||
        stride != (st->counts ? st->stride : 0))
        return gi_fail(err, GI_EPROTO, "radiosity checkpoint: does not match the job's mesh");
    if (st->counts) {
        size_t cells = (size_t)n * st->stride;
        if (2 * cells > in->left)
            return gi_fail(err, GI_EPROTO, "radiosity checkpoint: truncated counts");
        for (size_t i = 0; i < cells; i++)
            st->counts[i] = gi_get_u16(in);
    }
    st->ff.escaped = gi_get_u64(in);
    st->ff.backface = gi_get_u64(in);
    st->ff.d2 = gi_get_u64(in);
    st->ff.h2 = gi_get_u64(in);
    if (in->failed)
        return gi_fail(err, GI_EPROTO, "radiosity checkpoint: truncated");
    st->phase = (int)phase;
    if (phase == PHASE_IMAGES) {
        /* Rebuild what finish made (same bits), publish the tiles' data
         * again (same hashes), and take back the merged tiles. */
        if (build(job, st, err) || publish(job, st, err) || alloc_images(job, st, err))
            return -1;
        for (uint32_t i = 0; i < st->em->count; i++)
            if (gi_get_f32s(in, st->images[i].pixels, (size_t)job->width * job->height * 3))
                return gi_fail(err, GI_EPROTO, "radiosity checkpoint: truncated images");
    }
    const gi_rad_params *p = job->params;
    if (p->anim.enabled) {
        uint32_t frame = gi_get_u32(in);
        if (in->failed || frame >= p->anim.frames)
            return gi_fail(err, GI_EPROTO, "radiosity checkpoint: not one of this camera path");
        gi_anim_set_frame(&p->anim, job, frame);
    }
    return 0;
}

static void rad_release(gi_job *job)
{
    state_free(job->state);
    gi_rad_params *p = job->params;
    if (p)
        gi_rad_emissions_free(&p->emissions);
    free(p);
    job->state = job->params = NULL;
}

/* ------------------------------------------------------------------------ */
/* Worker side */

typedef struct rad_worker {
    gi_rad_mesh mesh;
    gi_rad_strata strata;
    /* The last image data fetched (tiles of one emission come together). */
    char hash[GI_HASH_HEX];
    float *corner; /* n x 3 corners x RGB */
} rad_worker;

static void worker_free(void *p)
{
    rad_worker *w = p;
    gi_rad_mesh_free(&w->mesh);
    gi_rad_strata_free(&w->strata);
    free(w->corner);
    free(w);
}

float *gi_rad_corners_decode(const gi_buf *blob, const char *hash, uint32_t elements,
                             gi_error *err)
{
    gi_published_layout l = {"radiosity: published image data", "element", "elements",
                             elements, 9};
    return gi_published_floats(blob, hash, &l, err);
}

static const float *worker_corners(gi_worker_ctx *ctx, rad_worker *w, const char *hash,
                                   gi_error *err)
{
    if (w->corner && strcmp(w->hash, hash) == 0)
        return w->corner;
    const gi_buf *blob;
    if (gi_worker_blob(ctx, hash, &blob, err))
        return NULL;
    free(w->corner);
    w->corner = gi_rad_corners_decode(blob, hash, w->mesh.element_count, err);
    if (!w->corner)
        return NULL;
    memcpy(w->hash, hash, GI_HASH_HEX);
    return w->corner;
}

static rad_worker *worker_state(gi_worker_ctx *ctx, gi_error *err)
{
    if (ctx->method_state)
        return ctx->method_state;
    const gi_rad_params *p = ctx->job.params;
    rad_worker *w = gi_xcalloc(1, sizeof *w);
    if (gi_rad_mesh_build(&w->mesh, &ctx->job.scene, gi_rad_patch_area(&ctx->job.scene, p->patches),
                          p->levels, err) ||
        gi_rad_strata_init(&w->strata, p->rays, err)) {
        worker_free(w);
        return NULL;
    }
    ctx->method_state = w;
    ctx->method_state_free = worker_free;
    return w;
}

typedef struct shade_ctx {
    const gi_rad_mesh *m;
    const gi_scene *s;
    const float *corner; /* n x 3 corners x RGB */
} shade_ctx;

/* Gouraud: the element under the hit, its corners' radiance interpolated
 * with the hit's barycentric coordinates in the element. Elements are
 * one-sided: their back faces are black. */
static gi_vec3 shade(void *user, const gi_hit *h, gi_vec3 p, gi_vec3 wo)
{
    const shade_ctx *sc = user;
    if (gi_dot(wo, sc->s->tri_normal[h->tri]) <= 0.0f)
        return gi_v3(0.0f, 0.0f, 0.0f);
    float b[3];
    uint32_t e = gi_rad_mesh_locate(sc->m, h->tri, h->u, h->v, b);
    if (e == UINT32_MAX)
        return gi_v3(0.0f, 0.0f, 0.0f);
    const float *c = sc->corner + 9 * (size_t)e;
    return gi_v3(b[0] * c[0] + b[1] * c[3] + b[2] * c[6], b[0] * c[1] + b[1] * c[4] + b[2] * c[7],
                 b[0] * c[2] + b[1] * c[5] + b[2] * c[8]);
}

static int rad_run(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    const gi_rad_params *p = ctx->job.params;
    rad_worker *w = worker_state(ctx, err);
    if (!w)
        return -1;
    if (t->kind == RAD_TASK_FF) {
        uint32_t e0, e1;
        if (gi_rad_task_block_decode(t, w->mesh.element_count, &e0, &e1, err))
            return -1;
        gi_rad_ff_opts o = {ctx->job.seed, tracked_level(p)};
        if (gi_rad_ff_rows(&ctx->rt, &ctx->job.scene, &w->mesh, &w->strata, &o, e0, e1, result,
                           err))
            return -1;
        ctx->stats.samples = (uint64_t)(e1 - e0) * p->rays;
        return 0;
    }
    if (t->kind == RAD_TASK_TILE) {
        gi_rad_tile_task tt;
        if (gi_rad_task_tile_decode(&ctx->job, t, UINT32_MAX, &tt, err))
            return -1;
        const float *corner = worker_corners(ctx, w, tt.hash, err);
        if (!corner)
            return -1;
        shade_ctx sc = {&w->mesh, &ctx->job.scene, corner};
        ctx->stats.samples = (uint64_t)(tt.tile.x1 - tt.tile.x0) * (tt.tile.y1 - tt.tile.y0) *
                             (uint64_t)p->image_spp;
        gi_camera cam; /* a still's: the job's */
        gi_anim_camera(&p->anim, gi_job_camera(&ctx->job), tt.frame, &cam);
        return gi_tile_render(&ctx->rt, &ctx->job, &cam, &tt.tile, p->image_spp, shade, &sc,
                              result, err);
    }
    return gi_fail(err, GI_EPROTO, "radiosity: unknown task kind %u", t->kind);
}

static const char *const rad_outputs[] = {"exr",    "png",           "ply", "glb",
                                           "report", "factorization", NULL};

const gi_method gi_method_radiosity = {
    .name = "radiosity",
    .summary = "low-rank radiosity (2MF/2MCE factorizations, SMW solve), fast relighting",
    .unit = "rays",
    .output_kinds = rad_outputs,
    .default_outputs = rad_outputs,
    .parse = rad_parse,
    .check_scene = rad_check_scene,
    .plan = rad_plan,
    .run = rad_run,
    .check_result = rad_check_result,
    .damage_result = rad_damage_result,
    .merge = rad_merge,
    .finish = rad_finish,
    .save = rad_save,
    .load = rad_load,
    .progress = rad_progress,
    .can_finish_again = rad_can_finish_again,
    .release = rad_release,
};
