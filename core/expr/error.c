/* error.c — formatting and setting compile errors (ism_error). */
#include "core/expr/expr.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

char *ism_error_format(const ism_error *err, char *buf, size_t n)
{
    if (!buf || n == 0)
        return buf;
    char where[96] = "";
    char pos[48] = "";
    if (err->where[0])
        snprintf(where, sizeof where, "let %s: ", err->where);
    if (err->line > 1)
        snprintf(pos, sizeof pos, "line %d, col %d: ", err->line, err->column);
    else if (err->line == 1)
        snprintf(pos, sizeof pos, "col %d: ", err->column);
    snprintf(buf, n, "%s%s%s", where, pos, err->message);
    return buf;
}

bool ism_error_set(ism_error *err, const char *fmt, ...)
{
    if (!err)
        return false;
    memset(err, 0, sizeof *err);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return false;
}
