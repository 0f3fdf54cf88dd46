/* dual_walk.c — the dual mesher's minimal-edge walk (dual_walk.h): cell, face and edge
 * calls down the octree (the tree of dual_tree.h) to the leaves round each edge, a quad
 * across every crossed minimal edge; the calls below WALK_SPLIT_LEVEL put off to the pool and
 * joined in a fixed order, and kept as a memo that a later round's unchanged subtrees take
 * their quads from. */
#include "core/octree/dual_walk.h"
#include "core/octree/dual_crease.h"

#include <stdlib.h>
#include <string.h>

/* The tree walk's calls on nodes of this level or below run on the pool: at the default
 * minimum depth 3, up to 512 cells and their faces and edges, enough tasks for a few
 * threads to share evenly. */
#define WALK_SPLIT_LEVEL 3

/* The cells round an edge along axis e, in counter-clockwise order seen from +e: their
 * offsets along axes e + 1 and e + 2 (mod 3). */
static const int AROUND_U[4] = {0, 1, 1, 0};
static const int AROUND_V[4] = {0, 0, 1, 1};

/* The axis after axis a (mod 3): a table, not a % (the walk's children are read by it). */
static const int NEXT_AXIS[3] = {1, 2, 0};

/* The child index of the octant whose bit along axis e is h, along the next axis u, along
 * the one after v (0: low half, 1: high). */
static inline int child_at(int e, int h, int u, int v)
{
    return h << e | u << NEXT_AXIS[e] | v << NEXT_AXIS[NEXT_AXIS[e]];
}

/* A call of the tree walk put off to run on the pool: a cell (c[0]), a face (c[0] below
 * c[1] across axis) or an edge (c[0..4) round an edge along axis). */
typedef struct walk_call {
    int32_t c[4];
    int8_t kind, axis;
} walk_call;

enum { WALK_CELL, WALK_FACE, WALK_EDGE };

/* The walk's state: the tree, where quads go, and — on the calling thread only — the calls
 * reaching WALK_SPLIT_LEVEL, put off instead of made. */
typedef struct walk {
    const dual *d;
    quads *out;
    bool deferring;   /* false: make every call */
    walk_call *defer;
    size_t nd, capd;
    bool nomem;
    worker *w;        /* evaluates f for edges beside a pair leaf (edge_quad) */
} walk;

/* Put off a call on nodes c[0..n) when the walk defers and one of them reaches the level;
 * true when it did (or could not: then nomem). */
static bool put_off(walk *wk, int kind, int axis, const int32_t *c, int n)
{
    if (!wk->deferring)
        return false;
    int level = 0;
    for (int k = 0; k < n; k++)
        level = wk->d->n[c[k]].level > level ? wk->d->n[c[k]].level : level;
    if (level < WALK_SPLIT_LEVEL)
        return false;
    if (!grow((void **)&wk->defer, &wk->capd, wk->nd + 1, sizeof *wk->defer)) {
        wk->nomem = true;
        return true;
    }
    walk_call *call = &wk->defer[wk->nd++];
    memset(call, 0, sizeof *call);
    memcpy(call->c, c, (size_t)n * sizeof *c);
    call->kind = (int8_t)kind;
    call->axis = (int8_t)axis;
    return true;
}

/* The quad v[0..4) into out; a repeated vertex (two sides of the edge in one larger leaf)
 * leaves a triangle. */
static void add_quad(quads *out, const uint32_t v[4])
{
    uint32_t u[4] = {0, 0, 0, UINT32_MAX};
    int m = 0;
    for (int k = 0; k < 4; k++)
        if (v[k] != v[(k + 3) % 4])
            u[m++] = v[k];
    if (m < 3)
        return;
    if (!grow((void **)&out->q, &out->cap, out->n + 1, 4 * sizeof *out->q)) {
        out->nomem = true;
        return;
    }
    memcpy(&out->q[4 * out->n++], u, sizeof u);
}

