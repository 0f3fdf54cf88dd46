"""test_one_computation.py — one polygonisation per surface and accuracy (issue 18, item 5):
drc, then ply, obj and a 12-bit drc with other attributes of the same surface are encoded
from the stored computed surface ("<surface key>.mesh"): isomesh_polygonisations_total moves
by exactly one, isomesh_stored_encodings_total by three. The encodings made from the stored
surface are the very bytes a fresh daemon computes for the same requests, their vertex counts
agree with the stats, and every answer carries proto/format.c's Content-Type. A second
accuracy (depth) is a second polygonisation. Formats asked for at the same time, before the
surface is computed, are one polygonisation too (the pool holds the others behind it), and so
is a format asked for after the first answer, while its surface is still being stored (the
test gate holds the store)."""
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ROOT, Daemon, draco_counts  # noqa: E402

VALIDATOR = os.path.join(ROOT, "tests", "unit", "proto", "validate_gltf.mjs")

# proto/format.c's table, written out independently.
MIME = {"drc": "application/vnd.google.draco", "glb": "model/gltf-binary",
        "ply": "application/ply", "obj": "model/obj", "stl": "model/stl"}

BASE = {"expr": "x^2 + y^2 - z^2 - 0.3 + a*x*y*z", "params": {"a": 1.7},
        "box": [-1.1, -1.1, -1.1, 1.1, 1.1, 1.1], "depth": {"min": 3, "max": 6}}


def with_(**kw):
    r = dict(BASE)
    r.update(kw)
    return r


def ply_vertex_count(body):
    head = body[:body.index(b"end_header")].decode()
    for line in head.splitlines():
        if line.startswith("element vertex"):
            return int(line.split()[2])
    raise AssertionError("no vertex element")


