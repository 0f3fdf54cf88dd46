/* curve_fns.h — a request's "curves" as the functions core cuts the mesh with: one per plane
 * offset and per level value, one per intersection and silhouette, each remembering its entry
 * and value number. */
#ifndef ISM_CURVE_FNS_H
#define ISM_CURVE_FNS_H

#include "core/curves/cut_fn.h"
#include "proto/request.h"

typedef struct ism_curve_fns {
    ism_cut_fn *fns;
    size_t n;
    ism_tape **tapes;   /* per entry (NULL where it has no expression), owned */
    size_t ntapes;
} ism_curve_fns;

/* Compiles the request's curves; on failure fills err (400 naming $.curves[i].expr for a g
 * that does not compile) and leaves out empty. */
bool ism_curve_fns_build(const ism_request *req, ism_curve_fns *out, ism_req_error *err);
void ism_curve_fns_free(ism_curve_fns *c);

/* Puts f's crease (f = min/max(a, b) at the top of its tape: where a = b) first; nothing
 * when f has none. False when out of memory. */
bool ism_curve_fns_add_crease(ism_curve_fns *c, const ism_tape *f);

#endif
