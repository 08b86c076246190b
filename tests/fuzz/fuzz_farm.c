/* fuzz_farm: libFuzzer target for what gi-farmd and gi read from outside
 * besides frames: the journal (a file that a crash may have torn), job
 * submission bodies (POST /api/v1/jobs), HTTP response heads and chunked
 * bodies (what `gi` reads from a farm), a job's affinity and published
 * files (read back when gi-farmd restarts), and the owner record of a `gi
 * render` batch root (read by the next `gi render`). The first byte picks
 * the parser. Whatever parses must survive a round trip: journal records
 * encode back to the same bytes, where the parser says they were (in order;
 * damaged ones skipped); a submission rebuilt by `gi submit`'s builder
 * parses to the same job text, priority and asset map; the affinity owners
 * read, written again, read back the same; the published entries written
 * again are the lines read, less the skipped ones; an owner record writes
 * back to its own bytes, and one that does not parse is refused with a
 * one-line GI_EINVAL message; the workers' standing file (read back when
 * gi-farmd restarts) gives entries that, written again, read back the
 * same. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_affinity.h"
#include "gi_batch_root.h"
#include "gi_farm_published.h"
#include "gi_farm_submit.h"
#include "gi_http_client.h"
#include "gi_journal.h"
#include "gi_log.h"
#include "gi_standing.h"

typedef struct replay {
    const uint8_t *data;
    size_t pos; /* the end of the last record */
} replay;

/* Each record must encode back to exactly the bytes it was parsed from. */
static int check_record(void *ctx, const gi_jrec *r, gi_error *err)
{
    replay *p = ctx;
    gi_buf b;
    gi_buf_init(&b);
    gi_jrec_encode(r, &b);
    if (r->at < p->pos || memcmp(b.data, p->data + r->at, b.len) != 0)
        abort();
    p->pos = r->at + b.len;
    gi_buf_free(&b);
    return 0;
}

static void journal(const uint8_t *data, size_t size)
{
    replay p = {data, 8};
    size_t valid, skipped;
    gi_error err;
    int rc = gi_journal_parse(data, size, check_record, &p, &valid, &skipped, &err);
    if (rc >= 0 && (valid > size || (rc == 0 && valid != size) || p.pos != valid))
        abort();
}

static void submission(const uint8_t *data, size_t size)
{
    gi_farm_submission s, t;
    gi_error err;
    if (gi_farm_submission_parse((const char *)data, size, &s, &err) != 0)
        return;
    gi_buf b;
    gi_buf_init(&b);
    gi_farm_submission_build(&b, s.file, s.text, &s.manifest, s.priority);
    if (gi_farm_submission_parse((const char *)b.data, b.len, &t, &err) != 0)
        abort();
    if (strcmp(s.text, t.text) != 0 || strcmp(s.file, t.file) != 0 || s.priority != t.priority ||
        s.manifest.count != t.manifest.count)
        abort();
    for (size_t i = 0; i < s.manifest.count; i++) {
        const gi_manifest_entry *e = gi_manifest_find(&t.manifest, s.manifest.entries[i].name);
        if (!e || strcmp(e->hash, s.manifest.entries[i].hash) != 0)
            abort();
    }
    gi_farm_submission_free(&s);
    gi_farm_submission_free(&t);
    gi_buf_free(&b);
}

static void http(const uint8_t *data, size_t size)
{
    gi_http_head h;
    size_t n = 0;
    gi_error err;
    int rc = gi_http_parse_head((const char *)data, size, &h, &n, &err);
    if (rc == 1 && (n > size || h.status < 100 || h.status > 999))
        abort();
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put(&b, rc == 1 ? data + n : data, rc == 1 ? size - n : size);
    size_t before = b.len;
    if (gi_http_dechunk(&b, &err) == 0 && b.len > before)
        abort();
    gi_buf_free(&b);
}

