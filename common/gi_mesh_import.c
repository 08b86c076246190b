/* gi_mesh_import: OBJ / PLY / glTF 2.0 meshes through assimp's C API.
 *
 * assimp never touches the disk: every file it opens (the mesh, an OBJ's
 * .mtl, a glTF's .bin) is read whole through the job's gi_asset_source and
 * served from memory, so imports work the same on a farm worker that has
 * only the job's assets, and the source's manifest lists every file used.
 * assimp itself runs in a child process (see "assimp in a child process"). */
#include "gi_mesh.h"
#include "gi_mesh_convert.h"
#include "gi_mesh_wire.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gi_clock.h"
#include "gi_fs.h"
#include "gi_log.h"

/* One file asked for during an import, read once (assimp opens the main
 * file several times: to check it exists, to detect the format, to read). */
typedef struct import_file {
    char *name; /* normalized */
    int ok;
    gi_buf bytes;
    gi_error err; /* why it could not be read, when !ok */
} import_file;

typedef struct import_ctx {
    const gi_asset_source *src;
    import_file **files; /* each allocated apart: open handles point into them */
    size_t count, cap;
    size_t open_handles; /* to free what assimp might leave open */
    struct handle **handles;
    size_t handles_cap;
} import_ctx;

/* An open file: a read cursor over a cached import_file. */
typedef struct handle {
    struct aiFile file;
    const gi_buf *bytes;
    size_t pos;
} handle;

static import_file *ctx_fetch(import_ctx *c, const char *raw_name)
{
    char *name = gi_path_normalize(raw_name);
    for (size_t i = 0; i < c->count; i++)
        if (strcmp(c->files[i]->name, name) == 0) {
            free(name);
            return c->files[i];
        }
    if (c->count == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 4;
        c->files = gi_xrealloc(c->files, c->cap * sizeof *c->files);
    }
    import_file *f = gi_xcalloc(1, sizeof *f);
    c->files[c->count++] = f;
    f->name = name;
    gi_buf_init(&f->bytes);
    gi_error_clear(&f->err);
    f->ok = gi_asset_read(c->src, name, &f->bytes, &f->err) == 0;
    if (!f->ok)
        gi_debug("mesh import: %s", f->err.msg);
    return f;
}

static size_t file_read(struct aiFile *af, char *buf, size_t size, size_t count)
{
    handle *h = (handle *)af->UserData;
    if (size == 0 || count == 0)
        return 0;
    size_t left = h->bytes->len - h->pos;
    size_t n = left / size < count ? left / size : count; /* whole elements, as fread */
    if (n == 0)
        return 0; /* also keeps an empty file's NULL data out of memcpy */
    memcpy(buf, h->bytes->data + h->pos, n * size);
    h->pos += n * size;
    return n;
}

static size_t file_write(struct aiFile *af, const char *buf, size_t size, size_t count)
{
    return 0; /* imports only read */
}

static size_t file_tell(struct aiFile *af) { return ((handle *)af->UserData)->pos; }

static size_t file_size(struct aiFile *af) { return ((handle *)af->UserData)->bytes->len; }

static void file_flush(struct aiFile *af) {}

static enum aiReturn file_seek(struct aiFile *af, size_t offset, enum aiOrigin origin)
{
    handle *h = (handle *)af->UserData;
    size_t len = h->bytes->len, base;
    switch (origin) {
    case aiOrigin_SET: base = 0; break;
    case aiOrigin_CUR: base = h->pos; break;
    case aiOrigin_END: base = len; break;
    default: return aiReturn_FAILURE;
    }
    /* offset is unsigned in this API: seeks only go forward from base. */
    if (offset > len - base)
        return aiReturn_FAILURE;
    h->pos = base + offset;
    return aiReturn_SUCCESS;
}

