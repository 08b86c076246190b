/* gi_error: the error record every fallible gi function fills.
 *
 * Convention: a function returns 0 on success, -1 on failure after filling
 * the gi_error it was given (which may be NULL when the caller only needs the
 * status). The code tells the caller what to do with it (exit 2 for bad
 * input, retry for a crashed task, ...); the message is one line that names
 * the file / field / frame and what is wrong. */
#ifndef GI_ERROR_H
#define GI_ERROR_H

#include <stddef.h>

typedef enum gi_errcode {
    GI_OK = 0,
    GI_EINVAL,   /* bad input: job, scene, mesh, request (exit status 2) */
    GI_EIO,      /* file or socket I/O failed */
    GI_ENOMEM,   /* allocation failed or a size limit was exceeded */
    GI_EPROTO,   /* malformed or unexpected protocol frame */
    GI_ECRASH,   /* a worker process died while running a task */
    GI_ECANCEL,  /* the job was cancelled */
    GI_EINTERNAL, /* a broken invariant or a library failure */
    GI_EHOST     /* this host's own disk failed (full, over quota, read-only, a device
                  * error): not the task's fault, another host may run it */
} gi_errcode;

typedef struct gi_error {
    gi_errcode code;
    /* The errno of the system call that failed, where the caller may act on
     * it (ECONNREFUSED from a connect: nobody listens there yet); else 0.
     * Callers test this, never the message's strerror text. */
    int sys_errno;
    char msg[1024];
} gi_error;

/* Fills err (if non-NULL, sys_errno 0) and returns -1, so callers can
 * `return gi_fail(...)`. */
int gi_fail(gi_error *err, gi_errcode code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* gi_fail, keeping errnum in sys_errno (the message says it in words). */
int gi_fail_errno(gi_error *err, gi_errcode code, int errnum, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Prepends "prefix: " to an existing message (adds context on the way up). */
int gi_error_prefix(gi_error *err, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

void gi_error_clear(gi_error *err);
const char *gi_errcode_name(gi_errcode code);

/* A count or integer for a message: every digit up to 1e15, beyond that
 * %g ("1e+308", not 309 digits). Returns buf. */
const char *gi_fmt_count(char buf[32], double d);

/* The code for a failed write to this host's own disk: GI_EHOST for no
 * space, quota, read-only file system or a device error; GI_EIO otherwise. */
gi_errcode gi_disk_errcode(int errnum);

/* Process exit status for an error: 2 for bad input, 1 otherwise. */
int gi_error_exit_status(const gi_error *err);

/* Checked allocation: aborts the process on out-of-memory only where a caller
 * cannot sensibly recover (small bookkeeping). Large, input-driven sizes use
 * gi_try_malloc and report GI_ENOMEM instead. */
void *gi_xmalloc(size_t n);
void *gi_xcalloc(size_t count, size_t size);
void *gi_xrealloc(void *p, size_t n);
char *gi_xstrdup(const char *s);
void *gi_try_malloc(size_t n, gi_error *err, const char *what);
void *gi_try_calloc(size_t count, size_t size, gi_error *err, const char *what);

#define GI_ARRAY_LEN(a) (sizeof(a) / sizeof((a)[0]))

#endif
