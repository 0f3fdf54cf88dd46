/* test_request.c — strict request decoding: a table of bad requests with their exact status,
 * code, JSON path and message; defaults filled from the polygoniser; presets expanded; both
 * let forms; the error JSON document. */
#include <criterion/criterion.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "proto/presets.h"
#include "proto/request.h"

typedef struct bad_case {
    const char *json;
    int status;
    const char *code;
    const char *path;
    const char *message; /* exact, or a prefix when it ends with '*' */
} bad_case;

static const bad_case bad_cases[] = {
    /* JSON itself (jansson flags: duplicates, UTF-8, trailing garbage, NaN, overflow) */
    {"{\"expr\": \"x\",", 400, "bad_json", "", "invalid JSON at line 1, column *"},
    {"", 400, "bad_json", "", "the request body is empty: send a JSON object, e.g. "
     "{\"preset\": \"sphere\"} (GET /v1/presets lists the names)"},
    {" \r\n\t", 400, "bad_json", "", "the request body is empty*"},
    {"{\"expr\": \"x\", \"expr\": \"y\"}", 400, "bad_json", "", "invalid JSON at line 1*"},
    {"{\"expr\": \"x\xff\"}", 400, "bad_json", "", "invalid JSON at line 1*"},
    {"{\"expr\": \"x\"} x", 400, "bad_json", "", "invalid JSON at line 1*"},
    {"{\"expr\": \"x\", \"box\": [NaN, 0, 0, 1, 1, 1]}", 400, "bad_json", "", "invalid JSON*"},
    {"{\"expr\": \"x\", \"box\": [1e999, 0, 0, 1, 1, 1]}", 400, "bad_json", "", "invalid JSON*"},
    /* shape */
    {"[1]", 400, "bad_request", "$", "$: a request is a JSON object, got an array"},
    {"{}", 400, "bad_request", "$",
     "$: missing the surface: give \"expr\" (an expression in x, y, z) or \"preset\" (a name "
     "from GET /v1/presets)"},
    {"{\"expr\": \"x\", \"colour\": 1}", 400, "bad_request", "$.colour",
     "$.colour: unknown field (expected one of: expr, preset, params, let, box, depth, "
     "max_error, quality, tolerances, output, curves, preview, simplify, straddle, dual)"},
    {"{\"expr\": \"x\", \"tolerances\": {\"gradiant\": 0.9}}", 400, "bad_request",
     "$.tolerances.gradiant",
     "$.tolerances.gradiant: unknown field (expected one of: gradient, double_root_eps, "
     "double_root_iters, stitch, flat_normal, flat_plane)"},
    {"{\"expr\": \"x\", \"depth\": {\"maximum\": 5}}", 400, "bad_request", "$.depth.maximum",
     "$.depth.maximum: unknown field (expected one of: min, max)"},
    {"{\"expr\": \"x\", \"output\": {\"fromat\": \"glb\"}}", 400, "bad_request",
     "$.output.fromat",
     "$.output.fromat: unknown field (expected one of: format, position_bits, normal_bits, "
     "curvature_bits, attributes, draco)"},
    {"{\"expr\": \"x\", \"a b\": 1}", 400, "bad_request", "$[\"a b\"]",
     "$[\"a b\"]: unknown field (expected one of: expr, preset, params, let, box, depth, "
     "max_error, quality, tolerances, output, curves, preview, simplify, straddle, dual)"},
    /* surface */
    {"{\"expr\": 3}", 400, "bad_request", "$.expr", "$.expr: expected a string, got an integer"},
    {"{\"expr\": \"\"}", 400, "bad_request", "$.expr", "$.expr: the expression is empty"},
    {"{\"expr\": \"x\", \"preset\": \"torus\"}", 400, "bad_request", "$.preset",
     "$.preset: give either \"expr\" or \"preset\", not both"},
    {"{\"preset\": \"tours\"}", 400, "bad_request", "$.preset",
     "$.preset: unknown preset (GET /v1/presets lists the 42 known)"},
    {"{\"preset\": \"torus\", \"params\": {\"q\": 1}}", 400, "bad_request", "$.params.q",
     "$.params.q: preset 'torus' has no parameter 'q' (it has R, r)"},
    {"{\"preset\": \"klein-bottle\", \"params\": {\"q\": 1}}", 400, "bad_request",
     "$.params.q", "$.params.q: preset 'klein-bottle' has no parameter 'q' (it has none)"},
    {"{\"preset\": \"torus\", \"let\": {\"p\": \"x\"}}", 400, "bad_request", "$.let",
     "$.let: a preset brings its own let bindings; write the expression out to change them"},
    {"{\"expr\": \"r\", \"params\": {\"r\": \"1\"}}", 400, "bad_request", "$.params.r",
     "$.params.r: expected a number, got a string"},
    {"{\"expr\": \"r\", \"params\": [1]}", 400, "bad_request", "$.params",
     "$.params: expected an object of numbers, got an array"},
    {"{\"expr\": \"x\", \"params\": {\"2r\": 1}}", 400, "bad_request", "$.params[\"2r\"]",
     "$.params[\"2r\"]: parameter name must be letters, digits and _, not starting with a "
     "digit"},
    {"{\"expr\": \"p\", \"let\": {\"p\": 1}}", 400, "bad_request", "$.let.p",
     "$.let.p: expected a string, got an integer"},
    {"{\"expr\": \"p\", \"let\": [[\"p\"]]}", 400, "bad_request", "$.let[0]",
     "$.let[0]: expected a pair [name, source]"},
    {"{\"expr\": \"p\", \"let\": [[\"p\", \"x\"], [\"p\", \"y\"]]}", 400, "bad_request",
     "$.let[1][1]", "$.let[1][1]: let 'p' is defined twice"},
    {"{\"expr\": \"p\", \"let\": \"p = x\"}", 400, "bad_request", "$.let",
     "$.let: expected an object {name: source} or an array of [name, source] pairs, got a "
     "string"},
    /* box */
    {"{\"expr\": \"x\", \"box\": [0, 0, 0, 1, 1]}", 400, "bad_request", "$.box",
     "$.box: expected [xmin, ymin, zmin, xmax, ymax, zmax], got an array of another length"},
    {"{\"expr\": \"x\", \"box\": {\"min\": 0}}", 400, "bad_request", "$.box",
     "$.box: expected [xmin, ymin, zmin, xmax, ymax, zmax], got an object"},
    {"{\"expr\": \"x\", \"box\": [0, 0, \"0\", 1, 1, 1]}", 400, "bad_request", "$.box[2]",
     "$.box[2]: expected a number, got a string"},
    {"{\"expr\": \"x\", \"box\": [0, 0, 0, 1, 0, 1]}", 400, "bad_request", "$.box",
     "$.box: ymin (0) must be below ymax (0)"},
    {"{\"expr\": \"x\", \"box\": [2, 0, 0, 1, 1, 1]}", 400, "bad_request", "$.box",
     "$.box: xmin (2) must be below xmax (1)"},
    {"{\"expr\": \"x\", \"box\": [-1e7, 0, 0, 1, 1, 1]}", 422, "over_limit", "$.box[0]",
     "$.box[0]: -10000000 is below the minimum -1000000"},
    {"{\"expr\": \"x\", \"box\": [0, 0, 0, 1, 1, 2e6]}", 422, "over_limit", "$.box[5]",
     "$.box[5]: 2000000 is above the limit 1000000"},
    {"{\"expr\": \"x\", \"box\": [1000, 0, 0, 1000.0000001, 1, 1]}", 422, "over_limit", "$.box",
     "$.box: the box is thinner along x (1e-07) than 1e-06 of its largest "
     "coordinate"},
    /* depth */
    {"{\"expr\": \"x\", \"depth\": {\"max\": 14}}", 422, "over_limit", "$.depth.max",
     "$.depth.max: 14 is above the limit 10"},
    {"{\"expr\": \"x\", \"depth\": {\"max\": 0}}", 422, "over_limit", "$.depth.max",
     "$.depth.max: 0 is below the minimum 1"},
    {"{\"expr\": \"x\", \"depth\": {\"min\": 7, \"max\": 8}}", 422, "over_limit", "$.depth.min",
     "$.depth.min: 7 is above the limit 6"},
    {"{\"expr\": \"x\", \"depth\": {\"min\": 5, \"max\": 4}}", 400, "bad_request", "$.depth",
     "$.depth: min (5) is above max (4)"},
    {"{\"expr\": \"x\", \"depth\": {\"max\": 7.5}}", 400, "bad_request", "$.depth.max",
     "$.depth.max: expected an integer, got 7.5"},
    {"{\"expr\": \"x\", \"depth\": {\"max\": \"7\"}}", 400, "bad_request", "$.depth.max",
     "$.depth.max: expected an integer, got a string"},
    {"{\"expr\": \"x\", \"depth\": 7}", 400, "bad_request", "$.depth",
     "$.depth: expected an object, got an integer"},
    /* max_error: above 0, within 1e-9 .. 1 of the box diagonal (default box: 2 sqrt 3) */
    {"{\"expr\": \"x\", \"max_error\": 0}", 422, "over_limit", "$.max_error",
     "$.max_error: 0 must be above 0 (a distance in model units)"},
    {"{\"expr\": \"x\", \"max_error\": -0.1}", 422, "over_limit", "$.max_error",
     "$.max_error: -0.1 must be above 0*"},
    {"{\"expr\": \"x\", \"max_error\": 3e-9}", 422, "over_limit", "$.max_error",
     "$.max_error: 3e-09 is below the minimum 3.47e-09 (1e-09 of the box diagonal 3.46)"},
    {"{\"expr\": \"x\", \"max_error\": 3.5}", 422, "over_limit", "$.max_error",
     "$.max_error: 3.5 is above the limit 3.46 (the box diagonal)"},
    {"{\"expr\": \"x\", \"max_error\": \"1e-3\"}", 400, "bad_request", "$.max_error",
     "$.max_error: expected a number, got a string"},
    {"{\"expr\": \"x\", \"max_error\": [0.01]}", 400, "bad_request", "$.max_error",
     "$.max_error: expected a number, got an array"},
    /* simplify: a boolean, true only under a bound (the default one too) */
    {"{\"expr\": \"x\", \"max_error\": null, \"simplify\": true}", 400, "bad_request",
     "$.simplify", "$.simplify: the simplification keeps the mesh within \"max_error\": not "
     "with \"max_error\": null (leave it out for the default bound, or give one)"},
    {"{\"expr\": \"x\", \"max_error\": 0.01, \"simplify\": 1}", 400, "bad_request",
     "$.simplify", "$.simplify: expected true or false, got an integer"},
    /* straddle: a boolean, true only under max_error */
    {"{\"expr\": \"x\", \"max_error\": null, \"straddle\": true}", 400, "bad_request",
     "$.straddle", "$.straddle: the vertices move by a share of \"max_error\": not with "
     "\"max_error\": null (leave it out for the default bound, or give one)"},
    {"{\"expr\": \"x\", \"max_error\": 0.01, \"straddle\": \"yes\"}", 400, "bad_request",
     "$.straddle", "$.straddle: expected true or false, got a string"},
    /* dual: a boolean, true only under max_error */
    {"{\"dual\": true, \"expr\": \"x\", \"max_error\": null}", 400, "bad_request", "$.dual",
     "$.dual: its cells are sized by \"max_error\": not with \"max_error\": null (leave it "
     "out for the default bound, or give one)"},
    {"{\"expr\": \"x\", \"max_error\": 0.01, \"dual\": 1}", 400, "bad_request", "$.dual",
     "$.dual: expected true or false, got an integer"},
    /* quality: "raw" or "good" */
    {"{\"expr\": \"x\", \"quality\": \"best\"}", 400, "bad_request", "$.quality",
     "$.quality: unknown quality \"best\" (raw or good)"},
    {"{\"expr\": \"x\", \"quality\": \"Good\"}", 400, "bad_request", "$.quality",
     "$.quality: unknown quality \"Good\" (raw or good)"},
    {"{\"expr\": \"x\", \"quality\": 1}", 400, "bad_request", "$.quality",
     "$.quality: expected a string, got an integer"},
    {"{\"expr\": \"x\", \"quality\": true}", 400, "bad_request", "$.quality",
     "$.quality: expected a string, got*"},
    {"{\"expr\": \"x\", \"quality\": null}", 400, "bad_request", "$.quality",
     "$.quality: expected a string, got null"},
    /* tolerances */
    {"{\"expr\": \"x\", \"tolerances\": {\"gradient\": 2}}", 422, "over_limit",
     "$.tolerances.gradient", "$.tolerances.gradient: 2 is above the limit 1"},
    {"{\"expr\": \"x\", \"tolerances\": {\"double_root_iters\": 0}}", 422, "over_limit",
     "$.tolerances.double_root_iters",
     "$.tolerances.double_root_iters: 0 is below the minimum 1"},
    {"{\"expr\": \"x\", \"tolerances\": {\"double_root_iters\": 61}}", 422, "over_limit",
     "$.tolerances.double_root_iters",
     "$.tolerances.double_root_iters: 61 is above the limit 60"},
    {"{\"expr\": \"x\", \"tolerances\": {\"stitch\": 0}}", 422, "over_limit",
     "$.tolerances.stitch", "$.tolerances.stitch: 0 is below the minimum 1e-09"},
    {"{\"expr\": \"x\", \"tolerances\": {\"flat_plane\": null}}", 400, "bad_request",
     "$.tolerances.flat_plane", "$.tolerances.flat_plane: expected a number, got null"},
    /* output */
    {"{\"expr\": \"x\", \"output\": {\"format\": \"gltf\"}}", 400, "bad_request",
     "$.output.format",
     "$.output.format: unknown format (expected one of: drc, glb, ply, obj, stl, png)"},
    {"{\"expr\": \"x\", \"output\": {\"position_bits\": 30}}", 422, "over_limit",
     "$.output.position_bits", "$.output.position_bits: 30 is above the limit 24"},
    {"{\"expr\": \"x\", \"output\": {\"normal_bits\": 2}}", 422, "over_limit",
     "$.output.normal_bits", "$.output.normal_bits: 2 is below the minimum 4"},
    {"{\"expr\": \"x\", \"output\": {\"curvature_bits\": 4}}", 422, "over_limit",
     "$.output.curvature_bits", "$.output.curvature_bits: 4 is below the minimum 8"},
    {"{\"expr\": \"x\", \"output\": {\"attributes\": [\"normal\", \"normal\"]}}", 400,
     "bad_request", "$.output.attributes[1]",
     "$.output.attributes[1]: 'normal' is listed twice"},
    {"{\"expr\": \"x\", \"output\": {\"attributes\": [\"normals\"]}}", 400, "bad_request",
     "$.output.attributes[0]",
     "$.output.attributes[0]: unknown attribute (expected one of: normal, mean_curvature, "
     "gauss_curvature, class)"},
    {"{\"expr\": \"x\", \"output\": {\"attributes\": \"normal\"}}", 400, "bad_request",
     "$.output.attributes", "$.output.attributes: expected an array of names, got a string"},
};

