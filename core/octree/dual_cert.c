/* dual_cert.c — enclosures and proofs over one box for the dual mesher (dual_cert.h). */
#include "core/octree/dual_cert.h"
#include "core/eval/interval_ops.h"

#include <math.h>

static ism_interval meet(ism_interval a, ism_interval b)
{
    return iv(fmax(a.lo, b.lo), fmin(a.hi, b.hi));
}

bool ism_dual_taylor(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                     const double hi[3], ism_dual_model *m, uint64_t *intervals)
{
    ism_interval box[3], mid[3];
    for (int a = 0; a < 3; a++) {
        m->c[a] = 0.5 * lo[a] + 0.5 * hi[a];
        box[a] = iv(lo[a], hi[a]);
        mid[a] = iv(m->c[a], m->c[a]);
    }
    *intervals += 2;
    return ism_eval_interval_jet(t, jet, box, NULL, NULL, &m->box) == 0 &&
           ism_eval_interval_grad(t, jet, mid, NULL, NULL, &m->at) == 0;
}

bool ism_dual_taylor_many(const ism_tape *t, ism_ivjet_ws *jet, const double (*lo)[3],
                          const double (*hi)[3], size_t n, ism_dual_model *m, bool *ok)
{
    ism_interval mid[ISM_IVGRAD_BATCH][3];
    ism_ivgrad at[ISM_IVGRAD_BATCH];
    if (n > ISM_IVGRAD_BATCH)
        return false;
    for (size_t k = 0; k < n; k++) {
        ism_interval box[3];
        for (int a = 0; a < 3; a++) {
            m[k].c[a] = 0.5 * lo[k][a] + 0.5 * hi[k][a];
            box[a] = iv(lo[k][a], hi[k][a]);
            mid[k][a] = iv(m[k].c[a], m[k].c[a]);
        }
        ok[k] = ism_eval_interval_jet(t, jet, box, NULL, NULL, &m[k].box) == 0;
    }
    /* after every jet: this batch's records replace those the jets took their values from */
    if (!ism_eval_interval_grad_batch(t, jet, (const ism_interval (*)[3])mid, n, at))
        return false;
    for (size_t k = 0; k < n; k++)
        m[k].at = at[k];
    return true;
}

/* x − c over lo..hi, rounded outward. */
static void round_centre(const ism_dual_model *m, const double lo[3], const double hi[3],
                         ism_interval dx[3])
{
    for (int a = 0; a < 3; a++)
        dx[a] = iv_sub(iv(lo[a], hi[a]), iv(m->c[a], m->c[a]));
}

ism_interval ism_dual_terms_quad(const ism_dual_terms *t)
{
    ism_interval q = t->quad[0];
    for (int k = 1; k < 6; k++)
        q = iv_add(q, t->quad[k]);
    return q;
}

/* f(x) = f(c) + ∇f(c)·(x − c) + ½ (x − c)ᵀ H(ξ) (x − c) over x − c ∈ dx. Out of line: inlined
 * into verdict_over it cost 7% more there (torus at 1e-2: 3.02M → 3.24M instructions). */
static __attribute__((noinline)) ism_interval second_order(const ism_dual_model *m,
                                                          const ism_interval dx[3])
{
    ism_dual_terms t;
    ism_dual_terms_of(&m->at, &m->box, dx, &t);
    return ism_dual_terms_f(m->at.v, &t);
}

ism_interval ism_dual_second_order(const ism_dual_model *m, const double lo[3],
                                   const double hi[3])
{
    ism_interval dx[3];
    round_centre(m, lo, hi, dx);
    return second_order(m, dx);
}

/* ism_dual_over on x − c ∈ dx, with v2 = second_order(m, dx) already taken. */
static bool over_dx(const ism_dual_model *m, const ism_interval dx[3], ism_interval v2,
                    ism_ivgrad *g)
{
    const ism_ivjet *j = &m->box;
    const ism_ivgrad *c = &m->at;
    /* ∇f(x) = ∇f(c) + H(ξ)(x − c), ξ between c and x: in the model's box */
    for (int a = 0; a < 3; a++) {
        ism_interval d = c->d[a];
        for (int b = 0; b < 3; b++)
            d = iv_add(d, iv_mul(j->h[ism_dual_hess_at(a, b)], dx[b]));
        g->d[a] = meet(j->d[a], d);
    }
    ism_interval v1 = c->v;
    for (int a = 0; a < 3; a++)
        v1 = iv_add(v1, iv_mul(g->d[a], dx[a])); /* the mean-value form on the new ∇f */
    g->v = meet(j->v, meet(v1, v2));
    for (int a = 0; a < 3; a++)
        if (!(g->d[a].lo <= g->d[a].hi))
            return false; /* NaN in a bound: no enclosure */
    return g->v.lo <= g->v.hi;
}

bool ism_dual_over(const ism_dual_model *m, const double lo[3], const double hi[3],
                   ism_ivgrad *g)
{
    ism_interval dx[3];
    round_centre(m, lo, hi, dx);
    return over_dx(m, dx, second_order(m, dx), g);
}

