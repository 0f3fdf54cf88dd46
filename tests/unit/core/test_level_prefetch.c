/* test_level_prefetch.c — the octree build's level prefetch (level_prefetch.h) and the flatness
 * test's error measure (cell_error.h) keep one root memo by one rule (root_table.h's claim and
 * store, corners.h's single-root edges): on every node of a level of the unit sphere, the ring
 * torus and Barth's sextic, in three placements, the roots the prefetch searches in lanes and
 * logs are, edge for edge and bit for bit, the ones ism_cell_error searches one at a time on
 * the same corners with a memo of its own, and neither logs an edge the other does not; the
 * prefetch's memo slots, which the build's tests read, hold the roots it logged (a claim
 * writes t = 0 and the store must overwrite it), and ism_cell_error reading them measures
 * each node's error bit for bit as with its own memo. Searched on each node's own shortened
 * tape (the level build's tape[]: tapes of several groups in one call), the roots are those
 * found on f's own, edge for edge and bit for bit. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/octree/cell_error.h"
#include "core/octree/leaf_tapes.h"
#include "core/octree/level_prefetch.h"
#include "core/octree/root_table.h"
#include "core/util/grow.h"
#include "poly_fixture.h"

#define DEPTH 6   /* the lattice: 64 steps an axis */
#define LEVEL 4   /* the nodes tested: 16^3, 4 steps across */
#define CHUNK 128 /* nodes a prefetch call, as the build's chunk */
#define HALF 1.6  /* the box: ±1.6 (Barth's ball r 1.5 inside) */

static int by_edge(const void *x, const void *y)
{
    const ism_root_entry *a = x, *b = y;
    return a->a != b->a ? (a->a < b->a ? -1 : 1) : a->b != b->b ? (a->b < b->b ? -1 : 1) : 0;
}

/* The log's roots sorted by edge, one per edge (a later search of an edge whose memo slot
 * was taken over in between logs the same root again: both sides must agree on that). */
static size_t distinct(ism_root_log *l)
{
    if (!l->n)
        return 0; /* l->v may be NULL (qsort's base must not be) */
    qsort(l->v, l->n, sizeof *l->v, by_edge);
    size_t m = 0;
    for (size_t i = 0; i < l->n; i++) {
        if (m && by_edge(&l->v[m - 1], &l->v[i]) == 0) {
            cr_expect(memcmp(&l->v[m - 1].t, &l->v[i].t, sizeof(double)) == 0,
                      "an edge logged twice with two roots");
            continue;
        }
        l->v[m++] = l->v[i];
    }
    return m;
}

/* The slots of memo (nroots of them) holding an edge whose root is not the one log holds
 * for it (its searches' roots, any order; sorted is a scratch copy of log's length). */
static size_t stale_slots(const ism_root_entry *memo, size_t nroots, const ism_root_log *log,
                          ism_root_entry *sorted)
{
    size_t n = log->n; /* 0 when a chunk's prefetch searched nothing: log->v may be NULL */
    if (n) {
        memcpy(sorted, log->v, n * sizeof *sorted);
        qsort(sorted, n, sizeof *sorted, by_edge);
    }
    size_t bad = 0;
    for (size_t i = 0; i < nroots; i++) {
        if (!memo[i].a)
            continue;
        const ism_root_entry *e = n ? bsearch(&memo[i], sorted, n, sizeof *sorted, by_edge) : NULL;
        bad += !e || memcmp(&e->t, &memo[i].t, sizeof(double)) != 0;
    }
    return bad;
}

/* The lattice over ±HALF at DEPTH, in placement (pf_sweep_box). */
static ism_grid level_grid(int placement)
{
    const double base[6] = {-HALF, -HALF, -HALF, HALF, HALF, HALF};
    double box[6];
    return pf_sweep_grid(base, DEPTH, placement, box);
}

