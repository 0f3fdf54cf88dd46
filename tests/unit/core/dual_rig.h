/* dual_rig.h — the dual mesher's state for one thread (dual_tree.h) over the box ±1.5 in a
 * test placement, and nodes made by hand as split_task hands them to classification: for the
 * tests that classify nodes themselves (test_dual_pre, test_dual_touch). */
#ifndef DUAL_RIG_H
#define DUAL_RIG_H

#include <stdint.h>
#include "core/octree/dual_classify.h"
#include "core/octree/dual_tree.h"
#include "core/octree/poly_options.h"

typedef struct dual_rig {
    dual d;
    worker w;
    ism_poly_options o;
} dual_rig;

/* r for tape t: the box ±1.5 placed by i (0, 1, 2: pf_sweep_box's −1, 0, 1), depths 1 to
 * depth, error bound e; a sampler and jet workspace of its own (dual_rig_tear_down). */
void dual_rig_set_up(dual_rig *r, const ism_tape *t, int i, int depth, double e);
/* dual_rig_set_up over the box base (lo x, y, z, hi x, y, z) placed by i instead of ±1.5. */
void dual_rig_set_up_box(dual_rig *r, const ism_tape *t, const double base[6], int i, int depth,
                         double e);
void dual_rig_tear_down(dual_rig *r);

/* Node at lattice origin q, level: f and the unit gradients at its corners (bit 0 = x,
 * 1 = y, 2 = z) into n and v, the rest of them cleared. */
void dual_rig_node(dual_rig *r, const int32_t q[3], int level, dnode *n, corner_view *v);

#endif
