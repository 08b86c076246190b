/* gi_exr: EXR files through OpenEXR's C API (OpenEXRCore 3.1).
 *
 * We give the library our own read/write/size callbacks on a file descriptor
 * instead of letting it open the path: writes then go to gi_temp_path() and
 * are committed by rename, and the callbacks' user data carries the first
 * library error message back to us (the error handler gets only the
 * context). Reads use the file size to validate offsets, so a truncated file
 * is an error message, not a read past the end.
 *
 * Determinism: the header holds only the required attributes (no dates,
 * no host names), each chunk is compressed on its own (by whichever thread)
 * at a fixed deflate level and the chunks are written in increasing y, so
 * the same image gives the same bytes (with the same libdeflate).
 * tests/unit/test_image.c checks this, also with malloc'ed memory pre-filled
 * with different patterns. */
#include "gi_image.h"

#include <OpenEXR/openexr.h>
#include <errno.h>
#include <fcntl.h>
#include <libdeflate.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_cores.h"
#include "gi_fs.h"


typedef struct exr_io {
    int fd;
    int64_t size;        /* file size when reading */
    char msg[512];       /* first message from the library's error handler */
} exr_io;

/* The file this thread reads or writes. The error handler finds its exr_io
 * here, not through exr_get_user_data: the library calls the handler with
 * the context's mutex held (writing the header, say), and that mutex does
 * not allow a second lock, so asking the context would wait for ever (a
 * full disk used to hang gi-farmd and gi render so). */
static _Thread_local exr_io *current_io;

static void exr_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    exr_io *io = current_io;
    if (!io || io->msg[0] || !msg)
        return;
    snprintf(io->msg, sizeof io->msg, "%s", msg);
    for (char *p = io->msg; *p; p++) /* messages are one line */
        if (*p == '\n' || *p == '\r')
            *p = ' ';
}

