/* thin_search.c — a depth-first walk over sub-boxes of one node (see thin_search.h): each
 * box is dropped when its natural enclosure of f, or the mean-value form f(c) + ∇F·(X − c),
 * keeps the corners' sign; a box that survives is probed by Newton from its centre and,
 * unless the probe crosses to the other sign, cut in eight. A point found where f has a
 * kink is reported as such (ISM_THIN_FOUND_KINKED): it may lie on a crease's sliver. */
#include "core/octree/thin_search.h"
#include "core/eval/interval_ops.h"

#include <math.h>
#include <string.h>

/* Sub-boxes down to 1/2^THIN_SEARCH_LEVELS of the node: a piece that the Newton probes
 * miss from the node's centre is found from the centre of a box this much smaller (a tube
 * or a ball a few times thinner than such a box is aimed at from any side). The octree
 * then splits the node and searches its children again, so deeper pieces are still reached
 * one level at a time. */
#define THIN_SEARCH_LEVELS 3
/* Sub-box levels where f has a kink (the box and its octants): near a crease the natural
 * enclosure drops few boxes (the mean-value form is no better there: the gradients'
 * enclosure spans both sides of the kink, so it is not computed), and a search that finds
 * nothing spends its whole budget. The gyroid ball (own box, depth 7, one thread), where
 * nothing is hidden: 2,051M instructions without searching at kinks, 2,363M with 3 levels,
 * 2,247M with 1, 2,161M with 1 and no mean-value form below the kink. A piece of its own a
 * quarter of the node across (cube minus ball r = 1.4: its bars at depth 5) is found by the
 * probes from the node's and its octants' centres. */
#define KINKED_SEARCH_LEVELS 1
/* Surviving boxes per search: at most one node's worth of the deepest level's neighbours
 * of a tangency (where f touches 0 without a sign change nothing is ever excluded: the
 * search must end undecided, not cover the node box by box). */
#define THIN_SEARCH_BOXES 48
/* Newton steps per probe: from a box's centre to a piece within it converges in a few. */
#define PROBE_STEPS 6
/* Each step goes this much past Newton's f = 0: lands on the other side of a simple zero
 * (the error flips to -PROBE_OVERSHOOT of itself), and from outside a tube or ball of
 * radius r at distance ρ ≫ r it gets within r in about log(ρ/r) steps. */
#define PROBE_OVERSHOOT 0.5
/* A probe stops when a step moves less than this fraction of the box (stuck on its wall). */
#define PROBE_MIN_MOVE 1e-9
/* Probes side by side at most (probe_lanes): a box's and its eight octants'. */
#define PROBE_LANES 9

typedef struct sbox {
    ism_interval x[3];
    int level;
} sbox;

/* v when lo <= v <= hi, its own zero included (+0 against a bound -0: the Newton step's
 * p - t g when the two are equal), else the nearer bound; v is not NaN (step). Bit for bit
 * the library calls it replaces as GCC 12 compiled them: fmin(fmax(v, lo), hi) was emitted as
 * fmin(hi, fmax(lo, v)) (C leaves the sign of their zero open, so GCC takes both as
 * commutative), and glibc's x86-64 fmax and fmin are maxsd and minsd (the second operand when
 * equal), as these two lines compile. Inline: the calls cost Barth's sextic at E 0.0259 2.5M
 * instructions of its probes' 16.7M. */
static inline double clamp(double v, double lo, double hi)
{
    v = lo > v ? lo : v;
    return hi < v ? hi : v;
}

static bool other_sign(double f, int sign) { return sign > 0 ? f < 0 : f > 0; }

static bool keeps_sign(ism_interval v, int sign) { return sign > 0 ? v.lo > 0 : v.hi < 0; }

/* Is the box flat along axis k (a node's face: the search stays in its plane)? */
static bool flat_along(const ism_interval x[3], int k) { return x[k].lo == x[k].hi; }

/* Newton from the box's centre toward f = 0 and a little past it, clamped to the box (in a
 * face, along the gradient's part in the face's plane). A step back to the point of two steps
 * before ends the probe: from there it would only visit those two points again (a 2-cycle
 * across a kink, between a CSG wedge's two planes, or clamped on a wall), both evaluated
 * without the other sign. One probe's state between its evaluations (probe_start,
 * probe_take), so that probes may run one at a time (probe) or side by side (probe_lanes). */