static struct aiFile *fs_open(struct aiFileIO *io, const char *name, const char *mode)
{
    import_ctx *c = (import_ctx *)io->UserData;
    if (strpbrk(mode, "wa+"))
        return NULL;
    import_file *f = ctx_fetch(c, name);
    /* A file that is not there fails quietly: assimp probes for optional
     * files (an OBJ's fallback .mtl) and carries on without them. */
    if (!f->ok)
        return NULL;
    handle *h = gi_xcalloc(1, sizeof *h);
    h->file.ReadProc = file_read;
    h->file.WriteProc = file_write;
    h->file.TellProc = file_tell;
    h->file.FileSizeProc = file_size;
    h->file.SeekProc = file_seek;
    h->file.FlushProc = file_flush;
    h->file.UserData = (aiUserData)h;
    h->bytes = &f->bytes;
    if (c->open_handles == c->handles_cap) {
        c->handles_cap = c->handles_cap ? 2 * c->handles_cap : 8;
        c->handles = gi_xrealloc(c->handles, c->handles_cap * sizeof *c->handles);
    }
    c->handles[c->open_handles++] = h;
    return &h->file;
}

static void fs_close(struct aiFileIO *io, struct aiFile *af)
{
    import_ctx *c = (import_ctx *)io->UserData;
    if (!af)
        return;
    handle *h = (handle *)af->UserData;
    for (size_t i = 0; i < c->open_handles; i++)
        if (c->handles[i] == h) {
            c->handles[i] = c->handles[--c->open_handles];
            break;
        }
    free(h);
}

static void ctx_free(import_ctx *c)
{
    for (size_t i = 0; i < c->open_handles; i++)
        free(c->handles[i]);
    free(c->handles);
    for (size_t i = 0; i < c->count; i++) {
        free(c->files[i]->name);
        gi_buf_free(&c->files[i]->bytes);
        free(c->files[i]);
    }
    free(c->files);
}

/* assimp's C API keeps the last error in a process-wide string: an import
 * and the reading of its error are one critical section. */
static pthread_mutex_t assimp_lock = PTHREAD_MUTEX_INITIALIZER;

/* assimp's glTF reader drops a face whose index is out of range and says so
 * only in its log (an OBJ's is refused with its line, gi_mesh_precheck.c):
 * the message is caught to refuse the file instead. */
static void on_assimp_log(const char *msg, char *user)
{
    if (strstr(msg, "out-of-range indices"))
        *(int *)(void *)user = 1;
}

/* assimp's import and gi_mesh_from_assimp, over the files of c (the main one first). */
static int assimp_import(import_ctx *c, const char *name, gi_mesh_data *out, gi_error *err)
{
    struct aiFileIO io = {fs_open, fs_close, (aiUserData)c};
    /* SortByPType leaves every mesh one primitive type; gi_mesh_from_assimp
     * skips the point and line meshes. (Not AI_CONFIG_PP_SBP_REMOVE: a file with
     * nothing but lines would then fail as "No meshes remaining" instead of
     * "no triangles".) No aiProcess_GenNormals: the scene computes
     * normals for meshes without (split at hard edges), the same way for every
     * format. */
    unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                     aiProcess_PreTransformVertices | aiProcess_SortByPType |
                     aiProcess_ValidateDataStructure;
    char aimsg[600] = "";
    int dropped = 0;
    struct aiLogStream log = {on_assimp_log, (char *)(void *)&dropped};
    pthread_mutex_lock(&assimp_lock);
    aiAttachLogStream(&log);
    const struct aiScene *sc = aiImportFileEx(c->files[0]->name, flags, &io);
    if (!sc)
        snprintf(aimsg, sizeof aimsg, "%s", aiGetErrorString());
    aiDetachLogStream(&log);
    pthread_mutex_unlock(&assimp_lock);
    if (sc && dropped) {
        aiReleaseImport(sc);
        return gi_fail(err, GI_EINVAL,
                       "%s: cannot import: a face uses a vertex index out of range (the "
                       "primitive's indices name vertices its accessors do not have)",
                       name);
    }
    if (sc) {
        /* Every file read after the main one is a material library (an
         * OBJ's; a glTF's buffers are never looked at for materials). */
        const gi_buf **libs = gi_xcalloc(c->count, sizeof *libs);
        size_t nlibs = 0;
        for (size_t i = 1; i < c->count; i++)
            if (c->files[i]->ok)
                libs[nlibs++] = &c->files[i]->bytes;
        int rc = gi_mesh_from_assimp(sc, libs, nlibs, name, out, err);
        free(libs);
        aiReleaseImport(sc);
        return rc;
    }
    /* A referenced file (.mtl, .bin) that could not be read is the likely
     * cause: say which, and keep its code (a failed fetch is not bad input). */
    const import_file *missing = NULL;
    for (size_t i = 1; i < c->count && !missing; i++)
        if (!c->files[i]->ok)
            missing = c->files[i];
    return gi_fail(err, missing && missing->err.code != GI_OK ? missing->err.code : GI_EINVAL,
                   "%s: cannot import: %s%s%s", name, aimsg[0] ? aimsg : "unknown assimp error",
                   missing ? "; " : "", missing ? missing->err.msg : "");
}

