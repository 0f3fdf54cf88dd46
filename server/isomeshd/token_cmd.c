/* token_cmd.c — `isomeshd token add NAME`, `token remove NAME`, `token list` (token_cmd.h).
 *
 * `add` prints a new token once on standard output and writes only its hash to the file.
 * Every change rewrites the file safely: the new content goes to FILE.new, created with
 * O_EXCL (so it is also the lock against a second command at the same time), is fsync'd,
 * takes the old file's permissions, and is renamed over FILE; then the directory is fsync'd
 * (ism_replace_file_via, fd_io.h).
 * A reader (the daemon on SIGHUP) sees the old file or the new one, never half of one.
 * Comments and the order of lines are kept. A file that does not parse is left alone. */
#include "server/common/fd_io.h"
#include "server/isomeshd/token_cmd.h"

#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <sodium.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "server/isomeshd/tokens.h"

#define PATH_CAP 4096

static const char HEADER[] =
    "# isomesh bearer tokens (isomeshd --tokens FILE): one token per line,\n"
    "#   blake2b:HASH USER [jobs=N] [running=N] [admin]\n"
    "# HASH is the BLAKE2b-256 of the token; the token itself is never stored.\n"
    "# Edit with `isomeshd token add|remove`; send SIGHUP to a running isomeshd to reload.\n";

static void usage(void)
{
    fprintf(stderr,
            "usage: isomeshd token add NAME [--file FILE] [--jobs N] [--running N] [--admin]\n"
            "       isomeshd token remove NAME [--file FILE]\n"
            "       isomeshd token list [--file FILE]\n"
            "FILE defaults to $XDG_CONFIG_HOME/isomesh/tokens (else ~/.config/isomesh/tokens).\n");
}

/* The default file path; creates its directory (0700) when create is set. */
static bool default_path(char *out, size_t cap, bool create)
{
    const char *xdg = getenv("XDG_CONFIG_HOME");
    const char *home = getenv("HOME");
    char dir[PATH_CAP];
    if (xdg && *xdg == '/')
        snprintf(dir, sizeof dir, "%s/isomesh", xdg);
    else if (home && *home == '/')
        snprintf(dir, sizeof dir, "%s/.config/isomesh", home);
    else {
        fprintf(stderr, "isomeshd token: no $HOME; give --file FILE\n");
        return false;
    }
    if (create) {
        char parent[PATH_CAP];
        snprintf(parent, sizeof parent, "%s", dir);
        mkdir(dirname(parent), 0700);
        if (mkdir(dir, 0700) != 0 && errno != EEXIST) {
            fprintf(stderr, "isomeshd token: %s: %s\n", dir, strerror(errno));
            return false;
        }
    }
    if (snprintf(out, cap, "%s/tokens", dir) >= (int)cap) {
        fprintf(stderr, "isomeshd token: path too long\n");
        return false;
    }
    return true;
}

/* Reads the whole file (checked and bounded: ismd_tokens_read_file). A missing file gives an
 * empty text and *exists = false. */
static bool read_text(const char *path, char **text, size_t *len, bool *exists, mode_t *mode)
{
    char err[600];
    unsigned m = 0;
    int got = ismd_tokens_read_file(path, text, len, &m, err, sizeof err);
    *exists = got > 0;
    if (got < 0) {
        fprintf(stderr, "isomeshd token: %s\n", err);
        return false;
    }
    if (got == 0)
        *text = calloc(1, 1);
    else
        *mode = (mode_t)m;
    return *text != NULL;
}

/* One change of the file: lock (FILE.new, O_EXCL), read and check the current text, let edit
 * build the new text, write it to FILE.new, fsync, rename over FILE (ism_replace_file_via). */
typedef bool (*editor)(const char *old, size_t oldlen, const ismd_tokens *parsed, void *ctx,
                       char **out, size_t *outlen);