/* The owners read: each name once (owners are compared by address). */
typedef struct owners {
    gi_affinity map;
    char **names;
    size_t count;
} owners;

static void owner_read(void *ctx, uint64_t key, const char *name)
{
    owners *o = ctx;
    const char *owner = NULL;
    for (size_t i = 0; i < o->count && !owner; i++)
        if (strcmp(o->names[i], name) == 0)
            owner = o->names[i];
    if (!owner) {
        o->names = realloc(o->names, (o->count + 1) * sizeof *o->names);
        if (!o->names)
            abort();
        owner = o->names[o->count++] = strdup(name);
    }
    gi_affinity_set(&o->map, key, owner);
}

static const char *owner_name(const void *owner) { return owner; }

static void owners_free(owners *o)
{
    for (size_t i = 0; i < o->count; i++)
        free(o->names[i]);
    free(o->names);
    gi_affinity_free(&o->map);
}

static void affinity(const uint8_t *data, size_t size)
{
    owners a = {{0}, NULL, 0}, b = {{0}, NULL, 0};
    gi_error err;
    int rc = gi_affinity_decode(data, size, "affinity", owner_read, &a, &err);
    if (rc != 0 && (!err.msg[0] || strchr(err.msg, '\n')))
        abort();
    if (rc < 0 && a.map.count)
        abort(); /* not an affinity file: nothing may have been read */
    gi_buf out;
    gi_buf_init(&out);
    gi_affinity_encode(&a.map, owner_name, &out);
    if (gi_affinity_decode(out.data, out.len, "written", owner_read, &b, &err) != 0 ||
        b.map.count != a.map.count)
        abort();
    for (size_t i = 0; i < a.map.cap; i++) {
        const gi_affinity_slot *s = &a.map.slots[i];
        const char *again = s->key ? gi_affinity_owner(&b.map, s->key) : NULL;
        if (s->key && s->owner && (!again || strcmp(again, s->owner) != 0))
            abort();
    }
    gi_buf_free(&out);
    owners_free(&a);
    owners_free(&b);
}

/* Every line that is not skipped is an entry (the last of equal hashes
 * wins), and the entries written again read back the same, none skipped. */
static void published(const uint8_t *data, size_t size)
{
    gi_manifest a, b;
    gi_manifest_init(&a);
    gi_manifest_init(&b);
    size_t lines = 0, empty = 0;
    for (size_t i = 0, start = 0; i <= size; i++)
        if (i == size || data[i] == '\n') {
            lines += i > start || i < size;
            empty += i == start && i < size;
            start = i + 1;
        }
    size_t skipped = gi_published_parse((const char *)data, size, &a);
    if (skipped + empty > lines || a.count > lines - skipped - empty)
        abort();
    gi_buf out;
    gi_buf_init(&out);
    gi_published_format(&a, &out);
    if (gi_published_parse((const char *)out.data, out.len, &b) != 0 || b.count != a.count)
        abort();
    for (size_t i = 0; i < a.count; i++) {
        const gi_manifest_entry *e = &a.entries[i];
        if (!gi_hash_is_valid(e->hash) || strcmp(e->name, e->hash) != 0 ||
            e->size > GI_ASSET_MAX_BYTES)
            abort();
        if (gi_manifest_find(&a, e->name) != e) /* each hash once */
            abort();
        const gi_manifest_entry *f = gi_manifest_find(&b, e->name);
        if (!f || strcmp(f->hash, e->hash) != 0 || f->size != e->size)
            abort();
    }
    gi_buf_free(&out);
    gi_manifest_free(&a);
    gi_manifest_free(&b);
}