static bool matches(const char *got, const char *want)
{
    size_t n = strlen(want);
    if (n && want[n - 1] == '*')
        return strncmp(got, want, n - 1) == 0;
    return strcmp(got, want) == 0;
}

Test(request, bad_requests_have_exact_status_path_and_message)
{
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        const bad_case *c = &bad_cases[i];
        ism_request req;
        ism_req_error err;
        bool ok = ism_request_decode(c->json, strlen(c->json), NULL, &req, &err);
        cr_expect(!ok, "accepted: %s", c->json);
        if (ok) {
            ism_request_free(&req);
            continue;
        }
        cr_expect_eq(err.status, c->status, "%s: status %d", c->json, err.status);
        cr_expect_str_eq(err.code, c->code, "%s", c->json);
        cr_expect_str_eq(err.path, c->path, "%s", c->json);
        cr_expect(matches(err.message, c->message), "%s\n got: %s\nwant: %s", c->json,
                  err.message, c->message);
        ism_request_free(&req); /* must be safe after a failure */
    }
}

Test(request, max_error_limits_in_the_message_pass_when_copied)
{
    /* the messages give the limits to three digits, rounded inwards (box diagonal 2 sqrt 3 =
     * 3.4641...: minimum 3.47e-09, limit 3.46): the numbers a user copies from them pass, in
     * the default box and in a box whose diagonal has many digits */
    const char *ok[] = {"{\"expr\": \"x\", \"max_error\": 3.47e-09}",
                        "{\"expr\": \"x\", \"max_error\": 3.46}",
                        "{\"expr\": \"x\", \"box\": [0, 0, 0, 1, 2, 3], \"max_error\": 3.75e-09}",
                        "{\"expr\": \"x\", \"box\": [0, 0, 0, 1, 2, 3], \"max_error\": 3.74}"};
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) {
        ism_request req;
        ism_req_error err;
        cr_expect(ism_request_decode(ok[i], strlen(ok[i]), NULL, &req, &err), "%s: %s", ok[i],
                  err.message);
        ism_request_free(&req);
    }
    const char *below = "{\"expr\": \"x\", \"box\": [0, 0, 0, 1, 2, 3], \"max_error\": 1e-9}";
    ism_request req;
    ism_req_error err;
    cr_assert(!ism_request_decode(below, strlen(below), NULL, &req, &err));
    cr_expect_str_eq(err.message, "$.max_error: 1e-09 is below the minimum 3.75e-09 (1e-09 of "
                                  "the box diagonal 3.74)");
    ism_request_free(&req);
}

