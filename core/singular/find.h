/* find.h — the singular locus of f in a box, found from f alone: the stages of
 * core/singular/ run in order (see locus.h for the picture). */
#ifndef ISM_SING_FIND_H
#define ISM_SING_FIND_H

#include <stdbool.h>
#include "core/singular/locus.h"
#include "core/expr/expr.h"

/* Fills out (initialised by ism_locus_init, normally empty) with the singular points (and,
 * as the stages land, curves and double sheets) of f = 0 in o->box, and the candidate boxes
 * no stage explained. Respects o->max_boxes, o->cancel and o->deadline_ms: cut short, it
 * returns true with out->incomplete set (what is listed is right, something may be
 * missing). False only on bad options or out of memory (err says which). */
bool ism_locus_find(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                    ism_error *err);

#endif
