/* preset_tape.h — a preset's f compiled with its parameters at their defaults, for the proto
 * tests that evaluate or polygonise every preset (test_ival_batch.c, test_batch_presets.c). */
#ifndef ISM_TEST_PRESET_TAPE_H
#define ISM_TEST_PRESET_TAPE_H

#include "core/expr/expr.h"
#include "proto/presets.h"

/* The tape of p, or NULL with err set (also when p has more parameters than it can hold). */
ism_tape *test_preset_tape(const ism_preset *p, ism_error *err);

#endif
