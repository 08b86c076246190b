/* gi_standing: the file in which gi-farmd keeps its workers' standing
 * across restarts (<state>/standing; gi_farm_standing.c writes and reads
 * it): each host's failure and loss counts, its streaks and blocklisting,
 * and each job's exclusions of hosts (gi_farm_sched.c, Blame, Blocklisting,
 * Exclusions). Times are epoch seconds (a restarted process has another
 * monotonic clock); 0: none.
 *
 * Layout (little-endian): u32 "GIST", u32 version 2, u64 host count, then
 * per host: string name, u64 failures, u64 own_failures, u32
 * consecutive_failures, u64 streak_job, u8 streak_wide, u64 losses, u32
 * consecutive_losses, f64 blocked_until, string last_error; u64 exclusion
 * count, then per exclusion: u64 job id, string host, u32 streak, u32
 * times, f64 until, f64 last_failed (version 2), string last_error.
 * Version 1 files are read (their exclusions' last_failed is 0). */
#ifndef GI_STANDING_H
#define GI_STANDING_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "gi_msg_ctrl.h"

#define GI_STANDING_ERROR_MAX 511

typedef struct gi_standing_host {
    char name[GI_MSG_MAX_NAME + 1];
    uint64_t failures, own_failures, losses, streak_job;
    uint32_t consecutive_failures, consecutive_losses;
    int streak_wide;
    double blocked_until; /* epoch seconds; 0: not blocklisted */
    char last_error[GI_STANDING_ERROR_MAX + 1];
} gi_standing_host;

typedef struct gi_standing_excl {
    uint64_t job_id;
    char host[GI_MSG_MAX_NAME + 1];
    uint32_t streak, times;
    double until;       /* epoch seconds; 0: never excluded */
    double last_failed; /* epoch seconds of its latest failure; 0: unknown */
    char last_error[GI_STANDING_ERROR_MAX + 1];
} gi_standing_excl;

void gi_standing_encode(const gi_standing_host *hosts, size_t host_count,
                        const gi_standing_excl *excl, size_t excl_count, gi_buf *out);

typedef struct gi_standing_sink {
    void (*host)(void *ctx, const gi_standing_host *h);
    void (*excl)(void *ctx, const gi_standing_excl *x);
    void *ctx;
} gi_standing_sink;

/* Reads such a file's bytes (`what` names it in errors), giving the sink
 * every entry in order. Returns 0 when all was read; -1 with err if it is
 * not a standing file (the sink got nothing); 1 with err if it is damaged
 * after the entries given (an entry out of range is damage: a name empty or
 * too long, a job id outside [1, GI_JOB_ID_MAX], a time not finite or
 * negative, a flag not 0 or 1). */
int gi_standing_decode(const void *data, size_t len, const char *what,
                       const gi_standing_sink *sink, gi_error *err);

#endif