static size_t compare(const pf_surface *surf, int placement)
{
    ism_sampler s;
    ism_tape *t = pf_build_sampler(surf, &s);
    ism_grid g = level_grid(placement);
    const size_t nroots = (size_t)1 << ISM_ROOT_MEMO_BITS;
    ism_point_entry *points = calloc((size_t)1 << ISM_CORNER_MEMO_BITS, sizeof *points);
    ism_root_entry *lanes_memo = calloc(nroots, sizeof *lanes_memo);
    ism_root_entry *one_memo = calloc(nroots, sizeof *one_memo);
    /* the prefetch's slots as each chunk left them, for ism_cell_error to read (its misses
     * claim slots: on a copy, so that the next chunk's prefetch finds what it left) */
    ism_root_entry *read_memo = calloc(nroots, sizeof *read_memo);
    cr_assert(points && lanes_memo && one_memo && read_memo);
    ism_root_log lanes_log = {NULL, 0, 0, (size_t)1 << 24}, one_log = lanes_log;
    ism_root_log read_log = lanes_log; /* the searches the reads missed */
    ism_root_entry *sorted = NULL;
    size_t sorted_cap = 0;
    ism_node_memo lanes = {lanes_memo, NULL, NULL, &lanes_log};
    ism_node_memo one = {one_memo, NULL, NULL, &one_log};
    ism_node_memo read = {read_memo, NULL, NULL, &read_log};
    const int side = 1 << LEVEL, step = 1 << (DEPTH - LEVEL);
    ism_node nodes[CHUNK];
    const ism_node *at[CHUNK];
    ism_corners k[CHUNK];
    bool have[CHUNK];
    size_t n = 0, measured = 0, nhave = 0, stale = 0, unequal = 0;
    for (int i = 0; i < side * side * side; i++) {
        ism_node nd = {{(i % side) * step, (i / side % side) * step, (i / side / side) * step},
                       -1, LEVEL, ISM_NODE_LEAF, 0, 0};
        nodes[n] = nd;
        at[n] = &nodes[n];
        if (++n < CHUNK && i + 1 < side * side * side)
            continue;
        ism_prefetch_nodes(&lanes, points, ISM_CORNER_MEMO_BITS, &g, at, NULL, n, &s, k,
                           have);
        cr_assert(ism_grow((void **)&sorted, &sorted_cap, lanes_log.n + 1, sizeof *sorted, 256));
        stale += stale_slots(lanes_memo, nroots, &lanes_log, sorted);
        memcpy(read_memo, lanes_memo, nroots * sizeof *read_memo);
        for (size_t j = 0; j < n; j++) {
            nhave += have[j];
            bool finite = have[j];
            for (int c = 0; c < 8 && finite; c++)
                finite = isfinite(k[j].f[c]);
            if (!finite || !ism_single_root_edges(k[j].f))
                continue;
            ism_corners own = k[j];
            own.memo = &one;
            ism_corners from_lanes = k[j];
            from_lanes.memo = &read;
            double err, err_lanes;
            ism_cell_error(&s, &own, 1e-3, 0, NULL, &err); /* its edge roots, one at a time */
            ism_cell_error(&s, &from_lanes, 1e-3, 0, NULL, &err_lanes); /* as the build */
            unequal += memcmp(&err, &err_lanes, sizeof err) != 0;
            measured++;
        }
        n = 0;
    }
    size_t na = distinct(&lanes_log), nb = distinct(&one_log);
    cr_expect_eq(na, nb, "%s: %zu edges searched in lanes, %zu one at a time", surf->expr, na,
                 nb);
    for (size_t i = 0; i < na && i < nb; i++) {
        cr_expect(lanes_log.v[i].a == one_log.v[i].a && lanes_log.v[i].b == one_log.v[i].b,
                  "%s: edge %zu differs", surf->expr, i);
        cr_expect(memcmp(&lanes_log.v[i].t, &one_log.v[i].t, sizeof(double)) == 0,
                  "%s: edge %zu: root %.17g in lanes, %.17g alone", surf->expr, i,
                  lanes_log.v[i].t, one_log.v[i].t);
    }
    cr_expect_gt(measured, 50, "%s: %zu nodes crossed", surf->expr, measured);
    /* a corner's memo slot is taken over within a chunk only by a collision (8 corners of
     * 128 nodes, 2^16 slots): a prefetch that dropped its corners would compare nothing */
    cr_expect_gt(nhave * 10, (size_t)(side * side * side) * 9, "%s: %zu of %d nodes' corners",
                 surf->expr, nhave, side * side * side);
    cr_expect_eq(stale, 0, "%s: %zu memo slots hold a root other than the logged one",
                 surf->expr, stale);
    cr_expect_eq(unequal, 0, "%s: %zu nodes measured otherwise from the prefetch's slots",
                 surf->expr, unequal);
    /* the reads found what the prefetch searched (a miss: its slot taken over in the chunk) */
    cr_expect_lt(read_log.n * 10, na, "%s: %zu of the %zu edges missed", surf->expr,
                 read_log.n, na);
    ism_root_log_free(&lanes_log);
    ism_root_log_free(&one_log);
    ism_root_log_free(&read_log);
    free(sorted);
    free(read_memo);
    free(points);
    free(lanes_memo);
    free(one_memo);
    ism_eval_ws_free(s.ws);
    ism_tape_free(t);
    return na;
}