bool ism_dual_over_v2(const ism_dual_model *m, const double lo[3], const double hi[3],
                      ism_interval v2, ism_ivgrad *g)
{
    ism_interval dx[3];
    round_centre(m, lo, hi, dx);
    return over_dx(m, dx, v2, g);
}

bool ism_dual_enclose(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                      const double hi[3], ism_ivgrad *g, uint64_t *intervals)
{
    ism_dual_model m;
    return ism_dual_taylor(t, jet, lo, hi, &m, intervals) && ism_dual_over(&m, lo, hi, g);
}

/* The sub-box k (bit a: upper half along a) of lo..hi halved at mid (NULL: the centre). */
static void sub_box(const double lo[3], const double *mid, const double hi[3], int k,
                    double sl[3], double sh[3])
{
    for (int a = 0; a < 3; a++) {
        double m = mid ? mid[a] : 0.5 * lo[a] + 0.5 * hi[a];
        sl[a] = (k >> a & 1) ? m : lo[a];
        sh[a] = (k >> a & 1) ? hi[a] : m;
    }
}

/* ∇f · d over g's box: its interval. */
static ism_interval slope_along(const ism_ivgrad *g, const double d[3])
{
    ism_interval slope = iv(0, 0);
    for (int a = 0; a < 3; a++)
        slope = iv_add(slope, iv_mul_c(g->d[a], d[a]));
    return slope;
}

/* What a box's enclosure proves: FREE (f has no zero in it), 1 (when d is not NULL:
 * ∇f · d > 0 all over it), -1 (∇f · d ≤ 0 all over a box where f may vanish: no proof
 * below it either), 0 (nothing: split). */
enum { FREE = 2 };
static int verdict(const ism_ivgrad *g, const double *d)
{
    if (ism_dual_encl_free(g))
        return FREE;
    if (!d)
        return 0;
    ism_interval slope = slope_along(g, d);
    return slope.lo > 0 ? 1 : slope.hi <= 0 ? -1 : 0;
}

/* The verdict on lo..hi by m's enclosure (ism_dual_over), the cheapest part first: when
 * the second-order form alone keeps f from 0, the enclosure's value (its meet with two
 * more forms) does too, and the verdict is FREE without the ∇f bounds (most of the cost;
 * on the torus at 1e-2 ~2,300 boxes a mesh). -1 also when there is no enclosure (a bound
 * not a number): no proof. */
static int verdict_of(const ism_dual_model *m, const ism_interval dx[3], ism_interval v2,
                      const double *d, ism_interval *v)
{
    if (v2.lo > 0 || v2.hi < 0)
        return FREE;
    ism_ivgrad g;
    if (!over_dx(m, dx, v2, &g))
        return -1;
    *v = g.v;
    return verdict(&g, d);
}

static int verdict_over(const ism_dual_model *m, const double lo[3], const double hi[3],
                        const double *d, ism_interval *v)
{
    ism_interval dx[3];
    round_centre(m, lo, hi, dx);
    return verdict_of(m, dx, second_order(m, dx), d, v);
}

/* The second-order form's terms (ism_dual_terms_of) over the 8 sub-boxes of lo..hi halved
 * at mid (NULL: the centre), from the two halves along each axis: x − c over each half
 * (dx), its linear and diagonal terms, and the off-diagonal ones over each pair of halves.
 * A sub-box's terms are those of its halves — the same operations on the same intervals as
 * ism_dual_terms_of on its own box, so its form has the same bounds — at 42 interval
 * products a box instead of 120 (8 boxes of 15); the sub-boxes' verdicts were ~60% of a
 * proof's cost on the torus at 1e-2. */
typedef struct halves_terms {
    ism_interval dx[3][2], lin[3][2], diag[3][2], off[3][2][2]; /* off: xy, xz, yz */
} halves_terms;

static int pair_of(int a, int b) { return a + b - 1; } /* (0,1) 0, (0,2) 1, (1,2) 2 */

static void halves_terms_of(const ism_dual_model *m, const double lo[3], const double *mid,
                            const double hi[3], halves_terms *h)
{
    for (int a = 0; a < 3; a++) {
        double cut = mid ? mid[a] : 0.5 * lo[a] + 0.5 * hi[a];
        ism_interval c = iv(m->c[a], m->c[a]);
        h->dx[a][0] = iv_sub(iv(lo[a], cut), c);
        h->dx[a][1] = iv_sub(iv(cut, hi[a]), c);
    }
    const ism_ivjet *j = &m->box;
    for (int a = 0; a < 3; a++)
        for (int s = 0; s < 2; s++) {
            ism_interval dx = h->dx[a][s];
            h->lin[a][s] = iv_mul(m->at.d[a], dx);
            h->diag[a][s] = iv_mul_c(iv_mul(j->h[ism_dual_hess_at(a, a)], iv_square(dx)), 0.5);
            for (int b = a + 1; b < 3; b++)
                for (int t = 0; t < 2; t++)
                    h->off[pair_of(a, b)][s][t] =
                        iv_mul(j->h[ism_dual_hess_at(a, b)], iv_mul(dx, h->dx[b][t]));
        }
}

