"""test_singular.py — the singular structure found from f, end to end through `isomesh
--features --stats` (and the glb's locus nodes), in boxes shifted off the octree lattice (by 1e-3 and by irrational fractions of
a finest cell: boxes.py), never only in symmetric ones. Every expected value comes from the closed
form of the surface: node positions, curve radii, counts, and the mesh's own structure (one vertex
with two cones of faces at a node, one component where two spheres cross, no non-manifold element
off the locus)."""
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import placements  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")

MAX_DEPTH = 6


def shifted_boxes(half):
    """The symmetric box [-half, half]^3 and its copies shifted off the lattice (boxes.py)."""
    return placements([-half] * 3 + [half] * 3, 2 * half / 2 ** MAX_DEPTH)


def diagonal(box):
    return math.dist(box[:3], box[3:])


def mesh(expr, box, extra=()):
    """(stats, features) of one run; extra: more command-line arguments."""
    with tempfile.TemporaryDirectory() as tmp:
        feats = os.path.join(tmp, "f.json")
        r = subprocess.run([ISOMESH, "-e", expr, *extra, "-b", ",".join(repr(v) for v in box),
                            "-d", f"3:{MAX_DEPTH}", "--stats", "--features", feats],
                           capture_output=True, text=True, timeout=300)
        if r.returncode != 0:
            raise AssertionError(f"isomesh failed ({r.returncode}): {r.stderr}")
        with open(feats) as f:
            return json.loads(r.stdout), json.load(f)


def f_and_grad(f, p, h=1e-6):
    """f and its gradient by central differences: a check of a closed form that shares
    nothing with the code under test."""
    g = []
    for k in range(3):
        a, b = list(p), list(p)
        a[k] += h
        b[k] -= h
        g.append((f(*a) - f(*b)) / (2 * h))
    return f(*p), g


class SingularPointsTest(unittest.TestCase):
    def assert_nodes(self, stats, feats, box, expected):
        pts = feats["singular_points"]
        self.assertEqual(len(pts), len(expected), pts)
        for want in expected:
            near = [p for p in pts if math.dist(p["xyz"], want) < 1e-9 * diagonal(box)]
            self.assertEqual(len(near), 1, f"no node at {want}: {[p['xyz'] for p in pts]}")
            p = near[0]
            self.assertEqual(p["type"], "node")
            self.assertTrue(p["certified"])
            self.assertLessEqual(p["radius"], 1e-9 * diagonal(box))
            self.assertEqual(p["cones"], 2, "a node is one vertex where two cones of faces meet")
        an = stats["analysis"]
        self.assertEqual(an["nonmanifold_vertices"], len(expected))
        self.assertEqual(an["nonmanifold_edges"], 0)
        self.assertEqual(stats["singular"]["artefacts"], 0)

    def test_tilted_cone_has_one_node_at_the_origin(self):
        expr = "x^2 + 2*y^2 - 3*z^2 + 0.5*x*z"
        for box in shifted_boxes(1.0):
            with self.subTest(box=box):
                stats, feats = mesh(expr, box)
                self.assert_nodes(stats, feats, box, [[0.0, 0.0, 0.0]])
                self.assertEqual(stats["analysis"]["vertex_components"], 1,
                                 "both nappes meet at the apex")

    def test_kummer_four_nodes_where_the_closed_form_puts_them(self):
        # (x²+y²+z²−μ²)² − λ p q r s with the tetrahedron p, q, r, s of w = 1: the nodes lie at
        # (±√2 b, 0, b) and (0, ±√2 b, −b), b = (1 − μ²) / 2 (checked below to be critical
        # zeros of f by finite differences).
        mu2, w = 0.6667, 1.0
        lam = (3 * mu2 - 1) / (3 - mu2)
        s2 = math.sqrt(2)

        def f(x, y, z):
            p, q = w - z - s2 * x, w - z + s2 * x
            r, s = w + z + s2 * y, w + z - s2 * y
            return (x * x + y * y + z * z - mu2) ** 2 - lam * p * q * r * s

        b = (1 - mu2) / 2
        nodes = [[s2 * b, 0, b], [-s2 * b, 0, b], [0, s2 * b, -b], [0, -s2 * b, -b]]
        for n in nodes:
            v, g = f_and_grad(f, n)
            self.assertLess(abs(v), 1e-12)
            self.assertLess(max(map(abs, g)), 1e-8)
        expr = ("(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s")
        lets = {"lambda": "(3*mu2 - 1)/(3 - mu2)", "p": "w - z - sqrt(2)*x",
                "q": "w - z + sqrt(2)*x", "r": "w + z + sqrt(2)*y", "s": "w + z - sqrt(2)*y"}
        for box in shifted_boxes(1.0):
            with self.subTest(box=box):
                args = []
                for k, v in lets.items():
                    args += ["--let", f"{k}={v}"]
                stats, feats = mesh(expr, box, args + ["-p", f"mu2={mu2}", "-p", f"w={w}"])
                self.assert_nodes(stats, feats, box, nodes)


