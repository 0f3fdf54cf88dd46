/* errors.h — the daemon's error bodies, always JSON of one shape:
 * {"error": {"code": "...", "message": "...", "path": "..."}} (path or column only when known).
 * The codes are stable identifiers for scripts; the messages are for people. */
#ifndef ISMD_ERRORS_H
#define ISMD_ERRORS_H

#include "server/common/blob.h"

/* A new error body; path may be NULL. Never NULL unless out of memory. */
ism_blob *ismd_error_json(const char *code, const char *message, const char *path);

#endif
