/* gi_job: job documents (docs/job-format.md): parsing, validation, scene
 * loading, outputs. */
#include "gi_job.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "gi_camera.h"
#include "gi_fs.h"
#include "gi_json.h"

static int valid_file_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > 200 || s[0] == '.')
        return 0;
    for (const char *p = s; *p; p++) {
        char c = *p;
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '_' || c == '-'))
            return 0;
    }
    return 1;
}

static char *default_name(const char *file)
{
    const char *base = strrchr(file, '/');
    base = base ? base + 1 : file;
    char *name = gi_xstrdup(base);
    char *dot = strrchr(name, '.');
    if (dot && dot != name)
        *dot = '\0';
    if (!valid_file_name(name)) {
        free(name);
        name = gi_xstrdup("job");
    }
    return name;
}

static int parse_outputs(gi_jv *v, gi_job *job, const cJSON *outs)
{
    const gi_method *m = job->method;
    if (!outs) {
        for (int i = 0; m->default_outputs[i]; i++) {
            /* A report is JSON: its default name says so, without being
             * the job file's own name (NAME.json, beside which
             * `gi render NAME.json --out .` would write it). */
            const char *kind = m->default_outputs[i];
            int report = strcmp(kind, "report") == 0 || strcmp(kind, "json") == 0;
            char file[300];
            if (report)
                snprintf(file, sizeof file, "%s-report.json", job->name);
            else
                snprintf(file, sizeof file, "%s.%s", job->name, kind);
            job->outputs[job->output_count].kind = gi_xstrdup(m->default_outputs[i]);
            job->outputs[job->output_count].file = gi_xstrdup(file);
            job->output_count++;
        }
        return 0;
    }
    if (gi_jv_keys(v, outs, "outputs", m->output_kinds))
        return -1;
    for (const cJSON *o = outs->child; o; o = o->next) {
        char p[512];
        gi_json_path(p, sizeof p, "outputs", o->string);
        if (!cJSON_IsString(o) || !valid_file_name(o->valuestring))
            return gi_jv_fail(v, p,
                              "expected a plain file name (letters, digits, '.', '_', '-'; "
                              "no directories)");
        for (int i = 0; i < job->output_count; i++)
            if (strcmp(job->outputs[i].file, o->valuestring) == 0)
                return gi_jv_fail(v, p, "\"%s\" is already the %s output", o->valuestring,
                                  job->outputs[i].kind);
        job->outputs[job->output_count].kind = gi_xstrdup(o->string);
        job->outputs[job->output_count].file = gi_xstrdup(o->valuestring);
        job->output_count++;
    }
    if (job->output_count == 0)
        return gi_jv_fail(v, "outputs", "no outputs requested");
    return 0;
}

