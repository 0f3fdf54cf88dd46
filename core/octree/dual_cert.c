/* dual_cert.c — enclosures and proofs over one box for the dual mesher (dual_cert.h). */
#include "core/octree/dual_cert.h"
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_lanes.h"
#include "core/eval/interval_ops.h"

#include <math.h>

/* The larger of two bounds, a's when they are equal (so -0 against +0 too), the number
 * over a NaN: glibc's fmax (C leaves the sign of a zero result open), written out so that
 * the sub-box lanes below (vmeet) take the same bits; fmin likewise. */
static double max_bound(double a, double b) { return a >= b || b != b ? a : b; }
static double min_bound(double a, double b) { return a <= b || b != b ? a : b; }

static ism_interval meet(ism_interval a, ism_interval b)
{
    return iv(max_bound(a.lo, b.lo), min_bound(a.hi, b.hi));
}

/* The centre of lo..hi along a (a model's centre c, the default halving point). */
static double centre_along(const double lo[3], const double hi[3], int a)
{
    return 0.5 * lo[a] + 0.5 * hi[a];
}

/* Where lo..hi is halved along a: at mid[a], or at its centre when mid is NULL. */
static double halving_at(const double lo[3], const double *mid, const double hi[3], int a)
{
    return mid ? mid[a] : centre_along(lo, hi, a);
}

