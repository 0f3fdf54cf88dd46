"""test_flatness_warning.py — without max_error, the stats warn about cells at depth.max that
were not flat enough only where a larger depth.max could help (proto/stats.c, octree_build.c
polygonise.c measure_unflat): never for cells on a crease (the cube's edges) or on the singular
locus (the double cone's node, the crossing planes' double line), which fail the flatness test at
every depth, in the presets' boxes and moved off the lattice (boxes.py); and when a cell is too
coarse (a sphere at depth 3) the warning gives the count and the worst distance reached, which the closed
form of the sphere confirms on the mesh written (at triangle centroids and edge midpoints), in
the box as given and moved off the lattice (boxes.py)."""
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import placements  # noqa: E402
from test_isomesh import read_ply  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")

FLAT = "not flat enough"


def run(args, ply=None):
    """The stats of one run (and the mesh written to ply when given). The warning belongs to
    the depth path: every run says --max-error off (without it the bound is 1e-3 x the box
    diagonal and the missed-bound warning speaks instead)."""
    r = subprocess.run([ISOMESH, *args, "--max-error", "off", "--stats"] +
                       (["-o", ply] if ply else []),
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise AssertionError(f"isomesh failed ({r.returncode}): {r.stderr}")
    return json.loads(r.stdout)


def flat_warnings(stats):
    return [w for w in stats["warnings"] if FLAT in w]


class FlatnessWarningTest(unittest.TestCase):
    def assert_quiet(self, name, h, depth, failing=100):
        """No flatness warning for the preset `name` (box [-h, h]³, depth.max `depth`) in its
        own box and off the lattice (boxes.py), where more than `failing` cells fail the
        flatness test: there the leaves beside the feature have decided sub-tapes and
        ism_quiet_near (quiet.c) has to tell them apart."""
        base = [-h] * 3 + [h] * 3
        for box in placements(base, 2 * h / 2 ** depth):
            with self.subTest(surface=name, box=box):
                s = run(["--surface", name, "-b", ",".join(repr(v) for v in box)])
                p = s["polygoniser"]
                # cells did fail the flatness test at depth.max (the old warning counted them) ...
                self.assertGreater(p["unresolved_nodes"], failing)
                # ... all on the crease / the locus: nothing a larger depth.max would improve
                self.assertEqual(p["unflat_nodes"], 0)
                self.assertEqual(flat_warnings(s), [])

    def test_cube_creases_do_not_warn(self):
        self.assert_quiet("cube", 1.3, 7)

    def test_node_and_double_line_do_not_warn(self):
        # the double cone: 2,336 cells fail in its own box (the node a lattice point), 94-96
        # moved off the lattice; there the cells 2.8-3.7 cells from the node warned (6 / 13,
        # worst 1.08e-3 / 9.55e-4 against 7.8e-4) until cells within 5 of their sizes of the
        # locus were told apart (a cone bends by more than the flatness tolerance there at
        # every depth: octree_build.c unflat)
        self.assert_quiet("double-cone", 1.0, 7, failing=50)
        self.assert_quiet("crossing-planes", 1.0, 6)

    def test_coarse_sphere_warns_with_its_worst_distance(self):
        depth = 3
        for box in placements([-1.5] * 3 + [1.5] * 3, 3.0 / 2 ** depth):
            with self.subTest(box=box), tempfile.TemporaryDirectory() as tmp:
                ply = os.path.join(tmp, "s.ply")
                s = run(["-e", "x^2 + y^2 + z^2 - 1", "-b", ",".join(repr(v) for v in box),
                         "-d", f"2:{depth}"], ply)
                p = s["polygoniser"]
                self.assertGreater(p["unflat_nodes"], 0)
                w = flat_warnings(s)
                self.assertEqual(len(w), 1, s["warnings"])
                m = re.match(r"(\d+) cells at the maximum depth were not flat enough: their "
                             r"triangles are up to ([0-9.e+-]+) from the surface", w[0])
                self.assertTrue(m, w[0])
                self.assertEqual(int(m.group(1)), p["unflat_nodes"])
                worst = float(m.group(2))
                self.assertAlmostEqual(worst, p["unflat_worst"], delta=5e-3 * worst)
                # the closed form: distance |‖p‖ - 1| at the mesh's centroids and midpoints
                verts, faces = read_ply(ply)
                far = 0.0
                for f in faces:
                    a, b, c = (verts[i][:3] for i in f)
                    pts = [[(a[k] + b[k] + c[k]) / 3 for k in range(3)]]
                    pts += [[(u[k] + v[k]) / 2 for k in range(3)] for u, v in ((a, b), (b, c), (c, a))]
                    far = max(far, max(abs(math.hypot(*q) - 1) for q in pts))
                # cells within the flatness test's tolerance (0.05 of a cell) are not counted:
                # the worst reported is beyond it, and it is what the mesh shows (the mesh's
                # farthest point is in a counted cell, measured to first order: |f| / |∇f| is
                # (1 - r²) / 2r for a point at r < 1, within 10% of 1 - r at these sags)
                cell = 3.0 / 2 ** depth
                self.assertGreater(worst, 0.05 * cell)
                self.assertLess(abs(worst - far), 0.1 * far, (worst, far))


if __name__ == "__main__":
    unittest.main()
