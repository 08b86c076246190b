/* gi_net: TCP listen / connect / peer names. */
#include "gi_net.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "gi_clock.h"

int gi_net_split(const char *addr, char **host, char **port, gi_error *err)
{
    *host = *port = NULL;
    const char *colon;
    const char *h0 = addr, *h1;
    if (addr[0] == '[') {
        const char *close = strchr(addr, ']');
        if (!close || close[1] != ':')
            return gi_fail(err, GI_EINVAL, "address \"%s\": expected [IPv6]:PORT", addr);
        h0 = addr + 1;
        h1 = close;
        colon = close + 1;
    } else {
        colon = strrchr(addr, ':');
        if (!colon)
            return gi_fail(err, GI_EINVAL, "address \"%s\": expected HOST:PORT", addr);
        if (memchr(addr, ':', (size_t)(colon - addr)))
            return gi_fail(err, GI_EINVAL, "address \"%s\": write IPv6 addresses as [ADDR]:PORT",
                           addr);
        h1 = colon;
    }
    const char *p = colon + 1;
    char *end;
    long v = strtol(p, &end, 10);
    if (!*p || *end || v < 0 || v > 65535)
        return gi_fail(err, GI_EINVAL, "address \"%s\": port must be 0-65535", addr);
    if (h1 == h0)
        return gi_fail(err, GI_EINVAL, "address \"%s\": no host", addr);
    *host = gi_xmalloc((size_t)(h1 - h0) + 1);
    memcpy(*host, h0, (size_t)(h1 - h0));
    (*host)[h1 - h0] = '\0';
    *port = gi_xstrdup(p);
    return 0;
}

static int resolve(const char *addr, int passive, struct addrinfo **res, gi_error *err)
{
    char *host, *port;
    if (gi_net_split(addr, &host, &port, err))
        return -1;
    struct addrinfo hints;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = passive ? AI_PASSIVE : 0;
    int rc = getaddrinfo(host, port, &hints, res);
    free(host);
    free(port);
    if (rc != 0)
        return gi_fail(err, GI_EINVAL, "address \"%s\": %s", addr, gai_strerror(rc));
    return 0;
}

void gi_net_sockaddr_name(const struct sockaddr *sa, char *out, size_t n)
{
    char host[INET6_ADDRSTRLEN] = "?";
    int port = 0;
    if (sa->sa_family == AF_INET) {
        const struct sockaddr_in *s = (const struct sockaddr_in *)sa;
        inet_ntop(AF_INET, &s->sin_addr, host, sizeof host);
        port = ntohs(s->sin_port);
        snprintf(out, n, "%s:%d", host, port);
    } else if (sa->sa_family == AF_INET6) {
        const struct sockaddr_in6 *s = (const struct sockaddr_in6 *)sa;
        inet_ntop(AF_INET6, &s->sin6_addr, host, sizeof host);
        port = ntohs(s->sin6_port);
        snprintf(out, n, "[%s]:%d", host, port);
    } else {
        snprintf(out, n, "(family %d)", sa->sa_family);
    }
}

int gi_net_listen(const char *addr, char *bound, size_t bound_len, gi_error *err)
{
    struct addrinfo *res;
    if (resolve(addr, 1, &res, err))
        return -1;
    int fd = -1, last = 0;
    for (struct addrinfo *ai = res; ai; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC,
                    ai->ai_protocol);
        if (fd < 0) {
            last = errno;
            continue;
        }
        int one = 1;
        setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (bind(fd, ai->ai_addr, ai->ai_addrlen) == 0 && listen(fd, 128) == 0)
            break;
        last = errno;
        close(fd);
        fd = -1;
    }
    freeaddrinfo(res);
    if (fd < 0)
        return gi_fail(err, GI_EIO, "cannot listen on %s: %s%s", addr, strerror(last),
                       last == EADDRINUSE ? " (another program, a gi-farmd perhaps, has that "
                                            "port: give another)" : "");
    struct sockaddr_storage ss;
    socklen_t sl = sizeof ss;
    if (bound && getsockname(fd, (struct sockaddr *)&ss, &sl) == 0)
        gi_net_sockaddr_name((struct sockaddr *)&ss, bound, bound_len);
    return fd;
}

void gi_net_tune(int fd)
{
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one);
}

/* Connects one address within the time left; 0 on success. */
static int connect_one(int fd, const struct addrinfo *ai, double deadline)
{
    if (connect(fd, ai->ai_addr, ai->ai_addrlen) == 0)
        return 0;
    if (errno != EINPROGRESS)
        return -1;
    for (;;) {
        double left = deadline - gi_now();
        if (left <= 0) {
            errno = ETIMEDOUT;
            return -1;
        }
        struct pollfd p = {.fd = fd, .events = POLLOUT};
        int r = poll(&p, 1, (int)(left * 1000) + 1);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -1;
        if (r == 0) {
            errno = ETIMEDOUT;
            return -1;
        }
        int e = 0;
        socklen_t el = sizeof e;
        getsockopt(fd, SOL_SOCKET, SO_ERROR, &e, &el);
        if (e) {
            errno = e;
            return -1;
        }
        return 0;
    }
}

int gi_net_connect(const char *addr, double timeout_s, gi_error *err)
{
    struct addrinfo *res;
    if (resolve(addr, 0, &res, err))
        return -1;
    double deadline = gi_now() + timeout_s;
    int fd = -1, last = 0;
    for (struct addrinfo *ai = res; ai; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC,
                    ai->ai_protocol);
        if (fd < 0) {
            last = errno;
            continue;
        }
        if (connect_one(fd, ai, deadline) == 0)
            break;
        last = errno;
        close(fd);
        fd = -1;
    }
    freeaddrinfo(res);
    if (fd < 0)
        return gi_fail_errno(err, GI_EIO, last, "cannot connect to %s: %s", addr,
                             strerror(last));
    int fl = fcntl(fd, F_GETFL);
    fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    gi_net_tune(fd);
    return fd;
}

void gi_net_peer(int fd, char *out, size_t n)
{
    struct sockaddr_storage ss;
    socklen_t sl = sizeof ss;
    if (getpeername(fd, (struct sockaddr *)&ss, &sl) != 0) {
        snprintf(out, n, "fd %d", fd);
        return;
    }
    gi_net_sockaddr_name((struct sockaddr *)&ss, out, n);
}

int gi_net_peer_is_loopback(int fd)
{
    struct sockaddr_storage ss;
    socklen_t len = sizeof ss;
    if (getpeername(fd, (struct sockaddr *)&ss, &len) != 0)
        return 0;
    if (ss.ss_family == AF_UNIX)
        return 1;
    if (ss.ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)&ss;
        return (ntohl(a->sin_addr.s_addr) >> 24) == 127;
    }
    if (ss.ss_family == AF_INET6) {
        const struct in6_addr *a = &((const struct sockaddr_in6 *)&ss)->sin6_addr;
        if (IN6_IS_ADDR_LOOPBACK(a))
            return 1;
        return IN6_IS_ADDR_V4MAPPED(a) && a->s6_addr[12] == 127;
    }
    return 0;
}
