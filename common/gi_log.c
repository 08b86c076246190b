/* gi_log: leveled logging to stderr. */
#include "gi_log.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static struct {
    const char *program;
    gi_log_level level;
    int initialized;
} log_state = {"gi", GI_LOG_WARN, 0};

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
    if (!gi_log_enabled(level))
        return;
    static const char *names[] = {"error", "warning", "info", "debug"};
    char line[2048];
    int n = snprintf(line, sizeof line, "%s[%ld] %s: ", log_state.program, (long)getpid(),
                     names[level]);
    va_list ap;
    va_start(ap, fmt);
    if (n > 0 && (size_t)n < sizeof line)
        vsnprintf(line + n, sizeof line - (size_t)n, fmt, ap);
    va_end(ap);
    fprintf(stderr, "%s\n", line);
}
