/* gi_progress: progress reports for a running job: a live bar with ETA on a
 * terminal, plain lines otherwise, or JSON lines for programs. */
#ifndef GI_PROGRESS_H
#define GI_PROGRESS_H

#include <stdio.h>

typedef enum {
    GI_PROGRESS_AUTO, /* bar on a terminal, lines otherwise */
    GI_PROGRESS_BAR,
    GI_PROGRESS_LINES,
    GI_PROGRESS_JSON,
    GI_PROGRESS_NONE
} gi_progress_mode;

typedef struct gi_progress {
    gi_progress_mode mode;
    FILE *out;
    const char *job_name, *unit;
    double start, last_print;
    double last_fraction_printed;
    int bar_drawn;
} gi_progress;

/* Parses "auto", "bar", "lines", "json", "none"; -1 if unknown. */
int gi_progress_mode_parse(const char *s, gi_progress_mode *out);
void gi_progress_init(gi_progress *p, gi_progress_mode mode, FILE *out, const char *job_name,
                      const char *unit);
/* done/total in work units; rays so far; rate-limited unless force. */
void gi_progress_update(gi_progress *p, double done, double total, double rays, int force);
/* Clears the bar line (before other output). */
void gi_progress_end(gi_progress *p);

double gi_now(void); /* monotonic seconds */
/* "1.23 M" style formatting of a number into buf. */
const char *gi_si(double v, char *buf, size_t n);
/* "1:02:03" / "2:03" / "4.5s" into buf. */
const char *gi_duration(double s, char *buf, size_t n);

#endif