class OneComputationTest(unittest.TestCase):
    def counters(self, d):
        return (d.metric("isomesh_polygonisations_total") or 0,
                d.metric("isomesh_stored_encodings_total") or 0)

    def test_concurrent_formats_one_polygonisation(self):
        # A surface that takes the worker a while (depth 7, ~1 s): drc, ply and glb asked for
        # at once with two workers free. Without holding, two workers would each polygonise.
        req = with_(params={"a": 1.3}, depth={"min": 3, "max": 7})
        with Daemon("--workers", "2") as d:
            p0, s0 = self.counters(d)
            with ThreadPoolExecutor(3) as ex:
                answers = list(ex.map(lambda fmt: d.post("/v1/mesh?format=" + fmt, req, timeout=300),
                                      ("drc", "ply", "glb")))
            for r in answers:
                self.assertEqual(r.status, 200, r.body[:300])
                self.assertEqual(r.header("X-Cache"), "miss")
            self.assertEqual(len({r.header("ETag") for r in answers}), 1)
            stats = d.get("/v1/meshes/%s/stats" % answers[0].header("ETag").strip('"')).json()
            self.assertEqual(ply_vertex_count(answers[1].body), stats["mesh"]["vertices"])
            self.assertEqual(self.counters(d), (p0 + 1, s0 + 2))

    def test_a_format_asked_while_the_surface_is_stored_waits_for_it(self):
        # W_STORING's hold, deterministically: the test gate (ISOMESHD_TEST_SURFACE_GATE)
        # keeps the drc's surface from being stored until the test creates the gate file, so
        # a ply of the same surface asked for meanwhile, with a second worker idle, can only
        # be held (isomesh_flights_held) or polygonised again. Held, it is answered once the
        # surface is stored, encoded from it: one polygonisation, one stored encoding.
        tmp = tempfile.mkdtemp(prefix="isomesh_gate_")
        gate = os.path.join(tmp, "open")
        req = with_(params={"a": 1.21})
        env = dict(os.environ, ISOMESHD_TEST_SURFACE_GATE=gate)
        try:
            with Daemon("--workers", "2", env=env) as d:
                p0, s0 = self.counters(d)
                r = d.post("/v1/mesh?format=drc", req)  # answered before its surface is stored
                self.assertEqual(r.status, 200, r.body[:300])
                self.assertTrue(d.wait_metric("isomesh_workers_storing", 1), d.log())
                with ThreadPoolExecutor(1) as ex:
                    ply = ex.submit(d.post, "/v1/mesh?format=ply", req, timeout=300)
                    self.assertTrue(d.wait_metric("isomesh_flights_held", 1),
                                    "the ply was not held behind the stored surface:\n" + d.log())
                    self.assertFalse(ply.done())
                    self.assertEqual(self.counters(d), (p0 + 1, s0))
                    open(gate, "w").close()
                    r2 = ply.result()
                self.assertEqual(r2.status, 200, r2.body[:300])
                self.assertEqual(r2.header("X-Cache"), "miss")
                self.assertEqual(self.counters(d), (p0 + 1, s0 + 1))
                self.assertEqual(d.metric("isomesh_workers_storing"), 0)
                self.assertEqual(d.metric("isomesh_flights_held"), 0)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)

    def test_four_encodings_one_polygonisation(self):
        twelve = with_(output={"position_bits": 12, "attributes": ["normal", "class"]})
        asks = [(BASE, "drc"), (BASE, "ply"), (BASE, "obj"), (twelve, "drc"), (BASE, "stl"),
                (BASE, "glb")]
        with Daemon("--workers", "1") as d:
            p0, s0 = self.counters(d)
            bodies = []
            for req, fmt in asks:
                r = d.post("/v1/mesh?format=" + fmt, req)
                self.assertEqual(r.status, 200, r.body[:300])
                self.assertEqual(r.header("Content-Type"), MIME[fmt])
                self.assertEqual(r.header("X-Cache"), "miss")
                bodies.append((r.header("ETag").strip('"'), fmt, r.body))
            p1, s1 = self.counters(d)
            self.assertEqual(p1 - p0, 1, "one polygonisation for one surface")
            self.assertEqual(s1 - s0, len(asks) - 1)
            # the 12-bit drc has its own key and fewer bytes than the 14-bit one
            self.assertNotEqual(bodies[0][0], bodies[3][0])
            self.assertLess(len(bodies[3][2]), len(bodies[0][2]))
            # vertex counts agree with the stats of each key
            stats = d.get("/v1/meshes/%s/stats" % bodies[1][0]).json()
            self.assertEqual(ply_vertex_count(bodies[1][2]), stats["mesh"]["vertices"])
            self.assertIn("polygoniser", stats)
            self.assertGreater(stats["mesh"]["triangles"], 100)
            verts, faces = draco_counts(bodies[3][2])
            st12 = d.get("/v1/meshes/%s/stats" % bodies[3][0]).json()
            self.assertEqual(verts, st12["mesh"]["encoded_points"])
            self.assertEqual(faces, st12["mesh"]["encoded_faces"])
            self.assertEqual(st12["analysis"], stats["analysis"])
            stl = bodies[4][2]
            self.assertEqual(struct.unpack("<I", stl[80:84])[0], stats["mesh"]["triangles"])
            # another accuracy is another surface
            r = d.post("/v1/mesh?format=ply", with_(depth={"min": 3, "max": 5}))
            self.assertEqual(r.status, 200)
            self.assertEqual(self.counters(d)[0] - p0, 2)
        # a fresh daemon computes each of them from scratch: the same bytes
        with Daemon("--workers", "1") as fresh:
            for (req, fmt), (key, _, body) in zip(asks, bodies):
                if fmt in ("drc", "ply") or req is twelve:
                    r = fresh.post("/v1/mesh?format=" + fmt, req)
                    self.assertEqual(r.status, 200)
                    self.assertEqual(r.body, body, "%s of %s differs" % (fmt, key))

    def test_stored_surface_with_split_double_curve(self):
        """Two spheres crossing at 29° at depth 3: the octree is split along their double
        circle (core/singular/curve_cell.h) and the entry keeps the locus with the curve's ends
        and split cell (computed.h, version 4). The glb, which draws the locus, and the obj
        encoded from the stored surface are the bytes a fresh daemon computes for them."""
        req = {"preset": "crossing-spheres",
               "box": [-1.8003, -1.2991, -1.3007, 1.7996, 1.3002, 1.2993],
               "depth": {"min": 3, "max": 3}}
        with Daemon("--workers", "1") as d:
            first = d.post("/v1/mesh?format=ply", req, timeout=300)
            self.assertEqual(first.status, 200, first.body[:300])
            p0, s0 = self.counters(d)
            stored = {fmt: d.post("/v1/mesh?format=" + fmt, req, timeout=300)
                      for fmt in ("glb", "obj")}
            self.assertEqual(self.counters(d), (p0, s0 + 2), "encoded from the stored surface")
            feats = d.get("/v1/meshes/%s/features" % first.header("ETag").strip('"')).json()
            self.assertEqual([c["kind"] for c in feats["curves"]], ["double"])
        with Daemon("--workers", "1") as fresh:
            for fmt, r in stored.items():
                self.assertEqual(r.status, 200, r.body[:300])
                f = fresh.post("/v1/mesh?format=" + fmt, req, timeout=300)
                self.assertEqual(f.status, 200)
                self.assertEqual(f.body, r.body, "%s from the stored surface differs" % fmt)

    def test_get_of_another_format_is_encoded_not_polygonised(self):
        with Daemon("--workers", "1") as d:
            r = d.post("/v1/mesh", with_(params={"a": 0.9}))
            self.assertEqual(r.status, 200)
            key = r.header("ETag").strip('"')
            p0, _ = self.counters(d)
            for fmt in ("glb", "obj", "stl"):
                g = d.get("/v1/meshes/%s.%s" % (key, fmt))
                self.assertEqual(g.status, 200)
                self.assertEqual(g.header("Content-Type"), MIME[fmt])
            self.assertEqual(self.counters(d)[0], p0)
            self.assertEqual(d.get("/v1/meshes/%s.drc" % key).header("Content-Type"), MIME["drc"])

    def test_plain_glb_without_draco(self):
        """?format=glb&draco=0: a glb whose surface is plain accessors (no extension
        required), from the same stored surface; the glTF validator finds no error; its
        positions lie on the sphere and its vertex count is the stats'."""
        sphere = {"expr": "x^2 + y^2 + z^2 - 0.64", "box": [-1.0037, -0.9963, -1, 1, 1.0029, 1],
                  "depth": {"min": 3, "max": 5}, "max_error": None,  # vertices on f = 0
                  "output": {"attributes": ["normal", "mean_curvature", "gauss_curvature",
                                            "class"]}}  # every accessor (the default: normals)
        with Daemon("--workers", "1") as d:
            drc = d.post("/v1/mesh", sphere)
            p0, _ = self.counters(d)
            r = d.post("/v1/mesh?format=glb&draco=0", sphere)
            self.assertEqual(r.status, 200, r.body[:300])
            self.assertEqual(r.header("Content-Type"), MIME["glb"])
            self.assertEqual(self.counters(d)[0], p0, "encoded from the stored surface")
            self.assertNotEqual(r.header("ETag"), drc.header("ETag"))
            body = r.body
            jlen = struct.unpack("<I", body[12:16])[0]
            gltf = json.loads(body[20:20 + jlen])
            self.assertNotIn("extensionsRequired", gltf)
            prim = gltf["meshes"][0]["primitives"][0]
            self.assertNotIn("extensions", prim)
            acc = gltf["accessors"]
            stats = d.get("/v1/meshes/%s/stats" % r.header("ETag").strip('"')).json()
            pos = acc[prim["attributes"]["POSITION"]]
            self.assertEqual(pos["count"], stats["mesh"]["vertices"])
            self.assertEqual(acc[prim["indices"]]["count"] % 3, 0)
            self.assertEqual(sorted(prim["attributes"]),
                             ["NORMAL", "POSITION", "_CLASS", "_GAUSS_CURVATURE", "_MEAN_CURVATURE"])
            view = gltf["bufferViews"][pos["bufferView"]]
            bin_at = 20 + jlen + 8
            xyz = struct.unpack_from("<%df" % (3 * pos["count"]), body, bin_at + view["byteOffset"])
            radii = [math.sqrt(sum(c * c for c in xyz[3 * i:3 * i + 3])) for i in range(pos["count"])]
            self.assertAlmostEqual(min(radii), 0.8, delta=1e-5)
            self.assertAlmostEqual(max(radii), 0.8, delta=1e-5)
            path = os.path.join(d.tmp, "plain.glb")
            with open(path, "wb") as f:
                f.write(body)
            proc = subprocess.run(["node", VALIDATOR, path], capture_output=True, text=True,
                                  timeout=120, cwd=ROOT)
            self.assertEqual(json.loads(proc.stdout)["errors"], 0, proc.stdout[-2000:])
            bad = d.post("/v1/mesh?format=glb&draco=no", sphere)
            self.assertEqual(bad.status, 400)


if __name__ == "__main__":
    unittest.main()