class SingularCurvesTest(unittest.TestCase):
    def test_two_spheres_crossing_share_one_circle(self):
        # Spheres of radius 1 centred at x = ±0.5 cross in the circle x = 0, r = √0.75.
        expr = "((x-0.5)^2 + y^2 + z^2 - 1)*((x+0.5)^2 + y^2 + z^2 - 1)"
        for box in shifted_boxes(1.6):
            with self.subTest(box=box):
                stats, feats = mesh(expr, box)
                curves = feats["curves"]
                self.assertEqual(len(curves), 1, [c["kind"] for c in curves])
                c = curves[0]
                self.assertEqual(c["kind"], "double")
                self.assertTrue(c["closed"])
                xyz = c["xyz"]
                for i in range(0, len(xyz), 3):
                    self.assertLess(abs(xyz[i]), 1e-6)
                    self.assertLess(abs(math.hypot(xyz[i + 1], xyz[i + 2]) - math.sqrt(0.75)), 1e-6)
                an = stats["analysis"]
                self.assertEqual(an["components"], 1, "the spheres are joined along the circle")
                self.assertGreater(an["nonmanifold_edges"], 0)
                self.assertEqual(stats["singular"]["artefacts"], 0)
                self.assertEqual(an["boundary_edges"], 0)

    def test_two_spheres_touching_share_one_vertex(self):
        # Unit spheres centred at x = ±1 touch only at the origin: there f = 0 and ∇f = 0
        # (a contact, Hessian rank 1: reported uncertified with a proved existence radius).
        # The mesh: two spheres joined at one vertex where two cones of faces meet, so
        # χ = 2 + 2 − 1 = 3, one piece through that vertex, nothing else non-manifold and no
        # curve (the "before": χ = −10 and a short curve 2 cells from the contact).
        # Box ±2.5: no placement cuts a sphere.
        expr = "((x-1)^2 + y^2 + z^2 - 1)*((x+1)^2 + y^2 + z^2 - 1)"
        for box in shifted_boxes(2.5):
            with self.subTest(box=box):
                stats, feats = mesh(expr, box, ["--max-error", "off"])
                pts = feats["singular_points"]
                self.assertEqual(len(pts), 1, pts)
                p = pts[0]
                self.assertEqual((p["type"], p["cones"]), ("degenerate", 2))
                self.assertLessEqual(math.dist(p["xyz"], (0, 0, 0)), p["exists_within"])
                self.assertLessEqual(p["exists_within"], 1e-6 * diagonal(box))
                self.assertEqual(feats["curves"], [])
                nmp = feats["nonmanifold_points"]
                self.assertEqual([q["kind"] for q in nmp], ["cones"])
                self.assertLess(math.dist(nmp[0]["xyz"], (0, 0, 0)), 1e-6)
                an = stats["analysis"]
                self.assertEqual((an["nonmanifold_vertices"], an["nonmanifold_edges"]), (1, 0))
                self.assertEqual(an["vertex_components"], 1, "joined at the contact")
                self.assertEqual(an["euler"], 3)
                self.assertEqual(an["boundary_edges"], 0)
                self.assertEqual(stats["singular"]["artefacts"], 0)

    def test_a_whisker_circle_has_no_sheet_and_length_pi(self):
        expr = "(x^2 + y^2 - 0.25)^2 + z^2"
        for box in shifted_boxes(1.0):
            with self.subTest(box=box):
                stats, feats = mesh(expr, box)
                curves = feats["curves"]
                self.assertEqual(len(curves), 1)
                c = curves[0]
                self.assertEqual(c["kind"], "whisker")
                self.assertTrue(c["closed"])
                xyz = c["xyz"]
                pts = [xyz[i:i + 3] for i in range(0, len(xyz), 3)]
                length = sum(math.dist(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts)))
                self.assertLess(abs(length - math.pi) / math.pi, 0.005)
                self.assertEqual(stats["mesh"]["triangles"], 0)


