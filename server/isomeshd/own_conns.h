/* own_conns.h — the connections isomeshd's own sender holds (--own-sender, http_front.h) in
 * the connection table (conns.h), like libmicrohttpd's: admitted, refused or evicted by the
 * same limits (--max-connections, --client-conns), counted in isomesh_connections, and handed
 * to libmicrohttpd with their entry (never counted twice, never let in a second time). */
#ifndef ISMD_OWN_CONNS_H
#define ISMD_OWN_CONNS_H

#include <stdbool.h>
#include <sys/socket.h>

#include "server/isomeshd/conns.h"

/* http_front.h's connection hooks; cls is the ismd_server. */
void *ismd_own_opened(void *cls, int fd, const struct sockaddr *peer, bool *keep);
void ismd_own_busy(void *cls, void *conn, bool busy);
void ismd_own_closed(void *cls, void *conn);
void ismd_own_handing(void *cls, void *conn);

/* In libmicrohttpd's connection notification: the entry of the connection this thread is
 * handing over now (taken: called once), or NULL when libmicrohttpd accepted it itself. */
ismd_conn *ismd_own_adopt(void);

#endif
