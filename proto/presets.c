/* presets.c — the table of named surfaces and the GET /v1/presets document. Formulas are
 * those of shared/surfaces.json (the seed paper's surfaces reconstructed and checked against
 * their standard forms); boxes and depths follow the paper's figures where it gives them. */
#include "proto/presets.h"
#include "proto/json_writer.h"

#include <stddef.h>
#include <stdio.h>
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


/* ---- the gallery: classic surfaces with their sources and checked facts ---------------- */

#define NOPARAMS NULL, 0
#define BOX(a) {-(a), -(a), -(a), (a), (a), (a)}
#define PARAMS(p) p, COUNT(p)

static const ism_preset_param cone_params[] = {{"c", 1, 0.3, 2}};
static const ism_preset_param cyl_params[] = {{"r", 1.3, 1.05, 1.4}};
static const ism_preset_param helicoid_params[] = {{"k", 2, 0.5, 4}};
static const ism_preset_param schwarz_params[] = {{"k", 3, 1, 6}};
static const ism_preset_param sphere2_params[] = {{"d", 1, 0.6, 1.6}};
static const ism_preset_param tangle_params[] = {{"c", 11.8, 10, 12.4}};
static const ism_preset_param cross_params[] = {{"d", 0.5, 0.1, 0.9}};
static const ism_preset_param ell_params[] = {{"a", 1.4, 0.5, 2}, {"b", 0.9, 0.5, 2}};
static const ism_preset_param hyp_params[] = {{"c", 0.25, -0.5, 0.5}};
static const ism_preset_param spindle_params[] = {{"a", 10, 6, 14}, {"r", 12, 11, 16}, {"f", 2, 0.5, 4}};
static const ism_preset_param heart_params[] = {{"s", 1, 0.5, 1.5}};
static const ism_preset_param blob_params[] = {{"t", 0.3, 0.05, 0.6}};

#define CYCLIDE "(x^2 + y^2 + z^2 + a^2 - f^2 - r^2)^2 - 4*(a*x - f*r)^2 - 4*(a^2 - f^2)*y^2"

