/* test_dual_pre.c — a split's children classified in two steps with their natural enclosures
 * and Taylor models made at once (ism_dual_kid_kinds: classify_head, ism_eval_interval_grad_batch,
 * ism_dual_pre_models, classify_tail) against each child alone (ism_dual_classify): the same
 * kind, the same have_model and, with it, the same model to the bit, and the same enclosure
 * left in the view (the models' enclosures at once: ism_dual_over_many). The tail skips the tests
 * ism_dual_pre_models saw fail (dual_classify.c natural_open); if the two ever chose
 * differently, a verdict or a model would differ here. A view the pre-pass left (its kept
 * natural_open answer in it) reused for another child is classified as a fresh one (split_task's
 * views are not cleared between nodes: classify_head must clear those answers). The torus's
 * nodes at levels 3-5 whose box reaches the tube, in three placements
 * (tests/unit/placements.h). And ism_dual_kid_kinds itself over chunks of split nodes
 * (ism_dual_chunk) in a box whose faces cut the tube: every child's kind and every node's own
 * "meets the cut box" flag as each child alone (ism_dual_leaf_kind). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/interval_jet.h"
#include "core/octree/dual_classify.h"
#include "core/octree/dual_tree.h"
#include "core/octree/grid.h"
#include "dual_rig.h"
#include "poly_fixture.h"

#define DEPTH 10
#define E 0.0141 /* the bench's 1e-2 setting on the torus */

/* The rig and the stale views' counts (stale_view_classified) over one placement. */
typedef struct rig {
    dual_rig r;
    int stale_kept;   /* views the pre-pass left with a kept natural_open answer */
    int stale_differ; /* (stale view, other child) pairs whose kept answers differ */
} rig;

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
 * from a fresh view (want). */
static void stale_view_classified(rig *r, const corner_view *stale, const dnode *node,
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
    cr_assert_eq(ism_dual_classify(&r->r.d, &r->r.w, &n, &v), want,
                 "a view the pre-pass left, reused for another node: another kind");
}

/* The lattice origins of the nodes of a level whose box reaches the torus's tube (its centre
 * within half its diagonal, 0.87 of a side, of the tube), in z, y, x order, malloc'd; their
 * number into *n. */
static int32_t (*tube_nodes(const rig *r, int level, int *n))[3]
{
    int32_t step = ism_grid_cell_steps(&r->r.d.g, level);
    int cells = 1 << level;
    double size = ism_grid_cell_size(&r->r.d.g, level);
    int32_t (*q)[3] = malloc((size_t)cells * cells * cells * sizeof *q);
    cr_assert(q);
    *n = 0;
    for (int z = 0; z < cells; z++)
        for (int y = 0; y < cells; y++)
            for (int x = 0; x < cells; x++) {
                int32_t at[3] = {x * step, y * step, z * step};
                double c[3];
                for (int a = 0; a < 3; a++)
                    c[a] = ism_grid_coord(&r->r.d.g, a, at[a] + step / 2);
                if (pf_ring_torus_dist(c) <= 0.87 * size)
                    memcpy(q[(*n)++], at, sizeof at);
            }
    return q;
}

/* The children of the node at q, level, both ways — and a third, with corner_view.corners
 * set beforehand (split_task's path) instead of 0 (classify_head counting them): the same
 * kinds; returns how many children took a model made at once. */
