/* detp_result: the encoding of a photon batch's result (see detp_method.h).
 * Small batches on large meshes leave most vertices untouched: the sparse
 * form then sends only the vertices that got something. */
#include <math.h>
#include <string.h>

#include "detp_method.h"

#define BATCH_MAGIC 0x42505444u /* "DTPB" */
enum { FORM_DENSE = 0, FORM_SPARSE = 1 };

/* Varints go a whole value at a time (a frame's result holds tens of
 * thousands of them): the bytes gathered, then one append or one read. */
static void put_varint(gi_buf *b, uint64_t v)
{
    uint8_t tmp[10];
    size_t n = 0;
    while (v >= 0x80) {
        tmp[n++] = (uint8_t)(v | 0x80);
        v >>= 7;
    }
    tmp[n++] = (uint8_t)v;
    gi_buf_put(b, tmp, n);
}

static uint64_t get_varint_slow(gi_reader *r)
{
    uint64_t v = 0;
    for (size_t k = 0; k < 10 && k < r->left && !r->failed; k++) {
        uint8_t b = r->p[k];
        v |= (uint64_t)(b & 0x7F) << (7 * k);
        if (!(b & 0x80)) {
            r->p += k + 1;
            r->left -= k + 1;
            return v;
        }
    }
    r->failed = 1; /* cut short, or more than 10 bytes: not a varint we wrote */
    return 0;
}

/* Most values of a result fit a byte or two, and all but the last few
 * varints have 10 bytes after them: those go without a check per byte. */
static inline uint64_t get_varint(gi_reader *r)
{
    if (r->left < 10 || r->failed)
        return get_varint_slow(r);
    const uint8_t *p = r->p;
    if (p[0] < 0x80) {
        r->p++;
        r->left--;
        return p[0];
    }
    uint64_t v = p[0] & 0x7F;
    for (size_t k = 1; k < 10; k++) {
        v |= (uint64_t)(p[k] & 0x7F) << (7 * k);
        if (p[k] < 0x80) {
            r->p += k + 1;
            r->left -= k + 1;
            return v;
        }
    }
    r->failed = 1;
    return 0;
}

static size_t varint_len(uint64_t v)
{
    size_t n = 1;
    while (v >= 0x80) {
        v >>= 7;
        n++;
    }
    return n;
}

void detp_encode_batch(const detp_batch_result *h, const gi_detp_accum *acc, double scale,
                       gi_buf *out)
{
    gi_buf_put_u32(out, BATCH_MAGIC);
    gi_buf_put_u64(out, h->photons);
    gi_buf_put_u64(out, h->segments);
    gi_buf_put_u64(out, h->rays);
    gi_buf_put_f64(out, h->trace_seconds);
    gi_buf_put_f64(out, h->build_seconds);
    gi_buf_put_f64(out, h->estimate_seconds);
    gi_detp_stats_encode(&h->stats, out);
    gi_buf_put_u32(out, acc->count);
    /* Sizes of the two forms, to pick the smaller. */
    size_t dense = (size_t)acc->count * 16, sparse = 4;
    uint32_t nnz = 0, last = 0;
    for (uint32_t i = 0; i < acc->count; i++) {
        const double *e = &acc->energy[3 * (size_t)i];
        if (acc->hits[i] == 0 && e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0)
            continue;
        sparse += varint_len(i - last) + 12 + varint_len(acc->hits[i]);
        last = i;
        nnz++;
    }
    if (sparse < dense) {
        gi_buf_put_u8(out, FORM_SPARSE);
        gi_buf_put_u32(out, nnz);
        last = 0;
        for (uint32_t i = 0; i < acc->count; i++) {
            const double *e = &acc->energy[3 * (size_t)i];
            if (acc->hits[i] == 0 && e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0)
                continue;
            put_varint(out, i - last);
            last = i;
            for (int c = 0; c < 3; c++)
                gi_buf_put_f32(out, (float)(e[c] * scale));
            put_varint(out, acc->hits[i]);
        }
    } else {
        gi_buf_put_u8(out, FORM_DENSE);
        for (uint32_t i = 0; i < acc->count; i++) {
            for (int c = 0; c < 3; c++)
                gi_buf_put_f32(out, (float)(acc->energy[3 * (size_t)i + c] * scale));
            gi_buf_put_u32(out, acc->hits[i]);
        }
    }
}

/* Adds one vertex's values (three floats, then its hit count); irr NULL:
 * only checks them. -1: cut short; 1: an energy is not finite or beyond
 * max in magnitude (*bad: that energy). */
