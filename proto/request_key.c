/* request_key.c — what a request means, written out twice: the canonical request (a valid
 * request that any client or the daemon can run again) and the key material that the cache
 * key hashes (BLAKE2b-256 with libsodium). Both are built from the decoded, typed values with
 * every default filled in, never from the client's text, so key order, white space, `1` vs
 * `1.0` and defaults written or left out do not matter; the expression enters the key as the
 * compiled tape's canonical text, so spacing does not matter and a preset equals its
 * written-out expression. */
#include "proto/request.h"
#include "proto/request_internal.h"
#include "proto/draco_encode.h"
#include "proto/json_writer.h"
#include "core/version.h"
#include "core/octree/tolerances.h"

#include <sodium.h>
#include <stdlib.h>
#include <string.h>

static const char *const attr_names[] = {"normal", "mean_curvature", "gauss_curvature",
                                         "class"};

static void write_box(ism_jw *w, const double box[6])
{
    ism_jw_array(w);
    for (int k = 0; k < 6; k++)
        ism_jw_number(w, box[k]);
    ism_jw_array_end(w);
}

static void write_tolerances(ism_jw *w, const ism_request *req)
{
    ism_jw_object(w);
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++) {
        const ism_tolerance *t = &ism_tolerances[i];
        double v = ism_tolerance_get(&req->poly, t);
        ism_jw_key(w, t->key);
        if (t->is_int)
            ism_jw_int(w, (int)v);
        else
            ism_jw_number(w, v);
    }
    ism_jw_object_end(w);
}

/* The error bound as resolved (a request that left it out holds the default's number, so an
 * explicit E equal to it is the same request), or null for the depth path: always written,
 * since a request without "max_error" means the default bound (mesher-21 on), and a
 * canonical request must run again as the same mesh. */
static void write_max_error(ism_jw *w, const ism_request *req)
{
    ism_jw_key(w, "max_error");
    if (!(req->poly.max_error > 0)) {
        ism_jw_null(w);
        return;
    }
    ism_jw_number(w, req->poly.max_error);
    /* Always said under a bound, as "dual" is: the default changed after mesher-18 (from
     * "after the primal polygons" to "only when asked"), and a key or canonical request
     * that leaves the choice out could not say which default it was made under. */
    ism_jw_key(w, "simplify");
    ism_jw_bool(w, req->simplify);
    if (req->poly.straddle) { /* only when asked for: other keys stay as they were */
        ism_jw_key(w, "straddle");
        ism_jw_bool(w, true);
    }
    ism_jw_key(w, "dual"); /* on by default since mesher-17: always said */
    ism_jw_bool(w, req->poly.dual);
}

/* The quality pass, only when asked for (keys of requests without it stay as they were). */
static void write_quality(ism_jw *w, const ism_request *req)
{
    if (req->quality == ISM_QUALITY_RAW)
        return;
    ism_jw_key(w, "quality");
    ism_jw_string(w, ism_quality_name(req->quality));
}

/* The preview mode, only when asked for (keys of full requests stay as they were). */
static void write_preview(ism_jw *w, const ism_request *req)
{
    if (!req->preview)
        return;
    ism_jw_key(w, "preview");
    ism_jw_bool(w, true);
}

/* The encoding options; with only_effective, bits of attributes that are not sent are left
 * out (they cannot change the bytes). */
static void write_output(ism_jw *w, const ism_request *req, bool only_effective)
{
    bool curv = req->attributes & (ISM_ATTR_MEAN_CURVATURE | ISM_ATTR_GAUSS_CURVATURE);
    ism_jw_object(w);
    ism_jw_key(w, "position_bits");
    ism_jw_int(w, req->position_bits);
    if (!only_effective || (req->attributes & ISM_ATTR_NORMAL)) {
        ism_jw_key(w, "normal_bits");
        ism_jw_int(w, req->normal_bits);
    }
    if (!only_effective || curv) {
        ism_jw_key(w, "curvature_bits");
        ism_jw_int(w, req->curvature_bits);
    }
    ism_jw_key(w, "attributes");
    ism_jw_array(w);
    for (int k = 0; k < 4; k++)
        if (req->attributes & (1u << k))
            ism_jw_string(w, attr_names[k]);
    ism_jw_array_end(w);
    if (req->plain_glb) { /* only when asked: every other key stays as it was */
        ism_jw_key(w, "draco");
        ism_jw_bool(w, false);
    }
    ism_jw_object_end(w);
}

static int by_name(const void *a, const void *b)
{
    return strcmp(((const ism_param *)a)->name, ((const ism_param *)b)->name);
}

