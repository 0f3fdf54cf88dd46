/* presets.c — the table of named surfaces and the GET /v1/presets document. Formulas are
 * those of shared/surfaces.json (the seed paper's surfaces reconstructed and checked against
 * their standard forms); boxes and depths follow the paper's figures where it gives them. */
#include "proto/presets.h"
#include "proto/json_writer.h"

#include <string.h>

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static const ism_preset_param sphere_params[] = {{"r", 1, 0.1, 1.4}};
static const ism_preset_param torus_params[] = {{"R", 1, 0.4, 1.2}, {"r", 0.3, 0.05, 0.6}};
static const ism_preset_param pretzel_params[] = {{"t", 0.03, 0.005, 0.1}};
static const ism_preset_param gyroid_params[] = {{"k", 4, 1, 10}};
static const ism_preset_param kummer4_params[] = {{"mu2", 0.6667, 0.34, 2.9}, {"w", 1, 0.5, 2}};
static const ism_preset_param kummer16_params[] = {{"mu2", 2, 0.34, 2.9}, {"w", 1, 0.5, 2}};
static const ism_preset_param cyclide_params[] = {{"a", 10, 6, 14}, {"r", 2, 0.5, 4},
                                                  {"f", 2, 0.5, 4}};

/* Kummer's quartic with four tetrahedral planes p q r s (both cases share the lets). */
static const ism_let kummer_lets[] = {
    {"lambda", "(3*mu2 - 1)/(3 - mu2)"},
    {"p", "w - z - sqrt(2)*x"},
    {"q", "w - z + sqrt(2)*x"},
    {"r", "w + z + sqrt(2)*y"},
    {"s", "w + z - sqrt(2)*y"},
};
static const char kummer_expr[] = "(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s";

static const ism_preset presets[] = {
    {"sphere", "Sphere", "The simplest closed surface: one component, Euler characteristic 2.",
     "x^2 + y^2 + z^2 - r^2", NULL, 0, sphere_params, COUNT(sphere_params),
     {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, 3, 6},
    {"torus", "Torus", "A ring of genus one: Euler characteristic 0, curvature of both signs.",
     "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)", NULL, 0, torus_params,
     COUNT(torus_params), {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, 3, 7},
    {"pretzel-genus2", "Genus-2 pretzel", "Two holes: Euler characteristic -2.",
     "(x*(x-1)^2*(x-2) + y^2)^2 + z^2 - t", NULL, 0, pretzel_params, COUNT(pretzel_params),
     {-0.5, -1.5, -1.5, 2.5, 1.5, 1.5}, 3, 7},
    {"gyroid-ball", "Gyroid in a ball",
     "A triply periodic gyroid cut by a ball: a sharp crease where the two meet.",
     "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
     NULL, 0, gyroid_params, COUNT(gyroid_params), {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, 3, 7},
    {"kummer-4-nodes", "Kummer surface, 4 nodes",
     "Kummer quartic with 4 real double points where separate parts meet (paper Fig. 5a).",
     kummer_expr, kummer_lets, COUNT(kummer_lets), kummer4_params, COUNT(kummer4_params),
     {-3, -3, -3, 3, 3, 3}, 3, 8},
    {"kummer-16-nodes", "Kummer surface, 16 nodes",
     "Kummer quartic with its 16 double points, cones meeting at each (paper Fig. 5b).",
     kummer_expr, kummer_lets, COUNT(kummer_lets), kummer16_params, COUNT(kummer16_params),
     {-3, -3, -3, 3, 3, 3}, 3, 9},
    {"horn-cyclide", "Horn cyclide",
     "A Dupin cyclide whose tube shrinks to a singular point at (a, 0, 0) where two horns "
     "touch (paper Fig. 6).",
     "(x^2 + y^2 + z^2 + a^2 - f^2 - r^2)^2 - 4*(a*x - f*r)^2 - 4*(a^2 - f^2)*y^2", NULL, 0,
     cyclide_params, COUNT(cyclide_params), {-14, -16, -16, 18, 16, 16}, 3, 8},
    {"klein-bottle", "Klein bottle",
     "Figure-8 Klein bottle: one-sided, self-intersecting along a curve in the plane z = 0 "
     "(paper Fig. 7).",
     "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
     "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
     NULL, 0, NULL, 0, {-4, -4, -4, 4, 4, 4}, 3, 8},
    {"steiner-roman", "Steiner's Roman surface",
     "Three double lines along the coordinate axes meeting in a triple point at the origin "
     "(paper Fig. 8).",
     "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", NULL, 0, NULL, 0, {-1, -1, -1, 1, 1, 1}, 3, 8},
};

size_t ism_preset_count(void) { return COUNT(presets); }

const ism_preset *ism_preset_at(size_t i) { return i < COUNT(presets) ? &presets[i] : NULL; }

const ism_preset *ism_preset_find(const char *name)
{
    for (size_t i = 0; i < COUNT(presets); i++)
        if (strcmp(presets[i].name, name) == 0)
            return &presets[i];
    return NULL;
}

static void write_preset(ism_jw *w, const ism_preset *p)
{
    ism_jw_object(w);
    ism_jw_key(w, "name");
    ism_jw_string(w, p->name);
    ism_jw_key(w, "title");
    ism_jw_string(w, p->title);
    ism_jw_key(w, "about");
    ism_jw_string(w, p->about);
    ism_jw_key(w, "expr");
    ism_jw_string(w, p->expr);
    ism_jw_key(w, "let");
    ism_jw_array(w);
    for (size_t i = 0; i < p->nlets; i++) {
        ism_jw_array(w);
        ism_jw_string(w, p->lets[i].name);
        ism_jw_string(w, p->lets[i].source);
        ism_jw_array_end(w);
    }
    ism_jw_array_end(w);
    ism_jw_key(w, "params");
    ism_jw_array(w);
    for (size_t i = 0; i < p->nparams; i++) {
        const ism_preset_param *q = &p->params[i];
        ism_jw_object(w);
        ism_jw_key(w, "name");
        ism_jw_string(w, q->name);
        ism_jw_key(w, "default");
        ism_jw_number(w, q->value);
        ism_jw_key(w, "min");
        ism_jw_number(w, q->min);
        ism_jw_key(w, "max");
        ism_jw_number(w, q->max);
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
    ism_jw_key(w, "box");
    ism_jw_array(w);
    for (int k = 0; k < 6; k++)
        ism_jw_number(w, p->box[k]);
    ism_jw_array_end(w);
    ism_jw_key(w, "depth");
    ism_jw_object(w);
    ism_jw_key(w, "min");
    ism_jw_int(w, p->min_depth);
    ism_jw_key(w, "max");
    ism_jw_int(w, p->max_depth);
    ism_jw_object_end(w);
    ism_jw_object_end(w);
}

char *ism_presets_json(size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "presets");
    ism_jw_array(&w);
    for (size_t i = 0; i < COUNT(presets); i++)
        write_preset(&w, &presets[i]);
    ism_jw_array_end(&w);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}