/* Which branch's zero (dual_crease.h ism_dual_edge_branch) the root of node n's edge c0 -> c1
 * is; -1 when it cannot tell. */
static int pair_edge_branch(const dual *d, worker *w, const dnode *n, int c0, int c1)
{
    double p[2][3], bv[2][2];
    for (int j = 0; j < 2; j++) {
        corner_point(d, n, j ? c1 : c0, p[j]);
        w->s.n_point++;
        if (!ism_eval_top_values(w->s.tape, w->s.ws, p[j][0], p[j][1], p[j][2], bv[j]))
            return -1;
    }
    return ism_dual_edge_branch(&w->s, p[0], p[1], bv[0], bv[1]);
}

/* Four leaves round an edge along axis e: the quad across the smallest one's edge there when
 * f changes sign along it (beside a pair leaf, its vertex of the edge's branch). */
static void edge_quad(walk *wk, const int32_t c[4], int e)
{
    const dual *d = wk->d;
    int deepest = 0;
    for (int k = 1; k < 4; k++)
        if (d->n[c[k]].level > d->n[c[deepest]].level)
            deepest = k;
    const dnode *n = &d->n[c[deepest]];
    int c0 = child_at(e, 0, 1 - AROUND_U[deepest], 1 - AROUND_V[deepest]), c1 = c0 | 1 << e;
    bool in0 = n->f[c0] < 0, in1 = n->f[c1] < 0;
    if (in0 == in1)
        return;
    int branch = 0; /* beside a pair leaf: the branch whose zero the edge's root is */
    for (int k = 0; k < 4; k++)
        if (d->n[c[k]].kind == DN_PAIR) {
            branch = pair_edge_branch(d, wk->w, n, c0, c1);
            if (branch < 0) {
                wk->out->bad = true;
                return;
            }
            break;
        }
    uint32_t v[4];
    for (int k = 0; k < 4; k++) {
        int32_t vert = branch && d->n[c[k]].kind == DN_PAIR ? d->n[c[k]].vert2 : d->n[c[k]].vert;
        if (vert < 0) {
            wk->out->bad = true; /* cannot happen for plain leaves; never emit a hole */
            return;
        }
        v[in0 ? k : 3 - k] = (uint32_t)vert;
    }
    add_quad(wk->out, v);
}

static bool is_leaf(const dual *d, int32_t i) { return d->n[i].child < 0; }

/* Node i itself when a leaf, else its child c. */
static int32_t sub(const dual *d, int32_t i, int c)
{
    return is_leaf(d, i) ? i : d->n[i].child + c;
}

static void edge_down(walk *wk, const int32_t c[4], int e);

/* Four nodes round an edge along axis e: the quad when all are leaves, else edge_down. The
 * tests that end most calls are made before the call (here and in face_proc, cell_proc:
 * always inlined), so that only the calls that go on are made (sphere at 0.00714: about half
 * of the walk's calls ended at once, ~25 instructions each to enter and leave). */
static inline __attribute__((always_inline)) void edge_proc(walk *wk, const int32_t c[4], int e)
{
    const dual *d = wk->d;
    if (!d->n[c[0]].surf || !d->n[c[1]].surf || !d->n[c[2]].surf || !d->n[c[3]].surf)
        return; /* a quad needs a surface leaf on every side */
    if (is_leaf(d, c[0]) && is_leaf(d, c[1]) && is_leaf(d, c[2]) && is_leaf(d, c[3]))
        edge_quad(wk, c, e);
    else
        edge_down(wk, c, e);
}

/* edge_down's halves for the axis e, a constant where it is inlined (edge_down): the
 * children's indices fold. */
static inline __attribute__((always_inline)) void edge_halves(walk *wk, const int32_t c[4],
                                                             const int e)
{
    const dual *d = wk->d;
#pragma GCC unroll 2
    for (int h = 0; h < 2; h++) {
        int32_t nc[4];
#pragma GCC unroll 4
        for (int k = 0; k < 4; k++)
            nc[k] = sub(d, c[k], child_at(e, h, 1 - AROUND_U[k], 1 - AROUND_V[k]));
        edge_proc(wk, nc, e);
    }
}

