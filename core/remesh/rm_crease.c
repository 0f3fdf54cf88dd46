/* rm_crease.c — whether a bend of the mesh is the surface's own curvature or a crease. An
 * edge whose two triangles meet at more than the crease angle (rm_locks.c) is a crease only
 * when f's curvature cannot account for it: the unit normal ∇f/|∇f| turns across the edge
 * at the rate |(I − n nᵀ) H u| / |∇f| (H the Hessian, u the unit tangent across the edge), and
 * over the two triangles' heights it turns by about that rate × their sum. Where a smooth f
 * bends faster than the cells (Whitney's umbrella beside the y axis, z = x²/y²: a normal
 * turning 70° within a tenth of a cell; Steiner's surface beside its pinch points) the mesh
 * bends by tens of degrees per edge and no crease is there; a min/max crease has a finite
 * Hessian on either side and a bend it cannot explain. */
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The turn the curvature predicts is compared with the bend after multiplying by this:
 * the rate is taken at the edge's ends, where a ridge narrower than the triangles (whose
 * tip lies between the ends and the far corners) turns slower than at its tip; a real
 * crease beside gentle curvature is predicted a turn of a few degrees against its tens. */
#define ISM_RM_CREASE_CURVE_SLACK 1.0

void rm_curvature_memo_open(rm_curvature_memo *memo, size_t nverts)
{
    memo->gh = malloc((nverts ? nverts : 1) * 9 * sizeof *memo->gh);
    memo->have = calloc(nverts ? nverts : 1, 1);
    if (!memo->gh || !memo->have)
        rm_curvature_memo_close(memo);
}

void rm_curvature_memo_close(rm_curvature_memo *memo)
{
    free(memo->gh);
    free(memo->have);
    memo->gh = NULL;
    memo->have = NULL;
}

/* ∇f (g) and the Hessian (h) at vertex v, from the memo when it holds them. */
static void gradient_hessian(const rm_pass *p, uint32_t v, rm_curvature_memo *memo,
                             double g[3], double h[6])
{
    const double *x = p->r.m->pos + 3 * (size_t)v;
    if (memo && memo->gh && memo->have[v]) {
        memcpy(g, memo->gh + 9 * (size_t)v, 3 * sizeof *g);
        memcpy(h, memo->gh + 9 * (size_t)v + 3, 6 * sizeof *h);
        return;
    }
    ism_eval_hessian(p->f, p->ws, x[0], x[1], x[2], g, h);
    if (memo && memo->gh) {
        memcpy(memo->gh + 9 * (size_t)v, g, 3 * sizeof *g);
        memcpy(memo->gh + 9 * (size_t)v + 3, h, 6 * sizeof *h);
        memo->have[v] = 1;
    }
}

/* The rate at which the unit normal turns at vertex v when walking across the edge of
 * direction t (unit), radians per unit length; 0 where ∇f vanishes (no normal to turn). */
static double turn_rate(const rm_pass *p, uint32_t v, const double t[3], rm_curvature_memo *memo)
{
    double g[3], h[6];
    gradient_hessian(p, v, memo, g, h);
    double len = ism_norm3(g);
    if (!(len > p->gthresh) || !isfinite(len))
        return 0;
    double n[3] = {g[0] / len, g[1] / len, g[2] / len};
    double u[3];
    ism_cross3(n, t, u);
    if (!(ism_normalise3(u) > 0))
        return 0;
    double hu[3] = {h[0] * u[0] + h[1] * u[1] + h[2] * u[2],
                    h[1] * u[0] + h[3] * u[1] + h[4] * u[2],
                    h[2] * u[0] + h[4] * u[1] + h[5] * u[2]};
    double along = ism_dot3(hu, n);
    for (int k = 0; k < 3; k++)
        hu[k] -= along * n[k];
    double rate = ism_norm3(hu) / len;
    return isfinite(rate) ? rate : 0;
}

bool rm_bend_is_curvature(const rm_pass *p, uint32_t a, uint32_t b, double bend, double width,
                          rm_curvature_memo *memo)
{
    const double *A = p->r.m->pos + 3 * (size_t)a, *B = p->r.m->pos + 3 * (size_t)b;
    double t[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]};
    if (!(ism_normalise3(t) > 0))
        return false;
    double rate = fmax(turn_rate(p, a, t, memo), turn_rate(p, b, t, memo));
    return bend <= ISM_RM_CREASE_CURVE_SLACK * rate * width;
}
