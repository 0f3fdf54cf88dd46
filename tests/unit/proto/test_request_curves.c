/* test_request_curves.c — the request's "curves" list: each kind decoded to its cut functions
 * (a plane stack one function per offset, levels one per value, the g of levels, surface and
 * the silhouette's direction carried through); each bad input a 400 naming its JSON path
 * (unknown kind, empty offsets, more than 256 curves, a zero normal, an unknown field, a g
 * that does not compile); the cache key changes with the curves, and an empty list is the
 * same request as none. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/curve_fns.h"
#include "proto/request.h"

static void decode_ok(const char *json, ism_request *req)
{
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, req, &err), "%s: %s", json,
              err.message);
}

/* The status and path of decoding json and building its cut functions. */
static int curves_status(const char *json, ism_req_error *err)
{
    ism_request req;
    if (!ism_request_decode(json, strlen(json), NULL, &req, err))
        return err->status;
    ism_curve_fns cf;
    bool ok = ism_curve_fns_build(&req, &cf, err);
    if (ok)
        ism_curve_fns_free(&cf);
    ism_request_free(&req);
    return ok ? 200 : err->status;
}

Test(request_curves, kinds_become_cut_functions)
{
    ism_request req;
    decode_ok("{\"expr\": \"x^2+y^2+z^2-r^2\", \"params\": {\"r\": 1}, \"curves\": ["
              "{\"kind\": \"plane\", \"normal\": [0, 0, 2], \"offsets\": [-0.5, 0, 0.5]},"
              "{\"kind\": \"levels\", \"expr\": \"x*r\", \"values\": [0.25, 0.75]},"
              "{\"kind\": \"surface\", \"expr\": \"(x-0.5)^2+y^2-0.25\"},"
              "{\"kind\": \"silhouette\", \"direction\": [1, 1, 0]}]}",
              &req);
    cr_assert_eq(req.ncurves, 4);
    ism_curve_fns cf;
    ism_req_error err;
    cr_assert(ism_curve_fns_build(&req, &cf, &err), "%s", err.message);
    cr_assert_eq(cf.n, 3 + 2 + 1 + 1);
    double p[3] = {0.3, -0.2, 0.1};
    ism_cut_eval ev; /* g values at p from the closed forms */
    ism_tape *f = ism_request_compile(&req, &err);
    cr_assert(f);
    cr_assert(ism_cut_eval_init(&ev, f, cf.fns, cf.n));
    cr_assert_float_eq(ism_cut_g(&ev, 0, p, NULL), 2 * 0.1 + 0.5, 1e-15);
    cr_assert_float_eq(ism_cut_g(&ev, 2, p, NULL), 2 * 0.1 - 0.5, 1e-15);
    cr_assert_float_eq(ism_cut_g(&ev, 4, p, NULL), 0.3 - 0.75, 1e-15);
    cr_assert_float_eq(ism_cut_g(&ev, 5, p, NULL), 0.2 * 0.2 + 0.04 - 0.25, 1e-15);
    cr_assert_float_eq(ism_cut_g(&ev, 6, p, NULL), 2 * 0.3 - 2 * 0.2, 1e-15); /* ∇f·d */
    cr_assert_eq(cf.fns[4].kind, ISM_CUT_LEVEL);
    cr_assert_eq(cf.fns[4].source, 1);
    cr_assert_eq(cf.fns[4].index, 1);
    cr_assert_eq(cf.fns[6].kind, ISM_CUT_SILHOUETTE);
    ism_cut_eval_free(&ev);
    ism_tape_free(f);
    ism_curve_fns_free(&cf);
    ism_request_free(&req);
}

typedef struct bad_curve {
    const char *curves;
    const char *path;
} bad_curve;

