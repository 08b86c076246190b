/* gi_log: leveled logging to stderr. */
#include "gi_log.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_json.h"

static struct {
    const char *program;
    gi_log_level level;
    int initialized;
    int json;
} log_state = {"gi", GI_LOG_WARN, 0, 0};

void gi_log_json(int on) { log_state.json = on; }

static __thread gi_log_hook hook_fn;
static __thread void *hook_ctx;
static __thread int in_hook;

void gi_log_hook_set(gi_log_hook fn, void *ctx)
{
    hook_fn = fn;
    hook_ctx = ctx;
}

void gi_log_hook_get(gi_log_hook *fn, void **ctx)
{
    *fn = hook_fn;
    *ctx = hook_ctx;
}

/* One line out: text, or the JSON event (level NULL: a message). */
static void emit(const char *level, const char *text)
{
    if (!log_state.json) {
        if (level)
            fprintf(stderr, "%s[%ld] %s: %s\n", log_state.program, (long)getpid(), level, text);
        else
            fprintf(stderr, "%s: %s\n", log_state.program, text);
        return;
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "event", level ? "log" : "message");
    if (level)
        cJSON_AddStringToObject(o, "level", level);
    cJSON_AddStringToObject(o, "program", log_state.program);
    if (level)
        cJSON_AddNumberToObject(o, "pid", (double)getpid());
    cJSON_AddStringToObject(o, "message", text);
    gi_json_print_line(stderr, o);
}

static void log_read_env(void)
{
    log_state.initialized = 1;
    const char *env = getenv("GI_LOG");
    if (!env)
        return;
    static const char *names[] = {"error", "warn", "info", "debug"};
    for (int i = 0; i < 4; i++)
        if (strcmp(env, names[i]) == 0)
            log_state.level = (gi_log_level)i;
    if (strcmp(env, "warning") == 0) /* the word the log lines print */
        log_state.level = GI_LOG_WARN;
}

void gi_log_init(const char *program)
{
    log_state.program = program;
    log_read_env();
}

void gi_log_set_level(gi_log_level level)
{
    log_state.initialized = 1;
    log_state.level = level;
}

int gi_log_enabled(gi_log_level level)
{
    if (!log_state.initialized)
        log_read_env();
    return level <= log_state.level;
}

void gi_log(gi_log_level level, const char *fmt, ...)
{
    int hooked = hook_fn && !in_hook && level <= GI_LOG_WARN;
    if (!gi_log_enabled(level) && !hooked)
        return;
    static const char *names[] = {"error", "warning", "info", "debug"};
    char line[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (gi_log_enabled(level))
        emit(names[level], line);
    if (hooked) {
        in_hook = 1;
        hook_fn(hook_ctx, level, line);
        in_hook = 0;
    }
}

void gi_say(const char *fmt, ...)
{
    char line[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    emit(NULL, line);
}