typedef struct probe_run {
    ism_interval x[3];
    double p[3], before[3], size;
    int it;
    bool flat[3]; /* flat_along each axis */
} probe_run;

enum { PROBE_GOES_ON, PROBE_HIT, PROBE_MISSED };

static void probe_start(probe_run *r, const ism_interval x[3])
{
    r->size = INFINITY;
    r->it = 0;
    for (int k = 0; k < 3; k++) {
        r->x[k] = x[k];
        r->p[k] = 0.5 * x[k].lo + 0.5 * x[k].hi;
        r->before[k] = NAN; /* equal to nothing */
        r->flat[k] = flat_along(x, k);
        double w = x[k].hi - x[k].lo;
        /* fmin(size, w), a NaN w (NaN bounds) included; off a flat axis w != 0, so which
         * operand wins on equality cannot change the sign of a zero */
        if (!r->flat[k])
            r->size = w < r->size ? w : r->size;
    }
}

/* p moved by -t g and clamped to the box x, how far (summed over the axes) into the result.
 * t and g are finite when finite_t (probe_take), so p - t g is not NaN; else an axis where g
 * is 0 gets inf · 0 = NaN, which the fmax(lo, v) clamp replaced took as lo. Inlined twice, so
 * that the check is made once a step, not once an axis. */
static inline __attribute__((always_inline)) double step(double p[3], const double g[3],
                                                         double t, const ism_interval x[3],
                                                         bool finite_t)
{
    double moved = 0;
    for (int k = 0; k < 3; k++) {
        double v = p[k] - t * g[k];
        if (!finite_t && isnan(v))
            v = x[k].lo;
        double q = clamp(v, x[k].lo, x[k].hi);
        moved += fabs(q - p[k]);
        p[k] = q;
    }
    return moved;
}

/* The probe r after f and its gradient g at r->p: HIT (r->p has the other sign), MISSED, or
 * GOES_ON from its next point, r->p. */
static int probe_take(probe_run *r, int sign, double f, double g[3])
{
    const ism_interval *x = r->x;
    if (other_sign(f, sign))
        return PROBE_HIT;
    for (int k = 0; k < 3; k++)
        if (r->flat[k])
            g[k] = 0;
    double gg = ism_dot3(g, g);
    if (r->it == PROBE_STEPS || !(gg > 0) || !isfinite(gg) || !isfinite(f))
        return PROBE_MISSED;
    double t = (1 + PROBE_OVERSHOOT) * f / gg, moved, last[3];
    double *p = r->p;
    memcpy(last, p, sizeof last);
    if (isfinite(t))
        moved = step(p, g, t, x, true);
    else /* f / gg overflowed (gg near the least doubles) */
        moved = step(p, g, t, x, false);
    if (!(moved > PROBE_MIN_MOVE * r->size) ||
        (p[0] == r->before[0] && p[1] == r->before[1] && p[2] == r->before[2]))
        return PROBE_MISSED;
    memcpy(r->before, last, sizeof r->before);
    r->it++;
    return PROBE_GOES_ON;
}

static bool probe(ism_sampler *s, const ism_interval x[3], int sign, double found[3])
{
    probe_run r;
    probe_start(&r, x);
    int v = PROBE_GOES_ON;
    while (v == PROBE_GOES_ON) {
        double g[3];
        double f = ism_sample_grad(s, r.p, g);
        v = probe_take(&r, sign, f, g);
    }
    if (v == PROBE_HIT)
        memcpy(found, r.p, sizeof r.p);
    return v == PROBE_HIT;
}

/* The probes of the boxes b[0..n) (n <= PROBE_LANES) side by side, their points' gradients in one
 * ism_sample_grad_batch a step (bit for bit one at a time's): what probing them one by one
 * in order until one hits answers, and found the same point. A probe goes on only while no
 * earlier one has hit (a later hit cannot be the first). */