Test(request, json_syntax_errors_carry_line_and_column)
{
    const char *json = "{\n  \"expr\": \"x\",\n  \"box\": [1, 2,, 3]\n}";
    ism_request req;
    ism_req_error err;
    cr_assert(!ism_request_decode(json, strlen(json), NULL, &req, &err));
    cr_expect_eq(err.line, 3);
    cr_expect_gt(err.column, 10);
}

/* Expression errors: the parser's column, the path of the text it was in. */
typedef struct expr_case {
    const char *json;
    int status;
    const char *code;
    const char *path;
    int column;
} expr_case;

Test(request, expression_errors_name_the_source_and_column)
{
    static const expr_case cases[] = {
        {"{\"expr\": \"x^2 + sinn(y)\"}", 400, "bad_expression", "$.expr", 7},
        {"{\"expr\": \"p\", \"let\": {\"p\": \"x +* y\"}}", 400, "bad_expression", "$.let.p", 4},
        {"{\"expr\": \"p + q\", \"let\": [[\"p\", \"x\"], [\"q\", \"x +\"]]}", 400,
         "bad_expression", "$.let[1][1]", 4},
        {"{\"expr\": \"x\", \"params\": {\"x\": 1}}", 400, "bad_expression", "$.params.x", 0},
        {"{\"expr\": \"x^1000\"}", 422, "over_limit", "$.expr", 2},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const expr_case *c = &cases[i];
        ism_request req;
        ism_req_error err;
        cr_assert(ism_request_decode(c->json, strlen(c->json), NULL, &req, &err), "%s: %s",
                  c->json, err.message);
        ism_tape *t = ism_request_compile(&req, &err);
        cr_expect_null(t, "%s compiled", c->json);
        if (t) {
            ism_tape_free(t);
            ism_request_free(&req);
            continue;
        }
        cr_expect_eq(err.status, c->status, "%s: %d %s", c->json, err.status, err.message);
        cr_expect_str_eq(err.code, c->code, "%s", c->json);
        cr_expect_str_eq(err.path, c->path, "%s", c->json);
        if (c->column) {
            cr_expect_geq(err.column, c->column, "%s: column %d", c->json, err.column);
            cr_expect_leq(err.column, c->column + 1, "%s: column %d", c->json, err.column);
            char prefix[64];
            snprintf(prefix, sizeof prefix, "%s: column %d: ", c->path, err.column);
            cr_expect(strncmp(err.message, prefix, strlen(prefix)) == 0, "%s", err.message);
        } else {
            cr_expect(strncmp(err.message, c->path, strlen(c->path)) == 0, "%s", err.message);
        }
        ism_request_free(&req);
    }
}

