/* test_key.c — the cache key: requests that mean the same mesh share a key (key order, white
 * space, defaults written or left out, 1 vs 1.0, expression spacing, a preset vs its
 * written-out expression, the file format); any change that changes the mesh or its encoding
 * changes it; the key is BLAKE2b-256 of material that names ISM_MESHER_VERSION; the canonical
 * request decodes back to the same key. */
#include <criterion/criterion.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/version.h"
#include "proto/request.h"

static void key_of(const char *json, char hex[65])
{
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err), "%s: %s", json,
              err.message);
    ism_tape *t = ism_request_compile(&req, &err);
    cr_assert_not_null(t, "%s: %s", json, err.message);
    cr_assert(ism_request_key(&req, t, hex));
    ism_tape_free(t);
    ism_request_free(&req);
}

#define TORUS "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)"

/* Each group: requests that must all share one key; different groups must differ. */
static const char *const same[][7] = {
    {"{\"expr\": \"x^2 + y^2 + z^2 - r^2\", \"params\": {\"r\": 1}, \"box\": [-2,-2,-2,2,2,2]}",
     "{ \"box\" : [ -2, -2, -2, 2, 2, 2 ],\n \"params\": {\"r\": 1.0},\n \"expr\": \"x^2+y^2+z^2-r^2\" }",
     "{\"expr\": \"(x^2) + (y^2) + (z^2) - r^2\", \"params\": {\"r\": 1e0}, \"box\": [-2.0,-2,-2,2,2,2.0]}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"box\": [-2,-2,-2,2,2,2]}",
     "{\"expr\": \"q + z^2 - 1\", \"let\": {\"q\": \"x^2 + y^2\"}, \"box\": [-2,-2,-2,2,2,2], "
     "\"params\": {\"unused\": 5}}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"box\": [-2,-2,-2,2,2,2], \"quality\": \"raw\"}",
     NULL},
    /* defaults written out or left out, format does not matter: the bound is 1e-3 of the
     * box diagonal (2 sqrt 3), the safety depth the operator's limit (10) */
    {"{\"expr\": \"x^2 + y^2 - 0.25\"}",
     "{\"expr\": \"x^2 + y^2 - 0.25\", \"max_error\": 0.0034641016151377543}",
     "{\"expr\": \"x^2 + y^2 - 0.25\", \"max_error\": 0.0034641016151377543, \"dual\": true, "
     "\"simplify\": false}",
     "{\"expr\": \"x^2 + y^2 - 0.25\", \"depth\": {\"min\": 3, \"max\": 10}, "
     "\"tolerances\": {\"gradient\": 0.9, \"double_root_eps\": 1e-9, \"double_root_iters\": 25, "
     "\"stitch\": 0.001}, \"output\": {\"format\": \"glb\", \"position_bits\": 14, "
     "\"normal_bits\": 10, \"curvature_bits\": 14, \"attributes\": [\"normal\"]}}",
     "{\"expr\": \"x^2 + y^2 - 0.25\", \"box\": [-1, -1, -1, 1, 1, 1], \"output\": {\"format\": \"stl\"}}",
     "{\"expr\": \"x^2 + y^2 - 0.25\", \"box\": [-1, -1, -1.0, 1, 1, 1], \"depth\": {\"min\": 3}}",
     NULL},
    /* a preset and its written-out expression (default bound 1e-3 * 3 sqrt 3) */
    {"{\"preset\": \"torus\"}",
     "{\"preset\": \"torus\", \"params\": {\"R\": 1, \"r\": 0.3}, \"depth\": {\"max\": 10}}",
     "{\"expr\": \"" TORUS "\", \"params\": {\"r\": 0.3, \"R\": 1}, \"box\": [-1.5,-1.5,-1.5,1.5,1.5,1.5]}",
     "{\"preset\": \"torus\", \"max_error\": 0.005196152422706632}",
     NULL},
    /* the depth path: null, the preset's depth */
    {"{\"preset\": \"torus\", \"max_error\": null}",
     "{\"preset\": \"torus\", \"max_error\": null, \"depth\": {\"min\": 3, \"max\": 7}}",
     "{\"expr\": \"" TORUS "\", \"params\": {\"r\": 0.3, \"R\": 1}, \"box\": [-1.5,-1.5,-1.5,1.5,1.5,1.5], "
     "\"max_error\": null, \"depth\": {\"max\": 7}}",
     NULL},
    /* under a bound: the dual mesh is the default, no simplification unless asked (for
     * the primal polygons too: one policy) */
    {"{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"dual\": true}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"simplify\": false}",
     NULL},
    {"{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"dual\": false}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"dual\": false, "
     "\"simplify\": false}",
     NULL},
    /* -0 is 0 */
    {"{\"expr\": \"x + y + z - 0.5\", \"box\": [-0.0, 0, 0, 1, 1, 1]}",
     "{\"expr\": \"x + y + z - 0.5\", \"box\": [0, -0, 0, 1, 1, 1]}",
     "{\"expr\": \"x + y + z - 0.5\", \"box\": [0, 0, 0, 1, 1, 1], \"preview\": false}",
     NULL},
    /* a preview sends normals only, whatever else is listed */
    {"{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"preview\": true}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"preview\": true, \"output\": {\"attributes\": [\"normal\"]}}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"preview\": true, \"output\": {\"attributes\": "
     "[\"class\", \"normal\", \"mean_curvature\"]}}",
     NULL},
    /* a preview that leaves max_error out has no bound: the depth path, as with null
     * (the server's rule, proto/request.c; the viewer sends null itself) */
    {"{\"preset\": \"torus\", \"preview\": true}",
     "{\"preset\": \"torus\", \"preview\": true, \"max_error\": null}",
     NULL},
    /* the default attributes (normals only) left out or named: one key; the curvature bits
     * do not matter while no curvature is sent */
    {"{\"expr\": \"x^2 + y^2 + z^2 - 1\"}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\"]}}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"curvature_bits\": 16}}",
     NULL},
    /* a curvature request names its set in any order */
    {"{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\", \"class\", "
     "\"mean_curvature\", \"gauss_curvature\"]}}",
     "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"gauss_curvature\", "
     "\"mean_curvature\", \"class\", \"normal\"], \"curvature_bits\": 14}}",
     NULL},
    /* bits of attributes that are not sent do not matter */
    {"{\"expr\": \"x - y\", \"output\": {\"attributes\": [\"class\"], \"normal_bits\": 12, \"curvature_bits\": 16}}",
     "{\"expr\": \"x - y\", \"output\": {\"attributes\": [\"class\"]}}",
     NULL},
    /* Kummer both ways */
    {"{\"preset\": \"kummer-4-nodes\"}",
     "{\"expr\": \"(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s\", \"let\": [[\"lambda\", "
     "\"(3*mu2 - 1)/(3 - mu2)\"], [\"p\", \"w - z - sqrt(2)*x\"], [\"q\", \"w - z + sqrt(2)*x\"], "
     "[\"r\", \"w + z + sqrt(2)*y\"], [\"s\", \"w + z - sqrt(2)*y\"]], \"params\": {\"mu2\": "
     "0.6667, \"w\": 1}, \"box\": [-3,-3,-3,3,3,3], \"depth\": {\"min\": 3, \"max\": 10}}",
     NULL},
};

