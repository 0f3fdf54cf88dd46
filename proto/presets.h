/* presets.h — the named surfaces a client can ask for by name instead of writing the
 * expression: the seed paper's non-manifold surfaces (both Kummer cases, horn cyclide, Klein
 * bottle, Steiner's Roman surface) and the classics of shared/surfaces.json (sphere, torus,
 * genus-2 pretzel, gyroid ball), each with its parameters, a suggested box and depth, and one
 * line saying what it shows. GET /v1/presets serves ism_presets_json(). */
#ifndef ISM_PRESETS_H
#define ISM_PRESETS_H

#include <stdbool.h>
#include <stddef.h>
#include "core/expr/expr.h"

typedef struct ism_preset_param {
    const char *name;
    double value;              /* default */
    double min, max;           /* suggested slider range (not enforced) */
} ism_preset_param;

typedef struct ism_preset {
    const char *name;          /* what `"preset"` says */
    const char *title;
    const char *about;         /* one line: what the surface shows */
    const char *expr;
    const ism_let *lets;
    size_t nlets;
    const ism_preset_param *params;
    size_t nparams;
    double box[6];
    int min_depth, max_depth;  /* max_depth: the depth path's ("max_error": null) */
    const char *source;        /* where the surface comes from (gallery entries) */
    unsigned facts;            /* which of the stated facts below hold (enum ism_fact bits) */
    int nodes;                 /* singular points of type node in the box */
    int euler;                 /* Euler characteristic of the mesh */
    int components;            /* connected components */
    int singular;              /* singular points of any type (features JSON v2) */
    int bound_depth;           /* under a bound without depth.max, the safety depth when it
                                  must be below the operator's limit (0: that limit); see
                                  ism_preset_bound_depth */
} ism_preset;

/* The facts a gallery entry states; tests/cli/test_gallery.py checks each against the mesh
 * (in the entry's box and in boxes shifted off the octree lattice). */
enum ism_fact { ISM_FACT_NODES = 1, ISM_FACT_EULER = 2, ISM_FACT_COMPONENTS = 4,
                ISM_FACT_SINGULAR = 8 };

/* depth.max of a request under a bound that gives none: the operator's limit, or p's
 * bound_depth when it has one below it (p NULL: a written-out expression). */
int ism_preset_bound_depth(const ism_preset *p, int limit);

size_t ism_preset_count(void);
const ism_preset *ism_preset_at(size_t i);
/* The preset called name, or NULL. */
const ism_preset *ism_preset_find(const char *name);
/* Does the preset have a parameter called name? (a request's "params" and the CLI's -p
 * refuse a name it has not: a misspelt one would otherwise be ignored without a word) */
bool ism_preset_has_param(const ism_preset *p, const char *name);
/* The preset's parameter names joined by ", " into buf (n bytes, cut short if it must),
 * or "none" when it has none: the "(it has ...)" of those refusals. */
void ism_preset_param_names(const ism_preset *p, char *buf, size_t n);

/* {"presets": [{"name", "title", "about", "expr", "let": [[name, source]...], "params":
 * [{"name", "default", "min", "max"}...], "box": [6], "depth": {"min", "max"}, "source",
 * "facts": {"nodes"?, "euler"?, "components"?, "singular_points"?}}...]}.
 * malloc'd text, NULL when out of memory. */
char *ism_presets_json(size_t *len);

#endif
