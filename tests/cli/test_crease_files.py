"""test_crease_files.py — on a CSG crease (min/max in f) the PLY and the OBJ are the mesh the
stats describe (issue 15/13). Along a crease each side's corners carry their own branch's
normal: the viewer's formats (drc, glb) split those points, the OBJ gives them `vn` lines of
their own through `f v//vn`; but a user who loads the PLY or the OBJ to count components,
check manifoldness or compute χ must get the stats' mesh, not one cut open along every crease
edge. Checked on cube-minus-ball (the cube's edges and corners: two and three sides) and
gyroid-ball (a curved crease), each in the three placements (boxes.py), with every attribute
(the viewer's download link):

- PLY: `element vertex` = stats vertices, `element face` = stats triangles, every row used;
  from the PLY's own faces: edges, boundary edges (an edge of one face), non-manifold edges
  and χ = V − E + F equal the stats' (V the rows faces use: the stats count vertices_used);
- OBJ: `v` lines = stats vertices, `f` lines = stats triangles, its faces the PLY's vertex
  for vertex (the same indices), and more `vn` lines than `v` lines (the crease sides' own);
- at a PLY row on the crease (closed form: two branches or more vanish within ON_CREASE) the
  normal is the normalised sum of the unit gradients of the sides its triangles lie on (a
  triangle's side: the branch f = max takes at its corner farthest from the crease) — on a
  cube edge (±1, ±1, 0)/√2, at a cube corner (±1, ±1, ±1)/√3 — within 1°; a row whose
  triangles all lie on one side (a sliver of triangles along the crease) has that side's;
  at least MIN_CREASE_ROWS rows with two sides or more per run.

On the code before (PLY rows split per crease side) cube-minus-ball's PLY at the viewer's
default had 36,706 rows against 28,714 stats vertices, 15,976 boundary edges (every crease
edge cut open; stats 0) and χ −4 (stats −8); every run here failed its row count.
Cheap: max_error 1e-2 × the diagonal, given explicitly (~0.1-0.5 s of meshing per run)."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import placements  # noqa: E402
from test_curve_outputs import read_ply  # noqa: E402  (rows, faces, header of a binary PLY)
from test_double_curve_normals import read_obj  # noqa: E402  (v, vn, faces of `f v//vn`)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")

ATTRIBUTES = ["normal", "mean_curvature", "gauss_curvature", "class"]
ON_CREASE = 1e-6      # |branch| at a float32 crease vertex (Newton puts it within ~1e-12;
                      # float32 rounds positions near 1 by 6e-8)
SIDE_MARGIN = 1e-6    # a triangle's side is decided where the top branch leads by this
MAX_ANGLE = 1.0       # degrees between a crease row's normal and the sides' closed-form sum
MIN_CREASE_ROWS = 500  # crease rows with two sides or more per run (measured 2,479-35,363)


def cube_minus_ball_branches(p, half, radius):
    """[(unit normal, value / |gradient|)] of the branches of
    max(max(|x|, |y|, |z|) - half, radius² - |p|²) at p: the cube's faces |x_k| = half (normal
    ±e_k) and the ball |p| = radius (normal -p / |p|)."""
    out = []
    for k in range(3):
        n = [0.0, 0.0, 0.0]
        n[k] = math.copysign(1.0, p[k])
        out.append((n, abs(p[k]) - half))
    r = math.sqrt(sum(v * v for v in p)) or 1.0
    out.append(([-v / r for v in p], (radius * radius - r * r) / (2 * r)))
    return out


def gyroid_ball_branches(p, k, r2):
    """[(unit normal, value / |gradient|)] of gyroid-ball's two branches at p (max): the
    gyroid sin kx cos ky + sin ky cos kz + sin kz cos kx and the ball x² + y² + z² − r2."""
    x, y, z = (k * v for v in p)
    g = math.sin(x) * math.cos(y) + math.sin(y) * math.cos(z) + math.sin(z) * math.cos(x)
    gg = [k * (math.cos(x) * math.cos(y) - math.sin(z) * math.sin(x)),
          k * (math.cos(y) * math.cos(z) - math.sin(x) * math.sin(y)),
          k * (math.cos(z) * math.cos(x) - math.sin(y) * math.sin(z))]
    b = sum(v * v for v in p) - r2
    bg = [2 * v for v in p]
    out = []
    for val, grad in ((g, gg), (b, bg)):
        n = math.sqrt(sum(v * v for v in grad)) or 1.0
        out.append(([v / n for v in grad], val / n))
    return out


def triangle_side(vals):
    """The branch a triangle lies on: the one f = max takes at its corner farthest from the
    crease (the largest lead of the top branch over the next; the centroid of a sliver along
    the crease may read the other side), or None when no corner leads by SIDE_MARGIN (float32
    positions cannot decide). vals: per corner, its branches' (value, index), highest first."""
    best, side = SIDE_MARGIN, None
    for corner in vals:  # per corner: its branches' values, highest first, with their index
        if corner[0][0] - corner[1][0] > best:
            best, side = corner[0][0] - corner[1][0], corner[0][1]
    return side


