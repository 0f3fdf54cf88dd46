/* lexer.c — the tokeniser: numbers (1, 1.5, .5, 1e-3), names, operators and punctuation,
 * with line and column tracking and a precise message for anything it cannot read. */
#include "core/expr/lexer.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ism_lexer_init(ism_lexer *lx, const char *src, size_t len, locale_t c_locale)
{
    memset(lx, 0, sizeof *lx);
    lx->src = src;
    lx->len = len;
    lx->line = 1;
    lx->column = 1;
    lx->c_locale = c_locale;
}

static int peek(const ism_lexer *lx, size_t ahead)
{
    return lx->pos + ahead < lx->len ? (unsigned char)lx->src[lx->pos + ahead] : -1;
}

static void advance(ism_lexer *lx)
{
    if (lx->src[lx->pos] == '\n') {
        lx->line++;
        lx->column = 1;
    } else {
        lx->column++;
    }
    lx->pos++;
}

static void skip_space(ism_lexer *lx)
{
    int c;
    while ((c = peek(lx, 0)) == ' ' || c == '\t' || c == '\n' || c == '\r')
        advance(lx);
}

static ism_token bad(ism_lexer *lx, ism_token t, const char *fmt, const char *arg)
{
    t.kind = ISM_T_BAD;
    snprintf(lx->message, sizeof lx->message, fmt, arg);
    return t;
}

static size_t count_digits(const ism_lexer *lx, size_t from)
{
    size_t k = 0;
    while (lx->pos + from + k < lx->len && isdigit((unsigned char)lx->src[lx->pos + from + k]))
        k++;
    return k;
}

static ism_token lex_number(ism_lexer *lx, ism_token t)
{
    size_t k = count_digits(lx, 0);
    if (peek(lx, k) == '.')
        k += 1 + count_digits(lx, k + 1);
    if (peek(lx, k) == 'e' || peek(lx, k) == 'E') {
        size_t e = k + 1;
        if (peek(lx, e) == '+' || peek(lx, e) == '-')
            e++;
        size_t d = count_digits(lx, e);
        if (d == 0) {
            char shown[40];
            snprintf(shown, sizeof shown, "%.*s", (int)(e < 32 ? e : 32), lx->src + lx->pos);
            return bad(lx, t, "malformed number '%s': the exponent needs digits", shown);
        }
        k = e + d;
    }
    if (isalpha(peek(lx, k)) || peek(lx, k) == '_' || peek(lx, k) == '.') {
        char shown[40];
        snprintf(shown, sizeof shown, "%.*s", (int)(k + 1 < 32 ? k + 1 : 32), lx->src + lx->pos);
        return bad(lx, t, "malformed number '%s' (write 2*x, not 2x)", shown);
    }
    char buf[64];
    if (k >= sizeof buf)
        return bad(lx, t, "number %s is too long (at most 63 characters)", "");
    memcpy(buf, lx->src + lx->pos, k);
    buf[k] = '\0';
    t.number = strtod_l(buf, NULL, lx->c_locale);
    t.text = lx->src + lx->pos;
    t.len = k;
    if (!isfinite(t.number))
        return bad(lx, t, "number %s is too large", buf);
    for (size_t i = 0; i < k; i++)
        advance(lx);
    t.kind = ISM_T_NUM;
    return t;
}

static ism_token lex_name(ism_lexer *lx, ism_token t)
{
    size_t k = 0;
    int c;
    while ((c = peek(lx, k)) != -1 && (isalnum(c) || c == '_'))
        k++;
    t.text = lx->src + lx->pos;
    t.len = k;
    if (k > ISM_NAME_MAX) {
        char shown[24];
        snprintf(shown, sizeof shown, "%.16s", t.text);
        return bad(lx, t, "name '%s...' is too long (at most 63 characters)", shown);
    }
    for (size_t i = 0; i < k; i++)
        advance(lx);
    t.kind = ISM_T_NAME;
    return t;
}

ism_token ism_lexer_next(ism_lexer *lx)
{
    skip_space(lx);
    ism_token t = { .kind = ISM_T_END, .line = lx->line, .column = lx->column,
                    .end_line = lx->line, .text = lx->src + lx->pos, .len = 0, .number = 0 };
    int c = peek(lx, 0);
    if (c == -1)
        return t;
    if (isdigit(c) || (c == '.' && isdigit(peek(lx, 1))))
        return lex_number(lx, t);
    if (isalpha(c) || c == '_')
        return lex_name(lx, t);
    static const char singles[] = "+-*/^(),;=";
    static const int kinds[] = { ISM_T_PLUS, ISM_T_MINUS, ISM_T_STAR, ISM_T_SLASH, ISM_T_CARET,
                                 ISM_T_LPAREN, ISM_T_RPAREN, ISM_T_COMMA, ISM_T_SEMI,
                                 ISM_T_ASSIGN };
    const char *hit = c ? strchr(singles, c) : NULL;
    if (hit) {
        t.kind = kinds[hit - singles];
        t.len = 1;
        advance(lx);
        return t;
    }
    char shown[16];
    if (c >= 0x21 && c < 0x7f)
        snprintf(shown, sizeof shown, "'%c'", c);
    else
        snprintf(shown, sizeof shown, "byte 0x%02X", (unsigned)c);
    return bad(lx, t, "unexpected character %s", shown);
}

void ism_token_describe(const ism_token *t, char *buf, size_t n)
{
    switch (t->kind) {
    case ISM_T_END: snprintf(buf, n, "the end of the expression"); break;
    case ISM_T_NUM: snprintf(buf, n, "number %.*s", (int)(t->len < 24 ? t->len : 24), t->text); break;
    case ISM_T_NAME: snprintf(buf, n, "name '%.*s'", (int)t->len, t->text); break;
    default: snprintf(buf, n, "'%.*s'", (int)(t->len ? t->len : 1), t->text); break;
    }
}
