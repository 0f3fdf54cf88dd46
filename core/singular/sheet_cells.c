/* sheet_cells.c — the candidate cells of sheet_cells.h. The box is cut into the nodes of
 * level SC_TOP_LEVEL, one task each; a task walks its subtree depth first with an explicit
 * stack, evaluating the eight children of a node in one batched interval call and keeping
 * those whose interval holds 0. A node one level above the finest is a block: its children
 * that survive are filtered on the block's 3×3×3 lattice points (f for all, ∇f where a
 * quiet child needs it). Tasks' lists are joined in task order, so the output does not
 * depend on the thread count. */
#include "core/singular/sheet_cells.h"
#include "core/singular/lattice_key.h"
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Level of the task roots: 64 tasks keep two to eight threads busy on lopsided surfaces. */
#define SC_TOP_LEVEL 2
/* Nodes between two looks at the clock and the cancel flag (a node costs ~1 µs). */
#define SC_POLL_NODES 1024
/* Corner values of one sign smaller than this fraction of the cell's largest |f| are
 * rounding noise, not a sign change: f = g² written out as a polynomial comes out as
 * -1e-17 next to its double zero, where one cell away it is ~1e-5 at depth 9. */
#define SC_SIGN_NOISE 1e-9
/* The mean-value form's margin, relative to its spread: f(c) carries rounding error that
 * the outward-rounded gradient enclosure does not; a node holding a zero of f has
 * |f(c)| ≤ spread exactly, so excluding only past (1 + 1e-6)·spread keeps every such node
 * while the spurious ones (|f(c)| several times the spread) still go. */
#define SC_MEAN_VALUE_SLACK 1e-6
/* Blocks of given cells per task (ism_sheet_cells_filter). */
#define SC_GIVEN_CHUNK 64
/* Kinks in one box up to which each choice of branches is tried (2^3 evaluations). */
#define SC_MAX_FORCED_KINKS 3
/* Gradients remembered per thread (direct-mapped by lattice point, 1 MiB): neighbouring
 * blocks share faces, and the depth-first walk visits them one after another. */
#define SC_MEMO_BITS 15

typedef struct sc_memo_entry {
    uint64_t key;    /* lattice key + 1; 0 = empty */
    double g[3];
} sc_memo_entry;

typedef struct sc_node {
    int32_t org[3];
    int level;
} sc_node;

typedef struct sc_thread {
    ism_eval_ws *ws;
    ism_ivjet_ws *jws;
    uint8_t *kinks, *force;                  /* a byte per instruction of f */
    sc_memo_entry *memo;                     /* gradients of f (pure: never stale) */
    ism_tape *tapes[ISM_GRID_MAX_DEPTH + 1]; /* shortened tape of the node being expanded */
} sc_thread;

typedef struct sc_task {
    uint64_t *cells;
    size_t n, cap;
    uint64_t intervals, gradient_boxes, zero_cells, points, gradients;
} sc_task;

/* A block of the lattice (level depth - 1) and which of its eight cells were given. */
typedef struct sc_given {
    uint64_t key;  /* lattice key of its lowest corner */
    uint8_t mask;
} sc_given;

typedef struct sc_run {
    const ism_sheet_cells_params *p;
    sc_thread *threads;
    sc_node *roots;           /* the task roots of a search, or */
    sc_given *blocks;         /* the blocks of given cells, SC_GIVEN_CHUNK a task */
    size_t nblocks;
    sc_task *tasks;
    atomic_size_t kept;       /* cells listed so far, all tasks (the budget) */
    atomic_int status;        /* first enum ism_sc_status other than OK */
} sc_run;

/* The 3×3×3 lattice points of a block; point (i, j, k) is index i + 3j + 9k. */
typedef struct sc_block {
    int32_t org[3];
    double x[27], y[27], z[27], f[27], g[27][3];
    uint32_t have_g; /* bit per point */
} sc_block;

static void stop(sc_run *r, enum ism_sc_status st)
{
    int expected = ISM_SC_OK;
    atomic_compare_exchange_strong(&r->status, &expected, (int)st);
}

static bool push_cell(sc_run *r, sc_task *t, const int32_t org[3])
{
    if (atomic_fetch_add(&r->kept, 1) + 1 > r->p->max_cells) {
        stop(r, ISM_SC_BUDGET);
        return false;
    }
    if (t->n == t->cap) {
        size_t c = t->cap ? 2 * t->cap : 256;
        uint64_t *v = realloc(t->cells, c * sizeof *v);
        if (!v) {
            stop(r, ISM_SC_NO_MEMORY);
            return false;
        }
        t->cells = v;
        t->cap = c;
    }
    t->cells[t->n++] = ism_lkey(org[0], org[1], org[2]);
    return true;
}