static int compare_children(rig *r, const int32_t q[3], int level, int placement)
{
    dnode kids[8], alone[8], preset[8], node[8];
    corner_view views[8], solo[8], counted[8], fresh[8], stale[8];
    int half = ism_grid_cell_steps(&r->r.d.g, level + 1), kind[8], at[8], nb = 0;
    for (int c = 0; c < 8; c++) {
        int32_t k[3] = {q[0] + (c & 1) * half, q[1] + (c >> 1 & 1) * half,
                        q[2] + (c >> 2 & 1) * half};
        dual_rig_node(&r->r, k, level + 1, &kids[c], &views[c]);
        alone[c] = kids[c];
        solo[c] = views[c];
        node[c] = kids[c];
        fresh[c] = views[c];
        preset[c] = kids[c];
        counted[c] = views[c];
        counted[c].corners = corner_count(&kids[c], &views[c]);
    }
    /* ism_dual_kid_kinds' order */
    ism_interval box[8][3];
    ism_ivgrad g[8];
    for (int c = 0; c < 8; c++) {
        kind[c] = ism_dual_classify_head(&r->r.d, &r->r.w, &kids[c], &views[c]);
        if (kind[c] != UNDECIDED || !tail_wants_g(&r->r.d, &views[c]))
            continue;
        ism_dual_node_box(&views[c], box[nb]);
        at[nb++] = c;
    }
    int made = 0;
    if (nb >= 2 && ism_eval_interval_grad_batch(r->r.w.s.tape, r->r.w.jet,
                                                (const ism_interval (*)[3])box, (size_t)nb, g)) {
        for (int k = 0; k < nb; k++) {
            views[at[k]].g = g[k];
            views[at[k]].pre_g = true;
        }
        ism_dual_pre_models(&r->r.w, kids, views, at, nb);
        for (int k = 0; k < nb; k++)
            made += views[at[k]].pre_model;
    }
    memcpy(stale, views, sizeof stale);
    for (int c = 0; c < 8; c++)
        if (kind[c] == UNDECIDED)
            kind[c] = ism_dual_classify_tail(&r->r.d, &r->r.w, &kids[c], &views[c]);
    for (int c = 0; c < 8; c++) {
        int want = ism_dual_classify(&r->r.d, &r->r.w, &alone[c], &solo[c]);
        cr_assert_eq(kind[c], want, "placement %d, level %d node (%d %d %d) child %d: %d at once, "
                                    "%d alone",
                     placement, level, q[0], q[1], q[2], c, kind[c], want);
        int given = ism_dual_classify(&r->r.d, &r->r.w, &preset[c], &counted[c]);
        cr_assert_eq(given, want, "placement %d, level %d node (%d %d %d) child %d: %d with "
                                  "the corners counted beforehand (%d), %d counting them",
                     placement, level, q[0], q[1], q[2], c, given, counted[c].corners, want);
        /* and the count is what is read: a view saying "not finite" is split unlooked at */
        dnode bad = kids[c];
        corner_view nf = solo[c];
        nf.corners = CORNERS_NOT_FINITE;
        cr_assert_eq(ism_dual_classify(&r->r.d, &r->r.w, &bad, &nf), DN_INNER);
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
    /* each view the pre-pass left (pre_g: with or without a kept answer) reused for each
       other child; a kept answer read for child b shows only where it is not b's own (b's
       kept one, taken on b's natural enclosure: the same as its tail's, compared above) */
    for (int c = 0; c < 8; c++) {
        r->stale_kept += stale[c].pre_g && stale[c].pre_open_known;
        for (int b = 0; b < 8 && stale[c].pre_g; b++) {
            if (b == c)
                continue;
            dnode alone_b = node[b];
            corner_view vb = fresh[b];
            int want = ism_dual_classify(&r->r.d, &r->r.w, &alone_b, &vb);
            stale_view_classified(r, &stale[c], &node[b], &fresh[b], want);
            r->stale_differ += stale[c].pre_open_known && stale[b].pre_open_known &&
                               stale[c].pre_open != stale[b].pre_open;
        }
    }
    return made;
}

Test(dual_pre, children_classified_at_once_as_one_by_one)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    for (int i = pf_first_box(); i < 3; i++) {
        rig r = {.stale_kept = 0};
        dual_rig_set_up(&r.r, t, i, DEPTH, E);
        int made = 0, nodes = 0;
        for (int level = 3; level <= 5; level++) {
            int n;
            int32_t (*q)[3] = tube_nodes(&r, level, &n);
            for (int k = 0; k < n; k++)
                made += compare_children(&r, q[k], level, i);
            nodes += n;
            free(q);
        }
        /* the batch path must carry the comparison: models made at once in at least a
         * quarter of the splits (1,672 in 3,056 here on main, the ratio ~0.55 in each
         * placement) */
        cr_expect_gt(made, nodes / 4, "placement %d: %d models made at once in %d splits", i,
                     made, nodes);
        /* the stale views must carry kept answers, and answers the other child's own
         * differs from, or they test nothing (views 15,320 and pairs 15,888 in 3,056 splits
         * here, about 5 a split each in each placement) */
        cr_expect_gt(r.stale_kept, 4 * nodes, "placement %d: %d stale views with a kept answer "
                                              "in %d splits", i, r.stale_kept, nodes);
        cr_expect_gt(r.stale_differ, nodes, "placement %d: %d kept answers another child's "
                                            "differs from, in %d splits", i, r.stale_differ,
                     nodes);
        dual_rig_tear_down(&r.r);
    }
    ism_tape_free(t);
}

