/* gi_cores: the processors this process may use (see gi_cores.h). */
#include "gi_cores.h"

#include <errno.h>
#include <limits.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A decimal integer filling the whole token (leading blanks allowed),
 * stored in *out; 0, or -1 if it is not one. */
static int parse_long(const char *s, const char **end, long *out)
{
    char *e;
    errno = 0;
    long v = strtol(s, &e, 10);
    if (e == s || errno)
        return -1;
    *out = v;
    *end = e;
    return 0;
}

static int at_line_end(const char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    return *s == '\0' || (*s == '\n' && s[1] == '\0');
}

/* ceil(quota / period), at least 1; 0 if either is not positive. */
static long quota_cpus(long quota, long period)
{
    if (quota <= 0 || period <= 0)
        return 0;
    long n = quota / period + (quota % period != 0);
    return n > 0 ? n : 1;
}

long gi_cores_from_cpu_max(const char *text)
{
    const char *s = text, *e;
    long quota, period;
    while (*s == ' ' || *s == '\t')
        s++;
    if (strncmp(s, "max", 3) == 0)
        return 0;
    if (parse_long(s, &e, &quota) || (*e != ' ' && *e != '\t') || parse_long(e, &e, &period) ||
        !at_line_end(e))
        return 0;
    return quota_cpus(quota, period);
}

long gi_cores_from_cfs(const char *quota_text, const char *period_text)
{
    const char *e;
    long quota, period;
    if (parse_long(quota_text, &e, &quota) || !at_line_end(e) ||
        parse_long(period_text, &e, &period) || !at_line_end(e))
        return 0;
    return quota_cpus(quota, period);
}

/* The first line of a small file (a cgroup knob), or "" if unreadable. */
static void read_knob(const char *path, char *buf, size_t size)
{
    buf[0] = '\0';
    FILE *f = fopen(path, "re");
    if (!f)
        return;
    if (!fgets(buf, (int)size, f))
        buf[0] = '\0';
    fclose(f);
}

/* The quota (in CPUs, 0: none) set on the cgroup at dir: v2 when v1 is
 * NULL, else v1's knobs. */
static long dir_limit(const char *dir, int v1)
{
    char path[PATH_MAX + 32], a[128], b[128];
    if (!v1) {
        snprintf(path, sizeof path, "%s/cpu.max", dir);
        read_knob(path, a, sizeof a);
        return gi_cores_from_cpu_max(a);
    }
    snprintf(path, sizeof path, "%s/cpu.cfs_quota_us", dir);
    read_knob(path, a, sizeof a);
    snprintf(path, sizeof path, "%s/cpu.cfs_period_us", dir);
    read_knob(path, b, sizeof b);
    return gi_cores_from_cfs(a, b);
}

/* The tightest quota on the cgroup at root + rel and its ancestors up to
 * root (0: none). Inside a container the cgroup's path as /proc names it
 * may not exist under the mount, whose root is then the container's own
 * cgroup: the walk reaches it. */
static long walk_limit(const char *root, const char *rel, int v1)
{
    char dir[PATH_MAX];
    long best = 0;
    int n = snprintf(dir, sizeof dir, "%s%s", root, rel);
    if (n < 0 || (size_t)n >= sizeof dir)
        return 0;
    size_t root_len = strlen(root);
    for (;;) {
        size_t len = strlen(dir);
        while (len > root_len && dir[len - 1] == '/')
            dir[--len] = '\0';
        long l = dir_limit(dir, v1);
        if (l > 0 && (best == 0 || l < best))
            best = l;
        char *slash = strrchr(dir, '/');
        if (len <= root_len || !slash || (size_t)(slash - dir) < root_len)
            break;
        *slash = '\0';
    }
    return best;
}

/* Whether the comma-separated controller list names "cpu". */
static int has_cpu(const char *list, size_t len)
{
    const char *p = list, *end = list + len;
    while (p < end) {
        const char *c = memchr(p, ',', (size_t)(end - p));
        size_t n = c ? (size_t)(c - p) : (size_t)(end - p);
        if (n == 3 && strncmp(p, "cpu", 3) == 0)
            return 1;
        p += n + 1;
    }
    return 0;
}

static long cgroup_limit(void)
{
    FILE *f = fopen("/proc/self/cgroup", "re");
    if (!f)
        return 0;
    char line[PATH_MAX + 128];
    long best = 0;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        char *c1 = strchr(line, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2)
            continue;
        const char *ctrl = c1 + 1, *rel = c2 + 1;
        size_t ctrl_len = (size_t)(c2 - ctrl);
        long l = 0;
        if (ctrl_len == 0) {
            if (access("/sys/fs/cgroup/cgroup.controllers", F_OK) == 0)
                l = walk_limit("/sys/fs/cgroup", rel, 0);
        } else if (has_cpu(ctrl, ctrl_len)) {
            char root[PATH_MAX];
            snprintf(root, sizeof root, "/sys/fs/cgroup/%.*s", (int)ctrl_len, ctrl);
            if (access(root, F_OK) != 0)
                snprintf(root, sizeof root, "/sys/fs/cgroup/cpu");
            l = walk_limit(root, rel, 1);
        }
        if (l > 0 && (best == 0 || l < best))
            best = l;
    }
    fclose(f);
    return best;
}

static long affinity_cpus(long online)
{
    long conf = sysconf(_SC_NPROCESSORS_CONF);
    int max = (int)(conf > online ? conf : online);
    if (max < 1024)
        max = 1024;
    cpu_set_t *set = CPU_ALLOC(max);
    if (!set)
        return 0;
    size_t size = CPU_ALLOC_SIZE(max);
    long n = 0;
    if (sched_getaffinity(0, size, set) == 0)
        n = CPU_COUNT_S(size, set);
    CPU_FREE(set);
    return n;
}

int gi_cores_usable(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1)
        n = 1;
    long a = affinity_cpus(n);
    if (a > 0 && a < n)
        n = a;
    long q = cgroup_limit();
    if (q > 0 && q < n)
        n = q;
    return n > INT_MAX ? INT_MAX : (int)n;
}
