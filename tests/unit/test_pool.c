/* Unit tests: the fork pool's event dispatch. */
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include "gi_pool.h"
#include "gi_test.h"

static void count_crash(void *user, int child, uint64_t job_id, uint64_t task_id,
                        uint32_t attempt, const char *why)
{
    (*(int *)user)++;
}

/* A worker that cancels a running task replaces its child between poll()
 * and dispatch; the new child's socket gets the old one's descriptor number.
 * The old child's readiness must not reach the new child: reading its idle
 * socket blocked the worker's whole loop (no heartbeats, leases expired,
 * the coordinator dropped the host). */
GI_TEST(test_pool_replaced_child_gets_no_stale_events)
{
    gi_error err;
    gi_pool p;
    GI_REQUIRE_OK(gi_pool_start(&p, 1, NULL, &err));
    struct pollfd fds[1];
    int child_of[1];
    int n = gi_pool_pollfds(&p, fds, child_of);
    GI_CHECK(n == 1);
    int old_fd = p.kids[0].fd;
    pid_t old_pid = p.kids[0].pid;
    kill(old_pid, SIGKILL); /* its socket reports end of file */
    GI_CHECK(poll(fds, 1, 5000) == 1 && fds[0].revents);

    GI_REQUIRE_OK(gi_pool_spawn(&p, 0, &err)); /* the replacement */
    GI_CHECK(p.kids[0].fd == old_fd && p.kids[0].pid != old_pid);

    int crashes = 0;
    gi_pool_events ev = {.user = &crashes, .crash = count_crash};
    alarm(20); /* a blocking read here would hang: fail instead */
    gi_pool_dispatch(&p, fds, child_of, n, &ev);
    alarm(0);
    GI_CHECK(crashes == 0);
    GI_CHECK(gi_pool_alive(&p, 0) && gi_pool_idle_child(&p) == 0);

    /* The next round sees the new child as it is: idle, nothing to read. */
    n = gi_pool_pollfds(&p, fds, child_of);
    GI_CHECK(n == 1 && poll(fds, 1, 100) == 0);
    gi_pool_stop(&p);
}
