/* fuzz_radiosity: libFuzzer target for the two parsers of `gi relight`:
 * the emissions file (JSON) and the factorization file (binary). Every
 * input goes to both. For the factorization, an input that does not start
 * with the magic has its first byte dropped and the rest wrapped in a valid
 * header (magic, version, length, CRC-32C), so the fuzzer reaches the
 * payload checks instead of stopping at the checksum; the dropped byte
 * picks the version (odd: the oldest still read, whose materials have no
 * flags). Any
 * input must parse or fail with a one-line GI_EINVAL message; never crash,
 * leak or hang. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_buf.h"
#include "gi_crc32c.h"
#include "radiosity/rad_emissions.h"
#include "radiosity/rad_file.h"

static void check(int rc, const gi_error *err)
{
    if (rc != 0 && (err->code != GI_EINVAL || strchr(err->msg, '\n') || !err->msg[0]))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    gi_error err;
    gi_error_clear(&err);
    gi_rad_emissions em;
    check(gi_rad_emissions_parse((const char *)data, size, "fuzz.json", &em, &err), &err);
    gi_rad_emissions_free(&em);

    gi_buf b;
    gi_buf_init(&b);
    if (size > 0 && (size < 8 || memcmp(data, GI_RAD_FILE_MAGIC, 8) != 0)) {
        gi_buf_put(&b, GI_RAD_FILE_MAGIC, 8);
        gi_buf_put_u32(&b, data[0] & 1 ? GI_RAD_FILE_OLDEST_VERSION : GI_RAD_FILE_VERSION);
        gi_buf_put_u32(&b, 0);
        gi_buf_put_u64(&b, size - 1);
        gi_buf_put_u32(&b, gi_crc32c(0, data + 1, size - 1));
        gi_buf_put(&b, data + 1, size - 1);
    } else {
        gi_buf_put(&b, data, size);
    }
    gi_rad_file_info info;
    gi_rad_model md;
    gi_rad_factor f;
    gi_error_clear(&err);
    int rc = gi_rad_file_decode(b.data, b.len, "fuzz.fact", &info, &md, &f, &err);
    check(rc, &err);
    if (rc == 0) {
        gi_rad_model_free(&md);
        gi_rad_factor_free(&f);
    }
    gi_buf_free(&b);
    return 0;
}
