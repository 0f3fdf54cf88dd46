/* tolerances.h — the polygoniser's six tunable tolerances, one table: for each its field in
 * ism_poly_options, its name in a request's "tolerances" object, its command-line flag, its
 * default, the one range every caller accepts, and why it is what it is. The defaults and
 * checks of ism_poly_options, the request decoder and its cache key, and the CLI's parsing and
 * --help are all driven by this table (tests compare proto/request.schema.json against it). */
#ifndef ISM_TOLERANCES_H
#define ISM_TOLERANCES_H

#include <stdbool.h>
#include <stddef.h>
#include "core/octree/poly_options.h"

typedef struct ism_tolerance {
    const char *field;    /* the ism_poly_options field, as in error messages */
    const char *key;      /* the request's tolerances.<key> */
    const char *flag;     /* the CLI flag, without "--" */
    const char *help;     /* one line for --help: what a value means */
    size_t offset;        /* of the field in ism_poly_options */
    bool is_int;          /* the field is an int (else a double) */
    double def, lo, hi;   /* default and accepted range [lo, hi] */
} ism_tolerance;

enum { ISM_TOLERANCE_COUNT = 6 };

/* The table, in the order requests write their "tolerances" object (the cache key's order). */
extern const ism_tolerance ism_tolerances[ISM_TOLERANCE_COUNT];

/* The tolerance named key in requests, or NULL. */
const ism_tolerance *ism_tolerance_by_key(const char *key);

/* The value of t in o (an int field as a double). */
double ism_tolerance_get(const ism_poly_options *o, const ism_tolerance *t);

/* Stores v into t's field of o (truncated toward zero for an int field; check first). */
void ism_tolerance_set(ism_poly_options *o, const ism_tolerance *t, double v);

/* True when v is finite, inside [lo, hi], and whole for an int field. */
bool ism_tolerance_accepts(const ism_tolerance *t, double v);

#endif
