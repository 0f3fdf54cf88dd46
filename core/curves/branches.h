/* branches.h — the smooth branches of a CSG function: f with every min/max decided the way
 * it goes at a point (f's tape shortened over that point). Points whose f takes the same
 * branch share its number; a crease of f = 0 is where neighbouring points take different
 * branches A and B, the curve f_A = f_B = 0. */
#ifndef ISM_BRANCHES_H
#define ISM_BRANCHES_H

#include <stdbool.h>
#include <stdint.h>
#include "core/curves/cut_fn.h"

/* Distinct branches kept (CSG of a few dozen primitives); points on further branches get
 * none, and no crease is cut there. */
#define ISM_BRANCH_MAX 32
#define ISM_BRANCH_NONE UINT32_MAX

typedef struct ism_branches {
    const ism_tape *f;
    ism_eval_ws *fws;
    ism_tape *scratch;                 /* f shortened at the last point */
    ism_tape *tape[ISM_BRANCH_MAX];    /* branch i: f with its min/max decided */
    ism_eval_ws *ws[ISM_BRANCH_MAX];
    ism_cut_fn fn[ISM_BRANCH_MAX + 1]; /* branch i as the function g = f_i; after the last
                                          branch, the plane of ism_branches_refine */
    ism_cut_eval *ev[ISM_BRANCH_MAX];  /* f_i with every branch as a function (made once
                                          labelling is done: see ism_branches_refine) */
    size_t n, nev;
} ism_branches;

/* Whether f's tape has a min or max (a possible crease). */
bool ism_branches_any(const ism_tape *f);

bool ism_branches_init(ism_branches *b, const ism_tape *f);
void ism_branches_free(ism_branches *b);

/* The branch f takes at p, ISM_BRANCH_NONE when f ties there (p on a crease to rounding)
 * or a new branch finds no room. False only when out of memory. */
bool ism_branches_at(ism_branches *b, const double p[3], uint32_t *id);

/* The branch f takes everywhere in the box lo..hi, when the box decides every min/max on
 * the way to f (at each point inside, ism_branches_at gives the same); ISM_BRANCH_NONE when
 * it does not. False only when out of memory. */
bool ism_branches_in_box(ism_branches *b, const double lo[3], const double hi[3], uint32_t *id);

/* f_i at p with its gradient. */
double ism_branches_gradient(ism_branches *b, uint32_t i, const double p[3], double grad[3]);

/* Newton steps along f_i's gradient (at most steps) moving p toward f_i = 0, until
 * |f_i| ≤ tol |∇f_i| (p then lies within tol of it). Nothing checks where p ends. */
void ism_branches_project(ism_branches *b, uint32_t i, int steps, double tol, double p[3]);

/* Newton puts p on f_a = 0 and f_k = 0 for the nk (1 or 2) branches in ks (crease points,
 * triple points), as ism_cut_refine; with plane (n, c; NULL for none) also on n·p = c. False
 * (p kept) when it fails or out of memory. */
bool ism_branches_refine(ism_branches *b, uint32_t a, const size_t *ks, int nk,
                         const double plane[4], double tol, double max_move, double p[3]);

#endif
