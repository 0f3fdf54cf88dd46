/* client_addr.c — who is on the other end of a connection (client_addr.h): the peer address
 * as text, and the client a trusted reverse proxy names in X-Real-IP or X-Forwarded-For. */
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
    ismd_sockaddr_text(ci ? ci->client_addr : NULL, out, cap);
}

void ismd_sockaddr_text(const struct sockaddr *sa, char *out, size_t cap)
{
    snprintf(out, cap, "-");
    if (!sa)
        return;
    if (sa->sa_family == AF_INET)
        inet_ntop(AF_INET, &((const struct sockaddr_in *)sa)->sin_addr, out, (socklen_t)cap);
    else if (sa->sa_family == AF_INET6)
        inet_ntop(AF_INET6, &((const struct sockaddr_in6 *)sa)->sin6_addr, out, (socklen_t)cap);
}

bool ismd_address_listed(const char *list, const char *addr)
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

/* Is the n bytes at s an IPv4 or IPv6 literal? Copied (terminated) into out when it is. */
static bool ip_literal(const char *s, size_t n, char *out, size_t cap)
{
    char text[64];
    unsigned char bin[16];
    if (n == 0 || n >= sizeof text || n >= cap)
        return false;
    memcpy(text, s, n);
    text[n] = 0;
    if (inet_pton(AF_INET, text, bin) != 1 && inet_pton(AF_INET6, text, bin) != 1)
        return false;
    memcpy(out, text, n + 1);
    return true;
}

/* X-Forwarded-For "client, proxy1, proxy2": each proxy appends the address it was reached
 * from, so only the entries right of the last untrusted one were written by trusted proxies.
 * Walks from the right over trusted proxies; the first other entry is the client (out
 * unchanged when an entry is not an IP literal: it may be forged, and so may all left of it). */
static void forwarded_for(const char *xff, const char *trusted, char *out, size_t cap)
{
    const char *end = xff + strlen(xff);
    while (end > xff) {
        const char *start = end;
        while (start > xff && start[-1] != ',')
            start--;
        const char *a = start, *b = end;
        while (a < b && (*a == ' ' || *a == '\t'))
            a++;
        while (b > a && (b[-1] == ' ' || b[-1] == '\t'))
            b--;
        char addr[64];
        if (!ip_literal(a, (size_t)(b - a), addr, sizeof addr))
            return;
        snprintf(out, cap, "%s", addr);
        if (!ismd_address_listed(trusted, addr))
            return;
        end = start > xff ? start - 1 : xff;
    }
}

void ismd_client_address(struct MHD_Connection *c, const char *peer, const char *trusted_proxy,
                         char *out, size_t cap)
{
    if (peer && cap) { /* a copy, not snprintf: this runs for every request */
        size_t n = strnlen(peer, cap - 1);
        memcpy(out, peer, n);
        out[n] = 0;
    } else
        ismd_peer_address(c, out, cap);
    if (!trusted_proxy[0] || !ismd_address_listed(trusted_proxy, out))
        return;
    const char *real = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Real-IP");
    if (real && ip_literal(real, strlen(real), out, cap))
        return;
    const char *xff = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Forwarded-For");
    if (xff)
        forwarded_for(xff, trusted_proxy, out, cap);
}