static int change_file(const char *path, editor edit, void *ctx)
{
    char tmp[PATH_CAP + 8];
    if (snprintf(tmp, sizeof tmp, "%s.new", path) >= (int)sizeof tmp) {
        fprintf(stderr, "isomeshd token: path too long\n");
        return 1;
    }
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
    if (fd < 0) {
        if (errno == EEXIST)
            fprintf(stderr, "isomeshd token: %s exists: another `isomeshd token` command is "
                            "changing the file (or one was interrupted: then remove %s)\n", tmp, tmp);
        else
            fprintf(stderr, "isomeshd token: %s: %s\n", tmp, strerror(errno));
        return 1;
    }
    int rc = 1;
    char *old = NULL, *text = NULL;
    size_t oldlen = 0, len = 0;
    bool exists;
    mode_t mode = 0600;
    ismd_tokens parsed = {0};
    char err[512];
    if (!read_text(path, &old, &oldlen, &exists, &mode))
        goto out;
    if (!ismd_tokens_parse(old, oldlen, path, &parsed, err, sizeof err)) {
        fprintf(stderr, "isomeshd token: %s\nfix the file first; it was not changed\n", err);
        goto out;
    }
    if (!edit(old, oldlen, &parsed, ctx, &text, &len))
        goto out;
    int locked = fd;
    fd = -1;   /* closed by the replacement, which removes tmp when it fails */
    if (!ism_replace_file_via(locked, tmp, path, text, len, mode, err, sizeof err)) {
        fprintf(stderr, "isomeshd token: %s\n", err);
        goto out;
    }
    rc = 0;
out:
    if (fd >= 0)
        close(fd);
    if (rc != 0)
        unlink(tmp);
    ismd_tokens_free(&parsed);
    if (text)
        sodium_memzero(text, len);
    free(text);
    free(old);
    return rc;
}

/* ---- add ----------------------------------------------------------------------------- */

typedef struct add_ctx {
    ismd_token_entry entry;
    bool jobs_set, running_set, admin_set;
} add_ctx;

static bool add_edit(const char *old, size_t oldlen, const ismd_tokens *parsed, void *vctx,
                     char **out, size_t *outlen)
{
    add_ctx *c = vctx;
    ismd_token_entry *e = &c->entry;
    const ismd_token_entry *same = ismd_tokens_find_user(parsed, e->user);
    if (same) { /* another token for a known user: the options must agree */
        if ((c->jobs_set && e->max_jobs != same->max_jobs) ||
            (c->running_set && e->max_running != same->max_running) ||
            (c->admin_set && e->admin != same->admin)) {
            fprintf(stderr, "isomeshd token: user '%s' already has tokens with other options; "
                            "remove them first to change the options\n", e->user);
            return false;
        }
        e->max_jobs = same->max_jobs;
        e->max_running = same->max_running;
        e->admin = same->admin;
    }
    char line[256];
    size_t n = ismd_token_line(e, line, sizeof line);
    const char *head = oldlen ? "" : HEADER;
    const char *sep = oldlen && old[oldlen - 1] != '\n' ? "\n" : "";
    size_t cap = strlen(head) + oldlen + strlen(sep) + n + 1;
    char *text = n ? malloc(cap) : NULL;
    if (!text)
        return false;
    size_t len = (size_t)snprintf(text, cap, "%s%.*s%s%s", head, (int)oldlen, old, sep, line);
    *out = text;
    *outlen = len;
    return true;
}

static bool parse_count(const char *flag, const char *v, int max, int *out)
{
    char *end;
    errno = 0;
    long n = v ? strtol(v, &end, 10) : 0;
    if (!v || !*v || errno || *end || n < 1 || n > max) {
        fprintf(stderr, "isomeshd token: %s expects a whole number from 1 to %d\n", flag, max);
        return false;
    }
    *out = (int)n;
    return true;
}

/* ---- remove -------------------------------------------------------------------------- */

typedef struct remove_ctx {
    const char *user;
    int removed;
} remove_ctx;

static bool remove_edit(const char *old, size_t oldlen, const ismd_tokens *parsed, void *vctx,
                        char **out, size_t *outlen)
{
    (void)parsed;
    remove_ctx *c = vctx;
    char *text = malloc(oldlen + 1);
    if (!text)
        return false;
    size_t len = 0, pos = 0;
    while (pos < oldlen) {
        const char *nl = memchr(old + pos, '\n', oldlen - pos);
        size_t n = nl ? (size_t)(nl - (old + pos)) + 1 : oldlen - pos;
        char user[ISMD_TOKEN_USER_MAX];
        if (ismd_token_line_user(old + pos, n, user) && !strcmp(user, c->user)) {
            c->removed++;
        } else {
            memcpy(text + len, old + pos, n);
            len += n;
        }
        pos += n;
    }
    if (!c->removed) {
        fprintf(stderr, "isomeshd token: no token of user '%s' in the file\n", c->user);
        free(text);
        return false;
    }
    *out = text;
    *outlen = len;
    return true;
}

