"""test_request_file.py — the service pipeline end to end through `isomesh REQUEST.json -o FILE`
(server/common/pipeline.c): every format is written and read back by an independent reader
(Debian's draco_decoder, the Khronos glTF validator with draco3d, PLY/STL/OBJ parsers here),
the stats agree with the files, one key serves every format and every equivalent request,
empty surfaces get the documented empty files, bad requests fail with their JSON path."""
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import placements  # noqa: E402
from drc import decode_drc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")
VALIDATOR = os.path.join(ROOT, "tests", "unit", "proto", "validate_gltf.mjs")
EVERY_ATTRIBUTE = ["normal", "mean_curvature", "gauss_curvature", "class"]

TORUS = {"preset": "torus", "depth": {"max": 5}}


class RequestFileTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="isomesh-cli-request-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def run_request(self, request, ext, expect_ok=True):
        """Runs one request; returns (stats dict or None, output path, completed process)."""
        req = os.path.join(self.dir, "request.json")
        with open(req, "w") as f:
            f.write(request if isinstance(request, str) else json.dumps(request))
        out = os.path.join(self.dir, "out." + ext)
        if os.path.exists(out):
            os.unlink(out)
        proc = subprocess.run([ISOMESH, req, "-o", out, "--stats"], capture_output=True,
                              text=True, timeout=120)
        if not expect_ok:
            return None, out, proc
        self.assertEqual(proc.returncode, 0, proc.stderr)
        return json.loads(proc.stdout), out, proc

    def test_drc_decodes_with_draco_decoder_to_the_stated_counts(self):
        stats, out, _ = self.run_request(TORUS, "drc")
        self.assertEqual(stats["format"], "drc")
        self.assertEqual(os.path.getsize(out), stats["bytes"])
        self.assertFalse(stats["empty"])
        obj = os.path.join(self.dir, "decoded.obj")
        subprocess.run(["draco_decoder", "-i", out, "-o", obj], check=True, timeout=60,
                       capture_output=True)
        with open(obj) as f:
            lines = f.read().splitlines()
        verts = sum(1 for l in lines if l.startswith("v "))
        faces = sum(1 for l in lines if l.startswith("f "))
        self.assertEqual(verts, stats["mesh"]["encoded_points"])
        self.assertEqual(faces, stats["mesh"]["encoded_faces"])
        self.assertEqual(faces, stats["analysis"]["triangles_used"])
        self.assertEqual(stats["analysis"]["euler"], 0, "a torus has Euler characteristic 0")

    def test_glb_is_valid_and_decodes(self):
        stats, out, _ = self.run_request({"preset": "klein-bottle", "depth": {"max": 6},
                                          "max_error": None,
                                          "output": {"attributes": EVERY_ATTRIBUTE}}, "glb")
        self.assertGreater(stats["analysis"]["nonmanifold_edges"], 0)
        proc = subprocess.run(["node", VALIDATOR, out], capture_output=True, text=True,
                              timeout=120, cwd=ROOT)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        report = json.loads(proc.stdout)
        self.assertEqual(report["errors"], 0, report["messages"])
        draco = report["draco"][0]
        self.assertTrue(draco["accessors_match"])
        self.assertEqual(draco["points"], stats["mesh"]["encoded_points"])
        self.assertEqual(draco["faces"], stats["mesh"]["encoded_faces"])
        for name in ("POSITION", "NORMAL", "_MEAN_CURVATURE", "_GAUSS_CURVATURE", "_CLASS"):
            self.assertTrue(draco["attributes"][name]["found"], name)
        self.assertEqual(draco["attributes"]["_CLASS"]["max"], 2, "non-manifold edges arrive")
        with open(out, "rb") as f:
            data = f.read()
        jlen = struct.unpack_from("<I", data, 12)[0]
        gltf = json.loads(data[20:20 + jlen])
        names = {n["name"] for n in gltf["nodes"]}
        self.assertIn("surface", names)
        self.assertIn("nonmanifold_curves", names)

    def test_ply_stl_obj_agree_with_the_stats(self):
        stats, out, _ = self.run_request(TORUS, "ply")
        with open(out, "rb") as f:
            data = f.read()
        head = data[:data.index(b"end_header\n")].decode()
        self.assertIn("format binary_little_endian 1.0", head)
        self.assertIn(f"element vertex {stats['mesh']['vertices']}", head)
        self.assertIn(f"element face {stats['mesh']['triangles']}", head)
        stats, out, _ = self.run_request(TORUS, "stl")
        with open(out, "rb") as f:
            data = f.read()
        count = struct.unpack_from("<I", data, 80)[0]
        self.assertEqual(count, stats["mesh"]["triangles"])
        self.assertEqual(len(data), 84 + 50 * count)
        stats, out, _ = self.run_request(TORUS, "obj")
        with open(out) as f:
            lines = f.read().splitlines()
        self.assertEqual(sum(l.startswith("v ") for l in lines), stats["mesh"]["vertices"])
        self.assertEqual(sum(l.startswith("f ") for l in lines), stats["mesh"]["triangles"])

    def drc_of(self, request):
        """(stats, bytes, decoded by draco3d) of request as .drc."""
        stats, out, _ = self.run_request(request, "drc")
        with open(out, "rb") as f:
            data = f.read()
        return stats, data, decode_drc(data, self.dir)

    def test_default_payload_is_normals_only_and_curvature_comes_when_asked(self):
        """A request that leaves output.attributes out gets positions and normals, what the
        viewer's shaded view draws: draco3d decodes no curvature and no class, and naming
        ["normal"] is the same key and the same bytes. Asked for, the curvatures arrive under
        their fixed ids with the sphere's closed-form values (|H| = 1/r, K = 1/r^2 at
        vertices on f = 0: the depth path), in boxes on and off the octree lattice; and
        they cost bytes: on gyroid-ball the default payload is smaller than with them."""
        r = 0.8
        cell = 2.0 / 2 ** 5
        for box in placements([-1, -1, -1, 1, 1, 1], cell):
            sphere = {"expr": "x^2 + y^2 + z^2 - 0.64", "box": box, "depth": {"min": 3, "max": 5},
                      "max_error": None}
            stats, plain, d = self.drc_of(sphere)
            self.assertEqual(d["attributes"], {"position": 0, "normal": 1}, box)
            self.assertNotIn("mean_curvature", d)
            named, same, _ = self.drc_of(dict(sphere, output={"attributes": ["normal"]}))
            self.assertEqual(named["key"], stats["key"], "the default named is the same request")
            self.assertEqual(same, plain)
            curved, data, c = self.drc_of(dict(sphere, output={"attributes": EVERY_ATTRIBUTE}))
            self.assertNotEqual(curved["key"], stats["key"])
            self.assertEqual(c["attributes"], {"position": 0, "normal": 1, "mean_curvature": 2,
                                               "gauss_curvature": 3, "class": 4}, box)
            self.assertEqual(c["faces"], d["faces"])
            self.assertEqual(len(c["mean_curvature"]), c["points"])
            for h, k in zip(c["mean_curvature"], c["gauss_curvature"]):
                self.assertAlmostEqual(abs(h), 1 / r, delta=1e-4 / r)
                self.assertAlmostEqual(k, 1 / r ** 2, delta=1e-4 / r ** 2)
            self.assertGreater(len(data), len(plain))
        # (its crease cells' labels travel whatever the attributes: openapi "cell")
        gyroid = {"preset": "gyroid-ball", "depth": {"max": 5}, "max_error": None}
        stats, plain, d = self.drc_of(gyroid)
        self.assertEqual(d["attributes"], {"position": 0, "normal": 1, "cell": 5})
        for attributes in (["normal", "mean_curvature"], EVERY_ATTRIBUTE):
            curved, data, c = self.drc_of(dict(gyroid, output={"attributes": attributes}))
            self.assertEqual(sorted(c["attributes"]), sorted(attributes + ["position", "cell"]))
            self.assertEqual(c["faces"], d["faces"])
            print("# gyroid-ball d5 drc bytes: default %d, %s %d" % (len(plain), "+".join(attributes),
                                                                  len(data)))
            self.assertLess(len(plain), len(data))

    def test_one_key_for_every_format_and_every_equivalent_request(self):
        keys = set()
        for ext in ("drc", "glb", "ply", "obj", "stl"):
            stats, _, _ = self.run_request(TORUS, ext)
            keys.add(stats["key"])
        written_out = {"expr": "(x^2+y^2+z^2+R^2-r^2)^2 - 4*R^2*(x^2+y^2)",
                       "params": {"r": 0.3, "R": 1.0},
                       "box": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5],
                       "depth": {"min": 3, "max": 5},
                       "output": {"format": "stl"}}
        stats, _, _ = self.run_request(written_out, "drc")
        keys.add(stats["key"])
        self.assertEqual(len(keys), 1, keys)
        stats, _, _ = self.run_request({"preset": "torus", "depth": {"max": 4}}, "drc")
        self.assertNotIn(stats["key"], keys)

    def test_empty_surfaces_get_the_documented_empty_files(self):
        nothing = {"expr": "x^2 + y^2 + z^2 + 1"}
        stats, out, _ = self.run_request(nothing, "drc")
        self.assertTrue(stats["empty"])
        self.assertEqual(os.path.getsize(out), 0)
        self.assertEqual(stats["mesh"]["triangles"], 0)
        stats, out, _ = self.run_request(nothing, "glb")
        self.assertTrue(stats["empty"])
        proc = subprocess.run(["node", VALIDATOR, out], capture_output=True, text=True,
                              timeout=120, cwd=ROOT)
        self.assertEqual(json.loads(proc.stdout)["errors"], 0)
        stats, out, _ = self.run_request(nothing, "ply")
        with open(out, "rb") as f:
            self.assertIn(b"element vertex 0\n", f.read())

    def test_bad_requests_fail_with_their_path(self):
        cases = [
            ({"preset": "torus", "depth": {"max": 17}}, "$.depth.max: 17 is above the limit 16"),
            ({"expr": "x^2 + sinn(y)"}, "$.expr: column 7: unknown function 'sinn'"),
            ({"expr": "x", "tolerance": {}}, "$.tolerance: unknown field"),
            ('{"expr": "x", "expr": "y"}', "invalid JSON at line 1"),
        ]
        for request, message in cases:
            _, out, proc = self.run_request(request, "drc", expect_ok=False)
            self.assertEqual(proc.returncode, 2, proc.stderr)
            self.assertIn(message, proc.stderr)
            self.assertFalse(os.path.exists(out), "no file is left behind")


if __name__ == "__main__":
    unittest.main()
