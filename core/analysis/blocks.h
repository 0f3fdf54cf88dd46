/* blocks.h — the block-parallel runner (blocks.c) the passes that evaluate f use, and the
 * fixed block sizes of the analysis's parallel loops. */
#ifndef ISM_AN_BLOCKS_H
#define ISM_AN_BLOCKS_H

#include <stddef.h>
#include <stdbool.h>
#include "core/expr/expr.h"
#include "core/eval/eval.h"
#include "core/util/pool.h"

/* Items per task of the analysis's parallel loops. Fixed, so what a task writes (its own
 * slots) never depends on the number of threads; a task is tens of microseconds, far above
 * what handing it out costs. Triangles or edges per task of the loops that do not evaluate
 * f (the edge table's, the quality measures, the duplicates, the accuracy's scans); vertices
 * or edges per task of the loops that evaluate f (a few evaluations each, so fewer per
 * task). */
#define ISM_AN_TRI_BLOCK 4096
#define ISM_AN_EVAL_BLOCK 1024

/* Runs fn(ctx, ws, block) for every block < nblocks on the threads of pool (NULL: on the
 * calling thread), each thread with its own workspace for f, made for this call. Blocks are
 * independent; results must not depend on which thread ran which block. False when a
 * workspace could not be made; with no blocks none is made. */
typedef void (*ism_an_block_fn)(void *ctx, ism_eval_ws *ws, size_t block);
bool ism_an_run_blocks(const ism_tape *f, ism_pool *pool, size_t nblocks, ism_an_block_fn fn,
                       void *ctx);

/* The threads option t asks for, made once for all of a call's parallel loops: NULL (the
 * calling thread alone) when that is one thread or the work is not `worth` starting
 * threads for (or the pool cannot be allocated). Freed with ism_pool_free. */
ism_pool *ism_an_pool_new(int t, bool worth);

#endif
