/* lexer.h — splits an expression source into tokens, each with its 1-based line and
 * column. Internal to core/expr. */
#ifndef ISM_LEXER_H
#define ISM_LEXER_H

#include <stddef.h>
#include <locale.h>

enum ism_tok {
    ISM_T_END, ISM_T_NUM, ISM_T_NAME, ISM_T_PLUS, ISM_T_MINUS, ISM_T_STAR, ISM_T_SLASH,
    ISM_T_CARET, ISM_T_LPAREN, ISM_T_RPAREN, ISM_T_COMMA, ISM_T_SEMI, ISM_T_ASSIGN,
    ISM_T_BAD      /* a lexical error; the lexer's message says what */
};

#define ISM_NAME_MAX 63

typedef struct ism_token {
    int kind;
    int line, column;      /* where the token starts */
    int end_line;          /* line of its last character */
    const char *text;      /* points into the source */
    size_t len;
    double number;         /* ISM_T_NUM */
} ism_token;

typedef struct ism_lexer {
    const char *src;
    size_t pos, len;
    int line, column;
    locale_t c_locale;     /* for strtod_l: numbers always use '.' */
    char message[160];     /* set when a token is ISM_T_BAD */
} ism_lexer;

void ism_lexer_init(ism_lexer *lx, const char *src, size_t len, locale_t c_locale);

/* Reads the next token. */
ism_token ism_lexer_next(ism_lexer *lx);

/* Describes a token for an error message: "')'", "number 2", "name 'x'", "end of input". */
void ism_token_describe(const ism_token *t, char *buf, size_t n);

#endif
