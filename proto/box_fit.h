/* box_fit.h — POST /v1/box: the box an expression's zero set needs. The body is a surface
 * request (expression or preset, params, let); its "box" is the cube searched (send a
 * generous one, e.g. ±10; the default box otherwise). The answer:
 *   {"box": [6], "cube": [6], "empty": bool, "complete": bool, "level": n, "evaluations": n}
 * where "box" contains every zero of f in the cube (core/eval/fit_box.h). */
#ifndef ISM_BOX_FIT_H
#define ISM_BOX_FIT_H

#include <stddef.h>
#include "proto/request.h"

/* Decodes, compiles and fits. Returns the answer JSON (malloc'd, *out_len set), or NULL with
 * err filled (400/422 for the request, 500 when out of memory). */
char *ism_box_fit_answer(const char *json, size_t len, const ism_request_limits *lim,
                         size_t *out_len, ism_req_error *err);

#endif