/* ---- assimp in a child process --------------------------------------------
 * assimp has assertions that malformed files reach (it is built with them:
 * a PLY with a garbled face list aborts in its triangulation; fuzz_mesh), and
 * leaks on some error paths. So it runs in a forked child: the parent serves
 * the files it asks for (through the job's source, whose manifest and cache
 * stay the parent's) and reads back the converted mesh or the error; a child
 * that dies is an error naming the file. One child imports a session's files
 * one after another (a scene of thousands of mesh files paid a fork and a
 * fresh process's page faults for each: 26 ms a file); after a file it fails
 * on, crashes on or outlives its deadline on, the next file gets a new child,
 * so a failure is always pinned to its file and no damage carries over.
 * Messages on the socket pair: u8 type, u64 length, payload. */

enum {
    MSG_IMPORT = 'I', /* parent: a file's name, to import */
    MSG_READ = 'R',  /* child: a file's name */
    MSG_FILE = 'F',  /* parent: u8 ok, then the bytes or u32 code + message */
    MSG_MESH = 'M',  /* child: the mesh (gi_mesh_encode) */
    MSG_ERROR = 'E', /* child: u32 code + message */
};

static int send_all(int fd, const void *p, size_t n)
{
    const uint8_t *b = p;
    while (n) {
        ssize_t w = send(fd, b, n, MSG_NOSIGNAL);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        b += w;
        n -= (size_t)w;
    }
    return 0;
}

static int recv_all(int fd, void *p, size_t n)
{
    uint8_t *b = p;
    while (n) {
        ssize_t r = recv(fd, b, n, 0);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return -1;
        b += r;
        n -= (size_t)r;
    }
    return 0;
}

static int send_msg(int fd, uint8_t type, const gi_buf *payload)
{
    uint8_t head[9];
    head[0] = type;
    gi_le_put_u64(head + 1, payload->len);
    return send_all(fd, head, sizeof head) || send_all(fd, payload->data, payload->len) ? -1 : 0;
}

static int recv_msg(int fd, uint8_t *type, gi_buf *payload)
{
    uint8_t head[9];
    if (recv_all(fd, head, sizeof head))
        return -1;
    uint64_t len = gi_le_get_u64(head + 1);
    if (len > ((uint64_t)1 << 40))
        return -1;
    *type = head[0];
    gi_buf_reset(payload);
    return recv_all(fd, gi_buf_grow(payload, (size_t)len), (size_t)len);
}

static void put_error(gi_buf *b, const gi_error *e)
{
    gi_buf_put_u32(b, (uint32_t)e->code);
    gi_buf_put_str(b, e->msg);
}

static void get_error(gi_reader *r, gi_error *err)
{
    uint32_t code = gi_get_u32(r);
    char *msg = gi_get_str(r, sizeof err->msg);
    gi_fail(err, code > GI_OK && code <= GI_EINTERNAL ? (gi_errcode)code : GI_EINTERNAL, "%s",
            msg ? msg : "mesh import: a bad error message from the importer process");
    free(msg);
}

/* The child's source: every read is a question to the parent. */
static int child_read(void *ctx, const char *name, gi_buf *out, gi_error *err)
{
    int fd = *(const int *)ctx;
    gi_buf q;
    gi_buf_init(&q);
    gi_buf_put(&q, name, strlen(name));
    uint8_t type;
    int rc = send_msg(fd, MSG_READ, &q) || recv_msg(fd, &type, &q) || type != MSG_FILE;
    if (rc) {
        gi_buf_free(&q);
        return gi_fail(err, GI_EIO, "%s: the importer lost its parent", name);
    }
    gi_reader r;
    gi_reader_init(&r, q.data, q.len, "mesh file");
    if (gi_get_u8(&r)) {
        gi_buf_reset(out);
        gi_buf_put(out, r.p, r.left);
    } else {
        get_error(&r, err);
        rc = -1;
    }
    gi_buf_free(&q);
    return rc;
}

