"""test_curve_outputs.py — the arrangement and the requested curves in every output format,
decoded by readers independent of the encoders: the unit sphere cut by the planes x = 0,
y = 0, z = 0 (in a box on the octree lattice and one shifted sqrt(2) - 1 of a finest cell off it).

- .drc (npm draco3d): every decoded triangle's three points carry one cell id, and the ids
  partition the triangles into exactly the features' faces — each face's triangle count, and
  its area summed from the decoded positions within 0.1% of the reported area and 0.5% of
  pi/2 (the closed form: an octant of the unit sphere).
- .glb (shifted box): the same through its KHR_draco_mesh_compression primitive (_CELL), and the curves as
  LINES nodes "section_curves" whose points lie on the sphere and on a coordinate plane.
- .obj (shifted box): a group `section_curves` of one `l` line per arrangement edge, on the sphere and a
  plane; .ply: the face property `cell` with the faces' counts and areas.
- Double sheets: f = s1 * s2^2 (two spheres of radius 0.4, the second a double sheet): the
  decoded double_sheet flag marks exactly the sheet's triangles (count as reported, all at
  x < 0, area 4 pi 0.16 within 1%), never a mixed triangle; with a section asked for too
  (the cut renumbers triangles: each takes its parent's flag).
- Crease normals: gyroid-ball (max of a gyroid G and a ball B) in a box on the lattice and
  ones shifted off it. In the decoded .drc and in the .obj every corner's normal is its
  triangle's branch gradient (closed form, G or B by the sign of B - G at the corner farthest
  from the crease: at the centroid, a sliver along the crease reads the wrong side) within
  1 degree, and at crease points the two sides' normals differ by the angle between grad G
  and grad B there (within 1 degree); likewise in the .ply away from the crease, whose rows
  are the mesh's vertices (one row per position; a crease point's one normal, the sides' sum,
  is checked against the closed forms in test_crease_files.py). Triangles whose side the
  14-bit positions cannot decide
  (every corner closer to the crease than 4 quantisation steps) are left out."""
import json
import math
import os
import shutil
import struct
import subprocess
import tempfile
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import IRR  # noqa: E402  (the placements' table: sqrt(2) - 1 of a cell)
from drc import decode_drc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")

DEPTH = 6
SIDE = 2.6
CELL = SIDE / 2 ** DEPTH
PLANES = [{"kind": "plane", "normal": n, "offsets": [0]}
          for n in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]
FLOAT_TOL = 1e-6   # float32 positions of points within 1e-10 of both surfaces
ON_CREASE = 1e-6   # a float32 crease vertex's distance to the crease (Newton: ~1e-12)


def box(side, shift):
    lo, hi = -side / 2 + shift, side / 2 + shift
    return [lo, lo, lo, hi, hi, hi]


def tri_area(p, q, r):
    u = [q[k] - p[k] for k in range(3)]
    w = [r[k] - p[k] for k in range(3)]
    c = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
    return 0.5 * math.sqrt(sum(v * v for v in c))


def glb_chunks(data):
    jlen = struct.unpack_from("<I", data, 12)[0]
    js = json.loads(data[20:20 + jlen])
    blen = struct.unpack_from("<I", data, 20 + jlen)[0]
    return js, data[28 + jlen:28 + jlen + blen]


def labels_by_triangle(d, name):
    """Each decoded triangle's label; fails on a triangle whose points disagree."""
    vals, idx = d[name]["values"], d["index"]
    out = []
    for t in range(d["faces"]):
        a, b, c = (vals[idx[3 * t + k]] for k in range(3))
        if not a == b == c:
            raise AssertionError(f"triangle {t} has points of {name} {a}, {b}, {c}")
        out.append(a)
    return out


def decoded_triangles(d):
    p, idx = d["position"], d["index"]
    return [[p[3 * idx[3 * t + k]:3 * idx[3 * t + k] + 3] for k in range(3)]
            for t in range(d["faces"])]