/* edge_proc's nodes, not all leaves: the edge's two halves (edge_halves, one copy an axis). */
static void edge_down(walk *wk, const int32_t c[4], int e)
{
    if (put_off(wk, WALK_EDGE, e, c, 4))
        return;
    if (e == 0)
        edge_halves(wk, c, 0);
    else if (e == 1)
        edge_halves(wk, c, 1);
    else
        edge_halves(wk, c, 2);
}

static void face_down(walk *wk, int32_t c0, int32_t c1, int a);

/* Two nodes sharing a face across axis a (c0 below, c1 above). */
static inline __attribute__((always_inline)) void face_proc(walk *wk, int32_t c0, int32_t c1,
                                                           int a)
{
    const dual *d = wk->d;
    if (d->n[c0].surf && d->n[c1].surf && (!is_leaf(d, c0) || !is_leaf(d, c1)))
        face_down(wk, c0, c1, a);
}

/* face_down's quarters and edges for the axis a, a constant where it is inlined
 * (face_down): the children's indices and the edges' axes fold (the walk's index
 * arithmetic was a third of its own instructions, sphere at E 7.14e-3). */
static inline __attribute__((always_inline)) void face_parts(walk *wk, int32_t c0, int32_t c1,
                                                            const int a)
{
    const dual *d = wk->d;
#pragma GCC unroll 4
    for (int q = 0; q < 4; q++) {
        int lo = child_at(a, 0, q & 1, q >> 1);
        face_proc(wk, sub(d, c0, lo | 1 << a), sub(d, c1, lo), a);
    }
#pragma GCC unroll 2
    for (int j = 1; j < 3; j++) {
        int e = j == 1 ? NEXT_AXIS[a] : NEXT_AXIS[NEXT_AXIS[a]], t = 3 - a - e; /* the edge's
                                                       axis and the face's other axis */
#pragma GCC unroll 2
        for (int h = 0; h < 2; h++) {
            int32_t nc[4];
#pragma GCC unroll 4
            for (int k = 0; k < 4; k++) {
                int ou = AROUND_U[k], ov = AROUND_V[k];
                int oa = NEXT_AXIS[e] == a ? ou : ov, ot = NEXT_AXIS[e] == a ? ov : ou;
                nc[k] = sub(d, oa ? c1 : c0, h << e | (1 - oa) << a | ot << t);
            }
            edge_proc(wk, nc, e);
        }
    }
}

/* face_proc's nodes, not both leaves: the face's four quarters and four edges (face_parts,
 * one copy an axis). */
static void face_down(walk *wk, int32_t c0, int32_t c1, int a)
{
    int32_t pair[2] = {c0, c1};
    if (put_off(wk, WALK_FACE, a, pair, 2))
        return;
    if (a == 0)
        face_parts(wk, c0, c1, 0);
    else if (a == 1)
        face_parts(wk, c0, c1, 1);
    else
        face_parts(wk, c0, c1, 2);
}

static void cell_down(walk *wk, int32_t i);

static inline __attribute__((always_inline)) void cell_proc(walk *wk, int32_t i)
{
    if (!is_leaf(wk->d, i) && wk->d->n[i].surf)
        cell_down(wk, i);
}

