/* interval_eval.h — the interval pass that tape shortening builds on (internal). */
#ifndef ISM_INTERVAL_EVAL_H
#define ISM_INTERVAL_EVAL_H

#include <stdint.h>
#include "core/eval/eval.h"

/* Evaluates t over the box; when choices is not NULL, choices[i] is set for every min/max
 * instruction i: 0 both operands matter, 1 only a, 2 only b (or the immediate). ws must
 * fit t. */
ism_interval ism_interval_run(const ism_tape *t, ism_eval_ws *ws, ism_interval x,
                              ism_interval y, ism_interval z, uint8_t *choices);

#endif
