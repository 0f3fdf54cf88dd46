/* sampler.c — the sampler's batched gradients (sampler.h): a group of points split by the
 * tape that holds at each (the leaf's shortened one inside its box, f's elsewhere; or, for
 * several leaves' points, each point's own leaf's), each part evaluated in passes over its
 * tape. */
#include "core/octree/sampler.h"

/* Lanes per pass, at most: the evaluator's unrolled width (ISM_GRAD_UNROLLED, eval.h; a
 * pass of more runs its out-of-line wide loop, which costs more a point — gyroid ball at
 * 0.0109: 1,533 wide passes 13.1M, ~8.5K each, where two passes of 16 cost less). At 16
 * rather than ISM_GRAD_BATCH's 32 (callgrind, one thread, ism_mesh_surface): gyroid-ball
 * 0.0109 −0.38%, 0.00109 −0.25%, klein-bottle 0.0141 −0.41%, barth-sextic 0.0259 −0.39%.
 * The lanes' values do not depend on how points are grouped (eval.h), so neither does
 * anything measured. */
#define SAMPLE_LANES ISM_GRAD_UNROLLED

/* The lanes idx[0..m) of p (1 <= m <= SAMPLE_LANES), all on tape t, in one pass. */
static void tape_pass(ism_sampler *s, const ism_tape *t, const double (*p)[3], double *f,
                      double (*g)[3], const size_t *idx, size_t m)
{
    double x[SAMPLE_LANES], y[SAMPLE_LANES], z[SAMPLE_LANES], fv[SAMPLE_LANES];
    double gv[SAMPLE_LANES][3];
    size_t j = 0;
    do { /* m >= 1 */
        const double *q = p[idx[j]];
        x[j] = q[0], y[j] = q[1], z[j] = q[2];
    } while (++j < m);
    ism_eval_gradient_batch(t, s->ws, x, y, z, fv, gv, m);
    for (j = 0; j < m; j++) {
        size_t i = idx[j];
        f[i] = fv[j];
        g[i][0] = gv[j][0], g[i][1] = gv[j][1], g[i][2] = gv[j][2];
    }
}

/* One pass over at most SAMPLE_LANES points: the lanes whose tape is `local` first, then the
 * others. */
static void sample_chunk(ism_sampler *s, const double (*p)[3], double *f, double (*g)[3],
                         size_t n)
{
    size_t idx[SAMPLE_LANES], nl = 0, nf = n;
    for (size_t i = 0; i < n; i++) /* local lanes from the front, f's from the back */
        if (ism_sampler_tape_at(s, p[i]) == s->tape)
            idx[--nf] = i;
        else
            idx[nl++] = i;
    if (nl)
        tape_pass(s, s->local, p, f, g, idx, nl);
    if (nl < n)
        tape_pass(s, s->tape, p, f, g, idx + nl, n - nl);
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

void ism_sample_grad_tapes(ism_sampler *s, const ism_tape **tape, const double (*p)[3],
                           double *f, double (*g)[3], size_t n)
{
    s->n_gradient += n;
    if (!s->batch) {
        for (size_t i = 0; i < n; i++)
            f[i] = ism_eval_gradient(tape[i], s->ws, p[i][0], p[i][1], p[i][2], g[i]);
        return;
    }
    /* the first point not yet evaluated names the next tape; its points (all after it)
       are taken SAMPLE_LANES at a time, each taken one's tape cleared */
    for (size_t i = 0; i < n; i++) {
        const ism_tape *t = tape[i];
        for (size_t j = i; t && j < n;) {
            size_t idx[SAMPLE_LANES], m = 0;
            for (; j < n && m < SAMPLE_LANES; j++)
                if (tape[j] == t) {
                    idx[m++] = j;
                    tape[j] = NULL;
                }
            if (m)
                tape_pass(s, t, p, f, g, idx, m);
        }
    }
}
