/* sampler.c — the sampler's batched gradients (sampler.h): a group of points split by the
 * tape that holds at each (the leaf's shortened one inside its box, f's elsewhere), each part
 * evaluated in one pass over its tape. */
#include "core/octree/sampler.h"

/* Lanes per pass, at most: the evaluator's unrolled width (ISM_GRAD_UNROLLED, eval.h; a
 * pass of more runs its out-of-line wide loop, which costs more a point — gyroid ball at
 * 0.0109: 1,533 wide passes 13.1M, ~8.5K each, where two passes of 16 cost less). At 16
 * rather than ISM_GRAD_BATCH's 32 (callgrind, one thread, ism_mesh_surface): gyroid-ball
 * 0.0109 −0.38%, 0.00109 −0.25%, klein-bottle 0.0141 −0.41%, barth-sextic 0.0259 −0.39%.
 * The lanes' values do not depend on how points are grouped (eval.h), so neither does
 * anything measured. */
#define SAMPLE_LANES ISM_GRAD_UNROLLED

/* One pass over at most SAMPLE_LANES points: the lanes whose tape is `local` first, then the
 * others, each group gathered into coordinate arrays and scattered back. */
static void sample_chunk(ism_sampler *s, const double (*p)[3], double *f, double (*g)[3],
                         size_t n)
{
    size_t idx[SAMPLE_LANES], nl = 0, nf = n;
    for (size_t i = 0; i < n; i++) /* local lanes from the front, f's from the back */
        if (ism_sampler_tape_at(s, p[i]) == s->tape)
            idx[--nf] = i;
        else
            idx[nl++] = i;
    for (int part = 0; part < 2; part++) {
        size_t lo = part ? nl : 0, hi = part ? n : nl, m = hi - lo;
        if (!m)
            continue;
        const ism_tape *t = part ? s->tape : s->local;
        double x[SAMPLE_LANES], y[SAMPLE_LANES], z[SAMPLE_LANES], fv[SAMPLE_LANES];
        double gv[SAMPLE_LANES][3];
        for (size_t j = 0; j < m; j++) {
            const double *q = p[idx[lo + j]];
            x[j] = q[0], y[j] = q[1], z[j] = q[2];
        }
        ism_eval_gradient_batch(t, s->ws, x, y, z, fv, gv, m);
        for (size_t j = 0; j < m; j++) {
            size_t i = idx[lo + j];
            f[i] = fv[j];
            g[i][0] = gv[j][0], g[i][1] = gv[j][1], g[i][2] = gv[j][2];
        }
    }
}

void ism_sample_grad_batch(ism_sampler *s, const double (*p)[3], double *f, double (*g)[3],
                           size_t n)
{
    if (!s->batch) {
        for (size_t i = 0; i < n; i++)
            f[i] = ism_sample_grad(s, p[i], g[i]);
        return;
    }
    s->n_gradient += n;
    for (size_t done = 0; done < n; done += SAMPLE_LANES) {
        size_t k = n - done < SAMPLE_LANES ? n - done : SAMPLE_LANES;
        sample_chunk(s, p + done, f + done, g + done, k);
    }
}
