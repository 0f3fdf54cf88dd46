/* test_dual_pre.c — a split's children classified in two steps with their natural enclosures
 * and Taylor models made at once (dual.c kid_kinds: classify_head, ism_eval_interval_grad_batch,
 * ism_dual_pre_models, classify_tail) against each child alone (ism_dual_classify): the same
 * kind, the same have_model and, with it, the same model to the bit, and the same enclosure
 * left in the view (the models' enclosures at once: ism_dual_over_many). The tail skips the tests
 * ism_dual_pre_models saw fail (dual_classify.c natural_open); if the two ever chose
 * differently, a verdict or a model would differ here. A view the pre-pass left (its kept
 * natural_open answer in it) reused for another child is classified as a fresh one (split_task's
 * views are not cleared between nodes: classify_head must clear those answers). The torus's
 * nodes at levels 3-5 whose
 * box reaches the tube, in three placements (tests/unit/placements.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/octree/corners.h"
#include "core/octree/dual_classify.h"
#include "core/octree/dual_tree.h"
#include "core/octree/grid.h"
#include "poly_fixture.h"

#define DEPTH 10
#define E 0.0141 /* the bench's 1e-2 setting on the torus */

typedef struct rig {
    dual d;
    worker w;
    ism_poly_options o;
    int stale_kept; /* stale views tried that held a kept natural_open answer */
} rig;

static void set_up(rig *r, const ism_tape *t, int i)
{
    double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, box[6];
    pf_sweep_box(base, DEPTH, i - 1, box);
    pf_options(&r->o, box, 1, DEPTH);
    r->o.max_error = E;
    memset(&r->d, 0, sizeof r->d);
    r->stale_kept = 0;
    memset(&r->w, 0, sizeof r->w);
    r->d.o = &r->o;
    ism_grid_init(&r->d.g, box, DEPTH);
    r->d.finest_step = fmin(r->d.g.step[0], fmin(r->d.g.step[1], r->d.g.step[2]));
    for (int e = 0; e < 12; e++)
        ism_cube_edge(e, &r->d.ec0[e], &r->d.ec1[e], r->d.ef[e]);
    r->w.s.tape = t;
    r->w.s.ws = ism_eval_ws_new(t);
    r->w.s.batch = true;
    r->w.jet = ism_ivjet_ws_new(t);
    cr_assert(r->w.s.ws && r->w.jet);
    r->d.w = &r->w;
    r->d.nw = 1;
}

static void tear_down(rig *r)
{
    ism_eval_ws_free(r->w.s.ws);
    ism_ivjet_ws_free(r->w.jet);
    free(r->w.pairs);
}

/* Node at lattice origin q, level: f and the unit gradients at its corners (bit 0 = x,
 * 1 = y, 2 = z), as split_task hands them to classify. */
static void make_node(rig *r, const int32_t q[3], int level, dnode *n, corner_view *v)
{
    memset(n, 0, sizeof *n);
    memset(v, 0, sizeof *v);
    int32_t step = ism_grid_cell_steps(&r->d.g, level);
    for (int a = 0; a < 3; a++)
        n->o.v[a] = q[a];
    n->level = (uint8_t)level;
    n->child = n->vert = n->vert2 = -1;
    for (int c = 0; c < 8; c++) {
        double g[3];
        for (int a = 0; a < 3; a++)
            v->p[c][a] = ism_grid_coord(&r->d.g, a, q[a] + (c >> a & 1) * step);
        n->f[c] = ism_eval_gradient(r->w.s.tape, r->w.s.ws, v->p[c][0], v->p[c][1], v->p[c][2],
                                    g);
        double len = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        for (int a = 0; a < 3; a++)
            v->n[c][a] = len > 0 ? g[a] / len : 0;
    }
    v->foot = FOOT_UNKNOWN;
}

/* corner_view.corners as split_task hands it over from its 27 points' masks (revR 7): from
 * the node's corners here, each looked at once: CORNERS_NOT_FINITE when some f or unit
 * gradient is not finite, else 1 + how many f < 0. */