Test(request, over_long_sources_and_bodies_are_limits)
{
    size_t n = ISM_REQ_MAX_SOURCE + 1;
    char *json = malloc(n + 32);
    strcpy(json, "{\"expr\": \"");
    memset(json + 10, 'x', n);
    strcpy(json + 10 + n, "\"}");
    ism_request req;
    ism_req_error err;
    cr_assert(!ism_request_decode(json, strlen(json), NULL, &req, &err));
    cr_expect_eq(err.status, 422);
    cr_expect_str_eq(err.message, "$.expr: the expression is longer than 16384 bytes");
    free(json);

    size_t big = ISM_REQ_MAX_BYTES + 1;
    char *body = malloc(big);
    memset(body, ' ', big);
    body[0] = '{';
    body[big - 1] = '}';
    cr_assert(!ism_request_decode(body, big, NULL, &req, &err));
    cr_expect_eq(err.status, 422);
    cr_expect_str_eq(err.code, "too_large");
    free(body);
}

Test(request, operator_depth_limit_applies)
{
    ism_request_limits lim = {6};
    const char *json = "{\"expr\": \"x\", \"depth\": {\"max\": 7}}";
    ism_request req;
    ism_req_error err;
    cr_assert(!ism_request_decode(json, strlen(json), &lim, &req, &err));
    cr_expect_str_eq(err.message, "$.depth.max: 7 is above the limit 6");
    /* the default depth is clamped to the limit instead of being refused */
    const char *plain = "{\"expr\": \"x\"}";
    lim.max_depth = 5;
    cr_assert(ism_request_decode(plain, strlen(plain), &lim, &req, &err));
    cr_expect_eq(req.poly.max_depth, 5);
    ism_request_free(&req);
}