def edge_counts(faces):
    """(edges, boundary edges, non-manifold edges, vertices used) of the faces, triangles
    with a repeated index left out (the stats' collapsed triangles)."""
    use = {}
    verts = set()
    for f in faces:
        if len(set(f)) < 3:
            continue
        verts.update(f)
        for i in range(3):
            e = (min(f[i], f[(i + 1) % 3]), max(f[i], f[(i + 1) % 3]))
            use[e] = use.get(e, 0) + 1
    return (len(use), sum(1 for c in use.values() if c == 1),
            sum(1 for c in use.values() if c > 2), len(verts))


def angle_deg(u, v):
    nu = math.sqrt(sum(a * a for a in u)) or 1.0
    nv = math.sqrt(sum(a * a for a in v)) or 1.0
    d = sum(a * b for a, b in zip(u, v)) / (nu * nv)
    return math.degrees(math.acos(max(-1.0, min(1.0, d))))


class CreaseFilesTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="isomesh-crease-files-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def run_request(self, preset, box, error, fmt):
        """(path of the file, stats) of preset in box, every attribute, max_error error."""
        req = os.path.join(self.dir, "r.json")
        with open(req, "w") as fh:
            json.dump({"preset": preset, "box": box, "max_error": error,
                       "output": {"attributes": ATTRIBUTES}}, fh)
        out = os.path.join(self.dir, "m." + fmt)
        r = subprocess.run([ISOMESH, req, "-o", out, "--stats"], capture_output=True,
                           text=True, timeout=300)
        self.assertEqual(r.returncode, 0, r.stderr)
        return out, json.loads(r.stdout)

    def check(self, preset, box, branches):
        diag = math.sqrt(sum((box[k + 3] - box[k]) ** 2 for k in range(3)))
        ply, stats = self.run_request(preset, box, 1e-2 * diag, "ply")
        mesh, a = stats["mesh"], stats["analysis"]
        with open(ply, "rb") as fh:
            rows, faces, head = read_ply(fh.read())
        self.assertIn("property float mean_curvature\n", head)
        self.assertEqual(len(rows), mesh["vertices"], "one PLY row per mesh vertex")
        self.assertEqual(len(faces), mesh["triangles"])
        edges, boundary, nonmanifold, used = edge_counts(faces)
        self.assertEqual(used, len(rows), "PLY rows no face uses")
        self.assertEqual(boundary, a["boundary_edges"], "crease edges cut open in the PLY")
        self.assertEqual(edges, a["edges"])
        self.assertEqual(nonmanifold, a["nonmanifold_edges"])
        live = sum(1 for f in faces if len(set(f)) == 3)
        self.assertEqual(used - edges + live, a["euler"], "χ of the PLY is the stats'")

        # crease rows: the normalised sum of the sides its triangles lie on (decided from
        # the closed forms); a row whose triangles all lie on one side carries that side's
        crease, inc, at = 0, {}, {}
        for t, f in enumerate(faces):
            for v in f:
                inc.setdefault(v, []).append(t)

        def row_branches(u):  # row u's branches, and their (value, index) highest first
            if u not in at:
                br = branches(rows[u][:3])
                at[u] = br, sorted(((val, i) for i, (_, val) in enumerate(br)), reverse=True)
            return at[u]

        for v, row in enumerate(rows):
            p, n = row[:3], row[3:]
            br = row_branches(v)[0]
            if sum(1 for _, val in br if abs(val) < ON_CREASE) < 2:
                continue
            sides = {triangle_side([row_branches(u)[1] for u in faces[t]]) for t in inc[v]}
            if None in sides:
                continue
            want = [sum(br[i][0][k] for i in sides) for k in range(3)]
            self.assertLess(angle_deg(n, want), MAX_ANGLE,
                            f"crease row at {p}: {n}, sides {sorted(sides)}' sum {want}")
            crease += len(sides) > 1
        self.assertGreaterEqual(crease, MIN_CREASE_ROWS, "crease rows with two sides or more")

        obj, ostats = self.run_request(preset, box, 1e-2 * diag, "obj")
        self.assertEqual(ostats["mesh"]["vertices"], mesh["vertices"])
        v, vn, f = read_obj(obj)
        self.assertEqual(len(v), mesh["vertices"], "one OBJ `v` per mesh vertex")
        self.assertEqual([tuple(c[0] for c in t) for t in f], faces,
                         "the OBJ's faces are the PLY's")
        self.assertGreater(len(vn), len(v), "the crease sides' own `vn` lines")
        return crease

    def test_cube_minus_ball(self):
        # max(max(|x|, |y|, |z|) - 1, r² - (x² + y² + z²)), r = 1.3, box ±1.3 (proto/presets.c)
        for box in placements([-1.3, -1.3, -1.3, 1.3, 1.3, 1.3], 2.6 / 2 ** 7):
            with self.subTest(box=box):
                self.check("cube-minus-ball", box,
                           lambda p: cube_minus_ball_branches(p, 1.0, 1.3))

    def test_gyroid_ball(self):
        # max(gyroid k = 4, x² + y² + z² - 1.96), box ±1.5 (proto/presets.c)
        for box in placements([-1.5, -1.5, -1.5, 1.5, 1.5, 1.5], 3.0 / 2 ** 7):
            with self.subTest(box=box):
                self.check("gyroid-ball", box, lambda p: gyroid_ball_branches(p, 4.0, 1.96))


if __name__ == "__main__":
    unittest.main()