class DoubleSheetTest(unittest.TestCase):
    def test_a_squared_sphere_is_a_closed_double_sheet(self):
        # (x²+y²+z²−0.5)² never changes sign: no edge of the octree sees a crossing, yet its
        # zero set is the sphere of radius √0.5, area 4π·0.5.
        for box in shifted_boxes(1.0):
            with self.subTest(box=box):
                stats, feats = mesh("(x^2 + y^2 + z^2 - 0.5)^2", box)
                sheets = feats["double_sheets"]
                self.assertEqual(len(sheets), 1)
                self.assertEqual(sheets[0]["triangles"], stats["mesh"]["triangles"])
                self.assertLess(abs(sheets[0]["area"] - 2 * math.pi) / (2 * math.pi), 0.01)
                an = stats["analysis"]
                self.assertEqual(an["euler"], 2)
                self.assertEqual(an["boundary_edges"], 0)
                self.assertLess(an["accuracy"]["max_dist_vertex"], 1e-9)

    def test_x_squared_is_the_plane_x_0_cut_by_the_box(self):
        for box in shifted_boxes(1.0):
            with self.subTest(box=box):
                stats, feats = mesh("x^2", box)
                area = (box[4] - box[1]) * (box[5] - box[2])
                self.assertEqual(len(feats["double_sheets"]), 1)
                self.assertLess(abs(stats["analysis"]["area"] - area) / area, 1e-9)
                self.assertEqual(stats["analysis"]["euler"], 1)


def preset_boxes(box, depth):
    """The preset's own box and its copies shifted off its lattice (boxes.py)."""
    side = max(box[3] - box[0], box[4] - box[1], box[5] - box[2])
    return placements(box, side / 2 ** depth)


def preset(name, box, depth):
    with tempfile.TemporaryDirectory() as tmp:
        feats = os.path.join(tmp, "f.json")
        r = subprocess.run([ISOMESH, "--surface", name, "-b", ",".join(repr(v) for v in box),
                            "-d", f"3:{depth}", "--stats", "--features", feats],
                           capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            raise AssertionError(f"isomesh failed ({r.returncode}): {r.stderr}")
        with open(feats) as f:
            return json.loads(r.stdout), json.load(f)


PRESET_BOXES = {"kummer-4-nodes": [-3, -3, -3, 3, 3, 3], "kummer-16-nodes": [-3, -3, -3, 3, 3, 3],
                "steiner-roman": [-1, -1, -1, 1, 1, 1], "klein-bottle": [-4, -4, -4, 4, 4, 4],
                "sphere": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5], "torus": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5],
                "heart": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5],
                "cross-cap": [-1.2, -1.2, -1.2, 1.2, 1.2, 1.2]}


