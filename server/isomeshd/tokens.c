/* tokens.c — the bearer tokens file of tokens.h: line parser with file:line errors, bounded
 * file reading, constant-time matching, token generation and hashing with libsodium.
 *
 * Why a fast hash (BLAKE2b-256) and not a password hash (Argon2, scrypt): the tokens are made
 * here from 256 random bits, never chosen by people. Slow hashes exist to make guessing
 * low-entropy passwords expensive; against 2^256 possibilities guessing is hopeless at any
 * speed, so slowness would buy nothing and would cost ~100 ms of CPU on every request in the
 * HTTP thread (a denial-of-service lever). A preimage-resistant hash is what keeps a stolen
 * tokens file from giving away the tokens, and BLAKE2b is one. */
#include "server/isomeshd/tokens.h"
#include "server/common/fd_io.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdarg.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define HASH_PREFIX "blake2b:"
#define TOKEN_PREFIX "ism_"
#define TOKEN_RANDOM_BYTES 32
#define LINE_MAX_CHARS 512
#define OPT_JOBS_MAX 100000
#define OPT_RUNNING_MAX 256

bool ismd_token_user_valid(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= ISMD_TOKEN_USER_MAX)
        return false;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (!isalnum(c) && c != '.' && c != '_' && c != '@' && c != '-')
            return false;
    }
    return true;
}

static bool sodium_ready(void)
{
    return sodium_init() >= 0;
}

bool ismd_token_hash(const char *token, size_t len, unsigned char out[ISMD_TOKEN_HASH_BYTES])
{
    return sodium_ready() &&
           crypto_generichash(out, ISMD_TOKEN_HASH_BYTES, (const unsigned char *)token, len,
                              NULL, 0) == 0;
}

bool ismd_token_new(char out[ISMD_TOKEN_MAX])
{
    if (!sodium_ready())
        return false;
    unsigned char rnd[TOKEN_RANDOM_BYTES];
    randombytes_buf(rnd, sizeof rnd);
    size_t plen = strlen(TOKEN_PREFIX);
    memcpy(out, TOKEN_PREFIX, plen);
    sodium_bin2base64(out + plen, ISMD_TOKEN_MAX - plen, rnd, sizeof rnd,
                      sodium_base64_VARIANT_URLSAFE_NO_PADDING);
    sodium_memzero(rnd, sizeof rnd);
    return true;
}

size_t ismd_token_line(const ismd_token_entry *e, char *buf, size_t cap)
{
    char hex[2 * ISMD_TOKEN_HASH_BYTES + 1];
    sodium_bin2hex(hex, sizeof hex, e->hash, sizeof e->hash);
    char opts[64] = "";
    size_t o = 0;
    if (e->max_jobs)
        o += (size_t)snprintf(opts + o, sizeof opts - o, " jobs=%d", e->max_jobs);
    if (e->max_running)
        o += (size_t)snprintf(opts + o, sizeof opts - o, " running=%d", e->max_running);
    if (e->admin)
        snprintf(opts + o, sizeof opts - o, " admin");
    int n = snprintf(buf, cap, "%s%s %s%s\n", HASH_PREFIX, hex, e->user, opts);
    return n > 0 && (size_t)n < cap ? (size_t)n : 0;
}

/* ---- parsing ------------------------------------------------------------------------- */

typedef struct parser {
    const char *path;
    int line;
    char *err;
    size_t errcap;
} parser;

