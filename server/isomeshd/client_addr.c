/* client_addr.c — who is on the other end of a connection (client_addr.h): the peer address
 * as text, and the client a trusted reverse proxy names in X-Real-IP. */
#include "server/isomeshd/client_addr.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>

void ismd_peer_address(struct MHD_Connection *c, char *out, size_t cap)
{
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    snprintf(out, cap, "-");
    if (!ci || !ci->client_addr)
        return;
    const struct sockaddr *sa = ci->client_addr;
    if (sa->sa_family == AF_INET)
        inet_ntop(AF_INET, &((const struct sockaddr_in *)sa)->sin_addr, out, (socklen_t)cap);
    else if (sa->sa_family == AF_INET6)
        inet_ntop(AF_INET6, &((const struct sockaddr_in6 *)sa)->sin6_addr, out, (socklen_t)cap);
}

/* Is addr one of the comma-separated addresses in list? */
static bool in_address_list(const char *list, const char *addr)
{
    size_t n = strlen(addr);
    for (const char *p = list; *p;) {
        size_t len = strcspn(p, ",");
        if (len == n && !strncmp(p, addr, n))
            return true;
        p += len + (p[len] == ',');
    }
    return false;
}

void ismd_client_address(struct MHD_Connection *c, const char *trusted_proxy, char *out,
                         size_t cap)
{
    ismd_peer_address(c, out, cap);
    if (!trusted_proxy[0] || !in_address_list(trusted_proxy, out))
        return;
    const char *real = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Real-IP");
    unsigned char bin[16];
    if (real && strlen(real) < cap &&
        (inet_pton(AF_INET, real, bin) == 1 || inet_pton(AF_INET6, real, bin) == 1))
        snprintf(out, cap, "%s", real);
}

