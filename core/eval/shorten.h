/* shorten.h — tape shortening (ism_tape_shorten, eval.h) in its two steps, for a caller that
 * may reuse a shortening it met before: the pass (f's interval over the box, the choices at
 * every min/max recorded in the workspace), then the shortening by those choices, which
 * reads nothing else, so the same tape and the same choices at its min/max shorten to the
 * same tape. */
#ifndef ISM_SHORTEN_H
#define ISM_SHORTEN_H

#include "core/eval/eval.h"

#include <stdint.h>

/* ism_tape_shorten's pass: f's interval over the box x × y × z into *range, and the choices
 * at t's min/max (and abs) in ws (ism_tape_shorten_choices). False, *range the whole line
 * and nothing recorded, when ws does not fit t (ism_tape_shorten then returns false). */
bool ism_tape_shorten_pass(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                           ism_interval z, ism_interval *range);

/* The choices the last pass recorded, one byte per instruction of its tape: 0 (both
 * operands), 1 (only a) or 2 (only b, or the constant) in the low two bits at a min/max. */
const uint8_t *ism_tape_shorten_choices(const ism_eval_ws *ws);

/* t shortened into out by the choices of the last ism_tape_shorten_pass over t (true from
 * it) in ws: what ism_tape_shorten returns after its pass, false (out untouched) when
 * nothing is dropped or out cannot hold t's shortening. The pass's choices are not kept. */
bool ism_tape_shorten_recorded(const ism_tape *t, ism_eval_ws *ws, ism_tape *out);

#endif
