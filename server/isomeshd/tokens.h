/* tokens.h — the bearer tokens file: its format, parsing into a table, the constant-time
 * match of a presented token against the table, and new tokens with their hashes.
 *
 * The file holds one token per line, never the token itself, only its hash:
 *
 *     # HASH                                                            USER   OPTIONS
 *     blake2b:9f0c...64 hex digits...                                   alice  jobs=8 running=2
 *     blake2b:41d7...                                                   bob    admin
 *
 * USER is 1-48 of [A-Za-z0-9._@-] (it names the user in logs, job lists and metrics labels).
 * Options: jobs=N (computations queued or running before 429), running=N (computing at once),
 * admin (sees every job). A user may have several lines (several tokens, e.g. a laptop and a
 * script); their options must then agree. `#` starts a comment; blank lines are skipped. */
#ifndef ISMD_TOKENS_H
#define ISMD_TOKENS_H

#include <stdbool.h>
#include <stddef.h>

#define ISMD_TOKEN_HASH_BYTES 32
#define ISMD_TOKEN_MAX 128        /* longest token accepted from a client, NUL included */
#define ISMD_TOKEN_USER_MAX 49    /* user name, NUL included */
#define ISMD_TOKENS_FILE_MAX (1u << 20)
#define ISMD_TOKENS_MAX_ENTRIES 4096

typedef struct ismd_token_entry {
    unsigned char hash[ISMD_TOKEN_HASH_BYTES];
    char user[ISMD_TOKEN_USER_MAX];
    int max_jobs, max_running;  /* 0 = the daemon's defaults (--user-jobs, --user-running) */
    bool admin;
} ismd_token_entry;

typedef struct ismd_tokens {
    ismd_token_entry *entries;
    size_t n;
} ismd_tokens;

/* Parses a whole file's text. On error fills err ("PATH:LINE: what") and returns false
 * (out is left empty). */
bool ismd_tokens_parse(const char *text, size_t len, const char *path, ismd_tokens *out,
                       char *err, size_t errcap);
/* Reads a whole tokens file without ever blocking: it must be a regular file (a FIFO or
 * device is refused), not writable by group or others, of at most ISMD_TOKENS_FILE_MAX bytes.
 * 1: *text (malloc'd, NUL-terminated), *len and *mode (permission bits) are set; 0: there is
 * no such file; -1: refused or unreadable, err says why ("PATH: what"). */
int ismd_tokens_read_file(const char *path, char **text, size_t *len, unsigned *mode,
                          char *err, size_t errcap);
/* Reads and parses path (bounded by ISMD_TOKENS_FILE_MAX). A missing file is an error unless
 * missing_ok, which gives an empty table. */
bool ismd_tokens_load(const char *path, bool missing_ok, ismd_tokens *out, char *err,
                      size_t errcap);
void ismd_tokens_free(ismd_tokens *t);

/* The entry whose hash is the hash of token (len bytes), or NULL. Every entry is compared with
 * sodium_memcmp and the scan never stops early, so the time taken does not depend on which
 * entry (if any) matched or on how many bytes of a hash agreed. */
const ismd_token_entry *ismd_tokens_match(const ismd_tokens *t, const char *token, size_t len);

/* The first entry of user, or NULL. */
const ismd_token_entry *ismd_tokens_find_user(const ismd_tokens *t, const char *user);

/* The user named on one line of the file (false for a blank or comment line, or a line without
 * a second field). Used to edit the file line by line, keeping comments. */
bool ismd_token_line_user(const char *line, size_t n, char user[ISMD_TOKEN_USER_MAX]);

/* True when s is a valid user name. */
bool ismd_token_user_valid(const char *s);

/* A new random token ("ism_" + 43 base64url characters: 256 bits from libsodium). */
bool ismd_token_new(char out[ISMD_TOKEN_MAX]);
/* BLAKE2b-256 of the token's bytes. */
bool ismd_token_hash(const char *token, size_t len, unsigned char out[ISMD_TOKEN_HASH_BYTES]);
/* The file line for e, with a trailing newline. Returns its length (0 if it does not fit). */
size_t ismd_token_line(const ismd_token_entry *e, char *buf, size_t cap);

#endif
