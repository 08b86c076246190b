/* gi_log: leveled log lines on stderr, "gi[pid] level: message".
 * The level comes from GI_LOG (error, warn, info, debug); default warn, so
 * a normal render prints only its progress and summary. */
#ifndef GI_LOG_H
#define GI_LOG_H

typedef enum { GI_LOG_ERROR, GI_LOG_WARN, GI_LOG_INFO, GI_LOG_DEBUG } gi_log_level;

void gi_log_init(const char *program);
void gi_log_set_level(gi_log_level level);
int gi_log_enabled(gi_log_level level);
void gi_log(gi_log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* While set (on this thread), warnings and errors are also handed to fn,
 * whatever GI_LOG says: gi-farmd sends a method's warnings about a job to
 * that job's log. fn's own logging does not come back to it. NULL unsets. */
typedef void (*gi_log_hook)(void *ctx, gi_log_level level, const char *msg);
void gi_log_hook_set(gi_log_hook fn, void *ctx);
void gi_log_hook_get(gi_log_hook *fn, void **ctx);
/* A message for the user: "program: message". */
void gi_say(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* JSON lines instead of text (--progress json): every log line becomes
 * {"event": "log", "level", "program", "pid", "message"} and every message
 * {"event": "message", "program", "message"}, so that a program reading
 * stderr meets only JSON. Forked children inherit it. */
void gi_log_json(int on);

#define gi_error_log(...) gi_log(GI_LOG_ERROR, __VA_ARGS__)
#define gi_warn(...) gi_log(GI_LOG_WARN, __VA_ARGS__)
#define gi_info(...) gi_log(GI_LOG_INFO, __VA_ARGS__)
#define gi_debug(...) gi_log(GI_LOG_DEBUG, __VA_ARGS__)

#endif