/* ---- list ---------------------------------------------------------------------------- */

static int list_file(const char *path)
{
    ismd_tokens t;
    char err[512];
    if (!ismd_tokens_load(path, false, &t, err, sizeof err)) {
        fprintf(stderr, "isomeshd token: %s\n", err);
        return 1;
    }
    for (size_t i = 0; i < t.n; i++) {
        const ismd_token_entry *e = &t.entries[i];
        if (ismd_tokens_find_user(&t, e->user) != e)
            continue; /* one row per user */
        int count = 0;
        for (size_t j = 0; j < t.n; j++)
            count += !strcmp(t.entries[j].user, e->user);
        char jobs[16] = "default", running[16] = "default";
        if (e->max_jobs)
            snprintf(jobs, sizeof jobs, "%d", e->max_jobs);
        if (e->max_running)
            snprintf(running, sizeof running, "%d", e->max_running);
        printf("%s tokens=%d jobs=%s running=%s%s\n", e->user, count, jobs, running,
               e->admin ? " admin" : "");
    }
    ismd_tokens_free(&t);
    return 0;
}

/* ---- the command --------------------------------------------------------------------- */

int ismd_token_command(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage();
        return argc < 2 ? 2 : 0;
    }
    const char *verb = argv[1];
    bool is_add = !strcmp(verb, "add"), is_remove = !strcmp(verb, "remove"),
         is_list = !strcmp(verb, "list");
    if (!is_add && !is_remove && !is_list) {
        fprintf(stderr, "isomeshd token: unknown command '%s'\n", verb);
        usage();
        return 2;
    }
    const char *name = NULL, *file = NULL;
    add_ctx add = {0};
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--file") && v) {
            file = v, i++;
        } else if (is_add && !strcmp(a, "--jobs")) {
            if (!parse_count("--jobs", v, 100000, &add.entry.max_jobs))
                return 2;
            add.jobs_set = true, i++;
        } else if (is_add && !strcmp(a, "--running")) {
            if (!parse_count("--running", v, 256, &add.entry.max_running))
                return 2;
            add.running_set = true, i++;
        } else if (is_add && !strcmp(a, "--admin")) {
            add.entry.admin = add.admin_set = true;
        } else if (a[0] != '-' && !name && !is_list) {
            name = a;
        } else {
            fprintf(stderr, "isomeshd token: unexpected argument '%s'\n", a);
            usage();
            return 2;
        }
    }
    if (!is_list && !name) {
        usage();
        return 2;
    }
    if (name && !ismd_token_user_valid(name)) {
        fprintf(stderr, "isomeshd token: bad user name '%s' (1-48 of A-Z a-z 0-9 . _ @ -)\n", name);
        return 2;
    }
    char path[PATH_CAP];
    if (file) {
        if (!*file || snprintf(path, sizeof path, "%s", file) >= (int)sizeof path) {
            fprintf(stderr, "isomeshd token: bad --file\n");
            return 2;
        }
    } else if (!default_path(path, sizeof path, is_add)) {
        return 1;
    }
    if (is_list)
        return list_file(path);
    if (is_remove) {
        remove_ctx rc = {.user = name};
        int st = change_file(path, remove_edit, &rc);
        if (st == 0)
            fprintf(stderr, "removed %d token%s of %s from %s; send SIGHUP to a running isomeshd "
                            "to apply\n", rc.removed, rc.removed == 1 ? "" : "s", name, path);
        return st;
    }
    char token[ISMD_TOKEN_MAX];
    snprintf(add.entry.user, sizeof add.entry.user, "%s", name);
    if (!ismd_token_new(token) || !ismd_token_hash(token, strlen(token), add.entry.hash)) {
        fprintf(stderr, "isomeshd token: libsodium did not start\n");
        return 1;
    }
    int st = change_file(path, add_edit, &add);
    if (st == 0) {
        printf("%s\n", token);
        fflush(stdout);
        fprintf(stderr, "added a token for %s to %s. It is shown only this once: the file keeps "
                        "its hash.\nSend it as `Authorization: Bearer TOKEN`; send SIGHUP to a "
                        "running isomeshd to apply.\n", name, path);
    }
    sodium_memzero(token, sizeof token);
    return st;
}