static bool fail(parser *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static bool fail(parser *p, const char *fmt, ...)
{
    char what[160];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(p->err, p->errcap, "%s:%d: %s", p->path, p->line, what);
    return false;
}

static bool parse_int_opt(const char *v, int max, int *out)
{
    if (!*v || !isdigit((unsigned char)*v))
        return false;
    char *end;
    errno = 0;
    long n = strtol(v, &end, 10);
    if (errno || *end || n < 1 || n > max)
        return false;
    *out = (int)n;
    return true;
}

static bool parse_hash(const char *word, unsigned char out[ISMD_TOKEN_HASH_BYTES])
{
    size_t plen = strlen(HASH_PREFIX);
    if (strncmp(word, HASH_PREFIX, plen) != 0 || strlen(word + plen) != 2 * ISMD_TOKEN_HASH_BYTES)
        return false;
    for (const char *c = word + plen; *c; c++)
        if (!isxdigit((unsigned char)*c))
            return false;
    size_t got = 0;
    return sodium_hex2bin(out, ISMD_TOKEN_HASH_BYTES, word + plen, 2 * ISMD_TOKEN_HASH_BYTES,
                          NULL, &got, NULL) == 0 &&
           got == ISMD_TOKEN_HASH_BYTES;
}

/* Splits line (modified) at blanks into at most max words. */
static size_t split_words(char *line, char **words, size_t max)
{
    size_t n = 0;
    char *p = line;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
            p++;
        if (!*p)
            return n;
        if (n == max)
            return max + 1;
        words[n++] = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r' && *p != '\n')
            p++;
        if (*p)
            *p++ = 0;
    }
}

static bool parse_line(parser *p, char *line, ismd_token_entry *e)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = 0;
    for (char *c = line; *c; c++)
        if ((unsigned char)*c < 0x20 && *c != '\t')
            return fail(p, "control character in the line");
    char *w[8];
    size_t nw = split_words(line, w, 6);
    if (nw == 0)
        return true; /* blank or comment: e->user stays "" */
    if (nw > 5)
        return fail(p, "too many fields (expected HASH USER [jobs=N] [running=N] [admin])");
    if (nw < 2)
        return fail(p, "expected HASH USER [jobs=N] [running=N] [admin]");
    if (!parse_hash(w[0], e->hash))
        return fail(p, "expected blake2b:<64 hex digits> as the hash, got '%.40s'", w[0]);
    if (!ismd_token_user_valid(w[1]))
        return fail(p, "bad user name '%.60s' (1-48 of A-Z a-z 0-9 . _ @ -)", w[1]);
    snprintf(e->user, sizeof e->user, "%s", w[1]);
    for (size_t i = 2; i < nw; i++) {
        if (!strncmp(w[i], "jobs=", 5)) {
            if (!parse_int_opt(w[i] + 5, OPT_JOBS_MAX, &e->max_jobs))
                return fail(p, "bad value in '%.40s' (a whole number from 1 to 100000)", w[i]);
        } else if (!strncmp(w[i], "running=", 8)) {
            if (!parse_int_opt(w[i] + 8, OPT_RUNNING_MAX, &e->max_running))
                return fail(p, "bad value in '%.40s' (a whole number from 1 to 256)", w[i]);
        } else if (!strcmp(w[i], "admin")) {
            e->admin = true;
        } else {
            return fail(p, "unknown option '%.40s' (jobs=N, running=N or admin)", w[i]);
        }
    }
    return true;
}

bool ismd_token_line_user(const char *line, size_t n, char user[ISMD_TOKEN_USER_MAX])
{
    char copy[LINE_MAX_CHARS + 1];
    if (n > LINE_MAX_CHARS)
        return false;
    memcpy(copy, line, n);
    copy[n] = 0;
    char *hash = strchr(copy, '#');
    if (hash)
        *hash = 0;
    char *w[3];
    size_t nw = split_words(copy, w, 2);
    if (nw < 2 || strlen(w[1]) >= ISMD_TOKEN_USER_MAX)
        return false;
    strcpy(user, w[1]);
    return true;
}

/* Rejects a repeated hash and a user whose lines disagree on options. */
static bool check_entry(parser *p, const ismd_tokens *t, const ismd_token_entry *e)
{
    for (size_t i = 0; i < t->n; i++) {
        const ismd_token_entry *o = &t->entries[i];
        if (!memcmp(o->hash, e->hash, sizeof e->hash))
            return fail(p, "this hash is already on an earlier line");
        if (!strcmp(o->user, e->user) &&
            (o->max_jobs != e->max_jobs || o->max_running != e->max_running || o->admin != e->admin))
            return fail(p, "user '%s' has different options on an earlier line", e->user);
    }
    return true;
}

