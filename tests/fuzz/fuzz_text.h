/* fuzz_text.h — the text layout shared by the expression and polygoniser fuzz targets: one
 * fuzz input becomes an expression with parameters and lets, so that every mutation is a
 * request a client could send.
 *
 *   $name=1.5        a parameter (value read with strtod: nan, inf, 1e999 all reach the API)
 *   @name=source     a let binding, in order
 *   anything else    a line of the main expression (inline `let NAME = ...` lines included)
 *
 * Up to FUZZ_TEXT_MAX_ITEMS parameters and lets each: more than the compiler's limits (64),
 * so the limit errors stay reachable. */
#ifndef ISM_FUZZ_TEXT_H
#define ISM_FUZZ_TEXT_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "core/expr/expr.h"

#define FUZZ_TEXT_MAX_ITEMS 80

typedef struct fuzz_text {
    char *buf;    /* the input, NUL-terminated and split in place (names, let sources) */
    char *expr;   /* the main expression: the other lines joined with '\n' */
    ism_param params[FUZZ_TEXT_MAX_ITEMS];
    size_t nparams;
    ism_let lets[FUZZ_TEXT_MAX_ITEMS];
    size_t nlets;
} fuzz_text;

/* "name=rest" split at the first '=' (no '=': the whole line is the name, rest is ""). */
static inline char *fuzz_text_split(char *line)
{
    char *eq = strchr(line, '=');
    if (!eq)
        return line + strlen(line);
    *eq = '\0';
    return eq + 1;
}

/* False when out of memory. Free with fuzz_text_free. */
static inline int fuzz_text_parse(fuzz_text *t, const uint8_t *data, size_t size)
{
    memset(t, 0, sizeof *t);
    t->buf = malloc(size + 1);
    t->expr = malloc(size + 1);
    if (!t->buf || !t->expr) {
        free(t->buf);
        free(t->expr);
        return 0;
    }
    if (size)
        memcpy(t->buf, data, size);
    t->buf[size] = '\0';
    size_t elen = 0;
    char *line = t->buf;
    for (;;) {
        char *nl = strchr(line, '\n');
        if (nl)
            *nl = '\0';
        if (line[0] == '$' && t->nparams < FUZZ_TEXT_MAX_ITEMS) {
            char *value = fuzz_text_split(line + 1);
            t->params[t->nparams].name = line + 1;
            t->params[t->nparams].value = strtod(value, NULL);
            t->nparams++;
        } else if (line[0] == '@' && t->nlets < FUZZ_TEXT_MAX_ITEMS) {
            char *source = fuzz_text_split(line + 1);
            t->lets[t->nlets].name = line + 1;
            t->lets[t->nlets].source = source;
            t->nlets++;
        } else {
            size_t n = strlen(line);
            if (elen)
                t->expr[elen++] = '\n';
            memcpy(t->expr + elen, line, n);
            elen += n;
        }
        if (!nl)
            break;
        line = nl + 1;
    }
    t->expr[elen] = '\0';
    return 1;
}

static inline void fuzz_text_free(fuzz_text *t)
{
    free(t->buf);
    free(t->expr);
    memset(t, 0, sizeof *t);
}

#endif