static uint8_t corner_count(const dnode *n, const corner_view *v)
{
    int neg = 0;
    for (int c = 0; c < 8; c++) {
        bool finite = isfinite(n->f[c]);
        for (int a = 0; a < 3; a++)
            finite &= isfinite(v->n[c][a]) != 0;
        if (!finite)
            return CORNERS_NOT_FINITE;
        neg += n->f[c] < 0;
    }
    return (uint8_t)(1 + neg);
}

/* A view left by the pre-pass (stale: ism_dual_pre_models' answers still in it) handed another
 * node's corners, as split_task's views on its stack are (it sets only a child's inputs, not
 * the pre-pass's fields): classify_head must clear those answers, so the node is classified as
 * from a fresh view (want). Returns whether the stale view held a kept natural_open answer. */
static bool stale_view_classified(rig *r, const corner_view *stale, const dnode *node,
                                  const corner_view *fresh, int want)
{
    corner_view v = *stale;
    dnode n = *node;
    memcpy(v.p, fresh->p, sizeof v.p);
    memcpy(v.n, fresh->n, sizeof v.n);
    v.corners = fresh->corners;
    v.foot = fresh->foot;
    v.known_free = fresh->known_free;
    v.free_kids = 0;
    v.kinked = false;
    cr_assert_eq(ism_dual_classify(&r->d, &r->w, &n, &v), want,
                 "a view the pre-pass left, reused for another node: another kind");
    return stale->pre_open_known;
}

/* The children of the node at q, level, both ways — and a third, with corner_view.corners
 * set beforehand (split_task's path) instead of 0 (classify_head counting them): the same
 * kinds; returns how many children took a model made at once. */