static int64_t exr_io_read(exr_const_context_t ctxt, void *ud, void *buffer, uint64_t sz,
                           uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_io *io = ud;
    if (offset > (uint64_t)INT64_MAX || sz > (uint64_t)INT64_MAX - offset) {
        error_cb(ctxt, EXR_ERR_READ_IO, "read of %llu bytes at offset %llu is out of range",
                 (unsigned long long)sz, (unsigned long long)offset);
        return -1;
    }
    uint64_t done = 0;
    while (done < sz) {
        ssize_t n = pread(io->fd, (char *)buffer + done, (size_t)(sz - done),
                          (off_t)(offset + done));
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            error_cb(ctxt, EXR_ERR_READ_IO, "read at offset %llu: %s",
                     (unsigned long long)(offset + done), strerror(errno));
            return -1;
        }
        if (n == 0)
            break; /* end of file: the library checks the short count */
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t exr_io_size(exr_const_context_t ctxt, void *ud)
{
    return ((exr_io *)ud)->size;
}

static int64_t exr_io_write(exr_const_context_t ctxt, void *ud, const void *buffer, uint64_t sz,
                            uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_io *io = ud;
    if (offset > (uint64_t)INT64_MAX || sz > (uint64_t)INT64_MAX - offset) {
        error_cb(ctxt, EXR_ERR_WRITE_IO, "write of %llu bytes at offset %llu is out of range",
                 (unsigned long long)sz, (unsigned long long)offset);
        return -1;
    }
    uint64_t done = 0;
    while (done < sz) {
        ssize_t n = pwrite(io->fd, (const char *)buffer + done, (size_t)(sz - done),
                           (off_t)(offset + done));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            error_cb(ctxt, EXR_ERR_WRITE_IO, "write at offset %llu: %s",
                     (unsigned long long)(offset + done), n < 0 ? strerror(errno) : "no progress");
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

/* Turns a library result into a gi_error naming the file and the step. */
static int exr_fail(gi_error *err, const char *path, const char *step, exr_result_t r,
                    const exr_io *io, int reading)
{
    gi_errcode code;
    switch (r) {
    case EXR_ERR_OUT_OF_MEMORY:
        code = GI_ENOMEM;
        break;
    case EXR_ERR_FILE_ACCESS:
    case EXR_ERR_WRITE_IO:
        code = GI_EIO;
        break;
    case EXR_ERR_READ_IO: /* includes reads past the end of a truncated file */
        code = reading ? GI_EINVAL : GI_EIO;
        break;
    default:
        code = reading ? GI_EINVAL : GI_EINTERNAL;
        break;
    }
    return gi_fail(err, code, "%s: EXR %s failed: %s (%s)", path, step,
                   io->msg[0] ? io->msg : exr_get_default_error_message(r),
                   exr_get_error_code_as_string(r));
}

/* ---- writing ---------------------------------------------------------- */

/* ZIP chunks, compressed here rather than by OpenEXRCore's pipeline:
 * the chunk's scanlines packed as EXR stores them (per line, each channel
 * in file order, little-endian floats), OpenEXR's byte reordering and
 * delta coding, then a zlib stream from libdeflate (about twice as fast as
 * zlib at the same level), several chunks at once on the host's cores,
 * written in increasing y. The bytes do not depend on the thread count. A
 * chunk that deflate does not make strictly smaller is stored raw: readers
 * (this library's and OpenEXR's) take a chunk as long as its raw size for
 * raw data (OpenEXRCore 3.1.5's own compressor kept such deflated bytes,
 * and a quadrature image read back as garbage). */
typedef struct zip_job {
    const gi_image *img;
    const int *order; /* image channel of each file channel */
    int lines, chunks;
    uint8_t **out;     /* per chunk: its bytes (malloc'ed) */
    size_t *out_bytes; /* and how many */
    int next;          /* next chunk to take */
    int failed;
    pthread_mutex_t lock;
} zip_job;

/* OpenEXR's ZIP predictor: the even bytes then the odd ones, each the
 * difference from the one before (+128). */
static void zip_deconstruct(uint8_t *out, const uint8_t *in, size_t n)
{
    uint8_t *t1 = out, *t2 = out + (n + 1) / 2;
    for (size_t i = 0; i + 1 < n; i += 2) {
        *t1++ = in[i];
        *t2++ = in[i + 1];
    }
    if (n % 2)
        *t1 = in[n - 1];
    int p = out[0];
    for (size_t i = 1; i < n; i++) {
        int d = (int)out[i] - p + (128 + 256);
        p = out[i];
        out[i] = (uint8_t)d;
    }
}

/* Compresses chunk c into j->out[c]: 0, or -1 out of memory. */
static int zip_chunk(zip_job *j, int c, struct libdeflate_compressor *dc, uint8_t *packed,
                     uint8_t *scratch)
{
    const gi_image *img = j->img;
    int y0 = c * j->lines, y1 = y0 + j->lines < img->height ? y0 + j->lines : img->height;
    size_t C = (size_t)img->channels, W = (size_t)img->width;
    uint8_t *p = packed;
    for (int y = y0; y < y1; y++)
        for (size_t k = 0; k < C; k++) {
            const float *src = gi_image_at(img, 0, y) + j->order[k];
            for (size_t x = 0; x < W; x++, p += 4) {
                uint32_t u;
                memcpy(&u, &src[x * C], 4);
                p[0] = (uint8_t)u, p[1] = (uint8_t)(u >> 8), p[2] = (uint8_t)(u >> 16);
                p[3] = (uint8_t)(u >> 24);
            }
        }
    size_t n = (size_t)(p - packed);
    uint8_t *out = malloc(n);
    if (!out)
        return -1;
    zip_deconstruct(scratch, packed, n);
    /* Room for n - 1 bytes: 0 (it does not fit) means "store raw". */
    size_t got = n > 1 ? libdeflate_zlib_compress(dc, scratch, n, out, n - 1) : 0;
    if (got == 0) {
        memcpy(out, packed, n);
        got = n;
    }
    j->out[c] = out;
    j->out_bytes[c] = got;
    return 0;
}

static void *zip_worker(void *arg)
{
    zip_job *j = arg;
    size_t most = (size_t)j->lines * (size_t)j->img->width * (size_t)j->img->channels * 4;
    struct libdeflate_compressor *dc = libdeflate_alloc_compressor(GI_EXR_ZIP_LEVEL);
    uint8_t *packed = malloc(most), *scratch = malloc(most);
    for (;;) {
        pthread_mutex_lock(&j->lock);
        int c = j->failed ? j->chunks : j->next++;
        pthread_mutex_unlock(&j->lock);
        if (c >= j->chunks)
            break;
        if (!dc || !packed || !scratch || zip_chunk(j, c, dc, packed, scratch)) {
            pthread_mutex_lock(&j->lock);
            j->failed = 1;
            pthread_mutex_unlock(&j->lock);
        }
    }
    free(packed);
    free(scratch);
    if (dc)
        libdeflate_free_compressor(dc);
    return NULL;
}

/* The CPUs this process may use, read once (gi_cores reads /proc and the
 * cgroup's files): an animation writes an image every frame. */
static int usable_cores;
static pthread_once_t usable_cores_once = PTHREAD_ONCE_INIT;
static void read_usable_cores(void) { usable_cores = gi_cores_usable(); }

/* Threads for an image of `chunks` chunks: the usable cores (at most 8),
 * none beyond one per 4 chunks. */
static int zip_threads(int chunks)
{
    pthread_once(&usable_cores_once, read_usable_cores);
    long t = usable_cores;
    if (t > 8)
        t = 8;
    if (t > chunks / 4)
        t = chunks / 4;
    return t > 1 ? (int)t : 1;
}

static int exr_write_chunks(exr_context_t ctx, const gi_image *img, const char *path,
                            const exr_io *io, gi_error *err)
{
    const int part = 0;
    int32_t lines = 0;
    exr_result_t r = exr_get_scanlines_per_chunk(ctx, part, &lines);
    if (r != EXR_ERR_SUCCESS || lines < 1)
        return exr_fail(err, path, "scanlines per chunk", r ? r : EXR_ERR_UNKNOWN, io, 0);
    /* The file lists channels sorted by name; the image may hold them in
     * any order. */
    const exr_attr_chlist_t *chl = NULL;
    r = exr_get_channels(ctx, part, &chl);
    if (r != EXR_ERR_SUCCESS || !chl || chl->num_channels != img->channels)
        return exr_fail(err, path, "channel list", r ? r : EXR_ERR_UNKNOWN, io, 0);
    int order[GI_IMAGE_MAX_CHANNELS];
    for (int k = 0; k < img->channels; k++)
        if ((order[k] = gi_image_channel(img, chl->entries[k].name.str)) < 0)
            return gi_fail(err, GI_EINTERNAL, "%s: EXR encoder: unexpected channel %s", path,
                           chl->entries[k].name.str);
    zip_job j = {img, order, lines, (img->height + lines - 1) / lines, NULL, NULL, 0, 0,
                 PTHREAD_MUTEX_INITIALIZER};
    j.out = calloc((size_t)j.chunks, sizeof *j.out);
    j.out_bytes = calloc((size_t)j.chunks, sizeof *j.out_bytes);
    int rc = 0;
    if (!j.out || !j.out_bytes) {
        rc = gi_fail(err, GI_ENOMEM, "%s: EXR write: out of memory", path);
    } else {
        pthread_t th[8];
        int n = zip_threads(j.chunks), started = 0;
        for (int t = 1; t < n; t++)
            started += pthread_create(&th[started], NULL, zip_worker, &j) == 0;
        zip_worker(&j);
        for (int t = 0; t < started; t++)
            pthread_join(th[t], NULL);
        if (j.failed)
            rc = gi_fail(err, GI_ENOMEM, "%s: EXR write: out of memory", path);
    }
    for (int c = 0; c < j.chunks && rc == 0; c++) {
        r = exr_write_scanline_chunk(ctx, part, c * lines, j.out[c], j.out_bytes[c]);
        if (r != EXR_ERR_SUCCESS)
            rc = exr_fail(err, path, "writing rows", r, io, 0);
    }
    for (int c = 0; j.out && c < j.chunks; c++)
        free(j.out[c]);
    free(j.out);
    free(j.out_bytes);
    return rc;
}

/* Header + chunks + offset table into io->fd (opened on `tmp`). */
static int exr_write_fd(const char *path, const char *tmp, const gi_image *img, exr_io *io,
                        gi_error *err)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_on_error;
    init.user_data = io;
    init.write_fn = exr_io_write;

    /* The library only names this file in messages (we do the I/O), but it
     * is the temporary one: nothing may ever touch `path` before the rename. */
    exr_context_t ctx = NULL;
    exr_result_t r = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    if (r != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return exr_fail(err, path, "start", r, io, 0);
    }
    int part = -1, rc = 0;
    const char *step = "add part";
    r = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (r == EXR_ERR_SUCCESS) {
        step = "header attributes";
        r = exr_initialize_required_attr_simple(ctx, part, img->width, img->height,
                                                EXR_COMPRESSION_ZIP);
    }
    for (int c = 0; c < img->channels && r == EXR_ERR_SUCCESS; c++) {
        step = "add channel";
        r = exr_add_channel(ctx, part, img->names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR,
                            1, 1);
    }
    if (r == EXR_ERR_SUCCESS) {
        step = "write header";
        r = exr_write_header(ctx);
    }
    if (r != EXR_ERR_SUCCESS)
        rc = exr_fail(err, path, step, r, io, 0);
    if (rc == 0)
        rc = exr_write_chunks(ctx, img, path, io, err);
    /* exr_finish writes the chunk offset table; always call it to free ctx. */
    r = exr_finish(&ctx);
    if (rc == 0 && r != EXR_ERR_SUCCESS)
        rc = exr_fail(err, path, "finish", r, io, 0);
    return rc;
}

int gi_exr_write(const char *path, const gi_image *img, gi_error *err)
{
    if (!img || !img->pixels || img->width < 1 || img->height < 1 || img->channels < 1 ||
        img->channels > GI_IMAGE_MAX_CHANNELS || img->width > GI_IMAGE_MAX_SIDE ||
        img->height > GI_IMAGE_MAX_SIDE)
        return gi_fail(err, GI_EINVAL, "%s: EXR write: empty or invalid image", path);
    for (int c = 0; c < img->channels; c++) {
        if (!img->names[c][0] || !memchr(img->names[c], '\0', sizeof img->names[c]))
            return gi_fail(err, GI_EINVAL, "%s: EXR write: channel %d has no valid name", path, c);
        for (int d = 0; d < c; d++)
            if (strcmp(img->names[c], img->names[d]) == 0)
                return gi_fail(err, GI_EINVAL, "%s: EXR write: channel name \"%s\" appears twice",
                               path, img->names[c]);
    }

    char *tmp = gi_temp_path(path);
    exr_io io = {.fd = -1};
    io.fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (io.fd < 0) {
        int e = errno;
        free(tmp);
        return gi_fail(err, GI_EIO, "%s: cannot create temporary file: %s", path, strerror(e));
    }
    current_io = &io;
    int rc = exr_write_fd(path, tmp, img, &io, err);
    current_io = NULL;
    if (close(io.fd) != 0 && rc == 0)
        rc = gi_fail(err, GI_EIO, "%s: close: %s", path, strerror(errno));
    rc = gi_temp_finish(tmp, path, rc, err);
    free(tmp);
    return rc;
}

/* ---- reading ---------------------------------------------------------- */

/* Checks that the file is something we read, and fills `out` with its shape
 * and channel names (zeroed pixels). */
static int exr_read_layout(exr_context_t ctx, const char *path, const exr_io *io,
                           exr_attr_box2i_t *dw, gi_image *out, gi_error *err)
{
    int count = 0;
    exr_result_t r = exr_get_count(ctx, &count);
    if (r != EXR_ERR_SUCCESS)
        return exr_fail(err, path, "part count", r, io, 1);
    if (count != 1)
        return gi_fail(err, GI_EINVAL, "%s: multi-part EXR (%d parts) is not supported", path,
                       count);
    exr_storage_t storage;
    r = exr_get_storage(ctx, 0, &storage);
    if (r != EXR_ERR_SUCCESS)
        return exr_fail(err, path, "storage type", r, io, 1);
    if (storage != EXR_STORAGE_SCANLINE)
        return gi_fail(err, GI_EINVAL, "%s: %s EXR is not supported (only scanline images)",
                       path,
                       storage == EXR_STORAGE_TILED           ? "tiled"
                       : storage == EXR_STORAGE_DEEP_SCANLINE ? "deep scanline"
                       : storage == EXR_STORAGE_DEEP_TILED    ? "deep tiled"
                                                              : "unknown-storage");
    r = exr_get_data_window(ctx, 0, dw);
    if (r != EXR_ERR_SUCCESS)
        return exr_fail(err, path, "data window", r, io, 1);
    int64_t w = (int64_t)dw->max.x - dw->min.x + 1, h = (int64_t)dw->max.y - dw->min.y + 1;
    if (w < 1 || h < 1 || w > GI_IMAGE_MAX_SIDE || h > GI_IMAGE_MAX_SIDE)
        return gi_fail(err, GI_EINVAL,
                       "%s: data window (%d,%d)-(%d,%d) is %lldx%lld, outside 1..%d per side",
                       path, dw->min.x, dw->min.y, dw->max.x, dw->max.y, (long long)w,
                       (long long)h, GI_IMAGE_MAX_SIDE);

    const exr_attr_chlist_t *chl = NULL;
    r = exr_get_channels(ctx, 0, &chl);
    if (r != EXR_ERR_SUCCESS || !chl)
        return exr_fail(err, path, "channel list", r ? r : EXR_ERR_MISSING_REQ_ATTR, io, 1);
    if (chl->num_channels < 1 || chl->num_channels > GI_IMAGE_MAX_CHANNELS)
        return gi_fail(err, GI_EINVAL, "%s: %d channels is outside 1..%d", path,
                       chl->num_channels, GI_IMAGE_MAX_CHANNELS);
    const char *names[GI_IMAGE_MAX_CHANNELS];
    for (int i = 0; i < chl->num_channels; i++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[i];
        const char *n = e->name.str ? e->name.str : "";
        if (e->name.length < 1 || e->name.length > GI_IMAGE_NAME_MAX)
            return gi_fail(err, GI_EINVAL,
                           "%s: channel %d name \"%.40s\" is empty or over %d bytes", path, i,
                           n, GI_IMAGE_NAME_MAX);
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT)
            return gi_fail(err, GI_EINVAL,
                           "%s: channel %s has pixel type %s (only HALF and FLOAT are read)", path,
                           n, e->pixel_type == EXR_PIXEL_UINT ? "UINT" : "unknown");
        if (e->x_sampling != 1 || e->y_sampling != 1)
            return gi_fail(err, GI_EINVAL, "%s: channel %s is subsampled (%dx%d), not supported",
                           path, n, e->x_sampling, e->y_sampling);
        names[i] = n;
    }
    if (gi_image_init(out, (int)w, (int)h, chl->num_channels, names, err) != 0)
        return gi_error_prefix(err, "%s", path);
    return 0;
}

static int exr_read_chunks(exr_context_t ctx, const char *path, const exr_io *io,
                           const exr_attr_box2i_t *dw, gi_image *out, gi_error *err)
{
    const size_t C = (size_t)out->channels;
    int32_t lines = 0;
    exr_result_t r = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (r != EXR_ERR_SUCCESS || lines < 1)
        return exr_fail(err, path, "scanlines per chunk", r ? r : EXR_ERR_INVALID_ATTR, io, 1);

    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int have_dec = 0, rc = 0;
    /* 64-bit y: the data window may end near INT32_MAX. */
    for (int64_t y = dw->min.y; y <= dw->max.y; y += lines) {
        exr_chunk_info_t ci;
        r = exr_read_scanline_chunk_info(ctx, 0, (int)y, &ci);
        if (r != EXR_ERR_SUCCESS) {
            rc = exr_fail(err, path, "chunk table", r, io, 1);
            break;
        }
        int64_t row = (int64_t)ci.start_y - dw->min.y;
        if (row < 0 || ci.height < 1 || row + ci.height > out->height || ci.width != out->width) {
            rc = gi_fail(err, GI_EINVAL, "%s: chunk for y=%lld has rows %d+%d, width %d", path,
                         (long long)y, ci.start_y, ci.height, ci.width);
            break;
        }
        r = have_dec ? exr_decoding_update(ctx, 0, &ci, &dec)
                     : exr_decoding_initialize(ctx, 0, &ci, &dec);
        if (r != EXR_ERR_SUCCESS) {
            rc = exr_fail(err, path, "decoder setup", r, io, 1);
            break;
        }
        have_dec = 1;
        for (int i = 0; i < dec.channel_count; i++) {
            exr_coding_channel_info_t *ch = &dec.channels[i];
            int k = gi_image_channel(out, ch->channel_name);
            if (k < 0 || ch->height != ci.height || ch->width != out->width) {
                rc = gi_fail(err, GI_EINVAL, "%s: decoder channel %s does not match the header",
                             path, ch->channel_name);
                break;
            }
            ch->decode_to_ptr = (uint8_t *)(out->pixels + (size_t)row * (size_t)out->width * C +
                                            (size_t)k);
            ch->user_pixel_stride = (int32_t)(C * sizeof(float));
            ch->user_line_stride = (int32_t)((size_t)out->width * C * sizeof(float));
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
        }
        if (rc)
            break;
        /* The routines depend on the channel types and our strides, which do
         * not change between chunks, so they are chosen once. */
        if (y == dw->min.y) {
            r = exr_decoding_choose_default_routines(ctx, 0, &dec);
            if (r != EXR_ERR_SUCCESS) {
                rc = exr_fail(err, path, "decoder setup", r, io, 1);
                break;
            }
        }
        r = exr_decoding_run(ctx, 0, &dec);
        if (r != EXR_ERR_SUCCESS) {
            rc = gi_fail(err, r == EXR_ERR_OUT_OF_MEMORY ? GI_ENOMEM : GI_EINVAL,
                         "%s: EXR rows %d..%d: %s (%s)", path, ci.start_y,
                         ci.start_y + ci.height - 1,
                         io->msg[0] ? io->msg : exr_get_default_error_message(r),
                         exr_get_error_code_as_string(r));
            break;
        }
    }
    if (have_dec)
        exr_decoding_destroy(ctx, &dec);
    return rc;
}

int gi_exr_read(const char *path, gi_image *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    exr_io io = {.fd = -1};
    struct stat st;
    io.fd = gi_open_regular(path, O_RDONLY, &st, err);
    if (io.fd < 0)
        return -1;
    io.size = (int64_t)st.st_size;

    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_on_error;
    init.user_data = &io;
    init.read_fn = exr_io_read;
    init.size_fn = exr_io_size;
    init.max_image_width = GI_IMAGE_MAX_SIDE;
    init.max_image_height = GI_IMAGE_MAX_SIDE;

    exr_context_t ctx = NULL;
    int rc = 0;
    current_io = &io;
    exr_result_t r = exr_start_read(&ctx, path, &init);
    if (r != EXR_ERR_SUCCESS) {
        rc = exr_fail(err, path, "header read", r, &io, 1);
    } else {
        exr_attr_box2i_t dw;
        rc = exr_read_layout(ctx, path, &io, &dw, out, err);
        if (rc == 0)
            rc = exr_read_chunks(ctx, path, &io, &dw, out, err);
    }
    exr_finish(&ctx);
    current_io = NULL;
    close(io.fd);
    if (rc != 0)
        gi_image_free(out);
    return rc;
}
