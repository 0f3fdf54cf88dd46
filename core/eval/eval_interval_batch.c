/* eval_interval_batch.c — the interval evaluator over many boxes at once (an octree node's
 * eight children, say): registers hold the lower and upper bounds of up to ISM_IV_CHUNK
 * boxes as two arrays, and each instruction is one loop over the boxes of the chunk. The
 * common operations are the branch-free ones of interval_ops.h, so these loops vectorise;
 * the rest (powers, sqrt, exp, log, trigonometry) run box by box. Bounds equal
 * ism_eval_interval's bit for bit (the same functions, the same rounding).
 *
 * Speed: one switch per instruction per chunk, loops of a whole chunk with restrict
 * pointers (no instruction writes a register it reads) and a trip count known to be a
 * multiple of the vector width, so gcc emits straight vector code without alias or
 * remainder checks; a NaN bound becomes its infinity by one max/min (x86's maxpd/minpd
 * return the second operand on NaN, which is exactly nan_to); the boxes are packed and
 * unpacked by vectorised loops too. */
#include "core/eval/interval_ops.h"
#include "core/eval/workspace.h"

#include <string.h>

/* Lanes are processed in multiples of this (one AVX2 vector of doubles). */
#define LANES 4

#define ALWAYS_INLINE inline __attribute__((always_inline))

/* nan_to(v, -inf) and nan_to(v, +inf) as a single max / min (equal for every v). */
static ALWAYS_INLINE double lo_sane(double v) { return ism_max(v, -INFINITY); }
static ALWAYS_INLINE double hi_sane(double v) { return ism_min(v, INFINITY); }

/* Tells gcc that m is a whole number of vectors (no remainder loop). */
#define WHOLE_VECTORS(m) \
    do { if ((m) % LANES != 0) __builtin_unreachable(); } while (0)

#define IV_KERNEL_RR(NAME, FN)                                                               \
    static ALWAYS_INLINE void NAME(double *restrict ol, double *restrict oh,                 \
                                   const double *restrict al, const double *restrict ah,     \
                                   const double *restrict bl, const double *restrict bh,     \
                                   size_t m)                                                 \
    {                                                                                        \
        WHOLE_VECTORS(m);                                                                    \
        for (size_t j = 0; j < m; j++) {                                                     \
            ism_interval r = FN(iv(al[j], ah[j]), iv(bl[j], bh[j]));                         \
            ol[j] = lo_sane(r.lo);                                                           \
            oh[j] = hi_sane(r.hi);                                                           \
        }                                                                                    \
    }
