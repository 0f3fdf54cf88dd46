/* dual_classify.c — the dual mesher's leaf tests (dual_classify.h): a node's corners, its
 * natural interval and Taylor model (dual_cert.c), the emptiness and one-graph proofs, the
 * crease kinds (dual_crease.c), the corner cases (a sheet through a lattice point, a cap
 * through a face at depth.max), and sag_split, which splits a node whose chords would sag
 * past E before it makes a vertex; the centre's foot by Newton; a split's children classified
 * together (ism_dual_kid_kinds) and the request's box's check on a leaf (ism_dual_leaf_kind). */
#include "core/octree/dual_classify.h"
#include "core/eval/interval_jet.h"
#include "core/octree/cell_cache.h"
#include "core/octree/corners.h"
#include "core/octree/dual_box.h"
#include "core/octree/dual_crease.h"
#include "core/octree/edge_roots.h"
#include "core/octree/graph_cert.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"
#include "core/util/bits.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps moving a leaf's mean edge root onto f = 0, stopping once a step is below
 * NEWTON_STOP of the leaf's size (far below any bound a request may ask for). */
#define NEWTON_STEPS 6
#define NEWTON_STOP 1e-9
/* Sub-boxes tried by the proofs below a node's own enclosure, each first by the node's
 * Taylor model (no evaluation), then by its own (two). Measured on the torus at 1e-2 /
 * 3e-3 / 1e-3 (instructions, raw triangles): no halving 70.4M / 120.2M / 293.6M, 3,344 /
 * 7,096 / 19,484; one 75.3M / 117.9M / 329.9M, 3,280 / 5,968 / 20,464; two 79.1M / 120.4M /
 * 300.5M, 3,280 / 6,128 / 19,264. One: the fewest triangles at 3e-3 for about the cost. */
#define CERT_HALVINGS 1
/* A crease leaf this many E across or less is judged by the measurement alone (crease_kind,
 * dual_crease.h's `small`): the primal path's rule for such nodes (cell_error.c, 4 E). */
#define CREASE_MEASURED_CELLS 4.0
/* A node with both signs at its corners is split without its proofs when the surface at its
 * centre's foot bends so fast (largest principal curvature k) that a chord as long as the
 * node (h) sags this many times the room a leaf's chords have, E + the straddle shift:
 * k h² / 8 > SAG_SPLIT (E + shift). Such a node is split anyway — as not plain, or as a
 * leaf whose triangles miss E — after proofs, a vertex, triangles and a measure it did not
 * need. Measured, k h² / 8 / (E + shift) of every two-signed node the mesher made (bench
 * torus r 0.3 and sphere r 1, E 0.0141 / 3.57e-3 / 1e-3): leaves kept at most 1.93 (torus
 * 1e-3, 40 of 7,624 depth-5 leaves; every other run 0.55-0.66); nodes split from 2.18 (the
 * torus's depth-3 cells at 0.0141, 0.375 wide against its tube's radius 0.3) up. A leaf
 * the rule splits that the measure would have kept costs triangles, never the bound (the
 * measure still judges every leaf kept). Whole runs (callgrind, isomesh --threads 1):
 * torus 3e-3 113.5M -> 91.7M, same triangle count; the box-cut presets at E/3 up to 2.4%
 * fewer triangles (the rounds' order changes which coarse leaves a miss splits). */
#define SAG_SPLIT 2.0
/* ... and where the surface bends one way (both principal curvatures of one sign, the least
 * k2 in magnitude), every chord through the foot, in any direction, sags at least k2 L² / 8:
 * a node is split at once when k2 h² / 8 > SAG_ROUND (E + shift), the sag of a chord its
 * size beyond the room by a margin (vertices of neighbouring leaves are about a cell apart,
 * some nearer). SAG_SPLIT, judged by the largest curvature for saddles too, keeps the
 * sphere's nodes that every measure splits: bench sphere r 1 in ±1.5 (k2 = k1), level-3
 * nodes at E 0.0141 have k2 h² / 8 / (E + shift) = 0.66 (104 of 128 kept), level 3 at
 * 7.14e-3 1.30 and level 4 at 1.3e-3 1.78 (each a whole round of vertices, fans and measures
 * made, every leaf then split). Whole runs (bench_error mesh S E 10, callgrind, ism_mesh_surface):
 * sphere 7.14e-3 10.61M -> 9.10M, 1.3e-3 42.40M -> 38.70M, the same triangle counts and max
 * centroid errors; 0.0141 and the torus at 0.0141 / 3.57e-3 / 1.19e-3 unchanged (its k2 h² / 8
 * stays below; SAG_ROUND 1.0 and 1.5 measured the same but for 1.5 at 7.14e-3). Why 1.2, not
 * a margin that only splits nodes the measure would: the ratio alone cannot tell them apart.
 * The sphere's level 3 at 7.14e-3 (1.30) had every leaf split, its level 4 at 1.73e-3 (1.34)
 * kept some, so no margin catches the first and spares the second; 1.2 sits under 1.30 and
 * takes that cost. Rule on against off (SAG_ROUND 1e300), isomesh --stats --threads 1,
 * every preset at the default E (1e-3 x diagonal) and E/3 in its own box, and the convex
 * and one-way presets (sphere, ellipsoid, tooth, two-spheres, blob-pair, sphere-pair-param,
 * spindle-cyclide, tanglecube, pretzel-genus2, torus, linked-tori, heart) at 3, 1, 1/3 and
 * 1/10 E in the own, 1e-3 and irr boxes: triangles changed in 16 of those 144 runs — sphere
 * E/3 3,996 / 4,002 / 4,004 -> 4,188 (+4.6-4.8%: the level-5 mesh; max centroid 1.68e-3 ->
 * 0.91e-3), tanglecube E/3 +0.2% (and +0.02% at E/10 irr), ellipsoid E/10 -0.04 to -0.17%,
 * blob-pair E/3 and E/10 -0.1 to -0.7% — and in none of the other presets' own-box runs
 * (the box-cut ones bend both ways; tooth, two-spheres, linked-tori, sphere-pair-param,
 * spindle-cyclide and heart take the primal path); mesh_identity.py: 1 of its 217 runs
 * (sphere irr, --quality good). Every dual run within E. Instructions
 * (callgrind --toggle-collect=ism_mesh_surface, own box): sphere E 11.14M -> 9.24M (-17%),
 * E/3 39.66M -> 37.00M (-6.7%), blob-pair E/3 89.79M -> 89.20M, E/10 204.52M -> 193.23M
 * (-5.5%), ellipsoid E/10 102.84M -> 102.26M, tanglecube E/3 336.18M -> 335.36M. */
#define SAG_ROUND 1.2

/* f kept from 0 along edge c0 -> c1 (axis a, length h) by the mean-value form from both
 * ends (g: ∇f enclosed over the node, so over the edge). */
