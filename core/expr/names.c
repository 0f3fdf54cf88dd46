/* names.c — the built-in names (variables, constants, functions with their arities) and the
 * table of parameters and lets bound by one compilation. */
#include "core/expr/names.h"
#include "core/util/grow.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const ism_func_info funcs[ISM_F_COUNT] = {
    [ISM_F_SQRT] = { "sqrt", 1, 1 }, [ISM_F_SIN] = { "sin", 1, 1 },
    [ISM_F_COS] = { "cos", 1, 1 },   [ISM_F_TAN] = { "tan", 1, 1 },
    [ISM_F_EXP] = { "exp", 1, 1 },   [ISM_F_LOG] = { "log", 1, 1 },
    [ISM_F_ABS] = { "abs", 1, 1 },   [ISM_F_MIN] = { "min", 2, -1 },
    [ISM_F_MAX] = { "max", 2, -1 },  [ISM_F_POW] = { "pow", 2, 2 },
};

static bool is(const char *name, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(name, word, len) == 0;
}

int ism_func_lookup(const char *name, size_t len)
{
    for (int f = 0; f < ISM_F_COUNT; f++)
        if (is(name, len, funcs[f].name))
            return f;
    return -1;
}

const ism_func_info *ism_func_get(int f)
{
    return &funcs[f];
}

int ism_var_lookup(const char *name, size_t len)
{
    if (len == 1 && name[0] >= 'x' && name[0] <= 'z')
        return name[0] - 'x';
    return -1;
}

bool ism_const_lookup(const char *name, size_t len, double *v)
{
    if (is(name, len, "pi")) {
        *v = M_PI;
        return true;
    }
    if (is(name, len, "e")) {
        *v = M_E;
        return true;
    }
    return false;
}

const ism_name *ism_names_find(const ism_names *s, const char *name, size_t len)
{
    for (size_t i = 0; i < s->count; i++)
        if (is(name, len, s->items[i].name))
            return &s->items[i];
    return NULL;
}

static bool valid_identifier(const char *name, size_t len)
{
    if (len == 0 || len > 63 || !(isalpha((unsigned char)name[0]) || name[0] == '_'))
        return false;
    for (size_t i = 1; i < len; i++)
        if (!(isalnum((unsigned char)name[i]) || name[i] == '_'))
            return false;
    return true;
}

bool ism_names_check_new(const ism_names *s, const char *name, size_t len, const char *what,
                         char *msg, size_t n)
{
    double v;
    const ism_name *old;
    int shown = (int)(len > 40 ? 40 : len);
    if (!valid_identifier(name, len))
        snprintf(msg, n, "%s name '%.*s%s' is not a valid name (letters, digits and _, "
                 "not starting with a digit, at most 63)", what, shown, name, len > 40 ? "..." : "");
    else if (ism_var_lookup(name, len) >= 0)
        snprintf(msg, n, "%s '%.*s' would shadow the variable %.*s", what, shown, name, shown, name);
    else if (ism_func_lookup(name, len) >= 0)
        snprintf(msg, n, "%s '%.*s' would shadow the function %.*s()", what, shown, name, shown, name);
    else if (ism_const_lookup(name, len, &v))
        snprintf(msg, n, "%s '%.*s' would shadow the constant %.*s", what, shown, name, shown, name);
    else if (is(name, len, "let"))
        snprintf(msg, n, "%s name 'let' is a keyword", what);
    else if ((old = ism_names_find(s, name, len)) != NULL)
        snprintf(msg, n, "%s '%.*s' is already defined as a %s", what, shown, name,
                 old->kind == ISM_N_PARAM ? "parameter" : "let");
    else
        return true;
    return false;
}

bool ism_names_add(ism_names *s, const char *name, size_t len, int kind, uint32_t node)
{
    if (!ism_grow((void **)&s->items, &s->cap, s->count + 1, sizeof *s->items, 16))
        return false;
    ism_name *e = &s->items[s->count++];
    memcpy(e->name, name, len);
    e->name[len] = '\0';
    e->kind = kind;
    e->node = node;
    return true;
}

void ism_names_free(ism_names *s)
{
    free(s->items);
    memset(s, 0, sizeof *s);
}
