/* rad_relight: from a factorization and emission sets to radiosity and its
 * outputs, without the scene, the form factors or Embree. This is the
 * interactive use the thesis is about: `gi relight` and the end of a
 * radiosity job go through here.
 *
 * Radiosity is kept in radiance units (W sr^-1 m^-2, like the scene's
 * emission and the path tracer's images): for diffuse surfaces radiosity is
 * pi times that, and the equation is linear, so nothing else changes. */
#ifndef GI_RAD_RELIGHT_H
#define GI_RAD_RELIGHT_H

#include <stdint.h>

#include <cjson/cJSON.h>

#include "gi_error.h"
#include "rad_emissions.h"
#include "rad_factor.h"
#include "rad_file.h"
#include "rad_model.h"

typedef enum { GI_RAD_SMW = 0, GI_RAD_NEUMANN = 1 } gi_rad_solver;

typedef struct gi_rad_solve_opts {
    gi_rad_solver solver;
    double tolerance; /* Neumann: relative residual */
    int max_iterations;
    int threads; /* for the product with U */
} gi_rad_solve_opts;

typedef struct gi_rad_solve_info {
    double seconds; /* the solve alone (emission vector built before) */
    int iterations; /* Neumann; 0 for SMW */
    double residual;
} gi_rad_solve_info;

void gi_rad_solve_opts_default(gi_rad_solve_opts *o);


/* Radiosity for every emission set: E and B are count x n x 3 (E may be
 * NULL when not wanted), info has count entries. Each set is solved on its
 * own (eq. 3.33, or eq. 3.30), so the bits of a set's solution do not
 * depend on the other sets. Unknown material or object names fail. */
int gi_rad_solve_emissions(const gi_rad_factor *f, const gi_rad_model *md,
                           const gi_rad_emissions *em, const gi_rad_solve_opts *o, float *E,
                           float *B, gi_rad_solve_info *info, gi_error *err);

/* Per-vertex radiance of a solution (B, n x 3) as the per-vertex output
 * `kind`: "ply" or "glb". 1 if written, 0 if skipped (a glb too large for
 * glTF, with a warning), -1 on failure. */
int gi_rad_vertex_output_write(const char *path, const char *kind, const gi_rad_model *md,
                               const float *B, double exposure, gi_error *err);

/* Summary of one solution for a JSON report: name, emitted flux, radiosity
 * statistics, solver figures. */
cJSON *gi_rad_solution_report(const gi_rad_model *md, const char *name, const float *E,
                              const float *B, const gi_rad_solve_info *info);

/* A JSON report: the factorization's figures, then (add_solutions) one
 * entry per emission set under "emissions". */
cJSON *gi_rad_report_new(const gi_rad_file_info *info, const gi_rad_factor *f);
void gi_rad_report_add_solutions(cJSON *doc, const gi_rad_model *md, const gi_rad_emissions *em,
                                 const float *E, const float *B, const gi_rad_solve_info *info);

/* Writes a JSON document to path (pretty-printed, temp file + rename). */
int gi_rad_write_json(const char *path, const cJSON *doc, gi_error *err);

/* The outputs of a relight, into `dir`: per set, "<ply stem>-<set>.ply"
 * and "<glb stem>-<set>.glb" (when ply, glb are not NULL), and one report
 * "<report stem>-relight.json" (when report is not NULL; `job` names the job
 * in it). note() (may be NULL) hears of every file written. For `gi relight`.
 * Refuses (GI_EINVAL, nothing written) names that land on one file
 * (gi_rad_outputs_distinct). */
int gi_rad_relight_write(const char *dir, const char *ply, const char *glb, const char *report,
                         const char *job,
                         double exposure, const gi_rad_file_info *info, const gi_rad_model *md,
                         const gi_rad_factor *f, const gi_rad_emissions *em, const float *E,
                         const float *B, const gi_rad_solve_info *si,
                         void (*note)(void *user, const char *kind, const char *path), void *user,
                         gi_error *err);

/* "<stem>-<emission><ext>" for "<stem><ext>" (malloc'ed). */
char *gi_rad_output_name(const char *file, const char *emission);

/* One output of a radiosity run: written as `file`, or once per emission
 * set under gi_rad_output_name(file, set) (per_set), or under
 * gi_rad_output_name(file, as) when `as` is given (a relight's report). */
typedef struct gi_rad_output_file {
    const char *kind, *file, *as;
    int per_set;
} gi_rad_output_file;

/* 0 if the outputs' files all differ; otherwise -1 with the first two
 * that would land on one file in msg ("\"a-b.ply\" is both set b's ply
 * output and the report output"). */
int gi_rad_outputs_distinct(const gi_rad_output_file *outs, int count, const gi_rad_emissions *em,
                            char *msg, size_t msg_len);

#endif
