/* own_conns.c — the own sender's connections in the connection table (own_conns.h): an entry
 * opened at accept, marked busy while an answer is sent (so that eviction at the limit takes
 * idle ones first, and the header deadline counts from the last answer), closed with the
 * connection, or passed to libmicrohttpd's notification through a per-thread slot when the
 * connection is handed over. */
#include "server/isomeshd/own_conns.h"

#include <stddef.h>

#include "server/isomeshd/client_addr.h"
#include "server/isomeshd/http_types.h"

/* The entry of the connection this thread is handing to libmicrohttpd: MHD_add_connection
 * notifies the start of the connection from the calling thread, before it returns (each
 * polling thread's daemon runs on that thread, http_loops.h), so one slot per thread holds it
 * across that call. */
static _Thread_local ismd_conn *handing_over;

void *ismd_own_opened(void *cls, int fd, const struct sockaddr *peer, bool *keep)
{
    ismd_server *s = cls;
    char addr[64];
    ismd_sockaddr_text(peer, addr, sizeof addr);
    ismd_conn *c = ismd_conns_opened(s->conns, fd, addr);
    *keep = c && !ismd_conns_cut_reason(s->conns, c); /* refused: libmicrohttpd says 503 */
    return c;
}

void ismd_own_busy(void *cls, void *conn, bool busy)
{
    ismd_server *s = cls;
    if (busy)
        ismd_conns_request(s->conns, conn, NULL, false);
    else
        ismd_conns_request_done(s->conns, conn);
}

void ismd_own_closed(void *cls, void *conn)
{
    ismd_server *s = cls;
    ismd_conns_closed(s->conns, conn);
}

void ismd_own_handing(void *cls, void *conn)
{
    ismd_server *s = cls;
    if (!conn && handing_over) /* libmicrohttpd did not take it (and closed the socket) */
        ismd_conns_closed(s->conns, handing_over);
    handing_over = conn;
}

ismd_conn *ismd_own_adopt(void)
{
    ismd_conn *c = handing_over;
    handing_over = NULL;
    return c;
}
