/* point_probe.h — POST /v1/point?at=X,Y,Z: f and its derivatives at one point, for the
 * viewer's picking. The body is the surface request (expression or preset, params, let). The
 * answer: {"xyz": [3], "f", "grad": [3], "grad_norm", "distance" (|f| / |∇f|, the first-order
 * distance to f = 0), "mean_curvature", "gauss_curvature", "k1", "k2"} — curvature of the
 * level set of f through the point (core/analysis/curvature.h; null where |∇f| = 0). */
#ifndef ISM_POINT_PROBE_H
#define ISM_POINT_PROBE_H

#include <stddef.h>
#include "proto/request.h"

/* Parses "X,Y,Z" (three finite numbers) into at; false otherwise. */
bool ism_point_parse(const char *text, double at[3]);

/* Decodes and compiles the request, evaluates at `at`. Returns the answer JSON (malloc'd,
 * *out_len set) or NULL with err filled (400/422, 500 when out of memory). */
char *ism_point_probe_answer(const char *json, size_t len, const ism_request_limits *lim,
                             const double at[3], size_t *out_len, ism_req_error *err);

#endif
