/* test_eval_surfaces.h — the example surfaces of /work/shared/surfaces.json, written out
 * for the evaluator tests, with a small deterministic random generator they share. */
#ifndef TEST_EVAL_SURFACES_H
#define TEST_EVAL_SURFACES_H

#include <stddef.h>
#include <stdint.h>
#include "core/eval/eval.h"

typedef struct test_surface {
    const char *name;
    const char *expr;
    ism_param params[4];
    size_t nparams;
    ism_let lets[6];
    size_t nlets;
    double box[6];   /* xmin ymin zmin xmax ymax zmax */
    int polynomial;  /* 1 when f is a polynomial */
} test_surface;

extern const test_surface TEST_SURFACES[];
extern const size_t TEST_NSURFACES;

/* Compiles a surface (fails the test on error). */
ism_tape *test_surface_compile(const test_surface *s);

/* The surface of TEST_SURFACES called name (fails the test when there is none). */
const test_surface *test_surface_named(const char *name);

/* splitmix64: a reproducible stream of uniform doubles. */
typedef struct test_rng {
    uint64_t s;
} test_rng;

double test_uniform(test_rng *r, double lo, double hi);

/* Work counts shrink under ISOMESH_TEST_QUICK=1 (the sanitizer run). */
size_t test_scaled(size_t full);

#endif
