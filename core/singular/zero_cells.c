/* zero_cells.c — the interval octree of zero_cells.h: the box is cut into the nodes of level
 * ZC_TOP_LEVEL, one task each; a task walks its subtree depth first with an explicit stack,
 * evaluating the eight children of a node in one batched interval call and keeping those
 * whose interval holds 0. Tasks' lists are joined in task order, so the output does not
 * depend on the thread count. */
#include "core/singular/zero_cells.h"
#include "core/singular/lattice_key.h"
#include "core/eval/eval.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Level of the task roots: 64 tasks keep two to eight threads busy on lopsided surfaces. */
#define ZC_TOP_LEVEL 2
/* Nodes between two looks at the clock and the cancel flag (a node costs ~1 µs). */
#define ZC_POLL_NODES 1024

typedef struct zc_node {
    int32_t org[3];
    int level;
} zc_node;

typedef struct zc_thread {
    ism_eval_ws *ws;
    ism_tape *tapes[ISM_GRID_MAX_DEPTH + 1]; /* shortened tape of the node being expanded */
} zc_thread;

typedef struct zc_task {
    uint64_t *cells;
    size_t n, cap;
    uint64_t visited;
} zc_task;

typedef struct zc_run {
    const ism_zero_cells_params *p;
    zc_thread *threads;
    zc_node *roots;
    zc_task *tasks;
    atomic_size_t total;  /* cells found so far, all tasks */
    atomic_int status;    /* first enum ism_zc_status other than OK */
} zc_run;

static void stop(zc_run *r, enum ism_zc_status st)
{
    int expected = ISM_ZC_OK;
    atomic_compare_exchange_strong(&r->status, &expected, (int)st);
}

static bool push_cell(zc_run *r, zc_task *t, const zc_node *nd)
{
    if (atomic_fetch_add(&r->total, 1) + 1 > r->p->max_cells) {
        stop(r, ISM_ZC_BUDGET);
        return false;
    }
    if (t->n == t->cap) {
        size_t c = t->cap ? 2 * t->cap : 256;
        uint64_t *v = realloc(t->cells, c * sizeof *v);
        if (!v) {
            stop(r, ISM_ZC_NO_MEMORY);
            return false;
        }
        t->cells = v;
        t->cap = c;
    }
    t->cells[t->n++] = ism_lkey(nd->org[0], nd->org[1], nd->org[2]);
    return true;
}

static ism_interval axis_range(const ism_grid *g, int a, int32_t org, int32_t steps)
{
    return (ism_interval){ism_grid_coord(g, a, org), ism_grid_coord(g, a, org + steps)};
}

/* The tape valid inside nd (shortened from `in` when the node decides some min/max). */
static const ism_tape *node_tape(zc_thread *th, const ism_grid *g, const zc_node *nd,
                                 const ism_tape *in)
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    ism_interval x = axis_range(g, 0, nd->org[0], s), y = axis_range(g, 1, nd->org[1], s),
                 z = axis_range(g, 2, nd->org[2], s), range;
    ism_tape *out = th->tapes[nd->level];
    return out && ism_tape_shorten(in, th->ws, x, y, z, out, &range) ? out : in;
}

/* Pushes the children of nd whose interval holds 0 onto the stack (last child on top). */
static size_t expand(zc_thread *th, const ism_grid *g, const zc_node *nd, const ism_tape *t,
                     zc_node *stack, size_t top)
{
    int32_t s = ism_grid_cell_steps(g, nd->level + 1);
    ism_interval x[8], y[8], z[8], out[8];
    for (int c = 0; c < 8; c++) {
        x[c] = axis_range(g, 0, nd->org[0] + (c & 1) * s, s);
        y[c] = axis_range(g, 1, nd->org[1] + ((c >> 1) & 1) * s, s);
        z[c] = axis_range(g, 2, nd->org[2] + ((c >> 2) & 1) * s, s);
    }
    ism_eval_interval_batch(t, th->ws, x, y, z, out, 8);
    for (int c = 7; c >= 0; c--)
        if (out[c].lo <= 0 && out[c].hi >= 0)
            stack[top++] = (zc_node){{nd->org[0] + (c & 1) * s, nd->org[1] + ((c >> 1) & 1) * s,
                                      nd->org[2] + ((c >> 2) & 1) * s},
                                     nd->level + 1};
    return top;
}

static bool keep_going(zc_run *r)
{
    if (atomic_load(&r->status) != ISM_ZC_OK)
        return false;
    if (r->p->cancel && *r->p->cancel) {
        stop(r, ISM_ZC_CANCELLED);
        return false;
    }
    if (r->p->deadline_ms > 0 && ism_now_ms() > r->p->deadline_ms) {
        stop(r, ISM_ZC_DEADLINE);
        return false;
    }
    return true;
}

