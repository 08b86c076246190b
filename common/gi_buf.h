/* gi_buf: a growable byte buffer, and explicit little-endian serialization.
 *
 * Everything that crosses a process boundary (tasks, results, frames,
 * checkpoints) is written field by field with gi_buf_put_* and read back
 * with a gi_reader, whose getters check every length against what is left
 * and latch the first error, so decoders read naturally and check once. */
#ifndef GI_BUF_H
#define GI_BUF_H

#include <stddef.h>
#include <stdint.h>

#include "gi_error.h"

typedef struct gi_buf {
    uint8_t *data;
    size_t len;
    size_t cap;
} gi_buf;

void gi_buf_init(gi_buf *b);
void gi_buf_free(gi_buf *b);
void gi_buf_reset(gi_buf *b);                 /* len = 0, keeps memory */
void gi_buf_reserve(gi_buf *b, size_t extra); /* aborts on OOM */
void gi_buf_move(gi_buf *dst, gi_buf *src);   /* dst takes src's bytes */
uint8_t *gi_buf_grow(gi_buf *b, size_t n);    /* appends n bytes, returns them */

void gi_buf_put(gi_buf *b, const void *p, size_t n);
/* Appends printf output (any length; no terminating NUL). */
void gi_buf_printf(gi_buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void gi_buf_put_u8(gi_buf *b, uint8_t v);
void gi_buf_put_u16(gi_buf *b, uint16_t v);
void gi_buf_put_u32(gi_buf *b, uint32_t v);
void gi_buf_put_u64(gi_buf *b, uint64_t v);
void gi_buf_put_i64(gi_buf *b, int64_t v);
void gi_buf_put_f32(gi_buf *b, float v);
void gi_buf_put_f64(gi_buf *b, double v);
void gi_buf_put_str(gi_buf *b, const char *s); /* u32 length + bytes */
void gi_buf_put_blob(gi_buf *b, const void *p, size_t n); /* u64 length + bytes */
void gi_buf_put_f32s(gi_buf *b, const float *v, size_t n);  /* no length prefix */
void gi_buf_put_f64s(gi_buf *b, const double *v, size_t n); /* no length prefix */

/* Little-endian helpers for fixed layouts (frame headers). */
void gi_le_put_u16(uint8_t *p, uint16_t v);
void gi_le_put_u32(uint8_t *p, uint32_t v);
void gi_le_put_u64(uint8_t *p, uint64_t v);
uint16_t gi_le_get_u16(const uint8_t *p);
uint32_t gi_le_get_u32(const uint8_t *p);
uint64_t gi_le_get_u64(const uint8_t *p);

typedef struct gi_reader {
    const uint8_t *p;
    size_t left;
    int failed;        /* set by the first short read; later reads return 0 */
    const char *what;  /* what is being decoded, for the error message */
} gi_reader;

void gi_reader_init(gi_reader *r, const void *data, size_t len, const char *what);
int gi_get(gi_reader *r, void *out, size_t n);
uint8_t gi_get_u8(gi_reader *r);
uint16_t gi_get_u16(gi_reader *r);
uint32_t gi_get_u32(gi_reader *r);
uint64_t gi_get_u64(gi_reader *r);
int64_t gi_get_i64(gi_reader *r);
float gi_get_f32(gi_reader *r);
double gi_get_f64(gi_reader *r);
/* Returns a malloc'ed NUL-terminated copy, or NULL (and fails r) if the
 * length exceeds max_len or what is left, or the bytes hold a NUL. */
char *gi_get_str(gi_reader *r, size_t max_len);
/* Points into the reader's data (no copy); fails if longer than max_len. */
const uint8_t *gi_get_blob(gi_reader *r, size_t max_len, size_t *len);
int gi_get_f32s(gi_reader *r, float *out, size_t n);
int gi_get_f64s(gi_reader *r, double *out, size_t n);
/* 0 if everything was read and nothing is left over; else fills err. */
int gi_reader_finish(gi_reader *r, gi_error *err);

#endif
