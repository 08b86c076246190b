/* gi_net: TCP endpoints for the farm: listening, connecting with a time
 * limit, naming peers. Addresses are "HOST:PORT" ("[v6addr]:PORT" for IPv6
 * literals); HOST may be a name, resolved with getaddrinfo. */
#ifndef GI_NET_H
#define GI_NET_H

#include <stddef.h>

#include "gi_error.h"

/* Splits "HOST:PORT" into host (malloc'ed, brackets removed) and port. */
int gi_net_split(const char *addr, char **host, char **port, gi_error *err);

/* A non-blocking, close-on-exec listening socket bound to addr (SO_REUSEADDR).
 * `bound` receives the address actually bound ("127.0.0.1:43121" when the
 * port was 0). */
int gi_net_listen(const char *addr, char *bound, size_t bound_len, gi_error *err);

/* A connected, blocking, close-on-exec TCP socket (TCP_NODELAY, keepalive),
 * trying each resolved address in turn within timeout_s. */
int gi_net_connect(const char *addr, double timeout_s, gi_error *err);

/* 1 if the socket's peer is on this host (127.0.0.0/8, ::1 or a v4-mapped
 * loopback address, or a Unix socket), else 0. */
int gi_net_peer_is_loopback(int fd);

/* "10.0.0.7:51234" for a connected socket's peer. */
void gi_net_peer(int fd, char *out, size_t n);
struct sockaddr;
void gi_net_sockaddr_name(const struct sockaddr *sa, char *out, size_t n);

/* Socket options for a worker connection: TCP_NODELAY (frames are whole
 * messages; Nagle would hold small ones back) and keepalive. */
void gi_net_tune(int fd);

#endif
