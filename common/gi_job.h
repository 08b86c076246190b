/* gi_job: a rendering job, as parsed from its JSON (docs/job-format.md).
 *
 * The same job text is parsed on the coordinator (which also loads the
 * scene without Embree, records the asset manifest, plans, merges and writes
 * outputs) and in every worker process (which loads the scene from the
 * manifest and runs tasks). */
#ifndef GI_JOB_H
#define GI_JOB_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_error.h"
#include "gi_method.h"
#include "gi_scene.h"

#define GI_JOB_MAX_BYTES (16u << 20)
#define GI_JOB_MAX_SIDE 16384
#define GI_JOB_MAX_OUTPUTS 16
/* The most tasks a job plans at once (a still's, or one frame's): the
 * coordinator holds each until it is merged. Methods refuse parameters
 * that would plan more (gi_job_check_tasks) rather than run out of memory. */
#define GI_JOB_MAX_TASKS (1u << 20)
/* The range of a task_timeout (seconds), the job's and the coordinators'. */
#define GI_JOB_MIN_TASK_TIMEOUT 1.0
#define GI_JOB_MAX_TASK_TIMEOUT 1e6

typedef struct gi_output_spec {
    char *kind; /* "exr", "png", "ply", ... */
    char *file; /* a plain file name inside the output directory */
} gi_output_spec;

struct gi_job {
    char *file; /* where the job came from, for messages */
    char *text; /* the job JSON as given (travels to workers) */
    cJSON *doc;
    char *name;
    char *scene_name; /* asset name of the scene, relative to the job */
    const gi_method *method;
    uint64_t seed;
    /* Seconds a task may run before it is stopped and its run failed
     * (0: no limit of its own; the coordinator's default applies). */
    double task_timeout;
    int width, height;
    double exposure; /* PNG preview, in stops */
    int has_camera;  /* job overrides the scene's camera */
    gi_camera camera;
    gi_output_spec outputs[GI_JOB_MAX_OUTPUTS];
    int output_count;
    void *params; /* method parameters (method->parse) */
    /* Animations write one set of outputs per frame: while in_frame is
     * set, output paths get the frame number before the extension
     * (NAME.0003.exr), zero-padded to 4 digits or as many as the last of
     * frame_count frames has, so that the names sort in frame order. */
    int in_frame;
    uint32_t frame, frame_count; /* frame_count: set by check_scene (0: a still) */

    /* Its tasks keep files in the worker host's batch directory (an
     * animation's photon batches), which the host removes when told the
     * job is over (gi_batch_dir.h). Set by the method's parse. */
    int keeps_batches;

    /* Coordinator side. */
    char *out_dir;
    gi_scene scene;
    int scene_loaded;
    /* Loaded by a worker (gi_worker_ctx_load): what a check only tells the
     * user (warnings) is said once, by the coordinator, not by every child. */
    int on_worker;
    gi_manifest manifest;   /* name -> hash of every file the scene read */
    gi_asset_store *assets; /* their bytes, plus blobs methods publish */
    void *state;            /* method accumulators (method->plan .. release) */
    /* Written outputs, for the summary: "kind path" lines. */
    char *written[GI_JOB_MAX_OUTPUTS * 2];
    int written_count;
    int written_more; /* outputs written but not listed (an animation's frames) */
    /* Optional: hears of every output as it is written (gi render's JSON
     * progress lists them all, an animation's frames too). */
    void (*on_output)(void *ctx, const char *kind, const char *path);
    void *on_output_ctx;
};

/* Parses and validates a job document. `file` names it in messages. Does not
 * touch the scene or the disk. */
int gi_job_parse(const char *text, size_t len, const char *file, gi_job *job, gi_error *err);
void gi_job_free(gi_job *job);

/* Reads and parses a job file, without its scene (`gi relight` needs only
 * the job's parameters and output names). */
int gi_job_read(const char *path, gi_job *job, gi_error *err);
/* Reads a job file, parses it, and loads its scene from the job file's
 * directory (recording the manifest); then the method's scene checks. */
int gi_job_load(const char *path, gi_job *job, gi_error *err);
/* Loads the scene through `src` (used by gi_job_load and by workers). */
int gi_job_load_scene(gi_job *job, const gi_asset_source *src, gi_error *err);

/* The camera the job renders with (job override, else the scene's). */
const gi_camera *gi_job_camera(const gi_job *job);
/* Files a job reads, which none of its outputs may replace: identified by
 * device and inode (another path to the same file is the same file), each
 * with how a message names it ("the job file"). */
typedef struct gi_job_input {
    uint64_t dev, ino;
    char *what;
} gi_job_input;
typedef struct gi_job_inputs {
    gi_job_input *items;
    size_t count, cap;
} gi_job_inputs;
/* The job file at job_path and the files its scene read (job->manifest,
 * names relative to the job file's directory). */
void gi_job_inputs_init(gi_job_inputs *in, const gi_job *job, const char *job_path);
/* One more input (a file that does not exist is skipped: nothing to lose). */
void gi_job_inputs_add(gi_job_inputs *in, const char *path, const char *what);
void gi_job_inputs_free(gi_job_inputs *in);
/* Refuses (GI_EINVAL, naming job_path, the output's kind, path and the input)
 * writing an output of `kind` at `path` that is one of `in`. */
int gi_job_inputs_spare(const gi_job_inputs *in, const char *path, const char *job_path,
                        const char *kind, gi_error *err);
/* Refuses (GI_EINVAL, naming the output) a job whose output in out_dir would
 * replace one of its inputs (gi_job_inputs_init). */
int gi_job_outputs_spare_inputs(const gi_job *job, const char *job_path, const char *out_dir,
                                gi_error *err);
/* The output file of a kind ("exr"), or NULL if the job does not ask for it. */
const char *gi_job_output(const gi_job *job, const char *kind);
/* Full path of an output in out_dir (malloc'ed); the current frame's file
 * while job->in_frame is set. */
char *gi_job_output_path(const gi_job *job, const char *file);
/* The kind of the output that `outs` (n specs) writes as file `name`: the
 * spec's own file, a frame's NAME.0003.EXT or a set's NAME-SET.EXT
 * (gi_job_output_path, gi_rad_output_name); NULL if none does. */
const char *gi_job_output_kind(const gi_output_spec *outs, int n, const char *name);
/* Refuses, naming `field`, parameters that make a job plan `tasks` tasks
 * at once, more than GI_JOB_MAX_TASKS; `what` (printf) says how they come
 * about, e.g. "4096 x 4096 pixels in tiles of 4". */
int gi_job_check_tasks(gi_jv *v, const char *field, double tasks, const char *what, ...)
    __attribute__((format(printf, 4, 5)));
/* Records a written output for the summary. */
void gi_job_note_output(gi_job *job, const char *kind, const char *path);

/* Coordinator-published data that tasks need (e.g. per-vertex radiance for
 * image tiles): stored by content hash; workers fetch it like any asset. */
void gi_job_publish(gi_job *job, const void *data, size_t len, char hash[GI_HASH_HEX]);
/* Drops published data no task will ask for again (an animation's frame
 * before), so that a long job does not hold every frame's. */
void gi_job_unpublish(gi_job *job, const char *hash);

#endif
