/* cut_resid.c — how close the cut's curve vertices are to f = 0 and to their curves (the
 * cut's worst_f and worst_g). Newton already measured that where it left a vertex: those
 * residuals are kept per vertex, and the final measure evaluates f and g only at vertices
 * that moved since, or whose Newton did not have that curve (on the benchmark the
 * evaluations were 6% of the cut and arrangement). */
#include "core/curves/cut_internal.h"
#include <stdlib.h>
#include <string.h>
#include "core/util/grow.h"

bool cut_note_residuals(cut_state *s, uint32_t v)
{
    size_t old = s->cap_vres;
    if (!ism_grow((void **)&s->vres, &s->cap_vres, (size_t)v + 1, sizeof *s->vres, CUT_FIRST))
        return false;
    for (size_t i = old; i < s->cap_vres; i++)
        s->vres[i].nk = 0;
    const ism_cut_eval *ev = s->ev;
    const double *p = s->m->pos + 3 * (size_t)v;
    if (ev->last_ok && !memcmp(ev->last_res.p, p, sizeof ev->last_res.p))
        s->vres[v] = ev->last_res;
    else
        s->vres[v].nk = 0;
    return true;
}

/* The residuals of vertex v for function fn: kept ones when they hold, else evaluated. */
static void residuals_of(cut_state *s, uint32_t v, uint32_t fn, double *df, double *dg)
{
    const double *p = s->m->pos + 3 * (size_t)v;
    if (v >= s->cap_vres || !ism_cut_known_residuals(&s->vres[v], fn, p, df, dg))
        ism_cut_residuals(s->ev, fn, p, df, dg);
}

void cut_measure_residuals(cut_state *s)
{
    ism_cut *c = s->c;
    uint32_t *seen = malloc((s->m->nverts + 1) * sizeof *seen); /* NULL: each end measured */
    for (size_t v = 0; seen && v < s->m->nverts; v++)
        seen[v] = CUT_NONE;
    for (size_t i = 0; i < c->nedges; i++)
        for (int e = 0; e < 2; e++) {
            uint32_t v = e ? c->edges[i].b : c->edges[i].a, fn = c->edges[i].fn;
            if (seen && c->edges[i].branch[0] == ISM_CUT_NO_BRANCH) {
                if (seen[v] == fn)
                    continue; /* measured for this curve already (a crease's g is its edge's) */
                seen[v] = fn;
            }
            double df, dg;
            memcpy(s->ev->pair, c->edges[i].branch, sizeof s->ev->pair);
            residuals_of(s, v, fn, &df, &dg);
            c->worst_f = df > c->worst_f ? df : c->worst_f;
            c->worst_g = dg > c->worst_g ? dg : c->worst_g;
        }
    free(seen);
    s->ev->pair[0] = s->ev->pair[1] = ISM_CUT_NO_BRANCH;
}