/* cell_proc's node, not a leaf: its children, its inner faces and its inner edges. */
static void cell_down(walk *wk, int32_t i)
{
    const dual *d = wk->d;
    if (put_off(wk, WALK_CELL, 0, &i, 1))
        return;
    int32_t first = d->n[i].child;
    for (int c = 0; c < 8; c++)
        cell_proc(wk, first + c);
#pragma GCC unroll 3 /* the axes constant: the children's offsets fold */
    for (int a = 0; a < 3; a++)
#pragma GCC unroll 4
        for (int q = 0; q < 4; q++) {
            int32_t lo = first + child_at(a, 0, q & 1, q >> 1);
            face_proc(wk, lo, lo + (1 << a), a);
        }
#pragma GCC unroll 3
    for (int e = 0; e < 3; e++)
#pragma GCC unroll 2
        for (int h = 0; h < 2; h++) {
            int32_t nc[4];
#pragma GCC unroll 4
            for (int k = 0; k < 4; k++)
                nc[k] = first + child_at(e, h, AROUND_U[k], AROUND_V[k]);
            edge_proc(wk, nc, e);
        }
}

/* Where put-off call k's quads went: thread's scratch (walk_job), from quad `at`, n of them. */
typedef struct walk_part {
    size_t at, n;
    int thread;
} walk_part;

/* The put-off walk calls (calls) to make, todo[0..), each into its thread's scratch quads
 * (one array a thread: the tasks of a thread run one after another), where part[k] says. */
typedef struct walk_job {
    dual *d;
    const walk_call *calls;
    quads *scratch;
    walk_part *part;
    const size_t *todo;
} walk_job;

/* Put-off walk call todo[t] made into its thread's scratch. */
static void walk_task(void *ctx, size_t t, int thread)
{
    walk_job *job = ctx;
    size_t k = job->todo[t];
    const walk_call *call = &job->calls[k];
    quads *out = &job->scratch[thread];
    size_t at = out->n;
    walk wk = {job->d, out, false, NULL, 0, 0, false, &job->d->w[thread]};
    if (call->kind == WALK_CELL)
        cell_proc(&wk, call->c[0]);
    else if (call->kind == WALK_FACE)
        face_proc(&wk, call->c[0], call->c[1], call->axis);
    else
        edge_proc(&wk, call->c, call->axis);
    job->part[k] = (walk_part){at, out->n - at, thread};
}

/* The memo's quads and calls freed (the struct left for the caller to zero or refill). */
void ism_dual_walk_memo_free(walk_memo *m)
{
    free(m->q);
    free(m->at);
    free(m->calls);
}

/* By node: 1 when its subtree changed since the memo's walk (a node added since, or one
 * with a child that did); NULL when out of memory. Children come after their parent. */
static uint8_t *changed_nodes(const dual *d)
{
    uint8_t *ch = malloc(d->nn ? d->nn : 1);
    size_t old = d->memo.nodes;
    for (size_t i = d->nn; ch && i-- > 0;) {
        const dnode *n = &d->n[i];
        uint8_t c = i >= old || (n->child >= 0 && (size_t)n->child >= old);
        for (int k = 0; !c && n->child >= 0 && k < 8; k++)
            c = ch[n->child + k];
        ch[i] = c;
    }
    return ch;
}

/* Put-off call k of this round's walk (calls[0..n)) as the memo's call k, on nodes whose
 * subtrees have not changed (ch): its quads are the memo's. The calls are the same list
 * while the walk's top levels (above WALK_SPLIT_LEVEL) keep their shape. */
static bool memo_holds(const dual *d, const uint8_t *ch, const walk_call *calls, size_t n,
                       size_t k)
{
    const walk_memo *m = &d->memo;
    if (!ch || !m->calls || m->n != n || memcmp(&m->calls[k], &calls[k], sizeof calls[k]))
        return false;
    int nodes = calls[k].kind == WALK_CELL ? 1 : calls[k].kind == WALK_FACE ? 2 : 4;
    for (int j = 0; j < nodes; j++)
        if (ch[calls[k].c[j]])
            return false;
    return true;
}

/* The put-off calls' quads (calls[0..n): held ones from the old memo, the others from the
 * threads' scratch as part says) after the top levels' in d->q, in the calls' order; then
 * kept as the memo (calls taken), each call's first quad in at. False when out of memory. */
