/* gi_auth: secret loading, handshake MACs, token comparison. */
#include "gi_auth.h"

#include <errno.h>
#include <fcntl.h>
#include <sodium.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void ensure_sodium(void)
{
    /* Idempotent and thread-safe; aborting is right if the CSPRNG is unusable. */
    if (sodium_init() < 0)
        abort();
}

/* path is a file of systemd's credentials directory for this service
 * ($CREDENTIALS_DIRECTORY, LoadCredential=), which others cannot enter. */
static int in_credentials_directory(const char *path)
{
    const char *dir = getenv("CREDENTIALS_DIRECTORY");
    if (!dir || !dir[0])
        return 0;
    char *real_dir = realpath(dir, NULL), *real = realpath(path, NULL);
    struct stat st;
    int in = real_dir && real && stat(real_dir, &st) == 0 && !(st.st_mode & S_IRWXO);
    if (in) {
        size_t n = strlen(real_dir);
        in = strncmp(real, real_dir, n) == 0 && real[n] == '/' && !strchr(real + n + 1, '/');
    }
    free(real_dir);
    free(real);
    return in;
}

static int read_secret_file(const char *path, const char *what, gi_buf *out, gi_error *err)
{
    /* O_NONBLOCK: opening a FIFO waits for a writer, forever. */
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd < 0)
        return gi_fail(err, GI_EINVAL, "%s file %s: %s", what, path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return gi_fail(err, GI_EINVAL, "%s file %s: not a regular file", what, path);
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0) {
        close(fd);
        return gi_fail(err, GI_EIO, "%s file %s: %s", what, path, strerror(errno));
    }
    /* systemd writes a credential 0400 and, where the file system has ACLs,
     * grants the service's user through one: stat then shows the ACL's mask
     * as group bits (0440) although no group may read it. */
    mode_t forbidden = in_credentials_directory(path) ? S_IRWXO : (S_IRWXG | S_IRWXO);
    if (st.st_mode & forbidden) {
        close(fd);
        return gi_fail(err, GI_EINVAL,
                       "%s file %s: group or others may access it (mode %03o); "
                       "chmod 600 it",
                       what, path, (unsigned)(st.st_mode & 0777));
    }
    if (st.st_size > GI_SECRET_MAX_BYTES) {
        close(fd);
        return gi_fail(err, GI_EINVAL, "%s file %s: longer than %d bytes", what, path,
                       GI_SECRET_MAX_BYTES);
    }
    /* One allocation up front: a realloc would leave a copy of the secret
     * in freed memory. */
    gi_buf_reserve(out, GI_SECRET_MAX_BYTES + 1);
    for (;;) {
        ssize_t n = read(fd, out->data + out->len, out->cap - out->len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            int e = errno;
            close(fd);
            return gi_fail(err, GI_EIO, "%s file %s: %s", what, path, strerror(e));
        }
        if (n == 0)
            break;
        out->len += (size_t)n;
        if (out->len > GI_SECRET_MAX_BYTES) {
            close(fd);
            return gi_fail(err, GI_EINVAL, "%s file %s: longer than %d bytes", what, path,
                           GI_SECRET_MAX_BYTES);
        }
    }
    close(fd);
    return 0;
}

int gi_secret_read(const char *file, const char *env_file, const char *env_value,
                   const char *what, const char *option, gi_buf *out, gi_error *err)
{
    gi_secret_free(out);
    int rc;
    const char *from;
    if (!file && env_file)
        file = getenv(env_file);
    if (file && file[0]) {
        rc = read_secret_file(file, what, out, err);
        from = file;
    } else {
        const char *v = env_value ? getenv(env_value) : NULL;
        if (!v || !v[0])
            return gi_fail(err, GI_EINVAL,
                           "no %s: name its file with %s or %s, or set %s (docs/farm.md, "
                           "\"Quick start\", makes one)",
                           what, option ? option : "the program's option",
                           env_file ? env_file : "-", env_value ? env_value : "-");
        size_t n = strlen(v);
        if (n > GI_SECRET_MAX_BYTES)
            return gi_fail(err, GI_EINVAL, "%s in %s: longer than %d bytes", what, env_value,
                           GI_SECRET_MAX_BYTES);
        gi_buf_put(out, v, n);
        /* Overwrite the environment copy before removing it. */
        sodium_memzero((char *)v, n);
        unsetenv(env_value);
        rc = 0;
        from = env_value;
    }
    if (rc) {
        gi_secret_free(out);
        return -1;
    }
    while (out->len && (out->data[out->len - 1] == '\n' || out->data[out->len - 1] == '\r' ||
                        out->data[out->len - 1] == ' ' || out->data[out->len - 1] == '\t'))
        out->len--;
    if (out->len < GI_SECRET_MIN_BYTES) {
        gi_secret_free(out);
        return gi_fail(err, GI_EINVAL, "%s from %s: shorter than %d bytes", what, from,
                       GI_SECRET_MIN_BYTES);
    }
    return 0;
}

