/* request.c — strict decoding of a surface request: jansson parses (rejecting duplicate keys,
 * invalid UTF-8, trailing garbage), then each section is walked field by field so that an
 * unknown field, a wrong type or a value out of range is reported with its JSON path.
 * Defaults come from the polygoniser (ism_poly_options_default) and from the preset. */
#include "proto/request.h"
#include "proto/request_internal.h"
#include "proto/presets.h"
#include "proto/json_writer.h"
#include "core/octree/tolerances.h"
#include "core/util/vec3.h"

#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------
 * Errors */

static bool bad(ism_req_error *err, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static bool bad(ism_req_error *err, const char *path, const char *fmt, ...)
{
    char reason[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    return ism_req_error_set(err, 400, "bad_request", path, "%s", reason);
}

static bool over(ism_req_error *err, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static bool over(ism_req_error *err, const char *path, const char *fmt, ...)
{
    char reason[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    return ism_req_error_set(err, 422, "over_limit", path, "%s", reason);
}

/* ---------------------------------------------------------------------------------------
 * Paths and small readers */

typedef char path_t[160];

static bool is_identifier(const char *s)
{
    if (!(*s == '_' || (*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z')))
        return false;
    for (s++; *s; s++)
        if (!(*s == '_' || (*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') ||
              (*s >= '0' && *s <= '9')))
            return false;
    return true;
}

/* parent.key, or parent["key"] (shortened) when key is not an identifier. */
static void path_key(path_t out, const char *parent, const char *key)
{
    if (is_identifier(key) && strlen(key) <= 64) {
        snprintf(out, sizeof(path_t), "%s.%s", parent, key);
        return;
    }
    char shown[48];
    size_t j = 0;
    for (const char *s = key; *s && j < 40; s++) {
        unsigned char c = (unsigned char)*s;
        shown[j++] = (c < 0x20 || c == '"' || c == '\\') ? '?' : (char)c;
    }
    shown[j] = '\0';
    snprintf(out, sizeof(path_t), "%s[\"%s%s\"]", parent, shown, strlen(key) > 40 ? "..." : "");
}

static void path_index(path_t out, const char *parent, size_t i)
{
    char index[32];
    snprintf(index, sizeof index, "[%zu]", i);
    size_t n = strlen(parent), k = strlen(index);
    if (n + k >= sizeof(path_t))
        n = sizeof(path_t) - 1 - k;
    memmove(out, parent, n);
    memcpy(out + n, index, k + 1);
}

static const char *type_name(const json_t *v)
{
    switch (json_typeof(v)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY: return "an array";
    case JSON_STRING: return "a string";
    case JSON_INTEGER: return "an integer";
    case JSON_REAL: return "a number";
    case JSON_TRUE: return "true";
    case JSON_FALSE: return "false";
    default: return "null";
    }
}

static const char *num(double v, char *buf) { return ism_jw_format_double(v, buf); }

static bool read_number(const json_t *v, const char *path, double *out, ism_req_error *err)
{
    if (!json_is_number(v))
        return bad(err, path, "expected a number, got %s", type_name(v));
    double d = json_number_value(v);
    if (!isfinite(d))
        return bad(err, path, "numbers must be finite");
    *out = d;
    return true;
}

static bool read_int(const json_t *v, const char *path, int *out, ism_req_error *err)
{
    double d;
    if (!json_is_number(v))
        return bad(err, path, "expected an integer, got %s", type_name(v));
    if (!read_number(v, path, &d, err))
        return false;
    char b[32];
    if (d != floor(d))
        return bad(err, path, "expected an integer, got %s", num(d, b));
    if (d < -1e9 || d > 1e9)
        return over(err, path, "%s is out of range", num(d, b));
    *out = (int)d;
    return true;
}

/* v within [lo, hi], or a 422 naming the bound it crosses, shown as lo_text / hi_text (NULL:
 * the bound itself, num()). */
static bool in_range_shown(double v, double lo, double hi, const char *lo_text,
                           const char *hi_text, const char *path, ism_req_error *err)
{
    char b[32], c[32];
    if (v < lo)
        return over(err, path, "%s is below the minimum %s", num(v, b),
                    lo_text ? lo_text : num(lo, c));
    if (v > hi)
        return over(err, path, "%s is above the limit %s", num(v, b),
                    hi_text ? hi_text : num(hi, c));
    return true;
}

static bool in_range(double v, double lo, double hi, const char *path, ism_req_error *err)
{
    return in_range_shown(v, lo, hi, NULL, NULL, path, err);
}

static bool read_string(const json_t *v, const char *path, const char **out, ism_req_error *err)
{
    if (!json_is_string(v))
        return bad(err, path, "expected a string, got %s", type_name(v));
    *out = json_string_value(v);
    return true;
}

/* An object whose keys must all be in `known` (NULL-terminated). */
static bool check_fields(const json_t *obj, const char *path, const char *const *known,
                         ism_req_error *err)
{
    if (!json_is_object(obj))
        return bad(err, path, "expected an object, got %s", type_name(obj));
    const char *key;
    json_t *val;
    json_object_foreach((json_t *)obj, key, val) {
        bool ok = false;
        for (const char *const *k = known; *k; k++)
            ok = ok || strcmp(*k, key) == 0;
        if (!ok) {
            char list[200] = "";
            for (const char *const *k = known; *k; k++) {
                strncat(list, *k, sizeof list - strlen(list) - 1);
                if (k[1])
                    strncat(list, ", ", sizeof list - strlen(list) - 1);
            }
            path_t p;
            path_key(p, path, key);
            return bad(err, p, "unknown field (expected one of: %s)", list);
        }
    }
    return true;
}

static char *dup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

static bool no_memory(ism_req_error *err)
{
    return ism_req_error_set(err, 500, "no_memory", "", "out of memory decoding the request");
}

/* ---------------------------------------------------------------------------------------
 * Sections */

static bool check_name(const char *name, const char *path, const char *what,
                       ism_req_error *err)
{
    if (strlen(name) > ISM_REQ_MAX_NAME)
        return over(err, path, "%s name is longer than %d bytes", what, ISM_REQ_MAX_NAME);
    if (!is_identifier(name))
        return bad(err, path, "%s name must be letters, digits and _, not starting with a digit",
                   what);
    return true;
}

static bool set_param(ism_request *req, const char *name, double value, ism_req_error *err)
{
    for (size_t i = 0; i < req->nparams; i++)
        if (strcmp(req->params[i].name, name) == 0) {
            req->params[i].value = value;
            return true;
        }
    ism_param *p = realloc(req->params, (req->nparams + 1) * sizeof *p);
    if (!p)
        return no_memory(err);
    req->params = p;
    char *n = dup(name);
    if (!n)
        return no_memory(err);
    p[req->nparams].name = n;
    p[req->nparams].value = value;
    req->nparams++;
    return true;
}

static bool decode_params(const json_t *v, const ism_preset *preset, ism_request *req,
                          ism_req_error *err)
{
    if (!json_is_object(v))
        return bad(err, "$.params", "expected an object of numbers, got %s", type_name(v));
    if (json_object_size(v) > ISM_REQ_MAX_PARAMS)
        return over(err, "$.params", "%zu parameters is above the limit %d",
                    json_object_size(v), ISM_REQ_MAX_PARAMS);
    const char *key;
    json_t *val;
    json_object_foreach((json_t *)v, key, val) {
        path_t p;
        path_key(p, "$.params", key);
        double d;
        if (!check_name(key, p, "parameter", err) || !read_number(val, p, &d, err))
            return false;
        if (preset && !ism_preset_has_param(preset, key)) {
            char names[200];
            ism_preset_param_names(preset, names, sizeof names);
            return bad(err, p, "preset '%s' has no parameter '%s' (it has %s)", preset->name,
                       key, names);
        }
        if (!set_param(req, key, d, err))
            return false;
    }
    return true;
}

static bool add_let(ism_request *req, const char *name, const char *source, const char *path,
                    ism_req_error *err)
{
    if (req->nlets >= ISM_REQ_MAX_LETS)
        return over(err, "$.let", "more than %d let bindings", ISM_REQ_MAX_LETS);
    if (strlen(source) > ISM_REQ_MAX_SOURCE)
        return over(err, path, "the source is longer than %d bytes", ISM_REQ_MAX_SOURCE);
    for (size_t i = 0; i < req->nlets; i++)
        if (strcmp(req->lets[i].name, name) == 0)
            return bad(err, path, "let '%s' is defined twice", name);
    ism_let *l = realloc(req->lets, (req->nlets + 1) * sizeof *l);
    if (!l)
        return no_memory(err);
    req->lets = l;
    char **lp = realloc(req->let_paths, (req->nlets + 1) * sizeof *lp);
    if (!lp)
        return no_memory(err);
    req->let_paths = lp;
    char *n = dup(name), *s = dup(source), *pp = dup(path);
    if (!n || !s || !pp) {
        free(n);
        free(s);
        free(pp);
        return no_memory(err);
    }
    l[req->nlets].name = n;
    l[req->nlets].source = s;
    lp[req->nlets] = pp;
    req->nlets++;
    return true;
}

/* "let": {"p": "...", ...} (in order) or [["p", "..."], ...]. */
static bool decode_lets(const json_t *v, ism_request *req, ism_req_error *err)
{
    if (json_is_object(v)) {
        if (json_object_size(v) > ISM_REQ_MAX_LETS)
            return over(err, "$.let", "%zu let bindings is above the limit %d",
                        json_object_size(v), ISM_REQ_MAX_LETS);
        const char *key;
        json_t *val;
        json_object_foreach((json_t *)v, key, val) {
            path_t p;
            path_key(p, "$.let", key);
            const char *src = NULL;
            if (!check_name(key, p, "let", err) || !read_string(val, p, &src, err) ||
                !add_let(req, key, src, p, err))
                return false;
        }
        return true;
    }
    if (!json_is_array(v))
        return bad(err, "$.let", "expected an object {name: source} or an array of "
                                 "[name, source] pairs, got %s", type_name(v));
    if (json_array_size(v) > ISM_REQ_MAX_LETS)
        return over(err, "$.let", "%zu let bindings is above the limit %d", json_array_size(v),
                    ISM_REQ_MAX_LETS);
    for (size_t i = 0; i < json_array_size(v); i++) {
        const json_t *pair = json_array_get(v, i);
        path_t p, pn, ps;
        path_index(p, "$.let", i);
        if (!json_is_array(pair) || json_array_size(pair) != 2)
            return bad(err, p, "expected a pair [name, source]");
        path_index(pn, p, 0);
        path_index(ps, p, 1);
        const char *name = NULL, *src = NULL;
        if (!read_string(json_array_get(pair, 0), pn, &name, err) ||
            !check_name(name, pn, "let", err) ||
            !read_string(json_array_get(pair, 1), ps, &src, err) ||
            !add_let(req, name, src, ps, err))
            return false;
    }
    return true;
}

static bool decode_box(const json_t *v, double box[6], ism_req_error *err)
{
    if (!json_is_array(v) || json_array_size(v) != 6)
        return bad(err, "$.box", "expected [xmin, ymin, zmin, xmax, ymax, zmax], got %s",
                   json_is_array(v) ? "an array of another length" : type_name(v));
    for (size_t i = 0; i < 6; i++) {
        path_t p;
        path_index(p, "$.box", i);
        if (!read_number(json_array_get(v, i), p, &box[i], err) ||
            !in_range(box[i], -ISM_REQ_MAX_COORD, ISM_REQ_MAX_COORD, p, err))
            return false;
        if (box[i] == 0)
            box[i] = 0; /* -0 means 0 */
    }
    return true;
}

static bool check_box(const double box[6], ism_req_error *err)
{
    static const char axis[3] = {'x', 'y', 'z'};
    double big = 1;
    for (int k = 0; k < 6; k++)
        big = fmax(big, fabs(box[k]));
    for (int k = 0; k < 3; k++) {
        char a[32], b[32];
        if (!(box[k] < box[k + 3]))
            return bad(err, "$.box", "%cmin (%s) must be below %cmax (%s)", axis[k],
                       num(box[k], a), axis[k], num(box[k + 3], b));
        if (box[k + 3] - box[k] < ISM_REQ_MIN_SIDE_REL * big)
            return over(err, "$.box", "the box is thinner along %c (%.3g) than %g of its "
                        "largest coordinate", axis[k], box[k + 3] - box[k],
                        ISM_REQ_MIN_SIDE_REL);
    }
    return true;
}

static bool decode_depth(const json_t *v, ism_request *req, int limit, ism_req_error *err)
{
    static const char *const known[] = {"min", "max", NULL};
    if (!check_fields(v, "$.depth", known, err))
        return false;
    const json_t *mn = json_object_get(v, "min"), *mx = json_object_get(v, "max");
    if (mx) {
        if (!read_int(mx, "$.depth.max", &req->poly.max_depth, err) ||
            !in_range(req->poly.max_depth, 1, limit, "$.depth.max", err))
            return false;
        if (!mn && req->poly.min_depth > req->poly.max_depth)
            req->poly.min_depth = req->poly.max_depth;
    }
    if (mn) {
        if (!read_int(mn, "$.depth.min", &req->poly.min_depth, err) ||
            !in_range(req->poly.min_depth, 0, ISM_REQ_MAX_MIN_DEPTH, "$.depth.min", err))
            return false;
        if (!mx && req->poly.max_depth < req->poly.min_depth)
            req->poly.max_depth = req->poly.min_depth;
    }
    if (req->poly.min_depth > req->poly.max_depth)
        return bad(err, "$.depth", "min (%d) is above max (%d)", req->poly.min_depth,
                   req->poly.max_depth);
    return true;
}

/* "tolerances": every field is one of the table's (core/octree/tolerances.h), within its
 * range. */
static bool decode_tolerances(const json_t *v, ism_request *req, ism_req_error *err)
{
    const char *known[ISM_TOLERANCE_COUNT + 1];
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++)
        known[i] = ism_tolerances[i].key;
    known[ISM_TOLERANCE_COUNT] = NULL;
    if (!check_fields(v, "$.tolerances", known, err))
        return false;
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++) {
        const ism_tolerance *t = &ism_tolerances[i];
        const json_t *f = json_object_get(v, t->key);
        if (!f)
            continue;
        path_t p;
        path_key(p, "$.tolerances", t->key);
        int n;
        double x;
        if (t->is_int ? !read_int(f, p, &n, err) : !read_number(f, p, &x, err))
            return false;
        if (t->is_int)
            x = n;
        if (!in_range(x, t->lo, t->hi, p, err))
            return false;
        ism_tolerance_set(&req->poly, t, x);
    }
    return true;
}

/* See proto/request.h. */
const char *ism_three_digits(double v, int dir, char buf[32])
{
    double unit = pow(10, floor(log10(v)) - 2), q = v / unit;
    q = dir > 0 ? ceil(q) : dir < 0 ? floor(q) : nearbyint(q);
    snprintf(buf, 32, "%.3g", q * unit);
    return buf;
}

double ism_request_default_error(const double box[6])
{
    return ISM_REQ_DEFAULT_ERROR_REL * ism_box_diagonal(box);
}

bool ism_request_error_in_range(double e, const double box[6], const char *path,
                                ism_req_error *err)
{
    char b[32], c[32], d[32], g[32];
    if (!(e > 0))
        return over(err, path, "%s must be above 0 (a distance in model units)", num(e, b));
    /* the limits to three digits, rounded inwards: a value copied from the message passes */
    double diag = ism_box_diagonal(box), lo = ISM_REQ_MIN_ERROR_REL * diag;
    if (!in_range_shown(e, lo, diag, ism_three_digits(lo, 1, c), ism_three_digits(diag, -1, g),
                        path, err)) {
        size_t at = strlen(err->message);
        if (e < lo)
            snprintf(err->message + at, sizeof err->message - at, " (%s of the box diagonal %s)",
                     num(ISM_REQ_MIN_ERROR_REL, d), ism_three_digits(diag, 0, g));
        else
            snprintf(err->message + at, sizeof err->message - at, " (the box diagonal)");
        return false;
    }
    return true;
}

/* "max_error": E > 0 in model units, at least ISM_REQ_MIN_ERROR_REL of the box diagonal and
 * at most the diagonal; left out, ISM_REQ_DEFAULT_ERROR_REL of the diagonal (resolved here,
 * so the key and the canonical request hold the number: an explicit E equal to the default
 * is the same request); null, no bound (the depth path: flatness tolerances and depth.max
 * decide). Under a bound without an explicit depth.max, the operator's depth limit becomes
 * the safety limit: the bound, not the preset's depth, decides (a preset p may set a lower
 * one: ism_preset_bound_depth). v is NULL when left out. */
static bool decode_max_error(const json_t *v, const json_t *depth, const ism_preset *p,
                             ism_request *req, int depth_limit, ism_req_error *err)
{
    if (json_is_null(v)) {
        req->poly.max_error = 0;
        return true;
    }
    double e;
    if (!v)
        e = ism_request_default_error(req->poly.box);
    else if (!read_number(v, "$.max_error", &e, err))
        return false;
    if (!ism_request_error_in_range(e, req->poly.box, "$.max_error", err))
        return false;
    req->poly.max_error = e;
    if (!(depth && json_object_get(depth, "max")))
        req->poly.max_depth = ism_preset_bound_depth(p, depth_limit);
    return true;
}

/* A boolean at path that only an error bound makes meaningful: true without "max_error"
 * is refused with why (its reason). */
static bool decode_bound_flag(const json_t *v, const ism_request *req, const char *path,
                              const char *why, bool *out, ism_req_error *err)
{
    if (!json_is_boolean(v))
        return bad(err, path, "expected true or false, got %s", type_name(v));
    if (json_is_true(v) && !(req->poly.max_error > 0))
        return bad(err, path, "%s: not with \"max_error\": null (leave it out for the "
                   "default bound, or give one)", why);
    *out = json_is_true(v);
    return true;
}

/* "simplify": true or false (after "max_error"; default false, whichever mesher runs:
 * ism_simplify_after). Without a bound there is nothing to keep the simplification honest,
 * so true is refused. */
static bool decode_simplify(const json_t *v, ism_request *req, ism_req_error *err)
{
    return decode_bound_flag(v, req, "$.simplify",
                             "the simplification keeps the mesh within \"max_error\"",
                             &req->simplify, err);
}

/* "straddle": true or false (after "max_error"; default false). The polygoniser then moves
 * vertices where the surface bends one way toward its convex side by 0.9 E and sizes the
 * cells for it (core/octree/straddle.h): fewer triangles within the same bound. Only a
 * bound says how far a vertex may move, so true without one is refused. */
static bool decode_straddle(const json_t *v, ism_request *req, ism_req_error *err)
{
    return decode_bound_flag(v, req, "$.straddle",
                             "the vertices move by a share of \"max_error\"",
                             &req->poly.straddle, err);
}

/* "dual": true or false (after "max_error"; default true under it). On a closed surface
 * without min/max and without a singular locus the polygoniser makes one vertex per octree
 * leaf and quads across the crossed lattice edges, cells sized by those triangles' error
 * (core/octree/dual.h); elsewhere, or with false, the primal polygons (the stats say which,
 * and why, core/octree/mesher.h). The cells are sized by the bound, so true without one is
 * refused. */
static bool decode_dual(const json_t *v, ism_request *req, ism_req_error *err)
{
    return decode_bound_flag(v, req, "$.dual", "its cells are sized by \"max_error\"",
                             &req->poly.dual, err);
}

/* "quality": "raw" or "good" (ism_quality_lookup). */
static bool decode_quality(const json_t *v, ism_request *req, ism_req_error *err)
{
    const char *name = NULL; /* set by read_string (gcc -O2 cannot see it once inlined) */
    if (!read_string(v, "$.quality", &name, err))
        return false;
    int q = ism_quality_lookup(name);
    if (q < 0)
        return bad(err, "$.quality", "unknown quality \"%.40s\" (raw or good)", name);
    req->quality = q;
    return true;
}

static const char *const attr_names[] = {"normal", "mean_curvature", "gauss_curvature",
                                         "class"};

static bool decode_attributes(const json_t *v, unsigned *out, ism_req_error *err)
{
    if (!json_is_array(v))
        return bad(err, "$.output.attributes", "expected an array of names, got %s",
                   type_name(v));
    unsigned set = 0;
    for (size_t i = 0; i < json_array_size(v); i++) {
        path_t p;
        path_index(p, "$.output.attributes", i);
        const char *name;
        if (!read_string(json_array_get(v, i), p, &name, err))
            return false;
        int found = -1;
        for (int k = 0; k < 4; k++)
            if (strcmp(attr_names[k], name) == 0)
                found = k;
        if (found < 0)
            return bad(err, p, "unknown attribute (expected one of: normal, mean_curvature, "
                               "gauss_curvature, class)");
        if (set & (1u << found))
            return bad(err, p, "'%s' is listed twice", name);
        set |= 1u << found;
    }
    *out = set;
    return true;
}

static bool decode_output(const json_t *v, ism_request *req, ism_req_error *err)
{
    static const char *const known[] = {"format", "position_bits", "normal_bits",
                                        "curvature_bits", "attributes", "draco", NULL};
    if (!check_fields(v, "$.output", known, err))
        return false;
    const json_t *f = json_object_get(v, "format");
    if (f) {
        const char *name;
        if (!read_string(f, "$.output.format", &name, err))
            return false;
        int k = ism_format_lookup(name);
        if (k < 0)
            return bad(err, "$.output.format",
                       "unknown format (expected one of: drc, glb, ply, obj, stl, png)");
        req->format = (enum ism_format)k;
    }
    const json_t *pb = json_object_get(v, "position_bits");
    if (pb && (!read_int(pb, "$.output.position_bits", &req->position_bits, err) ||
               !in_range(req->position_bits, 6, 24, "$.output.position_bits", err)))
        return false;
    const json_t *nb = json_object_get(v, "normal_bits");
    if (nb && (!read_int(nb, "$.output.normal_bits", &req->normal_bits, err) ||
               !in_range(req->normal_bits, 4, 16, "$.output.normal_bits", err)))
        return false;
    const json_t *cb = json_object_get(v, "curvature_bits");
    if (cb) {
        if (!read_int(cb, "$.output.curvature_bits", &req->curvature_bits, err))
            return false;
        if (req->curvature_bits != 0 &&
            !in_range(req->curvature_bits, 8, 24, "$.output.curvature_bits", err))
            return false;
    }
    const json_t *at = json_object_get(v, "attributes");
    if (at && !decode_attributes(at, &req->attributes, err))
        return false;
    const json_t *dr = json_object_get(v, "draco");
    if (dr && !json_is_boolean(dr))
        return bad(err, "$.output.draco", "expected true or false");
    if (dr)
        req->plain_glb = !json_is_true(dr);
    return true;
}

/* "preview": true or false (after "quality", "output" and "curves", which it checks): a
 * preview computes none of what curves, the quality pass and the curvatures and classes
 * need, so it sends positions and normals only and refuses curves and quality "good". */
static bool decode_preview(const json_t *v, ism_request *req, ism_req_error *err)
{
    if (!json_is_boolean(v))
        return bad(err, "$.preview", "expected true or false, got %s", type_name(v));
    req->preview = json_is_true(v);
    if (!req->preview)
        return true;
    if (req->ncurves)
        return bad(err, "$.preview", "a preview has no curves: leave out \"curves\"");
    if (req->quality != ISM_QUALITY_RAW)
        return bad(err, "$.preview", "a preview has no quality pass: leave out \"quality\"");
    req->attributes &= ISM_ATTR_NORMAL;
    return true;
}

/* ---------------------------------------------------------------------------------------
 * The whole request */

static void set_defaults(ism_request *req, int depth_limit)
{
    ism_poly_options_default(&req->poly);
    ism_poly_options *o = &req->poly;
    o->max_depth = o->max_depth < depth_limit ? o->max_depth : depth_limit;
    o->min_depth = o->min_depth < o->max_depth ? o->min_depth : o->max_depth;
    req->format = ISM_FORMAT_DRC;
    req->position_bits = ISM_REQ_DEFAULT_POSITION_BITS;
    req->normal_bits = ISM_REQ_DEFAULT_NORMAL_BITS;
    req->curvature_bits = ISM_REQ_DEFAULT_CURVATURE_BITS;
    req->attributes = ISM_ATTR_DEFAULT;
}

static bool apply_preset(ism_request *req, const ism_preset *p, int depth_limit,
                         ism_req_error *err)
{
    if (!(req->preset = dup(p->name)) || !(req->expr = dup(p->expr)))
        return no_memory(err);
    for (size_t i = 0; i < p->nlets; i++) {
        path_t path;
        snprintf(path, sizeof path, "$.preset (let %s)", p->lets[i].name);
        if (!add_let(req, p->lets[i].name, p->lets[i].source, path, err))
            return false;
    }
    for (size_t i = 0; i < p->nparams; i++)
        if (!set_param(req, p->params[i].name, p->params[i].value, err))
            return false;
    memcpy(req->poly.box, p->box, sizeof req->poly.box);
    req->poly.max_depth = p->max_depth < depth_limit ? p->max_depth : depth_limit;
    req->poly.min_depth = p->min_depth < req->poly.max_depth ? p->min_depth : req->poly.max_depth;
    return true;
}

static bool decode_root(const json_t *root, ism_request *req, int depth_limit,
                        ism_req_error *err)
{
    static const char *const known[] = {"expr", "preset", "params", "let", "box", "depth",
                                        "max_error", "quality", "tolerances", "output", "curves",
                                        "preview", "simplify", "straddle", "dual", NULL};
    if (!json_is_object(root))
        return bad(err, "$", "a request is a JSON object, got %s", type_name(root));
    if (!check_fields(root, "$", known, err))
        return false;

    const json_t *expr = json_object_get(root, "expr"), *preset = json_object_get(root, "preset");
    const json_t *lets = json_object_get(root, "let"), *params = json_object_get(root, "params");
    const ism_preset *p = NULL;
    if (expr && preset)
        return bad(err, "$.preset", "give either \"expr\" or \"preset\", not both");
    if (!expr && !preset)
        return bad(err, "$", "missing the surface: give \"expr\" (an expression in x, y, z) "
                             "or \"preset\" (a name from GET /v1/presets)");
    if (preset) {
        const char *name;
        if (!read_string(preset, "$.preset", &name, err))
            return false;
        if (!(p = ism_preset_find(name)))   /* the gallery is too long to list here */
            return bad(err, "$.preset", "unknown preset (GET /v1/presets lists the %zu known)",
                       ism_preset_count());
        if (lets)
            return bad(err, "$.let", "a preset brings its own let bindings; write the "
                                     "expression out to change them");
        if (!apply_preset(req, p, depth_limit, err))
            return false;
    } else {
        const char *src;
        if (!read_string(expr, "$.expr", &src, err))
            return false;
        if (!*src)
            return bad(err, "$.expr", "the expression is empty");
        if (strlen(src) > ISM_REQ_MAX_SOURCE)
            return over(err, "$.expr", "the expression is longer than %d bytes",
                        ISM_REQ_MAX_SOURCE);
        if (!(req->expr = dup(src)))
            return no_memory(err);
        if (lets && !decode_lets(lets, req, err))
            return false;
    }
    if (params && !decode_params(params, p, req, err))
        return false;

    const json_t *v;
    if ((v = json_object_get(root, "box")) && !decode_box(v, req->poly.box, err))
        return false;
    if (!check_box(req->poly.box, err))
        return false;
    const json_t *depth = json_object_get(root, "depth");
    if (depth && !decode_depth(depth, req, depth_limit, err))
        return false;
    /* a preview is coarse by depth: one that leaves max_error out has no bound */
    const json_t *bound = json_object_get(root, "max_error");
    if (!bound && json_is_true(json_object_get(root, "preview")))
        bound = json_null();
    if (!decode_max_error(bound, depth, p, req, depth_limit, err))
        return false;
    /* under a bound: the dual mesh where it applies, any mesh simplified only when asked */
    req->poly.dual = req->poly.max_error > 0;
    req->simplify = false;
    if ((v = json_object_get(root, "simplify")) && !decode_simplify(v, req, err))
        return false;
    if ((v = json_object_get(root, "dual")) && !decode_dual(v, req, err))
        return false;
    if ((v = json_object_get(root, "straddle")) && !decode_straddle(v, req, err))
        return false;
    if ((v = json_object_get(root, "quality")) && !decode_quality(v, req, err))
        return false;
    if ((v = json_object_get(root, "tolerances")) && !decode_tolerances(v, req, err))
        return false;
    if ((v = json_object_get(root, "output")) && !decode_output(v, req, err))
        return false;
    if ((v = json_object_get(root, "curves")) && !ism_request_decode_curves(v, req, err))
        return false;
    if ((v = json_object_get(root, "preview")) && !decode_preview(v, req, err))
        return false;
    return true;
}

bool ism_request_decode(const char *json, size_t len, const ism_request_limits *lim,
                        ism_request *req, ism_req_error *err)
{
    memset(req, 0, sizeof *req);
    memset(err, 0, sizeof *err);
    int depth_limit = lim ? lim->max_depth : ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT;
    if (depth_limit <= 0 || depth_limit > ISM_MAX_DEPTH_LIMIT)
        depth_limit = depth_limit <= 0 ? ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT : ISM_MAX_DEPTH_LIMIT;
    set_defaults(req, depth_limit);

    if (len > ISM_REQ_MAX_BYTES)
        return ism_req_error_set(err, 422, "too_large", "$", "the request is %zu bytes, above "
                                 "the limit %d", len, ISM_REQ_MAX_BYTES);
    size_t blank = 0;
    while (blank < len && strchr(" \t\r\n", json[blank]))
        blank++;
    if (blank == len) /* say so, not "'[' or '{' expected near end of file" */
        return ism_req_error_set(err, 400, "bad_json", "", "the request body is empty: send a "
                                 "JSON object, e.g. {\"preset\": \"sphere\"} (GET /v1/presets "
                                 "lists the names)");
    json_error_t je;
    json_t *root = json_loadb(json, len, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        ism_req_error_set(err, 400, "bad_json", "", "invalid JSON at line %d, column %d: %s",
                          je.line, je.column, je.text);
        err->line = je.line;
        err->column = je.column;
        return false;
    }
    bool ok = decode_root(root, req, depth_limit, err);
    json_decref(root);
    if (!ok) {
        ism_request_free(req);
        return false;
    }
    return true;
}

void ism_request_free(ism_request *req)
{
    for (size_t i = 0; i < req->nparams; i++)
        free((char *)req->params[i].name);
    for (size_t i = 0; i < req->nlets; i++) {
        free((char *)req->lets[i].name);
        free((char *)req->lets[i].source);
        free(req->let_paths[i]);
    }
    free(req->params);
    free(req->lets);
    free(req->let_paths);
    free(req->preset);
    free(req->expr);
    ism_request_free_curves(req);
    memset(req, 0, sizeof *req);
}

/* ---------------------------------------------------------------------------------------
 * The readers for the other sections' decoders (request_internal.h) */

bool ism_rq_check_fields(const json_t *obj, const char *path, const char *const *known,
                         ism_req_error *err)
{
    return check_fields(obj, path, known, err);
}

bool ism_rq_read_number(const json_t *v, const char *path, double *out, ism_req_error *err)
{
    return read_number(v, path, out, err);
}

const char *ism_rq_type_name(const json_t *v) { return type_name(v); }

void ism_rq_path_key(char out[160], const char *parent, const char *key)
{
    path_key(out, parent, key);
}

void ism_rq_path_index(char out[160], const char *parent, size_t i)
{
    path_index(out, parent, i);
}
