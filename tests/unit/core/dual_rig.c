/* dual_rig.c — the hand-made dual mesher state and nodes of dual_rig.h. */
#include "dual_rig.h"
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/octree/corners.h"
#include "core/octree/grid.h"
#include "poly_fixture.h"

void dual_rig_set_up(dual_rig *r, const ism_tape *t, int i, int depth, double e)
{
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    dual_rig_set_up_box(r, t, base, i, depth, e);
}

void dual_rig_set_up_box(dual_rig *r, const ism_tape *t, const double base[6], int i, int depth,
                         double e)
{
    double box[6];
    pf_sweep_box(base, depth, i - 1, box);
    pf_options(&r->o, box, 1, depth);
    r->o.max_error = e;
    memset(&r->d, 0, sizeof r->d);
    memset(&r->w, 0, sizeof r->w);
    r->d.o = &r->o;
    ism_grid_init(&r->d.g, box, depth);
    r->d.finest_step = fmin(r->d.g.step[0], fmin(r->d.g.step[1], r->d.g.step[2]));
    for (int k = 0; k < 12; k++)
        ism_cube_edge(k, &r->d.ec0[k], &r->d.ec1[k], r->d.ef[k]);
    r->w.s.tape = t;
    r->w.s.ws = ism_eval_ws_new(t);
    r->w.s.batch = true;
    r->w.jet = ism_ivjet_ws_new(t);
    cr_assert(r->w.s.ws && r->w.jet);
    r->d.w = &r->w;
    r->d.nw = 1;
}

void dual_rig_tear_down(dual_rig *r)
{
    ism_eval_ws_free(r->w.s.ws);
    ism_ivjet_ws_free(r->w.jet);
    free(r->w.pairs);
    free(r->w.pairs_filled);
}

void dual_rig_node(dual_rig *r, const int32_t q[3], int level, dnode *n, corner_view *v)
{
    memset(n, 0, sizeof *n);
    memset(v, 0, sizeof *v);
    int32_t step = ism_grid_cell_steps(&r->d.g, level);
    for (int a = 0; a < 3; a++)
        n->o.v[a] = q[a];
    n->level = (uint8_t)level;
    n->child = n->vert = n->vert2 = -1;
    for (int c = 0; c < 8; c++) {
        double g[3];
        for (int a = 0; a < 3; a++)
            v->p[c][a] = ism_grid_coord(&r->d.g, a, q[a] + (c >> a & 1) * step);
        n->f[c] = ism_eval_gradient(r->w.s.tape, r->w.s.ws, v->p[c][0], v->p[c][1], v->p[c][2],
                                    g);
        double len = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        for (int a = 0; a < 3; a++)
            v->n[c][a] = len > 0 ? g[a] / len : 0;
    }
    v->foot = FOOT_UNKNOWN;
}
