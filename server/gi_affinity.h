/* gi_affinity: which worker host owns each affinity key of a job.
 *
 * Tasks with the same non-zero gi_task.affinity reuse what a host keeps on
 * its disk for that key (a photon batch and its frames), so the coordinator
 * remembers, per job, the host that last returned a result for each key
 * (or, when the owner was gone, the host that took the key's task since).
 * The rule (gi_affinity_may_take): a task whose owner is present goes to
 * that owner only, when it has a free slot; a task without an owner, or
 * whose owner is absent (disconnected, draining, blocklisted, silent), goes
 * to whoever asks first, which becomes the owner. Absence is the caller's
 * judgement (a callback), so the rule never waits on a host that cannot
 * take work: no stalls. Owners are opaque pointers (gi-farmd: gi_farm_host,
 * which outlive connections), compared by address.
 *
 * The map is an open-addressing hash table (key 0 is never stored). */
#ifndef GI_AFFINITY_H
#define GI_AFFINITY_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

typedef struct gi_affinity_slot {
    uint64_t key; /* 0: empty */
    const void *owner;
} gi_affinity_slot;

typedef struct gi_affinity {
    gi_affinity_slot *slots;
    size_t count, cap; /* cap: 0 or a power of two */
} gi_affinity;

void gi_affinity_init(gi_affinity *m);
void gi_affinity_free(gi_affinity *m);
/* The key's owner, or NULL. */
const void *gi_affinity_owner(const gi_affinity *m, uint64_t key);
/* Makes owner the key's owner (NULL forgets the key); returns the previous one. */
const void *gi_affinity_set(gi_affinity *m, uint64_t key, const void *owner);

/* Is the owner able to take work now? (connected, active, not blocklisted) */
typedef int (*gi_affinity_present_fn)(void *ctx, const void *owner);

/* May `host` take a task with this affinity key? Yes when the key is 0,
 * has no owner, is owned by host, or its owner is not present. */
int gi_affinity_may_take(const gi_affinity *m, uint64_t key, const void *host,
                         gi_affinity_present_fn present, void *ctx);

/* The affinity file that gi-farmd keeps beside a job's checkpoint, so that
 * a restarted coordinator sends each key's tasks back to the host holding
 * its files: u32 "GIAF", u32 version 1, u64 count, then count times (u64
 * key, string owner name). name(owner) gives an owner's name. */
void gi_affinity_encode(const gi_affinity *m, const char *(*name)(const void *owner),
                        gi_buf *out);
/* Reads such a file's bytes (`what` names it in errors), calling each(ctx,
 * key, name) for every entry with a non-zero key and a name. Returns 0 when
 * all was read; -1 with err if it is not an affinity file (each never
 * called); 1 with err if it is damaged after the entries given to each. */
int gi_affinity_decode(const void *data, size_t len, const char *what,
                       void (*each)(void *ctx, uint64_t key, const char *name), void *ctx,
                       gi_error *err);

#endif
