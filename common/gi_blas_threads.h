/* gi_blas_threads: OpenBLAS runs on the calling thread only. */
#ifndef GI_BLAS_THREADS_H
#define GI_BLAS_THREADS_H

/* Called first thing in every program. Work is spread over forked
 * processes, one per core, so BLAS threads would only compete with them;
 * and OpenBLAS starts its thread pool when the library loads, whose idle
 * threads keep waking up (sched_yield) for the life of a process that
 * never forks: `gi submit --wait` spent 3% of a core on it, taken from the
 * renderers on the same host. */
void gi_blas_single_thread(void);

#endif
