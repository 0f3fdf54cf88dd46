/* interval_eval.h — the interval pass that tape shortening builds on (internal). */
#ifndef ISM_INTERVAL_EVAL_H
#define ISM_INTERVAL_EVAL_H

#include <stdint.h>
#include "core/eval/eval.h"

/* Evaluates t over the box; when choices is not NULL, choices[i] is set for every min/max
 * instruction i: 0 both operands matter, 1 only a, 2 only b (or the immediate); and for every
 * abs: 1 where its operand is ≥ 0 over the box, 2 where < 0, 0 else (the branches of an
 * ism_piece; shortening reads min/max's alone). ws must fit t. */
ism_interval ism_interval_run(const ism_tape *t, ism_eval_ws *ws, ism_interval x,
                              ism_interval y, ism_interval z, uint8_t *choices);

#endif