static void batch_root_owner(const uint8_t *data, size_t size)
{
    gi_batch_root_owner o;
    gi_error err;
    gi_error_clear(&err);
    if (gi_batch_root_owner_parse((const char *)data, size, "owner", &o, &err)) {
        if (err.code != GI_EINVAL || !err.msg[0] || strchr(err.msg, '\n') || o.ckpt)
            abort();
        return;
    }
    gi_buf out;
    gi_buf_init(&out);
    if (o.pid <= 0 || gi_batch_root_owner_format(&o, &out) != 0 || out.len != size ||
        memcmp(out.data, data, size) != 0)
        abort();
    gi_buf_free(&out);
    free(o.ckpt);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    gi_log_set_level(GI_LOG_ERROR); /* skipped journal records are warned about */
    return 0;
}

typedef struct standing {
    gi_standing_host *hosts;
    gi_standing_excl *excl;
    size_t host_count, excl_count;
} standing;

static void standing_host(void *ctx, const gi_standing_host *h)
{
    standing *s = ctx;
    s->hosts = gi_xrealloc(s->hosts, (s->host_count + 1) * sizeof *s->hosts);
    s->hosts[s->host_count++] = *h;
}

static void standing_excl(void *ctx, const gi_standing_excl *x)
{
    standing *s = ctx;
    s->excl = gi_xrealloc(s->excl, (s->excl_count + 1) * sizeof *s->excl);
    s->excl[s->excl_count++] = *x;
}

static int same_host(const gi_standing_host *a, const gi_standing_host *b)
{
    return !strcmp(a->name, b->name) && a->failures == b->failures &&
           a->own_failures == b->own_failures && a->losses == b->losses &&
           a->streak_job == b->streak_job && a->consecutive_failures == b->consecutive_failures &&
           a->consecutive_losses == b->consecutive_losses && a->streak_wide == b->streak_wide &&
           a->blocked_until == b->blocked_until && !strcmp(a->last_error, b->last_error);
}

static int same_excl(const gi_standing_excl *a, const gi_standing_excl *b)
{
    return a->job_id == b->job_id && !strcmp(a->host, b->host) && a->streak == b->streak &&
           a->times == b->times && a->until == b->until && a->last_failed == b->last_failed &&
           !strcmp(a->last_error, b->last_error);
}

/* What the standing file gives (all, or what comes before its damage),
 * written again, reads back the same, whole. */
static void standing_file(const uint8_t *data, size_t size)
{
    standing a = {0}, b = {0};
    gi_standing_sink sa = {standing_host, standing_excl, &a};
    gi_standing_sink sb = {standing_host, standing_excl, &b};
    gi_error err;
    int rc = gi_standing_decode(data, size, "standing", &sa, &err);
    if (rc != 0 && (!err.msg[0] || strchr(err.msg, '\n')))
        abort();
    if (rc < 0 && (a.host_count || a.excl_count))
        abort(); /* not a standing file: nothing may have been read */
    gi_buf out;
    gi_buf_init(&out);
    gi_standing_encode(a.hosts, a.host_count, a.excl, a.excl_count, &out);
    if (gi_standing_decode(out.data, out.len, "written", &sb, &err) != 0 ||
        b.host_count != a.host_count || b.excl_count != a.excl_count)
        abort();
    for (size_t i = 0; i < a.host_count; i++)
        if (!same_host(&a.hosts[i], &b.hosts[i]))
            abort();
    for (size_t i = 0; i < a.excl_count; i++)
        if (!same_excl(&a.excl[i], &b.excl[i]))
            abort();
    gi_buf_free(&out);
    free(a.hosts);
    free(a.excl);
    free(b.hosts);
    free(b.excl);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    switch (data[0] % 7) {
    case 0:
        journal(data + 1, size - 1);
        break;
    case 1:
        submission(data + 1, size - 1);
        break;
    case 2:
        http(data + 1, size - 1);
        break;
    case 3:
        affinity(data + 1, size - 1);
        break;
    case 4:
        published(data + 1, size - 1);
        break;
    case 5:
        batch_root_owner(data + 1, size - 1);
        break;
    default:
        standing_file(data + 1, size - 1);
        break;
    }
    return 0;
}
