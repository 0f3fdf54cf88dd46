/* eval.h — evaluating a compiled tape: points in batches, intervals that are guaranteed to
 * enclose the true range, value + gradient, value + gradient + Hessian, and interval-driven
 * tape shortening for min/max.
 *
 * A workspace holds the registers of one evaluation; give each thread its own. A workspace
 * made for a tape also serves every tape shortened from it.
 *
 * "Bit for bit" below means every number, ±0 and ±inf; a NaN lane is NaN where the one-point
 * evaluator's is, its sign and payload free (with two NaN operands x86 keeps the first, and
 * a batch may order them otherwise: test_eval_grad_batch.c). */
#ifndef ISM_EVAL_H
#define ISM_EVAL_H

#include <stddef.h>
#include <stdbool.h>
#include <stdint.h>
#include "core/expr/expr.h"

/* A closed interval [lo, hi]. lo may be -INFINITY and hi +INFINITY (the whole line). An
 * interval with lo > hi or a NaN bound never comes out of the evaluator. */
typedef struct ism_interval {
    double lo, hi;
} ism_interval;

/* Points per inner batch; ism_eval_batch takes any n and loops over chunks of this. */
#define ISM_EVAL_BATCH 256

typedef struct ism_eval_ws ism_eval_ws;

ism_eval_ws *ism_eval_ws_new(const ism_tape *t);
void ism_eval_ws_free(ism_eval_ws *ws);

/* f at one point. */
double ism_eval_point(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z);

/* out[i] = f(x[i], y[i], z[i]) for i < n. */
void ism_eval_batch(const ism_tape *t, ism_eval_ws *ws, const double *x, const double *y,
                    const double *z, double *out, size_t n);

/* An interval containing f(p) for every p in the box x × y × z (outward rounded). */
ism_interval ism_eval_interval(const ism_tape *t, ism_eval_ws *ws, ism_interval x,
                               ism_interval y, ism_interval z);

/* When t's last instruction is min(a, b) or max(a, b) of two registers giving f: a's and b's
 * intervals over the box x × y × z into val (outward rounded, as ism_eval_interval's), and 1
 * for max, 0 for min; -1 (nothing evaluated) when t does not end so or ws does not fit it. */
int ism_eval_interval_top(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                          ism_interval z, ism_interval val[2]);

/* The intervals of n boxes at once: out[i] encloses f over x[i] × y[i] × z[i] (outward
 * rounded), no wider than ism_eval_interval's for that box but for the last bits of libm
 * results (its bounds are rounded outward exactly, the single box's one ulp further),
 * computed in vectorised loops over the boxes. The caller's rounding mode is kept. */
void ism_eval_interval_batch(const ism_tape *t, ism_eval_ws *ws, const ism_interval *x,
                             const ism_interval *y, const ism_interval *z, ism_interval *out,
                             size_t n);

/* f and its gradient (forward mode). Returns f. */
double ism_eval_gradient(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                         double grad[3]);

/* Points per inner chunk of ism_eval_gradient_batch (its registers: value and three partials
 * of this many lanes each; 1 KB a register, so a tape's registers stay in L1/L2). The
 * polygoniser's batches are a leaf's triangles' centroids and edge midpoints
 * (ism_emitted_error): tens, not hundreds. */
#define ISM_GRAD_BATCH 32

/* Points a chunk of ism_eval_gradient_batch runs through its unrolled copies at most (4
 * groups of 4 lanes; eval_gradient_batch.c chunk_avx2, asserted there); a chunk of more runs
 * its out-of-line wide loop, which costs more a point under AVX2 (Klein bottle's tape: 160
 * instructions a point at 16, 206 at 32; eval_gradient_batch.c). Callers that pick their
 * own pass size take this one (sampler.c). */
#define ISM_GRAD_UNROLLED 16
_Static_assert(ISM_GRAD_UNROLLED <= ISM_GRAD_BATCH, "the unrolled chunks are chunks");

/* f[i] = f(x[i], y[i], z[i]) and g[i] = its gradient for i < n: lane by lane bit for bit what
 * ism_eval_gradient gives at that point (the same operations in the same order, a lane's
 * rounding never depends on another's), one pass over the tape per chunk of ISM_GRAD_BATCH
 * lanes instead of one per point. */
void ism_eval_gradient_batch(const ism_tape *t, ism_eval_ws *ws, const double *x,
                             const double *y, const double *z, double *f, double (*g)[3],
                             size_t n);

/* out[i] = f(x[i], y[i], z[i]) for i < n, lane by lane bit for bit ism_eval_point's value,
 * for short batches: unlike ism_eval_batch it pads no lane up to a group of 32 (a batch of 5
 * costs 5 lanes) and takes sines and cosines through the workspace's memo as ism_eval_point
 * does. n may be any size; chunks of ISM_EVAL_BATCH. Its caller: the conformance pass's rim
 * clearance samples (cf_rim_clear). Edge root searches in lockstep cost more: a node's are
 * 1.3 wide (batch19 notes), a split node's 8 children's 6 (5.3 lanes a step: Klein bottle at
 * E 3.27e-3 +131M instructions of 4,048M, gyroid-ball at 1.09e-2 +26M of 850M; edges24
 * notes). Instructions per point (callgrind): Klein bottle 410 one at a time, here 293 / 205 /
 * 161 / 139 at n = 4 / 8 / 16 / 32; gyroid-ball 680, here 610 / 511 / 464 / 499. */
void ism_eval_points(const ism_tape *t, ism_eval_ws *ws, const double *x, const double *y,
                     const double *z, double *out, size_t n);