static ism_interval axis_range(const ism_grid *g, int a, int32_t org, int32_t steps)
{
    return (ism_interval){ism_grid_coord(g, a, org), ism_grid_coord(g, a, org + steps)};
}

/* The tape valid inside nd (shortened from `in` when the node decides some min/max). */
static const ism_tape *node_tape(sc_thread *th, const ism_grid *g, const sc_node *nd,
                                 const ism_tape *in, sc_task *t)
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    ism_interval x = axis_range(g, 0, nd->org[0], s), y = axis_range(g, 1, nd->org[1], s),
                 z = axis_range(g, 2, nd->org[2], s), range;
    ism_tape *out = th->tapes[nd->level];
    t->intervals++;
    return out && ism_tape_shorten(in, th->ws, x, y, z, out, &range) ? out : in;
}

/* True when no component of the gradient enclosure holds 0. */
static bool gradient_nonzero(const ism_ivgrad *jet)
{
    for (int a = 0; a < 3; a++)
        if (!(jet->d[a].lo <= 0 && jet->d[a].hi >= 0))
            return true;
    return false;
}

/* Where min/max/abs may switch branch inside the box (kinks), f has no gradient there and
 * the free enclosure is the whole line. A double sheet point needs a smooth branch whose
 * gradient vanishes, so: true when every choice of branch at the listed kinks gives a
 * gradient that cannot vanish where that choice is active. */
static bool branches_nonzero(sc_thread *th, const ism_tape *t, const ism_interval box[3])
{
    size_t len = ism_tape_length(t), at[SC_MAX_FORCED_KINKS], nk = 0;
    for (size_t i = 0; i < len; i++) {
        th->force[i] = ISM_BRANCH_FREE;
        if (th->kinks[i])
            at[nk++] = i;
    }
    for (unsigned pick = 0; pick < 1u << nk; pick++) {
        for (size_t j = 0; j < nk; j++)
            th->force[at[j]] = pick >> j & 1 ? ISM_BRANCH_B : ISM_BRANCH_A;
        ism_ivgrad jet;
        if (ism_eval_interval_grad(t, th->jws, box, th->force, NULL, &jet) == (size_t)-1
            || !gradient_nonzero(&jet))
            return false;
    }
    return true;
}

/* True when intervals prove that f or ∇f has no zero in nd: no double sheet there (f = 0
 * and ∇f = 0 all along one). Near a sign-changing surface ∇f is bounded away from 0, so
 * this ends the walk a few levels above the finest. */
static bool excluded(sc_thread *th, const ism_grid *g, const sc_node *nd, const ism_tape *t,
                     sc_task *task)
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    ism_interval box[3];
    for (int a = 0; a < 3; a++)
        box[a] = axis_range(g, a, nd->org[a], s);
    ism_ivgrad jet;
    task->gradient_boxes++;
    size_t kinks = ism_eval_interval_grad(t, th->jws, box, NULL, th->kinks, &jet);
    if (kinks == (size_t)-1)
        return false;
    if (!(jet.v.lo <= 0 && jet.v.hi >= 0) || gradient_nonzero(&jet))
        return true;
    if (kinks > 0)
        return kinks <= SC_MAX_FORCED_KINKS && branches_nonzero(th, t, box);
    double c[3], spread = 0;
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5 * (box[a].lo + box[a].hi);
        spread += fmax(-jet.d[a].lo, jet.d[a].hi) * 0.5 * (box[a].hi - box[a].lo);
    }
    /* mean-value form: f(box) ⊆ f(c) + ∇f(box)·(box − c) ⊆ f(c) ± spread */
    double fc = ism_eval_point(t, th->ws, c[0], c[1], c[2]);
    task->points++;
    return fabs(fc) > (1 + SC_MEAN_VALUE_SLACK) * spread;
}

