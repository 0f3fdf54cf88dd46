/* auth.h — who is asking: bearer-token access control for isomeshd (--tokens FILE,
 * --private). Holds the live token table (tokens.h), swapped whole on reload (SIGHUP) so a
 * request sees either the old table or the new one; a file that does not parse keeps the old
 * table. Turns an Authorization header into an identity (the token's user, or the client
 * address when tokens are off) and says which routes need one.
 *
 * Policy: with tokens, computing needs a valid token — POST /v1/mesh, POST /v1/jobs, a GET of
 * a known mesh in a format not computed yet — and so do listing and canceling jobs. Reading
 * what is already computed (meshes by key, stats, features, job state), presets, documents,
 * /metrics and the viewer stay open, unless --private: then everything but /healthz, /readyz
 * and the viewer's own files (which must load to ask for a token) needs one. */
#ifndef ISMD_AUTH_H
#define ISMD_AUTH_H

#include <pthread.h>
#include <stdbool.h>

#include "server/isomeshd/metrics.h"
#include "server/isomeshd/tokens.h"

#define ISMD_USER_MAX 64

typedef enum ismd_auth_state {
    ISMD_AUTH_OFF,       /* no --tokens: the client address is the user */
    ISMD_AUTH_MISSING,   /* tokens on, no Authorization header (or not a bearer one) */
    ISMD_AUTH_INVALID,   /* a bearer token that matches no line of the file */
    ISMD_AUTH_OK,        /* a valid token */
} ismd_auth_state;

typedef struct ismd_identity {
    ismd_auth_state state;
    char user[ISMD_USER_MAX]; /* token's user, or the client address */
    bool admin;
    int max_jobs, max_running; /* from the tokens file; 0 = the flags' defaults */
} ismd_identity;

typedef struct ismd_auth {
    bool enabled, private_mode;
    char path[4096];
    pthread_mutex_t lock;     /* guards table (swap on reload, lookups) */
    ismd_tokens table;
} ismd_auth;

/* path NULL or "" = tokens off. Loads the file; false (err filled) when it cannot be read
 * or parsed — the daemon does not start with a broken tokens file. */
bool ismd_auth_init(ismd_auth *a, const char *path, bool private_mode, char *err, size_t errcap);
void ismd_auth_destroy(ismd_auth *a);

/* Re-reads the file into a new table and swaps it in; a bad file keeps the old table.
 * Logs the outcome either way. True when the new table is in use. */
bool ismd_auth_reload(ismd_auth *a);

/* Fills who from an Authorization header value (may be NULL) and the client address. */
void ismd_auth_identify(ismd_auth *a, const char *authorization, const char *client,
                        ismd_identity *who);

/* True when tokens are on and who has no valid one. */
bool ismd_auth_lacking(const ismd_auth *a, const ismd_identity *who);

/* Does this route (with this method) need a valid token before anything else happens? */
bool ismd_auth_route_needs_token(const ismd_auth *a, ismd_route route, const char *method);

/* May who see or cancel a job started by owner? (tokens off: anyone; on: its owner or an
 * admin.) */
bool ismd_auth_owns(const ismd_auth *a, const ismd_identity *who, const char *owner);

/* The WWW-Authenticate value for a 401 answer to who. */
const char *ismd_auth_challenge(const ismd_identity *who);

#endif