/* Sub-box k's form's bounds (second_order's), and its x − c into dx unless NULL. */
static ism_interval sub_form(const ism_dual_model *m, const halves_terms *h, int k,
                             ism_interval *dx)
{
    ism_dual_terms t;
    for (int a = 0; a < 3; a++) {
        int s = k >> a & 1;
        if (dx)
            dx[a] = h->dx[a][s];
        t.lin[a] = h->lin[a][s];
        t.quad[ism_dual_hess_at(a, a)] = h->diag[a][s];
        for (int b = a + 1; b < 3; b++)
            t.quad[ism_dual_hess_at(a, b)] = h->off[pair_of(a, b)][s][k >> b & 1];
    }
    return ism_dual_terms_f(m->at.v, &t);
}

void ism_dual_sub_forms(const ism_dual_model *m, const double lo[3], const double *mid,
                        const double hi[3], ism_interval f[8])
{
    halves_terms h;
    halves_terms_of(m, lo, mid, hi, &h);
    for (int k = 0; k < 8; k++)
        f[k] = sub_form(m, &h, k, NULL);
}

/* How nearly f's enclosure v (holding 0) is centred on 0: min(−lo, hi) / width, in [0, ½].
 * A sub-box whose enclosure is nearly one-signed is the likelier to be proven by its own
 * model; the most centred ones are tried first, so a proof that fails (the box holds the
 * surface) fails before the models of the sub-boxes beside it are made. */
static double centred(ism_interval v)
{
    double w = v.hi - v.lo;
    return w > 0 ? fmin(-v.lo, v.hi) / w : 0.5;
}

/* The proof (verdict) on lo..hi, whose model is m: from m itself, else on the sub-boxes —
 * each first from m (no evaluation: a sub-box of m's box), then from its own model. FREE
 * when f was shown to have no zero in the box, 1 when the proof holds otherwise, 0 when it
 * does not. The first halving is at mid (NULL: the centre), and bit k of *free_subs
 * (NULL: not wanted) is set for every sub-box k shown free on the way, whatever the
 * verdict. open: m's verdict on the whole box is known to be 0 (not taken again). */
static int prove(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                 const double lo[3], const double *mid, const double hi[3], const double *d,
                 int halvings, bool open_whole, uint8_t *free_subs, uint64_t *intervals)
{
    ism_interval encl;
    int v = open_whole ? 0 : verdict_over(m, lo, hi, d, &encl);
    if (v || halvings <= 0)
        return v > 0 ? v : 0;
    /* the proof holds when it holds on every sub-box: first every verdict m gives (no
     * evaluation), then each undecided sub-box by its own model, most centred first */
    int open[8], nopen = 0;
    double score[8];
    uint8_t shown = 0;
    halves_terms ht;
    halves_terms_of(m, lo, mid, hi, &ht);
    for (int k = 0; k < 8; k++) {
        ism_interval dx[3];
        ism_interval v2 = sub_form(m, &ht, k, dx);
        v = verdict_of(m, dx, v2, d, &encl);
        if (v == FREE)
            shown |= (uint8_t)(1u << k);
        if (v < 0)
            break;
        if (v > 0)
            continue;
        score[k] = centred(encl);
        int at = nopen++;
        for (; at > 0 && score[open[at - 1]] < score[k]; at--)
            open[at] = open[at - 1]; /* stable: equal scores keep sub-box order */
        open[at] = k;
    }
    for (int i = 0; v >= 0 && i < nopen; i++) {
        double sl[3], sh[3];
        ism_dual_model sm;
        sub_box(lo, mid, hi, open[i], sl, sh);
        v = ism_dual_taylor(t, jet, sl, sh, &sm, intervals)
                ? prove(t, jet, &sm, sl, NULL, sh, d, halvings - 1, false, NULL, intervals)
                : 0;
        if (v == FREE)
            shown |= (uint8_t)(1u << open[i]);
        if (!v)
            break;
    }
    if (free_subs)
        *free_subs |= shown;
    return v <= 0 ? 0 : shown == 0xff ? FREE : 1;
}

bool ism_dual_free(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                   const double lo[3], const double hi[3], int halvings, uint64_t *intervals)
{
    return prove(t, jet, m, lo, NULL, hi, NULL, halvings, false, NULL, intervals) > 0;
}

bool ism_dual_graph_along(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                          const double lo[3], const double hi[3], const double d[3],
                          int halvings, uint64_t *intervals)
{
    return prove(t, jet, m, lo, NULL, hi, d, halvings, false, NULL, intervals) > 0;
}

bool ism_dual_prove_halves(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                           const double lo[3], const double *mid, const double hi[3],
                           const double *d, int halvings, bool open_whole,
                           uint8_t *free_subs, uint64_t *intervals)
{
    return prove(t, jet, m, lo, mid, hi, d, halvings, open_whole, free_subs, intervals) > 0;
}