/* Each differs from the base in one thing that changes the mesh or the bytes. */
static const char base[] = "{\"expr\": \"x^2 + y^2 + z^2 - 1\"}";
static const char *const different[] = {
    "{\"expr\": \"x^2 + y^2 + z^2 - 1.01\"}",
    "{\"expr\": \"x^2 + y^2 + z^2 - r\", \"params\": {\"r\": 2}}",
    "{\"expr\": \"x^2 + y^2 - z^2 - 1\"}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"box\": [-1, -1, -1, 1, 1, 1.5]}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"depth\": {\"max\": 6}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": null}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": null, \"depth\": {\"max\": 10}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.0034641016151377}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.01, \"depth\": {\"max\": 7}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"depth\": {\"max\": 7}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"depth\": {\"max\": 7}, "
    "\"straddle\": true}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"depth\": {\"max\": 7}, "
    "\"dual\": false}",
    /* simplified: differs from the default (not simplified), on either mesher */
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"depth\": {\"max\": 7}, "
    "\"simplify\": true}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"max_error\": 0.02, \"depth\": {\"max\": 7}, "
    "\"dual\": false, \"simplify\": true}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"depth\": {\"min\": 2}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"tolerances\": {\"gradient\": 0.8}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"tolerances\": {\"double_root_eps\": 1e-8}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"tolerances\": {\"double_root_iters\": 24}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"tolerances\": {\"stitch\": 0.002}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"tolerances\": {\"flat_normal\": 0.5}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"tolerances\": {\"flat_plane\": 0.2}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"position_bits\": 16}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"normal_bits\": 12}}",
    /* a curvature is sent only when asked (the default is normals only), each set its own key,
     * and then its bits matter */
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\", \"mean_curvature\"]}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\", \"mean_curvature\"], "
    "\"curvature_bits\": 12}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\", \"gauss_curvature\"]}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\", \"mean_curvature\", "
    "\"gauss_curvature\", \"class\"]}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": [\"normal\", \"class\"]}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"output\": {\"attributes\": []}}",
    "{\"preset\": \"sphere\"}",
    "{\"preset\": \"sphere\", \"params\": {\"r\": 0.5}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"quality\": \"good\"}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"preview\": true, \"output\": {\"attributes\": [\"normal\"]}}",
    "{\"expr\": \"x^2 + y^2 + z^2 - 1\", \"preview\": true, \"output\": {\"attributes\": []}}",
};