static bool probe_lanes(ism_sampler *s, const ism_interval (*b)[3], int n, int sign,
                        double found[3])
{
    probe_run r[PROBE_LANES];
    int state[PROBE_LANES], first_hit = n;
    for (int c = 0; c < n; c++) {
        probe_start(&r[c], b[c]);
        state[c] = PROBE_GOES_ON;
    }
    for (;;) {
        double p[PROBE_LANES][3], f[PROBE_LANES], g[PROBE_LANES][3];
        int lane[PROBE_LANES], m = 0;
        for (int c = 0; c < first_hit; c++)
            if (state[c] == PROBE_GOES_ON) {
                memcpy(p[m], r[c].p, sizeof p[m]);
                lane[m++] = c;
            }
        if (!m)
            break;
        if (m == 1) /* one point: its own pass costs less than a padded group */
            f[0] = ism_sample_grad(s, p[0], g[0]);
        else
            ism_sample_grad_batch(s, (const double (*)[3])p, f, g, (size_t)m);
        for (int j = 0; j < m; j++) {
            int c = lane[j];
            state[c] = probe_take(&r[c], sign, f[j], g[j]);
            if (state[c] == PROBE_HIT && c < first_hit)
                first_hit = c;
        }
    }
    if (first_hit == n)
        return false;
    memcpy(found, r[first_hit].p, sizeof r[first_hit].p);
    return true;
}

/* Does the mean-value form prove that f keeps `sign` on the box? *kinked is set when f
 * has a kink in it (the form is then no better than the natural enclosure). */
static bool mean_value_keeps(ism_sampler *s, ism_thin_ws *w, const ism_interval x[3], int sign,
                             bool *kinked)
{
    ism_ivgrad over;
    s->n_interval++;
    size_t kinks = ism_eval_interval_grad(s->tape, w->jet, x, NULL, NULL, &over);
    *kinked = kinks != 0;
    if (kinks == (size_t)-1)
        return false;
    if (keeps_sign(over.v, sign))
        return true;
    if (*kinked)
        return false; /* the gradients' enclosure spans both sides of the kink */
    ism_interval c[3], d[3];
    for (int k = 0; k < 3; k++) {
        double m = 0.5 * x[k].lo + 0.5 * x[k].hi;
        c[k] = iv(m, m);
        d[k] = iv_sub(x[k], c[k]);
    }
    ism_ivgrad at;
    s->n_interval++;
    ism_eval_interval_grad(s->tape, w->jet, c, NULL, NULL, &at);
    ism_interval mv = at.v;
    for (int k = 0; k < 3; k++)
        mv = iv_add(mv, iv_mul(over.d[k], d[k]));
    return keeps_sign(mv, sign);
}

/* Pushes the children of b that the natural enclosure cannot drop (four in a face). */
static int push_children(ism_sampler *s, const sbox *b, int sign, sbox *stack, int top)
{
    ism_interval x[8], y[8], z[8], out[8];
    sbox kids[8];
    int n = 0;
    for (int c = 0; c < 8; c++) {
        bool twin = false; /* the same box as an earlier child: b is flat along that axis */
        for (int k = 0; k < 3; k++) {
            double m = 0.5 * b->x[k].lo + 0.5 * b->x[k].hi;
            twin |= ((c >> k) & 1) && flat_along(b->x, k);
            kids[n].x[k] = (c >> k) & 1 ? iv(m, b->x[k].hi) : iv(b->x[k].lo, m);
        }
        if (twin)
            continue;
        kids[n].level = b->level + 1;
        x[n] = kids[n].x[0];
        y[n] = kids[n].x[1];
        z[n] = kids[n].x[2];
        n++;
    }
    s->n_interval += (uint64_t)n;
    ism_eval_interval_batch(s->tape, s->ws, x, y, z, out, (size_t)n);
    for (int c = n - 1; c >= 0; c--) /* child 0 on top: examined first */
        if (!keeps_sign(out[c], sign))
            stack[top++] = kids[c];
    return top;
}

