/* cut_fn.h — the second function g of a curve on f = 0 (the curve is f = 0, g = 0): a plane
 * n·p − c, a level g − c of an expression, or a second surface g = 0; and Newton on the
 * 2 × 3 system (f, g) (3 × 3 where two curves cross) that puts a point on the curve. */
#ifndef ISM_CUT_FN_H
#define ISM_CUT_FN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/curves/cut_types.h"
#include "core/eval/eval.h"

enum ism_cut_kind { ISM_CUT_SECTION, ISM_CUT_LEVEL, ISM_CUT_INTERSECTION,
                    ISM_CUT_SILHOUETTE, ISM_CUT_CREASE, ISM_CUT_KIND_COUNT };

/* g(p) = tape(p) + n·p − c (tape NULL: the linear part alone); for a silhouette
 * g(p) = ∇f(p)·n (tape and c unused); for a crease between f's branches A and B
 * (branches.h), g = f_A − f_B (everything else unused). */
typedef struct ism_cut_fn {
    const ism_tape *tape;
    double n[3];
    double c;
    int kind;            /* enum ism_cut_kind */
    int source, index;   /* the request's curve entry and its offset / value number */
} ism_cut_fn;

/* Where a Newton ended (p) and the distances |value| / |gradient| there of f (res[0]) and
 * of the nk functions ks (res[i + 1]); nk 0: none known. */
typedef struct ism_cut_resid {
    double p[3];
    double res[3];
    uint32_t ks[2];
    int nk;
} ism_cut_resid;

/* Evaluation state for f and the cut functions (one thread). */
typedef struct ism_cut_eval {
    const ism_tape *f;
    ism_eval_ws *fws;
    const ism_cut_fn *fns;
    ism_eval_ws **gws;   /* per function, NULL for a plane */
    size_t nfns;
    ism_tape *const *branch_tape; /* while a crease is cut: f's branches (branches.h, owned
                                     by the cut) and a workspace for each; else NULL */
    ism_eval_ws *const *branch_ws;
    uint32_t pair[2];    /* the crease function is f_pair[0] − f_pair[1] (set per crease
                            edge); unset (ISM_CUT_NO_BRANCH): the top min/max's a − b */
    const double *box;   /* the meshed box (xmin ymin zmin xmax ymax zmax) or NULL: a curve
                            leaving the mesh through a box face ends on that face */
    double last_p[3];    /* where the last successful Newton ended, and ∇f there (its last */
    double last_grad[3]; /* evaluation: a new vertex's normal needs no evaluation of its own) */
    bool last_ok;        /* false until then */
    ism_cut_resid last_res; /* the residuals there (no evaluation for the final check) */
} ism_cut_eval;

/* The crease function of f when f's tape has a min or max (CSG); false otherwise. The crease
 * is cut by branches (crease.c), not by the sign of one function. */
bool ism_cut_crease_fn(const ism_tape *f, ism_cut_fn *out);

bool ism_cut_eval_init(ism_cut_eval *ev, const ism_tape *f, const ism_cut_fn *fns, size_t n);
void ism_cut_eval_free(ism_cut_eval *ev);

/* g_k at p, with its gradient when grad is not NULL. */
double ism_cut_g(ism_cut_eval *ev, size_t k, const double p[3], double grad[3]);

/* g_k, its gradient and Hessian (xx xy xz yy yz zz) at p: exact for a tape (a plane's is
 * zero); a silhouette's or a crease's by central differences of its gradient, step h. */
double ism_cut_g_hessian(ism_cut_eval *ev, size_t k, const double p[3], double h, double grad[3],
                         double hess[6]);

/* g_k at n points (pos: 3 per point) into out, in batches where g is a tape or a plane:
 * the same values as ism_cut_g up to the order of the sum's rounding. */
bool ism_cut_g_batch(ism_cut_eval *ev, size_t k, const double *pos, size_t n, double *out);

/* Moves p onto f = 0 and g_k = 0 for each of the nk functions in ks (nk is 1 or 2) by
 * minimum-norm Newton steps. True when it ends with every |value| / |gradient| ≤ tol and
 * moved at most max_move; p is left unchanged otherwise. */
bool ism_cut_refine(ism_cut_eval *ev, const size_t *ks, int nk, double tol, double max_move,
                    double p[3]);

/* As ism_cut_refine for g_k alone, the point also kept on the plane n·p = c (plane: n, c):
 * the curve's crossing with a plane across it (a node's branch, picked by the plane across
 * its tangent, where the minimum-norm step could run to the other branch). */
bool ism_cut_refine_on_plane(ism_cut_eval *ev, size_t k, const double plane[4], double tol,
                             double max_move, double p[3]);

/* The plane through p containing the edge direction b − a and the normal n: a point of the
 * edge's curve kept in it stays across the curve from the edge, so the points of consecutive
 * edges follow each other along the curve, and it does not slide along the curve past an
 * earlier one that the edge's ends are beside (a point free to slide goes to the foot of the
 * perpendicular). False when the edge and n are parallel. */
bool ism_cut_plane_along(const double a[3], const double b[3], const double n[3],
                         const double p[3], double plane[4]);

/* As ism_cut_refine_on_plane, the plane through p holding dir (an edge's direction) and ∇f
 * at p: a point of an edge's curve kept across the curve from the edge (the gradient is the
 * one Newton's first step evaluates). False (p kept) also when dir ∥ ∇f. */
bool ism_cut_refine_across(ism_cut_eval *ev, size_t k, const double dir[3], double tol,
                           double max_move, double p[3]);

/* ∇f at p into grad: the last Newton's when it ended at p, else evaluated. */
void ism_cut_f_gradient(ism_cut_eval *ev, const double p[3], double grad[3]);

/* The largest |value| / |gradient| of f and of g_k at p (the distance to each set). */
void ism_cut_residuals(ism_cut_eval *ev, size_t k, const double p[3], double *df, double *dg);

/* As ism_cut_residuals, the same numbers, from r without evaluating: true when r's Newton
 * ended at p (bit for bit) with g_k in its system (a crease's g is never kept: it depends
 * on the pair of branches); false (nothing written) otherwise. */
bool ism_cut_known_residuals(const ism_cut_resid *r, size_t k, const double p[3], double *df,
                             double *dg);

#endif
