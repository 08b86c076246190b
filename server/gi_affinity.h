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

#endif
