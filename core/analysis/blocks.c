/* blocks.c — runs independent blocks of analysis work (vertex or triangle ranges that
 * evaluate f) on the threads of the analysis's pool (parallel.h's ism_pool_for), each
 * thread with its own evaluation workspace. Results land in per-block slots, so they never
 * depend on which thread ran what. */
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"

#include <stdlib.h>

typedef struct block_run {
    ism_an_block_fn fn;
    void *ctx;
    ism_eval_ws **ws; /* per thread of the pool */
} block_run;

ism_pool *ism_an_pool_new(int t, bool worth)
{
    int threads = ism_threads_resolve(t);
    return threads > 1 && worth ? ism_pool_new(threads) : NULL;
}

static void run_block(void *ctx, size_t block, int thread)
{
    block_run *r = ctx;
    r->fn(r->ctx, r->ws[thread], block);
}

bool ism_an_run_blocks(const ism_tape *f, ism_pool *pool, size_t nblocks, ism_an_block_fn fn,
                       void *ctx)
{
    if (nblocks == 0) /* nothing to run: no workspaces (band_max's usual case, accuracy.c) */
        return true;
    int nt = ism_pool_threads(pool);
    ism_eval_ws **ws = calloc((size_t)nt, sizeof *ws);
    bool ok = ws != NULL;
    for (int i = 0; ok && i < nt; i++)
        ok = (ws[i] = ism_eval_ws_new(f)) != NULL;
    if (ok) {
        block_run r = {.fn = fn, .ctx = ctx, .ws = ws};
        ism_pool_for(pool, nblocks, run_block, &r, NULL);
    }
    for (int i = 0; ws && i < nt; i++)
        if (ws[i])
            ism_eval_ws_free(ws[i]);
    free(ws);
    return ok;
}
