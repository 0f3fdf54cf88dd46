/* client_addr.h — who is on the other end of a connection: the peer address (what the
 * connection table counts per address, conns.h) and the client (what users and logs see: the
 * peer, or behind a trusted proxy the address it names). */
#ifndef ISMD_CLIENT_ADDR_H
#define ISMD_CLIENT_ADDR_H

#include <microhttpd.h>
#include <stddef.h>

/* The peer's IP address as text ("-" when unknown). */
void ismd_peer_address(struct MHD_Connection *c, char *out, size_t cap);
/* The client: the peer address, or when the peer is one of trusted_proxy (comma-separated
 * addresses; "" = none) the address its X-Real-IP header names — only a well-formed IP
 * literal is taken, anything else keeps the proxy's. */
void ismd_client_address(struct MHD_Connection *c, const char *trusted_proxy, char *out,
                         size_t cap);

#endif
