/* gi_blas_threads: see gi_blas_threads.h. */
#include "gi_blas_threads.h"

#include <cblas.h>

/* OpenBLAS's own: stops its thread pool (the handler it runs before fork). */
int blas_thread_shutdown_(void);

void gi_blas_single_thread(void)
{
    openblas_set_num_threads(1);
    blas_thread_shutdown_();
}