Test(level_prefetch, lanes_and_the_error_measure_keep_the_same_roots)
{
    const pf_surface *surfs[] = {&pf_unit_sphere, &pf_ring_torus, &pf_barth_sextic};
    for (int sf = 0; sf < 3; sf++)
        for (int p = -1; p < 2; p++) /* own box, +1e-3, irrational (pf_sweep_box) */
            cr_expect_gt(compare(surfs[sf], p), 100, "%s placement %d: few roots",
                         surfs[sf]->expr, p);
}

/* Node nd's tape for its roots, as the level build passes it: f shortened over the node's
 * box (one copy per distinct tape, lt's), else f itself, as NULL or as f's pointer by turns
 * (both mean f's own). */
static const ism_tape *own_tape(const ism_grid *g, const ism_node *nd, ism_sampler *s,
                                ism_tape *scratch, ism_leaf_tapes *lt,
                                ism_leaf_tapes_cache *cache, size_t i)
{
    int32_t w = ism_grid_cell_steps(g, nd->level);
    ism_interval b[3];
    for (int a = 0; a < 3; a++)
        b[a] = (ism_interval){ism_grid_coord(g, a, nd->org[a]),
                              ism_grid_coord(g, a, nd->org[a] + w)};
    if (!ism_tape_shorten(s->tape, s->ws, b[0], b[1], b[2], scratch, NULL))
        return i % 2 ? s->tape : NULL;
    unsigned k = ism_leaf_tapes_number(lt, cache, scratch);
    cr_assert(k);
    return lt->v[k - 1];
}

/* The prefetch over a level's nodes twice, from empty memos: every root on f's own tape
 * (tape NULL), and each node's on its own (own_tape). Returns the nodes on a shortened tape. */