/* Nodes whose children one test call classifies together (split_task: ISM_DUAL_SPLIT_CHUNK). */
#define MANY 3

/* The children of the nq <= MANY nodes at q[0..nq) (level) classified together by the steps
 * of ism_dual_kid_kinds taken here one by one (every head, the natural enclosures
 * ISM_IVGRAD_BATCH at a time, then ism_dual_pre_models over all of them at once), against each
 * child alone: the same kind and the same model to the bit. And every child whose tail would
 * tighten (ism_dual_pre_models' answer kept in its view: pre_open) took its model at once,
 * but for a last batch of one (PRE_MODELS_MIN): the picks past the first ISM_IVGRAD_BATCH
 * are made too. Returns how many children took a model made at once. */
static int compare_many(rig *r, const int32_t (*q)[3], int nq, int level, int placement)
{
    dnode kids[8 * MANY], alone[8 * MANY];
    corner_view views[8 * MANY], solo[8 * MANY];
    int half = ism_grid_cell_steps(&r->r.d.g, level + 1), kind[8 * MANY], at[8 * MANY], nb = 0;
    for (int i = 0; i < 8 * nq; i++) {
        int c = i % 8;
        int32_t k[3] = {q[i / 8][0] + (c & 1) * half, q[i / 8][1] + (c >> 1 & 1) * half,
                        q[i / 8][2] + (c >> 2 & 1) * half};
        dual_rig_node(&r->r, k, level + 1, &kids[i], &views[i]);
        alone[i] = kids[i];
        solo[i] = views[i];
    }
    for (int i = 0; i < 8 * nq; i++) {
        kind[i] = ism_dual_classify_head(&r->r.d, &r->r.w, &kids[i], &views[i]);
        if (kind[i] == UNDECIDED && tail_wants_g(&r->r.d, &views[i]))
            at[nb++] = i;
    }
    int nat = 0;
    for (int b = 0; nb - b >= 2; b += ISM_IVGRAD_BATCH) {
        int m = nb - b < ISM_IVGRAD_BATCH ? nb - b : ISM_IVGRAD_BATCH;
        ism_interval box[ISM_IVGRAD_BATCH][3];
        ism_ivgrad g[ISM_IVGRAD_BATCH];
        for (int k = 0; k < m; k++)
            ism_dual_node_box(&views[at[b + k]], box[k]);
        cr_assert(ism_eval_interval_grad_batch(r->r.w.s.tape, r->r.w.jet,
                                               (const ism_interval (*)[3])box, (size_t)m, g));
        for (int k = 0; k < m; k++) {
            views[at[b + k]].g = g[k];
            views[at[b + k]].pre_g = true;
        }
        nat = b + m;
    }
    int made = 0, picks = 0;
    if (nat) {
        ism_dual_pre_models(&r->r.w, kids, views, at, nat);
        for (int k = 0; k < nat; k++) {
            made += views[at[k]].pre_model;
            picks += views[at[k]].pre_open_known && views[at[k]].pre_open;
        }
    }
    int want_made = picks % ISM_IVGRAD_BATCH == 1 ? picks - 1 : picks;
    cr_assert_eq(made, want_made, "placement %d, level %d: %d of %d picks made at once",
                 placement, level, made, picks);
    for (int i = 0; i < 8 * nq; i++) {
        if (kind[i] == UNDECIDED)
            kind[i] = ism_dual_classify_tail(&r->r.d, &r->r.w, &kids[i], &views[i]);
        int want = ism_dual_classify(&r->r.d, &r->r.w, &alone[i], &solo[i]);
        cr_assert_eq(kind[i], want, "placement %d, level %d, node %d child %d: %d together, "
                                    "%d alone", placement, level, i / 8, i % 8, kind[i], want);
        cr_assert_eq(views[i].have_model, solo[i].have_model);
        if (solo[i].have_model)
            cr_assert(!memcmp(&views[i].model, &solo[i].model, sizeof solo[i].model),
                      "placement %d, level %d, node %d child %d: another model", placement,
                      level, i / 8, i % 8);
    }
    return made;
}