int gi_job_parse(const char *text, size_t len, const char *file, gi_job *job, gi_error *err)
{
    memset(job, 0, sizeof *job);
    job->file = gi_xstrdup(file);
    gi_manifest_init(&job->manifest);
    if (len > GI_JOB_MAX_BYTES)
        return gi_fail(err, GI_EINVAL, "%s: job is %zu bytes (limit %u)", file, len,
                       GI_JOB_MAX_BYTES);
    job->text = gi_xmalloc(len + 1);
    memcpy(job->text, text, len);
    job->text[len] = '\0';
    if (gi_json_parse(job->text, len, file, &job->doc, err))
        return -1;
    gi_jv v = {file, err};
    const cJSON *root = job->doc;

    /* The method first: its name decides which parameter block is allowed. */
    const char *method = NULL;
    /* The usual slip: a scene or an emissions file given where a job goes. */
    const char *kind = NULL;
    if (cJSON_IsObject(root) && !cJSON_HasObjectItem(root, "method"))
        kind = cJSON_HasObjectItem(root, "objects")     ? "a scene"
               : cJSON_HasObjectItem(root, "emissions") ? "an emissions file (gi relight's)"
                                                        : NULL;
    if (kind)
        return gi_fail(err, GI_EINVAL,
                       "%s: method: missing (required): this is %s, not a job; a job names its "
                       "scene (\"scene\") and a method (docs/job-format.md; "
                       "scenes/cornell-box/pt.json is one)",
                       file, kind);
    if (gi_jv_string(&v, root, "", "method", 1, &method))
        return -1;
    job->method = gi_method_find(method);
    if (!job->method) {
        char list[256] = "";
        size_t n = 0;
        for (const gi_method *const *m = gi_methods(); *m; m++)
            n += (size_t)snprintf(list + n, sizeof list - n, "%s%s", n ? ", " : "", (*m)->name);
        return gi_jv_fail(&v, "method", "unknown method \"%s\" (available: %s)", method, list);
    }
    for (const cJSON *it = root->child; it; it = it->next) {
        const gi_method *other = gi_method_find(it->string);
        if (other && other != job->method)
            return gi_jv_fail(&v, it->string,
                              "parameters for method \"%s\", but the job's method is \"%s\"",
                              other->name, job->method->name);
    }
    const char *keys[] = {"name",   "description", "scene",   "method",          "seed",
                          "image",  "camera",      "outputs", "task_timeout", job->method->name,
                          NULL};
    if (gi_jv_keys(&v, root, "", keys))
        return -1;

    const char *name = NULL, *scene = NULL, *desc = NULL;
    int64_t seed = 1;
    const cJSON *image, *camera, *outputs, *params;
    if (gi_jv_string(&v, root, "", "name", 0, &name) ||
        gi_jv_string(&v, root, "", "description", 0, &desc) ||
        gi_jv_string(&v, root, "", "scene", 1, &scene) ||
        gi_jv_int(&v, root, "", "seed", 0, 0, ((int64_t)1 << 53) - 1, &seed) ||
        gi_jv_number(&v, root, "", "task_timeout", 0, GI_JOB_MIN_TASK_TIMEOUT,
                     GI_JOB_MAX_TASK_TIMEOUT, &job->task_timeout) ||
        gi_jv_member_object(&v, root, "", "image", 0, &image) ||
        gi_jv_member_object(&v, root, "", "camera", 0, &camera) ||
        gi_jv_member_object(&v, root, "", "outputs", 0, &outputs) ||
        gi_jv_member_object(&v, root, "", job->method->name, 0, &params))
        return -1;
    if (name && !valid_file_name(name))
        return gi_jv_fail(&v, "name",
                          "must be 1-200 letters, digits, '.', '_' or '-', not starting with '.'");
    job->name = name ? gi_xstrdup(name) : default_name(file);
    if (!scene[0])
        return gi_jv_fail(&v, "scene", "is empty");
    job->scene_name = gi_path_normalize(scene);
    job->seed = (uint64_t)seed;

    job->width = job->height = 512;
    if (image) {
        static const char *const ikeys[] = {"width", "height", "exposure", NULL};
        int64_t w = 512, h = 512;
        if (gi_jv_keys(&v, image, "image", ikeys) ||
            gi_jv_int(&v, image, "image", "width", 0, 1, GI_JOB_MAX_SIDE, &w) ||
            gi_jv_int(&v, image, "image", "height", 0, 1, GI_JOB_MAX_SIDE, &h) ||
            gi_jv_number(&v, image, "image", "exposure", 0, -30, 30, &job->exposure))
            return -1;
        job->width = (int)w;
        job->height = (int)h;
    }
    if (camera) {
        if (gi_camera_parse(&v, camera, "camera", &job->camera))
            return -1;
        job->has_camera = 1;
    }
    if (parse_outputs(&v, job, outputs))
        return -1;
    return job->method->parse(job, params, &v);
}

void gi_job_free(gi_job *job)
{
    if (job->method && job->method->release)
        job->method->release(job);
    free(job->file);
    free(job->text);
    cJSON_Delete(job->doc);
    free(job->name);
    free(job->scene_name);
    for (int i = 0; i < job->output_count; i++) {
        free(job->outputs[i].kind);
        free(job->outputs[i].file);
    }
    free(job->out_dir);
    if (job->scene_loaded)
        gi_scene_free(&job->scene);
    gi_manifest_free(&job->manifest);
    gi_asset_store_free(job->assets);
    for (int i = 0; i < job->written_count; i++)
        free(job->written[i]);
    memset(job, 0, sizeof *job);
}