static bool edge_free(const dnode *n, const ism_ivgrad *g, int a, int c0, int c1, double h)
{
    double lo = g->d[a].lo * h, hi = g->d[a].hi * h;
    double low = max_of(n->f[c0] + min_of(0, lo), n->f[c1] - max_of(0, hi));
    double high = min_of(n->f[c0] + max_of(0, hi), n->f[c1] - min_of(0, lo));
    return low > 0 || high < 0;
}

/* Where surface leaf n lies on the request's box: -1 when f changes sign between its
 * corners on a face of the box (the box cuts the surface), 1 when f is proven free of 0 on
 * every such face, 0 when neither is known (split it). */
int ism_dual_box_faces_clear(dual *d, worker *w, const dnode *n, const corner_view *v)
{
    int32_t step = ism_grid_cell_steps(&d->g, n->level), last = (int32_t)1 << d->g.depth;
    for (int a = 0; a < 3; a++)
        for (int side = 0; side < 2; side++) {
            if (n->o.v[a] != (side ? last - step : 0))
                continue;
            int neg = 0;
            for (int c = 0; c < 8; c++)
                neg += ((c >> a & 1) == side) && n->f[c] < 0;
            if (neg != 0 && neg != 4)
                return -1;
            double lo[3], hi[3];
            memcpy(lo, v->p[0], sizeof lo);
            memcpy(hi, v->p[7], sizeof hi);
            lo[a] = hi[a] = side ? v->p[7][a] : v->p[0][a];
            /* the node's model holds over its face; else the face's own */
            ism_dual_model fm;
            const ism_tape *t = w->s.tape;
            uint64_t *count = &w->s.n_interval;
            if (!(v->have_model &&
                  ism_dual_free(t, w->jet, &v->model, lo, hi, CERT_HALVINGS, count)) &&
                !(ism_dual_taylor(t, w->jet, lo, hi, &fm, count) &&
                  ism_dual_free(t, w->jet, &fm, lo, hi, CERT_HALVINGS, count)))
                return 0;
        }
    return 1;
}

_Static_assert(ISM_PAIR_MEMO_BITS >= 6, "the pair memo: at least 64 slots (whole words of bits)");

/* The search for a root pair on edge c0 -> c1 of node n (ends of one sign): 0 when there
 * is none. A function of the edge's two lattice points alone (f on the full tape between
 * their coordinates), and up to four nodes of a level share an edge (torus at 1e-2: 432
 * searches of 11.7K instructions each, 5.1M of 68M), so the answer is kept per thread under
 * the ends' lattice keys (cell_cache.h ism_pair_entry): a hit answers what the search
 * would, bit for bit. */
static int edge_root_pair(dual *d, worker *w, const dnode *n, const corner_view *v, int c0,
                          int c1)
{
    const ism_poly_options *o = d->o;
    int32_t step = ism_grid_cell_steps(&d->g, n->level), q0[3], q1[3];
    for (int a = 0; a < 3; a++) {
        q0[a] = n->o.v[a] + ((c0 >> a) & 1) * step;
        q1[a] = n->o.v[a] + ((c1 >> a) & 1) * step;
    }
    uint64_t k0 = ism_lattice_key(q0) + 1, k1 = ism_lattice_key(q1) + 1;
    if (!w->pairs_tried) {
        w->pairs_tried = true;
        /* NULL: every search made. The entries are not cleared, only their bits (512
         * bytes for 128 KB: calloc clearing it cost the torus at E 0.0141 99K of 17.1M
         * instructions, bench_error under callgrind) */
        w->pairs = ism_bits_table((size_t)1 << ISM_PAIR_MEMO_BITS, sizeof *w->pairs,
                                  &w->pairs_filled);
    }
    ism_pair_entry none = {0}, *m = w->pairs ? ism_pair_slot(w->pairs, k0, k1) : &none;
    size_t i = w->pairs ? (size_t)(m - w->pairs) : 0;
    if (w->pairs) {
        if (ism_bit_test(w->pairs_filled, i) && m->a == k0 && m->b == k1)
            return m->found;
        ism_bit_set(w->pairs_filled, i);
    }
    int found = 0;
    double t = 0;
    if (ism_segment_may_reach(&w->s, v->p[c0], v->p[c1], o->double_root_eps)) {
        ism_root_params prm = {o->gradient_test, o->double_root_eps, o->double_root_iters,
                               false};
        found = ism_double_root_search(&w->s, &prm, v->p[c0], v->p[c1], n->f[c0], n->f[c1],
                                       &t);
    }
    *m = (ism_pair_entry){k0, k1, t, found};
    return found;
}

/* No root on an edge whose ends share a sign: f monotone along its axis or kept from 0 by
 * the mean-value form (proofs), else the primal polygons' edge test (plot_test.c): the
 * paper's same-sheet test (eq. 1) on the ends' gradients, then its double-root search. */
static bool same_sign_edge_clear(dual *d, worker *w, const dnode *n, const corner_view *v,
                                 int e, int c0, int c1)
{
    int a = e / 4;
    if (v->have_g && (v->monotone >> a & 1 ||
                      edge_free(n, &v->g, a, c0, c1, v->p[c1][a] - v->p[c0][a])))
        return true;
    if (ism_dot3(v->n[c0], v->n[c1]) > d->o->gradient_test)
        return true;
    return edge_root_pair(d, w, n, v, c0, c1) == 0;
}

/* Bit c: f < 0 at node n's corner c. */
static unsigned corner_signs(const dnode *n)
{
    unsigned signs = 0;
#pragma GCC unroll 8
    for (int c = 0; c < 8; c++)
        signs |= (unsigned)(n->f[c] < 0) << c;
    return signs;
}

/* Crossed edges on every face 0 or 2 (one curve): from the corners' signs alone. */
static bool plain_faces(const dnode *n)
{
    return ism_dual_faces_plain(ism_edges_across(corner_signs(n)));
}

/* Crossed edges on every face 0 or 2 (one curve), and no root on an edge whose ends share
 * a sign (the faces first: signs alone; then the edges in ism_cube_edges' order). */
static bool plain_edges(dual *d, worker *w, const dnode *n, const corner_view *v)
{
    unsigned crossed = ism_edges_across(corner_signs(n));
    if (!ism_dual_faces_plain(crossed))
        return false;
    for (unsigned same = ~crossed & 0xfffu; same; same &= same - 1) {
        int e = __builtin_ctz(same);
        if (!same_sign_edge_clear(d, w, n, v, e, d->ec0[e], d->ec1[e]))
            return false;
    }
    return true;
}

