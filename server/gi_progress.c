/* gi_progress: progress bar, plain progress lines, JSON progress events. */
#include "gi_progress.h"

#include <math.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

double gi_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

const char *gi_si(double v, char *buf, size_t n)
{
    static const char *suffix[] = {"", " k", " M", " G", " T"};
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

void gi_progress_update(gi_progress *p, double done, double total, double rays, int force)
{
    double now = gi_now(), elapsed = now - p->start;
    double f = total > 0 ? done / total : 0.0;
    if (f > 1.0)
        f = 1.0;
    double eta = f > 0 ? elapsed * (1.0 - f) / f : NAN;
    double rate = elapsed > 0 ? done / elapsed : 0.0;
    char b1[32], b2[32], b3[32];
    switch (p->mode) {
    case GI_PROGRESS_BAR: {
        if (!force && now - p->last_print < 0.1)
            return;
        int width = 30, fill = (int)(f * width + 0.5);
        char bar[64];
        for (int i = 0; i < width; i++)
            bar[i] = i < fill ? '#' : '.';
        bar[width] = '\0';
        fprintf(p->out, "\r%s [%s] %5.1f%%  ETA %-8s %s%s/s  %srays/s ", p->job_name, bar,
                100.0 * f, gi_duration(eta, b1, sizeof b1), gi_si(rate, b2, sizeof b2),
                p->unit, gi_si(elapsed > 0 ? rays / elapsed : 0, b3, sizeof b3));
        fflush(p->out);
        p->bar_drawn = 1;
        break;
    }
    case GI_PROGRESS_LINES:
        /* Every 10% or every 10 seconds. */
        if (!force && f - p->last_fraction_printed < 0.1 && now - p->last_print < 10.0)
            return;
        p->last_fraction_printed = f;
        fprintf(p->out, "%s: %.1f%% done, ETA %s, %s%s/s\n", p->job_name, 100.0 * f,
                gi_duration(eta, b1, sizeof b1), gi_si(rate, b2, sizeof b2), p->unit);
        fflush(p->out);
        break;
    case GI_PROGRESS_JSON:
        if (!force && now - p->last_print < 0.5)
            return;
        snprintf(b1, sizeof b1, "%.3f", eta);
        fprintf(p->out,
                "{\"event\":\"progress\",\"job\":\"%s\",\"done\":%.17g,\"total\":%.17g,"
                "\"fraction\":%.6f,\"elapsed_s\":%.3f,\"eta_s\":%s,\"rays\":%.17g}\n",
                p->job_name, done, total, f, elapsed, isfinite(eta) ? b1 : "null", rays);
        fflush(p->out);
        break;
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