/* AddressSanitizer maps terabytes of shadow memory up front: an
 * address-space limit would fail its first allocation. */
#if defined(__SANITIZE_ADDRESS__)
#define IMPORT_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IMPORT_UNDER_ASAN 1
#endif
#endif

#ifndef IMPORT_UNDER_ASAN
/* How much memory assimp may take beyond what this process has mapped when
 * it forks: 2 GiB and 32 bytes per byte of the file, at most the machine's
 * physical memory. A small glTF whose nodes form a DAG (every node naming
 * the next twice) makes assimp expand it into gigabytes of meshes. */
static uint64_t import_memory_budget(size_t bytes)
{
    uint64_t budget = ((uint64_t)2 << 30) + 32 * (uint64_t)bytes;
    long pages = sysconf(_SC_PHYS_PAGES), psize = sysconf(_SC_PAGESIZE);
    uint64_t phys = pages > 0 && psize > 0 ? (uint64_t)pages * (uint64_t)psize : 0;
    return phys && phys < budget ? phys : budget;
}

/* In the child, before each file: caps its address space at what it has
 * mapped now plus the file's budget (never above `given`, the limit the
 * child started with: gi-farmd's check process sets one). Returns the
 * budget, or 0 if the limit is `given`'s. */
static uint64_t limit_import_memory(size_t bytes, const struct rlimit *given)
{
    unsigned long long vm_pages = 0;
    FILE *f = fopen("/proc/self/statm", "re");
    int ok = f && fscanf(f, "%llu", &vm_pages) == 1;
    if (f)
        fclose(f);
    long psize = sysconf(_SC_PAGESIZE);
    if (!ok || psize <= 0)
        return 0;
    uint64_t budget = import_memory_budget(bytes);
    rlim_t want = (rlim_t)(vm_pages * (uint64_t)psize + budget);
    struct rlimit rl = *given;
    if (given->rlim_cur != RLIM_INFINITY && given->rlim_cur <= want) {
        setrlimit(RLIMIT_AS, given); /* the tighter limit it was given */
        return 0;
    }
    rl.rlim_cur = want;
    return setrlimit(RLIMIT_AS, &rl) == 0 ? budget : 0;
}
#else
static uint64_t limit_import_memory(size_t bytes, const struct rlimit *given) { return 0; }
#endif

/* In the child: one file, its files asked of the parent; 0 when the answer
 * was sent. */
static int child_import(int fd, const char *name, const struct rlimit *given)
{
    import_ctx c;
    memset(&c, 0, sizeof c);
    gi_asset_source src = {child_read, &fd};
    c.src = &src;
    gi_mesh_data m;
    gi_mesh_data_init(&m);
    gi_error e;
    gi_error_clear(&e);
    gi_buf b;
    gi_buf_init(&b);
    import_file *main_file = ctx_fetch(&c, name);
    size_t bytes = main_file->bytes.len;
    int rc = main_file->ok ? -2 : -1;
    uint64_t budget = rc == -2 ? limit_import_memory(bytes, given) : 0;
    if (rc == -2)
        rc = assimp_import(&c, name, &m, &e);
    /* assimp says "std::bad_alloc"; a failed allocation of ours, GI_ENOMEM. */
    if (rc && budget && (e.code == GI_ENOMEM || strstr(e.msg, "bad_alloc")))
        gi_fail(&e, GI_EINVAL,
                "%s: cannot import: the importer ran out of its memory limit (%.1f GiB for "
                "its %zu bytes): the file is malformed or too big for this machine",
                name, (double)budget / (double)(1u << 30), bytes);
    if (rc == 0)
        gi_mesh_encode(&b, &m);
    else
        put_error(&b, e.code != GI_OK ? &e : &c.files[0]->err);
    rc = send_msg(fd, rc == 0 ? MSG_MESH : MSG_ERROR, &b);
    gi_buf_free(&b);
    gi_mesh_data_free(&m);
    ctx_free(&c);
    return rc;
}

/* In the child: imports the files the parent names until it hangs up;
 * never returns. */