/* max_error reaches the polygoniser; without depth.max the operator's limit is the safety
 * limit, an explicit depth.max stays; a request without it keeps the depth-driven test. */
Test(request, max_error_decodes_and_sets_the_safety_depth)
{
    ism_request_limits lim = {9};
    ism_request req;
    ism_req_error err;
    ism_poly_options o;
    const char *bound = "{\"preset\": \"torus\", \"max_error\": 0.002}";
    cr_assert(ism_request_decode(bound, strlen(bound), &lim, &req, &err), "%s", err.message);
    cr_expect_eq(req.poly.max_error, 0.002);
    cr_expect_eq(req.poly.max_depth, 9);
    /* under a bound: the dual mesh by default, no mesh simplified unless asked */
    cr_expect(!req.simplify);
    ism_request_poly_options(&req, &o);
    cr_expect_eq(o.max_error, 0.002);
    cr_expect_eq(o.max_depth, 9);
    cr_expect(o.dual, "a bound asks for the dual mesh unless it says false");
    cr_expect(!ism_simplify_after(req.simplify, 0.002));
    ism_request_free(&req);

    const char *asked = "{\"preset\": \"torus\", \"max_error\": 0.002, \"simplify\": true}";
    cr_assert(ism_request_decode(asked, strlen(asked), &lim, &req, &err), "%s", err.message);
    cr_expect(ism_simplify_after(req.simplify, 0.002));
    cr_expect(!ism_simplify_after(req.simplify, 0), "never without a bound");
    ism_request_free(&req);

    /* dual false: the primal polygons, not simplified either unless asked (one policy) */
    const char *primal = "{\"preset\": \"torus\", \"max_error\": 0.002, \"dual\": false}";
    cr_assert(ism_request_decode(primal, strlen(primal), &lim, &req, &err), "%s", err.message);
    ism_request_poly_options(&req, &o);
    cr_expect(!o.dual);
    cr_expect(!req.simplify);
    ism_request_free(&req);

    /* either order of the two keys */
    const char *both_asked = "{\"preset\": \"torus\", \"max_error\": 0.002, \"simplify\": true, "
                             "\"dual\": false}";
    cr_assert(ism_request_decode(both_asked, strlen(both_asked), &lim, &req, &err), "%s",
              err.message);
    cr_expect(req.simplify && !req.poly.dual);
    ism_request_free(&req);

    const char *both = "{\"preset\": \"torus\", \"max_error\": 0.002, \"depth\": {\"max\": 6}}";
    cr_assert(ism_request_decode(both, strlen(both), &lim, &req, &err), "%s", err.message);
    cr_expect_eq(req.poly.max_depth, 6);
    ism_request_free(&req);

    const char *raw = "{\"preset\": \"torus\", \"max_error\": 0.002, \"simplify\": false}";
    cr_assert(ism_request_decode(raw, strlen(raw), &lim, &req, &err), "%s", err.message);
    cr_expect(!req.simplify);
    cr_expect(!ism_simplify_after(req.simplify, 0.002));
    ism_request_free(&req);

    const char *moved = "{\"preset\": \"torus\", \"max_error\": 0.002, \"straddle\": true}";
    cr_assert(ism_request_decode(moved, strlen(moved), &lim, &req, &err), "%s", err.message);
    ism_request_poly_options(&req, &o);
    cr_expect(o.straddle, "straddle reaches the polygoniser's options");
    ism_request_free(&req);

    const char *dual = "{\"preset\": \"torus\", \"max_error\": 0.002, \"dual\": true}";
    cr_assert(ism_request_decode(dual, strlen(dual), &lim, &req, &err), "%s", err.message);
    ism_request_poly_options(&req, &o);
    cr_expect(o.dual, "dual reaches the polygoniser's options");
    ism_request_free(&req);

    /* left out: the default bound, 1e-3 of the box diagonal (torus box +-1.5: 3 sqrt 3),
     * with the same safety depth and meshers as an explicit bound */
    const char *plain = "{\"preset\": \"torus\"}";
    cr_assert(ism_request_decode(plain, strlen(plain), &lim, &req, &err), "%s", err.message);
    cr_expect_float_eq(req.poly.max_error, 1e-3 * 3 * sqrt(3), 1e-15, "%.17g",
                       req.poly.max_error);
    cr_expect_eq(req.poly.max_depth, 9);
    cr_expect(!req.simplify);
    ism_request_poly_options(&req, &o);
    cr_expect(o.dual, "the default bound asks for the dual mesh too");
    cr_expect(!o.straddle);
    ism_request_free(&req);

    /* null: no bound, the preset's depth and the flatness test decide */
    const char *off = "{\"preset\": \"torus\", \"max_error\": null}";
    cr_assert(ism_request_decode(off, strlen(off), &lim, &req, &err), "%s", err.message);
    cr_expect_eq(req.poly.max_error, 0);
    cr_expect_eq(req.poly.max_depth, 7, "the preset's depth.max");
    cr_expect(!req.simplify);
    ism_request_poly_options(&req, &o);
    cr_expect_eq(o.max_error, 0);
    cr_expect(!o.straddle);
    cr_expect(!o.dual);
    ism_request_free(&req);
}

