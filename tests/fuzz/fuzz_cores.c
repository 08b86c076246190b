/* fuzz_cores: libFuzzer target for the cgroup CPU quota parsers (gi_cores):
 * cpu.max, and cpu.cfs_quota_us / cpu.cfs_period_us split at the first
 * newline. A quota is 0 (none) or a positive count no larger than the quota
 * itself (a period is at least 1 us). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_cores.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    long n = gi_cores_from_cpu_max(text);
    if (n < 0)
        abort();
    char *nl = strchr(text, '\n');
    const char *period = "100000";
    if (nl) {
        *nl = '\0';
        period = nl + 1;
    }
    n = gi_cores_from_cfs(text, period);
    if (n < 0 || (n > 0 && n > strtol(text, NULL, 10)))
        abort();
    free(text);
    return 0;
}
