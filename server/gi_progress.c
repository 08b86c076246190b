/* gi_progress: progress bar, plain progress lines, JSON progress events. */
#include "gi_progress.h"

#include <math.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

const char *gi_si(double v, char *buf, size_t n)
{
    static const char *suffix[] = {" ", " k", " M", " G", " T"}; /* a unit follows */
    int i = 0;
    while (fabs(v) >= 1000.0 && i < 4) {
        v /= 1000.0;
        i++;
    }
    snprintf(buf, n, i ? "%.3g%s" : "%.4g%s", v, suffix[i]);
    return buf;
}

const char *gi_duration(double s, char *buf, size_t n)
{
    if (!isfinite(s) || s < 0)
        snprintf(buf, n, "?");
    else if (s < 60)
        snprintf(buf, n, "%.1fs", s);
    else if (s < 3600)
        snprintf(buf, n, "%d:%02d", (int)s / 60, (int)s % 60);
    else
        snprintf(buf, n, "%d:%02d:%02d", (int)s / 3600, ((int)s / 60) % 60, (int)s % 60);
    return buf;
}

int gi_progress_mode_parse(const char *s, gi_progress_mode *out)
{
    static const char *names[] = {"auto", "bar", "lines", "json", "none"};
    for (int i = 0; i < 5; i++)
        if (strcmp(s, names[i]) == 0) {
            *out = (gi_progress_mode)i;
            return 0;
        }
    return -1;
}

void gi_progress_init(gi_progress *p, gi_progress_mode mode, FILE *out, const char *job_name,
                      const char *unit)
{
    memset(p, 0, sizeof *p);
    if (mode == GI_PROGRESS_AUTO)
        mode = isatty(fileno(out)) ? GI_PROGRESS_BAR : GI_PROGRESS_LINES;
    p->mode = mode;
    p->out = out;
    p->job_name = job_name;
    p->unit = unit;
    p->start = p->last_print = gi_now();
    p->last_fraction_printed = -1.0;
}

void gi_progress_clock_note(gi_progress_clock *c, const gi_job_progress *at, double cost_total,
                            double cost_done, double now)
{
    if (!c->noted || at->frame != c->at.frame) {
        if (c->noted && c->frame_seen_whole && c->at.frame > 0) {
            c->later_seconds += now - c->t_frame;
            c->later_count++;
        }
        /* A frame is seen whole when none of its work was done before: at
         * a fresh start, or when the frame before it finished. A restored
         * job's frame starts where its checkpoint says, or (an older
         * checkpoint, past frame 0) from the work left in it. */
        c->frame_seen_whole = c->noted || cost_done == 0;
        if (c->noted)
            c->frame_base = cost_total;
        else if (c->restored_base >= 0 && c->restored_base <= cost_done)
            c->frame_base = c->restored_base;
        else
            c->frame_base = at->frame == 0 ? 0 : cost_done;
        c->t_frame = now;
        c->done_at_t = cost_done;
        c->working = 0;
        c->noted = 1;
    }
    c->at = *at;
}

void gi_progress_clock_working(gi_progress_clock *c, double cost_done, double now)
{
    /* Until a task is out the job waits (for a worker, a farm's free
     * slot): counted in the rate, that wait would inflate the first ETAs
     * by as much as it lasted. */
    if (c->noted && !c->working) {
        c->t_frame = now;
        c->done_at_t = cost_done;
        c->working = 1;
    }
}

void gi_progress_clock_read(const gi_progress_clock *c, double cost_total, double cost_done,
                            double now, gi_progress_at *out)
{
    uint32_t frames = c->at.frames ? c->at.frames : 1, frame = c->at.frame;
    double planned = cost_total + c->at.cost_unplanned;
    double left = planned > cost_done ? planned - cost_done : 0;
    double frame_work = planned - c->frame_base;
    double f = frame_work > 0 ? (cost_done - c->frame_base) / frame_work : 1.0;
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    double w0 = 1, wl = 1; /* frame 0's weight, a later frame's */
    if (c->at.first_frame_cost > 0 && c->at.later_frame_cost > 0) {
        w0 = c->at.first_frame_cost;
        wl = c->at.later_frame_cost;
    }
    double before = frame == 0 ? 0 : w0 + (frame - 1) * wl;
    out->fraction = (before + f * (frame == 0 ? w0 : wl)) / (w0 + (frames - 1) * wl);
    if (out->fraction > 1)
        out->fraction = 1;
    out->done = cost_done;
    out->total = planned;
    out->frame = frame;
    out->frames = frames;

    double dt = now - c->t_frame, dd = cost_done - c->done_at_t;
    double rest = left <= 0 ? 0 : dd > 0 && dt > 0 ? left * dt / dd : -1;
    uint32_t after = frame + 1 < frames ? frames - frame - 1 : 0;
    double per_frame = -1; /* a frame past 0 */
    if (c->later_count)
        per_frame = c->later_seconds / c->later_count;
    else if (frame > 0 && rest >= 0)
        per_frame = dt + rest;
    else if (frame == 0 && dd > 0 && dt > 0 && c->at.first_frame_cost > 0 &&
             c->at.later_frame_cost > 0) /* frame 0's rate, the method's estimate */
        per_frame = c->at.later_frame_cost / c->at.first_frame_cost * frame_work * dt / dd;
    if (rest < 0 && per_frame >= 0 && frame > 0)
        rest = per_frame > dt ? per_frame - dt : 0;
    if (rest < 0 || (after > 0 && per_frame < 0))
        out->eta_s = -1; /* frame 0 says nothing of how long the frames after it take */
    else
        out->eta_s = rest + (after > 0 ? per_frame * after : 0);
}

