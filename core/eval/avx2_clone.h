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
 * bit-for-bit tests, eval_* and batch_identity, against the same expectations). A compile-time
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

#endif