static bool join_parts(dual *d, walk_call *calls, size_t n, const uint8_t *held,
                       const quads *scratch, const walk_part *part)
{
    walk_memo *old = &d->memo, memo = {calls, NULL, NULL, n, d->nn};
    size_t base = d->q.n, total = 0;
    for (size_t k = 0; k < n; k++)
        total += held[k] ? old->at[k + 1] - old->at[k] : part[k].n;
    memo.at = malloc((n + 1) * sizeof *memo.at);
    memo.q = malloc((total ? total : 1) * 4 * sizeof *memo.q);
    bool ok = memo.at && memo.q &&
              grow((void **)&d->q.q, &d->q.cap, base + total, 4 * sizeof *d->q.q);
    for (size_t k = 0, m = 0; ok && k < n; k++) {
        const uint32_t *from = held[k] ? &old->q[4 * old->at[k]]
                                       : &scratch[part[k].thread].q[4 * part[k].at];
        size_t c = held[k] ? old->at[k + 1] - old->at[k] : part[k].n;
        memo.at[k] = m;
        if (c) /* a call with no quads may have no array: memcpy wants non-null even for 0 */
            memcpy(&memo.q[4 * m], from, 4 * c * sizeof *from);
        m += c;
    }
    if (ok) {
        memo.at[n] = total;
        if (total) /* d->q.q is still NULL when no round has written a quad */
            memcpy(&d->q.q[4 * base], memo.q, 4 * total * sizeof *memo.q);
        d->q.n = base + total;
    }
    ism_dual_walk_memo_free(old);
    if (!ok) {
        free(memo.q);
        free(memo.at);
        free(calls);
        memset(&memo, 0, sizeof memo);
    }
    *old = memo;
    return ok;
}

/* The round's quads into d->q: the walk's top levels on this thread, the calls below them
 * on the pool — but for those the last round's memo holds — their quads joined in the
 * calls' order (the same on any number of threads), and kept as the next round's memo.
 * The pool's calls write into one scratch array a thread, not one array a call (sphere at
 * 0.00714: 506 calls, ~1 quad each; their arrays cost ~190K instructions of malloc, realloc
 * and free, 2.3% of the run). */
void ism_dual_make_quads(dual *d)
{
    d->q.n = 0;
    walk wk = {d, &d->q, true, NULL, 0, 0, false, &d->w[0]};
    cell_proc(&wk, 0);
    size_t nd = wk.nd, nt = 0, nw = d->nw > 0 ? (size_t)d->nw : 1;
    quads *scratch = calloc(nw, sizeof *scratch);
    walk_part *part = malloc((nd ? nd : 1) * sizeof *part);
    size_t *todo = malloc((nd ? nd : 1) * sizeof *todo);
    uint8_t *held = malloc(nd ? nd : 1);
    uint8_t *ch = d->memo.calls ? changed_nodes(d) : NULL;
    bool ok = scratch && part && todo && held && !wk.nomem;
    for (size_t k = 0; ok && k < nd; k++) {
        held[k] = memo_holds(d, ch, wk.defer, nd, k);
        if (!held[k])
            todo[nt++] = k;
    }
    free(ch);
    if (ok) {
        walk_job job = {d, wk.defer, scratch, part, todo};
        ism_pool_for(d->pool, nt, walk_task, &job, NULL);
        for (size_t t = 0; t < nw; t++) {
            ok &= !scratch[t].nomem;
            if (scratch[t].bad) /* a crossed edge without a vertex (edge_quad) */
                decline(d, ISM_DUAL_WHY_OPEN_EDGE);
        }
    }
    if (ok && !d->q.nomem)
        ok = join_parts(d, wk.defer, nd, held, scratch, part); /* takes wk.defer */
    else
        free(wk.defer);
    d->nomem |= !ok || d->q.nomem;
    if (d->q.bad)
        decline(d, ISM_DUAL_WHY_OPEN_EDGE);
    for (size_t t = 0; scratch && t < nw; t++)
        free(scratch[t].q);
    free(scratch);
    free(part);
    free(todo);
    free(held);
}
