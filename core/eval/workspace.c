/* workspace.c — creating and freeing evaluation workspaces (see workspace.h). */
#include "core/eval/workspace.h"

#include <stdlib.h>
#include <string.h>

ism_eval_ws *ism_eval_ws_new(const ism_tape *t)
{
    if (!t)
        return NULL;
    ism_eval_ws *ws = calloc(1, sizeof *ws);
    if (!ws)
        return NULL;
    size_t n = t->nregs;
    size_t cap = t->origin_len > t->len ? t->origin_len : t->len;
    ws->nregs = t->nregs;
    ws->code_cap = cap;
    ws->batch = aligned_alloc(64, ((n * ISM_EVAL_BATCH * sizeof(double)) + 63) / 64 * 64);
    ws->scalar = malloc(n * sizeof *ws->scalar);
    ws->iv = malloc(n * sizeof *ws->iv);
    ws->iv_lo = aligned_alloc(64, n * ISM_IV_CHUNK * sizeof(double));
    ws->iv_hi = aligned_alloc(64, n * ISM_IV_CHUNK * sizeof(double));
    ws->dual = malloc(n * sizeof *ws->dual);
    ws->jet = malloc(n * sizeof *ws->jet);
    ws->choice = malloc(cap ? cap : 1);
    ws->needed = malloc(n);
    ws->trig = malloc(sizeof *ws->trig);
    if (!ws->trig || !ws->batch || !ws->scalar || !ws->iv || !ws->iv_lo || !ws->iv_hi || !ws->dual || !ws->jet || !ws->choice
        || !ws->needed) {
        ism_eval_ws_free(ws);
        return NULL;
    }
    memset(ws->batch, 0, n * ISM_EVAL_BATCH * sizeof(double));
    ism_trig_cache_init(ws->trig);
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
    free(ws->jet);
    free(ws->choice);
    free(ws->needed);
    free(ws->trig);
    free(ws);
}
