/* client_addr.h — who is on the other end of a connection: the peer address (what the
 * connection table counts per address, conns.h) and the client (what users and logs see: the
 * peer, or behind a trusted proxy the address it names). */
#ifndef ISMD_CLIENT_ADDR_H
#define ISMD_CLIENT_ADDR_H

#include <microhttpd.h>
#include <sys/socket.h>
#include <stdbool.h>
#include <stddef.h>

/* Is addr one of the comma-separated addresses in list? */
bool ismd_address_listed(const char *list, const char *addr);

/* The peer's IP address as text ("-" when unknown). */
void ismd_peer_address(struct MHD_Connection *c, char *out, size_t cap);
/* The IP address of sa as text ("-" for NULL or another family). */
void ismd_sockaddr_text(const struct sockaddr *sa, char *out, size_t cap);
/* The client: the peer address (peer, or read from c when NULL), or when the peer is one of
 * trusted_proxy (comma-separated addresses; "" = none) the address its X-Real-IP header
 * names, else the rightmost address of X-Forwarded-For that is not a trusted proxy — only
 * well-formed IP literals are taken (a malformed entry stops the walk at the last trusted
 * address). */
void ismd_client_address(struct MHD_Connection *c, const char *peer, const char *trusted_proxy,
                         char *out, size_t cap);

#endif
