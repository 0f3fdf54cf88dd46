/* rm_pass.c — opening and closing the state a pass over the mesh shares (rm_pass.h): the
 * incidence with room for insertions, ∇f's unit normals, the per-vertex marks and the
 * protection; at the end the renumbering without what collapses removed, and the frees. The
 * quality pass (remesh.c) and the simplification (simplify.c) both run on it. */
#include "core/remesh/rm_pass.h"
#include "core/eval/interval_jet.h"
#include "core/expr/tape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Whether f's gradient may jump across a curve of the surface: only at a min, max or abs
 * switching branch (a CSG crease), or where sqrt, a fractional power or log meets its clamp at
 * 0 (sqrt(max(x, 0)) + y = 0 bends by 90° along x = 0). Every other op of the tape is C¹ where
 * f is finite, so on a tape without these every bend of the mesh is the surface's own
 * curvature, a fold, or singular structure (non-manifold edges, vanishing ∇f: locked by their
 * own rules, rm_locks.c). */
static bool may_crease(const ism_tape *t)
{
    if (ism_tape_has_kink(t))
        return true;
    for (size_t i = 0; i < t->len; i++) {
        enum ism_opcode op = t->code[i].op;
        if (op == ISM_OP_SQRT || op == ISM_OP_POWC || op == ISM_OP_LOG)
            return true;
    }
    return false;
}

bool rm_pass_open(rm_pass *p, ism_mesh *m, const ism_remesh_options *o, size_t extra)
{
    memset(p, 0, sizeof *p);
    p->f = o->f;
    p->max_error = o->max_error > 0 ? o->max_error : 0;
    p->may_crease = o->f && may_crease(o->f);
    p->r.label = o->tri_label;
    p->ws = ism_eval_ws_new(o->f);
    bool ok = p->ws && rm_mesh_build(&p->r, m, extra);
    if (ok) {
        size_t cv = p->r.cap_verts ? p->r.cap_verts : 1;
        p->normal = malloc(cv * 3 * sizeof *p->normal);
        p->active = calloc(cv, 1);
        p->slide = calloc(cv, 1);
        p->touched = calloc(cv, 1);
        /* (out of memory: NULL, every triangle measured each time) */
        p->obtuse = malloc(p->r.cap_tris ? p->r.cap_tris : 1);
        if (p->obtuse)
            memset(p->obtuse, RM_OBTUSE_UNKNOWN, p->r.cap_tris ? p->r.cap_tris : 1);
    }
    return ok && p->normal && p->active && p->slide && p->touched && rm_normals(p) &&
           rm_lock_features(p, o);
}

bool rm_offset_open(rm_pass *p)
{
    size_t nv = p->r.cap_verts ? p->r.cap_verts : 1;
    p->offset = malloc(4 * nv * sizeof *p->offset);
    for (size_t i = 0; p->offset && i < 4 * nv; i++)
        p->offset[i] = NAN; /* no place (NaN matches none): measured when asked */
    /* every vertex's first offset, from rm_normals' batch: no evaluation (one point at a
       time as the moves asked it, through rm_bound_signed: callgrind --quality good
       --threads 1, chmutov-quartic own box, ism_quality_pass 295.45M -> 292.63M). Each is
       paired with its vertex's place now: right only while no vertex has moved since
       rm_normals (remesh.c opens the offsets before any step); the count bounds the loop
       whatever was added. */
    size_t found = p->found_offset_n < p->r.m->nverts ? p->found_offset_n : p->r.m->nverts;
    for (size_t v = 0; p->offset && p->found_offset && v < found; v++) {
        double *o = p->offset + 4 * v;
        memcpy(o, p->r.m->pos + 3 * v, 3 * sizeof *o);
        o[3] = p->found_offset[v];
    }
    rm_found_offset_drop(p);
    return p->offset != NULL;
}

bool rm_pass_close(rm_pass *p, size_t nverts_before, size_t ntris_before,
                   ism_remesh_renumber *ren)
{
    bool ok = !(p->r.dead && p->r.gone && p->r.origin) ||
              rm_compact(&p->r, nverts_before, ntris_before, ren);
    rm_mesh_free(&p->r);
    free(p->normal);
    free(p->active);
    free(p->slide);
    free(p->touched);
    free(p->sine);
    free(p->obtuse);
    free(p->crease_tried);
    free(p->cen_ref);
    free(p->cen_keep);
    free(p->brec);
    free(p->offset);
    free(p->found_offset);
    free(p->bend);
    ism_ivjet_ws_free(p->jws);
    ism_eval_ws_free(p->ws);
    memset(p, 0, sizeof *p);
    return ok;
}