/* f kept from 0 over the node by the mean-value form from each corner: f(x) = f(c) +
 * ∇f(ξ)·(x − c) with ∇f in its enclosure g; the 8 enclosures intersected. The natural
 * interval of a polynomial like the torus's loses to its own dependencies (width ~0.07 in a
 * cell 0.003 across, 0.02 off the surface, where f is 0.05): cells beside the surface would
 * be split to the last level. */
static bool mean_value_free(const dnode *n, const ism_ivgrad *g, const double lo[3],
                            const double hi[3])
{
    return ism_dual_mean_value_sign(n->f, g, lo, hi) != 0;
}

/* Does v->g, an enclosure of f and ∇f over node n (the natural one, or the Taylor model's),
 * leave the node open? Of one sign (v->neg 0 or 8): neither it nor the mean-value form from
 * the corners keeps f from 0; mixed: it shows no graph. classify_tail's tests before its
 * first tighten, in one place: ism_dual_pre_models picks the nodes that fail them
 * (tail_tightens), and the tail then skips them under v->pre_model. */
static bool natural_open(const dnode *n, const corner_view *v)
{
    if (v->neg != 0 && v->neg != 8)
        return !ism_graph_from_enclosure(&v->g);
    return !ism_dual_encl_free(&v->g) && !mean_value_free(n, &v->g, v->p[0], v->p[7]);
}

/* natural_open on the natural enclosure in v->g, read from ism_dual_pre_models' answer when
 * it took one (pre_open_known: once, as the tail asks once before any tighten; cleared
 * too where v->g is replaced, so it never speaks of another enclosure). */
static bool natural_open_once(const dnode *n, corner_view *v)
{
    if (v->pre_open_known) {
        v->pre_open_known = false;
        return v->pre_open;
    }
    return natural_open(n, v);
}

/* What node i is: empty (proven free of f = 0), a surface leaf, or to be split. */

/* Any two corner gradients within acos(flat_normal): the paper's one-sheet test, which the
 * primal polygons use too (plot_test.c). */
static bool normals_agree(const double (*n)[3], double cos_min)
{
#pragma GCC unroll 8 /* 28 pairs in a row (sphere at E 7.14e-3: the loops' steps ~0.1M) */
    for (int i = 0; i < 8; i++)
#pragma GCC unroll 8
        for (int j = i + 1; j < 8; j++)
            if (!(ism_dot3(n[i], n[j]) >= cos_min))
                return false;
    return true;
}

/* The node's Taylor model (dual_cert.h) into v->model: v->have_model. */
static bool take_model(worker *w, corner_view *v)
{
    if (v->pre_model) { /* made beforehand (ism_dual_pre_models), counted now */
        v->pre_model = false;
        v->have_model = v->pre_ok;
        w->s.n_interval += 2;
    } else
        v->have_model = ism_dual_taylor(w->s.tape, w->jet, v->p[0], v->p[7], &v->model,
                                        &w->s.n_interval);
    return v->have_model;
}

/* The model's second-order form over the node (ism_dual_second_order), from
 * ism_dual_pre_models' lanes when it took them. */
static ism_interval node_form(const corner_view *v)
{
    return v->pre_forms ? v->pre_v2 : ism_dual_second_order(&v->model, v->p[0], v->p[7]);
}

/* The model's enclosure of the node into *g (ism_dual_over, or ism_dual_over_v2 with its
 * form v2), from ism_dual_pre_models' lanes when it took them (used once: cleared). Beware: a
 * lane ism_dual_over_many skipped (every false: its group's four forms keep f from 0) reads
 * here as pre_over_ok false, a failed enclosure, not a missing one. Exact today only because
 * no tail reads the enclosure of a node with corners of one sign before its form decides
 * (empty_proven returns on the same form test first); a new reader of that enclosure for such
 * a node must make ism_dual_over_many tell skipped lanes apart (or take every = true), or a
 * skipped group becomes "tighten failed" and the mesh changes. */
static bool node_over(corner_view *v, const ism_interval *v2, ism_ivgrad *g)
{
    if (v->pre_forms) {
        v->pre_forms = false;
        *g = v->pre_over;
        return v->pre_over_ok;
    }
    return v2 ? ism_dual_over_v2(&v->model, v->p[0], v->p[7], *v2, g)
              : ism_dual_over(&v->model, v->p[0], v->p[7], g);
}

/* v->g (the node's natural enclosure) replaced by the Taylor model's (dual_cert.h), the
 * model kept in v; false when that cannot be had (g kept). */
static bool tighten(worker *w, corner_view *v)
{
    ism_ivgrad g;
    if (!take_model(w, v) || !node_over(v, NULL, &g))
        return false;
    v->g = g;
    v->pre_open_known = false; /* that answer was about the natural enclosure */
    return true;
}

/* The proof on the sub-boxes of node n's box (empty when d is NULL, else one graph along
 * d: ism_dual_prove_halves, with v->model), halved at its lattice centre so each sub-box is
 * a child's box; the children it shows free of f = 0 are kept in v->free_kids, for a split. */
static bool prove_on_halves(dual *d, worker *w, const dnode *n, corner_view *v,
                            const double *dir, bool open_whole)
{
    double mid[3];
    const double *at = NULL; /* no children (max_depth): halved at the centre */
    if (n->level < d->o->max_depth) {
        for (int a = 0; a < 3; a++)
            mid[a] = ism_grid_coord(&d->g, a,
                                    n->o.v[a] + ism_grid_cell_steps(&d->g, n->level + 1));
        at = mid;
    }
    return ism_dual_prove_halves(w->s.tape, w->jet, &v->model, v->p[0], at, v->p[7], dir,
                                 CERT_HALVINGS, open_whole, &v->free_kids, &w->s.n_interval);
}

/* f free of 0 over node n, whose corners share a sign (v->g: its natural enclosure): by the
 * enclosure or the mean-value form from the corners (natural_open; skipped under pre_model,
 * ism_dual_pre_models having seen them fail), then the Taylor model's second-order form
 * alone, then the model's enclosure and the mean-value form on it, then the sub-boxes. */
static bool empty_proven(dual *d, worker *w, const dnode *n, corner_view *v)
{
    if (!v->pre_model && !natural_open_once(n, v))
        return true;
    if (!take_model(w, v))
        return false;
    /* tighten's enclosure, its cheapest part first (dual_cert.c verdict_of's order): when
     * the second-order form alone keeps f from 0, so does the enclosure's value (its meet
     * with two more forms), and its ∇f bounds are not needed; nothing reads v->g of an empty
     * node. Torus at 1e-2: ~200 of ~500 models. */
    ism_interval v2 = node_form(v);
    if (v2.lo > 0 || v2.hi < 0)
        return true;
    ism_ivgrad g;
    if (!node_over(v, &v2, &g))
        return false;
    v->g = g;
    v->pre_open_known = false; /* as in tighten */
    if (!natural_open(n, v))
        return true;
    /* v->g is the model's enclosure of the whole box, just seen to hold 0 */
    return prove_on_halves(d, w, n, v, NULL, true);
}