Test(key, requests_that_mean_the_same_mesh_share_a_key)
{
    size_t groups = sizeof same / sizeof same[0];
    char (*first)[65] = calloc(groups, 65);
    for (size_t g = 0; g < groups; g++) {
        key_of(same[g][0], first[g]);
        for (int i = 1; same[g][i]; i++) {
            char k[65];
            key_of(same[g][i], k);
            cr_expect_str_eq(k, first[g], "group %zu: %s\n differs from %s", g, same[g][i],
                             same[g][0]);
        }
        for (size_t h = 0; h < g; h++)
            cr_expect_str_neq(first[g], first[h], "groups %zu and %zu share a key", g, h);
    }
    free(first);
}

Test(key, any_change_of_mesh_or_encoding_changes_the_key)
{
    size_t n = sizeof different / sizeof different[0];
    char (*keys)[65] = calloc(n + 1, 65);
    key_of(base, keys[n]);
    for (size_t i = 0; i < n; i++) {
        key_of(different[i], keys[i]);
        for (size_t j = 0; j <= n; j++)
            if (j != i && (j < i || j == n))
                cr_expect_str_neq(keys[i], keys[j], "%s\n and %s share a key", different[i],
                                  j == n ? base : different[j]);
    }
    free(keys);
}

Test(key, key_is_blake2b_of_material_naming_the_mesher_version)
{
    const char *json = "{\"preset\": \"steiner-roman\"}";
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err));
    ism_tape *t = ism_request_compile(&req, &err);
    cr_assert_not_null(t);
    size_t n;
    char *m = ism_request_key_material(&req, t, &n);
    cr_assert_not_null(m);
    cr_expect_not_null(strstr(m, "\"mesher\":\"" ISM_MESHER_VERSION "\""), "%s", m);
    cr_expect_null(strstr(m, "steiner"), "the preset name must not enter the key: %s", m);
    cr_expect_null(strstr(m, "\"format\""), "the format must not enter the key: %s", m);
    cr_assert(sodium_init() >= 0);
    unsigned char h[32];
    crypto_generichash(h, 32, (const unsigned char *)m, n, NULL, 0);
    char want[65], got[65];
    sodium_bin2hex(want, sizeof want, h, 32);
    cr_assert(ism_request_key(&req, t, got));
    cr_expect_str_eq(got, want);
    cr_expect_eq(strlen(got), 64);
    free(m);
    ism_tape_free(t);
    ism_request_free(&req);
}

/* Under a bound the simplification's choice is written out even when left at its default
 * (false since the one policy of ism_simplify_after): material made under the old default
 * ("after the primal polygons") said nothing, so a key that leaves it out could mean either.
 * Without a bound ("max_error": null) it is not written. */
Test(key, material_and_canonical_say_the_simplify_default_under_a_bound)
{
    const char *bound = "{\"preset\": \"klein-bottle\", \"max_error\": 0.01}";
    const char *plain = "{\"preset\": \"klein-bottle\", \"max_error\": null}";
    const char *jsons[2] = {bound, plain};
    for (int i = 0; i < 2; i++) {
        ism_request req;
        ism_req_error err;
        cr_assert(ism_request_decode(jsons[i], strlen(jsons[i]), NULL, &req, &err), "%s",
                  err.message);
        ism_tape *t = ism_request_compile(&req, &err);
        cr_assert_not_null(t);
        char *m = ism_request_key_material(&req, t, NULL);
        char *c = ism_request_canonical(&req, NULL);
        cr_assert(m && c);
        if (i == 0) {
            cr_expect_not_null(strstr(m, "\"simplify\":false"), "%s", m);
            cr_expect_not_null(strstr(c, "\"simplify\":false"), "%s", c);
        } else {
            cr_expect_null(strstr(m, "simplify"), "%s", m);
            cr_expect_null(strstr(c, "simplify"), "%s", c);
        }
        free(m);
        free(c);
        ism_tape_free(t);
        ism_request_free(&req);
    }
}

