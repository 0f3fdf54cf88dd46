/* workspace.c — creating and freeing evaluation workspaces (see workspace.h). Every array
 * has cache lines of its own: a thread writes its registers on every evaluation, and the
 * workspaces of several threads are made one after the other by one thread. */
#include "core/eval/workspace.h"
#include "core/util/cache_line.h"

#include <stdlib.h>
#include <string.h>

/* Does t take a sine or a cosine (the trig cache's size, trig_pair.h)? */
static bool takes_trig(const ism_tape *t)
{
    for (size_t i = 0; i < t->len; i++)
        if (t->code[i].op == ISM_OP_SIN || t->code[i].op == ISM_OP_COS)
            return true;
    return false;
}

/* Bytes of n rounded up to whole cache lines (at least one, as ism_line_alloc gives). */
static size_t whole_lines(size_t n)
{
    return (n ? (n + ISM_CACHE_LINE - 1) / ISM_CACHE_LINE : 1) * ISM_CACHE_LINE;
}

/* The workspace and its arrays are one allocation, each on lines of its own (the
 * workspace's own first): one aligned_alloc, not twelve (every mesh makes a workspace for
 * each stage and thread: ~600 instructions of malloc each, ~7K a workspace). None is
 * cleared: every evaluator writes a register before reading it (the batched evaluators'
 * lanes past n repeat the last point, eval_double.c), and the trig memo is initialised
 * whole. */
ism_eval_ws *ism_eval_ws_new(const ism_tape *t)
{
    if (!t)
        return NULL;
    size_t n = t->nregs;
    size_t cap = t->origin_len > t->len ? t->origin_len : t->len;
    unsigned trig_bits = takes_trig(t) ? ISM_TRIG_CACHE_BITS : ISM_TRIG_CACHE_SMALL_BITS;
    const size_t bytes[] = {
        sizeof(ism_eval_ws),                      /* the workspace */
        n * ISM_EVAL_BATCH * sizeof(double),      /* batch */
        n * sizeof(double),                       /* scalar */
        n * sizeof(ism_interval),                 /* iv */
        n * ISM_IV_CHUNK * sizeof(double),        /* iv_lo */
        n * ISM_IV_CHUNK * sizeof(double),        /* iv_hi */
        n * sizeof(ism_dual),                     /* dual */
        n * 4 * ISM_GRAD_BATCH * sizeof(double),  /* gbatch */
        n * sizeof(ism_jet),                      /* jet */
        cap,                                      /* choice */
        n,                                        /* needed */
        ism_trig_cache_size(trig_bits),           /* trig */
    };
    enum { PARTS = sizeof bytes / sizeof bytes[0] };
    size_t at[PARTS], total = 0;
    for (int k = 0; k < PARTS; k++) {
        at[k] = total;
        total += whole_lines(bytes[k]);
    }
    char *block = ism_line_alloc(total);
    if (!block)
        return NULL;
    ism_eval_ws *ws = (ism_eval_ws *)block;
    memset(ws, 0, sizeof *ws);
    ws->nregs = t->nregs;
    ws->code_cap = cap;
    ws->batch = (double *)(block + at[1]);
    ws->scalar = (double *)(block + at[2]);
    ws->iv = (ism_interval *)(block + at[3]);
    ws->iv_lo = (double *)(block + at[4]);
    ws->iv_hi = (double *)(block + at[5]);
    ws->dual = (ism_dual *)(block + at[6]);
    ws->gbatch = (double *)(block + at[7]);
    ws->jet = (ism_jet *)(block + at[8]);
    ws->choice = (uint8_t *)(block + at[9]);
    ws->needed = (uint8_t *)(block + at[10]);
    ws->trig = (ism_trig_cache *)(block + at[11]);
    ism_trig_cache_init(ws->trig, trig_bits);
    return ws;
}

void ism_eval_ws_free(ism_eval_ws *ws)
{
    if (!ws)
        return;
    free(ws->hbatch); /* made apart, on its first use */
    free(ws);         /* the block of every other array */
}