class PresetsOffTheLatticeTest(unittest.TestCase):
    """The presets' singular structure, the same in their own boxes and in boxes moved off
    the lattice, with nothing non-manifold off the locus."""

    def run_preset(self, name, depth):
        for box in preset_boxes(PRESET_BOXES[name], depth):
            with self.subTest(preset=name, box=box, depth=depth):
                stats, feats = preset(name, box, depth)
                self.assertEqual(stats["singular"]["artefacts"], 0)
                self.assertFalse(feats["incomplete"])
                yield stats, feats

    def test_smooth_presets_have_no_singular_structure(self):
        for name, chi in (("sphere", 2), ("torus", 0)):
            for stats, feats in self.run_preset(name, 6):
                self.assertEqual(feats["singular_points"], [])
                self.assertEqual(feats["curves"], [])
                self.assertEqual(stats["analysis"]["euler"], chi)

    def test_heart_is_a_sphere_with_two_cusps(self):
        # (x² + 9/4 y² + z² − 1)³ − x²z³ − 9/80 y²z³: ∇f = 0 on f = 0 at the cusps (0, 0, ±1)
        # (H of rank 2, f_zzz ≠ 0) and on the ring z = 0, x² + 9/4 y² = 1, where f vanishes to
        # third order but its zero set is a smooth sheet; the surface is a topological sphere.
        for stats, feats in self.run_preset("heart", 6):
            pts = feats["singular_points"]
            self.assertEqual(sorted(round(p["xyz"][2]) for p in pts), [-1, 1])
            for p in pts:
                self.assertEqual(p["type"], "cusp")
                self.assertEqual(p["certificate"], "deflation")
                self.assertLess(max(abs(p["xyz"][0]), abs(p["xyz"][1]), abs(abs(p["xyz"][2]) - 1)), 1e-9)
            self.assertEqual(feats["curves"], [])
            self.assertEqual(stats["analysis"]["euler"], 2)
            self.assertEqual(stats["analysis"]["components"], 1)
            self.assertEqual(stats["analysis"]["nonmanifold_vertices"], 0)

    def test_kummer_nodes(self):
        for name, nodes, depth in (("kummer-4-nodes", 4, 7), ("kummer-16-nodes", 16, 6)):
            for stats, feats in self.run_preset(name, depth):
                pts = feats["singular_points"]
                self.assertEqual(len(pts), nodes)
                self.assertTrue(all(p["type"] == "node" and p["certified"] and p["cones"] == 2
                                    for p in pts))
                self.assertEqual(stats["analysis"]["nonmanifold_vertices"], nodes)
                # nothing else non-manifold: no edge of more than two triangles
                self.assertEqual(stats["analysis"]["nonmanifold_edges"], 0)

    def test_steiner_double_lines_pinch_and_triple_points(self):
        # x²y² + y²z² + z²x² + xyz: the axes are double lines from the triple point at the
        # origin to pinch points at ±1/2, whiskers beyond them.
        want_pinch = {(sx * 0.5 if k == 0 else 0, sx * 0.5 if k == 1 else 0, sx * 0.5 if k == 2 else 0)
                      for k in range(3) for sx in (-1, 1)}
        for stats, feats in self.run_preset("steiner-roman", 6):
            pts = feats["singular_points"]
            pinch = [p["xyz"] for p in pts if p["type"] == "pinch"]
            triple = [p["xyz"] for p in pts if p["type"] == "triple"]
            self.assertEqual(len(pinch), 6)
            for w in want_pinch:
                self.assertTrue(any(math.dist(w, p) < 1e-6 for p in pinch), w)
            self.assertEqual(len(triple), 1)
            self.assertLess(math.dist(triple[0], (0, 0, 0)), 1e-6)
            # certified by their defining systems: rank 1 (pinch), rank 0 (triple)
            for p in pts:
                want = "rank-1 system" if p["type"] == "pinch" else "rank-0 system"
                self.assertEqual((p["certified"], p["certificate"]), (True, want), p)
                self.assertLess(p["perturbation"], 1e-9)
                self.assertNotIn("uncertified_reason", p)
            kinds = sorted(c["kind"] for c in feats["curves"])
            self.assertEqual(kinds, ["double"] * 6 + ["whisker"] * 6)
            self.assertEqual(stats["analysis"]["euler"], 5)
            # every curve lies on an axis: each point as printed (rounded by the digits its
            # certificate allows, proto/features.h) is within sqrt 2 x the stated radius of it
            for c in feats["curves"]:
                self.assert_printed_within(c, lambda p: sorted(abs(v) for v in p)[:2])

    def assert_printed_within(self, curve, off):
        """Each printed point p of a certified curve lies within sqrt 2 x its stated
        certificate_radius of the closed form: off(p) lists p's offsets from it."""
        self.assertTrue(curve["certified"])
        r = curve["certificate_radius"]
        self.assertGreater(r, 0)
        self.assertLess(r, 1e-9, "r + rounding stays far below the 1e-9 x diagonal trace bound")
        xyz = curve["xyz"]
        for i in range(0, len(xyz), 3):
            d = math.hypot(*off(xyz[i:i + 3]))
            self.assertLessEqual(d, math.sqrt(2) * r + 1e-15, (xyz[i:i + 3], d, r))

    def test_cross_cap_chains_close_round_the_zero_axis(self):
        # 4x²(x² + y² + z² + z) + y²(y² + z² − 1) is 0 (and ∇f with it) on the whole z axis: a
        # double segment between the pinch points (0, 0, 0) and (0, 0, 1), whiskers beyond.
        # In the own box the axis runs along cell edges; the cells beside z = 0, z = ±1 had a
        # face line leave that zero edge at a singular point (an end at z = 0, inside it at
        # z = ±1), which the walk dropped: 28 open chains at depths 6 and 7 (face_lines.c,
        # singular_run). In every box: no open chain, χ 2 and one component (as
        # tube_folds/pinch_points_few_turned_over counts the mesh), one non-manifold chain
        # from pinch point to pinch point, nothing else non-manifold.
        for depth in (6, 7):
            for stats, feats in self.run_preset("cross-cap", depth):
                self.assertEqual(stats["polygoniser"]["open_chains"], 0)
                self.assertEqual(stats["analysis"]["euler"], 2)
                self.assertEqual(stats["analysis"]["components"], 1)
                pinch = sorted(p["xyz"][2] for p in feats["singular_points"] if p["type"] == "pinch")
                self.assertEqual(len(pinch), 2)
                self.assertLess(max(abs(pinch[0]), abs(pinch[1] - 1)), 1e-9)
                chains = feats["nonmanifold_edges"]
                self.assertEqual(len(chains), 1)
                self.assertFalse(chains[0]["closed"])
                xyz = chains[0]["xyz"]
                ends = sorted((xyz[0:3], xyz[-3:]), key=lambda p: p[2])
                self.assertLess(math.dist(ends[0], (0, 0, 0)), 1e-6)
                self.assertLess(math.dist(ends[1], (0, 0, 1)), 1e-6)
                self.assertEqual([p["kind"] for p in feats["nonmanifold_points"]],
                                 ["curve_end", "curve_end"])

    def test_klein_bottle_self_intersection_circle(self):
        # The figure-8 Klein bottle crosses itself along x² + (y − 1)² = 2 in z = 0.
        for stats, feats in self.run_preset("klein-bottle", 6):
            curves = feats["curves"]
            self.assertEqual([(c["kind"], c["closed"]) for c in curves], [("double", True)])
            xyz = curves[0]["xyz"]
            for i in range(0, len(xyz), 3):
                self.assertLess(abs(xyz[i + 2]), 1e-6)
                self.assertLess(abs(math.hypot(xyz[i], xyz[i + 1] - 1) - math.sqrt(2)), 1e-6)
            # as printed (features.h's digits), within sqrt 2 x the stated radius of the circle
            self.assert_printed_within(curves[0], lambda p: (
                p[2], math.hypot(p[0], p[1] - 1) - math.sqrt(2)))
            self.assertEqual(stats["analysis"]["euler"], 0)