bool ism_dual_taylor(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                     const double hi[3], ism_dual_model *m, uint64_t *intervals)
{
    ism_interval box[3], mid[3];
    for (int a = 0; a < 3; a++) {
        m->c[a] = centre_along(lo, hi, a);
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
    /* no tape test here: a scan of the tape each call cost the torus at 1e-2 +0.14%; the
       centre batch below refuses tapes with a min, max or abs (test_dual_cert
       models_at_once_declined_on_a_tape_with_a_kink fails if it ever takes them) */
    if (n > ISM_IVGRAD_BATCH)
        return false;
    ism_interval box[ISM_IVGRAD_BATCH][3];
    ism_ivjet bj[ISM_IVGRAD_BATCH];
    for (size_t k = 0; k < n; k++) {
        for (int a = 0; a < 3; a++) {
            m[k].c[a] = centre_along(lo[k], hi[k], a);
            box[k][a] = iv(lo[k][a], hi[k][a]);
            mid[k][a] = iv(m[k].c[a], m[k].c[a]);
        }
    }
    /* the jets in lanes (bit for bit the one-box jets; hess_only's lanes from the records
       of one group of the natural batch when every box has one there, else the whole
       second-order pass): torus at 1e-2, 16.23M -> 15.64M instructions (callgrind). ok
       true: the centre batch below takes no tape with a min, max or abs (else false, and
       nothing here is read), so neither the jets nor the centres have kinks */
    if (ism_eval_interval_jet_lanes(t, jet, (const ism_interval (*)[3])box, n, bj)) {
        for (size_t k = 0; k < n; k++) {
            m[k].box = bj[k];
            ok[k] = true;
        }
    } else
        for (size_t k = 0; k < n; k++)
            ok[k] = ism_eval_interval_jet(t, jet, box[k], NULL, NULL, &m[k].box) == 0;
    /* after every jet: this batch's records replace those the jets took their values from */
    if (!ism_eval_interval_grad_batch(t, jet, (const ism_interval (*)[3])mid, n, at))
        return false;
    for (size_t k = 0; k < n; k++)
        m[k].at = at[k];
    return true;
}

/* x − c along a over lo..hi, rounded outward. */
static ism_interval from_centre(const ism_dual_model *m, int a, double lo, double hi)
{
    return iv_sub(iv(lo, hi), iv(m->c[a], m->c[a]));
}

/* x − c over lo..hi, rounded outward. */
static void round_centre(const ism_dual_model *m, const double lo[3], const double hi[3],
                         ism_interval dx[3])
{
    for (int a = 0; a < 3; a++)
        dx[a] = from_centre(m, a, lo[a], hi[a]);
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
        double m = halving_at(lo, mid, hi, a);
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

/* verdict_of from the form v2 and the enclosure g already taken (ok: over_dx's answer; g
 * and ok not read when v2 keeps f from 0). */
static int verdict_from(ism_interval v2, bool ok, const ism_ivgrad *g, const double *d,
                        ism_interval *v)
{
    if (v2.lo > 0 || v2.hi < 0)
        return FREE;
    if (!ok)
        return -1;
    *v = g->v;
    return verdict(g, d);
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
    bool ok = over_dx(m, dx, v2, &g);
    return verdict_from(v2, ok, &g, d, v);
}

static int verdict_over(const ism_dual_model *m, const double lo[3], const double hi[3],
                        const double *d, ism_interval *v)
{
    ism_interval dx[3];
    round_centre(m, lo, hi, dx);
    return verdict_of(m, dx, second_order(m, dx), d, v);
}

/* Models' second-order forms and enclosures in lanes, four boxes a step (interval_lanes.h):
 * for box k, f's second-order form (form, ism_dual_second_order's bounds) and the
 * enclosure (g, ok: ism_dual_over's). Each lane takes the same operations on the same
 * intervals as the scalar code on its own box (x − c as round_centre takes it, the terms
 * in ism_dual_terms_of's operand order, summed in ism_dual_terms_f's, then over_dx's
 * steps), so the same bits. Two uses: the 8 sub-boxes of a proof from its node's model
 * (sub_encls; one by one, with the terms shared by halves, 42 interval products for 8
 * boxes, and an enclosure wherever the form held 0, they were ~1.6M of the torus's 22.2M
 * instructions at 1e-2, ~7K a proof), and the nodes whose models were made at once
 * (ism_dual_over_many). */
typedef struct lane_out {
    ism_interval form[4];
    ism_ivgrad g[4];
    bool ok[4];
} lane_out;

/* A model per lane: the centre's value and gradient, the box's Hessian, gradient, value. */
typedef struct vmodel {
    vi cv, cd[3], h[6], jd[3], jv;
} vmodel;

/* vmodel's fields and the ism_dual_model part each holds, (lane field, model field): both
 * fillers (gather_model, splat_model) run this one list, so a field added to vmodel and here
 * reaches both, and one missing here is left unset in both. */
#define VMODEL_FIELDS(X)                                                                  \
    X(cv, at.v) X(jv, box.v)                                                              \
    X(cd[0], at.d[0]) X(cd[1], at.d[1]) X(cd[2], at.d[2])                                 \
    X(jd[0], box.d[0]) X(jd[1], box.d[1]) X(jd[2], box.d[2])                              \
    X(h[0], box.h[0]) X(h[1], box.h[1]) X(h[2], box.h[2])                                 \
    X(h[3], box.h[3]) X(h[4], box.h[4]) X(h[5], box.h[5])

/* meet on lanes: max_bound / min_bound's choices */
INLINE vi vmeet(vi a, vi b)
{
    return (vi){v4_pick((a.lo >= b.lo) | (b.lo != b.lo), a.lo, b.lo),
                v4_pick((a.hi <= b.hi) | (b.hi != b.hi), a.hi, b.hi)};
}

/* Lane j: *u[j]. */
INLINE vi gather(const ism_interval *const u[4])
{
    return (vi){{u[0]->lo, u[1]->lo, u[2]->lo, u[3]->lo}, {u[0]->hi, u[1]->hi, u[2]->hi, u[3]->hi}};
}

/* Lane j: m[j]'s part (four different models: ism_dual_over_many's nodes; many_groups pads
 * a short last group by repeating one). */
INLINE void gather_model(const ism_dual_model *const m[4], vmodel *M)
{
    const ism_interval *u[4];
#define GATHER(dst, field)                                                                 \
    do {                                                                                   \
        for (int j = 0; j < 4; j++)                                                        \
            u[j] = &m[j]->field;                                                           \
        M->dst = gather(u);                                                                \
    } while (0);
    VMODEL_FIELDS(GATHER)
#undef GATHER
}

/* Every lane: m's part (gather_model of one model four times, each part one broadcast: the
 * gathers' loads were ~0.1M of the torus's 16.6M instructions at E 0.0141). */
INLINE void splat_model(const ism_dual_model *m, vmodel *M)
{
#define SPLAT(dst, field) M->dst = v_splat(m->field);
    VMODEL_FIELDS(SPLAT)
#undef SPLAT
}

INLINE void store_lanes(vi u, ism_interval *out, size_t stride)
{
    double lo[4], hi[4];
    v4_st(lo, u.lo);
    v4_st(hi, u.hi);
    for (int j = 0; j < 4; j++)
        *(ism_interval *)((char *)out + j * stride) = iv(lo[j], hi[j]);
}

/* Four boxes' forms and enclosures (x − c over them in dx); the enclosures only when some
 * form does not keep f from 0 (holds 0, or a NaN bound), unless every (g undefined and ok
 * false otherwise). */
INLINE void lanes_encl(const vmodel *M, const vi dx[3], bool every, lane_out *out)
{
    vi f = M->cv; /* second_order */
    for (int a = 0; a < 3; a++) {
        f = v_add(f, v_mul(M->cd[a], dx[a]));
        for (int b = a; b < 3; b++) {
            vi h = M->h[ism_dual_hess_at(a, b)];
            f = v_add(f, b == a ? v_mul_c(v_mul(h, v_square(dx[a])), 0.5)
                                : v_mul(h, v_mul(dx[a], dx[b])));
        }
    }
    store_lanes(f, out->form, sizeof(ism_interval));
    /* verdict_from's FREE test: a NaN bound keeps nothing from 0, and the scalar code then
       takes the enclosure (its meets may give a number there) */
    v4i kept = (v4i)(f.lo > splat(0.0)) | (v4i)(f.hi < splat(0.0));
    if (!every && (kept[0] & kept[1] & kept[2] & kept[3])) {
        for (int j = 0; j < 4; j++) /* every form keeps f from 0: no verdict reads g */
            out->ok[j] = false;     /* (ok set all the same: a bool is passed on) */
        return;
    }
    vi gd[3]; /* over_dx */
    v4i ok = (v4i){-1, -1, -1, -1};
    for (int a = 0; a < 3; a++) {
        vi d = M->cd[a];
        for (int b = 0; b < 3; b++)
            d = v_add(d, v_mul(M->h[ism_dual_hess_at(a, b)], dx[b]));
        gd[a] = vmeet(M->jd[a], d);
        ok &= (v4i)(gd[a].lo <= gd[a].hi);
    }
    vi v1 = M->cv;
    for (int a = 0; a < 3; a++)
        v1 = v_add(v1, v_mul(gd[a], dx[a]));
    vi gv = vmeet(M->jv, vmeet(v1, f));
    ok &= (v4i)(gv.lo <= gv.hi);
    store_lanes(gv, &out->g[0].v, sizeof(ism_ivgrad));
    for (int a = 0; a < 3; a++)
        store_lanes(gd[a], &out->g[0].d[a], sizeof(ism_ivgrad));
    for (int j = 0; j < 4; j++)
        out->ok[j] = ok[j] != 0;
}

/* Sub-box k = 4 q + j of a proof in group q, lane j: dxh[a][k >> a & 1] along a. */
INLINE void sub_groups(const ism_dual_model *m, const ism_interval dxh[3][2], bool every,
                       lane_out out[2])
{
    vmodel M;
    splat_model(m, &M);
    for (int q = 0; q < 2; q++) {
        vi dx[3];
        for (int a = 0; a < 3; a++) {
            const ism_interval *u[4];
            for (int j = 0; j < 4; j++)
                u[j] = &dxh[a][(4 * q + j) >> a & 1];
            dx[a] = gather(u);
        }
        lanes_encl(&M, dx, every, &out[q]);
    }
}

/* Boxes 4 q + j of n (the last repeated to fill a group): model m[k], x − c in dx[k]. */
INLINE void many_groups(const ism_dual_model *m, const ism_interval (*dx)[3], size_t n,
                        bool every, lane_out *out)
{
    for (size_t q = 0; 4 * q < n; q++) {
        const ism_dual_model *ms[4];
        const ism_interval *u[3][4];
        for (size_t j = 0; j < 4; j++) {
            size_t k = 4 * q + j < n ? 4 * q + j : n - 1;
            ms[j] = &m[k];
            for (int a = 0; a < 3; a++)
                u[a][j] = &dx[k][a];
        }
        vmodel M;
        gather_model(ms, &M);
        vi vdx[3];
        for (int a = 0; a < 3; a++)
            vdx[a] = gather(u[a]);
        lanes_encl(&M, vdx, every, &out[q]);
    }
}

#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE static void sub_avx2(const ism_dual_model *m, const ism_interval dxh[3][2],
                                    bool every, lane_out out[2])
{
    sub_groups(m, dxh, every, out);
}
ISM_AVX2_CLONE static void many_avx2(const ism_dual_model *m, const ism_interval (*dx)[3],
                                     size_t n, bool every, lane_out *out)
{
    many_groups(m, dx, n, every, out);
}
#endif

static void sub_base(const ism_dual_model *m, const ism_interval dxh[3][2], bool every,
                     lane_out out[2])
{
    sub_groups(m, dxh, every, out);
}
static void many_base(const ism_dual_model *m, const ism_interval (*dx)[3], size_t n,
                      bool every, lane_out *out)
{
    many_groups(m, dx, n, every, out);
}

/* lanes_encl on m's 8 sub-boxes: sub-box k in out[k >> 2], lane k & 3. */
static void sub_encls(const ism_dual_model *m, const double lo[3], const double *mid,
                      const double hi[3], bool every, lane_out out[2])
{
    ism_interval dxh[3][2];
    for (int a = 0; a < 3; a++) {
        double cut = halving_at(lo, mid, hi, a);
        dxh[a][0] = from_centre(m, a, lo[a], cut); /* round_centre's on each half */
        dxh[a][1] = from_centre(m, a, cut, hi[a]);
    }
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2()) {
        sub_avx2(m, (const ism_interval (*)[2])dxh, every, out);
        return;
    }
#endif
    sub_base(m, (const ism_interval (*)[2])dxh, every, out);
}