static size_t own_tapes(const pf_surface *surf, int placement)
{
    ism_sampler s;
    ism_tape *t = pf_build_sampler(surf, &s);
    ism_grid g = level_grid(placement);
    const size_t nroots = (size_t)1 << ISM_ROOT_MEMO_BITS;
    const size_t npoints = (size_t)1 << ISM_CORNER_MEMO_BITS;
    ism_point_entry *points[2] = {calloc(npoints, sizeof **points),
                                  calloc(npoints, sizeof **points)};
    ism_root_entry *memo[2] = {calloc(nroots, sizeof **memo), calloc(nroots, sizeof **memo)};
    ism_leaf_tapes_cache *cache = calloc(1, sizeof *cache);
    ism_tape *scratch = ism_tape_new_like(t);
    ism_leaf_tapes lt;
    cr_assert(points[0] && points[1] && memo[0] && memo[1] && cache && scratch &&
              ism_leaf_tapes_init(&lt, NULL));
    ism_root_log log[2] = {{NULL, 0, 0, (size_t)1 << 24}, {NULL, 0, 0, (size_t)1 << 24}};
    ism_node_memo nm[2] = {{memo[0], NULL, NULL, &log[0]}, {memo[1], NULL, NULL, &log[1]}};
    ism_root_entry *sorted = NULL;
    size_t sorted_cap = 0;
    const int side = 1 << LEVEL, step = 1 << (DEPTH - LEVEL);
    ism_node nodes[CHUNK];
    const ism_node *at[CHUNK];
    const ism_tape *tape[CHUNK];
    ism_corners k[CHUNK];
    bool have[CHUNK];
    size_t n = 0, shortened = 0, mixed = 0, stale = 0;
    for (int i = 0; i < side * side * side; i++) {
        nodes[n] = (ism_node){{(i % side) * step, (i / side % side) * step,
                               (i / side / side) * step}, -1, LEVEL, ISM_NODE_LEAF, 0, 0};
        at[n] = &nodes[n];
        tape[n] = own_tape(&g, &nodes[n], &s, scratch, &lt, cache, (size_t)i);
        shortened += tape[n] && tape[n] != t;
        if (++n < CHUNK && i + 1 < side * side * side)
            continue;
        for (size_t j = 1; j < n; j++)
            if (tape[j] != tape[0]) {
                mixed++; /* the call groups the nodes tape by tape (prefetch_roots) */
                break;
            }
        ism_prefetch_nodes(&nm[0], points[0], ISM_CORNER_MEMO_BITS, &g, at, NULL, n, &s, k,
                           have);
        ism_prefetch_nodes(&nm[1], points[1], ISM_CORNER_MEMO_BITS, &g, at, tape, n, &s, k,
                           have);
        /* each slot holds the root its own prefetch logged for its edge */
        for (int w = 0; w < 2; w++) {
            cr_assert(ism_grow((void **)&sorted, &sorted_cap, log[w].n + 1, sizeof *sorted, 256));
            stale += stale_slots(memo[w], nroots, &log[w], sorted);
        }
        n = 0;
    }
    size_t na = distinct(&log[0]), nb = distinct(&log[1]);
    cr_expect_eq(na, nb, "%s: %zu edges searched on f, %zu on own tapes", surf->expr, na, nb);
    for (size_t i = 0; i < na && i < nb; i++)
        cr_expect(log[0].v[i].a == log[1].v[i].a && log[0].v[i].b == log[1].v[i].b &&
                      memcmp(&log[0].v[i].t, &log[1].v[i].t, sizeof(double)) == 0,
                  "%s: edge %zu: root %.17g on f, %.17g on its own tape", surf->expr, i,
                  log[0].v[i].t, log[1].v[i].t);
    cr_expect_eq(stale, 0, "%s: %zu memo slots hold a root other than the logged one",
                 surf->expr, stale);
    /* not vacuous: shortened tapes, chunks of several tapes, and roots compared */
    cr_expect(shortened > 100 && mixed > 4 && na > 100,
              "%s: %zu nodes on shortened tapes, %zu mixed chunks, %zu roots", surf->expr,
              shortened, mixed, na);
    for (int w = 0; w < 2; w++) {
        ism_root_log_free(&log[w]);
        free(points[w]);
        free(memo[w]);
    }
    ism_leaf_tapes_free(&lt);
    free(cache);
    free(sorted);
    ism_tape_free(scratch);
    ism_eval_ws_free(s.ws);
    ism_tape_free(t);
    return shortened;
}

Test(level_prefetch, roots_on_own_shortened_tapes_as_on_f)
{
    const pf_surface *surfs[] = {&pf_barth_sextic, &pf_gyroid_ball};
    for (int sf = 0; sf < 2; sf++)
        for (int p = -1; p < 2; p++) /* own box, +1e-3, irrational (pf_sweep_box) */
            own_tapes(surfs[sf], p);
}