/* f >= 0 over node n, whose corners are all >= 0 and one of them, c, exactly 0 (a sheet
 * through a lattice point, tangent there to a lattice plane as the sphere of radius 1 is at
 * (1, 0, 0) in the box +-2): with "f >= 0 is outside" the node is empty, but no enclosure
 * shows it (f is 0 at c, and every bound is pushed an ulp outward, so f's lower bound is
 * below 0 however tight the form). Taylor's theorem from c instead, in signs: with
 * w_a = s_a (x − c)_a >= 0 (s_a = +1 when c is on the node's low side along a),
 * f(x) = f(c) + Σ ∇f(c)_a s_a w_a + ½ Σ_ab s_a s_b H_ab(ξ) w_a w_b, ξ in the node;
 * each linear term is >= 0 when ∇f(c)_a s_a >= 0, and the quadratic one when every
 * s_a s_b H_ab's enclosure (m: the node's Taylor model) has its lower bound, minus the
 * negative parts t_ab (an ulp below 0 where H_ab is 0 at the node's face) beside it, >= 0:
 * w_a w_b <= (w_a² + w_b²) / 2 gives ½ Σ_a w_a² (H_aa − Σ_{b≠a} t_ab). The sum of
 * the t_ab is doubled against its own rounding. ∇f(c) is the sampled gradient, taken as
 * exact as the sampled 0 at c is (corner signs are samples everywhere in this file).
 *
 * The same expansion proves a node empty from a corner where f(c) > 0 is tiny and some
 * ∇f(c)_a s_a < 0 but small: a sheet passing a corner at a critical value of one coordinate
 * (tanglecube's z⁴ − 5 z² at z = √2.5, box ±3 moved by 0.37 / −0.23 / 0.41 of a depth-9
 * cell, E = 3e-3: f(c) = 1.44e-5, ∂f/∂z = −3.2e-3, min f in the node 1.41e-5; the enclosures
 * round the centre are 8.6e-5 wide, so the node was split to depth.max and the dual mesh
 * declined, not_plain, in that box only). There each axis adds at least the minimum of
 * G_a w + ½ D_a w² over w in [0, h_a], with G_a the lower bound of s_a ∇f(c)_a — from the
 * model, ∇f(centre) + H (c − centre), not a sample — and D_a = H_aa − 2 Σ_{b≠a} t_ab; the
 * node is empty when f(c) plus these minima stays above CORNER_ROUNDING of their sizes. */
/* The sums above are of a few products in plain floating point (the enclosures themselves
 * are rounded outward): their error is ~1e-15 of the terms' sizes, kept far below this. The
 * d9 cells of that tanglecube box have f(c) = 3.4e-4 and a dip of 3.3e-4 along z (min f in
 * the node 1.41e-5): a margin of half f(c) did not prove them. */
#define CORNER_ROUNDING 1e-9
/* touch_empty's numbers that depend on a corner only through its side along each axis,
 * taken once for the node where they were taken for each corner (72 calls ~4.6K instructions
 * each on the torus at 1e-2, every one failing): each the same operations on the same
 * operands as before, so the same bits. A corner c's point is the box's (bit a of c: p[7][a],
 * else p[0][a]), as every corner_view's builder makes it (split_task's 27 points, the root's
 * lattice corners). */
typedef struct touch_terms {
    /* d[a][m]: D_a = H_aa − 2 Σ_{b≠a} t_ab, bit i of m set when the corner's side along a
     * is its side along the i-th other axis (s_a s_b > 0: t_ab from H_ab's lower bound) */
    double d[3][4];
    /* lo[a][b][k], hi[a][b][k]: H_ab (x − c)_b's bounds with x_b on side k along b */
    double lo[3][3][2], hi[3][3][2];
    double w[3]; /* the node's sides */
} touch_terms;

/* The other two axes than a, in ascending order. */
static void other_axes(int a, int *b1, int *b2)
{
    *b1 = a == 0 ? 1 : 0;
    *b2 = a == 2 ? 1 : 2;
}

static void touch_terms_of(const corner_view *v, touch_terms *tt)
{
    const ism_interval *h = v->model.box.h;
    for (int a = 0; a < 3; a++) {
        int b1, b2;
        other_axes(a, &b1, &b2);
        ism_interval h1 = h[ism_dual_hess_at(a, b1)], h2 = h[ism_dual_hess_at(a, b2)];
        for (int m = 0; m < 4; m++) {
            double t = 0;
            t += m & 1 ? max_of(0, -h1.lo) : max_of(0, h1.hi);
            t += m & 2 ? max_of(0, -h2.lo) : max_of(0, h2.hi);
            tt->d[a][m] = h[ism_dual_hess_at(a, a)].lo - 2 * t;
        }
        for (int b = 0; b < 3; b++) {
            ism_interval hab = h[ism_dual_hess_at(a, b)];
            for (int k = 0; k < 2; k++) {
                double off = v->p[k ? 7 : 0][b] - v->model.c[b];
                tt->lo[a][b][k] = off >= 0 ? hab.lo * off : hab.hi * off;
                tt->hi[a][b][k] = off >= 0 ? hab.hi * off : hab.lo * off;
            }
        }
        tt->w[a] = fabs(v->p[7][a] - v->p[0][a]);
    }
}

/* The least f may gain along axis a from corner c, whose f is f > 0 (G_a w + ½ D_a w² over
 * w in [0, h_a]; D_a = d); NaN or infinite when that is not known. */
static double touch_least(const corner_view *v, const touch_terms *tt, int c, int a, double d)
{
    /* G_a: s_a ∇f(c)_a's lower bound, ∇f(c) in ∇f(centre) + H (c − centre) */
    ism_interval g = v->model.at.d[a];
    for (int b = 0; b < 3; b++) {
        g.lo += tt->lo[a][b][c >> b & 1];
        g.hi += tt->hi[a][b][c >> b & 1];
    }
    double g_a = !(c >> a & 1) ? g.lo : -g.hi, w = tt->w[a];
    double at_w = g_a * w + 0.5 * d * w * w, least = fmin(0, at_w);
    if (g_a < 0 && d > 0 && -g_a / d < w)
        least = -g_a * g_a / (2 * d); /* the parabola's vertex inside [0, w] */
    return least;
}

