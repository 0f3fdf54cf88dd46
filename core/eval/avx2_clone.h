/* avx2_clone.h — "compiled twice, chosen at run time": an evaluator's hot loop is written once
 * and compiled for the x86-64 baseline (SSE2) and again, under ISM_AVX2_CLONE, for AVX2; where
 * ISM_HAVE_AVX2_CLONE, the caller runs the second when ISM_RUN_AVX2() (the CPU has AVX2). An
 * explicit choice rather than ifunc target_clones, whose resolvers run before sanitizer and
 * coverage runtimes start. Both clones give the same bits (the same IEEE operations lane by
 * lane, lanes4.h).
 *
 * Built with -DISM_BASELINE_ONLY (the Makefile's sanitizer build, SAN=1) the AVX2 clones are
 * not compiled and the baseline always runs, so `make test` checks the bits of both on an AVX2
 * machine: the release lane the AVX2 clones, the sanitizer lane the baseline (the evaluators'
 * bit-for-bit tests against the same expectations: interval_golden's committed digests of
 * the interval passes' outputs, interval_lanes, eval_*, batch_identity). A compile-time
 * switch, not a run-time one: core/ keeps no mutable global state. */
#ifndef ISM_AVX2_CLONE_H
#define ISM_AVX2_CLONE_H

#if !defined(ISM_BASELINE_ONLY) && defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define ISM_HAVE_AVX2_CLONE 1
#define ISM_AVX2_CLONE __attribute__((target("avx2")))
#define ISM_RUN_AVX2() __builtin_cpu_supports("avx2")
#else
#define ISM_HAVE_AVX2_CLONE 0
#endif

/* A static function NAME(PARAMS) (ARGS: its parameters' names, parenthesised) whose body, the
 * rest, is compiled twice, NAME_base and NAME_avx2, NAME calling the one the CPU runs; both
 * copies are ordinary statics a test may call. For the one-box evaluators (eval_interval.c,
 * eval_interval_jet.c), whose SSE2 interval operations (interval_ops.h) take VEX's
 * three-operand forms in the AVX2 one: fewer register copies (figures: notes/iv28.md).
 *
 * A macro, not an always_inline body called from two targets: GCC will not inline a function
 * that holds a computed goto, and the threaded evaluators (threaded.h) are such functions, so
 * an inlined body would lose its threading. A body may hold labels (each copy is its own
 * function) but no preprocessor line (#if, #pragma: directives inside a macro's arguments are
 * undefined behaviour); use _Pragma.
 *
 * Older hand-written pairs to move onto it: eval_interval_grad_batch.c, eval_hessian_batch.c,
 * eval_gradient.c, eval_gradient_batch.c, dual_cert.c. */
#if ISM_HAVE_AVX2_CLONE
#define ISM_AVX2_TWICE(RET, NAME, PARAMS, ARGS, ...)                                       \
    static RET NAME##_base PARAMS { __VA_ARGS__ }                                            \
    ISM_AVX2_CLONE static RET NAME##_avx2 PARAMS { __VA_ARGS__ }                             \
    static RET NAME PARAMS                                                                   \
    {                                                                                        \
        return ISM_RUN_AVX2() ? NAME##_avx2 ARGS : NAME##_base ARGS;                         \
    }
#else
#define ISM_AVX2_TWICE(RET, NAME, PARAMS, ARGS, ...) static RET NAME PARAMS { __VA_ARGS__ }
#endif

#endif
