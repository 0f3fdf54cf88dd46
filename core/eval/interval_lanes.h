/* interval_lanes.h — interval_ops.h's common operations on four intervals at once (lanes4.h's
 * v4d, lower and upper bounds apart), lane by lane the same IEEE operations in the same order
 * as the scalar ones, so each lane's bits are the scalar operation's: the outward rounding
 * (down1 / up1), products from their four corner products in iv_mul's order (a NaN corner,
 * 0 × inf, counted as 0), squares as iv_square. For the batched interval gradient pass
 * (eval_interval_grad_batch.c) and the dual mesher's sub-box enclosures (octree/dual_cert.c).
 * INLINE helpers only (lanes4.h's rule). Its names are unprefixed and reserved in the files
 * that include it: the types vi, v4u; splat, pick, vabs, vdown1, vup1, vdown4, vup4, vmin,
 * vmax, vnan_to, ivz and every v_* (v_splat, v_add, v_sub, v_neg, v_mul_c, v_mul, v_square,
 * v_trig_resolves, v_may_contain, v_trig_at, v_sin_at, v_cos_at); a local helper there takes
 * another name. Also iv_sin_at / iv_cos_at's
 * lane forms (down4 / up4 and may_contain's ceil test lane by lane), for eval_interval_batch.c's
 * sines and cosines: the same IEEE operations, so the same bits, in round-to-nearest. */
#ifndef ISM_INTERVAL_LANES_H
#define ISM_INTERVAL_LANES_H

#include "core/eval/interval_ops.h"
#include "core/eval/lanes4.h"

typedef unsigned long long v4u __attribute__((vector_size(4 * sizeof(double))));

/* An interval per lane. */
typedef struct vi {
    v4d lo, hi;
} vi;

INLINE v4d splat(double x) { return (v4d){x, x, x, x}; }

INLINE v4d vabs(v4d x) { return v4_abs(x); }

/* interval_ops.h's down1 / up1, min / max (ism_min: a < b ? a : b) and nan_to */
INLINE v4d vdown1(v4d x)
{
    return (x - splat(ISM_ROUND1_ABS)) - vabs(x) * splat(ISM_ROUND1_REL);
}
INLINE v4d vup1(v4d x)
{
    return (x + splat(ISM_ROUND1_ABS)) + vabs(x) * splat(ISM_ROUND1_REL);
}
INLINE v4d vmin(v4d a, v4d b)
{
    v4d r;
    for (int j = 0; j < 4; j++)
        r[j] = a[j] < b[j] ? a[j] : b[j];
    return r;
}
INLINE v4d vmax(v4d a, v4d b)
{
    v4d r;
    for (int j = 0; j < 4; j++)
        r[j] = a[j] > b[j] ? a[j] : b[j];
    return r;
}
INLINE v4d vnan_to(v4d x, double c) { return v4_pick(x == x, x, splat(c)); }

INLINE vi v_splat(ism_interval u) { return (vi){splat(u.lo), splat(u.hi)}; }

INLINE vi v_add(vi a, vi b) { return (vi){vdown1(a.lo + b.lo), vup1(a.hi + b.hi)}; }
INLINE vi v_sub(vi a, vi b) { return (vi){vdown1(a.lo - b.hi), vup1(a.hi - b.lo)}; }
INLINE vi v_neg(vi a) { return (vi){-a.hi, -a.lo}; }

INLINE vi ivz(void) { return (vi){splat(0.0), splat(0.0)}; }

/* iv_mul_c */
INLINE vi v_mul_c(vi a, double c)
{
    if (c == 0.0)
        return ivz();
    v4d k = splat(c);
    return c > 0.0 ? (vi){vdown1(a.lo * k), vup1(a.hi * k)}
                   : (vi){vdown1(a.hi * k), vup1(a.lo * k)};
}

/* iv_mul: the four corner products (a NaN one, 0 × inf, as 0), min / max in min4's order */
INLINE vi v_mul(vi a, vi b)
{
    v4d p1 = vnan_to(a.lo * b.lo, 0.0), p2 = vnan_to(a.lo * b.hi, 0.0);
    v4d p3 = vnan_to(a.hi * b.lo, 0.0), p4 = vnan_to(a.hi * b.hi, 0.0);
    return (vi){vdown1(vmin(vmin(p1, p2), vmin(p3, p4))), vup1(vmax(vmax(p1, p2), vmax(p3, p4)))};
}

INLINE vi v_square(vi a)
{
    v4d l2 = a.lo * a.lo, h2 = a.hi * a.hi;
    v4d inner = v4_pick(a.hi <= splat(0.0), h2, splat(0.0));
    v4d lo = v4_pick(a.lo >= splat(0.0), l2, inner);
    return (vi){vmax(vdown1(lo), splat(0.0)), vup1(vmax(l2, h2))};
}

/* interval_ops.h's down4 / up4 */
INLINE v4d vdown4(v4d x)
{
    return (x - splat(ISM_ROUND4_ABS)) - vabs(x) * splat(ISM_ROUND4_REL);
}
INLINE v4d vup4(v4d x)
{
    return (x + splat(ISM_ROUND4_ABS)) + vabs(x) * splat(ISM_ROUND4_REL);
}

/* iv_trig_resolves lane by lane: all ones where it holds */
INLINE v4i v_trig_resolves(vi a)
{
    v4d limit = splat(ISM_TRIG_LIMIT);
    return (a.hi - a.lo < splat(2.0 * M_PI)) & (vabs(a.lo) < limit) & (vabs(a.hi) < limit);
}

/* may_contain lane by lane (holds_integer's ceil(u) <= v; ceil is exact, so any form of it) */
INLINE v4i v_may_contain(vi a, double phase, double period)
{
    v4d tol = splat(ISM_TRIG_TOL_ABS) + splat(ISM_TRIG_TOL_REL) * vmax(vabs(a.lo), vabs(a.hi));
    v4d u = (a.lo - splat(phase)) / splat(period) - tol;
    v4d v = (a.hi - splat(phase)) / splat(period) + tol, cu;
    for (int j = 0; j < 4; j++)
        cu[j] = ceil(u[j]);
    return cu <= v;
}

/* iv_sin_at / iv_cos_at (for lanes where v_trig_resolves holds): the bounds from the sines
 * (cosines) w1, w2 of a's bounds, then 1 where a may hold hi_phase + 2k pi and -1 where it
 * may hold lo_phase + 2k pi (the scalar forms' phases, as written there: the same quotients) */
INLINE vi v_trig_at(vi a, v4d w1, v4d w2, double hi_phase, double lo_phase)
{
    v4d lo = vmax(vdown4(vmin(w1, w2)), splat(-1.0)), hi = vmin(vup4(vmax(w1, w2)), splat(1.0));
    hi = v4_pick(v_may_contain(a, hi_phase, 2.0 * M_PI), splat(1.0), hi);
    lo = v4_pick(v_may_contain(a, lo_phase, 2.0 * M_PI), splat(-1.0), lo);
    return (vi){lo, hi};
}
INLINE vi v_sin_at(vi a, v4d s1, v4d s2) { return v_trig_at(a, s1, s2, M_PI / 2, -M_PI / 2); }
INLINE vi v_cos_at(vi a, v4d c1, v4d c2) { return v_trig_at(a, c1, c2, 0.0, M_PI); }

#endif
