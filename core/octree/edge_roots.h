/* edge_roots.h — the roots of f on one lattice segment (a piece of an octree node's edge):
 * the paper's sign test and gradient test, regula falsi for one root, and the paper's
 * bisection with the |f(c)| < eps double-root rule for two roots or one tangent (double)
 * root. Callers always pass a segment in its canonical direction (lower lattice coordinate
 * first), so every cell that shares a segment gets bit-identical roots. */
#ifndef ISM_EDGE_ROOTS_H
#define ISM_EDGE_ROOTS_H

#include <assert.h>
#include <math.h>
#include "core/octree/sampler.h"
#include "core/util/vec3.h"

enum ism_root_kind {
    ISM_ROOT_CROSS, /* f changes sign here */
    ISM_ROOT_TOUCH, /* f touches 0 without changing sign (|f(c)| < eps) */
};

typedef struct ism_root {
    double t;           /* 0..1 along the canonical segment */
    double p[3];
    double g[3];        /* ∇f at p */
    enum ism_root_kind kind;
} ism_root;

enum ism_segment_flags {
    ISM_SEG_SEARCHED = 1,    /* signs agreed but gradients did not: searched for two roots */
    ISM_SEG_MANY_ROOTS = 2,  /* more than two roots suspected (paper's failure case) */
};

typedef struct ism_seg_roots {
    int n;                /* 0, 1 or 2 roots, ordered by t */
    int flags;
    ism_root r[2];
} ism_seg_roots;

typedef struct ism_root_params {
    double gradient_test;  /* ĝa·ĝb above this: same sheet, no root when signs agree */
    double eps;            /* double-root threshold on |f| */
    int iters;             /* bisection steps of the double-root search */
    bool crease;           /* f has min/max (a C0 crease may cross a segment): same-sign ends
                              where |f| falls toward the middle are searched (edge_roots.c) */
} ism_root_params;

/* Unit-gradient agreement of two points given |ga| and |gb|; -2 when either gradient vanishes
 * or is not finite. */
static inline double ism_agreement_normed(const double ga[3], const double gb[3], double na,
                                          double nb)
{
    if (!(na > 0) || !(nb > 0) || !isfinite(na) || !isfinite(nb))
        return -2;
    return ism_dot3(ga, gb) / (na * nb);
}

/* An end at 0 or undefined: the segment reports no interior root (ism_segment_roots). */
static inline bool ism_rootless_ends(double fa, double fb)
{
    return fa == 0 || fb == 0 || !isfinite(fa) || !isfinite(fb);
}

/* Same sign, same sheet: no root by the paper's eq. 2 (unless a pocket, below). */
static inline bool ism_one_sheet(const ism_root_params *prm, double fa, double fb,
                                 const double ga[3], const double gb[3], double na, double nb)
{
    return (fa < 0) == (fb < 0) && ism_agreement_normed(ga, gb, na, nb) > prm->gradient_test;
}

/* Does |f| fall from both ends of the segment a→b (same sign) toward its middle — sa and sb
 * are f's slopes there, ∇f(a)·(b − a) and ∇f(b)·(b − a) — and, unless f may have a crease
 * (crease: its tape holds min/max), do the tangent lines of f there meet past 0? The
 * paper's eq. 2 reads agreeing gradients as one sheet on both ends; across a C0 crease
 * (min/max of two sheets, the seam of a CSG union) the gradients of two sheets can agree to
 * within the test while f rises from both ends to the crease and crosses 0 there — a pocket
 * of the other sign that both ends miss:
 *
 *        f    tangent at a ╲   ╱ tangent at b      |f| falls from both ends toward the
 *        0 ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─ ─     crease: search the segment for two
 *                          ╱╳╲  (f: the crease)     roots
 *        a ───────────────╱───╲─────────────── b
 *
 * Where the tangent lines meet does not tell at a crease: each sheet is curved, and its
 * tangent line from the far end of the segment can lie below it by more than the pocket is
 * deep (the double torus's seam 1e-3 off the lattice at depth 9: tangents meeting at
 * f = −1.1e-4 while f rises to +9e-5 between them, ½ f''L² = 5.8e-4 — a hole of one
 * triangle), so with min/max any fall from both ends is searched (double torus: +5% gradient
 * evaluations). A smooth f keeps the meeting test (searching every fall costs the torus 29%).
 * Costs no evaluation (the gradients at the ends are known); the search it lets through is
 * still guarded by the segment's interval. */
static inline bool ism_pocket_by_slopes(double fa, double fb, double sa, double sb,
                                        bool crease)
{
    double side = fa < 0 ? -1 : 1;
    if (!(side * sa < 0) || !(side * sb > 0))
        return false; /* |f| does not fall from both ends toward the middle */
    if (crease)
        return true;
    double t = (fb - fa - sb) / (sa - sb); /* fa + sa t = fb + sb (t - 1) */
    return t > 0 && t < 1 && side * (fa + sa * t) < 0;
}