static void child_main(int fd)
{
    struct rlimit given = {RLIM_INFINITY, RLIM_INFINITY};
    getrlimit(RLIMIT_AS, &given);
    gi_buf b;
    gi_buf_init(&b);
    uint8_t type;
    int rc = 0;
    while (rc == 0 && recv_msg(fd, &type, &b) == 0 && type == MSG_IMPORT) {
        char *name = gi_xmalloc(b.len + 1);
        memcpy(name, b.data, b.len);
        name[b.len] = '\0';
        rc = child_import(fd, name, &given);
        free(name);
    }
    _exit(rc ? 1 : 0); /* no atexit handlers or stdio flushes of the parent's */
}

/* How long assimp may take: a few seconds, and more for big files (it reads
 * tens of MB a second). It loops forever on some malformed files (a PLY
 * with a garbled header: fuzz_mesh). */
static double import_seconds(size_t bytes) { return 5.0 + 2.0 * (double)bytes / 1e6; }

/* Waits for the child to say something until the deadline: 0 when it
 * did, 1 when time ran out, -1 on an error. */
static int wait_readable(int fd, double deadline)
{
    for (;;) {
        double left = deadline - gi_now();
        if (left <= 0)
            return 1;
        struct pollfd pfd = {fd, POLLIN, 0};
        int n = poll(&pfd, 1, (int)(left * 1000.0) + 1);
        if (n < 0 && errno == EINTR)
            continue;
        return n > 0 ? 0 : n == 0 ? 1 : -1;
    }
}

struct gi_mesh_importer {
    const gi_asset_source *src;
    int fd;    /* the child's end of the socket pair, -1 with no child */
    pid_t pid; /* the child, -1 with none */
    unsigned processes; /* children started */
};

gi_mesh_importer *gi_mesh_importer_new(const gi_asset_source *src)
{
    gi_mesh_importer *imp = gi_xcalloc(1, sizeof *imp);
    imp->src = src;
    imp->fd = -1;
    imp->pid = -1;
    return imp;
}

/* Ends the child (killed: it may be looping in assimp) and reaps it; its
 * wait status into *status if asked. */
static void stop_child(gi_mesh_importer *imp, int *status)
{
    if (imp->fd >= 0)
        close(imp->fd);
    if (imp->pid > 0) {
        kill(imp->pid, SIGKILL);
        int st = 0;
        pid_t w;
        while ((w = waitpid(imp->pid, &st, 0)) < 0 && errno == EINTR)
            ;
        if (status)
            *status = w == imp->pid ? st : -1;
    }
    imp->fd = -1;
    imp->pid = -1;
}

void gi_mesh_importer_free(gi_mesh_importer *imp)
{
    if (!imp)
        return;
    stop_child(imp, NULL);
    free(imp);
}

/* Forks the session's child if none runs: 0, or -1 with errno set. */
static int start_child(gi_mesh_importer *imp)
{
    if (imp->pid > 0)
        return 0;
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        return -1;
    fflush(NULL); /* nothing buffered is written twice */
    pid_t pid = fork();
    if (pid == 0) {
        close(sv[0]);
        prctl(PR_SET_PDEATHSIG, SIGKILL); /* no importer outlives its parent */
        /* Die by the signal (the parent names it), whatever handlers this
         * process had installed (a crash reporter, a fuzzer's). */
        static const int crash_signals[] = {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL};
        for (size_t i = 0; i < sizeof crash_signals / sizeof crash_signals[0]; i++)
            signal(crash_signals[i], SIG_DFL);
        child_main(sv[1]);
    }
    int why = errno;
    close(sv[1]);
    if (pid < 0) {
        close(sv[0]);
        errno = why;
        return -1;
    }
    imp->fd = sv[0];
    imp->pid = pid;
    imp->processes++;
    return 0;
}

unsigned gi_mesh_importer_processes(const gi_mesh_importer *imp) { return imp->processes; }

