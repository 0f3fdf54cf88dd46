/* octree_fixture.h — one adapted octree for the tests that read a tree's structure (face
 * tiles, the break-point registry): f's tree over a ±half cube swept into a placement
 * (placements.h), the flatness settings those tests share. */
#ifndef ISM_TEST_OCTREE_FIXTURE_H
#define ISM_TEST_OCTREE_FIXTURE_H

#include "core/expr/expr.h"
#include "core/octree/octree.h"

/* The tree of t over the cube ±half moved into placement (pf_sweep_box at max_depth), levels
 * 3..max_depth, max_error the build's error bound, one thread, into *tree (zeroed first);
 * asserts the build succeeds. */
void of_build_swept(const ism_tape *t, double half, int max_depth, double max_error,
                    int placement, ism_octree *tree);

#endif