static int compare_children(rig *r, const int32_t q[3], int level, int placement)
{
    dnode kids[8], alone[8], preset[8], node[8];
    corner_view views[8], solo[8], counted[8], fresh[8], stale[8];
    int half = ism_grid_cell_steps(&r->d.g, level + 1), kind[8], at[8], nb = 0;
    for (int c = 0; c < 8; c++) {
        int32_t k[3] = {q[0] + (c & 1) * half, q[1] + (c >> 1 & 1) * half,
                        q[2] + (c >> 2 & 1) * half};
        make_node(r, k, level + 1, &kids[c], &views[c]);
        alone[c] = kids[c];
        solo[c] = views[c];
        node[c] = kids[c];
        fresh[c] = views[c];
        preset[c] = kids[c];
        counted[c] = views[c];
        counted[c].corners = corner_count(&kids[c], &views[c]);
    }
    /* kid_kinds' order */
    ism_interval box[8][3];
    ism_ivgrad g[8];
    for (int c = 0; c < 8; c++) {
        kind[c] = ism_dual_classify_head(&r->d, &r->w, &kids[c], &views[c]);
        if (kind[c] != UNDECIDED || !tail_wants_g(&r->d, &views[c]))
            continue;
        ism_dual_node_box(&views[c], box[nb]);
        at[nb++] = c;
    }
    int made = 0;
    if (nb >= 2 && ism_eval_interval_grad_batch(r->w.s.tape, r->w.jet,
                                                (const ism_interval (*)[3])box, (size_t)nb, g)) {
        for (int k = 0; k < nb; k++) {
            views[at[k]].g = g[k];
            views[at[k]].pre_g = true;
        }
        ism_dual_pre_models(&r->w, kids, views, at, nb);
        for (int k = 0; k < nb; k++)
            made += views[at[k]].pre_model;
    }
    memcpy(stale, views, sizeof stale);
    for (int c = 0; c < 8; c++)
        if (kind[c] == UNDECIDED)
            kind[c] = ism_dual_classify_tail(&r->d, &r->w, &kids[c], &views[c]);
    for (int c = 0; c < 8; c++) {
        int want = ism_dual_classify(&r->d, &r->w, &alone[c], &solo[c]);
        cr_assert_eq(kind[c], want, "placement %d, level %d node (%d %d %d) child %d: %d at once, "
                                    "%d alone",
                     placement, level, q[0], q[1], q[2], c, kind[c], want);
        int given = ism_dual_classify(&r->d, &r->w, &preset[c], &counted[c]);
        cr_assert_eq(given, want, "placement %d, level %d node (%d %d %d) child %d: %d with "
                                  "the corners counted beforehand (%d), %d counting them",
                     placement, level, q[0], q[1], q[2], c, given, counted[c].corners, want);
        /* and the count is what is read: a view saying "not finite" is split unlooked at */
        dnode bad = kids[c];
        corner_view nf = solo[c];
        nf.corners = CORNERS_NOT_FINITE;
        cr_assert_eq(ism_dual_classify(&r->d, &r->w, &bad, &nf), DN_INNER);
        cr_assert_eq(views[c].have_model, solo[c].have_model,
                     "placement %d, level %d node (%d %d %d) child %d: have_model", placement,
                     level, q[0], q[1], q[2], c);
        if (solo[c].have_model)
            cr_assert(!memcmp(&views[c].model, &solo[c].model, sizeof solo[c].model),
                      "placement %d, level %d node (%d %d %d) child %d: another model",
                      placement, level, q[0], q[1], q[2], c);
        /* the enclosure the tail left (natural, or the model's: taken in lanes with the
           other models' at once, ism_dual_over_many) */
        cr_assert_eq(views[c].have_g, solo[c].have_g);
        if (kind[c] != DN_EMPTY && solo[c].have_g)
            cr_assert(!memcmp(&views[c].g, &solo[c].g, sizeof solo[c].g),
                      "placement %d, level %d node (%d %d %d) child %d: another enclosure",
                      placement, level, q[0], q[1], q[2], c);
    }
    /* each view the pre-pass left with a kept answer, reused for each other child */
    for (int c = 0; c < 8; c++)
        for (int b = 0; b < 8 && stale[c].pre_g; b++) {
            if (b == c)
                continue;
            dnode nb = node[b];
            corner_view vb = fresh[b];
            int want = ism_dual_classify(&r->d, &r->w, &nb, &vb);
            r->stale_kept += stale_view_classified(r, &stale[c], &node[b], &fresh[b], want);
        }
    return made;
}

Test(dual_pre, children_classified_at_once_as_one_by_one)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    for (int i = pf_first_box(); i < 3; i++) {
        rig r;
        set_up(&r, t, i);
        int made = 0, nodes = 0;
        for (int level = 3; level <= 5; level++) {
            int32_t step = ism_grid_cell_steps(&r.d.g, level);
            int cells = 1 << level;
            double size = ism_grid_cell_size(&r.d.g, level);
            for (int z = 0; z < cells; z++)
                for (int y = 0; y < cells; y++)
                    for (int x = 0; x < cells; x++) {
                        int32_t q[3] = {x * step, y * step, z * step};
                        double c[3];
                        for (int a = 0; a < 3; a++)
                            c[a] = ism_grid_coord(&r.d.g, a, q[a] + step / 2);
                        /* boxes reaching the tube (half their diagonal: 0.87 of a side) */
                        if (pf_ring_torus_dist(c) > 0.87 * size)
                            continue;
                        made += compare_children(&r, q, level, i);
                        nodes++;
                    }
        }
        /* the batch path must carry the comparison: models made at once in at least a
         * quarter of the splits (1,672 in 3,056 here on main, the ratio ~0.55 in each
         * placement) */
        cr_expect_gt(made, nodes / 4, "placement %d: %d models made at once in %d splits", i,
                     made, nodes);
        /* the stale views must carry kept answers, or they test nothing */
        cr_expect_gt(r.stale_kept, nodes, "placement %d: %d stale views with a kept answer", i,
                     r.stale_kept);
        tear_down(&r);
    }
    ism_tape_free(t);
}
