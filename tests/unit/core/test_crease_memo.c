/* test_crease_memo.c — the crease-point memo (crease_memo.h) changes nothing but the work: a
 * strip of triangles across the crease circle of a unit ball cut by the plane z = 0.3
 * (f = max(|p|² − 1, z − 0.3), the top's two branches) split by ism_crease_split with the
 * memo gives bit for bit the triangles and vertices it gives without one, both the first
 * time (edges that two triangles share hit within the one call) and again with every edge in
 * the memo; hits are counted, so a memo that never answered would fail. Independently of the
 * code, every crease point (ISM_FP_CREASE) lies on the circle: |p|² = 1 and z = 0.3 to
 * CIRCLE_TOL. The strip (not the surface) is placed as given, moved by PF_OFF_* and by
 * PF_IRR_* of its step: its edges cross the circle at other points. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/octree/cell.h"
#include "core/octree/crease_memo.h"
#include "core/octree/crease_split.h"
#include "core/octree/triangulate.h"

#define STRIP_N 12          /* quads round the circle: 24 triangles, 36 mixed edges */
#define STRIP_ARC 0.6       /* radians the strip spans */
#define BELOW_Z 0.2         /* the strip's lower row, on the ball's branch (z − 0.3 < |p|² − 1) */
#define ABOVE_Z 0.4         /* its upper row, on the plane's branch */
#define CIRCLE_TOL 1e-12    /* Newton's crease points on both zero sets, to rounding */

static const pf_surface cut_ball = {"max(x^2 + y^2 + z^2 - 1, z - 0.3)", NULL, 0, NULL, 0};

/* The strip: row k (0 below, 1 above) of points on the unit sphere at height BELOW_Z or
 * ABOVE_Z, moved by off; triangles (a_i, a_i+1, b_i) and (a_i+1, b_i+1, b_i). */
static void strip(const double off[3], ism_cell_out *out)
{
    memset(out, 0, sizeof *out);
    const double zs[2] = {BELOW_Z, ABOVE_Z};
    for (int k = 0; k < 2; k++)
        for (int i = 0; i <= STRIP_N; i++) {
            double th = STRIP_ARC * i / STRIP_N, r = sqrt(1 - zs[k] * zs[k]);
            ism_fpoint v = {{r * cos(th) + off[0], r * sin(th) + off[1], zs[k] + off[2]},
                            {0, 0, 1}, 0};
            uint32_t idx;
            cr_assert(ism_cell_out_vert(out, &v, &idx));
        }
    for (uint32_t i = 0; i < STRIP_N; i++) {
        uint32_t a = i, a1 = i + 1, b = STRIP_N + 1 + i, b1 = b + 1;
        cr_assert(ism_cell_out_tri(out, a, a1, b) && ism_cell_out_tri(out, a1, b1, b));
    }
}

/* out split along f's crease by a sampler with memo m (NULL: none). */
static void split(const ism_tape *t, ism_eval_ws *ws, ism_crease_memo *m, ism_cell_out *out)
{
    ism_sampler s = {.tape = t, .ws = ws, .memo_tape = m ? t : NULL, .crease_memo = m};
    cr_assert(ism_crease_split(&s, out, 0));
}

static bool same_out(const ism_cell_out *a, const ism_cell_out *b)
{
    if (a->nverts != b->nverts || a->ntris != b->ntris ||
        memcmp(a->tris, b->tris, 3 * a->ntris * sizeof *a->tris))
        return false;
    for (size_t v = 0; v < a->nverts; v++)
        if (memcmp(a->verts[v].p, b->verts[v].p, sizeof a->verts[v].p) ||
            memcmp(a->verts[v].g, b->verts[v].g, sizeof a->verts[v].g) ||
            a->verts[v].flags != b->verts[v].flags)
            return false;
    return true;
}

Test(crease_memo, hit_is_the_fresh_crease_point)
{
    ism_tape *t = pf_compile(&cut_ball);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double step = STRIP_ARC / STRIP_N;
    const double offs[3][3] = {{0, 0, 0},
                               {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                               {PF_IRR_X * step, PF_IRR_Y * step, PF_IRR_Z * step}};
    for (int placed = 0; placed < 3; placed++) {
        const double *off = offs[placed];
        ism_crease_memo *m = ism_crease_memo_new(NULL, 1, NULL);
        cr_assert_not_null(m);
        ism_cell_out fresh, first, again;
        strip(off, &fresh);
        strip(off, &first);
        strip(off, &again);
        split(t, ws, NULL, &fresh);
        split(t, ws, m, &first);
        uint64_t hits_first = m->hits;
        split(t, ws, m, &again);
        /* each mixed edge but the strip's two ends is shared by two triangles */
        cr_expect_gt(hits_first, 0, "placement %d: no edge answered from the memo", placed);
        cr_expect_geq(m->hits - hits_first, 3 * STRIP_N, "placement %d: %llu hits again",
                      placed, (unsigned long long)(m->hits - hits_first));
        cr_expect(same_out(&fresh, &first), "placement %d: memo's first pass differs", placed);
        cr_expect(same_out(&fresh, &again), "placement %d: memo's hits differ", placed);
        size_t crease = 0;
        for (size_t v = 0; v < fresh.nverts; v++) {
            const double *p = fresh.verts[v].p;
            if (!(fresh.verts[v].flags & ISM_FP_CREASE))
                continue;
            crease++;
            cr_expect_leq(fabs(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1), CIRCLE_TOL,
                          "placement %d", placed);
            cr_expect_leq(fabs(p[2] - 0.3), CIRCLE_TOL, "placement %d", placed);
        }
        cr_expect_geq(crease, 2 * STRIP_N + 1, "placement %d: %zu crease points", placed,
                      crease);
        ism_cell_out_free(&fresh);
        ism_cell_out_free(&first);
        ism_cell_out_free(&again);
        ism_crease_memo_free(m);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}