static bool touch_empty(const dnode *n, const corner_view *v)
{
    if (!v->have_model)
        return false;
    const ism_interval *h = v->model.box.h;
    for (int e = 0; e < 6; e++)
        if (!(h[e].lo <= h[e].hi))
            return false; /* a NaN bound: no corner's expansion holds */
    touch_terms tt;
    bool made = false;
    for (int c = 0; c < 8; c++) {
        if (!(n->f[c] >= 0))
            continue;
        if (!made) {
            touch_terms_of(v, &tt);
            made = true;
        }
        bool ok = true;
        for (int a = 0; a < 3; a++) /* s_a = −1 on the corner's upper side along a */
            ok = ok && (n->f[c] != 0 || v->n[c][a] * ((c >> a & 1) ? -1.0 : 1.0) >= 0);
        double low = 0; /* the sum of the axes' minima (f(c) > 0) */
        for (int a = 0; a < 3 && ok; a++) {
            int b1, b2;
            other_axes(a, &b1, &b2);
            int side = c >> a & 1;
            double d_a = tt.d[a][((c >> b1 & 1) == side) | ((c >> b2 & 1) == side) << 1];
            if (n->f[c] == 0) {
                ok = d_a >= 0;
                continue;
            }
            double least = touch_least(v, &tt, c, a, d_a);
            ok = isfinite(least);
            low += least;
        }
        if (ok && (n->f[c] == 0 || n->f[c] + low > CORNER_ROUNDING * (n->f[c] - low)))
            return true;
    }
    return false;
}

/* The slab widths face_cap tries, as shares of the node's side: the first that proves it. */
#define CAP_SLABS 3

/* At depth.max, a node whose corners share a sign and which is not proven empty: is every
 * zero of f in it a cap of a sheet that crosses one of its faces, at most min(E, side / 2)
 * deep? Proven when, for a slab of depth δ along that face, f has no zero in the rest of
 * the node (so f keeps the corners' sign there) and every line across the slab meets f = 0
 * at most once (ism_dual_graph_along): each zero then lies on a line from a point of the face
 * where f has the other sign, within δ of it. The sheet crosses the face; the leaf beyond it
 * holds the rest, and that leaf's own corner signs already pass over the crossing curve on
 * their shared face (no lattice point inside it): the dual mesh misses the cap, no more —
 * δ ≤ E from the mesh there. Why: a convex fold whose extreme point lies within ~h² / 4R
 * beyond a lattice plane (R its radius of curvature; h the finest cell) pokes through a face
 * between the face's lattice points at every depth. Kummer's tropes fold with R 0.1 between
 * two nodes (1.241, 0, −0.79 between 1.207, ±0.207, −0.707): kummer-16-nodes in its own box
 * declined not_plain at 1e-2 and 3e-3. Only at depth.max, where the node would decline: no
 * mesh the dual mesher made before changes. */
static bool face_cap(dual *d, worker *w, corner_view *v)
{
    if (!v->have_model && !tighten(w, v))
        return false;
    double h = v->p[7][0] - v->p[0][0];
    for (int k = 1; k <= CAP_SLABS; k++) {
        double slab = ldexp(h, -k);
        if (!(slab <= d->o->max_error))
            continue;
        for (int a = 0; a < 3; a++)
            for (int side = 0; side < 2; side++) {
                double lo[3], hi[3], slo[3], shi[3], dir[3] = {0, 0, 0};
                memcpy(lo, v->p[0], sizeof lo);
                memcpy(hi, v->p[7], sizeof hi);
                memcpy(slo, lo, sizeof slo);
                memcpy(shi, hi, sizeof shi);
                if (side) { /* the face hi[a]: the rest below it */
                    hi[a] -= slab;
                    slo[a] = hi[a];
                } else {
                    lo[a] += slab;
                    shi[a] = lo[a];
                }
                if (!ism_dual_free(w->s.tape, w->jet, &v->model, lo, hi, CERT_HALVINGS,
                                   &w->s.n_interval))
                    continue;
                for (int sign = -1; sign <= 1; sign += 2) {
                    dir[a] = sign;
                    if (ism_dual_graph_along(w->s.tape, w->jet, &v->model, slo, shi, dir,
                                             CERT_HALVINGS, &w->s.n_interval))
                        return true;
                }
            }
    }
    return false;
}

/* One graph along the corner gradients' mean (the direction the sheet in the node faces)
 * wherever f may vanish in the node's sub-boxes (the node's own enclosure failed). */
static bool graph_on_sub_boxes(dual *d, worker *w, const dnode *n, corner_view *v)
{
    double m[3] = {0, 0, 0};
    for (int c = 0; c < 8; c++)
        for (int a = 0; a < 3; a++)
            m[a] += v->n[c][a];
    if (!(ism_dot3(m, m) > 0))
        return false;
    return prove_on_halves(d, w, n, v, m, false);
}

/* What a node with f's crease kink in its box is (dual_crease.h): empty, a leaf with its
 * vertex on the crease or a plain leaf of one branch (each with plain edges), or to split
 * (v->kinked). */
static int crease_kind(dual *d, worker *w, dnode *n, corner_view *v)
{
    bool small = ism_grid_cell_size(&d->g, n->level) <= CREASE_MEASURED_CELLS * d->o->max_error;
    bool last = n->level >= d->o->max_depth;
    const double (*p)[3] = (const double (*)[3])v->p;
    enum ism_crease_node k = ism_dual_crease_node(&w->s, w->jet, w->force, p, n->f,
                                                  d->o->flat_normal, small, last);
    int kind = k == ISM_CREASE_EMPTY    ? DN_EMPTY
               : k == ISM_CREASE_VERTEX ? DN_CREASE
               : k == ISM_CREASE_SMOOTH ? DN_SURF
               : k == ISM_CREASE_PAIR   ? DN_PAIR
                                        : DN_INNER;
    /* a leaf with the kink at most 4 E across is judged by the measurement alone (as
     * cell_error.c judges the primal polygons'): the crease's wedge pokes through the
     * same-sign edges beside it at every level (two roots), so splitting for them went on
     * to depth.max. Its faces still hold one crossing curve each (two on a face made
     * Barth's sextic at 1e-2 non-manifold along 4 edges by the crease). */
    if (has_sheet(kind) && kind != DN_PAIR &&
        (small ? !plain_faces(n) : !plain_edges(d, w, n, v)))
        /* at depth.max a crease leaf may have a face crossed four times by two branches'
           curves (the ridge along its diagonal): its neighbour there is a pair leaf */
        kind = kind == DN_CREASE && small && last &&
                       ism_dual_crease_branch_faces(&w->s, p, n->f) >= 0
                   ? DN_CREASE
                   : DN_INNER;
    /* at depth.max a small leaf with plain faces whose crease point Newton missed (more than
       half a cell outside, or not converging) is a plain leaf: the measurement judges it */
    if (kind == DN_INNER && k == ISM_CREASE_SPLIT && small && last && plain_faces(n))
        kind = DN_SURF;
    v->kinked = kind == DN_INNER;
    return kind;
}