Test(request, defaults_come_from_the_polygoniser)
{
    /* the depth path: without a bound every option is the polygoniser's default */
    const char *json = "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": null}";
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err), "%s", err.message);
    ism_poly_options o;
    ism_poly_options_default(&o);
    for (int k = 0; k < 6; k++)
        cr_expect_eq(req.poly.box[k], o.box[k]);
    cr_expect_eq(req.poly.min_depth, o.min_depth);
    cr_expect_eq(req.poly.max_depth, o.max_depth);
    cr_expect_eq(req.poly.gradient_test, o.gradient_test);
    cr_expect_eq(req.poly.double_root_eps, o.double_root_eps);
    cr_expect_eq(req.poly.double_root_iters, o.double_root_iters);
    cr_expect_eq(req.poly.stitch_tol, o.stitch_tol);
    cr_expect_eq(req.poly.flat_normal, o.flat_normal);
    cr_expect_eq(req.poly.flat_plane, o.flat_plane);
    cr_expect_eq(req.format, ISM_FORMAT_DRC);
    cr_expect_eq(req.position_bits, 14);
    cr_expect_eq(req.normal_bits, 10);
    cr_expect_eq(req.attributes, (unsigned)ISM_ATTR_NORMAL); /* the viewer's shaded view */
    cr_expect_null(req.preset);

    ism_poly_options p;
    ism_request_poly_options(&req, &p);
    ism_error e;
    cr_expect(ism_poly_options_check(&p, &e), "%s", e.message);
    ism_request_free(&req);

    /* left out, the bound is 1e-3 of the default box's diagonal (2 sqrt 3) and the
     * operator's depth limit is its safety limit */
    const char *plain = "{\"expr\": \"x^2 + y^2 + z^2 - 1\"}";
    cr_assert(ism_request_decode(plain, strlen(plain), NULL, &req, &err), "%s", err.message);
    cr_expect_float_eq(req.poly.max_error, 2e-3 * sqrt(3), 1e-15);
    cr_expect_eq(req.poly.max_depth, ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT);
    cr_expect_eq(req.poly.min_depth, o.min_depth);
    ism_request_poly_options(&req, &p);
    cr_expect(ism_poly_options_check(&p, &e), "%s", e.message);
    ism_request_free(&req);
}

