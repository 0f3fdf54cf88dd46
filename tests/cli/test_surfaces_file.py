"""test_surfaces_file.py — `isomesh --surfaces FILE --surface NAME` (issue 18): the example
file in the repository meshes every entry (the ellipsoid's vertices lie on it, checked by its
closed form at vertices and triangle centroids, in its own box and shifted off the lattice),
--help names that file, and each wrong shape gets its own error naming where and what was
expected; a missing file says it cannot be read (no "line -1")."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import IRR  # noqa: E402  (the placements' table: sqrt(2) - 1 of a cell)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")
EXAMPLE = os.path.join(ROOT, "examples", "surfaces.json")


def read_obj(path):
    vs, fs = [], []
    with open(path) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "v":
                vs.append(tuple(map(float, w[1:4])))
            elif w and w[0] == "f":
                fs.append(tuple(int(t.split("/")[0]) - 1 for t in w[1:4]))
    return vs, fs


class SurfacesFileTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="isomesh_surfaces_")

    def run_cli(self, *args):
        return subprocess.run([ISOMESH, *args], capture_output=True, text=True, timeout=120)

    def test_help_names_the_example_file_which_exists(self):
        out = self.run_cli("--help")
        self.assertIn("examples/surfaces.json", out.stdout + out.stderr)
        self.assertTrue(os.path.isfile(EXAMPLE))

    def test_every_example_meshes_and_the_ellipsoid_is_right(self):
        with open(EXAMPLE) as f:
            names = [s["name"] for s in json.load(f)["surfaces"]]
        self.assertGreaterEqual(len(names), 3)
        for name in names:
            out = os.path.join(self.dir, name + ".obj")
            p = self.run_cli("--surfaces", EXAMPLE, "--surface", name, "-d", "3:5", "-o", out)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertGreater(len(read_obj(out)[1]), 100)
        a, b, c = 1.2, 0.8, 0.5
        for shift in (0.0, 1e-3, IRR * 3.0 / 2 ** 6):
            out = os.path.join(self.dir, "e.obj")
            box = ",".join(str(v + shift) for v in (-1.5, -1.5, -1.5, 1.5, 1.5, 1.5))
            # the depth path: its vertices lie on the surface (the default bound's dual
            # vertices sit up to 0.9 E off it, toward the convex side)
            p = self.run_cli("--surfaces", EXAMPLE, "--surface", "ellipsoid", "-d", "3:6",
                             "--max-error", "off", "-b", box, "-o", out)
            self.assertEqual(p.returncode, 0, p.stderr)
            vs, fs = read_obj(out)

            def level(q):  # |F| / |grad F| ~ distance to the ellipsoid
                g = (2 * q[0] / a ** 2, 2 * q[1] / b ** 2, 2 * q[2] / c ** 2)
                f = (q[0] / a) ** 2 + (q[1] / b) ** 2 + (q[2] / c) ** 2 - 1
                return abs(f) / max(1e-12, sum(t * t for t in g) ** 0.5)
            self.assertLess(max(level(v) for v in vs), 1e-6)
            cents = [tuple(sum(vs[i][k] for i in t) / 3 for k in range(3)) for t in fs]
            self.assertLess(max(level(q) for q in cents), 0.02)

    def write(self, doc):
        path = os.path.join(self.dir, "s.json")
        with open(path, "w") as f:
            f.write(doc if isinstance(doc, str) else json.dumps(doc))
        return path

    def test_each_wrong_shape_has_its_own_error(self):
        ok = {"name": "s", "expr": "x^2 + y^2 + z^2 - 1"}
        cases = [
            ([1, 2], "$: expected an object with a \"surfaces\" array"),
            ({"surfaces": {"s": ok}}, "$: expected an object with a \"surfaces\" array"),
            ({"surfaces": ["s"]}, "$.surfaces[0]: expected an object with a \"name\" string"),
            ({"surfaces": [{"expr": "x"}]}, "$.surfaces[0]: expected an object with a \"name\""),
            ({"surfaces": [{"name": "s", "expr": 3}]}, "$.surfaces[0].expr: expected a string"),
            ({"surfaces": [dict(ok, params=[1])]}, "$.surfaces[0].params: expected an object of numbers"),
            ({"surfaces": [dict(ok, params={"r": "1"})]}, "$.surfaces[0].params.r: expected a number"),
            ({"surfaces": [dict(ok, let=["a"])]}, "$.surfaces[0].let: expected an object"),
            ({"surfaces": [dict(ok, let={"a": 1})]}, "$.surfaces[0].let.a: expected a string"),
            ({"surfaces": [dict(ok, box=[0, 0, 0, 1, 1])]}, "$.surfaces[0].box: expected six numbers"),
            ({"surfaces": [dict(ok, box=[0, 0, 0, 1, -1, 1])]}, "each min < max"),
            ({"surfaces": [dict(ok, name="t")]}, "no surface named 's'"),
            ('{"surfaces": [', "line 1, column"),
        ]
        for doc, want in cases:
            path = self.write(doc)
            p = self.run_cli("--surfaces", path, "--surface", "s", "-o",
                             os.path.join(self.dir, "x.ply"))
            self.assertEqual(p.returncode, 2, (doc, p.stderr))
            self.assertIn(want, p.stderr, doc)
            self.assertEqual(p.stderr.count("\n"), 1, p.stderr)

    def test_missing_file_says_so_without_a_position(self):
        p = self.run_cli("--surfaces", os.path.join(self.dir, "nope.json"), "--surface", "s",
                         "-o", os.path.join(self.dir, "x.ply"))
        self.assertEqual(p.returncode, 2)
        self.assertIn("cannot read the surfaces file", p.stderr)
        self.assertIn("nope.json", p.stderr)
        self.assertNotIn("-1", p.stderr)


if __name__ == "__main__":
    unittest.main()
