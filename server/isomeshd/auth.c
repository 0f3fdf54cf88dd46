/* auth.c — the live token table and the access policy of auth.h. */
#include "server/isomeshd/auth.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "server/common/log.h"

bool ismd_auth_init(ismd_auth *a, const char *path, bool private_mode, char *err, size_t errcap)
{
    memset(a, 0, sizeof *a);
    pthread_mutex_init(&a->lock, NULL);
    a->private_mode = private_mode;
    if (!path || !*path)
        return true;
    snprintf(a->path, sizeof a->path, "%s", path);
    if (!ismd_tokens_load(a->path, false, &a->table, err, errcap))
        return false;
    a->enabled = true;
    return true;
}

void ismd_auth_destroy(ismd_auth *a)
{
    ismd_tokens_free(&a->table);
    pthread_mutex_destroy(&a->lock);
}

static size_t count_users(const ismd_tokens *t)
{
    size_t n = 0;
    for (size_t i = 0; i < t->n; i++)
        n += ismd_tokens_find_user(t, t->entries[i].user) == &t->entries[i];
    return n;
}

bool ismd_auth_reload(ismd_auth *a)
{
    if (!a->enabled) {
        ism_logf(ISM_LOG_INFO, "reload_ignored", "SIGHUP: no --tokens file to reload");
        return false;
    }
    ismd_tokens fresh;
    char err[600];
    if (!ismd_tokens_load(a->path, false, &fresh, err, sizeof err)) {
        pthread_mutex_lock(&a->lock);
        size_t kept = a->table.n;
        pthread_mutex_unlock(&a->lock);
        ism_log_field f[] = {ISM_LS("error", err), ISM_LI("kept_tokens", kept)};
        ism_log_fields(ISM_LOG_ERROR, "tokens_reload_failed", f, 2);
        return false;
    }
    pthread_mutex_lock(&a->lock);
    ismd_tokens old = a->table;
    a->table = fresh;
    pthread_mutex_unlock(&a->lock);
    ismd_tokens_free(&old);
    ism_log_field f[] = {ISM_LS("file", a->path), ISM_LI("tokens", fresh.n),
                         ISM_LI("users", count_users(&fresh))};
    ism_log_fields(ISM_LOG_INFO, "tokens_reloaded", f, 3);
    return true;
}

/* The token of "Bearer TOKEN" (scheme case-insensitive, RFC 6750 token68 characters), or
 * NULL when the header is not a well-formed bearer credential. */
static const char *bearer_token(const char *h, size_t *len)
{
    while (*h == ' ')
        h++;
    if (strncasecmp(h, "Bearer", 6) != 0 || h[6] != ' ')
        return NULL;
    h += 7;
    while (*h == ' ')
        h++;
    size_t n = 0;
    while (h[n] && (isalnum((unsigned char)h[n]) || strchr("-._~+/", h[n])))
        n++;
    while (h[n] == '=')
        n++;
    size_t end = n;
    while (h[end] == ' ')
        end++;
    if (n == 0 || n >= ISMD_TOKEN_MAX || h[end])
        return NULL;
    *len = n;
    return h;
}

void ismd_auth_identify(ismd_auth *a, const char *authorization, const char *client,
                        ismd_identity *who)
{
    memset(who, 0, sizeof *who);
    snprintf(who->user, sizeof who->user, "%s", client);
    if (!a->enabled) {
        who->state = ISMD_AUTH_OFF;
        return;
    }
    if (!authorization) {
        who->state = ISMD_AUTH_MISSING;
        return;
    }
    size_t len = 0;
    const char *token = bearer_token(authorization, &len);
    if (!token) {
        const char *h = authorization + strspn(authorization, " ");
        bool bearer = !strncasecmp(h, "Bearer", 6) && (h[6] == ' ' || !h[6]);
        who->state = bearer ? ISMD_AUTH_INVALID : ISMD_AUTH_MISSING; /* Basic... = none */
        return;
    }
    pthread_mutex_lock(&a->lock);
    const ismd_token_entry *e = ismd_tokens_match(&a->table, token, len);
    if (e) {
        who->state = ISMD_AUTH_OK;
        snprintf(who->user, sizeof who->user, "%s", e->user);
        who->admin = e->admin;
        who->max_jobs = e->max_jobs;
        who->max_running = e->max_running;
    } else {
        who->state = ISMD_AUTH_INVALID;
    }
    pthread_mutex_unlock(&a->lock);
}

bool ismd_auth_lacking(const ismd_auth *a, const ismd_identity *who)
{
    return a->enabled && who->state != ISMD_AUTH_OK;
}

bool ismd_auth_route_needs_token(const ismd_auth *a, ismd_route route, const char *method)
{
    if (!a->enabled || !strcmp(method, "OPTIONS"))
        return false;
    switch (route) {
    case ISMD_R_MESH:
    case ISMD_R_JOBS:
    case ISMD_R_SWEEP:
    case ISMD_R_BOX:
    case ISMD_R_POINT:
        return true; /* POST computes; GET lists the caller's jobs */
    case ISMD_R_JOB:
        return !strcmp(method, "DELETE") || a->private_mode;
    case ISMD_R_HEALTHZ:
    case ISMD_R_READYZ:
    case ISMD_R_STATIC:
    case ISMD_R_VENDOR:
    case ISMD_R_OTHER:
        return false;
    default:
        return a->private_mode;
    }
}

bool ismd_auth_owns(const ismd_auth *a, const ismd_identity *who, const char *owner)
{
    if (!a->enabled)
        return true;
    return who->state == ISMD_AUTH_OK && (who->admin || !strcmp(who->user, owner));
}

const char *ismd_auth_challenge(const ismd_identity *who)
{
    return who->state == ISMD_AUTH_INVALID ? "Bearer realm=\"isomesh\", error=\"invalid_token\""
                                           : "Bearer realm=\"isomesh\"";
}
