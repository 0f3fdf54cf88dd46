/* eval_interval_batch.c — the interval evaluator over many boxes at once (an octree node's
 * eight children, say): registers hold the lower and upper bounds of ISM_IV_CHUNK boxes as
 * two arrays, and each instruction is one loop over the boxes. The common operations are
 * the branch-free ones of interval_ops.h, so these loops vectorise; the rest (powers,
 * sqrt, exp, log, trigonometry) run box by box. Bounds equal ism_eval_interval's. */
#include "core/eval/interval_ops.h"
#include "core/eval/workspace.h"

#include <string.h>

#define LANES 8

#define IV_KERNEL_RR(NAME, FN)                                                          \
    static inline __attribute__((always_inline)) void NAME(double *restrict ol, double *restrict oh,                   \
                            const double *restrict al, const double *restrict ah,       \
                            const double *restrict bl, const double *restrict bh)       \
    {                                                                                   \
        for (size_t j = 0; j < LANES; j++) {                                            \
            ism_interval r = FN(iv(al[j], ah[j]), iv(bl[j], bh[j]));                    \
            ol[j] = nan_to(r.lo, -INFINITY);                                            \
            oh[j] = nan_to(r.hi, INFINITY);                                             \
        }                                                                               \
    }
#define IV_KERNEL_RC(NAME, FN)                                                          \
    static inline __attribute__((always_inline)) void NAME(double *restrict ol, double *restrict oh,                   \
                            const double *restrict al, const double *restrict ah,       \
                            double c)                                                   \
    {                                                                                   \
        for (size_t j = 0; j < LANES; j++) {                                            \
            ism_interval r = FN(iv(al[j], ah[j]), c);                                   \
            ol[j] = nan_to(r.lo, -INFINITY);                                            \
            oh[j] = nan_to(r.hi, INFINITY);                                             \
        }                                                                               \
    }

static inline ism_interval iv_c_sub_rc(ism_interval a, double c) { return iv_c_sub(c, a); }
static inline ism_interval iv_c_div_rc(ism_interval a, double c) { return iv_c_div(c, a); }
static inline ism_interval iv_min_rc(ism_interval a, double c) { return iv_min(a, iv(c, c)); }
static inline ism_interval iv_max_rc(ism_interval a, double c) { return iv_max(a, iv(c, c)); }
static inline ism_interval iv_neg_rc(ism_interval a, double c) { (void)c; return iv_neg(a); }
static inline ism_interval iv_square_rc(ism_interval a, double c) { (void)c; return iv_square(a); }
static inline ism_interval iv_abs_rc(ism_interval a, double c) { (void)c; return iv_abs(a); }
static inline ism_interval iv_copy_rc(ism_interval a, double c) { (void)c; return a; }

IV_KERNEL_RR(k_add, iv_add)
IV_KERNEL_RR(k_sub, iv_sub)
IV_KERNEL_RR(k_mul, iv_mul)
IV_KERNEL_RR(k_div, iv_div)
IV_KERNEL_RR(k_min, iv_min)
IV_KERNEL_RR(k_max, iv_max)
IV_KERNEL_RC(k_add_c, iv_add_c)
IV_KERNEL_RC(k_c_sub, iv_c_sub_rc)
IV_KERNEL_RC(k_mul_cpos, iv_mul_cpos)
IV_KERNEL_RC(k_mul_cneg, iv_mul_cneg)
IV_KERNEL_RC(k_div_c, iv_div_c)
IV_KERNEL_RC(k_c_div, iv_c_div_rc)
IV_KERNEL_RC(k_min_c, iv_min_rc)
IV_KERNEL_RC(k_max_c, iv_max_rc)
IV_KERNEL_RC(k_neg, iv_neg_rc)
IV_KERNEL_RC(k_square, iv_square_rc)
IV_KERNEL_RC(k_abs, iv_abs_rc)
IV_KERNEL_RC(k_copy, iv_copy_rc)

/* The operations without a branch-free form, box by box. */
static ism_interval scalar_op(const ism_instr *in, ism_interval a)
{
    switch (in->op) {
    case ISM_OP_MUL_RC: return iv_mul_c(a, in->imm);
    case ISM_OP_POWI: return iv_powi(a, in->b);
    case ISM_OP_POWC: return iv_powc(a, in->imm);
    case ISM_OP_SQRT: return iv_sqrt(a);
    case ISM_OP_SIN: return iv_sin(a);
    case ISM_OP_COS: return iv_cos(a);
    case ISM_OP_TAN: return iv_tan(a);
    case ISM_OP_EXP: return iv_exp(a);
    case ISM_OP_LOG: return iv_log(a);
    default: return ism_iv_whole();
    }
}

