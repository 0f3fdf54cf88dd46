/* eval_interval_grad_batch.c — interval enclosures of f and ∇f over up to ISM_IVGRAD_BATCH
 * boxes at once (interval_jet.h's ism_eval_interval_grad_batch): the gradient pass of
 * eval_interval_jet.c on tapes of affine operations, +, −, ×, squares and integer powers,
 * each instruction one step over every box. Each lane computes exactly what
 * ism_eval_interval_grad_kept computes over its box, operation for operation: the same
 * outward rounding (interval_ops.h's down1 / up1, as IEEE operations element by element),
 * products' bounds from their four corner products in iv_mul's order (a NaN corner counted
 * as 0), the exact zeros of derivatives kept and skipped as mulz / addz / subz do (as bit
 * masks with the same outcome), the partials a value does not depend on (free_of) written
 * as 0, and NaN bounds turned into infinities; so the two agree bit for bit and a caller
 * may use either. Its records (one per lane, interval_jet_ws.h) let the jet over the same
 * box compute only the Hessian, as the scalar pass's record does.
 *
 * min, max and abs are taken as ism_eval_interval_grad takes them with no branch forced
 * (eval_interval_jet.c's op_branch), lane by lane: the value the natural enclosure, the
 * partials those of the branch the lane's box decides, or at a free kink (both branches
 * allowed) the whole line but 0 where both operands' partials are exactly [0, 0] over the
 * lane's box (or the variable is outside the want: set_whole_derivs' test, not dependence:
 * x² over x = [0, 0] depends on x, its partial is 0); each lane's free kinks are kept in the
 * workspace (ism_ivjet_lane_kinks) as that pass would list them. Tapes with these give no
 * records (hess_only takes none of them).
 *
 * Why: the dual mesher takes f and ∇f's natural enclosure over most children of a split
 * node (octree/dual_classify.c, ism_dual_classify_tail); one box costs ~1,700 instructions
 * on the torus's short tape, most of them the instruction dispatch and the zero tests a
 * batch shares.
 *
 * The steps themselves (one instruction over a group of lanes) are interval_grad_lanes.h's,
 * which the batched jets (eval_interval_jet_lanes.c) take too. */
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_grad_lanes.h"
#include "core/eval/interval_jet_ws.h"
#include "core/eval/workspace.h"
#include "core/expr/tape.h"
#include "core/util/cache_line.h"

#include <stdlib.h>
#include <string.h>

/* The tape over one group's registers r (the variables loaded): without branches each
 * instruction's register recorded in keep (ISM_IVG_REG doubles an instruction, this
 * group's part); with them its free kinks' lanes (those in `lanes`: not padding) or'ed into
 * ws->lane_kinks[i] at bit `first` + lane and counted in nk[lane]. */
INLINE void run_group(const ism_tape *t, vj *r, vj *keep, ism_ivjet_ws *ws, uint32_t *nk,
                      unsigned lanes, unsigned first, bool branches)
{
    uint8_t *kinks = ws->lane_kinks;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        unsigned w = in->free_of == 0 ? 7u : ISM_FREE_ALL & ~(unsigned)in->free_of;
        v4i took_a;
        v4i free = step(in, r, w, branches, &took_a);
        if (!branches) /* a constant in each copy: records only without kinks */
            keep[i * ISM_IVG_GROUPS] = r[in->out];
        if (!branches || !ism_op_is_kink(in->op))
            continue;
        unsigned m = 0;
        _Pragma("GCC unroll 4") for (int j = 0; j < VL; j++)
            m |= free[j] ? 1u << j : 0u;
        m &= lanes;
        if (m && !kinks[i]) /* the first lane with a kink here: listed once */
            ws->lane_kink_at[ws->lane_nkink_at++] = (uint32_t)i;
        kinks[i] |= (uint8_t)(m << first);
        for (; m; m &= m - 1)
            nk[__builtin_ctz(m)]++;
    }
}

#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE static void run_avx2(const ism_tape *t, vj *r, vj *keep, ism_ivjet_ws *ws,
                                    uint32_t *nk, unsigned lanes, unsigned first, bool branches)
{
    if (branches) /* two copies: a tape without kinks pays no kink test an instruction */
        run_group(t, r, keep, ws, nk, lanes, first, true);
    else
        run_group(t, r, keep, ws, nk, lanes, first, false);
}
#endif

static void run_base(const ism_tape *t, vj *r, vj *keep, ism_ivjet_ws *ws, uint32_t *nk,
                     unsigned lanes, unsigned first, bool branches)
{
    if (branches)
        run_group(t, r, keep, ws, nk, lanes, first, true);
    else
        run_group(t, r, keep, ws, nk, lanes, first, false);
}

