/* gi-tests: runs the registered unit tests. See gi_test.h. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_test.h"

typedef struct {
    const char *name, *file;
    gi_test_fn fn;
} test_entry;

static test_entry tests[1024];
static int test_count;
static int failures;
static char tmpdir[512];

void gi_test_register(const char *name, const char *file, gi_test_fn fn)
{
    if (test_count == (int)(sizeof tests / sizeof tests[0])) {
        fprintf(stderr, "gi-tests: too many tests\n");
        exit(1);
    }
    tests[test_count++] = (test_entry){name, file, fn};
}

void gi_test_failed(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "  %s:%d: ", file, line);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n");
    va_end(ap);
    failures++;
}

const char *gi_test_tmpdir(void)
{
    if (!tmpdir[0]) {
        const char *base = getenv("GI_TEST_TMP");
        snprintf(tmpdir, sizeof tmpdir, "%s/gi-test-%ld", base ? base : "/tmp", (long)getpid());
        mkdir(tmpdir, 0755);
    }
    return tmpdir;
}

const char *gi_test_srcdir(void)
{
    const char *s = getenv("GI_SRCDIR");
    return s ? s : ".";
}

static int run_one(const test_entry *t)
{
    failures = 0;
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    t->fn();
    clock_gettime(CLOCK_MONOTONIC, &b);
    double s = (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
    printf("%s %s (%.2fs)\n", failures ? "FAIL" : "PASS", t->name, s);
    fflush(stdout);
    return failures ? 1 : 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--list") == 0) {
        for (int i = 0; i < test_count; i++)
            printf("%s\n", tests[i].name);
        return 0;
    }
    int failed = 0, ran = 0;
    for (int i = 0; i < test_count; i++) {
        int selected = argc < 2 || strcmp(argv[1], "--all") == 0;
        for (int a = 1; a < argc; a++)
            if (strcmp(argv[a], tests[i].name) == 0)
                selected = 1;
        if (!selected)
            continue;
        ran++;
        failed += run_one(&tests[i]);
    }
    if (ran == 0) {
        fprintf(stderr, "gi-tests: no test matches\n");
        return 2;
    }
    return failed ? 1 : 0;
}
