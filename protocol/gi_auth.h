/* gi_auth: the farm's shared secrets and what is computed from them.
 *
 * Two secrets (docs/farm.md, "Security"):
 * - the farm secret, shared by gi-farmd and every gi-worker: each side of a
 *   worker connection proves it knows it with an HMAC over both sides'
 *   random nonces (libsodium crypto_auth, HMAC-SHA-512-256), so a passive
 *   listener learns nothing reusable and a replayed handshake fails;
 * - the API token, which HTTP clients send as "Authorization: Bearer".
 * Secrets come from a file or the environment, never from the command line
 * (where any local user can read them in /proc), and are never logged. */
#ifndef GI_AUTH_H
#define GI_AUTH_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "gi_msg_ctrl.h"

#define GI_AUTH_KEY_BYTES 32
#define GI_SECRET_MIN_BYTES 16
#define GI_SECRET_MAX_BYTES 4096

/* Reads a secret: from `file` if non-NULL, else from the file named by the
 * environment variable env_file, else from the variable env_value itself
 * (which is then removed from the environment, so children do not inherit
 * it). Trailing white space (a final newline) is dropped. Refuses a file
 * that group or others may read, and secrets shorter than
 * GI_SECRET_MIN_BYTES. `what` names the secret in messages ("farm secret"),
 * `option` the program's option that names its file ("--secret-file", or
 * NULL), so that a missing secret says how to give it; the messages never
 * contain secret bytes. out is cleared first. */
int gi_secret_read(const char *file, const char *env_file, const char *env_value,
                   const char *what, const char *option, gi_buf *out, gi_error *err);
/* Overwrites and frees a secret. */
void gi_secret_free(gi_buf *secret);

/* The HMAC key of worker authentication, derived from the farm secret. */
void gi_auth_key(const gi_buf *secret, uint8_t key[GI_AUTH_KEY_BYTES]);

/* The worker's proof: MAC over the coordinator's nonce, the worker's nonce
 * and the HELLO payload as sent (so its advertised resources are bound). */
void gi_auth_worker_mac(const uint8_t key[GI_AUTH_KEY_BYTES],
                        const uint8_t coord_nonce[GI_MSG_NONCE_BYTES],
                        const uint8_t worker_nonce[GI_MSG_NONCE_BYTES], const void *hello,
                        size_t hello_len, uint8_t mac[GI_MSG_MAC_BYTES]);
/* The coordinator's proof: MAC over both nonces (in the other order, and
 * under another label) and the worker id it assigns. */
void gi_auth_coord_mac(const uint8_t key[GI_AUTH_KEY_BYTES],
                       const uint8_t worker_nonce[GI_MSG_NONCE_BYTES],
                       const uint8_t coord_nonce[GI_MSG_NONCE_BYTES], uint64_t worker_id,
                       uint8_t mac[GI_MSG_MAC_BYTES]);
/* Constant-time comparison of two MACs: 1 if equal. */
int gi_auth_mac_equal(const uint8_t a[GI_MSG_MAC_BYTES], const uint8_t b[GI_MSG_MAC_BYTES]);

/* Fresh random bytes (libsodium's CSPRNG). */
void gi_auth_random(void *out, size_t n);

/* 1 if `given` (n bytes, not NUL-terminated) equals the token. Both are
 * hashed first and the digests compared in constant time, so neither the
 * token's bytes nor its length leak through timing. */
int gi_token_equal(const gi_buf *token, const char *given, size_t n);

#endif
