"""boxes.py — the placements of a box that every geometric CLI test meshes in: as given,
shifted by 1e-3 (x up, y down, z up by 0.7e-3), and by 0.37 / -0.23 / 0.41 of a finest cell
(no lattice plane of any depth through the box's centre). Against the sanitizer build
(ISOMESH_TEST_QUICK=1) only the last one: that run looks for memory errors, 5-10x slower,
while the release run checks the geometry in all three."""
import os

QUICK = os.environ.get("ISOMESH_TEST_QUICK") == "1"


def placements(box, cell):
    """[lo x, lo y, lo z, hi x, hi y, hi z] boxes: `box` and its shifted copies; cell: the
    finest cell's side."""
    shifts = [(0, 0, 0), (1e-3, -1e-3, 0.7e-3), (0.37 * cell, -0.23 * cell, 0.41 * cell)]
    return [[box[k] + s[k % 3] for k in range(6)] for s in (shifts[2:] if QUICK else shifts)]
