/* placements.h — the placements of a box every geometric C test meshes in (unit_core through
 * poly_fixture.h, unit_proto), one table; tests/cli/boxes.py holds the same numbers for the
 * Python tests and tests/bench/sweep_singular.py. */
#ifndef TESTS_UNIT_PLACEMENTS_H
#define TESTS_UNIT_PLACEMENTS_H

/* The three placements:
 *   own    the box as given: its corners and the planes between its cells at every depth are
 *          where the test's author put them (on x = 0, on a node, through a sheet...);
 *   1e-3   moved by (PF_OFF_X, PF_OFF_Y, PF_OFF_Z) = (1e-3, −1e-3, 0.7e-3) in the box's own
 *          units: every lattice plane passes just beside where it passed (a small fraction of a
 *          cell at the depths the tests run), the case where a near-tangency meets a plane;
 *   irr    moved by (PF_IRR_X, PF_IRR_Y, PF_IRR_Z) = (√2 − 1, −(√5 − 1)/4, 1/e) of a finest
 *          cell of each axis.
 * Why irrational: the features of the tests' surfaces (nodes, pinch points, axes, sheets of
 * planes, centres of spheres) sit at rational coordinates, as do the boxes. A lattice plane of
 * depth j of the moved box passes through such a feature when (x − lo)/c − s is a multiple of
 * 2^(d−j) (c the finest cell, s the shift in cells): with s rational (0.37, −0.23 and 0.41 once
 * stood here) that can happen at some depth, and a decimal fraction sits near the finer
 * lattices (0.37 × 8 = 2.96: 0.04 of a cell from a plane three depths down); with s irrational
 * it never happens at any depth. (A double is 53 binary digits of s: dyadic only at 2^−53 of a
 * cell, far below any depth meshed.)
 * Why these magnitudes: 0.31–0.41 of a cell, far from 0 and 1 (the box back on the lattice:
 * the own placement) and from ½ (on the lattice one depth finer, where a deeper request, the
 * singular stage's depth or a thin search would see the own placement again); from the
 * multiples of ¼ (two depths finer) they are 0.086, 0.059 and 0.118 of a cell. They differ per
 * axis, y with the other sign, so the box's centre does not move along a lattice diagonal.
 * Tests that move every axis by one fraction of a cell use PF_IRR (the x entry). Figures that
 * older comments quote "in the 0.37-cell box" were measured at the old rational placement
 * (PF_OLD_* below). test_placements.c checks the numbers against their closed forms. */
#define PF_OFF_X 1e-3
#define PF_OFF_Y (-1e-3)
#define PF_OFF_Z 0.7e-3
#define PF_IRR_X 0.41421356237309515    /* √2 − 1 */
#define PF_IRR_Y (-0.30901699437494745) /* −(√5 − 1)/4 */
#define PF_IRR_Z 0.36787944117144233    /* 1/e */
#define PF_IRR PF_IRR_X

/* The rational placement this table replaced (0.37, −0.23, 0.41 of a finest cell); kept only
 * as test_polygonise_crease.c's double-torus regression placement (pf_sweep_box_old). Not for
 * new tests. */
#define PF_OLD_X 0.37
#define PF_OLD_Y (-0.23)
#define PF_OLD_Z 0.41

#endif