static inline __attribute__((always_inline)) void chunk_op(const ism_instr *in, double *lo, double *hi, size_t ngroups)
{
    size_t o = (size_t)in->out * ISM_IV_CHUNK, a = (size_t)in->a * ISM_IV_CHUNK;
    size_t b = (size_t)(ism_op_has_reg_b(in->op) ? in->b : in->a) * ISM_IV_CHUNK;
    const double c = in->imm;
#define RUN_RR(K) \
    for (size_t g = 0; g < ngroups * LANES; g += LANES) \
        K(lo + o + g, hi + o + g, lo + a + g, hi + a + g, lo + b + g, hi + b + g)
#define RUN_SCALAR() \
    for (size_t j = 0; j < ngroups * LANES; j++) { \
        ism_interval r_ = ism_iv_sane(scalar_op(in, iv(lo[a + j], hi[a + j]))); \
        lo[o + j] = r_.lo; \
        hi[o + j] = r_.hi; \
    }
#define RUN_RC(K) \
    for (size_t g = 0; g < ngroups * LANES; g += LANES) \
        K(lo + o + g, hi + o + g, lo + a + g, hi + a + g, c)
    switch (in->op) {
    case ISM_OP_CONST:
        for (size_t j = 0; j < ngroups * LANES; j++)
            lo[o + j] = hi[o + j] = c;
        break;
    case ISM_OP_COPY: RUN_RC(k_copy); break;
    case ISM_OP_ADD_RR: RUN_RR(k_add); break;
    case ISM_OP_ADD_RC: RUN_RC(k_add_c); break;
    case ISM_OP_SUB_RR: RUN_RR(k_sub); break;
    case ISM_OP_SUB_CR: RUN_RC(k_c_sub); break;
    case ISM_OP_MUL_RR: RUN_RR(k_mul); break;
    case ISM_OP_MUL_RC:
        if (c > 0.0)
            RUN_RC(k_mul_cpos);
        else if (c < 0.0)
            RUN_RC(k_mul_cneg);
        else
            RUN_SCALAR();
        break;
    case ISM_OP_DIV_RR: RUN_RR(k_div); break;
    case ISM_OP_DIV_RC: RUN_RC(k_div_c); break;
    case ISM_OP_DIV_CR: RUN_RC(k_c_div); break;
    case ISM_OP_MIN_RR: RUN_RR(k_min); break;
    case ISM_OP_MIN_RC: RUN_RC(k_min_c); break;
    case ISM_OP_MAX_RR: RUN_RR(k_max); break;
    case ISM_OP_MAX_RC: RUN_RC(k_max_c); break;
    case ISM_OP_NEG: RUN_RC(k_neg); break;
    case ISM_OP_SQUARE: RUN_RC(k_square); break;
    case ISM_OP_ABS: RUN_RC(k_abs); break;
    default: RUN_SCALAR(); break;
    }
#undef RUN_RR
#undef RUN_RC
#undef RUN_SCALAR
}

/* The tape over one chunk, compiled for AVX2 and for the x86-64 baseline, chosen at run
 * time (see eval_double.c). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx2")))
static void run_tape_avx2(const ism_tape *t, double *lo, double *hi, size_t ngroups)
{
    for (size_t i = 0; i < t->len; i++)
        chunk_op(&t->code[i], lo, hi, ngroups);
}
#define HAVE_AVX2_PATH 1
#endif

static void run_tape_base(const ism_tape *t, double *lo, double *hi, size_t ngroups)
{
    for (size_t i = 0; i < t->len; i++)
        chunk_op(&t->code[i], lo, hi, ngroups);
}

static void run_tape(const ism_tape *t, double *lo, double *hi, size_t ngroups)
{
#ifdef HAVE_AVX2_PATH
    if (__builtin_cpu_supports("avx2")) {
        run_tape_avx2(t, lo, hi, ngroups);
        return;
    }
#endif
    run_tape_base(t, lo, hi, ngroups);
}

static double sane_lo(ism_interval v) { return v.lo <= v.hi ? v.lo : -INFINITY; }
static double sane_hi(ism_interval v) { return v.lo <= v.hi ? v.hi : INFINITY; }

/* n <= ISM_IV_CHUNK boxes; lanes past n repeat the last box. */
static void eval_chunk(const ism_tape *t, ism_eval_ws *ws, const ism_interval *x,
                       const ism_interval *y, const ism_interval *z, ism_interval *out,
                       size_t n)
{
    size_t ngroups = (n + LANES - 1) / LANES;
    const ism_interval *in[3] = { x, y, z };
    for (size_t k = 0; k < 3; k++) {
        double *lo = ws->iv_lo + k * ISM_IV_CHUNK, *hi = ws->iv_hi + k * ISM_IV_CHUNK;
        for (size_t j = 0; j < ngroups * LANES; j++) {
            ism_interval v = in[k][j < n ? j : n - 1];
            lo[j] = sane_lo(v);
            hi[j] = sane_hi(v);
        }
    }
    run_tape(t, ws->iv_lo, ws->iv_hi, ngroups);
    const double *lo = ws->iv_lo + (size_t)t->result * ISM_IV_CHUNK;
    const double *hi = ws->iv_hi + (size_t)t->result * ISM_IV_CHUNK;
    for (size_t j = 0; j < n; j++)
        out[j] = iv(lo[j], hi[j]);
}

void ism_eval_interval_batch(const ism_tape *t, ism_eval_ws *ws, const ism_interval *x,
                             const ism_interval *y, const ism_interval *z, ism_interval *out,
                             size_t n)
{
    if (!ism_ws_fits(ws, t)) {
        for (size_t i = 0; i < n; i++)
            out[i] = ism_iv_whole();
        return;
    }
    for (size_t done = 0; done < n; done += ISM_IV_CHUNK) {
        size_t k = n - done < ISM_IV_CHUNK ? n - done : ISM_IV_CHUNK;
        eval_chunk(t, ws, x + done, y + done, z + done, out + done, k);
    }
}