def glb_nodes(data):
    """{node name: (extras, mode, [float32 positions])} of a glb's non-surface nodes, read
    from the container by hand (no glTF library)."""
    jlen = struct.unpack_from("<I", data, 12)[0]
    js = json.loads(data[20:20 + jlen])
    blen = struct.unpack_from("<I", data, 20 + jlen)[0]
    bin_ = data[28 + jlen:28 + jlen + blen]
    out = {}
    for n in js["nodes"]:
        prim = js["meshes"][n["mesh"]]["primitives"][0]
        if "POSITION" not in prim["attributes"] or "extensions" in prim:
            continue
        acc = js["accessors"][prim["attributes"]["POSITION"]]
        view = js["bufferViews"][acc["bufferView"]]
        off = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        pts = [struct.unpack_from("<3f", bin_, off + 12 * i) for i in range(acc["count"])]
        out[n["name"]] = (n.get("extras", {}), prim.get("mode", 4), pts)
    return out


class GlbLocusTest(unittest.TestCase):
    def test_steiner_locus_travels_as_points_and_lines(self):
        # x²y² + y²z² + z²x² + xyz (closed form, see PresetsOffTheLatticeTest): the triple
        # point at 0, pinch points at ±1/2 on each axis, double segments |t| < 1/2 on the
        # axes, whiskers |t| > 1/2 to the box. The glb carries them as a POINTS node
        # "singular_points" (extras: type, certified, xyz per point) and LINES nodes
        # "double_curves" / "whiskers" (extras: kind, curves), positions as float32.
        f32 = 1e-6  # float32 of coordinates ≤ 1.01: half an ulp is 6e-8
        want = [(0.0, 0.0, 0.0)] + [tuple(s * 0.5 if k == a else 0.0 for k in range(3))
                                    for a in range(3) for s in (-1, 1)]
        for box in shifted_boxes(1.0):
            with self.subTest(box=box), tempfile.TemporaryDirectory() as tmp:
                out, req = os.path.join(tmp, "m.glb"), os.path.join(tmp, "r.json")
                with open(req, "w") as f:  # the CLI writes a glb only from a request file
                    json.dump({"preset": "steiner-roman", "box": box, "max_error": None,
                               "depth": {"min": 3, "max": MAX_DEPTH}}, f)
                r = subprocess.run([ISOMESH, req, "-o", out], capture_output=True, text=True,
                                   timeout=300)
                self.assertEqual(r.returncode, 0, r.stderr)
                with open(out, "rb") as f:
                    nodes = glb_nodes(f.read())
                ex, mode, pts = nodes["singular_points"]
                self.assertEqual(mode, 0)  # POINTS
                self.assertEqual(len(pts), 7)
                self.assertEqual(sorted(ex["type"]), ["pinch"] * 6 + ["triple"])
                self.assertEqual(ex["certified"], [True] * 7)
                xyz = [ex["xyz"][3 * i:3 * i + 3] for i in range(7)]
                for i, w in enumerate(want):  # each closed-form point exactly once
                    near = [j for j in range(7) if math.dist(xyz[j], w) < 1e-9 * diagonal(box)]
                    self.assertEqual(len(near), 1, (w, xyz))
                    j = near[0]
                    self.assertEqual(ex["type"][j], "triple" if i == 0 else "pinch")
                    self.assertLess(math.dist(pts[j], w), f32)
                for name, kind, inside in (("double_curves", "double", True),
                                           ("whiskers", "whisker", False)):
                    ex, mode, pts = nodes[name]
                    self.assertEqual(mode, 1)  # LINES
                    self.assertEqual((ex["kind"], ex["curves"]), (kind, 6))
                    ends = [0, 0, 0]  # points at each axis's far end of the kind's range
                    for p in pts:
                        a = max(range(3), key=lambda k: abs(p[k]))
                        off_axis = max(abs(p[k]) for k in range(3) if k != a)
                        self.assertLess(off_axis, f32, (name, p))
                        t = abs(p[a])
                        if inside:
                            self.assertLess(t, 0.5 + f32, (name, p))
                        else:
                            self.assertGreater(t, 0.5 - f32, (name, p))
                        self.assertTrue(all(box[k] - f32 <= p[k] <= box[k + 3] + f32
                                            for k in range(3)), (name, p))
                        ends[a] += abs(t - 0.5) < f32
                    # every axis reaches its pinch points (both signs: 2 ends per axis, or
                    # 4 if the double segment through 0 is cut there into two curves)
                    self.assertTrue(all(e >= 2 for e in ends), (name, ends))