void gi_progress_update(gi_progress *p, const gi_progress_at *at, int force)
{
    double now = gi_now(), elapsed = now - p->start;
    if (!p->updated) {
        p->updated = 1;
        p->samples_at_start = at->samples;
        p->rays_at_start = at->rays;
    }
    double f = at->fraction, eta = at->eta_s >= 0 ? at->eta_s : NAN;
    double rate = elapsed > 0 ? (at->samples - p->samples_at_start) / elapsed : 0.0;
    double ray_rate = elapsed > 0 ? (at->rays - p->rays_at_start) / elapsed : 0.0;
    char b1[32], b2[32], b3[32], what[64];
    /* Before any work is seen there is no rate yet: "?", not a 0 that reads
     * as a stalled render. */
    int measured = elapsed > 0 && at->rays > p->rays_at_start;
    /* An animation shows its frames done; a still the rate in the method's unit. */
    if (at->frames > 1)
        snprintf(what, sizeof what, "%u/%u frames", f >= 1 ? at->frames : at->frame,
                 at->frames);
    else if (!measured)
        snprintf(what, sizeof what, "? %s/s", p->unit);
    else
        snprintf(what, sizeof what, "%s%s/s", gi_si(rate, b2, sizeof b2), p->unit);
    switch (p->mode) {
    case GI_PROGRESS_BAR: {
        if (!force && now - p->last_print < 0.1)
            return;
        int width = 30, fill = (int)(f * width + 0.5);
        char bar[64];
        for (int i = 0; i < width; i++)
            bar[i] = i < fill ? '#' : '.';
        bar[width] = '\0';
        fprintf(p->out, "\r%s [%s] %5.1f%%  ETA %-8s %s  %srays/s ", p->job_name, bar,
                100.0 * f, gi_duration(eta, b1, sizeof b1), what,
                measured ? gi_si(ray_rate, b3, sizeof b3) : "? ");
        fflush(p->out);
        p->bar_drawn = 1;
        break;
    }
    case GI_PROGRESS_LINES:
        /* Every 10% or every 10 seconds. */
        if (!force && f - p->last_fraction_printed < 0.1 && now - p->last_print < 10.0)
            return;
        p->last_fraction_printed = f;
        fprintf(p->out, "%s: %.1f%% done, ETA %s, %s\n", p->job_name, 100.0 * f,
                gi_duration(eta, b1, sizeof b1), what);
        fflush(p->out);
        break;
    case GI_PROGRESS_JSON:
        if (!force && now - p->last_print < 0.5)
            return;
    {
        snprintf(b1, sizeof b1, "%.3f", eta);
        cJSON *name = cJSON_CreateString(p->job_name); /* quoted and escaped */
        char *quoted = cJSON_PrintUnformatted(name);
        fprintf(p->out,
                "{\"event\":\"progress\",\"job\":%s,\"done\":%.17g,\"total\":%.17g,"
                "\"fraction\":%.6f,\"frame\":%u,\"frames\":%u,\"elapsed_s\":%.3f,"
                "\"eta_s\":%s,\"rays\":%.17g}\n",
                quoted ? quoted : "\"\"", at->done, at->total, f, at->frame, at->frames, elapsed,
                isfinite(eta) ? b1 : "null", at->rays);
        fflush(p->out);
        cJSON_free(quoted);
        cJSON_Delete(name);
        break;
    }
    default:
        return;
    }
    p->last_print = now;
}

void gi_progress_end(gi_progress *p)
{
    if (p->mode == GI_PROGRESS_BAR && p->bar_drawn) {
        fprintf(p->out, "\n");
        fflush(p->out);
        p->bar_drawn = 0;
    }
}

void gi_progress_json_output(FILE *out, const char *job, const char *kind, const char *path)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "event", "output");
    cJSON_AddStringToObject(o, "job", job);
    cJSON_AddStringToObject(o, "kind", kind);
    cJSON_AddStringToObject(o, "path", path);
    gi_json_print_line(out, o);
}

void gi_progress_json_end(FILE *out, const char *job, const char *state, double elapsed_s,
                          const char *error)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "event", "end");
    cJSON_AddStringToObject(o, "job", job);
    cJSON_AddStringToObject(o, "state", state);
    cJSON_AddNumberToObject(o, "elapsed_s", floor(elapsed_s * 1000.0 + 0.5) / 1000.0);
    if (error)
        cJSON_AddStringToObject(o, "error", error);
    gi_json_print_line(out, o);
}