bool ismd_tokens_parse(const char *text, size_t len, const char *path, ismd_tokens *out,
                       char *err, size_t errcap)
{
    parser p = {.path = path, .err = err, .errcap = errcap};
    ismd_tokens t = {0};
    size_t cap = 0;
    bool ok = true;
    size_t pos = 0;
    while (ok && pos < len) {
        p.line++;
        const char *nl = memchr(text + pos, '\n', len - pos);
        size_t n = nl ? (size_t)(nl - (text + pos)) : len - pos;
        if (n > LINE_MAX_CHARS) {
            ok = fail(&p, "line too long");
            break;
        }
        char line[LINE_MAX_CHARS + 1];
        memcpy(line, text + pos, n);
        line[n] = 0;
        pos += n + 1;
        if (memchr(line, 0, n)) {
            ok = fail(&p, "NUL byte in the line");
            break;
        }
        if (n && line[n - 1] == '\r')
            line[n - 1] = 0;
        ismd_token_entry e = {0};
        if (!(ok = parse_line(&p, line, &e)) || !e.user[0])
            continue;
        if (!(ok = check_entry(&p, &t, &e)))
            break;
        if (t.n == ISMD_TOKENS_MAX_ENTRIES) {
            ok = fail(&p, "more than 4096 tokens");
            break;
        }
        if (t.n == cap) {
            size_t ncap = cap ? cap * 2 : 16;
            ismd_token_entry *ne = realloc(t.entries, ncap * sizeof *ne);
            if (!ne) {
                ok = fail(&p, "out of memory");
                break;
            }
            t.entries = ne;
            cap = ncap;
        }
        t.entries[t.n++] = e;
    }
    if (!ok) {
        ismd_tokens_free(&t);
        return false;
    }
    *out = t;
    return true;
}

/* Opening never blocks (a FIFO or device put at the path would hang the reader: the daemon
 * re-reads on SIGHUP in the thread that also takes SIGTERM), and the checks are made on the
 * opened file itself (fstat), so a path swapped between a check and the open cannot slip by.
 * Symbolic links are followed: secret stores (Kubernetes volumes) publish files as links;
 * what is checked is the file they lead to. */
int ismd_tokens_read_file(const char *path, char **text, size_t *len, unsigned *mode,
                          char *err, size_t errcap)
{
    int rc = ism_read_file(path, ISMD_TOKENS_FILE_MAX, text, len, mode, err, errcap);
    if (rc == 1 && (*mode & (S_IWGRP | S_IWOTH))) {
        free(*text);
        *text = NULL;
        *len = 0;
        snprintf(err, errcap, "%s: writable by group or others: anyone who can write it can "
                 "give themselves a token (chmod go-w it)", path);
        return -1;
    }
    return rc;
}

bool ismd_tokens_load(const char *path, bool missing_ok, ismd_tokens *out, char *err,
                      size_t errcap)
{
    memset(out, 0, sizeof *out);
    char *text;
    size_t len;
    unsigned mode;
    int got = ismd_tokens_read_file(path, &text, &len, &mode, err, errcap);
    if (got == 0 && !missing_ok)
        snprintf(err, errcap, "%s: %s", path, strerror(ENOENT));
    if (got <= 0)
        return got == 0 && missing_ok;
    bool ok = ismd_tokens_parse(text, len, path, out, err, errcap);
    free(text);
    return ok;
}

void ismd_tokens_free(ismd_tokens *t)
{
    free(t->entries);
    t->entries = NULL;
    t->n = 0;
}

const ismd_token_entry *ismd_tokens_match(const ismd_tokens *t, const char *token, size_t len)
{
    unsigned char h[ISMD_TOKEN_HASH_BYTES];
    if (!ismd_token_hash(token, len, h))
        return NULL;
    const ismd_token_entry *found = NULL;
    for (size_t i = 0; i < t->n; i++) {
        bool same = sodium_memcmp(t->entries[i].hash, h, sizeof h) == 0;
        /* no early exit: every entry is compared whatever happened before */
        found = same && !found ? &t->entries[i] : found;
    }
    sodium_memzero(h, sizeof h);
    return found;
}

const ismd_token_entry *ismd_tokens_find_user(const ismd_tokens *t, const char *user)
{
    for (size_t i = 0; i < t->n; i++)
        if (!strcmp(t->entries[i].user, user))
            return &t->entries[i];
    return NULL;
}