OPENAPI = os.path.join(ROOT, "proto", "openapi.yaml")
JSON_TYPES = {"object": dict, "array": list, "string": str, "boolean": bool, "integer": int,
              "number": (int, float), "null": type(None)}


def schema_errors(value, schema, schemas, path="Features"):
    """Where value departs from an OpenAPI schema (the subset openapi.yaml uses: $ref, oneOf,
    allOf (of object parts), type (or a list of types), const, enum, minimum, properties, required, items, minItems,
    maxItems): a field the schema does not name, a required one missing, a wrong type or
    value, an object documented only as a bare {type: object}. A small reader of its own, no
    jsonschema dependency."""
    while "$ref" in schema:
        schema = schemas[schema["$ref"].split("/")[-1]]
    if "allOf" in schema:  # an object made of parts: their properties and required together
        whole = {"type": "object", "properties": {}, "required": []}
        for part in schema["allOf"]:
            while "$ref" in part:
                part = schemas[part["$ref"].split("/")[-1]]
            whole["properties"].update(part.get("properties", {}))
            whole["required"] += part.get("required", [])
        schema = whole
    if "oneOf" in schema:
        tries = [schema_errors(value, alt, schemas, path) for alt in schema["oneOf"]]
        return [] if [] in tries else min(tries, key=len)
    errs = []
    types = schema.get("type")
    if types is not None:
        types = types if isinstance(types, list) else [types]
        if not any(isinstance(value, JSON_TYPES[t])
                   and not (t in ("integer", "number") and isinstance(value, bool))
                   for t in types):
            errs.append(f"{path}: {value!r:.40} is not {types}")
    if "const" in schema and value != schema["const"]:
        errs.append(f"{path}: {value!r} is not {schema['const']!r}")
    if "enum" in schema and value not in schema["enum"]:
        errs.append(f"{path}: {value!r} not in {schema['enum']}")
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if "minimum" in schema and number and value < schema["minimum"]:
        errs.append(f"{path}: {value!r} < {schema['minimum']}")
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0):
            errs.append(f"{path}: {len(value)} items < {schema['minItems']}")
        if len(value) > schema.get("maxItems", len(value)):
            errs.append(f"{path}: {len(value)} items > {schema['maxItems']}")
    if isinstance(value, dict):
        props = schema.get("properties")
        if props is None:
            errs.append(f"{path}: a bare object in the schema")
            props = {}
        errs += [f"{path}: {r} missing" for r in schema.get("required", []) if r not in value]
        for k, v in value.items():
            if k in props:
                errs += schema_errors(v, props[k], schemas, f"{path}.{k}")
            else:
                errs.append(f"{path}.{k}: not in openapi.yaml")
    if isinstance(value, list) and "items" in schema:
        for i, v in enumerate(value):
            errs += schema_errors(v, schema["items"], schemas, f"{path}[{i}]")
    return errs


