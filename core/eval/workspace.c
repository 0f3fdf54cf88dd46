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

ism_eval_ws *ism_eval_ws_new(const ism_tape *t)
{
    if (!t)
        return NULL;
    ism_eval_ws *ws = ism_line_alloc(sizeof *ws);
    if (!ws)
        return NULL;
    memset(ws, 0, sizeof *ws);
    size_t n = t->nregs;
    size_t cap = t->origin_len > t->len ? t->origin_len : t->len;
    ws->nregs = t->nregs;
    ws->code_cap = cap;
    ws->batch = ism_line_alloc(n * ISM_EVAL_BATCH * sizeof(double));
    ws->scalar = ism_line_alloc(n * sizeof *ws->scalar);
    ws->iv = ism_line_alloc(n * sizeof *ws->iv);
    ws->iv_lo = ism_line_alloc(n * ISM_IV_CHUNK * sizeof(double));
    ws->iv_hi = ism_line_alloc(n * ISM_IV_CHUNK * sizeof(double));
    ws->dual = ism_line_alloc(n * sizeof *ws->dual);
    ws->gbatch = ism_line_alloc(n * 4 * ISM_GRAD_BATCH * sizeof(double));
    ws->jet = ism_line_alloc(n * sizeof *ws->jet);
    ws->choice = ism_line_alloc(cap);
    ws->needed = ism_line_alloc(n);
    unsigned trig_bits = takes_trig(t) ? ISM_TRIG_CACHE_BITS : ISM_TRIG_CACHE_SMALL_BITS;
    ws->trig = ism_line_alloc(ism_trig_cache_size(trig_bits));
    if (!ws->trig || !ws->batch || !ws->scalar || !ws->iv || !ws->iv_lo || !ws->iv_hi || !ws->dual || !ws->gbatch || !ws->jet || !ws->choice
        || !ws->needed) {
        ism_eval_ws_free(ws);
        return NULL;
    }
    memset(ws->batch, 0, n * ISM_EVAL_BATCH * sizeof(double));
    ism_trig_cache_init(ws->trig, trig_bits);
    return ws;
}

void ism_eval_ws_free(ism_eval_ws *ws)
{
    if (!ws)
        return;
    free(ws->batch);
    free(ws->scalar);
    free(ws->iv);
    free(ws->iv_lo);
    free(ws->iv_hi);
    free(ws->dual);
    free(ws->gbatch);
    free(ws->jet);
    free(ws->hbatch);
    free(ws->choice);
    free(ws->needed);
    free(ws->trig);
    free(ws);
}
