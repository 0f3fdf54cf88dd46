/* point_probe.c — the POST /v1/point answer (point_probe.h): value, gradient and Hessian of
 * the request's f at one point, and the curvature of its level set there. */
#include "proto/point_probe.h"
#include "proto/json_writer.h"
#include "core/eval/eval.h"
#include "core/analysis/curvature.h"

#include <math.h>
#include <stdlib.h>

bool ism_point_parse(const char *text, double at[3])
{
    const char *p = text;
    for (int k = 0; k < 3; k++) {
        char *end;
        at[k] = strtod(p, &end);
        if (end == p || !isfinite(at[k]))
            return false;
        p = end;
        if (k < 2 && *p++ != ',')
            return false;
    }
    return *p == '\0';
}

static void number_or_null(ism_jw *w, const char *key, double v, bool ok)
{
    if (key)
        ism_jw_key(w, key);
    if (ok && isfinite(v))
        ism_jw_number(w, v);
    else
        ism_jw_null(w);
}

char *ism_point_probe_answer(const char *json, size_t len, const ism_request_limits *lim,
                             const double at[3], size_t *out_len, ism_req_error *err)
{
    ism_request req;
    if (!ism_request_decode(json, len, lim, &req, err))
        return NULL;
    char *out = NULL;
    ism_tape *t = ism_request_compile(&req, err);
    ism_eval_ws *ws = t ? ism_eval_ws_new(t) : NULL;
    if (t && !ws)
        ism_req_error_set(err, 500, "out_of_memory", "", "out of memory");
    if (ws) {
        double g[3], h[6], mean, gauss, k1, k2;
        double f = ism_eval_hessian(t, ws, at[0], at[1], at[2], g, h);
        double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        bool curved = ism_curvature_from_derivatives(g, h, &mean, &gauss, &k1, &k2);
        ism_jw w;
        ism_jw_init(&w);
        ism_jw_object(&w);
        ism_jw_key(&w, "xyz");
        ism_jw_array(&w);
        for (int k = 0; k < 3; k++)
            ism_jw_number(&w, at[k]);
        ism_jw_array_end(&w);
        number_or_null(&w, "f", f, true);
        ism_jw_key(&w, "grad");
        ism_jw_array(&w);
        for (int k = 0; k < 3; k++)
            number_or_null(&w, NULL, g[k], true);
        ism_jw_array_end(&w);
        number_or_null(&w, "grad_norm", gn, true);
        number_or_null(&w, "distance", fabs(f) / gn, gn > 0);
        number_or_null(&w, "mean_curvature", mean, curved);
        number_or_null(&w, "gauss_curvature", gauss, curved);
        number_or_null(&w, "k1", k1, curved);
        number_or_null(&w, "k2", k2, curved);
        ism_jw_object_end(&w);
        out = ism_jw_take(&w, out_len);
        if (!out)
            ism_req_error_set(err, 500, "out_of_memory", "", "out of memory");
    }
    if (ws)
        ism_eval_ws_free(ws);
    ism_tape_free(t);
    ism_request_free(&req);
    return out;
}