class FeaturesSchemaTest(unittest.TestCase):
    def test_features_json_is_what_openapi_documents(self):
        # Every field of the features JSON documented in proto/openapi.yaml (Features), of its
        # type and enum, the required ones present: on a locus with certified pinch and triple
        # points and both kinds of curve (Steiner), an uncertified contact with exists_within
        # and uncertified_reason (two spheres touching), and a double sheet (x², the plane
        # x = 0: a third of the squared sphere's time).
        # Fields, not geometry: the irrational placement only (the others run above).
        import yaml
        with open(OPENAPI) as f:
            schemas = yaml.safe_load(f)["components"]["schemas"]
        cases = (("x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", 1.0),
                 ("((x-1)^2 + y^2 + z^2 - 1)*((x+1)^2 + y^2 + z^2 - 1)", 2.0),
                 ("x^2", 1.0))
        seen = set()
        for expr, half in cases:
            box = shifted_boxes(half)[-1]
            with self.subTest(expr=expr):
                stats, feats = mesh(expr, box, ["--max-error", "off"])
                self.assertEqual(schema_errors(feats, schemas["Features"], schemas), [])
                self.assert_stats(stats, schemas)
                seen |= {k for p in feats["singular_points"] for k in p}
                seen |= {"double_sheets"} if feats["double_sheets"] else set()
        # the cases reach the optional fields they are here for
        self.assertLessEqual({"uncertified_reason", "exists_within", "perturbation",
                              "double_sheets"}, seen)

    def assert_stats(self, stats, schemas):
        """The whole stats JSON against openapi's Stats (every field written is documented, of
        its type), and its analysis block both ways: a field written but not documented
        fails, and so does a documented one not written (every documented field of the
        analysis is required: the writer, proto/stats.c, always writes them all)."""
        self.assertEqual(schema_errors(stats, schemas["Stats"], schemas, "Stats"), [])
        if "analysis" not in stats:  # a preview
            return
        schema = schemas["Stats"]["properties"]["analysis"]
        self.assertEqual(schema_errors(stats["analysis"], schema, schemas, "analysis"), [])
        for name, sub in (("analysis", schema), *schema["properties"].items()):
            if sub.get("type") == "object":
                self.assertEqual(set(sub.get("required", [])), set(sub["properties"]),
                                 f"{name}: every documented field is required")

    def test_stats_are_what_openapi_documents(self):
        # The stats JSON documented in openapi's Stats, and its analysis block (23 figures,
        # vertex_classes, quality, accuracy) field by field both ways: under a bound with the
        # simplification and the quality pass (accuracy's max_error a number, met a boolean;
        # the cases above have no bound: both null), for an empty mesh (every figure 0, genus
        # -1), and a preview (no analysis; its preview block). Then the reader itself: a field
        # deleted from the schema, or from the stats, is found.
        import copy
        import yaml
        with open(OPENAPI) as f:
            schemas = yaml.safe_load(f)["components"]["schemas"]
        box = shifted_boxes(1.0)[-1]
        runs = []
        for expr, extra in (("x^2 + y^2 + z^2 - 0.6",
                             ["--max-error", "0.004", "--simplify", "--quality", "good"]),
                            ("x^2 + y^2 + z^2 - 100", ["--max-error", "off"])):
            with self.subTest(expr=expr):
                stats, _ = mesh(expr, box, extra)
                self.assert_stats(stats, schemas)
                runs.append(stats)
        self.assertLessEqual({"simplify", "remesh", "singular"}, set(runs[0]))
        with tempfile.TemporaryDirectory() as tmp:
            req = os.path.join(tmp, "preview.json")
            with open(req, "w") as f:
                json.dump({"expr": "x^2 + y^2 + z^2 - 0.6", "box": box, "preview": True,
                           "max_error": None, "depth": {"min": 3, "max": MAX_DEPTH}}, f)
            r = subprocess.run([ISOMESH, req, "--stats", "-o", os.path.join(tmp, "p.ply")],
                               capture_output=True, text=True, timeout=300)
            self.assertEqual(r.returncode, 0, r.stderr)
            preview = json.loads(r.stdout)
        self.assertIn("preview", preview)
        self.assert_stats(preview, schemas)
        bounded, empty = (s["analysis"] for s in runs)
        self.assertEqual((bounded["accuracy"]["max_error"], bounded["accuracy"]["met"]),
                         (0.004, True))
        self.assertEqual((empty["edges"], empty["genus"], empty["accuracy"]["met"]), (0, -1, None))
        self.assertEqual(bounded["genus"], 0)  # a sphere
        schema = schemas["Stats"]["properties"]["analysis"]
        for field in schema["properties"]:
            undocumented = copy.deepcopy(schema)
            del undocumented["properties"][field]
            self.assertIn(f"analysis.{field}: not in openapi.yaml",
                          schema_errors(bounded, undocumented, schemas, "analysis"))
            missing = {k: v for k, v in bounded.items() if k != field}
            self.assertIn(f"analysis: {field} missing",
                          schema_errors(missing, schema, schemas, "analysis"))


if __name__ == "__main__":
    unittest.main()
