/* json_writer.h — a small streaming JSON text builder for everything proto/ emits (errors,
 * canonical requests, stats, features, presets, glTF): compact output, commas placed for the
 * caller, strings escaped, and doubles printed in their shortest form that reads back to the
 * same value (jansson would print 0.1 as 0.10000000000000001). */
#ifndef ISM_JSON_WRITER_H
#define ISM_JSON_WRITER_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

#define ISM_JW_MAX_NESTING 32

typedef struct ism_jw {
    char *data;
    size_t len, cap;
    bool failed;                         /* out of memory or misuse: the text is unusable */
    int depth;
    bool first[ISM_JW_MAX_NESTING + 1];  /* no value yet at this nesting level */
    bool after_key;
} ism_jw;

void ism_jw_init(ism_jw *w);
void ism_jw_free(ism_jw *w);

void ism_jw_object(ism_jw *w);        /* { */
void ism_jw_object_end(ism_jw *w);    /* } */
void ism_jw_array(ism_jw *w);         /* [ */
void ism_jw_array_end(ism_jw *w);     /* ] */
void ism_jw_key(ism_jw *w, const char *key);

void ism_jw_string(ism_jw *w, const char *s);
void ism_jw_string_n(ism_jw *w, const char *s, size_t n);
void ism_jw_number(ism_jw *w, double v);  /* shortest round trip; null when not finite */
void ism_jw_numbers(ism_jw *w, const double *v, size_t n); /* [v0, ..., vn-1] */
void ism_jw_float(ism_jw *w, float v);    /* shortest text that reads back to the same float */
/* v rounded to `decimals` places after the point (0..17; off by at most 0.5 * 10^-decimals),
 * trailing zeros dropped, -0 as 0: for values whose own tolerance makes further digits noise
 * (the caller derives decimals from that tolerance); null when not finite. decimals < 0: in
 * full, as ism_jw_number prints it. */
void ism_jw_number_decimals(ism_jw *w, double v, int decimals);
void ism_jw_numbers_decimals(ism_jw *w, const double *v, size_t n, int decimals);
void ism_jw_int(ism_jw *w, long long v);
void ism_jw_uint(ism_jw *w, uint64_t v);
void ism_jw_bool(ism_jw *w, bool v);
void ism_jw_null(ism_jw *w);
void ism_jw_raw(ism_jw *w, const char *json, size_t n); /* an already-encoded JSON value */
/* The members of an already-encoded JSON object, spliced into the open object (failed when
 * the text is not braced). */
void ism_jw_members(ism_jw *w, const char *object, size_t n);

/* Writes the shortest decimal form of v that strtod reads back to v into buf (at least 32
 * bytes); "null" when v is not finite. Returns buf. */
char *ism_jw_format_double(double v, char *buf);

/* Hands over the NUL-terminated text (free() it) and its length; NULL when failed. The
 * writer is reset. */
char *ism_jw_take(ism_jw *w, size_t *len);

#endif