Test(dual_pre, children_of_several_nodes_classified_together_as_one_by_one)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    for (int i = pf_first_box(); i < 3; i++) {
        rig r = {.stale_kept = 0};
        dual_rig_set_up(&r.r, t, i, DEPTH, E);
        int made = 0, batches = 0;
        for (int level = 3; level <= 4; level++) {
            int n;
            int32_t (*q)[3] = tube_nodes(&r, level, &n);
            for (int k = 0; k < n; k += MANY) {
                int m = compare_many(&r, (const int32_t (*)[3])q + k, n - k < MANY ? n - k : MANY,
                                     level, i);
                made += m;
                batches += m > ISM_IVGRAD_BATCH;
            }
            free(q);
        }
        /* the calls must carry picks past one batch of models, or the loop past the first
           ISM_IVGRAD_BATCH is not tested */
        cr_expect_gt(batches, 10, "placement %d: %d calls made more than %d models (%d in all)",
                     i, batches, ISM_IVGRAD_BATCH, made);
        dual_rig_tear_down(&r.r);
    }
    ism_tape_free(t);
}

/* Node q's (level) 8 children as split_task makes them (kids, views: node j's at 8 j), each
 * classified alone on copies with the request's box's check (ism_dual_leaf_kind) into want;
 * returns whether one of them met the cut box (its own flag, not ism_dual_kid_kinds'). */
static bool children_alone(rig *r, const int32_t q[3], int level, dnode *kids,
                           corner_view *views, int *want)
{
    int half = ism_grid_cell_steps(&r->r.d.g, level + 1);
    bool bad = false;
    for (int c = 0; c < 8; c++) {
        int32_t k[3] = {q[0] + (c & 1) * half, q[1] + (c >> 1 & 1) * half,
                        q[2] + (c >> 2 & 1) * half};
        dual_rig_node(&r->r, k, level + 1, &kids[c], &views[c]);
        dnode n = kids[c];
        corner_view v = views[c];
        want[c] = ism_dual_leaf_kind(&r->r.d, &r->r.w, &n, &v, &bad);
    }
    return bad;
}

/* The block of nq nodes q[0..nq) (level) classified chunk by chunk as split_task does
 * (ism_dual_chunk, ism_dual_kid_kinds: the real function, not a copy of its steps), against
 * each child alone: the chunks cover the block once, in order; every child has its kind
 * alone, and node j's bad flag is the OR of its own children's alone, node by node. Every
 * other child found DN_EMPTY alone is handed over as empty (split_task's masks; its view
 * not made). Returns how many nodes met the cut box at a place > 0 of a chunk whose first
 * node did not (what a flag put on another node of the chunk would get wrong). */