Test(request, every_preset_decodes_compiles_and_passes_the_polygonisers_check)
{
    for (size_t i = 0; i < ism_preset_count(); i++) {
        const ism_preset *p = ism_preset_at(i);
        char json[128];
        snprintf(json, sizeof json, "{\"preset\": \"%s\", \"max_error\": null}", p->name);
        ism_request req;
        ism_req_error err;
        cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err), "%s: %s", p->name,
                  err.message);
        cr_expect_str_eq(req.preset, p->name);
        cr_expect_eq(req.nparams, p->nparams);
        cr_expect_eq(req.nlets, p->nlets);
        cr_expect_eq(req.poly.max_depth, p->max_depth, "%s: the depth path keeps its depth",
                     p->name);
        for (size_t k = 0; k < p->nparams; k++) {
            cr_expect_leq(p->params[k].min, p->params[k].value, "%s", p->name);
            cr_expect_geq(p->params[k].max, p->params[k].value, "%s", p->name);
        }
        ism_tape *t = ism_request_compile(&req, &err);
        cr_expect_not_null(t, "%s: %s", p->name, err.message);
        ism_tape_free(t);
        ism_poly_options o;
        ism_request_poly_options(&req, &o);
        ism_error e;
        cr_expect(ism_poly_options_check(&o, &e), "%s: %s", p->name, e.message);
        ism_request_free(&req);
    }
}