Test(key, canonical_request_decodes_to_the_same_key_and_itself)
{
    const char *jsons[] = {
        "{\"preset\": \"kummer-16-nodes\", \"params\": {\"w\": 1.25}, \"output\": {\"format\": \"ply\"}}",
        "{\"expr\": \"p*p - 0.1\", \"let\": {\"p\": \"x + y\"}, \"params\": {\"b\": 0.1, \"a\": 2}, "
        "\"box\": [-1, -2, -3, 1, 2, 3], \"quality\": \"good\", \"tolerances\": {\"stitch\": 0.01}}",
        "{\"preset\": \"gyroid-ball\", \"depth\": {\"max\": 4}, \"preview\": true}",
    };
    for (size_t i = 0; i < sizeof jsons / sizeof *jsons; i++) {
        char k1[65], k2[65];
        key_of(jsons[i], k1);
        ism_request req;
        ism_req_error err;
        cr_assert(ism_request_decode(jsons[i], strlen(jsons[i]), NULL, &req, &err));
        size_t n1;
        char *c1 = ism_request_canonical(&req, &n1);
        cr_assert_not_null(c1);
        ism_request_free(&req);
        key_of(c1, k2);
        cr_expect_str_eq(k1, k2, "canonical %s", c1);
        cr_assert(ism_request_decode(c1, n1, NULL, &req, &err), "%s: %s", c1, err.message);
        size_t n2;
        char *c2 = ism_request_canonical(&req, &n2);
        cr_expect_str_eq(c1, c2);
        cr_expect_null(strstr(c1, "\"format\""), "%s", c1);
        free(c1);
        free(c2);
        ism_request_free(&req);
    }
}

Test(key, canonical_numbers_are_shortest_round_trip)
{
    const char *json = "{\"expr\": \"x - a\", \"params\": {\"a\": 0.1}, \"box\": [-0.1, -1, -1, 0.3, 1, 1]}";
    ism_request req;
    ism_req_error err;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &err));
    char *c = ism_request_canonical(&req, NULL);
    cr_expect_not_null(strstr(c, "\"a\":0.1}"), "%s", c);
    cr_expect_not_null(strstr(c, "[-0.1,-1,-1,0.3,1,1]"), "%s", c);
    cr_expect_null(strstr(c, "0000000"), "%s", c);
    free(c);
    ism_request_free(&req);
}

/* A preview is another computed surface (its own surface key), and the canonical request
 * says so; it refuses what it does not compute, naming $.preview. */
Test(key, preview_has_its_own_surface_key_and_refuses_curves_and_quality)
{
    const char *jsons[2] = {"{\"preset\": \"torus\", \"output\": {\"attributes\": [\"normal\"]}}",
                            "{\"preset\": \"torus\", \"preview\": true}"};
    char surface[2][65];
    for (int i = 0; i < 2; i++) {
        ism_request req;
        ism_req_error err;
        cr_assert(ism_request_decode(jsons[i], strlen(jsons[i]), NULL, &req, &err));
        cr_expect_eq(req.preview, i == 1);
        cr_expect_eq(req.attributes, (unsigned)ISM_ATTR_NORMAL);
        ism_tape *t = ism_request_compile(&req, &err);
        cr_assert_not_null(t);
        cr_assert(ism_request_surface_key(&req, t, surface[i]));
        size_t n;
        char *c = ism_request_canonical(&req, &n);
        cr_expect_eq(strstr(c, "\"preview\":true") != NULL, i == 1, "%s", c);
        free(c);
        ism_tape_free(t);
        ism_request_free(&req);
    }
    cr_expect_str_neq(surface[0], surface[1]);
    const char *bad[] = {
        "{\"preset\": \"torus\", \"preview\": true, \"quality\": \"good\"}",
        "{\"preset\": \"torus\", \"preview\": true, \"curves\": [{\"kind\": \"plane\", "
        "\"normal\": [0, 0, 1], \"offsets\": [0]}]}",
        "{\"preset\": \"torus\", \"preview\": \"yes\"}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        ism_request req;
        ism_req_error err;
        cr_expect_not(ism_request_decode(bad[i], strlen(bad[i]), NULL, &req, &err), "%s", bad[i]);
        cr_expect_eq(err.status, 400, "%s", bad[i]);
        cr_expect_str_eq(err.path, "$.preview", "%s: %s", bad[i], err.message);
    }
}