/* Does f fall from its zero at corner c into the node along each of the node's three edges
 * from c (the unit gradient's component along each, taken into the node, below 0)? Then the
 * sheet through c crosses the node transversally, cutting off the corner: the node's three
 * crossed edges (the other seven corners < 0, 0 counting as > 0) have their roots at c and
 * the node is a plain leaf whose vertex is c, the nodes round c having theirs elsewhere
 * (Barth's sextic through the lattice point (1/2, 1/2, 1/2) with ∇f along (1, 1, 1), the
 * sphere r = 1.5 through (1.4, -0.2, -0.5) in the box ±1.6: at every level). Not so where
 * the sheet is tangent to a lattice line through c (tooth at (0, 1, 1)) or ∇f vanishes
 * there (a cone's apex). */
static bool zero_corner_transverse(const corner_view *v, int c)
{
    bool down = true;
    for (int a = 0; a < 3; a++) {
        double into = (c >> a & 1) ? -v->n[c][a] : v->n[c][a];
        down &= into < 0;
    }
    return down;
}

/* What one Newton step did (newton_step). */
enum { STEP_FAIL, STEP_GO, STEP_STOP };

/* One Newton step of m along ∇f towards f = 0 (f and g = ∇f at m): STEP_FAIL without
 * moving m when ∇f vanishes or f, ∇f are not finite; else m moved, and STEP_STOP once the
 * step was below NEWTON_STOP of size. ism_dual_newton_onto and ism_dual_newton_lanes both
 * step so. */
static inline __attribute__((always_inline)) int newton_step(double m[3], double f,
                                                             const double g[3], double size)
{
    double gg = ism_dot3(g, g);
    if (!isfinite(f) || !(gg > 0) || !isfinite(gg))
        return STEP_FAIL;
    double step = fabs(f) / sqrt(gg);
#pragma GCC unroll 3
    for (int a = 0; a < 3; a++)
        m[a] -= f * g[a] / gg;
    return step < NEWTON_STOP * size ? STEP_STOP : STEP_GO;
}

/* m moved onto f = 0 by Newton along ∇f, stopping once a step is below NEWTON_STOP of
 * size; false when it could not finish a step (∇f vanishing or not finite). */
bool ism_dual_newton_onto(worker *w, double m[3], double size)
{
    for (int it = 0; it < NEWTON_STEPS; it++) {
        double g[3];
        double f = ism_sample_grad(&w->s, m, g);
        int r = newton_step(m, f, g, size);
        if (r == STEP_FAIL)
            return false;
        if (r == STEP_STOP)
            break;
    }
    return true;
}

/* Is m in the closed box lo..hi? */
static bool in_closed_box(const double m[3], const double lo[3], const double hi[3])
{
    bool inside = true;
#pragma GCC unroll 3
    for (int a = 0; a < 3; a++)
        inside &= m[a] >= lo[a] && m[a] <= hi[a];
    return inside;
}

/* The centre of the box lo..hi (side size) moved onto f = 0 by Newton into m; true when
 * that lands in the closed box. */
bool ism_dual_foot_in_node(worker *w, const double lo[3], const double hi[3], double size,
                         double m[3])
{
    for (int a = 0; a < 3; a++)
        m[a] = 0.5 * lo[a] + 0.5 * hi[a];
    return ism_dual_newton_onto(w, m, size) && in_closed_box(m, lo, hi);
}

void ism_dual_newton_lanes(worker *w, double (*m)[3], const double *size, size_t n, bool *ok)
{
    size_t live[ISM_GRAD_BATCH], nl = 0;
    for (size_t k = 0; k < n; k++) {
        ok[k] = true;
        live[nl++] = k;
    }
    for (int it = 0; it < NEWTON_STEPS && nl; it++) {
        double p[ISM_GRAD_BATCH][3], f[ISM_GRAD_BATCH], g[ISM_GRAD_BATCH][3];
        for (size_t j = 0; j < nl; j++)
            memcpy(p[j], m[live[j]], sizeof p[j]);
        ism_sample_grad_batch(&w->s, (const double (*)[3])p, f, g, nl);
        size_t kept = 0;
        for (size_t j = 0; j < nl; j++) { /* ism_dual_newton_onto's step, lane by lane */
            size_t k = live[j];
            int r = newton_step(m[k], f[j], g[j], size[k]);
            ok[k] = r != STEP_FAIL;
            if (r == STEP_GO)
                live[kept++] = k;
        }
        nl = kept;
    }
}

/* foot_in_node for n boxes at once (lo[k]..hi[k] of side size[k], n <= ISM_GRAD_BATCH):
 * ism_dual_newton_lanes from their centres. Into m[k] and state[k]: FOOT_AT when the foot
 * lands in the closed box, else FOOT_OUT. */
void ism_dual_feet_in_nodes(worker *w, const double (*lo)[3], const double (*hi)[3],
                          const double *size, size_t n, double (*m)[3], uint8_t *state)
{
    bool ok[ISM_GRAD_BATCH];
    for (size_t k = 0; k < n; k++)
#pragma GCC unroll 3
        for (int a = 0; a < 3; a++)
            m[k][a] = 0.5 * lo[k][a] + 0.5 * hi[k][a];
    ism_dual_newton_lanes(w, m, size, n, ok);
    for (size_t k = 0; k < n; k++)
        state[k] = ok[k] && in_closed_box(m[k], lo[k], hi[k]) ? FOOT_AT : FOOT_OUT;
}

/* Node n, with both signs at its corners, split at once for the sag of a chord its size
 * (SAG_SPLIT, SAG_ROUND)? Under the straddle move and above depth.max only (no crease, no points:
 * their leaves place vertices otherwise), and only inside the request's box: in the grown
 * box's margin the triangles the clip drops are not measured, so leaves there stay coarse
 * (helicoid at 1.6e-3: kept leaves up to k h² / 8 / (E + shift) = 12 there, 1.27 inside;
 * splitting them cost 7% more instructions). The centre's foot, moved as place_vertex moves
 * it, is kept in v for a node kept as a leaf (the Hessian that moves it gives the
 * curvature), and a foot outside the node is remembered: place_vertex repeats neither. */
static bool sag_split(dual *d, worker *w, const dnode *n, corner_view *v)
{
    if (!sag_may_split(d, n->level, v->p[0], v->p[7]))
        return false;
    double size = ism_grid_cell_size(&d->g, n->level), m[3], bend[2];
    bool inside = v->foot == FOOT_UNKNOWN ? ism_dual_foot_in_node(w, v->p[0], v->p[7], size, m)
                                          : v->foot == FOOT_AT;
    if (!inside) {
        v->placed = FOOT_OUT;
        return false;
    }
    if (v->foot == FOOT_AT)
        memcpy(m, v->foot_at, sizeof m);
    ism_straddle_balanced_point_at(&w->s, d->shift, d->o->box, m,
                                   v->foot == FOOT_AT ? &v->foot_jet : NULL, v->at, bend);
    double room = 8 * (d->o->max_error + d->shift);
    bool split = bend[0] * size * size > SAG_SPLIT * room ||
                 bend[1] * size * size > SAG_ROUND * room;
    v->placed = split ? FOOT_UNKNOWN : FOOT_AT;
    return split;
}

