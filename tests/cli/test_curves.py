"""test_curves.py — requested curves through the service pipeline (`isomesh REQUEST.json -o FILE
--features F`): the unit sphere cut by the planes x = 0, y = 0 and the level z = 0 gives the
arrangement 6 / 12 / 8 with faces of area pi/2 (0.5%) and every arc point within 1e-10 of
the box diagonal of the sphere and of its plane (checked here from the closed forms), in a
box shifted off the lattice by sqrt(2) - 1 of a finest cell; a curve that misses the surface gives
no curve and one face, not an error; a bad curve is refused with its JSON path. The Klein
bottle preset cut by x = 0, in its lattice box (the plane through lattice vertices) and boxes
shifted off it by 1e-3 and sqrt(2) - 1 cell: the section is three circles
(closed form below), crossing on the double curve at (0, 1 +- sqrt 2, 0) (vertices typed
double_curve, where the section's arcs end: 4 ends each) and at the four points where the
plane touches the surface (typed branch), each a vertex of degree 4; 12 edges. The cone
x^2 + y^2 = z^2 cut by a plane through its apex (in three boxes): two lines through the node,
one vertex typed singular_point (its index naming the certified node at the origin) of
degree 4, four arcs each one curve from the node to the box (ends singular_point and box), of
the closed-form lengths; V - E + F per component matches on the two nappes. Three
overlapping balls (min of three spheres, in the lattice box and two shifted off it): the
crease is three arcs between the two triple points where all three spheres meet (closed
form: the circumcentre of the centres, +-z), each a vertex of degree 3 within 1e-9 x diagonal,
every crease vertex of the mesh (the .obj's crease_curves) within that of two of the spheres
and every printed crease point within that plus its rounding (the depth path: printed within
a tenth of a finest cell); the mesh stays a sphere (chi 2); cut by
planes a tenth and a fiftieth of a cell past the triple points' heights (two loops each, one
a small curved triangle round the triple point's dimple), 14 / 27 / 15 with no mesh edge
across the crease. The
gyroid-ball preset (max of the gyroid G and the ball B, its box and the two shifted ones, the
default bound E named): every crease vertex of the mesh (the .obj's crease_curves, with the
.obj's own rounding) lies within 1e-9 x diagonal of G = 0 and of B = 0, each evaluated here in
closed form, and every point of the features' crease arcs within that plus the rounding of
the decimals it is printed with. Both crease tests check features.h's rule for the printed
crease: it states "tolerance" = a tenth of E (of a finest cell on the depth path), no number
has more decimals than d (the fewest with (sqrt 3 / 2) 10^-d <= tolerance / 2), each printed
point is a mesh crease vertex rounded, the ends are kept, and every dropped vertex lies
within the tolerance of the printed segment across it. The seven
presets with nodes cut by the viewer's three z planes (-0.5, 0, 0.5), in their own boxes and
the two shifted ones: the arrangement's V - E + F equals V - E + T counted here from the
written mesh's own triangles, and its check passes (a node off the curves, where two cones
each a face of their own meet, was counted once per face: kummer-4-nodes gave 4 for chi 0).
The crossing-spheres preset cut by the same planes (three boxes): the six cut vertices lie
within 1e-9 of the closed-form double circle x = 0, y^2 + z^2 = 1 - d^2/4, and they and the
double-curve chain count as on the locus (artefacts 0): the check allows each chord of the
traced circle its bulge (it counted 10 edges off, the chain 305 in the viewer)."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import drawn  # noqa: E402
from boxes import IRR, placements  # noqa: E402
from test_curve_outputs import ball, ball_grad, gyroid, gyroid_grad  # noqa: E402
from test_surfaces_file import read_obj  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")

DEPTH = 7
SIDE = 2.6
# Three overlapping balls of radius sqrt 0.5 (min of the three) and their triple points
# (x0, 0, +-z0), equidistant from the centres: x0 on the x axis with (0.6 - x0)^2 =
# (x0 + 0.3)^2 + 0.52^2, then z0^2 = 0.5 - (0.6 - x0)^2.
BALLS3 = [(0.6, 0, 0), (-0.3, 0.52, 0), (-0.3, -0.52, 0)]
BALLS3_EXPR = "min(" + ", ".join(f"(x - {cx})^2 + (y - {cy})^2 + z^2 - 0.5"
                                 for cx, cy, _ in BALLS3) + ")"
BALLS3_X0 = (0.36 - 0.09 - 0.52 ** 2) / 1.8
BALLS3_Z0 = math.sqrt(0.5 - (0.6 - BALLS3_X0) ** 2)
SHIFT = IRR * SIDE / 2 ** DEPTH


class CurvesTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="isomesh-curves-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def run_request(self, request, out="out.ply"):
        """Runs request; the curves' lengths and counts here are the depth path's at the
        depth each request gives, so one that names no bound says "max_error": null."""
        req = os.path.join(self.dir, "request.json")
        with open(req, "w") as f:
            json.dump({"max_error": None, **request}, f)
        out, feat = os.path.join(self.dir, out), os.path.join(self.dir, "f.json")
        proc = subprocess.run([ISOMESH, req, "-o", out, "--features", feat],
                              capture_output=True, text=True, timeout=120)
        if proc.returncode != 0:
            return None, proc
        with open(feat) as f:
            return json.load(f), proc

    def crease_printed_and_meshed(self, request, tol_want):
        """The crease of request, as the features JSON prints it and as the mesh has it (the
        .obj's crease_curves): each crease curve and the document state "tolerance" tol_want,
        and the printed crease follows features.h's rule for thinned chains (drawn.py).
        Returns (the features, the printed points, their rounding bound, the mesh's chains of
        (point, its .obj rounding))."""
        f, proc = self.run_request(request, out="out.obj")
        self.assertIsNotNone(f, proc.stderr)
        text = drawn.printed_text(os.path.join(self.dir, "f.json"))
        crease = [c for c in text["curves"] if c["kind"] == "crease"]
        self.assertTrue(crease)
        tol = float(text["tolerance"])
        self.assertAlmostEqual(tol, tol_want, delta=1e-12 * tol_want)
        self.assertEqual({float(c["tolerance"]) for c in crease}, {tol})
        chains = drawn.obj_chains(os.path.join(self.dir, "out.obj"), "crease_curves")
        self.assertTrue(chains)
        pts, rounding = drawn.check_thinned(self, [a for c in crease for a in c["arcs"]],
                                            chains, tol)
        return f, pts, rounding, chains

    def sphere(self, shift, curves):
        lo, hi = -SIDE / 2 + shift, SIDE / 2 + shift
        return {"expr": "x^2 + y^2 + z^2 - 1", "box": [lo, lo, lo, hi, hi, hi],
                "depth": {"max": DEPTH + 1}, "max_error": 1e-3, "curves": curves}

    def test_sphere_octants_on_and_off_the_lattice(self):
        planes = [{"kind": "plane", "normal": [1, 0, 0], "offsets": [0]},
                  {"kind": "plane", "normal": [0, 1, 0], "offsets": [0]},
                  {"kind": "levels", "expr": "z", "values": [0]}]
        for shift in (0.0, SHIFT):
            f, proc = self.run_request(self.sphere(shift, planes))
            self.assertIsNotNone(f, proc.stderr)
            a = f["arrangement"]
            self.assertEqual((len(a["vertices"]), len(a["edges"]), len(a["faces"])), (6, 12, 8))
            self.assertTrue(a["euler"]["ok"])
            self.assertEqual(a["euler"]["mesh"], 2)
            for face in a["faces"]:
                self.assertAlmostEqual(face["area"], math.pi / 2, delta=0.005 * math.pi / 2)
                self.assertEqual(face["euler"], 1)
            cut = [c for c in f["curves"] if c["kind"] in ("section", "level")]
            self.assertEqual(len(cut), 3)
            tol = 1e-10 * math.sqrt(3) * SIDE
            for c in cut:
                self.assertTrue(c["closed"])
                axis = c["source"]  # x, y, z in the order of the request
                for arc in c["arcs"]:
                    for i in range(0, len(arc), 3):
                        p = arc[i:i + 3]
                        r = math.sqrt(sum(v * v for v in p))
                        self.assertLess(abs(r - 1), tol)
                        self.assertLess(abs(p[axis]), tol)

    def test_klein_bottle_section(self):
        # f(0, y, z) = (y^2 + z^2 + 2y - 1) ((y^2 + z^2 - 2y - 1)^2 - 8 z^2): the circles
        # C0 (y + 1)^2 + z^2 = 2 and C+- (y - 1)^2 + (z -+ sqrt 2)^2 = 4. C+ and C- cross on the
        # double curve x^2 + (y - 1)^2 = 2 (z = 0) at y = 1 +- sqrt 2; C0 meets C+- where the
        # plane is tangent to the surface: (1/3, -+ sqrt2/3) and (-1, +- sqrt 2) (solved by hand).
        r2 = math.sqrt(2)
        circles = [(-1, 0, r2), (1, r2, 2), (1, -r2, 2)]
        want = [(1 + r2, 0), (1 - r2, 0), (1 / 3, -r2 / 3), (1 / 3, r2 / 3), (-1, r2), (-1, -r2)]
        length = 2 * math.pi * r2 + 2 * 2 * math.pi * 2
        cell = 8 / 2 ** 7
        for shift in (0.0, 1e-3, IRR * cell):
            d = [0.61 * shift, shift, -0.83 * shift]
            f, proc = self.run_request({
                "preset": "klein-bottle", "depth": {"max": 7},
                "box": [-4 + d[0], -4 + d[1], -4 + d[2], 4 + d[0], 4 + d[1], 4 + d[2]],
                "curves": [{"kind": "plane", "normal": [1, 0, 0], "offsets": [0]}]})
            self.assertIsNotNone(f, proc.stderr)
            a = f["arrangement"]
            self.assertTrue(a["euler"]["ok"])
            self.assertEqual((len(a["vertices"]), len(a["edges"])), (6, 12))
            tol = 1e-9 * math.sqrt(3) * 8
            for i, w in enumerate(want):
                near = [v for v in a["vertices"]
                        if math.hypot(v["xyz"][1] - w[0], v["xyz"][2] - w[1]) < 1e-6]
                self.assertEqual(len(near), 1, (shift, w))
                v = near[0]
                self.assertEqual(v["degree"], 4)
                self.assertEqual(v["type"], "double_curve" if i < 2 else "branch", (shift, w))
                self.assertLess(max(abs(v["xyz"][0]), math.hypot(v["xyz"][1] - w[0],
                                                                 v["xyz"][2] - w[1])), tol)
            cut = [c for c in f["curves"] if c["kind"] == "section"]
            total = sum(c["length"] for c in cut)
            self.assertAlmostEqual(total, length, delta=0.005 * length)
            ends = [e for c in cut for e in c["ends"]]  # every arc end at the double curve
            self.assertEqual(sorted(e["type"] for e in ends), ["double_curve"] * 8)
            for e in ends:
                y = e["xyz"][1]
                self.assertLess(min(abs(y - 1 - r2), abs(y - 1 + r2)), tol)
            self.assertFalse(any(c["closed"] for c in cut))
            for c in cut:
                for arc in c["arcs"]:
                    for i in range(0, len(arc), 3):
                        x, y, z = arc[i:i + 3]
                        off = min(abs(math.hypot(y - cy, z - cz) - r) for cy, cz, r in circles)
                        self.assertLess(max(abs(x), off), tol)

    def test_cone_section_through_the_node(self):
        n = (1.0, 0.3, 0.2)
        # Directions (a, b, 1) on the cone (a^2 + b^2 = 1) and the plane (n.d = 0): the line
        # n0 a + n1 b = -n2 meets the unit circle at foot +- s * (-n1, n0) / |(n0, n1)|.
        m = math.hypot(n[0], n[1])
        foot = [-n[2] * n[0] / m ** 2, -n[2] * n[1] / m ** 2]
        s = math.sqrt(1 - (n[2] / m) ** 2)
        dirs = []
        for sg in (1, -1):
            a, b = foot[0] - sg * s * n[1] / m, foot[1] + sg * s * n[0] / m
            dirs += [(a, b, 1.0), (-a, -b, -1.0)]
        depth, side = 6, 2.0
        cell = side / 2 ** depth
        for shift in (0.0, 1e-3, IRR * cell):
            with self.subTest(shift=shift):
                d = [shift, 0.61 * shift, -0.83 * shift]
                box = [-1 + d[0], -1 + d[1], -1 + d[2], 1 + d[0], 1 + d[1], 1 + d[2]]
                diag = math.sqrt(3) * side
                tol = 1e-9 * diag
                f, proc = self.run_request({
                    "expr": "x^2 + y^2 - z^2", "box": box, "depth": {"max": depth},
                    "curves": [{"kind": "plane", "normal": list(n), "offsets": [0]}]})
                self.assertIsNotNone(f, proc.stderr)
                a = f["arrangement"]
                self.assertTrue(a["euler"]["ok"], a["euler"])
                self.assertEqual(a["euler"]["mesh"], 1)  # two disks sharing the apex
                self.assertEqual(a["components"], 2)
                self.assertEqual((len(a["vertices"]), len(a["edges"]), len(a["faces"])),
                                 (5, 4, 4))
                apex = [v for v in a["vertices"] if v["type"] == "singular_point"]
                self.assertEqual(len(apex), 1)
                self.assertEqual(apex[0]["degree"], 4)
                self.assertLess(max(map(abs, apex[0]["xyz"])), tol)
                node = f["singular_points"][apex[0]["point"]]
                self.assertEqual(node["type"], "node")
                self.assertLess(max(map(abs, node["xyz"])), tol)
                self.assertEqual(sorted(v["type"] for v in a["vertices"]),
                                 ["end"] * 4 + ["singular_point"])
                cut = [c for c in f["curves"] if c["kind"] == "section"]
                self.assertEqual(len(cut), 4)
                want = []
                for dv in dirs:  # to where the ray leaves the box
                    t = min((box[k + 3] if dv[k] > 0 else box[k]) / dv[k] for k in range(3))
                    want.append(t * math.sqrt(sum(x * x for x in dv)))
                got = sorted(c["length"] for c in cut)
                for g, w in zip(got, sorted(want)):
                    self.assertAlmostEqual(g, w, delta=1e-6 * w)
                for c in cut:
                    self.assertFalse(c["closed"])
                    self.assertEqual(sorted(e["type"] for e in c["ends"]),
                                     ["box", "singular_point"])
                    for arc in c["arcs"]:
                        for i in range(0, len(arc), 3):
                            x, y, z = arc[i:i + 3]
                            r = math.sqrt(x * x + y * y + z * z)
                            on_cone = abs(x * x + y * y - z * z) / max(2 * r, 1e-300)
                            self.assertLess(max(abs(n[0] * x + n[1] * y + n[2] * z) /
                                                math.sqrt(sum(v * v for v in n)), on_cone),
                                            tol)

    def test_three_balls_crease_arcs_and_triple_points(self):
        centres, expr, x0, z0 = BALLS3, BALLS3_EXPR, BALLS3_X0, BALLS3_Z0
        depth, side = 6, 3.0
        cell = side / 2 ** depth
        tol = 1e-9 * math.sqrt(3) * side

        def sphere_dist(p, c):
            return abs(math.dist(p, c) - math.sqrt(0.5))

        for shift in (0.0, 1e-3 * cell, IRR * cell):
            with self.subTest(shift=shift):
                d = [shift, 0.61 * shift, -0.83 * shift]
                box = [-side / 2 + d[0], -side / 2 + d[1], -side / 2 + d[2],
                       side / 2 + d[0], side / 2 + d[1], side / 2 + d[2]]
                # the depth path: the crease printed within a tenth of a finest cell
                f, pts, rounding, chains = self.crease_printed_and_meshed(
                    {"expr": expr, "box": box, "depth": {"max": depth}}, 0.1 * cell)
                a = f["arrangement"]
                self.assertTrue(a["euler"]["ok"])
                self.assertEqual(a["euler"]["mesh"], 2)
                self.assertEqual((len(a["vertices"]), len(a["edges"]), len(a["faces"])),
                                 (2, 3, 3))
                for v, sz in zip(sorted(a["vertices"], key=lambda v: v["xyz"][2]), (-1, 1)):
                    self.assertEqual(v["degree"], 3)
                    self.assertLess(math.dist(v["xyz"], (x0, 0, sz * z0)), tol, v)
                arcs = [arc for c in f["curves"] if c["kind"] == "crease" for arc in c["arcs"]]
                self.assertEqual(len(arcs), 3)
                self.assertEqual(len(chains), 3)
                for p, r in (v for ch in chains for v in ch):  # the mesh's: every vertex
                    near = sorted(sphere_dist(p, c) for c in centres)
                    self.assertLess(near[1], tol + r, p)
                for p in pts:  # as printed: within the rounding
                    near = sorted(sphere_dist(p, c) for c in centres)
                    self.assertLess(near[1], tol + rounding, p)

    def test_three_balls_sections_beside_the_triple_points(self):
        """Planes z = c a fraction of a cell off the triple points' heights +-z0 (issue 14's
        near-triple straddles): above the top one the union's section is two loops — the
        outer one and a small curved triangle round the dimple over the triple point, each
        crossing the three crease arcs — and its mirror below the bottom one likewise, so
        the arrangement is V 2 + 12, E 3 x 5 crease pieces + 12 section arcs, F 15 (chi 2),
        the crossings of degree 4 and the triple points of degree 3. No mesh edge joins two
        points on different balls' sides unless one lies on the crease (the closed-form
        nearest sphere), and every section point lies on its plane and on a sphere."""
        centres, expr, z0 = BALLS3, BALLS3_EXPR, BALLS3_Z0
        depth, side = 6, 3.0
        cell = side / 2 ** depth
        tol = 1e-9 * math.sqrt(3) * side
        heights = (z0 + 0.1 * cell, -z0 - 0.02 * cell)

        def values(p):  # each ball's function; f is their min
            return [(p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2 + p[2] ** 2 - 0.5 for c in centres]

        for shift in (0.0, 1e-3 * cell, IRR * cell):
            with self.subTest(shift=shift):
                d = [shift, 0.61 * shift, -0.83 * shift]
                box = [-side / 2 + d[0], -side / 2 + d[1], -side / 2 + d[2],
                       side / 2 + d[0], side / 2 + d[1], side / 2 + d[2]]
                curves = [{"kind": "plane", "normal": [0, 0, 1], "offsets": list(heights)}]
                req = os.path.join(self.dir, "request.json")
                with open(req, "w") as fh:
                    json.dump({"expr": expr, "box": box, "depth": {"max": depth},
                               "max_error": None, "curves": curves}, fh)
                obj, feat = os.path.join(self.dir, "m.obj"), os.path.join(self.dir, "f.json")
                proc = subprocess.run([ISOMESH, req, "-o", obj, "--features", feat],
                                      capture_output=True, text=True, timeout=120)
                self.assertEqual(proc.returncode, 0, proc.stderr)
                with open(feat) as fh:
                    a = json.load(fh)["arrangement"]
                self.assertTrue(a["euler"]["ok"])
                self.assertEqual(a["euler"]["mesh"], 2)
                self.assertEqual((len(a["vertices"]), len(a["edges"]), len(a["faces"])),
                                 (14, 27, 15))
                self.assertEqual(sorted(v["degree"] for v in a["vertices"]), [3] * 2 + [4] * 12)
                verts, tris = read_obj(obj)
                with open(obj) as fh:
                    lines = [[int(x) - 1 for x in w.split()[1:]] for w in fh
                             if w.startswith("l ")]
                side_of, on = [], []
                for p in verts:  # the ball f takes there, and whether p is on the crease
                    g = values(p)
                    order = sorted(range(3), key=lambda i: g[i])
                    grad = max(2 * math.dist(p, (c[0], c[1], 0)) for c in centres)
                    side_of.append(order[0])
                    on.append((g[order[1]] - g[order[0]]) / grad < tol)
                straddle = [(verts[t[i]], verts[t[(i + 1) % 3]]) for t in tris for i in range(3)
                            if not on[t[i]] and not on[t[(i + 1) % 3]]
                            and side_of[t[i]] != side_of[t[(i + 1) % 3]]]
                self.assertGreater(sum(on), 100)  # the crease's vertices told apart
                self.assertEqual(straddle, [], "mesh edges across the crease")
                for chain in lines:
                    for v in chain:
                        p = verts[v]
                        g = min(values(p))
                        near = min(range(3), key=lambda i: values(p)[i])
                        r = math.dist(p, (centres[near][0], centres[near][1], 0))
                        self.assertLess(abs(g) / (2 * r), tol, p)
                sec = [v for chain in lines for v in chain
                       if min(abs(verts[v][2] - h) for h in heights) < 1e-6]
                self.assertGreater(len(sec), 20)
                for v in sec:
                    self.assertLess(min(abs(verts[v][2] - h) for h in heights), tol)

    def check_double_circle(self, text, tol, off):
        """The Klein bottle's double curve as printed (features.h: the certified trace points
        that keep every other one within tol, with their certificate's decimals): each
        printed point within sqrt 2 x certificate_radius of the circle of radius sqrt 2
        (off), the chord between two printed points bulging from the circle by no more than
        tol (the trace between them lay within tol of it), and no fewer points than any such
        polygon needs (chords of angle <= 2 acos(1 - tol / R))."""
        curves = [c for c in text["curves"] if c["kind"] == "double"]
        self.assertEqual(len(curves), 1)
        c = curves[0]
        self.assertTrue(c["closed"])
        self.assertEqual(float(c["tolerance"]), tol)
        r = float(c["certificate_radius"])
        pts = [[float(v) for v in c["xyz"][i:i + 3]] for i in range(0, len(c["xyz"]), 3)]
        self.assertLess(len(pts), c["points"])
        R = math.sqrt(2)
        self.assertGreaterEqual(len(pts), 2 * math.pi / (2 * math.acos(1 - tol / R)))
        for p in pts:
            self.assertLessEqual(off(p), math.sqrt(2) * r + 1e-15, p)
        for a, b in zip(pts, pts[1:] + pts[:1]):  # closed: the last joins the first
            half = math.dist(a, b) / 2
            self.assertLessEqual(R - math.sqrt(max(0, R * R - half * half)), 1.01 * tol, (a, b))

    def test_mesh_chains_drawn_within_the_tolerance(self):
        """features.h's drawing rule on the mesh's own polylines, the default bound E named,
        in three boxes: the document states "tolerance" E / 10; the Klein bottle's
        non-manifold chains, every edge on the locus (the double circle x^2 + (y - 1)^2 = 2,
        z = 0), are thinned (drawn.py's rule against the .obj's nonmanifold_curves), each
        printed point off that circle by no more than the mesh's own chain vertices plus the
        rounding, and its double curve likewise (check_double_circle); Kummer's boundary
        chains (where the box cuts it) are thinned too (against the .obj's boundaries), each
        printed point on a face of the box within the rounding, counts.boundary_edges the
        mesh's."""
        for name, half, depth in (("klein-bottle", 3.0, 6), ("kummer-16-nodes", 3.0, 5)):
            side = 2 * half
            e = 1e-3 * math.sqrt(3) * side
            for box in placements([-half] * 3 + [half] * 3, side / 2 ** depth):
                with self.subTest(preset=name, box=box):
                    f, proc = self.run_request({"preset": name, "box": box, "max_error": e,
                                                "depth": {"max": depth}}, out="out.obj")
                    self.assertIsNotNone(f, proc.stderr)
                    text = drawn.printed_text(os.path.join(self.dir, "f.json"))
                    tol = float(text["tolerance"])
                    self.assertAlmostEqual(tol, 0.1 * e, delta=1e-12 * e)
                    obj = os.path.join(self.dir, "out.obj")
                    if name == "klein-bottle":
                        chains = text["nonmanifold_edges"]
                        self.assertTrue(chains)
                        self.assertTrue(all(c["on_locus"] and not c["off_edges"] for c in chains))
                        mesh = drawn.obj_chains(obj, "nonmanifold_curves")
                        pts, rounding = drawn.check_thinned(self, [c["xyz"] for c in chains],
                                                            mesh, tol)

                        def off(p):
                            return math.hypot(p[2], math.hypot(p[0], p[1] - 1) - math.sqrt(2))
                        own = max(off(p) + r for ch in mesh for p, r in ch)
                        self.assertLess(own, 1e-3)
                        self.assertLessEqual(max(off(p) for p in pts), own + rounding)
                        self.check_double_circle(text, tol, off)
                    else:
                        mesh = drawn.obj_chains(obj, "boundaries")
                        self.assertTrue(mesh)
                        self.assertEqual(text["counts"]["boundary_edges"],
                                         sum(len(ch) - 1 for ch in mesh))
                        pts, rounding = drawn.check_thinned(
                            self, [c["xyz"] for c in text["boundaries"]], mesh, tol)
                        for p in pts:
                            face = min(abs(p[k] - box[k + j]) for k in range(3) for j in (0, 3))
                            self.assertLessEqual(face, rounding, p)

    def test_gyroid_ball_crease_vertices_on_both_branches(self):
        side, depth = 3.0, 6
        tol = 1e-9 * math.sqrt(3) * side
        for box in placements([-side / 2] * 3 + [side / 2] * 3, side / 2 ** depth):
            with self.subTest(box=box):
                # the default bound, named: the crease printed within a tenth of it
                e = 1e-3 * math.sqrt(3) * side
                _, printed, rounding, chains = self.crease_printed_and_meshed(
                    {"preset": "gyroid-ball", "box": box, "depth": {"max": depth},
                     "max_error": e}, 0.1 * e)
                meshed = [v for ch in chains for v in ch]
                self.assertGreater(len(meshed), 1000)
                for what, pts, slack in (("meshed", meshed, None),
                                         ("printed", [(p, rounding) for p in printed], 1.01)):
                    worst = [0.0, 0.0]
                    for p, r in pts:
                        for k, (v, g) in enumerate(((gyroid(p), gyroid_grad(p)),
                                                    (ball(p), ball_grad(p)))):
                            off = abs(v) / math.sqrt(sum(x * x for x in g))
                            # a first-order distance: the printed points' rounding, 1 % more
                            worst[k] = max(worst[k], off - (r * slack if slack else r))
                    self.assertLess(max(worst), tol, f"{len(pts)} {what} crease points: off G "
                                    f"{worst[0]:.2e}, off B {worst[1]:.2e}")

    def test_presets_with_nodes_euler_of_the_arrangement(self):
        # (preset, its box) at depth.max 6: the presets' own 7-9 took 90 s under load, and
        # how a node is counted does not depend on the depth
        presets = (("kummer-4-nodes", [-3] * 3 + [3] * 3), ("kummer-16-nodes", [-3] * 3 + [3] * 3),
                   ("cayley-cubic", [-1.3] * 3 + [1.3] * 3),
                   ("chmutov-quartic", [-1.2] * 3 + [1.2] * 3),
                   ("double-cone", [-1] * 3 + [1] * 3), ("ding-dong", [-1.2] * 3 + [1.2] * 3),
                   ("spindle-cyclide", [-26, -24, -24, 26, 24, 24]))
        depth = 6
        planes = [{"kind": "plane", "normal": [0, 0, 1], "offsets": [-0.5, 0, 0.5]}]
        for name, base in presets:
            side = max(base[k + 3] - base[k] for k in range(3))
            for box in placements(base, side / 2 ** depth):
                with self.subTest(preset=name, box=box):
                    f, proc = self.run_request({"preset": name, "box": box, "curves": planes,
                                                "depth": {"max": depth}}, out="out.obj")
                    self.assertIsNotNone(f, proc.stderr)
                    _, tris = read_obj(os.path.join(self.dir, "out.obj"))
                    verts = {v for t in tris for v in t}
                    edges = {(min(a, b), max(a, b)) for t in tris
                             for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
                    chi = len(verts) - len(edges) + len(tris)
                    e = f["arrangement"]["euler"]
                    self.assertGreater(sum(p["type"] == "node" for p in f["singular_points"]), 0)
                    self.assertEqual((e["mesh"], e["arrangement"], e["ok"]), (chi, chi, True))

    def test_crossing_spheres_cut_on_the_double_circle_is_no_artefact(self):
        base = [-1.8, -1.3, -1.3, 1.8, 1.3, 1.3]  # the preset's box, depth.max 7
        r = math.sqrt(1 - 0.5 ** 2 / 4)  # d = 0.5: the spheres cross on x = 0, |(y, z)| = r
        planes = [{"kind": "plane", "normal": [0, 0, 1], "offsets": [-0.5, 0, 0.5]}]
        for box in placements(base, tuple((base[a + 3] - base[a]) / 2 ** 7 for a in range(3))):
            with self.subTest(box=box):
                f, proc = self.run_request({"preset": "crossing-spheres", "box": box,
                                            "curves": planes})
                self.assertIsNotNone(f, proc.stderr)
                cut = [v["xyz"] for v in f["arrangement"]["vertices"]
                       if v["type"] == "double_curve"]
                self.assertEqual(sorted(round(p[2], 6) for p in cut), [-0.5, -0.5, 0, 0, 0.5, 0.5])
                worst = max(max(abs(p[0]), abs(math.hypot(p[1], p[2]) - r)) for p in cut)
                self.assertLess(worst, 1e-9, "cut vertices off the closed-form double circle")
                self.assertEqual(f["counts"]["artefacts"], 0)
                self.assertTrue(all(c["on_locus"] for c in f["nonmanifold_edges"]))

    def test_a_curve_missing_the_surface_is_no_curve(self):
        f, proc = self.run_request(self.sphere(0.0, [{"kind": "plane", "normal": [0, 0, 1],
                                                      "offsets": [1.2]}]))
        self.assertIsNotNone(f, proc.stderr)
        self.assertEqual([c for c in f["curves"] if c["kind"] == "section"], [])
        self.assertEqual(len(f["arrangement"]["faces"]), 1)
        self.assertEqual(f["arrangement"]["faces"][0]["euler"], 2)

    def test_bad_curve_names_its_path(self):
        f, proc = self.run_request(self.sphere(0.0, [{"kind": "levels", "expr": "x +",
                                                      "values": [0]}]))
        self.assertIsNone(f)
        self.assertIn("$.curves[0].expr", proc.stderr)


if __name__ == "__main__":
    unittest.main()