GYROID_K = 4.0
GYROID_BALL = ("max(sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x), "
               "x^2 + y^2 + z^2 - 1.96)")


def gyroid(p):
    x, y, z = (GYROID_K * v for v in p)
    return math.sin(x) * math.cos(y) + math.sin(y) * math.cos(z) + math.sin(z) * math.cos(x)


def gyroid_grad(p):
    x, y, z = (GYROID_K * v for v in p)
    k = GYROID_K
    return [k * (math.cos(x) * math.cos(y) - math.sin(z) * math.sin(x)),
            k * (math.cos(y) * math.cos(z) - math.sin(x) * math.sin(y)),
            k * (math.cos(z) * math.cos(x) - math.sin(y) * math.sin(z))]


def ball(p):
    return sum(v * v for v in p) - 1.96


def ball_grad(p):
    return [2 * v for v in p]


def angle_deg(u, v):
    nu, nv = math.sqrt(sum(a * a for a in u)), math.sqrt(sum(a * a for a in v))
    d = sum(a * b for a, b in zip(u, v)) / (nu * nv)
    return math.degrees(math.acos(max(-1.0, min(1.0, d))))


def read_ply(data):
    """(rows [(x, y, z, nx, ny, nz)], faces [(a, b, c)], header) of a binary PLY with float
    x y z nx ny nz first among its vertex properties (the service's, with normals)."""
    head_end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:head_end].decode()
    nv = int(head.split("element vertex ")[1].split()[0])
    nt = int(head.split("element face ")[1].split()[0])
    vhead, fhead = head.split("element vertex")[1].split("element face")
    assert vhead.split("property")[4].split()[1] == "nx"
    vbytes = 4 * vhead.count("property float") + vhead.count("property uchar")
    fextra = 4 * fhead.count("property uint") + fhead.count("property uchar")
    rows = [struct.unpack_from("<6f", data, head_end + vbytes * i) for i in range(nv)]
    at, faces = head_end + vbytes * nv, []
    for _ in range(nt):
        assert data[at] == 3
        faces.append(struct.unpack_from("<3i", data, at + 1))
        at += 13 + fextra
    assert at == len(data)
    return rows, faces, head


def parse_ply_corners(data):
    """[(corner positions, corner normals)] per face of read_ply's PLY."""
    rows, faces, _ = read_ply(data)
    return [([list(rows[i][:3]) for i in ids], [list(rows[i][3:]) for i in ids])
            for ids in faces]


def ply_rows(data):
    """The `element vertex` count of a PLY."""
    return len(read_ply(data)[0])


def unused_ply_rows(data):
    """Vertex rows of read_ply's PLY that no face uses."""
    rows, faces, _ = read_ply(data)
    return len(rows) - len({i for ids in faces for i in ids})


def unused_obj_vertices(text):
    """`v` lines of an OBJ that no face or line uses."""
    nv, used = 0, set()
    for line in text.splitlines():
        w = line.split()
        if w and w[0] == "v":
            nv += 1
        elif w and w[0] in ("f", "l"):
            used.update(int(x.split("/")[0]) for x in w[1:])
    return nv - len(used)


def parse_obj_corners(text):
    """[(corner positions, corner normals)] per face of an OBJ with `f v//n` faces."""
    v, vn, faces = [], [], []
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            v.append([float(a) for a in parts[1:4]])
        elif parts[0] == "vn":
            vn.append([float(a) for a in parts[1:4]])
        elif parts[0] == "f":
            ids = [[int(i) - 1 for i in c.split("//")] for c in parts[1:4]]
            faces.append(([v[a] for a, _ in ids], [vn[b] for _, b in ids]))
    return faces


class CurveOutputsTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="isomesh-curve-outputs-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def run_request(self, request, fmt):
        """Runs request; these tests are written for the depth path at the depth each gives,
        so a request that names no bound says "max_error": null."""
        req = os.path.join(self.dir, "request.json")
        with open(req, "w") as f:
            json.dump({"max_error": None, **request}, f)
        out, feat = os.path.join(self.dir, "out." + fmt), os.path.join(self.dir, "f.json")
        proc = subprocess.run([ISOMESH, req, "-o", out, "--features", feat],
                              capture_output=True, text=True, timeout=120)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(feat) as f, open(out, "rb") as g:
            return json.load(f), g.read()

    def sphere(self, shift):
        return {"expr": "x^2 + y^2 + z^2 - 1", "box": box(SIDE, shift),
                "depth": {"max": DEPTH}, "curves": PLANES}

    def assert_cells_partition(self, cells, triangles, faces):
        """cells: per triangle; triangles: their corners; faces: the features' faces."""
        self.assertEqual(len(faces), 8)
        count, area = {}, {}
        for c, tri in zip(cells, triangles):
            count[c] = count.get(c, 0) + 1
            area[c] = area.get(c, 0.0) + tri_area(*tri)
        self.assertEqual(sorted(count), [f["id"] for f in faces])
        for f in faces:
            self.assertEqual(count[f["id"]], f["triangles"], f)
            self.assertLess(abs(area[f["id"]] - f["area"]) / f["area"], 1e-3, f)
            self.assertLess(abs(area[f["id"]] - math.pi / 2) / (math.pi / 2), 0.005, f)

    def assert_on_sphere_and_a_plane(self, pts):
        self.assertTrue(pts)
        for p in pts:
            self.assertLess(abs(math.sqrt(sum(v * v for v in p)) - 1), FLOAT_TOL, p)
            self.assertLess(min(abs(v) for v in p), FLOAT_TOL, p)

    def test_drc_and_glb_cells_partition_the_triangles(self):
        for shift in (0.0, IRR * CELL):
            with self.subTest(shift=shift):
                f, drc = self.run_request(self.sphere(shift), "drc")
                faces = f["arrangement"]["faces"]
                d = decode_drc(drc, self.dir)
                self.assertEqual(d["cell"]["unique_id"], 5)
                self.assert_cells_partition(labels_by_triangle(d, "cell"), decoded_triangles(d),
                                            faces)
        f, glb = self.run_request(self.sphere(IRR * CELL), "glb")
        js, bin_ = glb_chunks(glb)
        prim = js["meshes"][0]["primitives"][0]
        ext = prim["extensions"]["KHR_draco_mesh_compression"]
        self.assertEqual(ext["attributes"]["_CELL"], 5)
        self.assertIn("_CELL", prim["attributes"])
        view = js["bufferViews"][ext["bufferView"]]
        off = view.get("byteOffset", 0)
        d = decode_drc(bin_[off:off + view["byteLength"]], self.dir)
        self.assert_cells_partition(labels_by_triangle(d, "cell"), decoded_triangles(d),
                                    f["arrangement"]["faces"])
        self.check_glb_lines(js, bin_, f)

    def check_glb_lines(self, js, bin_, f):
        node = [n for n in js["nodes"] if n["name"] == "section_curves"]
        self.assertEqual(len(node), 1)
        ex = node[0]["extras"]
        self.assertEqual((ex["kind"], ex["curves"]), ("section", 3))
        self.assertEqual(len(ex["curve"]), len(f["arrangement"]["edges"]))
        prim = js["meshes"][node[0]["mesh"]]["primitives"][0]
        self.assertEqual(prim["mode"], 1)  # LINES
        acc = js["accessors"][prim["attributes"]["POSITION"]]
        view = js["bufferViews"][acc["bufferView"]]
        raw = bin_[view.get("byteOffset", 0):view.get("byteOffset", 0) + 12 * acc["count"]]
        pts = [struct.unpack_from("<3f", raw, 12 * i) for i in range(acc["count"])]
        self.assert_on_sphere_and_a_plane(pts)
        points_in_arcs = sum(len(a) // 3 for c in f["curves"] if c["kind"] == "section"
                             for a in c["arcs"])
        self.assertEqual(acc["count"], points_in_arcs)

    def test_obj_lines_and_ply_cells(self):
        shift = IRR * CELL
        f, obj = self.run_request(self.sphere(shift), "obj")
        verts, lines, group = [], [], None
        for line in obj.decode().splitlines():
            parts = line.split()
            if parts and parts[0] == "v":
                verts.append([float(v) for v in parts[1:4]])
            elif parts and parts[0] == "g":
                group = parts[1]
            elif parts and parts[0] == "l" and group == "section_curves":
                lines.append([int(i) - 1 for i in parts[1:]])
        self.assertEqual(len(lines), len(f["arrangement"]["edges"]))
        self.assert_on_sphere_and_a_plane([verts[i] for ln in lines for i in ln])

        f, ply = self.run_request(self.sphere(shift), "ply")
        head_end = ply.index(b"end_header\n") + len(b"end_header\n")
        head = ply[:head_end].decode()
        self.assertIn("element face", head)
        self.assertIn("property uint cell", head)
        nv = int(head.split("element vertex ")[1].split()[0])
        nt = int(head.split("element face ")[1].split()[0])
        vprops = head.split("element vertex")[1].split("element face")[0].count("property float")
        vbytes = 4 * vprops + head.split("element face")[0].count("property uchar")
        pos = [struct.unpack_from("<3f", ply, head_end + vbytes * i) for i in range(nv)]
        at = head_end + vbytes * nv
        cells, tris = [], []
        for _ in range(nt):
            self.assertEqual(ply[at], 3)
            i, j, k, c = struct.unpack_from("<3iI", ply, at + 1)
            tris.append([pos[i], pos[j], pos[k]])
            cells.append(c)
            at += 17
        self.assertEqual(at, len(ply))
        self.assert_cells_partition(cells, tris, f["arrangement"]["faces"])

    def test_double_sheet_flag_marks_the_sheet(self):
        """Also with curves asked for (the cut renumbers the triangles: each takes its
        parent's flag), where the sheet's triangle count grows past the polygoniser's."""
        expr = "((x-0.5)^2+y^2+z^2-0.16) * ((x+0.5)^2+y^2+z^2-0.16)^2"
        cell = 2.2 / 2 ** 5
        section = [{"kind": "plane", "normal": [0, 0, 1], "offsets": [0.05]}]
        for shift, curves in ((0.0, None), (IRR * cell, None), (IRR * cell, section)):
            with self.subTest(shift=shift, curves=bool(curves)):
                b = [-1.1 + shift, -0.6 + shift, -0.6 + shift, 1.1 + shift, 0.6 + shift,
                     0.6 + shift]
                req = {"expr": expr, "box": b, "depth": {"max": 5}}
                if curves:
                    req["curves"] = curves
                f, drc = self.run_request(req, "drc")
                sheets = f["double_sheets"]
                self.assertEqual(len(sheets), 1)
                d = decode_drc(drc, self.dir)
                self.assertEqual(d["double_sheet"]["unique_id"], 6)
                flags = labels_by_triangle(d, "double_sheet")
                tris = decoded_triangles(d)
                flagged = [t for t, s in zip(tris, flags) if s]
                if curves:  # the section cuts both spheres: more triangles than meshed
                    self.assertGreater(len(flagged), sheets[0]["triangles"])
                    self.assertTrue(any(c["kind"] == "section" and c["arcs"]
                                        for c in f["curves"]))
                else:
                    self.assertEqual(len(flagged), sheets[0]["triangles"])
                for t, s in zip(tris, flags):
                    cx = sum(p[0] for p in t) / 3
                    self.assertTrue(cx < 0 if s else cx > 0, (s, t))
                area = sum(tri_area(*t) for t in flagged)
                self.assertLess(abs(area - 4 * math.pi * 0.16) / (4 * math.pi * 0.16), 0.01)


    def assert_branch_normals(self, faces, quantum, one_row=False):
        """faces: [(3 positions, 3 normals)]. Returns (corners checked, crease points).
        one_row (the PLY: one row per mesh vertex): a corner on the crease (within ON_CREASE
        of both branches) carries its vertex's one normal, the same at every corner there
        (its value, the sides' sum, is test_crease_files.py's), and is not held to a side."""
        worst, sides, checked, shared = 0.0, {}, 0, {}
        def crease_dist(c):  # signed distance to the surface B = G (ball side positive)
            d = [a - b for a, b in zip(ball_grad(c), gyroid_grad(c))]
            return (ball(c) - gyroid(c)) / math.sqrt(sum(x * x for x in d))

        for pts, nrms in faces:
            # The side: at the corner farthest from the crease (a point of the surface; a
            # flat triangle's centroid lies off it, on the wrong side for a sliver).
            margin = max((crease_dist(p) for p in pts), key=abs)
            if abs(margin) < 4 * quantum:
                continue  # the side is below what the positions resolve
            on_ball = margin > 0
            for p, n in zip(pts, nrms):
                checked += 1
                if one_row and abs(crease_dist(p)) < ON_CREASE:
                    shared.setdefault(tuple(p), set()).add(tuple(n))
                    continue
                worst = max(worst, angle_deg(n, ball_grad(p) if on_ball else gyroid_grad(p)))
                sides.setdefault(tuple(p), {}).setdefault(on_ball, set()).add(tuple(n))
        self.assertLess(worst, 1.0, "a corner normal is not its branch's gradient")
        if one_row:
            self.assertEqual([p for p, s in shared.items() if len(s) > 1], [],
                             "crease points with more than one normal")
            return checked, len(shared)
        crease = [p for p, s in sides.items() if len(s) == 2]
        for p in crease:
            want = angle_deg(gyroid_grad(p), ball_grad(p))
            for n0 in sides[p][False]:
                for n1 in sides[p][True]:
                    self.assertLess(abs(angle_deg(n0, n1) - want), 1.0, (p, n0, n1, want))
        return checked, len(crease)

    def test_crease_sides_carry_their_branch_normals(self):
        depth, side = 5, 3.0
        cell = side / 2 ** depth
        for shift, fmt in ((0.0, "drc"), (IRR * cell, "drc"), (1e-3 * cell, "obj"),
                           (1e-3 * cell, "ply")):
            with self.subTest(shift=shift, format=fmt):
                req = {"expr": GYROID_BALL, "box": box(side, shift), "depth": {"max": depth}}
                f, out = self.run_request(req, fmt)
                self.assertTrue(any(c["kind"] == "crease" for c in f["curves"]))
                if fmt == "drc":
                    d = decode_drc(out, self.dir)
                    self.assertEqual(len(d["normal"]), 3 * d["points"])
                    nrm = [d["normal"][3 * i:3 * i + 3] for i in range(d["points"])]
                    faces = [(t, [nrm[d["index"][3 * f_ + k]] for k in range(3)])
                             for f_, t in enumerate(decoded_triangles(d))]
                    quantum = side / 2 ** 14  # 14-bit positions over the box
                elif fmt == "ply":  # one row per mesh vertex, a crease's sides share it
                    faces = parse_ply_corners(out)
                    quantum = 2e-7  # float32 positions
                    self.assertEqual(unused_ply_rows(out), 0, "vertex rows no face uses")
                    self.assertEqual(ply_rows(out), len({tuple(p) for t, _ in faces
                                                         for p in t}),
                                     "one row per vertex position")
                else:
                    faces = parse_obj_corners(out.decode())
                    quantum = 1e-7  # 9 significant digits
                    self.assertEqual(unused_obj_vertices(out.decode()), 0,
                                     "vertices no face or line uses")
                checked, crease = self.assert_branch_normals(faces, quantum, fmt == "ply")
                self.assertGreater(checked, 0.9 * 3 * len(faces))
                self.assertGreater(crease, 500, "crease points with both sides decided")


if __name__ == "__main__":
    unittest.main()
