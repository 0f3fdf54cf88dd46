/* threaded.h — direct threading (GNU C's labels as values) over an evaluator's list of
 * operations (eval_double.c's POINT_OPS, eval_interval.c's INTERVAL_OPS, eval_gradient.c's
 * DUAL_STEPS; each X(OP, what) once per operation): the proof that a list names every
 * operation, the 256-entry table of labels L_<OP> (codes past the list: L_BAD) and the tail
 * each step's code ends in. Each evaluator supplies its list, its labelled steps and L_BAD. */
#ifndef ISM_EVAL_THREADED_H
#define ISM_EVAL_THREADED_H

#include "core/expr/tape.h"

/* A list names every operation: its entry count is ISM_OP_COUNT (a repeated entry does not
 * compile, its label twice; so no entry short and none repeated is every one). A missing one
 * would leave its table slot zero, a jump to NULL. */
#define ISM_THREADED_ONE(OP, E) +1
#define ISM_THREADED_COMPLETE(LIST, why) \
    _Static_assert(0 LIST(ISM_THREADED_ONE) == ISM_OP_COUNT, why)

/* The jump table `name` over the list's labels, every code past it to L_BAD (in->op is a
 * uint8_t: 256 entries cover every code). */
#define ISM_THREADED_ENTRY(OP, E) [OP] = &&L_##OP,
#define ISM_THREADED_TABLE(name, LIST) \
    static const void *const name[256] = { LIST(ISM_THREADED_ENTRY)[ISM_OP_COUNT ... 255] = &&L_BAD }

/* A step's tail: the next instruction, `at_end` (a statement: return or break) past the
 * last, else a jump to the next instruction's code. */
#define ISM_THREADED_NEXT(table, in, end, at_end) \
    if (++(in) == (end))                          \
        at_end;                                   \
    goto *(table)[(in)->op];

#endif