int gi_job_load_scene(gi_job *job, const gi_asset_source *src, gi_error *err)
{
    if (gi_scene_load(src, job->scene_name, &job->scene, err))
        return gi_error_prefix(err, "%s: scene", job->file);
    job->scene_loaded = 1;
    if (job->method->check_scene && job->method->check_scene(job, err))
        return -1;
    return 0;
}

int gi_job_read(const char *path, gi_job *job, gi_error *err)
{
    gi_buf text;
    gi_buf_init(&text);
    if (gi_read_file(path, GI_JOB_MAX_BYTES, &text, err)) {
        gi_buf_free(&text);
        memset(job, 0, sizeof *job);
        return -1;
    }
    int rc = gi_job_parse((const char *)text.data, text.len, path, job, err);
    gi_buf_free(&text);
    return rc;
}

int gi_job_load(const char *path, gi_job *job, gi_error *err)
{
    if (gi_job_read(path, job, err))
        return -1;
    char *dir = gi_dirname(path);
    gi_dir_source ds;
    gi_dir_source_init(&ds, dir);
    free(dir);
    gi_asset_source src = gi_dir_source_as_source(&ds);
    int rc = gi_job_load_scene(job, &src, err);
    /* The job keeps what it read: the manifest and the bytes, so workers
     * get exactly these files whatever happens on disk meanwhile. */
    job->manifest = ds.manifest;
    gi_manifest_init(&ds.manifest);
    job->assets = ds.store;
    ds.store = NULL;
    gi_dir_source_free(&ds);
    return rc;
}

const gi_camera *gi_job_camera(const gi_job *job)
{
    return job->has_camera ? &job->camera : &job->scene.camera;
}

void gi_job_inputs_add(gi_job_inputs *in, const char *path, const char *what)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return; /* a file that is not there cannot be replaced */
    if (in->count == in->cap) {
        in->cap = in->cap ? 2 * in->cap : 16;
        in->items = gi_xrealloc(in->items, in->cap * sizeof *in->items);
    }
    gi_job_input *it = &in->items[in->count++];
    it->dev = (uint64_t)st.st_dev;
    it->ino = (uint64_t)st.st_ino;
    it->what = gi_xstrdup(what);
}

void gi_job_inputs_init(gi_job_inputs *in, const gi_job *job, const char *job_path)
{
    memset(in, 0, sizeof *in);
    gi_job_inputs_add(in, job_path, "the job file");
    char *dir = gi_dirname(job_path);
    for (size_t i = 0; i < job->manifest.count; i++) {
        const char *name = job->manifest.entries[i].name;
        char *p = gi_path_join(dir, name);
        size_t len = strlen(name) + 32;
        char *what = gi_xmalloc(len);
        snprintf(what, len, "the scene's %s", name);
        gi_job_inputs_add(in, p, what);
        free(what);
        free(p);
    }
    free(dir);
}

void gi_job_inputs_free(gi_job_inputs *in)
{
    for (size_t i = 0; i < in->count; i++)
        free(in->items[i].what);
    free(in->items);
    memset(in, 0, sizeof *in);
}

int gi_job_inputs_spare(const gi_job_inputs *in, const char *path, const char *job_path,
                        const char *kind, gi_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return 0;
    for (size_t i = 0; i < in->count; i++)
        if ((uint64_t)st.st_dev == in->items[i].dev && (uint64_t)st.st_ino == in->items[i].ino)
            return gi_fail(err, GI_EINVAL,
                           "%s: outputs.%s: %s would replace one of the job's own files (%s): "
                           "name the output otherwise or write into another --out",
                           job_path, kind, path, in->items[i].what);
    return 0;
}

