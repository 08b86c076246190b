/* Unit tests: the processors a process may use (gi_cores): the cgroup quota
 * parsers, and a narrowed affinity mask. */
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gi_cores.h"
#include "gi_test.h"

GI_TEST(test_cores_cgroup_v2_cpu_max)
{
    GI_CHECK(gi_cores_from_cpu_max("max 100000\n") == 0);
    GI_CHECK(gi_cores_from_cpu_max("200000 100000\n") == 2);
    GI_CHECK(gi_cores_from_cpu_max("150000 100000") == 2); /* 1.5 CPUs: 2 processes */
    GI_CHECK(gi_cores_from_cpu_max("50000 100000\n") == 1);
    GI_CHECK(gi_cores_from_cpu_max("400000 50000\n") == 8);
    /* Not a quota: no limit, rather than a guess. */
    GI_CHECK(gi_cores_from_cpu_max("") == 0);
    GI_CHECK(gi_cores_from_cpu_max("0 100000") == 0);
    GI_CHECK(gi_cores_from_cpu_max("-5 100000") == 0);
    GI_CHECK(gi_cores_from_cpu_max("200000") == 0);
    GI_CHECK(gi_cores_from_cpu_max("200000 0") == 0);
    GI_CHECK(gi_cores_from_cpu_max("200000 100000 7") == 0);
    GI_CHECK(gi_cores_from_cpu_max("2e5 100000") == 0);
    GI_CHECK(gi_cores_from_cpu_max("99999999999999999999999 1") == 0);
}

GI_TEST(test_cores_cgroup_v1_cfs)
{
    GI_CHECK(gi_cores_from_cfs("-1\n", "100000\n") == 0);
    GI_CHECK(gi_cores_from_cfs("300000\n", "100000\n") == 3);
    GI_CHECK(gi_cores_from_cfs("250000\n", "100000\n") == 3);
    GI_CHECK(gi_cores_from_cfs("", "100000\n") == 0);
    GI_CHECK(gi_cores_from_cfs("300000\n", "x") == 0);
}

/* In a child narrowed to one CPU (as `taskset -c 0` or a Slurm step would),
 * the usable count is 1 whatever the machine has. */
GI_TEST(test_cores_follow_the_affinity_mask)
{
    int all = gi_cores_usable();
    GI_CHECK(all >= 1 && all <= sysconf(_SC_NPROCESSORS_ONLN));
    pid_t pid = fork();
    GI_REQUIRE(pid >= 0);
    if (pid == 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        if (sched_getaffinity(0, sizeof set, &set) != 0)
            _exit(3);
        int first = 0;
        while (first < CPU_SETSIZE && !CPU_ISSET(first, &set))
            first++;
        CPU_ZERO(&set);
        CPU_SET(first, &set);
        if (sched_setaffinity(0, sizeof set, &set) != 0)
            _exit(4);
        _exit(gi_cores_usable() == 1 ? 0 : 5);
    }
    int status = 0;
    GI_REQUIRE(waitpid(pid, &status, 0) == pid);
    GI_CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "child status %d", status);
}
