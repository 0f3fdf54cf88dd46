/* dual_cert.c — enclosures and proofs over one box for the dual mesher (dual_cert.h). */
#include "core/octree/dual_cert.h"
#include "core/eval/interval_ops.h"

#include <math.h>

/* The Hessian pairs in ism_ivjet's order (xx xy xz yy yz zz). */
static int hess_at(int a, int b)
{
    static const int AT[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    return AT[a][b];
}

static ism_interval meet(ism_interval a, ism_interval b)
{
    return iv(fmax(a.lo, b.lo), fmin(a.hi, b.hi));
}

bool ism_dual_enclose(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                      const double hi[3], ism_ivgrad *g, uint64_t *intervals)
{
    ism_interval box[3], mid[3], dx[3];
    for (int a = 0; a < 3; a++) {
        double c = 0.5 * lo[a] + 0.5 * hi[a];
        box[a] = iv(lo[a], hi[a]);
        mid[a] = iv(c, c);
        dx[a] = iv_sub(box[a], mid[a]); /* the box round its centre, rounded outward */
    }
    ism_ivjet j;
    ism_ivgrad c;
    *intervals += 2;
    if (ism_eval_interval_jet(t, jet, box, NULL, NULL, &j) != 0 ||
        ism_eval_interval_grad(t, jet, mid, NULL, NULL, &c) != 0)
        return false;
    /* ∇f(x) = ∇f(c) + H(ξ)(x − c), ξ in the box */
    for (int a = 0; a < 3; a++) {
        ism_interval d = c.d[a];
        for (int b = 0; b < 3; b++)
            d = iv_add(d, iv_mul(j.h[hess_at(a, b)], dx[b]));
        g->d[a] = meet(j.d[a], d);
    }
    /* f(x) = f(c) + ∇f(c)·(x − c) + ½ (x − c)ᵀ H(ξ) (x − c); the diagonal terms take the
     * square's [0, r²], the two equal off-diagonal ones are counted once at twice their
     * weight (H's xy entry times δx δy, twice, halved). */
    ism_interval v2 = c.v, v1 = c.v;
    for (int a = 0; a < 3; a++) {
        v2 = iv_add(v2, iv_mul(c.d[a], dx[a]));
        v2 = iv_add(v2, iv_mul_c(iv_mul(j.h[hess_at(a, a)], iv_square(dx[a])), 0.5));
        for (int b = a + 1; b < 3; b++)
            v2 = iv_add(v2, iv_mul(j.h[hess_at(a, b)], iv_mul(dx[a], dx[b])));
        v1 = iv_add(v1, iv_mul(g->d[a], dx[a])); /* the mean-value form on the new ∇f */
    }
    g->v = meet(j.v, meet(v1, v2));
    for (int a = 0; a < 3; a++)
        if (!(g->d[a].lo <= g->d[a].hi))
            return false; /* NaN in a bound: no enclosure */
    return g->v.lo <= g->v.hi;
}

/* The sub-box k (bit a: upper half along a) of lo..hi. */
static void sub_box(const double lo[3], const double hi[3], int k, double sl[3], double sh[3])
{
    for (int a = 0; a < 3; a++) {
        double m = 0.5 * lo[a] + 0.5 * hi[a];
        sl[a] = (k >> a & 1) ? m : lo[a];
        sh[a] = (k >> a & 1) ? hi[a] : m;
    }
}

bool ism_dual_free(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3], const double hi[3],
                   int halvings, bool self, uint64_t *intervals)
{
    ism_ivgrad g;
    if (self) {
        if (!ism_dual_enclose(t, jet, lo, hi, &g, intervals))
            return false;
        if (ism_dual_encl_free(&g))
            return true;
    }
    if (halvings <= 0)
        return false;
    for (int k = 0; k < 8; k++) {
        double sl[3], sh[3];
        sub_box(lo, hi, k, sl, sh);
        if (!ism_dual_free(t, jet, sl, sh, halvings - 1, true, intervals))
            return false;
    }
    return true;
}

bool ism_dual_graph_along(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                          const double hi[3], const double d[3], int halvings, bool self,
                          uint64_t *intervals)
{
    if (self) {
        ism_ivgrad g;
        if (!ism_dual_enclose(t, jet, lo, hi, &g, intervals))
            return false;
        if (ism_dual_encl_free(&g))
            return true;
        ism_interval slope = iv(0, 0);
        for (int a = 0; a < 3; a++)
            slope = iv_add(slope, iv_mul_c(g.d[a], d[a]));
        if (slope.lo > 0)
            return true;
        if (slope.hi <= 0)
            return false; /* ∇f·d ≤ 0 all over a box where f may vanish */
    }
    if (halvings <= 0)
        return false;
    for (int k = 0; k < 8; k++) {
        double sl[3], sh[3];
        sub_box(lo, hi, k, sl, sh);
        if (!ism_dual_graph_along(t, jet, sl, sh, d, halvings - 1, true, intervals))
            return false;
    }
    return true;
}