int gi_job_outputs_spare_inputs(const gi_job *job, const char *job_path, const char *out_dir,
                                gi_error *err)
{
    gi_job_inputs in;
    gi_job_inputs_init(&in, job, job_path);
    int rc = 0;
    for (int i = 0; i < job->output_count && rc == 0; i++) {
        char *p = gi_path_join(out_dir, job->outputs[i].file);
        rc = gi_job_inputs_spare(&in, p, job_path, job->outputs[i].kind, err);
        free(p);
    }
    gi_job_inputs_free(&in);
    return rc;
}

const char *gi_job_output(const gi_job *job, const char *kind)
{
    for (int i = 0; i < job->output_count; i++)
        if (strcmp(job->outputs[i].kind, kind) == 0)
            return job->outputs[i].file;
    return NULL;
}

int gi_job_check_tasks(gi_jv *v, const char *field, double tasks, const char *what, ...)
{
    if (tasks <= GI_JOB_MAX_TASKS)
        return 0;
    char how[256];
    va_list ap;
    va_start(ap, what);
    vsnprintf(how, sizeof how, what, ap);
    va_end(ap);
    return gi_jv_fail(v, field, "%s make %.4g tasks at once; a job plans at most %u", how, tasks,
                      GI_JOB_MAX_TASKS);
}

/* How much of `name` identifies it as written from `file` (0: not at all):
 * the whole name, or file's stem before a '.' or '-' and more, with file's
 * extension at the end. */
static size_t written_from(const char *file, const char *name)
{
    if (strcmp(file, name) == 0)
        return strlen(file) + 1;
    const char *dot = strrchr(file, '.');
    size_t stem = dot && dot != file ? (size_t)(dot - file) : strlen(file);
    size_t ext = strlen(file + stem), len = strlen(name);
    if (len < stem + 2 + ext || strncmp(name, file, stem) != 0 ||
        (name[stem] != '.' && name[stem] != '-') || strcmp(name + len - ext, file + stem) != 0)
        return 0;
    return stem;
}

const char *gi_job_output_kind(const gi_output_spec *outs, int n, const char *name)
{
    const char *kind = NULL;
    size_t best = 0;
    for (int i = 0; i < n; i++) {
        size_t m = written_from(outs[i].file, name);
        if (m > best) {
            best = m;
            kind = outs[i].kind;
        }
    }
    return kind;
}

char *gi_job_output_path(const gi_job *job, const char *file)
{
    const char *dir = job->out_dir ? job->out_dir : ".";
    if (!job->in_frame)
        return gi_path_join(dir, file);
    /* NAME.EXT -> NAME.0003.EXT (a name without extension gets .0003). */
    const char *dot = strrchr(file, '.');
    size_t stem = dot && dot != file ? (size_t)(dot - file) : strlen(file);
    int width = 4;
    for (uint32_t last = job->frame_count ? job->frame_count - 1 : 0; last >= 10000; last /= 10)
        width++;
    size_t n = strlen(file) + 16;
    char *framed = gi_xmalloc(n);
    snprintf(framed, n, "%.*s.%0*u%s", (int)stem, file, width, job->frame, file + stem);
    char *path = gi_path_join(dir, framed);
    free(framed);
    return path;
}

void gi_job_note_output(gi_job *job, const char *kind, const char *path)
{
    if (job->on_output)
        job->on_output(job->on_output_ctx, kind, path);
    if (job->written_count + 2 > (int)GI_ARRAY_LEN(job->written)) {
        job->written_more++;
        return;
    }
    job->written[job->written_count++] = gi_xstrdup(kind);
    job->written[job->written_count++] = gi_xstrdup(path);
}

void gi_job_publish(gi_job *job, const void *data, size_t len, char hash[GI_HASH_HEX])
{
    gi_hash_hex(data, len, hash);
    if (!job->assets)
        job->assets = gi_asset_store_new();
    gi_asset_store_put(job->assets, hash, data, len);
}

void gi_job_unpublish(gi_job *job, const char *hash)
{
    /* Never a file the job read (the same bytes). */
    if (job->assets && !gi_manifest_has_hash(&job->manifest, hash))
        gi_asset_store_remove(job->assets, hash);
}
