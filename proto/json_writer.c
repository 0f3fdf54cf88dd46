/* json_writer.c — the streaming JSON builder: a growable text buffer, a stack that knows
 * whether a comma is due, string escaping (UTF-8 passes through; control characters, quotes
 * and backslashes are escaped) and shortest round-trip number printing. */
#include "proto/json_writer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ism_jw_init(ism_jw *w)
{
    memset(w, 0, sizeof *w);
    w->first[0] = true;
}

void ism_jw_free(ism_jw *w)
{
    free(w->data);
    ism_jw_init(w);
}

static void put(ism_jw *w, const char *s, size_t n)
{
    if (w->failed)
        return;
    if (w->len + n + 1 > w->cap) {
        size_t c = w->cap ? w->cap : 256;
        while (c < w->len + n + 1)
            c *= 2;
        char *d = realloc(w->data, c);
        if (!d) {
            w->failed = true;
            return;
        }
        w->data = d;
        w->cap = c;
    }
    memcpy(w->data + w->len, s, n);
    w->len += n;
    w->data[w->len] = '\0';
}

static void putc1(ism_jw *w, char c) { put(w, &c, 1); }

/* Emits the comma that separates this value from the previous one at the same level. */
static void before_value(ism_jw *w)
{
    if (w->after_key) {
        w->after_key = false;
        return;
    }
    if (!w->first[w->depth])
        putc1(w, ',');
    w->first[w->depth] = false;
}

static void jw_open(ism_jw *w, char c)
{
    before_value(w);
    if (w->depth >= ISM_JW_MAX_NESTING) {
        w->failed = true;
        return;
    }
    putc1(w, c);
    w->first[++w->depth] = true;
}

static void jw_close(ism_jw *w, char c)
{
    if (w->depth <= 0 || w->after_key) {
        w->failed = true;
        return;
    }
    w->depth--;
    putc1(w, c);
}

void ism_jw_object(ism_jw *w) { jw_open(w, '{'); }
void ism_jw_object_end(ism_jw *w) { jw_close(w, '}'); }
void ism_jw_array(ism_jw *w) { jw_open(w, '['); }
void ism_jw_array_end(ism_jw *w) { jw_close(w, ']'); }

static void put_escaped(ism_jw *w, const char *s, size_t n)
{
    putc1(w, '"');
    size_t run = 0; /* bytes copied as they are, flushed in one put */
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        const char *esc = NULL;
        char hex[8];
        if (c == '"')
            esc = "\\\"";
        else if (c == '\\')
            esc = "\\\\";
        else if (c == '\n')
            esc = "\\n";
        else if (c == '\t')
            esc = "\\t";
        else if (c == '\r')
            esc = "\\r";
        else if (c < 0x20 || c == 0x7f) {
            snprintf(hex, sizeof hex, "\\u%04x", c);
            esc = hex;
        }
        if (esc) {
            put(w, s + i - run, run);
            run = 0;
            put(w, esc, strlen(esc));
        } else {
            run++;
        }
    }
    put(w, s + n - run, run);
    putc1(w, '"');
}

void ism_jw_key(ism_jw *w, const char *key)
{
    if (w->after_key || w->depth == 0) {
        w->failed = true;
        return;
    }
    if (!w->first[w->depth])
        putc1(w, ',');
    w->first[w->depth] = false;
    put_escaped(w, key, strlen(key));
    putc1(w, ':');
    w->after_key = true;
}

void ism_jw_string_n(ism_jw *w, const char *s, size_t n)
{
    before_value(w);
    put_escaped(w, s, n);
}

void ism_jw_string(ism_jw *w, const char *s) { ism_jw_string_n(w, s, strlen(s)); }

