/* own_sender.h — isomeshd's hooks for its own sender (server/common/http_front.h,
 * --own-sender): cached mesh GETs answered with the header block held back, then sendfile. */
#ifndef ISMD_OWN_SENDER_H
#define ISMD_OWN_SENDER_H

#include "server/common/http_front.h"
#include "server/isomeshd/http_types.h"

/* http_front.h's answer hook; cls is the ismd_server. */
bool ismd_own_answer(void *cls, const char *head, size_t len, void *conn, ism_front_answer *a);
/* http_front.h's done hook: the log line and metrics, the file and the body released. */
void ismd_own_done(void *cls, ism_front_answer *a, bool sent);

#endif
