/* request_error.c — request errors: setting one (the path leads its message) and the error
 * document every non-200 answer carries:
 * {"error": {"code": "...", "message": "...", "path": "$.x", "line": L, "column": C}}
 * (path, line and column only when known; "max_error_that_fits": E on a too_big answer
 * under a bound, when one was found). */
#include "proto/request.h"
#include "proto/json_writer.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Length of the valid UTF-8 sequence starting at s (1 to 4), or 0 when none starts there
 * (a stray continuation byte, an overlong form, a surrogate, above U+10FFFF, cut short). */
static size_t utf8_sequence(const unsigned char *s)
{
    unsigned c = s[0];
    if (c < 0x80)
        return 1;
    if (c < 0xc2 || c > 0xf4)
        return 0;
    size_t n = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : 2;
    for (size_t i = 1; i < n; i++)
        if ((s[i] & 0xc0) != 0x80) /* also stops at the terminating NUL */
            return 0;
    if ((c == 0xe0 && s[1] < 0xa0) || (c == 0xed && s[1] > 0x9f) ||
        (c == 0xf0 && s[1] < 0x90) || (c == 0xf4 && s[1] > 0x8f))
        return 0;
    return n;
}

/* Replaces each byte that is not part of valid UTF-8 by '?': messages quote the client's
 * bytes (jansson's "near '...'", JSON keys in paths) and cutting a message or a path short
 * can split a character, but the error document must stay valid JSON text. */
static void utf8_repair(char *s)
{
    unsigned char *p = (unsigned char *)s;
    while (*p) {
        size_t n = utf8_sequence(p);
        if (n)
            p += n;
        else
            *p++ = '?';
    }
}

bool ism_req_error_set(ism_req_error *err, int status, const char *code, const char *path,
                       const char *fmt, ...)
{
    if (!err)
        return false;
    memset(err, 0, sizeof *err);
    err->status = status;
    snprintf(err->code, sizeof err->code, "%s", code);
    snprintf(err->path, sizeof err->path, "%s", path ? path : "");
    char reason[sizeof err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    size_t at = 0, cap = sizeof err->message - 1;
    if (err->path[0]) {
        for (const char *s = err->path; *s && at < cap; s++)
            err->message[at++] = *s;
        for (const char *s = ": "; *s && at < cap; s++)
            err->message[at++] = *s;
    }
    for (const char *s = reason; *s && at < cap; s++)
        err->message[at++] = *s;
    err->message[at] = '\0';
    utf8_repair(err->path);
    utf8_repair(err->message);
    return false;
}

char *ism_req_error_json(const ism_req_error *err, size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "error");
    ism_jw_object(&w);
    ism_jw_key(&w, "code");
    ism_jw_string(&w, err->code[0] ? err->code : "internal");
    ism_jw_key(&w, "message");
    ism_jw_string(&w, err->message);
    if (err->path[0]) {
        ism_jw_key(&w, "path");
        ism_jw_string(&w, err->path);
    }
    if (err->line > 0) {
        ism_jw_key(&w, "line");
        ism_jw_int(&w, err->line);
    }
    if (err->column > 0) {
        ism_jw_key(&w, "column");
        ism_jw_int(&w, err->column);
    }
    if (err->max_error_that_fits > 0) {
        ism_jw_key(&w, "max_error_that_fits");
        ism_jw_number(&w, err->max_error_that_fits);
    }
    ism_jw_object_end(&w);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}
