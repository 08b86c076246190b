/* gi_clock: the monotonic clock (see the header). */
#include "gi_clock.h"

#include <time.h>

double gi_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