char *ism_request_canonical(const ism_request *req, size_t *len)
{
    ism_param *sorted = malloc((req->nparams ? req->nparams : 1) * sizeof *sorted);
    if (!sorted)
        return NULL;
    if (req->nparams)
        memcpy(sorted, req->params, req->nparams * sizeof *sorted);
    qsort(sorted, req->nparams, sizeof *sorted, by_name);

    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "expr");
    ism_jw_string(&w, req->expr);
    ism_jw_key(&w, "let");
    ism_jw_array(&w);
    for (size_t i = 0; i < req->nlets; i++) {
        ism_jw_array(&w);
        ism_jw_string(&w, req->lets[i].name);
        ism_jw_string(&w, req->lets[i].source);
        ism_jw_array_end(&w);
    }
    ism_jw_array_end(&w);
    ism_jw_key(&w, "params");
    ism_jw_object(&w);
    for (size_t i = 0; i < req->nparams; i++) {
        ism_jw_key(&w, sorted[i].name);
        ism_jw_number(&w, sorted[i].value);
    }
    ism_jw_object_end(&w);
    free(sorted);
    ism_jw_key(&w, "box");
    write_box(&w, req->poly.box);
    ism_jw_key(&w, "depth");
    ism_jw_object(&w);
    ism_jw_key(&w, "min");
    ism_jw_int(&w, req->poly.min_depth);
    ism_jw_key(&w, "max");
    ism_jw_int(&w, req->poly.max_depth);
    ism_jw_object_end(&w);
    write_max_error(&w, req);
    write_quality(&w, req);
    write_preview(&w, req);
    ism_jw_key(&w, "tolerances");
    write_tolerances(&w, req);
    ism_jw_key(&w, "output");
    write_output(&w, req, false);
    ism_request_write_curves(&w, req, false);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}

/* The key material; with_encoding adds what changes the bytes but not the surface. */
/* The encoder's tools change the bytes too (an override only when set, so keys made with the
 * speed alone stay as they were). */
static void write_draco_tools(ism_jw *w, const ism_draco_tools *t)
{
    ism_jw_key(w, "draco_speed");
    ism_jw_int(w, t->speed);
    if (t->connectivity != ISM_DRACO_CONN_BY_SPEED) {
        ism_jw_key(w, "draco_connectivity");
        ism_jw_int(w, (int)t->connectivity);
    }
    if (t->position_prediction != ISM_DRACO_PRED_BY_SPEED) {
        ism_jw_key(w, "draco_position_prediction");
        ism_jw_int(w, (int)t->position_prediction);
    }
}

static char *key_material(const ism_request *req, const ism_tape *tape, bool with_encoding,
                          size_t *len)
{
    size_t n = ism_tape_canonical(tape, NULL, 0);
    char *text = n ? malloc(n + 1) : NULL; /* 0: the tape writer ran out of memory */
    if (!text || ism_tape_canonical(tape, text, n + 1) != n) {
        free(text);
        return NULL;
    }

    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "key_format");
    ism_jw_int(&w, 1);
    ism_jw_key(&w, "mesher");
    ism_jw_string(&w, ISM_MESHER_VERSION);
    ism_jw_key(&w, "surface");
    ism_jw_string_n(&w, text, n);
    free(text);
    ism_jw_key(&w, "box");
    write_box(&w, req->poly.box);
    ism_jw_key(&w, "depth");
    ism_jw_array(&w);
    ism_jw_int(&w, req->poly.min_depth);
    ism_jw_int(&w, req->poly.max_depth);
    ism_jw_array_end(&w);
    write_max_error(&w, req);
    write_quality(&w, req);
    write_preview(&w, req);
    if (req->preview) { /* how a preview searches for hidden pieces (core/version.h) */
        ism_jw_key(&w, "preview_search");
        ism_jw_string(&w, ISM_PREVIEW_SEARCH);
    }
    ism_jw_key(&w, "tolerances");
    write_tolerances(&w, req);
    ism_request_write_curves(&w, req, true);
    if (with_encoding) {
        ism_jw_key(&w, "encoding");
        write_output(&w, req, true);
        write_draco_tools(&w, &ism_draco_default_tools);
    }
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}

char *ism_request_key_material(const ism_request *req, const ism_tape *tape, size_t *len)
{
    return key_material(req, tape, true, len);
}

char *ism_request_surface_key_material(const ism_request *req, const ism_tape *tape,
                                       size_t *len)
{
    return key_material(req, tape, false, len);
}

bool ism_key_valid(const char *key)
{
    if (strnlen(key, ISM_KEY_HEX_LEN + 1) != ISM_KEY_HEX_LEN)
        return false;
    /* Every byte tested, no early exit: a loop of fixed count the compiler vectorises (a
     * cached GET checks its key several times: cache.c's names). */
    unsigned bad = 0;
    for (size_t i = 0; i < ISM_KEY_HEX_LEN; i++) {
        unsigned char c = (unsigned char)key[i];
        bad |= (unsigned char)(c - '0') > 9 && (unsigned char)(c - 'a') > 5;
    }
    return !bad;
}

/* BLAKE2b-256 of the material as hex. */
static bool hash_hex(char *m, size_t n, char hex[ISM_KEY_HEX_LEN + 1])
{
    unsigned char h[ISM_KEY_HEX_LEN / 2];
    int rc = crypto_generichash(h, sizeof h, (const unsigned char *)m, n, NULL, 0);
    free(m);
    if (rc != 0)
        return false;
    sodium_bin2hex(hex, ISM_KEY_HEX_LEN + 1, h, sizeof h);
    return true;
}

bool ism_request_key(const ism_request *req, const ism_tape *tape, char hex[ISM_KEY_HEX_LEN + 1])
{
    if (sodium_init() < 0)
        return false;
    size_t n;
    char *m = ism_request_key_material(req, tape, &n);
    return m && hash_hex(m, n, hex);
}

bool ism_request_surface_key(const ism_request *req, const ism_tape *tape,
                             char hex[ISM_KEY_HEX_LEN + 1])
{
    if (sodium_init() < 0)
        return false;
    size_t n;
    char *m = ism_request_surface_key_material(req, tape, &n);
    return m && hash_hex(m, n, hex);
}
