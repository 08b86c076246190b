/* gi_cores: how many processors this process may use, which is what the
 * default pool sizes and thread counts follow.
 *
 * Not the machine's count: a Slurm step or `taskset` gives a process some of
 * the CPUs (its affinity mask), and a container's CPU limit (Kubernetes'
 * `resources.limits.cpu`, `docker --cpus`) is a cgroup quota of CPU time.
 * One pool process per machine CPU in either would run dozens of processes
 * on a few CPUs' time. */
#ifndef GI_CORES_H
#define GI_CORES_H

/* The CPUs online, at most the affinity mask's, at most the cgroup's CPU
 * quota rounded up (cgroup v2 cpu.max, or v1 cpu.cfs_quota_us, of this
 * process's cgroup and its ancestors); at least 1. */
int gi_cores_usable(void);

/* A cgroup v2 cpu.max ("QUOTA PERIOD" or "max PERIOD"): the quota in CPUs
 * rounded up, or 0 for no limit or text that is not one. */
long gi_cores_from_cpu_max(const char *text);

/* cgroup v1 cpu.cfs_quota_us and cpu.cfs_period_us: the same (-1: no limit). */
long gi_cores_from_cfs(const char *quota_text, const char *period_text);

#endif