/* The pass's registers, records and kink bytes for t, made or grown; false when out of
 * memory. */
static inline __attribute__((always_inline)) bool reserve(ism_ivjet_ws *ws,
                                                            const ism_tape *t)
{
    if (!ws->lane_regs) {
        ws->lane_regs = ism_line_alloc((size_t)ws->nregs * ISM_IVG_REG * sizeof(double));
        if (!ws->lane_regs)
            return false;
    }
    if (ws->lane_cap < t->len) {
        free(ws->lane_kept);
        free(ws->lane_kinks);
        free(ws->lane_kink_at);
        ws->lane_cap = 0;
        ws->lane_kept = ism_line_alloc(t->len * ISM_IVG_REG * sizeof(double));
        ws->lane_kinks = malloc(t->len);
        ws->lane_kink_at = malloc(t->len * sizeof *ws->lane_kink_at);
        if (!ws->lane_kept || !ws->lane_kinks || !ws->lane_kink_at)
            return false;
        ws->lane_cap = t->len;
    }
    return true;
}

/* The pass over box[0..n) into out; with branches (t holds min, max or abs) the kinks' lanes
 * into ws->lane_kinks and their counts into ws->lane_nk (without, lane_nk untouched), else
 * the records kept. */
static inline __attribute__((always_inline)) void
run_lanes(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval (*box)[3], size_t n,
          ism_ivgrad *out, bool branches)
{
    if (branches) {
        memset(ws->lane_kinks, 0, t->len);
        memset(ws->lane_nk, 0, sizeof ws->lane_nk);
    }
    ws->lane_nkink_at = 0;
    size_t ng = (n + VL - 1) / VL;
    for (size_t g = 0; g < ng; g++) {
        vj *r = (vj *)ws->lane_regs + g * ws->nregs;
        vj *rec = (vj *)ws->lane_kept + g; /* written without branches only */
        load_group(r, box, n, g);
        unsigned lanes = n - g * VL >= VL ? (1u << VL) - 1 : (1u << (n - g * VL)) - 1;
        unsigned first = (unsigned)(g * VL);
#if ISM_HAVE_AVX2_CLONE
        if (ISM_RUN_AVX2())
            run_avx2(t, r, rec, ws, ws->lane_nk + first, lanes, first, branches);
        else
#endif
            run_base(t, r, rec, ws, ws->lane_nk + first, lanes, first, branches);
    }
    for (size_t b = 0; b < n; b++) {
        const double *res = (const double *)((const vj *)ws->lane_regs +
                                             (b / VL) * ws->nregs + t->result);
        size_t j = b % VL;
        out[b].v = iv(res[j], res[VL + j]);
        for (int k = 0; k < 3; k++)
            out[b].d[k] = iv(res[(2 + 2 * k) * VL + j], res[(3 + 2 * k) * VL + j]);
        memcpy(ws->lane_box[b], box[b], sizeof ws->lane_box[b]);
    }
    ws->lane_t = t;
    ws->lane_n = (uint32_t)n;
    ws->lane_pass_t = t;
}

/* The checks both entry points make; ws's lane state reset (no records, no pass). */
static inline __attribute__((always_inline)) bool can_run(const ism_tape *t, ism_ivjet_ws *ws,
                                                            size_t n)
{
    if (!ws || !t || !n || n > ISM_IVGRAD_BATCH || ws->nregs < t->nregs)
        return false;
    ws->lane_ok = 0; /* before reserve, which may free the records and fail to grow them */
    ws->lane_pass_t = NULL;
    return true;
}

bool ism_eval_interval_grad_batch(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out)
{
    if (!t || !ism_ivjet_tape_hess_from_kept(t) || !can_run(t, ws, n) || !reserve(ws, t))
        return false;
    run_lanes(t, ws, box, n, out, false);
    ws->lane_ok = (1u << n) - 1;
    return true;
}

bool ism_eval_interval_grad_lanes(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out,
                                  uint32_t *nk)
{
    bool branches;
    if (!t || !lanes_take(t, &branches) || !can_run(t, ws, n) || !reserve(ws, t))
        return false;
    run_lanes(t, ws, box, n, out, branches);
    ws->lane_ok = branches ? 0 : (1u << n) - 1;
    if (!branches) /* no kink: run_lanes left lane_nk as it was */
        memset(ws->lane_nk, 0, sizeof ws->lane_nk);
    if (nk)
        memcpy(nk, ws->lane_nk, n * sizeof *nk);
    return true;
}