/* Bit c set when child c of nd has an interval holding 0. */
static unsigned children_mask(sc_thread *th, const ism_grid *g, const sc_node *nd,
                              const ism_tape *t, sc_task *task)
{
    int32_t s = ism_grid_cell_steps(g, nd->level + 1);
    ism_interval x[8], y[8], z[8], out[8];
    for (int c = 0; c < 8; c++) {
        x[c] = axis_range(g, 0, nd->org[0] + (c & 1) * s, s);
        y[c] = axis_range(g, 1, nd->org[1] + ((c >> 1) & 1) * s, s);
        z[c] = axis_range(g, 2, nd->org[2] + ((c >> 2) & 1) * s, s);
    }
    ism_eval_interval_batch(t, th->ws, x, y, z, out, 8);
    task->intervals += 8;
    unsigned mask = 0;
    for (int c = 0; c < 8; c++)
        if (out[c].lo <= 0 && out[c].hi >= 0)
            mask |= 1u << c;
    return mask;
}

/* Index in the block of corner k of child c. */
static int block_point(int c, int k)
{
    return ((c & 1) + (k & 1)) + 3 * (((c >> 1) & 1) + ((k >> 1) & 1))
         + 9 * (((c >> 2) & 1) + ((k >> 2) & 1));
}

static bool quiet(const sc_block *b, int c)
{
    double lo = INFINITY, hi = -INFINITY, big = 0;
    for (int k = 0; k < 8; k++) {
        double f = b->f[block_point(c, k)];
        lo = fmin(lo, f);
        hi = fmax(hi, f);
        big = fmax(big, fabs(f));
    }
    return !(lo < -SC_SIGN_NOISE * big && hi > SC_SIGN_NOISE * big);
}

/* ∇f at block point i, through the thread's memo. */
static void block_gradient(sc_thread *th, const ism_tape *tape, sc_block *b, int i, sc_task *t)
{
    uint64_t key = ism_lkey(b->org[0] + i % 3, b->org[1] + i / 3 % 3, b->org[2] + i / 9) + 1;
    uint64_t h = key * 0x9e3779b97f4a7c15ull;
    sc_memo_entry *e = &th->memo[h >> (64 - SC_MEMO_BITS)];
    if (e->key != key) {
        /* the full tape and a shortened one agree inside the block: either will do */
        ism_eval_gradient(tape, th->ws, b->x[i], b->y[i], b->z[i], e->g);
        e->key = key;
        t->gradients++;
    }
    memcpy(b->g[i], e->g, sizeof e->g);
    b->have_g |= 1u << i;
}

static bool opposed(sc_thread *th, const ism_tape *tape, sc_block *b, int c, sc_task *t)
{
    int idx[8];
    for (int k = 0; k < 8; k++) {
        int i = idx[k] = block_point(c, k);
        if (!(b->have_g >> i & 1))
            block_gradient(th, tape, b, i, t);
    }
    for (int i = 0; i < 8; i++)
        for (int j = i + 1; j < 8; j++) {
            const double *u = b->g[idx[i]], *v = b->g[idx[j]];
            if (u[0] * v[0] + u[1] * v[1] + u[2] * v[2] <= 0)
                return true;
        }
    return false;
}

/* Filters the children of block nd listed in mask and appends those that stay. */
static bool filter_block(sc_run *r, sc_thread *th, const sc_node *nd, const ism_tape *tape,
                         unsigned mask, sc_task *t)
{
    const ism_grid *g = r->p->grid;
    sc_block b;
    b.have_g = 0;
    memcpy(b.org, nd->org, sizeof b.org);
    for (int i = 0; i < 27; i++) {
        b.x[i] = ism_grid_coord(g, 0, nd->org[0] + i % 3);
        b.y[i] = ism_grid_coord(g, 1, nd->org[1] + i / 3 % 3);
        b.z[i] = ism_grid_coord(g, 2, nd->org[2] + i / 9);
    }
    ism_eval_batch(tape, th->ws, b.x, b.y, b.z, b.f, 27);
    t->points += 27;
    for (int c = 0; c < 8; c++) {
        if (!(mask >> c & 1) || !quiet(&b, c) || !opposed(th, tape, &b, c, t))
            continue;
        sc_node cell = {{nd->org[0] + (c & 1), nd->org[1] + ((c >> 1) & 1),
                         nd->org[2] + ((c >> 2) & 1)},
                        nd->level + 1};
        if (excluded(th, g, &cell, tape, t))
            continue;
        const int32_t *org = cell.org;
        if (!push_cell(r, t, org))
            return false;
    }
    return true;
}

static bool keep_going(sc_run *r)
{
    if (atomic_load(&r->status) != ISM_SC_OK)
        return false;
    if (r->p->cancel && *r->p->cancel) {
        stop(r, ISM_SC_CANCELLED);
        return false;
    }
    if (r->p->deadline_ms > 0 && ism_now_ms() > r->p->deadline_ms) {
        stop(r, ISM_SC_DEADLINE);
        return false;
    }
    return true;
}