/* What node n is (f and the unit gradients at its corners in n->f and v): empty (proven
 * free of f = 0), a surface leaf with one sheet (corner gradients agreeing, or one graph
 * proven by interval gradients), or to be split. The interval is taken only where the
 * corners cannot decide: a node whose corners share a sign, or disagree. In two steps (a
 * split classifies a node's children's heads first, then takes the enclosures their tails
 * want in one batch: ism_dual_kid_kinds): classify_head answers what the corners (and sag_split)
 * decide, else UNDECIDED, and classify_tail the rest. */
int ism_dual_classify_head(dual *d, worker *w, dnode *n, corner_view *v)
{
    int neg = 0;
    v->placed = FOOT_UNKNOWN;
    v->pre_g = v->pre_model = v->pre_forms = v->pre_open_known = false;
    if (v->corners == CORNERS_NOT_FINITE)
        return DN_INNER;
    if (v->corners)
        neg = v->corners - 1;
    else
        for (int c = 0; c < 8; c++) {
            if (!ism_dual_corner_finite(n->f[c], v->n[c]))
                return DN_INNER;
            neg += n->f[c] < 0;
        }
    bool mixed = neg != 0 && neg != 8;
    /* shown free by its parent's proofs or its interval (known_free): above depth.min too,
     * as nothing in it is meshed at any depth (children_free's batches start at level 1) */
    if (!mixed && v->known_free)
        return DN_EMPTY;
    if (n->level < d->o->min_depth)
        return DN_INNER;
    /* a sheet through the one corner >= 0, where f is exactly 0 (tooth at (0, 1, 1), tangent
     * to the lattice edge along x; spindle-cyclide at the origin): every crossed edge's root
     * is that corner, so is the leaf's vertex, and so are those of the leaves round it —
     * triangles of no area, at every level alike. Split, so the mesh declines at depth.max
     * (not_plain) before vertices and measurements: meshing them to find the misses cost
     * tooth 1e-2 +11.5% and spindle-cyclide +30.8% of the whole run (callgrind). A sheet
     * crossing the lattice point transversally (zero_corner_transverse) is a plain case. */
    if (neg == 7)
        for (int c = 0; c < 8; c++)
            if (n->f[c] == 0 && !zero_corner_transverse(v, c))
                return DN_INNER;
    if (mixed && sag_split(d, w, n, v))
        return DN_INNER;
    v->neg = neg;
    v->agree = mixed && normals_agree((const double (*)[3])v->n, d->o->flat_normal);
    v->have_g = v->have_model = false;
    v->monotone = 0;
    return UNDECIDED;
}

/* Will classify_tail tighten node n, its natural enclosure in v->g (pre_g)? A node whose
 * corners agree takes no tighten; the others do when natural_open, the tail's own tests
 * before its first tighten, leave them open (that answer kept in v for the tail). */
static bool tail_tightens(const dnode *n, corner_view *v)
{
    if (v->agree)
        return false;
    v->pre_open = natural_open(n, v);
    v->pre_open_known = true;
    return v->pre_open;
}

/* Models made at once for fewer nodes cost more than one by one (ism_dual_taylor_many's
 * centre batch: interval_jet.h, ISM_IVGRAD_BATCH's figures). */
#define PRE_MODELS_MIN 2

/* The models of nodes views[pick[0..np)] (np <= ISM_IVGRAD_BATCH) made at once, with their
 * forms and enclosures, into the views (ism_dual_pre_models). */
static void models_at_once(worker *w, corner_view *views, const int *pick, int np)
{
    double lo[ISM_IVGRAD_BATCH][3], hi[ISM_IVGRAD_BATCH][3];
    ism_dual_model m[ISM_IVGRAD_BATCH];
    bool ok[ISM_IVGRAD_BATCH];
    for (int k = 0; k < np; k++) {
        memcpy(lo[k], views[pick[k]].p[0], sizeof lo[k]);
        memcpy(hi[k], views[pick[k]].p[7], sizeof hi[k]);
    }
    if (!ism_dual_taylor_many(w->s.tape, w->jet, (const double (*)[3])lo,
                              (const double (*)[3])hi, (size_t)np, m, ok))
        return;
    /* the tails' first enclosures of these models, in lanes (the form alone decides for
       some: taken anyway, a group of four lanes costing about one box's form and enclosure)
       — but for a group of four whose forms all keep f from 0 when every node picked has
       corners of one sign: each such tail then answers from its form (empty_proven) and
       never reads the enclosure; a node with both signs reads it (tighten) */
    ism_interval v2[ISM_IVGRAD_BATCH];
    ism_ivgrad over[ISM_IVGRAD_BATCH];
    bool over_ok[ISM_IVGRAD_BATCH], every = false;
    /* mixed from the corners' signs, not the form: corner values are rounded point values,
       so a node with both signs can have a form that keeps f from 0, and its tail (tighten)
       reads the enclosure a skip would leave unset (node_over) */
    for (int k = 0; k < np; k++)
        every |= views[pick[k]].neg != 0 && views[pick[k]].neg != 8;
    bool forms = ism_dual_over_many(m, (const double (*)[3])lo, (const double (*)[3])hi,
                                    (size_t)np, every, v2, over, over_ok);
    for (int k = 0; k < np; k++) {
        corner_view *v = &views[pick[k]];
        v->model = m[k];
        v->pre_ok = ok[k];
        v->pre_model = true;
        v->pre_forms = forms && ok[k];
        if (v->pre_forms) { /* else not computed (forms false) or from a failed jet */
            v->pre_v2 = v2[k];
            v->pre_over = over[k];
            v->pre_over_ok = over_ok[k];
        }
    }
}

void ism_dual_pre_models(worker *w, const dnode *kids, corner_view *views, const int *at,
                         int nb)
{
    int pick[ISM_IVGRAD_BATCH], np = 0;
    for (int k = 0; k < nb; k++) {
        corner_view *v = &views[at[k]];
        if (!v->pre_g || !tail_tightens(&kids[at[k]], v))
            continue;
        pick[np++] = at[k];
        if (np == ISM_IVGRAD_BATCH) {
            models_at_once(w, views, pick, np);
            np = 0;
        }
    }
    if (np >= PRE_MODELS_MIN)
        models_at_once(w, views, pick, np);
}

