/* gi_progress: progress reports for a running job: a live bar with ETA on a
 * terminal, plain lines otherwise, or JSON lines for programs. */
#ifndef GI_PROGRESS_H
#define GI_PROGRESS_H

#include <stdint.h>
#include <stdio.h>

#include "gi_clock.h"
#include "gi_method.h"

typedef enum {
    GI_PROGRESS_AUTO, /* bar on a terminal, lines otherwise */
    GI_PROGRESS_BAR,
    GI_PROGRESS_LINES,
    GI_PROGRESS_JSON,
    GI_PROGRESS_NONE
} gi_progress_mode;

/* A job's progress at one moment, as the displays show it. */
typedef struct gi_progress_at {
    double fraction; /* of the whole job, 0..1 */
    double eta_s;    /* seconds left; < 0 if not known yet */
    double done, total; /* work in the method's unit: done; planned and still to plan */
    double samples, rays; /* so far (the rates) */
    uint32_t frame, frames; /* the frame being computed, of how many (a still: 0 of 1) */
} gi_progress_at;

/* The clock behind a job's fraction and ETA. A frame's fraction is its
 * work done over its work planned and still to plan; the whole job's is
 * the frames before it plus that fraction of it, over all frames, each
 * frame weighed by the method's estimate of its time (frame 0 bakes
 * everything, the others update: gi_job_progress.first_frame_cost,
 * later_frame_cost), or alike without one. The weights depend on the job's
 * state alone, so that a restored job's fraction goes on where it was.
 * The ETA is the current frame's rest at the rate this process has seen in
 * it since it handed out the frame's first task (time a job waits for a
 * worker, queued on a farm with none free, is no work), plus the frames
 * after it at the mean time of the frames this process saw whole past
 * frame 0 (before one is seen: the current frame's
 * projected time, or in frame 0 its rate times the method's estimate).
 * Monotonic seconds; not checkpointed. */
typedef struct gi_progress_clock {
    gi_job_progress at;
    int noted;
    double frame_base;   /* planned work of the frames before this one */
    /* Set before the first note by a job restored from a checkpoint that
     * kept its frame_base (< 0: not kept; frame 0's is 0 all the same). */
    double restored_base;
    double t_frame;      /* when this process saw this frame (or itself) start, moved to
                          * when it handed out the frame's first task */
    double done_at_t;    /* work done then */
    int working;         /* a task of this frame was handed out: t_frame stays */
    int frame_seen_whole; /* this process saw this frame start */
    double later_seconds; /* frames past 0 seen whole: their time and count */
    uint32_t later_count;
} gi_progress_clock;

/* Where the job stands now (method->progress), before its newly planned
 * tasks are counted in cost_total. */
void gi_progress_clock_note(gi_progress_clock *c, const gi_job_progress *at, double cost_total,
                            double cost_done, double now);
/* A task was handed out (to a worker or a pool child), cost_done being
 * done: the first of the frame starts its rate's clock. */
void gi_progress_clock_working(gi_progress_clock *c, double cost_done, double now);
/* Fills fraction, eta_s, done, total, frame and frames. */
void gi_progress_clock_read(const gi_progress_clock *c, double cost_total, double cost_done,
                            double now, gi_progress_at *out);

typedef struct gi_progress {
    gi_progress_mode mode;
    FILE *out;
    const char *job_name, *unit;
    double start, last_print;
    double samples_at_start, rays_at_start; /* rates count from the first update */
    int updated;
    double last_fraction_printed;
    int bar_drawn;
} gi_progress;

/* Parses "auto", "bar", "lines", "json", "none"; -1 if unknown. */
int gi_progress_mode_parse(const char *s, gi_progress_mode *out);
void gi_progress_init(gi_progress *p, gi_progress_mode mode, FILE *out, const char *job_name,
                      const char *unit);
/* Shows *at; rate-limited unless force. */
void gi_progress_update(gi_progress *p, const gi_progress_at *at, int force);
/* Clears the bar line (before other output). */
void gi_progress_end(gi_progress *p);

/* JSON mode's other events, one line each on out (for programs that follow
 * a render to its end; paths and messages escaped):
 *   {"event":"output","job":J,"kind":K,"path":P}   a file written or fetched
 *   {"event":"end","job":J,"state":S,"elapsed_s":T[,"error":E]}  the last line;
 *     S is done, failed, cancelled, interrupted or (gi wait: the farm stopped
 *     answering) unreachable; E says why when not done. */
void gi_progress_json_output(FILE *out, const char *job, const char *kind, const char *path);
void gi_progress_json_end(FILE *out, const char *job, const char *state, double elapsed_s,
                          const char *error);

/* "1.23 M" / "500 " style formatting of a number into buf, for a unit to
 * follow. */
const char *gi_si(double v, char *buf, size_t n);
/* "1:02:03" / "2:03" / "4.5s" into buf. */
const char *gi_duration(double s, char *buf, size_t n);

#endif