/* Expands nd: a block's children are filtered, other nodes' children go on the stack (last
 * child on top). Returns the new stack top, or SIZE_MAX to stop. */
static size_t expand(sc_run *r, sc_thread *th, const sc_node *nd, const ism_tape *tape,
                     sc_node *stack, size_t top, sc_task *t)
{
    const ism_grid *g = r->p->grid;
    unsigned mask = children_mask(th, g, nd, tape, t);
    if (nd->level + 1 == g->depth) {
        t->zero_cells += (uint64_t)__builtin_popcount(mask);
        return mask && !filter_block(r, th, nd, tape, mask, t) ? SIZE_MAX : top;
    }
    int32_t s = ism_grid_cell_steps(g, nd->level + 1);
    for (int c = 7; c >= 0; c--)
        if (mask >> c & 1)
            stack[top++] = (sc_node){{nd->org[0] + (c & 1) * s, nd->org[1] + ((c >> 1) & 1) * s,
                                      nd->org[2] + ((c >> 2) & 1) * s},
                                     nd->level + 1};
    return top;
}

static void run_task(void *ctx, size_t task, int thread)
{
    sc_run *r = ctx;
    sc_thread *th = &r->threads[thread];
    sc_task *t = &r->tasks[task];
    const ism_tape *tapes[ISM_GRID_MAX_DEPTH + 1]; /* tapes[L]: valid inside the node of
                                                      level L - 1 being expanded */
    sc_node stack[8 * (ISM_GRID_MAX_DEPTH + 1)];
    size_t top = 0;
    stack[top++] = r->roots[task];
    tapes[r->roots[task].level] = r->p->f;
    for (unsigned polls = 1; top > 0; polls++) {
        if (polls % SC_POLL_NODES == 0 && !keep_going(r))
            return;
        sc_node nd = stack[--top];
        const ism_tape *sub = node_tape(th, r->p->grid, &nd, tapes[nd.level], t);
        tapes[nd.level + 1] = sub;
        if (excluded(th, r->p->grid, &nd, sub, t))
            continue;
        if ((top = expand(r, th, &nd, sub, stack, top, t)) == SIZE_MAX)
            return;
    }
}

static void free_threads(sc_thread *th, int n)
{
    for (int i = 0; th && i < n; i++) {
        ism_eval_ws_free(th[i].ws);
        ism_ivjet_ws_free(th[i].jws);
        free(th[i].kinks);
        free(th[i].force);
        free(th[i].memo);
        for (int l = 0; l <= ISM_GRID_MAX_DEPTH; l++)
            ism_tape_free(th[i].tapes[l]);
    }
    free(th);
}

static sc_thread *make_threads(const ism_sheet_cells_params *p)
{
    sc_thread *th = calloc((size_t)p->threads, sizeof *th);
    if (!th)
        return NULL;
    for (int i = 0; i < p->threads; i++) {
        th[i].memo = calloc((size_t)1 << SC_MEMO_BITS, sizeof *th[i].memo);
        th[i].jws = ism_ivjet_ws_new(p->f);
        th[i].kinks = malloc(ism_tape_length(p->f) + 1);
        th[i].force = malloc(ism_tape_length(p->f) + 1);
        if (!(th[i].ws = ism_eval_ws_new(p->f)) || !th[i].memo || !th[i].jws || !th[i].kinks
            || !th[i].force) {
            free_threads(th, p->threads);
            return NULL;
        }
        for (int l = 0; l < p->grid->depth; l++)
            if (!(th[i].tapes[l] = ism_tape_new_like(p->f))) {
                free_threads(th, p->threads);
                return NULL;
            }
    }
    return th;
}

/* The nodes of level `top` in x-y-z order. */
static size_t make_roots(int top, const ism_grid *g, sc_node *roots)
{
    int32_t n = 1 << top, s = ism_grid_cell_steps(g, top);
    size_t k = 0;
    for (int32_t i = 0; i < n; i++)
        for (int32_t j = 0; j < n; j++)
            for (int32_t l = 0; l < n; l++)
                roots[k++] = (sc_node){{i * s, j * s, l * s}, top};
    return k;
}