static int add_vertex(gi_reader *r, uint64_t i, int sparse, double max, double *irr,
                      uint64_t *hits, double *bad)
{
    float e[3] = {gi_get_f32(r), gi_get_f32(r), gi_get_f32(r)};
    uint64_t h = sparse ? get_varint(r) : gi_get_u32(r);
    if (r->failed)
        return -1;
    for (int c = 0; c < 3; c++)
        if (!(fabsf(e[c]) <= max)) { /* NaN too */
            *bad = e[c];
            return 1;
        }
    if (!irr)
        return 0;
    for (int c = 0; c < 3; c++)
        irr[3 * i + c] += e[c];
    hits[i] += h;
    return 0;
}

/* The fixed part, up to the vertex count and the form; -1: not a batch's. */
static int batch_header_get(gi_reader *r, detp_batch_result *h, uint32_t *count, uint8_t *form)
{
    memset(h, 0, sizeof *h);
    if (gi_get_u32(r) != BATCH_MAGIC)
        return -1;
    h->photons = gi_get_u64(r);
    h->segments = gi_get_u64(r);
    h->rays = gi_get_u64(r);
    h->trace_seconds = gi_get_f64(r);
    h->build_seconds = gi_get_f64(r);
    h->estimate_seconds = gi_get_f64(r);
    gi_detp_stats_decode(r, &h->stats);
    *count = gi_get_u32(r);
    *form = gi_get_u8(r);
    return 0;
}

int detp_decode_batch(gi_reader *r, uint32_t nv, double max, detp_batch_result *h,
                      double *irr, uint64_t *hits, gi_error *err)
{
    uint32_t count;
    uint8_t form;
    if (batch_header_get(r, h, &count, &form))
        return gi_fail(err, GI_EPROTO, "%s: not a detp batch result", r->what);
    if (r->failed || count != nv || form > FORM_SPARSE)
        return gi_fail(err, GI_EPROTO, "%s: %u vertices (expected %u), form %u", r->what, count,
                       nv, form);
    uint32_t entries = nv;
    if (form == FORM_SPARSE && (entries = gi_get_u32(r)) > nv)
        return gi_fail(err, GI_EPROTO, "%s: %u entries for %u vertices", r->what, entries, nv);
    uint64_t i = 0;
    double value = 0;
    for (uint32_t k = 0; k < entries; k++) {
        if (form == FORM_SPARSE)
            i += get_varint(r);
        else
            i = k;
        int bad = i < nv ? add_vertex(r, i, form == FORM_SPARSE, max, irr, hits, &value) : -1;
        if (bad > 0 && !isfinite(value))
            return gi_fail(err, GI_EPROTO, "%s: vertex %llu's energy is not finite", r->what,
                           (unsigned long long)i);
        if (bad > 0)
            return gi_fail(err, GI_EPROTO, "%s: vertex %llu's energy is %g, beyond +-%g",
                           r->what, (unsigned long long)i, value, max);
        if (bad && form == FORM_DENSE)
            return gi_fail(err, GI_EPROTO, "%s: bad entry for vertex %u", r->what, k);
        if (bad)
            return gi_fail(err, GI_EPROTO, "%s: bad entry %u", r->what, k);
    }
    return gi_reader_finish(r, err);
}

int detp_batch_damage(gi_buf *result, float value)
{
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp result");
    detp_batch_result h;
    uint32_t count;
    uint8_t form;
    if (batch_header_get(&r, &h, &count, &form) || (form == FORM_SPARSE && gi_get_u32(&r) == 0))
        return 1;
    if (form == FORM_SPARSE)
        get_varint(&r);
    if (r.failed || r.left < 4)
        return 1;
    memcpy((uint8_t *)r.p, &value, 4);
    return 0;
}

/* ---- Animation frames: exact integer sums ---------------------------- */

#define ANIM_MAGIC 0x41505444u /* "DTPA" */

static uint64_t zigzag(int64_t v) { return ((uint64_t)v << 1) ^ (uint64_t)(v >> 63); }
static int64_t unzigzag(uint64_t u) { return (int64_t)(u >> 1) ^ -(int64_t)(u & 1); }

void detp_anim_header_put(const detp_anim_result *h, gi_buf *out)
{
    gi_buf_put_u32(out, ANIM_MAGIC);
    gi_buf_put_u32(out, h->frame);
    gi_buf_put_u32(out, h->batch);
    gi_buf_put_u64(out, h->photons);
    gi_buf_put_u64(out, h->paths_examined);
    gi_buf_put_u64(out, h->segments);
    gi_buf_put_u64(out, h->segments_old);
    gi_buf_put_u64(out, h->segments_new);
    gi_buf_put_u64(out, h->paths_retraced);
    gi_buf_put_u64(out, h->segments_repaired);
    gi_buf_put_u64(out, h->bv_passes);
    gi_buf_put_u64(out, h->rays);
    gi_buf_put_u64(out, h->regenerated_frames);
    gi_buf_put_u64(out, h->segments_from_mobile);
    gi_buf_put_f64(out, h->sec_build);
    gi_buf_put_f64(out, h->sec_load);
    gi_buf_put_f64(out, h->sec_regenerate);
    gi_buf_put_f64(out, h->sec_trace);
    gi_buf_put_f64(out, h->sec_static);
    gi_buf_put_f64(out, h->sec_mobile);
    gi_buf_put_f64(out, h->sec_store);
    gi_detp_stats_encode(&h->stats, out);
}