Test(request, preset_params_override_defaults)
{
    const char *json = "{\"preset\": \"torus\", \"params\": {\"r\": 0.25}, \"depth\": {\"max\": 5}}";
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err), "%s", err.message);
    for (size_t i = 0; i < req.nparams; i++) {
        if (strcmp(req.params[i].name, "r") == 0)
            cr_expect_eq(req.params[i].value, 0.25);
        if (strcmp(req.params[i].name, "R") == 0)
            cr_expect_eq(req.params[i].value, 1.0);
    }
    cr_expect_eq(req.poly.max_depth, 5);
    cr_expect_eq(req.poly.min_depth, 3);
    cr_expect_eq(req.poly.box[0], -1.5);
    ism_request_free(&req);
}

Test(request, let_object_keeps_order_and_equals_the_pair_form)
{
    const char *obj = "{\"expr\": \"b\", \"let\": {\"a\": \"x\", \"b\": \"a*a\"}}";
    const char *arr = "{\"expr\": \"b\", \"let\": [[\"a\", \"x\"], [\"b\", \"a*a\"]]}";
    ism_request r1, r2;
    ism_req_error err;
    cr_assert(ism_request_decode(obj, strlen(obj), NULL, &r1, &err), "%s", err.message);
    cr_assert(ism_request_decode(arr, strlen(arr), NULL, &r2, &err), "%s", err.message);
    cr_assert_eq(r1.nlets, 2);
    cr_assert_eq(r2.nlets, 2);
    for (int i = 0; i < 2; i++) {
        cr_expect_str_eq(r1.lets[i].name, r2.lets[i].name);
        cr_expect_str_eq(r1.lets[i].source, r2.lets[i].source);
    }
    cr_expect_str_eq(r1.lets[0].name, "a");
    ism_tape *t = ism_request_compile(&r1, &err);
    cr_expect_not_null(t, "%s", err.message);
    ism_tape_free(t);
    ism_request_free(&r1);
    ism_request_free(&r2);
}

Test(request, integral_reals_are_integers_and_negative_zero_is_zero)
{
    const char *json = "{\"expr\": \"x\", \"depth\": {\"min\": 2.0, \"max\": 6e0}, "
                       "\"box\": [-0.0, -1, -1, 1, 1, 1]}";
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err), "%s", err.message);
    cr_expect_eq(req.poly.min_depth, 2);
    cr_expect_eq(req.poly.max_depth, 6);
    cr_expect(!signbit(req.poly.box[0]));
    ism_request_free(&req);
}

Test(request, format_names_and_override)
{
    const char *json = "{\"expr\": \"x\", \"output\": {\"format\": \"glb\"}}";
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err), "%s", err.message);
    cr_expect_eq(req.format, ISM_FORMAT_GLB);
    cr_expect(ism_request_set_format(&req, "stl", &err));
    cr_expect_eq(req.format, ISM_FORMAT_STL);
    cr_expect(!ism_request_set_format(&req, "fbx", &err));
    cr_expect_eq(err.status, 400);
    for (int f = 0; f < ISM_FORMAT_COUNT; f++)
        cr_expect_eq(ism_format_lookup(ism_format_name((enum ism_format)f)), f);
    ism_request_free(&req);
}

Test(request, error_json_is_the_documented_document)
{
    const char *json = "{\"expr\": \"x\", \"depth\": {\"max\": 14}}";
    ism_request req;
    ism_req_error err;
    cr_assert(!ism_request_decode(json, strlen(json), NULL, &req, &err));
    size_t n;
    char *text = ism_req_error_json(&err, &n);
    cr_assert_not_null(text);
    json_error_t je;
    json_t *doc = json_loadb(text, n, JSON_REJECT_DUPLICATES, &je);
    cr_assert_not_null(doc, "%s", je.text);
    json_t *e = json_object_get(doc, "error");
    cr_expect_str_eq(json_string_value(json_object_get(e, "code")), "over_limit");
    cr_expect_str_eq(json_string_value(json_object_get(e, "path")), "$.depth.max");
    cr_expect_str_eq(json_string_value(json_object_get(e, "message")),
                     "$.depth.max: 14 is above the limit 10");
    cr_expect_null(json_object_get(e, "column"));
    json_decref(doc);
    free(text);
}
