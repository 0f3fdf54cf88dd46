"""test_python_client.py — proto/clients/python/isomesh_client.py against a real daemon
(issue 18, item 6): mesh() answers with the key, stats and the URL of every format
(Accept: application/json), and the PLY and OBJ it loads without numpy hold as many vertices
and triangles as the stats say; job().wait(); a sweep of 5 parameter values gives 5 meshes
whose vertex counts match their stats and whose radii follow the parameter (a sphere of
radius r has its vertices at distance r); the sweep's bounds and errors."""
import math
import os
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from harness import ROOT, Daemon  # noqa: E402

sys.path.insert(0, os.path.join(ROOT, "proto", "clients", "python"))
import isomesh_client  # noqa: E402

SPHERE = {"expr": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1},
          "box": [-1.3, -1.3, -1.3, 1.3, 1.3, 1.3], "depth": {"min": 3, "max": 5}}


class PythonClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.d = Daemon("--workers", "2")
        try:
            cls.d.start()
        except Exception:
            cls.d.cleanup()
            raise
        cls.c = isomesh_client.Client("http://127.0.0.1:%d" % cls.d.port)

    @classmethod
    def tearDownClass(cls):
        cls.d.stop()
        cls.d.cleanup()

    def test_mesh_links_and_loaders(self):
        m = self.c.mesh(dict(SPHERE, params={"r": 0.8}))
        self.assertRegex(m.key, "^[0-9a-f]{64}$")
        for fmt in ("drc", "glb", "ply", "obj", "stl"):
            self.assertEqual(m.urls[fmt], "/v1/meshes/%s.%s" % (m.key, fmt))
        self.assertEqual(m.urls["stats"], "/v1/meshes/%s/stats" % m.key)
        nv, nt = m.stats["mesh"]["vertices"], m.stats["mesh"]["triangles"]
        ply = m.load("ply")
        self.assertEqual(len(ply.vertices), nv)
        self.assertEqual(len(ply.faces), nt)
        self.assertEqual(len(ply.props["nx"]), nv)
        obj = m.load("obj")
        self.assertEqual(len(obj.vertices), nv)
        self.assertEqual(len(obj.faces), nt)
        for v in ply.vertices[::50]:
            self.assertAlmostEqual(math.sqrt(sum(c * c for c in v)), 0.8, delta=0.02)
        # ?format=json gives the same document as Accept: application/json
        r = self.d.post("/v1/mesh?format=json", dict(SPHERE, params={"r": 0.8}))
        self.assertEqual(r.status, 200)
        self.assertEqual(r.header("Content-Type"), "application/json")
        self.assertEqual(r.json()["key"], m.key)
        self.assertEqual(r.json()["stats"]["mesh"]["vertices"], nv)

    def test_job_wait(self):
        m = self.c.job(dict(SPHERE, params={"r": 0.7}), format="obj").wait(timeout=60)
        self.assertEqual(m.format, "obj")
        obj = isomesh_client.load_obj(m.fetch())
        self.assertEqual(len(obj.vertices), m.stats["mesh"]["vertices"])

    def test_sweep_of_five(self):
        radii = [0.5, 0.6, 0.7, 0.9, 1.1]
        jobs = self.c.sweep(SPHERE, {"r": radii}, format="ply")
        self.assertEqual(len(jobs), 5)
        self.assertEqual([j.params["r"] for j in jobs], radii)
        keys = set()
        for j, r in zip(jobs, radii):
            m = j.wait(timeout=120)
            keys.add(m.key)
            ply = isomesh_client.load_ply(m.fetch("ply"))
            self.assertEqual(len(ply.vertices), m.stats["mesh"]["vertices"])
            self.assertEqual(len(ply.faces), m.stats["mesh"]["triangles"])
            mean = sum(math.sqrt(sum(c * c for c in v)) for v in ply.vertices) / len(ply.vertices)
            self.assertAlmostEqual(mean, r, delta=0.01 * r + 0.005)
        self.assertEqual(len(keys), 5)

    def test_sweep_grid_order_and_refusals(self):
        jobs = self.c.sweep(dict(SPHERE, expr="x^2 + y^2 + z^2 - r^2 + 0*s"),
                            {"r": [0.5, 0.6], "s": [1, 2, 3]})
        self.assertEqual([(j.params["r"], j.params["s"]) for j in jobs],
                         [(0.5, 1), (0.5, 2), (0.5, 3), (0.6, 1), (0.6, 2), (0.6, 3)])
        with self.assertRaises(isomesh_client.IsomeshError) as e:
            self.c.sweep(SPHERE, {"r": [0.1 * i for i in range(1, 66)]})
        self.assertEqual(e.exception.status, 422)
        with self.assertRaises(isomesh_client.IsomeshError) as e:
            self.c.sweep(SPHERE, {"r": []})
        self.assertEqual(e.exception.status, 400)
        with self.assertRaises(isomesh_client.IsomeshError) as e:
            self.c.sweep(SPHERE, {"r": [0.5, 0.6]}, format="gif")
        self.assertEqual(e.exception.status, 400)
        self.assertIn("grid point 0", e.exception.message)
        with self.assertRaises(isomesh_client.IsomeshError) as e:
            self.c.sweep(dict(SPHERE, depth={"min": 3, "max": 40}), {"r": [0.5]})
        self.assertEqual(e.exception.status, 422)

    def test_ply_attributes_and_obj_features(self):
        # a cylinder of radius r cut by the box (off the octree lattice): two boundary circles
        r = math.sqrt(0.5)
        cyl = {"expr": "x^2 + y^2 - 0.5", "box": [-1.0037, -0.9963, -1.0013, 0.9971, 1.0029, 0.9987],
               "depth": {"min": 3, "max": 6}, "max_error": None,
               "output": {"attributes": ["normal", "mean_curvature", "gauss_curvature", "class"]}}
        m = self.c.mesh(cyl, format="ply")
        ply = m.load("ply")
        self.assertEqual(sorted(ply.props), ["class", "gauss_curvature", "mean_curvature",
                                             "nx", "ny", "nz"])
        h = sorted(abs(v) for v in ply.props["mean_curvature"])
        self.assertAlmostEqual(h[len(h) // 2], 1 / (2 * r), delta=0.05 / (2 * r))
        k = sorted(abs(v) for v in ply.props["gauss_curvature"])
        self.assertLess(k[len(k) // 2], 0.05)
        obj = m.load("obj")
        self.assertEqual(len(obj.vertices), len(ply.vertices))
        self.assertEqual(len(obj.lines), 2)
        on_lines = set()
        for line in obj.lines:
            self.assertEqual(line[0], line[-1])  # closed circles
            zs = [obj.vertices[i][2] for i in line]
            self.assertAlmostEqual(min(zs), max(zs), delta=1e-6)
            for i in line:
                x, y, _ = obj.vertices[i]
                self.assertAlmostEqual(math.hypot(x, y), r, delta=2e-3)
            on_lines.update(line)
        boundary = {i for i, c in enumerate(ply.props["class"]) if c == 1}
        self.assertEqual(on_lines, boundary)
        # two planes crossing along the z axis: one non-manifold curve, on x = y = 0
        planes = self.c.mesh({"expr": "x*y", "box": cyl["box"], "depth": {"min": 3, "max": 5}},
                             format="obj")
        obj = planes.load("obj")
        text = planes.fetch().decode()
        self.assertIn("g nonmanifold_curves", text)
        curve = obj.lines[0]
        for i in curve:
            x, y, _ = obj.vertices[i]
            self.assertLess(math.hypot(x, y), 1e-6)
        zs = sorted(obj.vertices[i][2] for i in curve)
        self.assertAlmostEqual(zs[0], cyl["box"][2], delta=1e-6)
        self.assertAlmostEqual(zs[-1], cyl["box"][5], delta=1e-6)


if __name__ == "__main__":
    unittest.main()