/* Why the child gave no answer, from how it ended. */
static int child_lost(const char *name, int status, gi_error *err)
{
    if (status != -1 && WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        /* An assertion or a bad access in assimp is the file's doing; a
         * kill (the OOM killer, an operator) is not. */
        int file = sig == SIGABRT || sig == SIGSEGV || sig == SIGBUS || sig == SIGFPE ||
                   sig == SIGILL;
        return gi_fail(err, file ? GI_EINVAL : GI_ECRASH,
                       "%s: cannot import: the importer (assimp) died on it (%s)%s", name,
                       strsignal(sig), file ? ": the file is malformed or unsupported" : "");
    }
    return gi_fail(err, GI_ECRASH,
                   "%s: cannot import: the importer process ended without an answer (exit "
                   "status %d)",
                   name, status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

/* Has the child import `name`, serving its reads, until it answers or the
 * deadline passes. A child that did not answer with a mesh is stopped. 1:
 * the child was gone before it was asked (nothing was tried). */
static int child_run(gi_mesh_importer *imp, import_ctx *c, const char *name, gi_mesh_data *out,
                     gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put(&b, name, strlen(name));
    int rc = -1, answered = 0, late = 0, mesh = 0;
    uint8_t type;
    double limit = import_seconds(c->files[0]->bytes.len), deadline = gi_now() + limit;
    if (send_msg(imp->fd, MSG_IMPORT, &b)) { /* it died while it waited */
        gi_buf_free(&b);
        stop_child(imp, NULL);
        return 1;
    }
    while (!answered && !(late = wait_readable(imp->fd, deadline) == 1) &&
           recv_msg(imp->fd, &type, &b) == 0) {
        if (type == MSG_READ) {
            char *want = gi_xmalloc(b.len + 1);
            memcpy(want, b.data, b.len);
            want[b.len] = '\0';
            import_file *f = ctx_fetch(c, want);
            free(want);
            gi_buf_reset(&b);
            gi_buf_put_u8(&b, (uint8_t)f->ok);
            if (f->ok)
                gi_buf_put(&b, f->bytes.data, f->bytes.len);
            else
                put_error(&b, &f->err);
            if (send_msg(imp->fd, MSG_FILE, &b))
                break;
        } else if (type == MSG_MESH) {
            rc = gi_mesh_decode(b.data, b.len, name, out, err);
            answered = mesh = 1;
        } else if (type == MSG_ERROR) {
            gi_reader r;
            gi_reader_init(&r, b.data, b.len, "importer error");
            get_error(&r, err);
            answered = 1;
        } else {
            break;
        }
    }
    gi_buf_free(&b);
    if (mesh)
        return rc;
    /* An error may leave assimp's memory in any state (it leaks on some
     * error paths): the next file gets a new child. */
    int status = -1;
    stop_child(imp, late || answered ? NULL : &status);
    if (answered)
        return rc;
    if (late)
        return gi_fail(err, GI_EINVAL,
                       "%s: cannot import: the importer (assimp) took more than %.0f s on its "
                       "%zu bytes: the file is malformed or unsupported",
                       name, limit, c->files[0]->bytes.len);
    return child_lost(name, status, err);
}

int gi_mesh_importer_run(gi_mesh_importer *imp, const char *name, gi_mesh_data *out,
                         gi_error *err)
{
    gi_mesh_data_init(out);
    import_ctx c;
    memset(&c, 0, sizeof c);
    c.src = imp->src;
    /* Read the main file first, so a missing one is reported as the
     * source says it (and not as assimp's "unable to open"). */
    import_file *main_file = ctx_fetch(&c, name);
    if (!main_file->ok) {
        if (err && main_file->err.code == GI_OK)
            gi_fail(err, GI_EIO, "%s: the asset source could not read it", name);
        else if (err)
            *err = main_file->err;
        ctx_free(&c);
        return -1;
    }

    if (gi_mesh_precheck(name, main_file->bytes.data, main_file->bytes.len, err)) {
        ctx_free(&c);
        return -1;
    }

    gi_error e;
    gi_error_clear(&e);
    int rc;
    int started = start_child(imp) == 0;
    rc = started ? child_run(imp, &c, name, out, &e) : -1;
    if (rc == 1 && (started = start_child(imp) == 0))
        rc = child_run(imp, &c, name, out, &e);
    if (rc == 1)
        rc = gi_fail(&e, GI_ECRASH, "%s: cannot import: the importer process is gone", name);
    if (!started) {
        gi_debug("%s: importing in this process (no child: %s)", name, strerror(errno));
        rc = assimp_import(&c, name, out, &e);
    }
    if (rc && err)
        *err = e;
    ctx_free(&c);
    if (rc)
        gi_mesh_data_free(out);
    return rc;
}

int gi_mesh_import(const gi_asset_source *src, const char *name, gi_mesh_data *out,
                   gi_error *err)
{
    gi_mesh_importer *imp = gi_mesh_importer_new(src);
    int rc = gi_mesh_importer_run(imp, name, out, err);
    gi_mesh_importer_free(imp);
    return rc;
}