static void run_task(void *ctx, size_t task, int thread)
{
    zc_run *r = ctx;
    const ism_grid *g = r->p->grid;
    zc_thread *th = &r->threads[thread];
    zc_task *t = &r->tasks[task];
    const ism_tape *tapes[ISM_GRID_MAX_DEPTH + 2]; /* tapes[L + 1]: valid below level L */
    zc_node stack[8 * (ISM_GRID_MAX_DEPTH + 1)];
    size_t top = 0;
    zc_node root = r->roots[task];
    ism_interval x = axis_range(g, 0, root.org[0], ism_grid_cell_steps(g, root.level));
    ism_interval y = axis_range(g, 1, root.org[1], ism_grid_cell_steps(g, root.level));
    ism_interval z = axis_range(g, 2, root.org[2], ism_grid_cell_steps(g, root.level));
    ism_interval range = ism_eval_interval(r->p->f, th->ws, x, y, z);
    t->visited++;
    if (!(range.lo <= 0 && range.hi >= 0))
        return;
    tapes[root.level] = r->p->f;
    stack[top++] = root;
    for (unsigned polls = 1; top > 0; polls++) {
        if (polls % ZC_POLL_NODES == 0 && !keep_going(r))
            return;
        zc_node nd = stack[--top];
        if (nd.level == g->depth) {
            if (!push_cell(r, t, &nd))
                return;
            continue;
        }
        const ism_tape *sub = node_tape(th, g, &nd, tapes[nd.level]);
        tapes[nd.level + 1] = sub;
        top = expand(th, g, &nd, sub, stack, top);
        t->visited += 8;
    }
}

static void free_threads(zc_thread *th, int n)
{
    for (int i = 0; th && i < n; i++) {
        ism_eval_ws_free(th[i].ws);
        for (int l = 0; l <= ISM_GRID_MAX_DEPTH; l++)
            ism_tape_free(th[i].tapes[l]);
    }
    free(th);
}

static zc_thread *make_threads(const ism_zero_cells_params *p)
{
    zc_thread *th = calloc((size_t)p->threads, sizeof *th);
    if (!th)
        return NULL;
    for (int i = 0; i < p->threads; i++) {
        if (!(th[i].ws = ism_eval_ws_new(p->f))) {
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

/* The nodes of level `top` in z-y-x order. */
static size_t make_roots(int top, const ism_grid *g, zc_node *roots)
{
    int32_t n = 1 << top, s = ism_grid_cell_steps(g, top);
    size_t k = 0;
    for (int32_t i = 0; i < n; i++)
        for (int32_t j = 0; j < n; j++)
            for (int32_t l = 0; l < n; l++)
                roots[k++] = (zc_node){{i * s, j * s, l * s}, top};
    return k;
}

static bool join_tasks(zc_run *r, size_t ntasks, ism_zero_cells *out)
{
    size_t total = 0;
    for (size_t i = 0; i < ntasks; i++)
        total += r->tasks[i].n;
    out->cells = malloc((total ? total : 1) * sizeof *out->cells);
    if (!out->cells)
        return false;
    for (size_t i = 0; i < ntasks; i++) {
        if (r->tasks[i].n)
            memcpy(out->cells + out->n, r->tasks[i].cells, r->tasks[i].n * sizeof *out->cells);
        out->n += r->tasks[i].n;
        out->visited += r->tasks[i].visited;
    }
    return true;
}

enum ism_zc_status ism_zero_cells_find(const ism_zero_cells_params *p, ism_zero_cells *out)
{
    memset(out, 0, sizeof *out);
    int top = p->grid->depth < ZC_TOP_LEVEL ? p->grid->depth : ZC_TOP_LEVEL;
    zc_node roots[1 << (3 * ZC_TOP_LEVEL)];
    zc_run r = {.p = p};
    atomic_init(&r.total, 0);
    atomic_init(&r.status, ISM_ZC_OK);
    size_t ntasks = make_roots(top, p->grid, roots);
    r.roots = roots;
    r.threads = make_threads(p);
    r.tasks = calloc(ntasks, sizeof *r.tasks);
    if (r.threads && r.tasks)
        ism_parallel_for(p->threads, ntasks, run_task, &r);
    else
        stop(&r, ISM_ZC_NO_MEMORY);
    if (r.tasks && !join_tasks(&r, ntasks, out))
        stop(&r, ISM_ZC_NO_MEMORY);
    for (size_t i = 0; r.tasks && i < ntasks; i++)
        free(r.tasks[i].cells);
    free(r.tasks);
    free_threads(r.threads, p->threads);
    return (enum ism_zc_status)atomic_load(&r.status);
}