enum ism_thin_verdict ism_thin_search(ism_sampler *s, ism_thin_ws *w, const double lo[3],
                                      const double hi[3], int sign, double found[3])
{
    double scratch[3];
    if (!found)
        found = scratch;
    /* depth first: at most 8 children pushed per level below the one expanded */
    sbox stack[8 * THIN_SEARCH_LEVELS + 1];
    int top = 0;
    for (int k = 0; k < 3; k++)
        stack[0].x[k] = iv(lo[k], hi[k]);
    stack[0].level = 0;
    top = 1;
    bool undecided = false, kinked_box = false;
    for (int budget = THIN_SEARCH_BOXES; top > 0;) {
        sbox b = stack[--top];
        w->n_boxes++;
        bool kinked = kinked_box;
        /* below a kink the children's natural enclosure (push_children) is all there is */
        if (!kinked_box && mean_value_keeps(s, w, b.x, sign, &kinked))
            continue;
        kinked_box |= kinked && b.level == 0;
        if (probe(s, b.x, sign, found))
            return kinked_box ? ISM_THIN_FOUND_KINKED : ISM_THIN_FOUND;
        int levels = kinked_box ? KINKED_SEARCH_LEVELS : THIN_SEARCH_LEVELS;
        if (b.level == levels || --budget == 0) {
            undecided = true;
            if (budget == 0)
                break;
            continue;
        }
        top = push_children(s, &b, sign, stack, top);
    }
    return undecided ? ISM_THIN_UNDECIDED : ISM_THIN_EXCLUDED;
}

enum ism_thin_verdict ism_thin_probe(ism_sampler *s, const double lo[3], const double hi[3],
                                     int sign, double found[3])
{
    double scratch[3];
    if (!found)
        found = scratch;
    bool kinked = ism_tape_has_min_max(s->tape);
    enum ism_thin_verdict hit = kinked ? ISM_THIN_FOUND_KINKED : ISM_THIN_FOUND;
    ism_interval x[3];
    for (int k = 0; k < 3; k++)
        x[k] = iv(lo[k], hi[k]);
    /* the box's probe first, then the octants' (quadrants in a face) where their batched
     * interval leaves the other sign possible (a probe never leaves its box); the first in
     * that order to hit answers. Side by side (probe_lanes) where f has a min or max, whose
     * one-point gradients cost more than a lane's: Barth's sextic at E 0.0259, 4,144 calls,
     * 73.9M -> 70.6M instructions (the octants' interval then taken even where the box's
     * probe hits alone, 72 calls). One by one elsewhere: a lane cost the Klein bottle's tape
     * as much as a point alone, and the calls at E 0.00327 56.9M -> 62.8M side by side. */
    if (!kinked && probe(s, x, sign, found))
        return hit;
    ism_interval open[PROBE_LANES][3], ox[8], oy[8], oz[8], kept[8];
    int n = 0, m = 0;
    if (kinked)
        memcpy(open[m++], x, sizeof open[0]);
    for (int c = 0; c < 8; c++) {
        bool twin = false; /* the same octant as an earlier one: the box is flat there */
        ism_interval o[3];
        for (int k = 0; k < 3; k++) {
            double mid = 0.5 * lo[k] + 0.5 * hi[k];
            twin |= ((c >> k) & 1) && flat_along(x, k);
            o[k] = (c >> k) & 1 ? iv(mid, hi[k]) : iv(lo[k], mid);
        }
        if (twin)
            continue;
        ox[n] = o[0], oy[n] = o[1], oz[n] = o[2];
        n++;
    }
    s->n_interval += (uint64_t)n;
    ism_eval_interval_batch(s->tape, s->ws, ox, oy, oz, kept, (size_t)n);
    for (int c = 0; c < n; c++)
        if (!keeps_sign(kept[c], sign)) {
            open[m][0] = ox[c], open[m][1] = oy[c], open[m][2] = oz[c];
            m++;
        }
    const ism_interval (*b)[3] = (const ism_interval (*)[3])open;
    if (kinked)
        return probe_lanes(s, b, m, sign, found) ? hit : ISM_THIN_UNDECIDED;
    for (int c = 0; c < m; c++)
        if (probe(s, b[c], sign, found))
            return hit;
    return ISM_THIN_UNDECIDED;
}

bool ism_thin_probe_one(ism_sampler *s, const double lo[3], const double hi[3], int sign,
                        double found[3])
{
    ism_interval x[3];
    for (int k = 0; k < 3; k++)
        x[k] = iv(lo[k], hi[k]);
    return probe(s, x, sign, found);
}

bool ism_thin_ws_init(ism_thin_ws *w, const ism_tape *t)
{
    w->n_boxes = 0;
    w->jet = ism_ivjet_ws_new(t);
    return w->jet != NULL;
}

void ism_thin_ws_free(ism_thin_ws *w)
{
    if (w->jet)
        ism_ivjet_ws_free(w->jet);
    w->jet = NULL;
}