int detp_anim_header_get(gi_reader *r, detp_anim_result *h, int with_from_mobile)
{
    memset(h, 0, sizeof *h);
    if (gi_get_u32(r) != ANIM_MAGIC)
        return -1;
    h->frame = gi_get_u32(r);
    h->batch = gi_get_u32(r);
    h->photons = gi_get_u64(r);
    h->paths_examined = gi_get_u64(r);
    h->segments = gi_get_u64(r);
    h->segments_old = gi_get_u64(r);
    h->segments_new = gi_get_u64(r);
    h->paths_retraced = gi_get_u64(r);
    h->segments_repaired = gi_get_u64(r);
    h->bv_passes = gi_get_u64(r);
    h->rays = gi_get_u64(r);
    h->regenerated_frames = gi_get_u64(r);
    if (with_from_mobile)
        h->segments_from_mobile = gi_get_u64(r);
    h->sec_build = gi_get_f64(r);
    h->sec_load = gi_get_f64(r);
    h->sec_regenerate = gi_get_f64(r);
    h->sec_trace = gi_get_f64(r);
    h->sec_static = gi_get_f64(r);
    h->sec_mobile = gi_get_f64(r);
    h->sec_store = gi_get_f64(r);
    gi_detp_stats_decode(r, &h->stats);
    return r->failed ? -1 : 0;
}

void detp_encode_anim(const detp_anim_result *h, const int64_t *sum, const int64_t *hits,
                      uint32_t nv, gi_buf *out)
{
    detp_anim_header_put(h, out);
    gi_buf_put_u32(out, nv);
    uint32_t nnz = 0;
    for (uint32_t i = 0; i < nv; i++)
        nnz += hits[i] != 0 || sum[3 * (size_t)i] != 0 || sum[3 * (size_t)i + 1] != 0 ||
               sum[3 * (size_t)i + 2] != 0;
    gi_buf_put_u32(out, nnz);
    uint32_t last = 0;
    for (uint32_t i = 0; i < nv; i++) {
        const int64_t *e = &sum[3 * (size_t)i];
        if (hits[i] == 0 && e[0] == 0 && e[1] == 0 && e[2] == 0)
            continue;
        put_varint(out, i - last);
        last = i;
        for (int c = 0; c < 3; c++)
            put_varint(out, zigzag(e[c]));
        put_varint(out, zigzag(hits[i]));
    }
}

/* |v|, which for INT64_MIN only a uint64_t holds. */
static uint64_t magnitude(int64_t v) { return v < 0 ? -(uint64_t)v : (uint64_t)v; }

int detp_anim_decode(gi_reader *r, uint32_t nv, int64_t max, detp_anim_result *h,
                     const int64_t *sum, const int64_t *hits, uint64_t bound, gi_buf *entries,
                     gi_error *err)
{
    /* A value this small cannot take a total within the bound out of range. */
    uint64_t safe = bound < (uint64_t)INT64_MAX ? (uint64_t)INT64_MAX - bound : 0;
    static const char *const what[4] = {"red sum", "green sum", "blue sum", "hit count"};
    if (detp_anim_header_get(r, h, 1))
        return gi_fail(err, GI_EPROTO, "%s: not a detp animation result", r->what);
    uint32_t count = gi_get_u32(r), nnz = gi_get_u32(r);
    if (r->failed || count != nv || nnz > nv)
        return gi_fail(err, GI_EPROTO, "%s: %u vertices (expected %u), %u entries", r->what,
                       count, nv, nnz);
    detp_anim_entry *out = NULL;
    if (entries) {
        /* An entry takes 5 bytes at least: a short result cannot make the
         * coordinator reserve for nv. */
        size_t most = r->left / 5 < nnz ? r->left / 5 : nnz;
        gi_buf_reserve(entries, most * sizeof *out);
    }
    uint64_t i = 0;
    for (uint32_t k = 0; k < nnz; k++) {
        uint64_t step = get_varint(r);
        i += step;
        int c = 0;
        int64_t v[4];
        if (!r->failed && i < nv && (k == 0 || step > 0)) {
            for (; c < 4; c++) {
                v[c] = unzigzag(get_varint(r));
                if (r->failed)
                    break;
                if (v[c] > max || v[c] < -max)
                    return gi_fail(err, GI_EPROTO, "%s: vertex %llu's %s is %lld, beyond +-%lld",
                                   r->what, (unsigned long long)i, what[c], (long long)v[c],
                                   (long long)max);
                if (!sum || magnitude(v[c]) <= safe)
                    continue; /* (the totals, cold in cache, are not read) */
                int64_t total = c < 3 ? sum[3 * i + c] : hits[i], out_of_range;
                if (__builtin_add_overflow(total, v[c], &out_of_range))
                    return gi_fail(err, GI_EPROTO,
                                   "%s: vertex %llu's %s overflows: %lld + %lld is out of range",
                                   r->what, (unsigned long long)i, what[c], (long long)total,
                                   (long long)v[c]);
            }
        }
        if (c < 4)
            return gi_fail(err, GI_EPROTO, "%s: bad entry %u", r->what, k);
        if (entries) {
            out = (detp_anim_entry *)gi_buf_grow(entries, sizeof *out);
            out->vertex = i;
            memcpy(out->v, v, sizeof v);
        }
    }
    return gi_reader_finish(r, err);
}