#define IV_KERNEL_RC(NAME, FN)                                                               \
    static ALWAYS_INLINE void NAME(double *restrict ol, double *restrict oh,                 \
                                   const double *restrict al, const double *restrict ah,     \
                                   double c, size_t m)                                       \
    {                                                                                        \
        WHOLE_VECTORS(m);                                                                    \
        for (size_t j = 0; j < m; j++) {                                                     \
            ism_interval r = FN(iv(al[j], ah[j]), c);                                        \
            ol[j] = lo_sane(r.lo);                                                           \
            oh[j] = hi_sane(r.hi);                                                           \
        }                                                                                    \
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

static void run_scalar(const ism_instr *in, double *ol, double *oh, const double *al,
                       const double *ah, size_t m)
{
    for (size_t j = 0; j < m; j++) {
        ism_interval r = ism_iv_sane(scalar_op(in, iv(al[j], ah[j])));
        ol[j] = r.lo;
        oh[j] = r.hi;
    }
}

/* One instruction over the first m lanes (a multiple of LANES) of every register. */
static ALWAYS_INLINE void chunk_op(const ism_instr *in, double *lo, double *hi, size_t m)
{
    double *ol = lo + (size_t)in->out * ISM_IV_CHUNK, *oh = hi + (size_t)in->out * ISM_IV_CHUNK;
    const double *al = lo + (size_t)in->a * ISM_IV_CHUNK, *ah = hi + (size_t)in->a * ISM_IV_CHUNK;
    size_t b = (size_t)(ism_op_has_reg_b(in->op) ? in->b : in->a) * ISM_IV_CHUNK;
    const double *bl = lo + b, *bh = hi + b;
    const double c = in->imm;
    switch (in->op) {
    case ISM_OP_CONST:
        for (size_t j = 0; j < m; j++)
            ol[j] = oh[j] = c;
        break;
    case ISM_OP_COPY: k_copy(ol, oh, al, ah, c, m); break;
    case ISM_OP_ADD_RR: k_add(ol, oh, al, ah, bl, bh, m); break;
    case ISM_OP_ADD_RC: k_add_c(ol, oh, al, ah, c, m); break;
    case ISM_OP_SUB_RR: k_sub(ol, oh, al, ah, bl, bh, m); break;
    case ISM_OP_SUB_CR: k_c_sub(ol, oh, al, ah, c, m); break;
    case ISM_OP_MUL_RR: k_mul(ol, oh, al, ah, bl, bh, m); break;
    case ISM_OP_MUL_RC:
        if (c > 0.0)
            k_mul_cpos(ol, oh, al, ah, c, m);
        else if (c < 0.0)
            k_mul_cneg(ol, oh, al, ah, c, m);
        else
            run_scalar(in, ol, oh, al, ah, m);
        break;
    case ISM_OP_DIV_RR: k_div(ol, oh, al, ah, bl, bh, m); break;
    case ISM_OP_DIV_RC: k_div_c(ol, oh, al, ah, c, m); break;
    case ISM_OP_DIV_CR: k_c_div(ol, oh, al, ah, c, m); break;
    case ISM_OP_MIN_RR: k_min(ol, oh, al, ah, bl, bh, m); break;
    case ISM_OP_MIN_RC: k_min_c(ol, oh, al, ah, c, m); break;
    case ISM_OP_MAX_RR: k_max(ol, oh, al, ah, bl, bh, m); break;
    case ISM_OP_MAX_RC: k_max_c(ol, oh, al, ah, c, m); break;
    case ISM_OP_NEG: k_neg(ol, oh, al, ah, c, m); break;
    case ISM_OP_SQUARE: k_square(ol, oh, al, ah, c, m); break;
    case ISM_OP_ABS: k_abs(ol, oh, al, ah, c, m); break;
    default: run_scalar(in, ol, oh, al, ah, m); break;
    }
}

static ALWAYS_INLINE void pack_box(const double *restrict b, double *restrict lo,
                                   double *restrict hi, size_t j)
{
    double l = b[2 * j], h = b[2 * j + 1];
    lo[j] = l <= h ? l : -INFINITY;
    hi[j] = l <= h ? h : INFINITY;
}

/* Box coordinates into a register: n lanes, then lanes n..m-1 repeat the last box. The
 * boxes are read as a flat array of bounds (lo, hi, lo, hi, ...), whole vectors first (so
 * gcc vectorises without a remainder loop), then the rest. */
static ALWAYS_INLINE void pack(const ism_interval *v, double *restrict lo, double *restrict hi,
                               size_t n, size_t m)
{
    const double *restrict b = &v[0].lo;
    size_t whole = n / LANES * LANES;
    WHOLE_VECTORS(whole);
    for (size_t j = 0; j < whole; j++)
        pack_box(b, lo, hi, j);
    for (size_t j = whole; j < n; j++)
        pack_box(b, lo, hi, j);
    for (size_t j = n; j < m; j++) {
        lo[j] = lo[n - 1];
        hi[j] = hi[n - 1];
    }
}

/* The result register's first n lanes into out, likewise. */
static ALWAYS_INLINE void unpack(const double *restrict lo, const double *restrict hi,
                                 ism_interval *out, size_t n)
{
    double *restrict o = &out[0].lo;
    size_t whole = n / LANES * LANES;
    WHOLE_VECTORS(whole);
    for (size_t j = 0; j < whole; j++) {
        o[2 * j] = lo[j];
        o[2 * j + 1] = hi[j];
    }
    for (size_t j = whole; j < n; j++) {
        o[2 * j] = lo[j];
        o[2 * j + 1] = hi[j];
    }
}

/* n <= ISM_IV_CHUNK boxes through the whole tape. */
static ALWAYS_INLINE void chunk(const ism_tape *t, double *lo, double *hi,
                                const ism_interval *x, const ism_interval *y,
                                const ism_interval *z, ism_interval *out, size_t n)
{
    size_t m = (n + LANES - 1) / LANES * LANES;
    pack(x, lo + ISM_REG_X * ISM_IV_CHUNK, hi + ISM_REG_X * ISM_IV_CHUNK, n, m);
    pack(y, lo + ISM_REG_Y * ISM_IV_CHUNK, hi + ISM_REG_Y * ISM_IV_CHUNK, n, m);
    pack(z, lo + ISM_REG_Z * ISM_IV_CHUNK, hi + ISM_REG_Z * ISM_IV_CHUNK, n, m);
    for (size_t i = 0; i < t->len; i++)
        chunk_op(&t->code[i], lo, hi, m);
    size_t r = (size_t)t->result * ISM_IV_CHUNK;
    unpack(lo + r, hi + r, out, n);
}

#define CHUNKS_BODY                                                                     \
    for (size_t done = 0; done < n; done += ISM_IV_CHUNK) {                             \
        size_t k = n - done < ISM_IV_CHUNK ? n - done : ISM_IV_CHUNK;                   \
        chunk(t, lo, hi, x + done, y + done, z + done, out + done, k);                  \
    }

/* Every chunk, compiled for AVX2 and for the x86-64 baseline, chosen at run time (see
 * eval_double.c). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx2")))
static void chunks_avx2(const ism_tape *t, double *lo, double *hi, const ism_interval *x,
                        const ism_interval *y, const ism_interval *z, ism_interval *out,
                        size_t n)
{
    CHUNKS_BODY
}
#define HAVE_AVX2_PATH 1
#endif

static void chunks_base(const ism_tape *t, double *lo, double *hi, const ism_interval *x,
                        const ism_interval *y, const ism_interval *z, ism_interval *out,
                        size_t n)
{
    CHUNKS_BODY
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
    if (n == 0)
        return;
#ifdef HAVE_AVX2_PATH
    if (__builtin_cpu_supports("avx2")) {
        chunks_avx2(t, ws->iv_lo, ws->iv_hi, x, y, z, out, n);
        return;
    }
#endif
    chunks_base(t, ws->iv_lo, ws->iv_hi, x, y, z, out, n);
}
