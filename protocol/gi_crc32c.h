/* gi_crc32c: CRC-32C (Castagnoli, reflected polynomial 0x82F63B78), the
 * checksum of every wire frame.
 *
 * Castagnoli rather than zlib's CRC-32 because x86-64-v2 has it in hardware
 * (SSE4.2 `crc32`) and it detects more error patterns at frame sizes
 * (Castagnoli, Braeuer, Herrmann, IEEE Trans. Commun. 41(6), 1993; RFC 3720
 * section 12.1 uses it for iSCSI for the same reason).
 *
 * Chaining follows zlib's crc32(): start from 0 and feed the previous result
 * back in; the pre- and post-inversion happen inside, so
 * gi_crc32c(gi_crc32c(0, a, n), b, m) == crc of a||b.
 * Check value: gi_crc32c(0, "123456789", 9) == 0xE3069283. */
#ifndef GI_CRC32C_H
#define GI_CRC32C_H

#include <stddef.h>
#include <stdint.h>

/* The fastest implementation available on this CPU: the SSE4.2 instruction
 * when the build targets it (-march=x86-64-v2) or, in generic x86-64
 * builds, when the CPU reports it at run time; else slicing-by-8. */
uint32_t gi_crc32c(uint32_t crc, const void *data, size_t n);

/* Portable table version (slicing-by-8, 8 KiB of tables). Exposed so tests
 * can check it against the hardware path. */
uint32_t gi_crc32c_sw(uint32_t crc, const void *data, size_t n);

#if defined(__x86_64__) || defined(__i386__)
#define GI_CRC32C_HAVE_HW 1
/* 1 if this CPU executes the SSE4.2 crc32 instruction. */
int gi_crc32c_hw_available(void);
/* The SSE4.2 version; call only when gi_crc32c_hw_available(). */
uint32_t gi_crc32c_hw(uint32_t crc, const void *data, size_t n);
#endif

#endif
