/* gi_clock: the one monotonic clock, in seconds, behind every duration the
 * project measures (reports' timings, progress and ETA, deadlines). */
#ifndef GI_CLOCK_H
#define GI_CLOCK_H

/* Seconds since an arbitrary point; never goes back. */
double gi_now(void);

#endif