void ism_dual_sub_encls(const ism_dual_model *m, const double lo[3], const double *mid,
                        const double hi[3], bool every, ism_interval form[8], ism_ivgrad g[8],
                        bool ok[8])
{
    lane_out out[2];
    sub_encls(m, lo, mid, hi, every, out);
    for (int k = 0; k < 8; k++) {
        form[k] = out[k >> 2].form[k & 3];
        g[k] = out[k >> 2].g[k & 3];
        ok[k] = out[k >> 2].ok[k & 3];
    }
}

bool ism_dual_over_many(const ism_dual_model *m, const double (*lo)[3], const double (*hi)[3],
                        size_t n, bool every, ism_interval *v2, ism_ivgrad *g, bool *ok)
{
    ism_interval dx[ISM_IVGRAD_BATCH][3];
    lane_out out[(ISM_IVGRAD_BATCH + 3) / 4]; /* many_groups: a group of 4 per started 4 */
    if (n == 0 || n > ISM_IVGRAD_BATCH)
        return false;
    for (size_t k = 0; k < n; k++)
        round_centre(&m[k], lo[k], hi[k], dx[k]);
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2())
        many_avx2(m, (const ism_interval (*)[3])dx, n, every, out);
    else
#endif
        many_base(m, (const ism_interval (*)[3])dx, n, every, out);
    for (size_t k = 0; k < n; k++) {
        v2[k] = out[k / 4].form[k % 4];
        g[k] = out[k / 4].g[k % 4];
        ok[k] = out[k / 4].ok[k % 4];
    }
    return true;
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

