/* fuzz_request.c — libFuzzer target for the JSON request decoder: ism_request_decode on
 * arbitrary bytes, then for a decoded request everything the daemon does with it before the
 * polygoniser — compile, canonical request, key material and key — checking that:
 *   - every failure has a status, a code and a message, and its error document is valid
 *     JSON (jansson reads it back: UTF-8 included) carrying that message;
 *   - a decoded request gives polygoniser options that ism_poly_options_check accepts, and
 *     key material that is JSON;
 *   - the canonical request decodes again, to the same canonical text, and (when the
 *     expression compiles) to the same cache key.
 *
 * The regression tests include this file with ISM_FUZZ_NO_ENTRY defined and call
 * ism_fuzz_request on every committed input. */
#include <jansson.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "proto/request.h"
#include "core/octree/polygonise.h"
#include "tests/fuzz/fuzz_check.h"

static void request_check_error(const ism_req_error *err, const char *stage)
{
    FUZZ_CHECK(err->status == 400 || err->status == 422 || err->status == 500,
               "%s: status %d", stage, err->status);
    FUZZ_CHECK(memchr(err->code, 0, sizeof err->code) && err->code[0], "%s: no code", stage);
    FUZZ_CHECK(memchr(err->message, 0, sizeof err->message) && err->message[0],
               "%s: no message", stage);
    FUZZ_CHECK(memchr(err->path, 0, sizeof err->path) != NULL, "%s: path not terminated",
               stage);
    size_t n = 0;
    char *doc = ism_req_error_json(err, &n);
    FUZZ_CHECK(doc != NULL, "%s: no error document", stage);
    json_error_t je;
    json_t *root = json_loadb(doc, n, JSON_REJECT_DUPLICATES, &je);
    FUZZ_CHECK(root != NULL, "%s: error document is not valid JSON (%s at column %d): %s",
               stage, je.text, je.column, doc);
    const char *message = NULL, *code = NULL;
    FUZZ_CHECK(json_unpack(root, "{s:{s:s, s:s}}", "error", "message", &message, "code",
                           &code) == 0, "%s: error document lacks code or message: %s", stage,
               doc);
    FUZZ_CHECK(strcmp(message, err->message) == 0 && strcmp(code, err->code) == 0,
               "%s: error document says something else: %s", stage, doc);
    json_decref(root);
    free(doc);
}

/* The key of a decoded request whose expression compiles, else "" (error checked). */
static ism_tape *request_compile_key(const ism_request *req, char hex[65], const char *stage)
{
    ism_req_error err;
    memset(&err, 0, sizeof err);
    hex[0] = '\0';
    ism_tape *t = ism_request_compile(req, &err);
    if (!t) {
        request_check_error(&err, stage);
        return NULL;
    }
    FUZZ_CHECK(ism_request_key(req, t, hex), "%s: no key", stage);
    FUZZ_CHECK(strlen(hex) == 64 && strspn(hex, "0123456789abcdef") == 64, "%s: key '%s'",
               stage, hex);
    size_t n = 0;
    char *material = ism_request_key_material(req, t, &n);
    FUZZ_CHECK(material && strlen(material) == n, "%s: key material", stage);
    json_error_t je;
    json_t *doc = json_loadb(material, n, JSON_REJECT_DUPLICATES, &je);
    FUZZ_CHECK(doc != NULL, "%s: key material is not JSON (%s): %s", stage, je.text, material);
    json_decref(doc);
    free(material);
    return t;
}

int ism_fuzz_request(const uint8_t *data, size_t size)
{
    ism_request req;
    ism_req_error err;
    if (!ism_request_decode((const char *)data, size, NULL, &req, &err)) {
        request_check_error(&err, "decode");
        ism_request_free(&req); /* promised safe after a failure */
        return 0;
    }
    FUZZ_CHECK(req.expr && req.expr[0], "decoded request without an expression");
    ism_poly_options o;
    ism_request_poly_options(&req, &o);
    ism_error perr;
    memset(&perr, 0, sizeof perr);
    FUZZ_CHECK(ism_poly_options_check(&o, &perr),
               "a decoded request gives options the polygoniser refuses: %s", perr.message);

    char key[65], key2[65];
    ism_tape *t = request_compile_key(&req, key, "compile");

    size_t n1 = 0;
    char *canon = ism_request_canonical(&req, &n1);
    FUZZ_CHECK(canon && strlen(canon) == n1, "canonical request");
    ism_request again;
    ism_req_error err2;
    FUZZ_CHECK(ism_request_decode(canon, n1, NULL, &again, &err2),
               "the canonical request does not decode: %s\n%s", err2.message, canon);
    size_t n2 = 0;
    char *canon2 = ism_request_canonical(&again, &n2);
    FUZZ_CHECK(canon2 && n2 == n1 && memcmp(canon, canon2, n1) == 0,
               "canonical request changes when decoded again:\n%s\n%s", canon, canon2);
    ism_tape *t2 = request_compile_key(&again, key2, "compile canonical");
    FUZZ_CHECK((t == NULL) == (t2 == NULL), "the canonical request %s compile",
               t ? "does not" : "does");
    FUZZ_CHECK(strcmp(key, key2) == 0, "the canonical request has another key");

    ism_tape_free(t2);
    ism_tape_free(t);
    free(canon2);
    free(canon);
    ism_request_free(&again);
    ism_request_free(&req);
    return 0;
}

#ifndef ISM_FUZZ_NO_ENTRY
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return ism_fuzz_request(data, size);
}
#endif