static int compare_block(rig *r, const int32_t (*q)[3], size_t nq, int level, int placement)
{
    dnode kids[8 * ISM_DUAL_SPLIT_CHUNK];
    corner_view views[8 * ISM_DUAL_SPLIT_CHUNK];
    int kind[8 * ISM_DUAL_SPLIT_CHUNK], want[8 * ISM_DUAL_SPLIT_CHUNK], late = 0;
    size_t next = 0, chunks = (nq + ISM_DUAL_SPLIT_CHUNK - 1) / ISM_DUAL_SPLIT_CHUNK;
    for (size_t k = 0; k < chunks; k++) {
        size_t lo, nodes = ism_dual_chunk(nq, k, &lo);
        cr_assert(lo == next && nodes >= 1 && nodes <= ISM_DUAL_SPLIT_CHUNK && lo + nodes <= nq,
                  "chunk %zu of %zu nodes: from %zu, %zu nodes", k, nq, lo, nodes);
        next = lo + nodes;
        uint8_t empty[ISM_DUAL_SPLIT_CHUNK] = {0};
        bool bad[ISM_DUAL_SPLIT_CHUNK] = {false}, want_bad[ISM_DUAL_SPLIT_CHUNK];
        for (size_t j = 0; j < nodes; j++) {
            want_bad[j] = children_alone(r, q[lo + j], level, &kids[8 * j], &views[8 * j],
                                         &want[8 * j]);
            for (int c = (int)j % 2; c < 8; c += 2)
                empty[j] |= (uint8_t)((want[8 * j + (size_t)c] == DN_EMPTY) << c);
            late += j > 0 && want_bad[j] && !want_bad[0];
        }
        ism_dual_kid_kinds(&r->r.d, &r->r.w, kids, views, empty, nodes, kind, bad);
        for (size_t i = 0; i < 8 * nodes; i++)
            cr_assert_eq(kind[i], want[i], "placement %d, %zu nodes, chunk %zu, node %zu "
                                           "child %zu: %d together, %d alone", placement, nq,
                         k, i / 8, i % 8, kind[i], want[i]);
        for (size_t j = 0; j < nodes; j++)
            cr_assert_eq(bad[j], want_bad[j], "placement %d, %zu nodes, chunk %zu, node %zu: "
                                              "meets the cut box %d together, %d alone",
                         placement, nq, k, j, bad[j], want_bad[j]);
    }
    cr_assert_eq(next, nq, "the chunks cover %zu of %zu nodes", next, nq);
    return late;
}

Test(dual_pre, chunks_of_nodes_classified_together_as_one_by_one_with_the_cut_box)
{
    /* the box's faces x = 1 and y = 1 cut the tube (radii 1 and 0.3): surface leaves there
       meet the box (ism_dual_box_faces_clear < 0), the others not */
    const double cut[6] = {-1.5, -1.5, -1.5, 1.0, 1.0, 1.0};
    ism_tape *t = pf_compile(&pf_ring_torus);
    for (int i = pf_first_box(); i < 3; i++) {
        rig r = {.stale_kept = 0};
        dual_rig_set_up_box(&r.r, t, cut, i, DEPTH, E);
        int n, level = 3;
        int32_t (*q)[3] = tube_nodes(&r, level, &n);
        /* 8 nodes, one chunk, with only its 6th node meeting the cut box */
        int32_t eight[ISM_DUAL_SPLIT_CHUNK][3];
        int cut_at = -1, clear = 0;
        for (int k = 0; k < n && (cut_at < 0 || clear < ISM_DUAL_SPLIT_CHUNK - 1); k++) {
            dnode kids[8];
            corner_view views[8];
            int want[8];
            bool bad = children_alone(&r, q[k], level, kids, views, want);
            if (bad && cut_at < 0)
                cut_at = k;
            else if (!bad && clear < ISM_DUAL_SPLIT_CHUNK - 1)
                memcpy(eight[clear < 5 ? clear : clear + 1], q[k], sizeof eight[0]), clear++;
        }
        cr_assert(cut_at >= 0 && clear == ISM_DUAL_SPLIT_CHUNK - 1,
                  "placement %d: no node meeting the cut box among %d", i, n);
        memcpy(eight[5], q[cut_at], sizeof eight[5]);
        int late = compare_block(&r, (const int32_t (*)[3])eight, ISM_DUAL_SPLIT_CHUNK, level, i);
        cr_assert_eq(late, 1, "placement %d: %d late nodes in the chunk of 8", i, late);
        /* 8 k + 3 nodes: whole chunks and a last one of 3 */
        size_t nq = (size_t)(n - 3) / 8 * 8 + 3;
        cr_assert_geq(nq, 19);
        late = compare_block(&r, (const int32_t (*)[3])q, nq, level, i);
        /* the tube's nodes in z, y, x order put those on the faces x = 1 and y = 1 amid
           others: the check must see some past a chunk's first */
        cr_expect_gt(late, 0, "placement %d: no node past a chunk's first meets the box", i);
        free(q);
        dual_rig_tear_down(&r.r);
    }
    ism_tape_free(t);
}
