/* jet4.c — interval derivatives of f up to the fourth over a box (jet4.h): f's interval jet,
 * those of its three first partials and (order 4) of its six second partials. */
#include "core/singular/jet4.h"
#include "core/eval/interval_jet.h"
#include "core/eval/tape_partial.h"

#include <stdlib.h>

/* The tapes: f, ∂f/∂x_k (k = 0..2), ∂²f/∂x_k∂x_l (k ≤ l, in the order of SYM). */
#define TAPES_MAX 10

static const int SYM[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };

struct ism_jet4_ws {
    int ntapes;
    ism_tape *own[TAPES_MAX];    /* the partial tapes (own[0] unused: f is the caller's) */
    const ism_tape *tape[TAPES_MAX];
    ism_ivjet_ws *jw[TAPES_MAX];
};

ism_jet4_ws *ism_jet4_ws_new(const ism_tape *f, int order)
{
    if (order < 3 || order > 4)
        return NULL;
    ism_jet4_ws *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    w->ntapes = order == 3 ? 4 : TAPES_MAX;
    w->tape[0] = f;
    bool ok = true;
    for (int k = 0; ok && k < 3; k++)
        ok = (w->tape[1 + k] = w->own[1 + k] = ism_tape_partial(f, k)) != NULL;
    for (int k = 0; ok && order == 4 && k < 3; k++)
        for (int l = k; ok && l < 3; l++)
            ok = (w->tape[4 + SYM[k][l]] = w->own[4 + SYM[k][l]] =
                      ism_tape_partial(w->own[1 + k], l)) != NULL;
    for (int i = 0; ok && i < w->ntapes; i++)
        ok = (w->jw[i] = ism_ivjet_ws_new(w->tape[i])) != NULL;
    if (!ok) {
        ism_jet4_ws_free(w);
        return NULL;
    }
    return w;
}

void ism_jet4_ws_free(ism_jet4_ws *w)
{
    if (!w)
        return;
    for (int i = 0; i < TAPES_MAX; i++) {
        ism_ivjet_ws_free(w->jw[i]);
        ism_tape_free(w->own[i]);
    }
    free(w);
}

void ism_jet4_eval(ism_jet4_ws *w, const ism_interval x[3], ism_jet4 *out, uint64_t *evals)
{
    ism_ivjet j;
    ism_eval_interval_jet(w->tape[0], w->jw[0], x, NULL, NULL, &j);
    out->v = j.v;
    for (int i = 0; i < 3; i++) {
        out->d[i] = j.d[i];
        for (int k = 0; k < 3; k++)
            out->h[i][k] = j.h[SYM[i][k]];
    }
    for (int k = 0; k < 3; k++) {
        ism_eval_interval_jet(w->tape[1 + k], w->jw[1 + k], x, NULL, NULL, &j);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                out->t[a][b][k] = j.h[SYM[a][b]];
    }
    for (int k = 0; w->ntapes == TAPES_MAX && k < 3; k++)
        for (int l = k; l < 3; l++) {
            int s = 4 + SYM[k][l];
            ism_eval_interval_jet(w->tape[s], w->jw[s], x, NULL, NULL, &j);
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    out->q[a][b][k][l] = out->q[a][b][l][k] = j.h[SYM[a][b]];
        }
    if (evals)
        *evals += (uint64_t)w->ntapes;
}