static bool join_tasks(sc_run *r, size_t ntasks, ism_sheet_cells *out)
{
    size_t total = 0;
    for (size_t i = 0; i < ntasks; i++)
        total += r->tasks[i].n;
    out->cells = malloc((total ? total : 1) * sizeof *out->cells);
    if (!out->cells)
        return false;
    for (size_t i = 0; i < ntasks; i++) {
        const sc_task *t = &r->tasks[i];
        if (t->n)
            memcpy(out->cells + out->n, t->cells, t->n * sizeof *out->cells);
        out->n += t->n;
        out->intervals += t->intervals;
        out->gradient_boxes += t->gradient_boxes;
        out->zero_cells += t->zero_cells;
        out->points += t->points;
        out->gradients += t->gradients;
    }
    return true;
}

/* Runs ntasks tasks of fn over r (roots or given blocks set by the caller) and joins their
 * cells into out. */
static enum ism_sc_status run_all(sc_run *r, size_t ntasks, void (*fn)(void *, size_t, int),
                                  ism_sheet_cells *out)
{
    const ism_sheet_cells_params *p = r->p;
    atomic_init(&r->kept, 0);
    atomic_init(&r->status, ISM_SC_OK);
    /* No task, no thread state: its gradient memos (1 MiB each, zeroed) would cost more
     * than the whole stage where no box is left for the sheets (cross-cap: 1.05M of 1.12M
     * instructions). */
    r->threads = ntasks ? make_threads(p) : NULL;
    r->tasks = calloc(ntasks ? ntasks : 1, sizeof *r->tasks);
    if ((r->threads || !ntasks) && r->tasks)
        ism_parallel_for(p->threads, ntasks, fn, r);
    else
        stop(r, ISM_SC_NO_MEMORY);
    if (r->tasks && !join_tasks(r, ntasks, out))
        stop(r, ISM_SC_NO_MEMORY);
    for (size_t i = 0; r->tasks && i < ntasks; i++)
        free(r->tasks[i].cells);
    free(r->tasks);
    free_threads(r->threads, p->threads);
    return (enum ism_sc_status)atomic_load(&r->status);
}

enum ism_sc_status ism_sheet_cells_find(const ism_sheet_cells_params *p, ism_sheet_cells *out)
{
    memset(out, 0, sizeof *out);
    int top = p->grid->depth - 1 < SC_TOP_LEVEL ? p->grid->depth - 1 : SC_TOP_LEVEL;
    sc_node roots[1 << (3 * SC_TOP_LEVEL)];
    sc_run r = {.p = p, .roots = roots};
    return run_all(&r, make_roots(top, p->grid, roots), run_task, out);
}

static void given_task(void *ctx, size_t task, int thread)
{
    sc_run *r = ctx;
    size_t end = (task + 1) * SC_GIVEN_CHUNK < r->nblocks ? (task + 1) * SC_GIVEN_CHUNK
                                                          : r->nblocks;
    if (!keep_going(r))
        return;
    for (size_t i = task * SC_GIVEN_CHUNK; i < end; i++) {
        sc_node nd = {{0, 0, 0}, r->p->grid->depth - 1};
        ism_lkey_unpack(r->blocks[i].key, nd.org);
        if (!filter_block(r, &r->threads[thread], &nd, r->p->f, r->blocks[i].mask,
                          &r->tasks[task]))
            return;
    }
}

static int cmp_block(const void *a, const void *b)
{
    const sc_given *x = a, *y = b;
    return (x->key > y->key) - (x->key < y->key);
}

enum ism_sc_status ism_sheet_cells_filter(const ism_sheet_cells_params *p, const uint64_t *cells,
                                          size_t n, ism_sheet_cells *out)
{
    memset(out, 0, sizeof *out);
    sc_given *b = malloc((n ? n : 1) * sizeof *b);
    if (!b)
        return ISM_SC_NO_MEMORY;
    const uint64_t even = ~(((uint64_t)1 << (2 * ISM_LKEY_BITS)) | ((uint64_t)1 << ISM_LKEY_BITS) | 1);
    for (size_t i = 0; i < n; i++) { /* the block (level depth - 1) and child of each cell */
        int32_t v[3];
        ism_lkey_unpack(cells[i], v);
        b[i] = (sc_given){cells[i] & even, (uint8_t)(1u << ((v[0] & 1) | (v[1] & 1) << 1 | (v[2] & 1) << 2))};
    }
    qsort(b, n, sizeof *b, cmp_block);
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (m && b[m - 1].key == b[i].key)
            b[m - 1].mask |= b[i].mask;
        else
            b[m++] = b[i];
    }
    sc_run r = {.p = p, .blocks = b, .nblocks = m};
    enum ism_sc_status st = run_all(&r, (m + SC_GIVEN_CHUNK - 1) / SC_GIVEN_CHUNK, given_task, out);
    free(b);
    return st;
}
