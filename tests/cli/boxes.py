"""boxes.py — the placements of a box that every geometric Python test meshes in (the CLI and
HTTP tests, tests/bench/sweep_singular.py and mesh_identity.py); tests/unit/core/poly_fixture.h
holds the same table for the C tests (PF_OFF_*, PF_IRR_*):

  own   the box as given (lattice planes where the test's author put them);
  1e-3  moved by (1e-3, -1e-3, 0.7e-3) in the box's units: every lattice plane just beside
        where it passed;
  irr   moved by (sqrt(2) - 1, -(sqrt(5) - 1)/4, 1/e) of a finest cell of each axis.

Why irrational: the surfaces' features (nodes, pinch points, axes, planes, centres) and the
boxes sit at rational coordinates; a lattice plane of some depth of the moved box passes through
such a feature only when the shift in cells is rational (0.37 / -0.23 / 0.41 once stood here,
0.37 x 8 = 2.96 is 0.04 of a cell from a plane three depths down) — never with an irrational
one. Why these magnitudes: 0.31-0.41 of a cell, far from 0 and 1 (the own placement again) and
from 1/2 (the lattice one depth finer); 0.086 / 0.059 / 0.118 of a cell from the multiples of
1/4; per axis different, y with the other sign, so the centre does not move along a diagonal.

Against the sanitizer build (ISOMESH_TEST_QUICK=1) only the irrational placement: that run looks
for memory errors, 5-10x slower, while the release run checks the geometry in all three."""
import math
import os

QUICK = os.environ.get("ISOMESH_TEST_QUICK") == "1"

OFF_1E3 = (1e-3, -1e-3, 0.7e-3)  # in the box's units
IRR_CELLS = (math.sqrt(2) - 1, -(math.sqrt(5) - 1) / 4, 1 / math.e)  # of a finest cell
IRR = IRR_CELLS[0]  # one fraction of a cell, for tests that move every axis alike

# (label, shift per axis, whether the shift is in finest cells)
PLACEMENTS = (("own", (0, 0, 0), False), ("1e-3", OFF_1E3, False), ("irr", IRR_CELLS, True))


def labelled_placements(box, cell):
    """(label, box) pairs: `box` and its shifted copies as placements() gives them, each with
    its PLACEMENTS label; cell as there."""
    c = cell if isinstance(cell, tuple) else (cell,) * 3
    chosen = PLACEMENTS[2:] if QUICK else PLACEMENTS
    return [(label, [box[k] + (s[k % 3] * c[k % 3] if in_cells else s[k % 3])
                     for k in range(6)])
            for label, s, in_cells in chosen]


def placements(box, cell):
    """[lo x, lo y, lo z, hi x, hi y, hi z] boxes: `box` and its shifted copies; cell: the
    finest cell's side, or a tuple of the three sides (a box that is not a cube)."""
    return [b for _, b in labelled_placements(box, cell)]