/* Proofs with at most this many sub-boxes left open by their node's model take those
 * sub-boxes' models two at once (sub_models), the others one by one. Two models in lanes (2
 * boxes' jets and 2 centres', one group of 4) cost ~5.3K instructions on the torus against
 * ~4.2K for one model alone (its box's jet ~2.9K, its centre's gradient ~1.1K), so a pair
 * pays only when both are used, and a failing proof stops at its first failing sub-box.
 * Torus at 1e-2 (the same counts at 3e-3 and 1e-3), emptiness proofs by sub-boxes left open:
 * 2 open, 32 proofs, all held; 3 open, 24 held, 8 failed at the first; 4 open, 48 failed at
 * the first, 16 at the second; 1 open, 8 held, 16 failed. Pairs wherever two are left:
 * 15,644K -> 15,636K; pairs up to 2 open: 15,583K; up to 3: 15,508K (callgrind,
 * ism_mesh_surface, bench_error mesh torus 0.0141 10; 3e-3 35,121K -> 34,984K). */
#define PAIRED_OPEN 3

bool ism_dual_taylor_pair(const ism_tape *t, ism_ivjet_ws *jet, const double (*lo)[3],
                          const double (*hi)[3], ism_dual_model *m, bool *ok)
{
    ism_interval box[4][3]; /* the two boxes, then their centres */
    ism_ivjet j[4];
    for (int k = 0; k < 2; k++)
        for (int a = 0; a < 3; a++) {
            m[k].c[a] = centre_along(lo[k], hi[k], a);
            box[k][a] = iv(lo[k][a], hi[k][a]);
            box[2 + k][a] = iv(m[k].c[a], m[k].c[a]);
        }
    /* no min, max or abs: neither evaluation has a kink, so ism_dual_taylor's answer is
       true; a jet's value and first partials are the gradient pass's (interval_jet.h), so
       the centre's jet gives m[k].at */
    if (ism_tape_has_kink(t) ||
        !ism_eval_interval_jet_lanes(t, jet, (const ism_interval (*)[3])box, 4, j))
        return false;
    for (int k = 0; k < 2; k++) {
        m[k].box = j[k];
        m[k].at = (ism_ivgrad){j[2 + k].v, {j[2 + k].d[0], j[2 + k].d[1], j[2 + k].d[2]}};
        ok[k] = true;
    }
    return true;
}