char *ism_jw_format_double(double v, char *buf)
{
    if (!isfinite(v)) {
        strcpy(buf, "null");
        return buf;
    }
    if (v == 0) { /* also folds -0 into 0 */
        strcpy(buf, "0");
        return buf;
    }
    /* %g drops trailing zeros, so the first precision that reads back exactly is short. */
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(buf, 32, "%.*g", prec, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    return buf;
}

void ism_jw_number(ism_jw *w, double v)
{
    char buf[32];
    before_value(w);
    ism_jw_format_double(v, buf);
    put(w, buf, strlen(buf));
}

void ism_jw_numbers(ism_jw *w, const double *v, size_t n)
{
    ism_jw_array(w);
    for (size_t i = 0; i < n; i++)
        ism_jw_number(w, v[i]);
    ism_jw_array_end(w);
}

void ism_jw_number_decimals(ism_jw *w, double v, int decimals)
{
    /* %f of a double below 1e300 with <= 17 decimals fits 340 bytes. */
    char buf[340];
    before_value(w);
    if (decimals < 0 || !isfinite(v) || fabs(v) >= 1e300) { /* in full */
        ism_jw_format_double(v, buf);
        put(w, buf, strlen(buf));
        return;
    }
    decimals = decimals > 17 ? 17 : decimals;
    int n = snprintf(buf, sizeof buf, "%.*f", decimals, v);
    if (n < 0 || (size_t)n >= sizeof buf) {
        w->failed = true;
        return;
    }
    if (strchr(buf, '.')) { /* drop trailing zeros, then a bare point */
        while (n > 0 && buf[n - 1] == '0')
            n--;
        if (n > 0 && buf[n - 1] == '.')
            n--;
    }
    buf[n] = '\0';
    if (strcmp(buf, "-0") == 0) /* a value that rounds to zero prints as 0 */
        put(w, "0", 1);
    else
        put(w, buf, (size_t)n);
}

void ism_jw_numbers_decimals(ism_jw *w, const double *v, size_t n, int decimals)
{
    ism_jw_array(w);
    for (size_t i = 0; i < n; i++)
        ism_jw_number_decimals(w, v[i], decimals);
    ism_jw_array_end(w);
}

void ism_jw_float(ism_jw *w, float v)
{
    char buf[32];
    before_value(w);
    if (!isfinite(v)) {
        put(w, "null", 4);
        return;
    }
    if (v == 0) {
        put(w, "0", 1);
        return;
    }
    for (int prec = 6; prec <= 9; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, (double)v);
        if (strtof(buf, NULL) == v)
            break;
    }
    put(w, buf, strlen(buf));
}

void ism_jw_int(ism_jw *w, long long v)
{
    char buf[32];
    before_value(w);
    int n = snprintf(buf, sizeof buf, "%lld", v);
    put(w, buf, (size_t)n);
}

void ism_jw_uint(ism_jw *w, uint64_t v)
{
    char buf[32];
    before_value(w);
    int n = snprintf(buf, sizeof buf, "%llu", (unsigned long long)v);
    put(w, buf, (size_t)n);
}

void ism_jw_bool(ism_jw *w, bool v)
{
    before_value(w);
    put(w, v ? "true" : "false", v ? 4 : 5);
}

void ism_jw_null(ism_jw *w)
{
    before_value(w);
    put(w, "null", 4);
}

void ism_jw_raw(ism_jw *w, const char *json, size_t n)
{
    before_value(w);
    put(w, json, n);
}

void ism_jw_members(ism_jw *w, const char *object, size_t n)
{
    while (n && (*object == ' ' || *object == '\n'))
        object++, n--;
    while (n && (object[n - 1] == ' ' || object[n - 1] == '\n'))
        n--;
    if (n < 2 || object[0] != '{' || object[n - 1] != '}' || w->after_key) {
        w->failed = true;
        return;
    }
    if (n == 2)
        return; /* {} */
    before_value(w);
    put(w, object + 1, n - 2);
}

char *ism_jw_take(ism_jw *w, size_t *len)
{
    if (w->failed || w->depth != 0 || !w->data) {
        ism_jw_free(w);
        return NULL;
    }
    char *d = w->data;
    if (len)
        *len = w->len;
    w->data = NULL;
    ism_jw_init(w);
    return d;
}
