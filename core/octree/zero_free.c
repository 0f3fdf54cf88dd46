/* zero_free.c — proving a node free of f = 0 (zero_free.h): intervals over its octants in
 * one batched call, then the mean-value form over the whole node. */
#include "core/octree/zero_free.h"
#include "core/eval/interval_ops.h"
#include "core/expr/tape.h"

/* The boxes reach this fraction of the node past its faces: a point the polygoniser samples
 * on a segment of the node (a + t (b - a)) may round an ulp or so past the box, and must
 * still lie in it. Far below any feature: 1e-9 of a cell. */
#define BOX_MARGIN 1e-9
/* The mean-value form must clear eps by this many times the width of f's enclosure at the
 * node's centre. The form encloses f itself, while the polygoniser compares f as evaluated
 * in double, which rounding moves off f; the enclosure at a point, each step rounded
 * outward, is at least as wide as that rounding there, and points a node apart (terms of
 * about the same size) round alike. The natural enclosures need no margin: they hold the
 * double evaluation itself. */
#define ROUNDING_MARGIN 16.0

/* The one sign of the corners when each lies beyond eps, else 0. */
static int corner_sign(const ism_corners *k, double eps)
{
    int sign = k->f[0] > eps ? 1 : k->f[0] < -eps ? -1 : 0;
    for (int c = 1; c < 8 && sign != 0; c++)
        if (!(sign > 0 ? k->f[c] > eps : k->f[c] < -eps))
            sign = 0;
    return sign;
}

static bool beyond(ism_interval v, int sign, double eps)
{
    return sign > 0 ? v.lo > eps : v.hi < -eps;
}

/* The natural enclosures over the 8 octants, in one batched call. */
static bool octants_free(const ism_tape *t, ism_eval_ws *ws, const ism_interval box[3],
                         int sign, double eps)
{
    ism_interval part[3][8], out[8];
    for (int a = 0; a < 3; a++) {
        /* [lo, mid] and [mid, hi] cover the closed box whatever mid rounds to */
        double mid = 0.5 * (box[a].lo + box[a].hi);
        ism_interval low = {box[a].lo, mid}, high = {mid, box[a].hi};
        for (int o = 0; o < 8; o++)
            part[a][o] = (o >> a) & 1 ? high : low;
    }
    ism_eval_interval_batch(t, ws, part[0], part[1], part[2], out, 8);
    for (int o = 0; o < 8; o++)
        if (!beyond(out[o], sign, eps))
            return false;
    return true;
}

/* Whether a min, max or abs may feed f: its instruction (the last) is not smooth. Only where
 * it says so are the values asked first (the gradient pass's own count decides either way):
 * a scan of the whole tape for one cost Klein's bottle, which has none, 210 instructions a
 * form (1.3M at E = 0.0141, more than the asking saved there). */
static bool may_kink(const ism_tape *t)
{
    return t->len > 0 && !t->code[t->len - 1].smooth;
}

/* f(c) + ∇f(box) · (box − c), c the centre; not where f has a kink in the box. f(c) is the
 * natural enclosure at the point c (ism_eval_interval): the slopes come from the box, which
 * the kink test already covers, so a min/max tie or abs(0) at c itself changes nothing. The
 * kink is told from the values first (ism_eval_interval_meets_kink, the gradient pass's
 * bit for bit): Barth's sextic at E = 0.0259 meets it in 6,752 of 9,512 forms, each a
 * whole gradient pass (~2,300 instructions) spent for nothing before. */
static bool mean_value_free(const ism_tape *t, ism_eval_ws *ws, ism_ivjet_ws *jet,
                            const ism_interval box[3], int sign, double eps)
{
    ism_interval c[3];
    for (int a = 0; a < 3; a++) {
        double m = 0.5 * box[a].lo + 0.5 * box[a].hi;
        c[a] = iv(m, m);
    }
    if (may_kink(t) && ism_eval_interval_meets_kink(t, jet, box))
        return false; /* the slopes would be unbounded there, or the workspace misfits */
    ism_ivgrad over;
    if (ism_eval_interval_grad(t, jet, box, NULL, NULL, &over) != 0)
        return false; /* a kink (the slopes are unbounded there) or a workspace misfit */
    ism_interval at = ism_eval_interval(t, ws, c[0], c[1], c[2]);
    ism_interval mv = at;
    for (int a = 0; a < 3; a++)
        mv = iv_add(mv, iv_mul(over.d[a], iv_sub(box[a], c[a])));
    return beyond(mv, sign, eps + ROUNDING_MARGIN * (at.hi - at.lo));
}

bool ism_box_zero_free(const ism_tape *t, ism_eval_ws *ws, ism_ivjet_ws *jet,
                       const double lo[3], const double hi[3], const ism_corners *k,
                       double eps, uint64_t *intervals)
{
    int sign = corner_sign(k, eps);
    if (sign == 0)
        return false; /* a corner near 0 or corners of both signs: f = 0 may be in it */
    ism_interval box[3];
    for (int a = 0; a < 3; a++) {
        double pad = BOX_MARGIN * (hi[a] - lo[a]);
        box[a] = iv(lo[a] - pad, hi[a] + pad);
    }
    *intervals += 8;
    if (octants_free(t, ws, box, sign, eps))
        return true;
    *intervals += 2;
    return jet && mean_value_free(t, ws, jet, box, sign, eps);
}