/* True when the end values alone prove that ism_segment_roots(a→b) finds no root (an end
 * at 0 or undefined, or one sign at both ends with gradients agreeing beyond gradient_test
 * and tangents that do not meet past 0 — with prm->crease: |f| not falling from both ends
 * toward the middle): it would then evaluate nothing, so there is
 * nothing to memoise either. Give a and b in the order ism_segment_roots gets them. */
bool ism_segment_rootless(const ism_root_params *prm, const double a[3], const double b[3],
                          double fa, double fb, const double ga[3], const double gb[3]);

/* The same, given |ga| and |gb| (memoised with the end points' gradients). */
bool ism_segment_rootless_normed(const ism_root_params *prm, const double a[3],
                                 const double b[3], double fa, double fb, const double ga[3],
                                 const double gb[3], double na, double nb);

/* ism_segment_rootless_normed's answer, inline, for a lattice segment: a and b differ only
 * along `axis`. The slopes are then ga[axis] × (b − a)[axis] and the same at b, bit for bit
 * ism_dot3's: where the pocket test is reached the gradients are finite (ism_one_sheet: a
 * vanishing or undefined one agrees -2, below any gradient_test, tolerances.c's -1 .. 1),
 * so their terms along the other axes are ±0, which leave a nonzero sum as it is, and a zero
 * slope fails the test whatever its sign. The face walk asks it of every segment it meets
 * (Klein's bottle at E 3.27e-3: 740K times). Preconditions of that argument: na, nb are
 * |ga|, |gb| (ism_norm3: an inf or NaN component makes the norm inf or NaN, so a finite norm
 * means finite components), and prm->gradient_test >= -1 (above ism_one_sheet's -2), asserted
 * where the pocket test is reached: an ism_root_params built from option structs bypasses
 * tolerances.c's bounds. */
static inline bool ism_lattice_segment_rootless(const ism_root_params *prm, int axis,
                                                const double a[3], const double b[3],
                                                double fa, double fb, const double ga[3],
                                                const double gb[3], double na, double nb)
{
    if (ism_rootless_ends(fa, fb))
        return true;
    if (!ism_one_sheet(prm, fa, fb, ga, gb, na, nb))
        return false;
    assert(prm->gradient_test > -2); /* else an inf gradient could reach the slopes */
    double d = b[axis] - a[axis];
    return !ism_pocket_by_slopes(fa, fb, ga[axis] * d, gb[axis] * d, prm->crease);
}

/* Roots of f on the segment a→b with f(a) = fa, f(b) = fb and gradients ga, gb. When fa
 * or fb is exactly 0 the segment reports no interior root: that end point is a root of
 * its own, handled by whoever owns the lattice point. known: where the signs differ, the
 * parameter ism_regula_falsi(s, a, b, fa, fb) returns, found earlier (root_table.h), or
 * NULL to search. */
void ism_segment_roots(ism_sampler *s, const ism_root_params *prm, const double a[3],
                       const double b[3], double fa, double fb, const double ga[3],
                       const double gb[3], const double *known, ism_seg_roots *out);

/* One root of f on a→b by regula falsi (Illinois), given fa·fb < 0. Returns t in (0, 1). */
double ism_regula_falsi(ism_sampler *s, const double a[3], const double b[3], double fa,
                        double fb);

/* ism_regula_falsi on n segments a[i]→b[i] (fa[i]·fb[i] < 0) into t[i], bit for bit each
 * single search's root, the searches stepped side by side (f at a step's points in one
 * batch: ism_eval_points, lane by lane ism_eval_point's value). s->local must be NULL
 * (asserted): every point is evaluated on s->tape (the octree build's samplers). Without
 * s->batch (the scalar reference path) the searches run one at a time (ism_regula_falsi). */
void ism_regula_falsi_lanes(ism_sampler *s, const double (*a)[3], const double (*b)[3],
                            const double *fa, const double *fb, double *t, size_t n);

/* Can |f| come within eps of 0 on the segment a→b? False when the interval over its
 * bounding box proves |f| > eps everywhere on it (then no root and no tangent point). */
bool ism_segment_may_reach(ism_sampler *s, const double a[3], const double b[3], double eps);

/* The paper's double-root bisection on a→b (fa, fb of the same sign): returns 2 and a
 * split point t (one root each side), 1 and the tangent point t (|f| < eps), or 0 — early,
 * the same answer, once an interval over what is left of the bracket proves that no later
 * halving could see a sign change or |f| < eps (edge_roots.c). */
int ism_double_root_search(ism_sampler *s, const ism_root_params *prm, const double a[3],
                           const double b[3], double fa, double fb, double *t);

#endif