int detp_anim_damage(gi_buf *result)
{
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp animation result");
    detp_anim_result h;
    if (detp_anim_header_get(&r, &h, 1) || (gi_get_u32(&r), gi_get_u32(&r) == 0))
        return 1;
    get_varint(&r); /* the first entry's vertex */
    size_t at = result->len - r.left;
    get_varint(&r); /* its red sum, replaced */
    if (r.failed)
        return 1;
    gi_buf out;
    gi_buf_init(&out);
    gi_buf_put(&out, result->data, at);
    put_varint(&out, zigzag(INT64_MAX));
    gi_buf_put(&out, r.p, r.left);
    gi_buf_free(result);
    *result = out;
    return 0;
}

int detp_anim_add(const detp_anim_entry *e, size_t n, int64_t *sum, int64_t *hits,
                  uint64_t *bound, const char *what, gi_error *err)
{
    uint64_t most = 0;
    static const char *const names[4] = {"red sum", "green sum", "blue sum", "hit count"};
    for (size_t k = 0; k < n; k++) {
        int64_t *t[4] = {&sum[3 * e[k].vertex], &sum[3 * e[k].vertex + 1],
                         &sum[3 * e[k].vertex + 2], &hits[e[k].vertex]};
        for (int c = 0; c < 4; c++) {
            int64_t out;
            if (!__builtin_add_overflow(*t[c], e[k].v[c], &out)) {
                *t[c] = out;
                most = magnitude(out) > most ? magnitude(out) : most;
                continue;
            }
            gi_fail(err, GI_EPROTO, "%s: vertex %llu's %s overflows: %lld + %lld is out of range",
                    what, (unsigned long long)e[k].vertex, names[c], (long long)*t[c],
                    (long long)e[k].v[c]);
            /* Taken back: this entry's channels before c, the entries before it. */
            while (c-- > 0)
                *t[c] -= e[k].v[c];
            while (k-- > 0) {
                sum[3 * e[k].vertex] -= e[k].v[0];
                sum[3 * e[k].vertex + 1] -= e[k].v[1];
                sum[3 * e[k].vertex + 2] -= e[k].v[2];
                hits[e[k].vertex] -= e[k].v[3];
            }
            return -1;
        }
    }
    if (bound && most > *bound)
        *bound = most;
    return 0;
}

uint64_t detp_anim_bound(const int64_t *sum, const int64_t *hits, uint32_t nv)
{
    uint64_t most = 0;
    for (size_t i = 0; i < (size_t)nv * 3; i++)
        most = magnitude(sum[i]) > most ? magnitude(sum[i]) : most;
    for (uint32_t i = 0; i < nv; i++)
        most = magnitude(hits[i]) > most ? magnitude(hits[i]) : most;
    return most;
}

int detp_decode_anim(gi_reader *r, uint32_t nv, int64_t max, detp_anim_result *h, int64_t *sum,
                     int64_t *hits, int apply, gi_error *err)
{
    if (!apply || !sum)
        return detp_anim_decode(r, nv, max, h, sum, hits, INT64_MAX, NULL, err);
    gi_buf e;
    gi_buf_init(&e);
    const char *what = r->what;
    int rc = detp_anim_decode(r, nv, max, h, sum, hits, INT64_MAX, &e, err);
    if (rc == 0)
        rc = detp_anim_add((const detp_anim_entry *)e.data, e.len / sizeof(detp_anim_entry),
                           sum, hits, NULL, what, err);
    gi_buf_free(&e);
    return rc;
}