Test(request_curves, bad_inputs_are_400_naming_the_path)
{
    static const bad_curve cases[] = {
        {"[{\"kind\": \"cone\"}]", "$.curves[0].kind"},
        {"[{\"normal\": [0, 0, 1]}]", "$.curves[0].kind"},
        {"[{\"kind\": \"plane\", \"normal\": [0, 0, 1], \"offsets\": []}]", "$.curves[0].offsets"},
        {"[{\"kind\": \"plane\", \"normal\": [0, 0, 1]}]", "$.curves[0].offsets"},
        {"[{\"kind\": \"plane\", \"normal\": [0, 0, 0], \"offsets\": [1]}]", "$.curves[0].normal"},
        {"[{\"kind\": \"plane\", \"normal\": [0, 1], \"offsets\": [1]}]", "$.curves[0].normal"},
        {"[{\"kind\": \"plane\", \"normal\": [0, 0, 1], \"offsets\": [\"a\"]}]",
         "$.curves[0].offsets[0]"},
        {"[{\"kind\": \"surface\", \"expr\": \"x\", \"values\": [1]}]", "$.curves[0].values"},
        {"[{\"kind\": \"surface\", \"expr\": \"x +* y\"}]", "$.curves[0].expr"},
        {"[{\"kind\": \"plane\", \"normal\": [1, 0, 0], \"offsets\": [0]}, "
         "{\"kind\": \"levels\", \"expr\": \"sin(\", \"values\": [0]}]", "$.curves[1].expr"},
        {"[{\"kind\": \"silhouette\"}]", "$.curves[0].direction"},
        {"{\"kind\": \"plane\"}", "$.curves"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char json[512];
        snprintf(json, sizeof json, "{\"expr\": \"x^2+y^2+z^2-1\", \"curves\": %s}",
                 cases[i].curves);
        ism_req_error err;
        cr_expect_eq(curves_status(json, &err), 400, "%s", json);
        cr_expect_str_eq(err.path, cases[i].path, "%s: %s", json, err.message);
    }
}

/* n entries, or one plane entry with n offsets. */
static char *many(size_t n, bool offsets)
{
    char *s = malloc(64 * n + 128), *p = s;
    p += sprintf(p, "{\"expr\": \"x\", \"curves\": [");
    if (offsets)
        p += sprintf(p, "{\"kind\": \"plane\", \"normal\": [1, 0, 0], \"offsets\": [");
    for (size_t i = 0; i < n; i++)
        p += sprintf(p, offsets ? "%s%zu" : "%s{\"kind\": \"silhouette\", \"direction\": [1, 0, %zu]}",
                     i ? ", " : "", i + 1);
    sprintf(p, offsets ? "]}]}" : "]}");
    return s;
}

Test(request_curves, at_most_256_curves)
{
    for (int off = 0; off < 2; off++) {
        ism_req_error err;
        char *ok = many(256, off), *over = many(257, off);
        cr_expect_eq(curves_status(ok, &err), 200, "%s", err.message);
        cr_expect_eq(curves_status(over, &err), 400);
        cr_expect_str_eq(err.path, off ? "$.curves[0].offsets" : "$.curves");
        free(ok);
        free(over);
    }
}

static void key_of(const char *json, char hex[65])
{
    ism_request req;
    decode_ok(json, &req);
    ism_req_error err;
    ism_tape *t = ism_request_compile(&req, &err);
    cr_assert(t);
    cr_assert(ism_request_key(&req, t, hex));
    ism_tape_free(t);
    ism_request_free(&req);
}

Test(request_curves, curves_are_in_the_key)
{
    char none[65], empty[65], a[65], b[65], c[65];
    key_of("{\"expr\": \"x^2+y^2+z^2-1\"}", none);
    key_of("{\"expr\": \"x^2+y^2+z^2-1\", \"curves\": []}", empty);
    key_of("{\"expr\": \"x^2+y^2+z^2-1\", \"curves\": [{\"kind\": \"plane\", \"normal\": "
           "[0, 0, 1], \"offsets\": [0]}]}", a);
    key_of("{\"expr\": \"x^2+y^2+z^2-1\", \"curves\": [{\"kind\": \"plane\", \"normal\": "
           "[0, 0, 1], \"offsets\": [0.5]}]}", b);
    /* a parameter only g uses changes the key through g's compiled text */
    key_of("{\"expr\": \"x^2+y^2+z^2-1\", \"params\": {\"a\": 2}, \"curves\": [{\"kind\": "
           "\"surface\", \"expr\": \"x - a\"}]}", c);
    char d[65];
    key_of("{\"expr\": \"x^2+y^2+z^2-1\", \"params\": {\"a\": 3}, \"curves\": [{\"kind\": "
           "\"surface\", \"expr\": \"x - a\"}]}", d);
    cr_expect_str_eq(none, empty);
    cr_expect_str_neq(none, a);
    cr_expect_str_neq(a, b);
    cr_expect_str_neq(c, d);
}