/* When t's last instruction is min(a, b) or max(a, b) of two registers (a CSG union or
 * intersection at the top of f): true, with the two branches' values and gradients at the
 * point; false otherwise (nothing evaluated). */
bool ism_eval_top_branches(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                           double val[2], double grad[2][3]);

/* ism_eval_top_branches, also when f passes that min/max on through one-operand steps (f =
 * g(max(a, b)), g a chain of steps each reading only the one before: max(...) − 1 in the
 * cube and steinmetz): the values and gradients of g(a) and g(b), whose zero sets meet on
 * f's crease where g(a) = g(b) = 0. False when f has no such min/max. */
bool ism_eval_crease_branches(const ism_tape *t, ism_eval_ws *ws, double x, double y,
                              double z, double val[2], double grad[2][3]);

/* ism_eval_top_branches' values alone (bit for bit the same), for a fraction of its cost. */
bool ism_eval_top_values(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                         double val[2]);

/* When t ends in min/max of two registers (as ism_eval_top_branches asks): 0 or 1, the
 * branch whose value f takes given their values val (min: the smaller, max: the larger; 0 on
 * a tie); -1 when t does not end so. */
int ism_top_active_branch(const ism_tape *t, const double val[2]);

/* A smooth piece of f: which branch each min, max and abs on f's active path takes. For the
 * k-th such instruction of the tape (k < ISM_PIECE_KINKS, in tape order) bits 2k and 2k + 1
 * hold 1 (min/max: its first operand; abs(a): +a), 2 (the second operand or the constant;
 * abs: −a), or 0 when f's value does not read it through the branches taken above it (the
 * cube's |y| on its face x = 1, every kink of the cube in cube-minus-ball's ball). Two points
 * with equal pieces lie on one smooth function of the tape's (f with those branches forced);
 * where neighbouring pieces' surfaces meet, f has a crease (the cube's edges inside
 * max(cube, ball)'s top branch) or a corner where three meet. */
typedef uint64_t ism_piece;
#define ISM_PIECE_KINKS 32
/* Not a piece: the tape has more than ISM_PIECE_KINKS kinks (or the workspace does not fit). */
#define ISM_PIECE_NONE UINT64_MAX

/* The number of min, max and abs instructions in t. */
size_t ism_tape_kinks(const ism_tape *t);

/* The piece of f at the point (the branches ism_eval_gradient takes there; a tie takes the
 * branch it does: min/max's second operand, abs(0)'s +a). ISM_PIECE_NONE when t has more
 * than ISM_PIECE_KINKS kinks. */
ism_piece ism_eval_piece(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z);

/* Is f one piece over the box: every kink on f's active path decided by intervals (a
 * min/max's operands apart, an abs's operand of one sign)? False also when t has more than
 * ISM_PIECE_KINKS kinks. */
bool ism_tape_one_piece(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                        ism_interval z);

/* f on piece pc at the point: every kink pc names takes pc's branch, the others the one the
 * point gives them; value and gradient (a smooth function past the piece's own region: the
 * face x = 1's plane beyond the cube's edge). NAN when ws does not fit t. */
double ism_eval_piece_gradient(const ism_tape *t, ism_eval_ws *ws, ism_piece pc, double x,
                               double y, double z, double grad[3]);

/* The value alone of ism_eval_piece_gradient's f on piece pc (the same bits: each step the
 * same operation on the same values), for less than a third of its instructions. NAN when ws
 * does not fit t. */
double ism_eval_piece_value(const ism_tape *t, ism_eval_ws *ws, ism_piece pc, double x,
                            double y, double z);

/* f, gradient and Hessian (hess = xx, xy, xz, yy, yz, zz). Returns f. */
double ism_eval_hessian(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                        double grad[3], double hess[6]);

/* Points per inner chunk of ism_eval_hessian_batch (its registers: ten partials of this
 * many lanes, 2.5 KB a register): the dual mesher's batches are a split pass's feet, up to
 * ISM_GRAD_BATCH at a time. */
#define ISM_HESS_BATCH 32

/* f[i], g[i] and h[i] at p[i] for i < n: lane by lane bit for bit what ism_eval_hessian gives
 * at that point (the same operations in the same order), one pass over the tape per chunk
 * of ISM_HESS_BATCH lanes instead of one per point. */
void ism_eval_hessian_batch(const ism_tape *t, ism_eval_ws *ws, const double (*p)[3],
                            double *f, double (*g)[3], double (*h)[6], size_t n);

/* Whether t holds a min or max (f may have a C0 crease where its operands are equal). */
bool ism_tape_has_min_max(const ism_tape *t);

/* Whether t holds a min, max or abs (f may have a C0 kink: its gradient jumps). */
bool ism_tape_has_kink(const ism_tape *t);

/* Whether t's only min, max or abs is its last instruction, min(a, b) or max(a, b) of two
 * registers giving f (a CSG union or intersection of two smooth branches: one crease, where
 * they are equal; ism_eval_top_branches gives both). */
bool ism_tape_top_min_max_only(const ism_tape *t);

/* A tape with room for any shortened version of t (free with ism_tape_free). */
ism_tape *ism_tape_new_like(const ism_tape *t);

/* Evaluates t over the box by intervals and writes into out (made by ism_tape_new_like(t)
 * or of a tape t was shortened from) a tape equal to t everywhere inside the box, without
 * the min/max branches that the box proves dominated. Also returns the box's interval in
 * *range when range is not NULL — always, whether or not anything was dropped (it is the
 * ism_eval_interval result; no need to evaluate the box again). Returns true when out is
 * shorter than t, false when nothing could be dropped (out is then unchanged and t should
 * be used as it is). out must not be t. */
bool ism_tape_shorten(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                      ism_interval z, ism_tape *out, ism_interval *range);

#endif
