/* box_fit.c — the POST /v1/box answer (box_fit.h): the request decoded and compiled as for a
 * mesh, core's interval pass run over its box, the result written as JSON. */
#include "proto/box_fit.h"
#include "proto/json_writer.h"
#include "core/eval/fit_box.h"

static void write_box(ism_jw *w, const char *key, const double b[6])
{
    ism_jw_key(w, key);
    ism_jw_array(w);
    for (int k = 0; k < 6; k++)
        ism_jw_number(w, b[k]);
    ism_jw_array_end(w);
}

char *ism_box_fit_answer(const char *json, size_t len, const ism_request_limits *lim,
                         size_t *out_len, ism_req_error *err)
{
    ism_request req;
    if (!ism_request_decode(json, len, lim, &req, err))
        return NULL;
    char *out = NULL;
    ism_tape *t = ism_request_compile(&req, err);
    ism_fit_box_result f;
    if (t && !ism_fit_box(t, req.poly.box, &f)) {
        ism_req_error_set(err, 500, "out_of_memory", "", "out of memory while fitting the box");
    } else if (t) {
        ism_jw w;
        ism_jw_init(&w);
        ism_jw_object(&w);
        write_box(&w, "box", f.box);
        write_box(&w, "cube", req.poly.box);
        ism_jw_key(&w, "empty");
        ism_jw_bool(&w, f.empty);
        ism_jw_key(&w, "complete");
        ism_jw_bool(&w, f.complete);
        ism_jw_key(&w, "level");
        ism_jw_int(&w, f.level);
        ism_jw_key(&w, "evaluations");
        ism_jw_int(&w, (long long)f.evaluations);
        ism_jw_object_end(&w);
        out = ism_jw_take(&w, out_len);
        if (!out)
            ism_req_error_set(err, 500, "out_of_memory", "", "out of memory");
    }
    ism_tape_free(t);
    ism_request_free(&req);
    return out;
}
