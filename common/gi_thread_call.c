/* gi_thread_call: a function run on a thread of its own (see the header). */
#include "gi_thread_call.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#include "gi_error.h"

struct gi_thread_call {
    pthread_t thread;
    int threaded;
    void (*fn)(void *arg);
    void *arg;
    int wake_fd;
    atomic_int done;
};

static void *call_main(void *p)
{
    gi_thread_call *c = p;
    c->fn(c->arg);
    atomic_store(&c->done, 1);
    if (c->wake_fd >= 0) {
        uint64_t one = 1;
        /* Best effort: an eventfd whose count is already set wakes the poll. */
        ssize_t n = write(c->wake_fd, &one, sizeof one);
        (void)n;
    }
    return NULL;
}

gi_thread_call *gi_thread_call_start(void (*fn)(void *arg), void *arg, int wake_fd)
{
    gi_thread_call *c = gi_xcalloc(1, sizeof *c);
    c->fn = fn;
    c->arg = arg;
    c->wake_fd = wake_fd;
    atomic_init(&c->done, 0);
    c->threaded = pthread_create(&c->thread, NULL, call_main, c) == 0;
    if (!c->threaded)
        call_main(c);
    return c;
}

int gi_thread_call_done(const gi_thread_call *c)
{
    return atomic_load(&((gi_thread_call *)c)->done);
}

void gi_thread_call_join(gi_thread_call *c)
{
    if (!c)
        return;
    if (c->threaded)
        pthread_join(c->thread, NULL);
    free(c);
}