/* ism_dual_taylor on sub-box sub[0] of lo..hi halved at mid, and on sub[1] too when want >=
 * 2 and ism_dual_taylor_pair takes t: sub-box sub[k] into sl[k]..sh[k], its model into m[k]
 * and ism_dual_taylor's answer into ok[k], bit for bit. Returns how many were made (1 or
 * 2); counts no evaluation (prove counts each model it reads, as ism_dual_taylor would). */
static int sub_models(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                      const double *mid, const double hi[3], const int *sub, int want,
                      double (*sl)[3], double (*sh)[3], ism_dual_model *m, bool *ok)
{
    sub_box(lo, mid, hi, sub[0], sl[0], sh[0]);
    if (want >= 2) {
        sub_box(lo, mid, hi, sub[1], sl[1], sh[1]);
        if (ism_dual_taylor_pair(t, jet, (const double (*)[3])sl, (const double (*)[3])sh, m,
                                 ok))
            return 2;
    }
    uint64_t counted = 0;
    ok[0] = ism_dual_taylor(t, jet, sl[0], sh[0], &m[0], &counted);
    return 1;
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
    lane_out se[2];
    sub_encls(m, lo, mid, hi, false, se);
    for (int k = 0; k < 8; k++) {
        const lane_out *o = &se[k >> 2];
        v = verdict_from(o->form[k & 3], o->ok[k & 3], &o->g[k & 3], d, &encl);
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
    double sl[2][3], sh[2][3];
    ism_dual_model sm[2];
    bool sok[2];
    for (int i = 0, q = 0, made = 0; v >= 0 && i < nopen; i++, q++) {
        if (q == made) { /* the next sub-box's model, or the next two's */
            made = sub_models(t, jet, lo, mid, hi, open + i,
                              nopen <= PAIRED_OPEN ? nopen - i : 1, sl, sh, sm, sok);
            q = 0;
        }
        *intervals += 2; /* as ism_dual_taylor counts the model it makes */
        v = sok[q] ? prove(t, jet, &sm[q], sl[q], NULL, sh[q], d, halvings - 1, false, NULL,
                           intervals)
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