static const ism_preset presets[] = {
    {"sphere", "Sphere", "The simplest closed surface: one component, Euler characteristic 2.",
     "x^2 + y^2 + z^2 - r^2", NULL, 0, sphere_params, COUNT(sphere_params),
     {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, 3, 6, .source = NULL},
    {"torus", "Torus", "A ring of genus one: Euler characteristic 0, curvature of both signs.",
     "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)", NULL, 0, torus_params,
     COUNT(torus_params), {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, 3, 7, .source = NULL},
    {"pretzel-genus2", "Genus-2 pretzel", "Two holes: Euler characteristic -2.",
     "(x*(x-1)^2*(x-2) + y^2)^2 + z^2 - t", NULL, 0, pretzel_params, COUNT(pretzel_params),
     {-0.5, -1.5, -1.5, 2.5, 1.5, 1.5}, 3, 7, .source = NULL},
    {"gyroid-ball", "Gyroid in a ball",
     "A triply periodic gyroid cut by a ball: a sharp crease where the two meet.",
     "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
     NULL, 0, gyroid_params, COUNT(gyroid_params), {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, 3, 7, .source = NULL},
    {"kummer-4-nodes", "Kummer surface, 4 nodes",
     "Kummer quartic with 4 real double points where separate parts meet (paper Fig. 5a).",
     kummer_expr, kummer_lets, COUNT(kummer_lets), kummer4_params, COUNT(kummer4_params),
     {-3, -3, -3, 3, 3, 3}, 3, 8, .source = NULL},
    {"kummer-16-nodes", "Kummer surface, 16 nodes",
     "Kummer quartic with its 16 double points, cones meeting at each (paper Fig. 5b).",
     kummer_expr, kummer_lets, COUNT(kummer_lets), kummer16_params, COUNT(kummer16_params),
     {-3, -3, -3, 3, 3, 3}, 3, 9, .source = NULL},
    {"horn-cyclide", "Horn cyclide",
     "A Dupin cyclide whose tube shrinks to a singular point at (a, 0, 0) where two horns "
     "touch (paper Fig. 6).",
     "(x^2 + y^2 + z^2 + a^2 - f^2 - r^2)^2 - 4*(a*x - f*r)^2 - 4*(a^2 - f^2)*y^2", NULL, 0,
     cyclide_params, COUNT(cyclide_params), {-15, -16, -16, 17, 16, 16}, 3, 8, .source = NULL},
    {"klein-bottle", "Klein bottle",
     "Figure-8 Klein bottle: one-sided, self-intersecting along a curve in the plane z = 0 "
     "(paper Fig. 7).",
     "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
     "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
     NULL, 0, NULL, 0, {-4, -4, -4, 4, 4, 4}, 3, 8, .source = NULL},
    {"steiner-roman", "Steiner's Roman surface",
     "Three double lines along the coordinate axes meeting in a triple point at the origin "
     "(paper Fig. 8).",
     "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", NULL, 0, NULL, 0, {-1, -1, -1, 1, 1, 1}, 3, 8, .source = NULL},

    /* nodes and other singular points */
    {"cayley-cubic", "Cayley's nodal cubic",
     "The cubic surface with the most nodes: 4, at the vertices of a tetrahedron.",
     "4*(x^2 + y^2 + z^2) + 16*x*y*z - 1", NULL, 0, NOPARAMS, BOX(1.3), 3, 7,
     "A. Cayley 1869; nodes at (-1/2,-1/2,-1/2) and its three sign changes of two coordinates",
     ISM_FACT_NODES, .nodes = 4},
    {"chmutov-quartic", "Chmutov quartic",
     "T4(x) + T4(y) + T4(z) + 1 = 0 with Chebyshev's T4: 12 real nodes, one coordinate 0 and two "
     "at ±1/√2.",
     "8*(x^4 + y^4 + z^4) - 8*(x^2 + y^2 + z^2) + 4", NULL, 0, NOPARAMS, BOX(1.2), 3, 7,
     "S. Chmutov 1992 (Chebyshev-polynomial surfaces with many nodes)",
     ISM_FACT_NODES, .nodes = 12},
    {"double-cone", "Double cone", "Two nappes meeting in one node at the origin.",
     "x^2 + y^2 - c^2*z^2", NULL, 0, PARAMS(cone_params), BOX(1), 3, 7,
     "quadric cone; its apex is the simplest node (A1)", ISM_FACT_NODES, .nodes = 1},
    {"ding-dong", "Ding-dong surface",
     "x^2 + y^2 = (1 - z) z^2: a bell that closes at z = 1 and a cone node at the origin.",
     "x^2 + y^2 - (1 - z)*z^2", NULL, 0, NOPARAMS, {-1.2, -1.2, -1.2, 1.2, 1.2, 1.2}, 3, 7,
     "cubic surface of revolution (the nodal cubic curve spun about its axis)", ISM_FACT_NODES,
     .nodes = 1},
    {"cusp-a2", "Cusp (A2)", "x^2 + y^2 = z^3: a cuspidal point at the origin.",
     "x^2 + y^2 - z^3", NULL, 0, NOPARAMS, BOX(1), 3, 7,
     "the A2 singularity x^2 + y^2 + z^3 = 0 (Arnold's list)", .facts = 0},
    {"isolated-point", "Sphere and an isolated point",
     "A sphere and a single real point at the origin where f = |p|^2 g has a definite Hessian.",
     "(x^2 + y^2 + z^2)*((x - 1.1)^2 + y^2 + z^2 - 0.25)", NULL, 0, NOPARAMS,
     {-0.8, -0.8, -0.8, 1.8, 0.8, 0.8}, 3, 7,
     "product of a definite quadratic form and a sphere", ISM_FACT_COMPONENTS, .components = 1},
    {"whitney-umbrella", "Whitney umbrella",
     "x^2 = y^2 z: a double line on z > 0, a whisker on z < 0, a pinch point between.",
     "x^2 - y^2*z", NULL, 0, NOPARAMS, BOX(1), 3, 7,
     "H. Whitney 1944 (the stable singularity of maps R^2 -> R^3)", .facts = 0},
    {"cross-cap", "Cross-cap",
     "A sphere crossing itself along a segment that ends in two pinch points.",
     "4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", NULL, 0, NOPARAMS, BOX(1.2), 3, 7,
     "the quartic cross-cap (a model of the real projective plane)", .facts = 0},
    /* bound_depth 7 (this preset and the next): the planes are met exactly at any depth.
     * It was set when the cells along their double lines failed the plot test at every
     * level and split to the safety depth (depth 10 cost 5.4x / 4.4x the depth path). Since
     * a lattice corner on f = 0 counts as one root (core/octree/corners.c), those cells pass
     * at the singular stage's depth (7 at the default bound), and depth.max 7, 8 and 10 give
     * the same mesh at the same cost (callgrind, one thread, `isomesh --surface P [-d 3:10]`,
     * whole run: crossing-planes 191.9M, coordinate-planes 573.3M at each, PLY md5 equal,
     * the bound met; the depth path 305.8M / 898.6M). The cap stays as a safety limit. */
    {"crossing-planes", "Two crossing planes", "x y = 0: a double line along the z axis.", "x*y",
     NULL, 0, NOPARAMS, BOX(1), 3, 6, "the simplest double curve", .facts = 0,
     .bound_depth = 7},
    {"coordinate-planes", "Three coordinate planes",
     "x y z = 0: three double lines meeting in a triple point.", "x*y*z", NULL, 0, NOPARAMS,
     BOX(1), 3, 6, "the simplest triple point", .facts = 0, .bound_depth = 7},
    {"crossing-spheres", "Two crossing spheres",
     "Two unit spheres whose centres are d apart cross along a double circle.",
     "((x - d/2)^2 + y^2 + z^2 - 1)*((x + d/2)^2 + y^2 + z^2 - 1)", NULL, 0,
     PARAMS(cross_params), {-1.8, -1.3, -1.3, 1.8, 1.3, 1.3}, 3, 7,
     "product of two spheres: f = g h vanishes to second order on g = h = 0", ISM_FACT_COMPONENTS,
     .components = 1},
    {"heart", "Taubin's heart", "A sextic heart with two singular points on its axis.",
     "(x^2 + 9/4*y^2 + z^2 - s)^3 - x^2*z^3 - 9/80*y^2*z^3", NULL, 0, PARAMS(heart_params),
     BOX(1.5), 3, 6, "G. Taubin 1994", .facts = 0},
    /* Dupin cyclides */
    {"spindle-cyclide", "Spindle cyclide",
     "The seed paper's cyclide quartic with r > a: a spindle-like Dupin cyclide.",
     CYCLIDE, NULL, 0, PARAMS(spindle_params), {-26, -24, -24, 26, 24, 24}, 3, 7,
     "C. Dupin 1822; the same quartic with r > a", .facts = 0},
    /* smooth closed surfaces */
    {"ellipsoid", "Ellipsoid", "A smooth oval: Euler characteristic 2.",
     "x^2/a^2 + y^2/b^2 + z^2 - 1", NULL, 0, PARAMS(ell_params), BOX(2.2), 3, 6, "quadric",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 2, .components = 1},
    {"tooth", "Tooth surface", "x^4 + y^4 + z^4 = x^2 + y^2 + z^2: a rounded cube, a sphere's topology.",
     "x^4 + y^4 + z^4 - (x^2 + y^2 + z^2)", NULL, 0, NOPARAMS, BOX(1.6), 3, 7, "quartic",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 2, .components = 1},
    {"tanglecube", "Tanglecube", "A quartic of genus 5: Euler characteristic -8.",
     "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + c", NULL, 0, PARAMS(tangle_params), BOX(3), 3, 7,
     "classic test surface of implicit-surface polygonisers", ISM_FACT_EULER | ISM_FACT_COMPONENTS,
     .euler = -8, .components = 1},
    {"two-spheres", "Two separate spheres", "Two components, each a sphere: Euler characteristic 4.",
     "min((x - 1)^2 + y^2 + z^2 - 0.64, (x + 1)^2 + y^2 + z^2 - 0.64)", NULL, 0, NOPARAMS,
     {-2, -1.2, -1.2, 2, 1.2, 1.2}, 3, 7, "CSG union of disjoint balls",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 4, .components = 2},
    {"hyperboloid", "Hyperboloid", "x^2 + y^2 - z^2 = c: one sheet (c > 0), two (c < 0), a cone (0).",
     "x^2 + y^2 - z^2 - c", NULL, 0, PARAMS(hyp_params), BOX(1.5), 3, 7, "quadric",
     ISM_FACT_COMPONENTS, .components = 1},
    {"clebsch-cubic", "Clebsch diagonal cubic",
     "The smooth cubic surface whose 27 lines are all real.",
     "x^3 + y^3 + z^3 + 1 - (x + y + z + 1)^3", NULL, 0, NOPARAMS, BOX(2), 3, 7,
     "A. Clebsch 1871 (x0^3 + ... + x4^3 = 0 = x0 + ... + x4, with x4 eliminated)", .facts = 0},
    /* minimal surfaces, triply periodic and classic */
    {"schwarz-p", "Schwarz P in a ball",
     "The primitive triply periodic minimal surface (its cosine approximation) cut by a ball.",
     "max(cos(k*x) + cos(k*y) + cos(k*z), x^2 + y^2 + z^2 - 1.96)", NULL, 0,
     PARAMS(schwarz_params), BOX(1.5), 3, 7, "H. A. Schwarz 1865; nodal approximation", .facts = 0},
    {"schwarz-d", "Schwarz D in a ball", "The diamond surface (nodal approximation) cut by a ball.",
     "max(sin(k*x)*sin(k*y)*sin(k*z) + sin(k*x)*cos(k*y)*cos(k*z) + cos(k*x)*sin(k*y)*cos(k*z) + "
     "cos(k*x)*cos(k*y)*sin(k*z), x^2 + y^2 + z^2 - 1.96)",
     NULL, 0, PARAMS(schwarz_params), BOX(1.5), 3, 7, "H. A. Schwarz 1865; nodal approximation", .facts = 0},
    {"neovius", "Neovius surface in a ball", "Neovius's triply periodic surface cut by a ball.",
     "max(3*(cos(k*x) + cos(k*y) + cos(k*z)) + 4*cos(k*x)*cos(k*y)*cos(k*z), x^2 + y^2 + z^2 - 1.96)",
     NULL, 0, PARAMS(schwarz_params), BOX(1.5), 3, 7, "E. R. Neovius 1883; nodal approximation", .facts = 0},
    {"scherk", "Scherk's first surface", "e^z cos y = cos x: a doubly periodic minimal surface.",
     "exp(z)*cos(y) - cos(x)", NULL, 0, NOPARAMS, {-4, -4, -3, 4, 4, 3}, 3, 7,
     "H. F. Scherk 1834 (exact)", .facts = 0},
    {"helicoid", "Helicoid", "x sin(kz) = y cos(kz): a ruled minimal surface around the z axis.",
     "x*sin(k*z) - y*cos(k*z)", NULL, 0, PARAMS(helicoid_params), BOX(1.2), 3, 7,
     "J. B. Meusnier 1776 (exact)", ISM_FACT_COMPONENTS, .components = 1},
    {"catenoid", "Catenoid", "x^2 + y^2 = cosh^2 z: the soap film between two rings.",
     "x^2 + y^2 - ((exp(z) + exp(-z))/2)^2", NULL, 0, NOPARAMS, {-2.2, -2.2, -1.2, 2.2, 2.2, 1.2},
     3, 7, "L. Euler 1744 (exact)", ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 0,
     .components = 1},
    /* constructive solid geometry */
    {"cube-minus-ball", "Cube minus a ball",
     "A cube with a ball of radius r (between 1 and sqrt 2) removed: a frame of 12 bars, genus 5.",
     "max(max(abs(x), abs(y), abs(z)) - 1, r^2 - (x^2 + y^2 + z^2))", NULL, 0,
     PARAMS(cyl_params), BOX(1.3), 3, 7, "CSG difference; creases where the pieces meet",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = -8, .components = 1},
    {"steinmetz", "Steinmetz tricylinder", "The common part of three perpendicular cylinders.",
     "max(x^2 + y^2, y^2 + z^2, z^2 + x^2) - 1", NULL, 0, NOPARAMS, BOX(1.3), 3, 7,
     "CSG intersection (Archimedes, Steinmetz)", ISM_FACT_EULER | ISM_FACT_COMPONENTS,
     .euler = 2, .components = 1},
    {"cube", "Cube", "max(|x|, |y|, |z|) = 1: flat faces, sharp edges and corners.",
     "max(abs(x), abs(y), abs(z)) - 1", NULL, 0, NOPARAMS, BOX(1.3), 3, 7, "CSG (the L-infinity ball)",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 2, .components = 1},
    {"three-balls", "Union of three balls", "Three overlapping balls: one component, a sphere's topology.",
     "min((x - 0.6)^2 + y^2 + z^2 - 0.5, (x + 0.3)^2 + (y - 0.52)^2 + z^2 - 0.5, "
     "(x + 0.3)^2 + (y + 0.52)^2 + z^2 - 0.5)", NULL, 0, NOPARAMS, BOX(1.5), 3, 7, "CSG union",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 2, .components = 1},
    {"linked-tori", "Two linked tori",
     "Two rings (R = 1, r = 0.3) through each other, each through the other's centre: two "
     "components of genus 1.",
     "min((x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2), ((x - 1)^2 + y^2 + z^2 + 0.91)^2 - 4*((x - 1)^2 + z^2))",
     NULL, 0, NOPARAMS, {-1.8, -1.8, -1.8, 2.8, 1.8, 1.8}, 3, 7, "CSG union of disjoint tori",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 0, .components = 2},
    {"double-torus", "Double torus (union)", "Two overlapping tori: genus 2, Euler characteristic -2.",
     "min((x^2 + y^2 + z^2 + 0.75)^2 - 4*(x^2 + y^2), ((x - 2.2)^2 + y^2 + z^2 + 0.75)^2 - 4*((x - 2.2)^2 + y^2))",
     NULL, 0, NOPARAMS, {-1.8, -1.8, -0.8, 4, 1.8, 0.8}, 3, 7, "CSG union", 
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = -2, .components = 1},
    {"blob-pair", "Two blobs joined", "Two metaballs that merge as t grows (one component at t = 0.3).",
     "t - exp(-4*((x - 0.6)^2 + y^2 + z^2)) - exp(-4*((x + 0.6)^2 + y^2 + z^2))", NULL, 0,
     PARAMS(blob_params), {-2, -1.4, -1.4, 2, 1.4, 1.4}, 3, 7, "J. Blinn 1982 (blobby molecules)",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 2, .components = 1},
    {"sphere-pair-param", "Two balls drawn apart",
     "Two balls of radius 0.7 at distance 2d: one component while d < 0.7, two after.",
     "min((x - d)^2 + y^2 + z^2 - 0.49, (x + d)^2 + y^2 + z^2 - 0.49)", NULL, 0,
     PARAMS(sphere2_params), {-2.5, -1, -1, 2.5, 1, 1}, 3, 7, "CSG union",
     ISM_FACT_EULER | ISM_FACT_COMPONENTS, .euler = 4, .components = 2},
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

int ism_preset_bound_depth(const ism_preset *p, int limit)
{
    return p && p->bound_depth > 0 && p->bound_depth < limit ? p->bound_depth : limit;
}

bool ism_preset_has_param(const ism_preset *p, const char *name)
{
    for (size_t k = 0; k < p->nparams; k++)
        if (strcmp(p->params[k].name, name) == 0)
            return true;
    return false;
}

void ism_preset_param_names(const ism_preset *p, char *buf, size_t n)
{
    snprintf(buf, n, "none");
    for (size_t k = 0, at = 0; k < p->nparams && at < n; k++)
        at += (size_t)snprintf(buf + at, n - at, "%s%s", k ? ", " : "", p->params[k].name);
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
    ism_jw_key(w, "source");
    ism_jw_string(w, p->source ? p->source : "Balsys & Suffern 2005 / shared/surfaces.json");
    ism_jw_key(w, "facts");
    ism_jw_object(w);
    static const struct { unsigned bit; const char *name; size_t off; } FACTS[] = {
        {ISM_FACT_NODES, "nodes", offsetof(ism_preset, nodes)},
        {ISM_FACT_EULER, "euler", offsetof(ism_preset, euler)},
        {ISM_FACT_COMPONENTS, "components", offsetof(ism_preset, components)},
        {ISM_FACT_SINGULAR, "singular_points", offsetof(ism_preset, singular)},
    };
    for (size_t i = 0; i < COUNT(FACTS); i++) {
        if (!(p->facts & FACTS[i].bit))
            continue;
        ism_jw_key(w, FACTS[i].name);
        ism_jw_int(w, *(const int *)((const char *)p + FACTS[i].off));
    }
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