int ism_dual_classify_tail(dual *d, worker *w, dnode *n, corner_view *v)
{
    int neg = v->neg;
    bool mixed = neg != 0 && neg != 8;
    if (tail_wants_g(d, v)) {
        /* the natural interval first (one evaluation, enough on the sphere), then the
         * Taylor form (two), then the sub-boxes */
        ism_interval box[3];
        ism_dual_node_box(v, box);
        w->s.n_interval++;
        /* kept: the Taylor model of the same box (tighten) then computes only the Hessian
         * (interval_jet.h); torus at 1e-2, 680 of 1,392 such nodes */
        size_t kinks =
            v->pre_g ? 0 : ism_eval_interval_grad_kept(w->s.tape, w->jet, box, &v->g);
        v->have_g = kinks == 0;
        if (!v->have_g) /* a kink in the node */
            return d->crease && kinks != (size_t)-1 ? crease_kind(d, w, n, v) : DN_INNER;
        if (v->agree)
            return plain_edges(d, w, n, v) ? DN_SURF : DN_INNER;
        if (!mixed) /* empty, or maybe a piece no corner sees */
            return empty_proven(d, w, n, v) || (neg == 0 && touch_empty(n, v)) ||
                           (n->level >= d->o->max_depth && face_cap(d, w, v))
                       ? DN_EMPTY
                       : DN_INNER;
        /* pre_model: the enclosure was seen to show no graph (ism_dual_pre_models) */
        if ((v->pre_model || natural_open_once(n, v)) &&
            !(tighten(w, v) &&
              (ism_graph_from_enclosure(&v->g) || graph_on_sub_boxes(d, w, n, v))))
            return DN_INNER;
        for (int a = 0; a < 3; a++)
            v->monotone |= (v->g.d[a].lo > 0 || v->g.d[a].hi < 0) << a;
    }
    return plain_edges(d, w, n, v) ? DN_SURF : DN_INNER;
}

int ism_dual_classify(dual *d, worker *w, dnode *n, corner_view *v)
{
    int kind = ism_dual_classify_head(d, w, n, v);
    return kind != UNDECIDED ? kind : ism_dual_classify_tail(d, w, n, v);
}

/* Does node n touch the request's box (a face of the tree's lattice)? */
static bool touches_box(const dual *d, const dnode *n)
{
    int32_t step = ism_grid_cell_steps(&d->g, n->level), last = (int32_t)1 << d->g.depth;
    for (int a = 0; a < 3; a++)
        if (n->o.v[a] == 0 || n->o.v[a] + step == last)
            return true;
    return false;
}

/* Node kind (kind: classify's) after the checks near points and on the request's box:
 * empty, a surface leaf, or inner (to split; bad set when the box cuts the surface). */
static inline __attribute__((always_inline)) int box_kind(dual *d, worker *w, dnode *n,
                                                         corner_view *v, int kind, bool *bad)
{
    if (kind == DN_INNER && d->nballs &&
        ism_dual_balls_near(d->balls, d->nballs, &d->cover, v->p[0], v->p[7],
                            ism_grid_cell_size(&d->g, n->level)))
        return DN_HOLE; /* not plain near a point, as small as its hole's leaves (near_point) */
    if (has_sheet(kind) && touches_box(d, n)) {
        if (d->inner) {
            if (n->level < ISM_DUAL_BOX_LEVEL)
                kind = DN_INNER; /* no larger than the margin's cells (dual_box.h) */
        } else {
            int clear = ism_dual_box_faces_clear(d, w, n, v);
            if (clear < 0)
                *bad = true; /* the box cuts the surface: its faces need the primal polygons */
            else if (!clear)
                kind = DN_INNER; /* split until the box's faces are proven clear */
        }
    }
    return kind;
}

int ism_dual_leaf_kind(dual *d, worker *w, dnode *n, corner_view *v, bool *bad)
{
    if (d->nballs) { /* round a singular point: split, or a hole leaf (dual_balls.h) */
        int hole = ism_dual_balls_node(d->balls, d->nballs, &d->cover, v->p[0], v->p[7],
                                       ism_grid_cell_size(&d->g, n->level),
                                       n->level >= d->o->max_depth);
        if (hole == 0 || (hole == 1 && n->level < d->o->min_depth))
            return DN_INNER;
        if (hole == 1)
            return DN_HOLE;
    }
    return box_kind(d, w, n, v, ism_dual_classify(d, w, n, v), bad);
}

/* Children whose classify_tail takes f and ∇f's natural enclosure, at least this many,
 * take them in one batch (ism_eval_interval_grad_batch): fewer cost more than one by one
 * (interval_jet.h, ISM_IVGRAD_BATCH's figures). */
#define BATCH_ENCLOSURES 2

void ism_dual_kid_kinds(dual *d, worker *w, dnode *kids, corner_view *views,
                        const uint8_t *empty, size_t nodes, int *kind, bool *bad)
{
    size_t nk = 8 * nodes;
    if (d->nballs) {
        for (size_t i = 0; i < nk; i++)
            kind[i] = ism_dual_leaf_kind(d, w, &kids[i], &views[i], &bad[i / 8]);
        return;
    }
    int at[8 * ISM_DUAL_SPLIT_CHUNK], nb = 0;
    for (size_t i = 0; i < nk; i++) {
        kind[i] = empty[i / 8] >> (i % 8) & 1
                      ? DN_EMPTY
                      : ism_dual_classify_head(d, w, &kids[i], &views[i]);
        if (kind[i] != UNDECIDED || !tail_wants_g(d, &views[i]) || d->crease)
            continue; /* a crease's tape has its min/max: not one the batch takes */
        at[nb++] = (int)i;
    }
    int nat = 0; /* at[0..nat): natural enclosures in views (pre_g) */
    for (int b = 0; nb - b >= BATCH_ENCLOSURES; b += ISM_IVGRAD_BATCH) {
        int m = nb - b < ISM_IVGRAD_BATCH ? nb - b : ISM_IVGRAD_BATCH;
        ism_interval box[ISM_IVGRAD_BATCH][3];
        ism_ivgrad g[ISM_IVGRAD_BATCH];
        for (int k = 0; k < m; k++)
            ism_dual_node_box(&views[at[b + k]], box[k]);
        if (!ism_eval_interval_grad_batch(w->s.tape, w->jet, (const ism_interval (*)[3])box,
                                          (size_t)m, g))
            break;
        for (int k = 0; k < m; k++) {
            views[at[b + k]].g = g[k];
            views[at[b + k]].pre_g = true;
        }
        nat = b + m;
    }
    if (nat)
        ism_dual_pre_models(w, kids, views, at, nat);
    for (size_t i = 0; i < nk; i++) {
        if (empty[i / 8] >> (i % 8) & 1)
            continue; /* box_kind leaves DN_EMPTY as it is */
        if (kind[i] == UNDECIDED)
            kind[i] = ism_dual_classify_tail(d, w, &kids[i], &views[i]);
        kind[i] = box_kind(d, w, &kids[i], &views[i], kind[i], &bad[i / 8]);
    }
}