void gi_secret_free(gi_buf *secret)
{
    if (secret->data)
        sodium_memzero(secret->data, secret->cap);
    gi_buf_free(secret);
}

void gi_auth_key(const gi_buf *secret, uint8_t key[GI_AUTH_KEY_BYTES])
{
    ensure_sodium();
    /* Domain separation: the same secret used elsewhere gives another key. */
    static const char label[] = "gi-farm worker authentication v1";
    crypto_generichash_state st;
    crypto_generichash_init(&st, NULL, 0, GI_AUTH_KEY_BYTES);
    crypto_generichash_update(&st, (const unsigned char *)label, sizeof label - 1);
    crypto_generichash_update(&st, secret->data, secret->len);
    crypto_generichash_final(&st, key, GI_AUTH_KEY_BYTES);
    sodium_memzero(&st, sizeof st);
}

/* HMAC over label || a || b || extra (lengths fixed except extra, which is last). */
static void mac4(const uint8_t key[GI_AUTH_KEY_BYTES], const char *label, const uint8_t *a,
                 const uint8_t *b, const void *extra, size_t extra_len,
                 uint8_t mac[GI_MSG_MAC_BYTES])
{
    ensure_sodium();
    crypto_auth_hmacsha512256_state st;
    crypto_auth_hmacsha512256_init(&st, key, GI_AUTH_KEY_BYTES);
    crypto_auth_hmacsha512256_update(&st, (const unsigned char *)label, strlen(label) + 1);
    crypto_auth_hmacsha512256_update(&st, a, GI_MSG_NONCE_BYTES);
    crypto_auth_hmacsha512256_update(&st, b, GI_MSG_NONCE_BYTES);
    crypto_auth_hmacsha512256_update(&st, extra, extra_len);
    crypto_auth_hmacsha512256_final(&st, mac);
    sodium_memzero(&st, sizeof st);
}

void gi_auth_worker_mac(const uint8_t key[GI_AUTH_KEY_BYTES],
                        const uint8_t coord_nonce[GI_MSG_NONCE_BYTES],
                        const uint8_t worker_nonce[GI_MSG_NONCE_BYTES], const void *hello,
                        size_t hello_len, uint8_t mac[GI_MSG_MAC_BYTES])
{
    /* The HELLO is bound through its hash (fixed-size input to the MAC). */
    uint8_t h[32];
    ensure_sodium();
    crypto_generichash(h, sizeof h, hello, hello_len, NULL, 0);
    mac4(key, "gi-farm worker proof", coord_nonce, worker_nonce, h, sizeof h, mac);
}

void gi_auth_coord_mac(const uint8_t key[GI_AUTH_KEY_BYTES],
                       const uint8_t worker_nonce[GI_MSG_NONCE_BYTES],
                       const uint8_t coord_nonce[GI_MSG_NONCE_BYTES], uint64_t worker_id,
                       uint8_t mac[GI_MSG_MAC_BYTES])
{
    uint8_t id[8];
    gi_le_put_u64(id, worker_id);
    mac4(key, "gi-farm coordinator proof", worker_nonce, coord_nonce, id, sizeof id, mac);
}

int gi_auth_mac_equal(const uint8_t a[GI_MSG_MAC_BYTES], const uint8_t b[GI_MSG_MAC_BYTES])
{
    ensure_sodium();
    return sodium_memcmp(a, b, GI_MSG_MAC_BYTES) == 0;
}

void gi_auth_random(void *out, size_t n)
{
    ensure_sodium();
    randombytes_buf(out, n);
}

int gi_token_equal(const gi_buf *token, const char *given, size_t n)
{
    ensure_sodium();
    uint8_t a[32], b[32];
    crypto_generichash(a, sizeof a, token->data, token->len, NULL, 0);
    crypto_generichash(b, sizeof b, (const unsigned char *)given, n, NULL, 0);
    return sodium_memcmp(a, b, sizeof a) == 0;
}
