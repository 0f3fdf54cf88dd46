"""test_isomesh.py — the `isomesh` command as a user meets it: output files in every format
read back and checked (closed sphere: every edge in two triangles, Euler characteristic 2),
one-line errors with exit status 2 for bad input and the column of an expression error, no
partial file ever, surfaces from a file and from the built-in list, identical output for one
and two threads, request files through the service pipeline."""
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from boxes import placements  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESH = os.path.join(BUILD, "isomesh")
FIXTURE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "surfaces_fixture.json")


def run(*args, timeout=120):
    return subprocess.run([ISOMESH, *args], capture_output=True, text=True, timeout=timeout)


def run_counting_threads(*args, timeout=120):
    """run(), and the most threads the process was seen running at once: its /proc/PID/task
    entries, read every millisecond until it exits. A count read is one it had, so a peak can
    be missed but never overstated; a thread running beside the analysis lasts all of it
    (100+ ms for the meshes of 8,192+ triangles below: a hundred reads)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen([ISOMESH, *args], stdout=out, stderr=err, text=True)
        task, peak = "/proc/%d/task" % p.pid, 0
        deadline = time.monotonic() + timeout
        while p.poll() is None:
            if time.monotonic() > deadline:  # a hung run stops here, as run()'s would
                p.kill()
                p.wait()
                raise subprocess.TimeoutExpired(p.args, timeout)
            try:
                peak = max(peak, len(os.listdir(task)))
            except OSError:  # exited between the poll and the read
                break
            time.sleep(0.001)
        p.wait(timeout=timeout)
        out.seek(0)
        err.seek(0)
        return subprocess.CompletedProcess(p.args, p.returncode, out.read(), err.read()), peak


def slurp(path, mode="rb"):
    with open(path, mode) as f:
        return f.read()


def read_ply(path):
    data = slurp(path)
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    assert "format binary_little_endian 1.0" in header
    nv = int(header.split("element vertex ")[1].split()[0])
    nf = int(header.split("element face ")[1].split()[0])
    # vertex properties: x y z nx ny nz first (floats), then maybe more (request files:
    # curvature floats and a uchar class)
    vprops = header.split("element vertex ")[1].split("element face")[0]
    stride = sum({"float": 4, "uchar": 1}[w.split()[1]] for w in vprops.splitlines()
                 if w.startswith("property "))
    verts = [struct.unpack_from("<6f", data, end + stride * i) for i in range(nv)]
    off = end + stride * nv
    faces = []
    for i in range(nf):
        n, a, b, c = struct.unpack_from("<Biii", data, off + 13 * i)
        assert n == 3
        faces.append((a, b, c))
    return verts, faces


def read_obj(path):
    verts, faces = [], []
    for line in slurp(path, "r").splitlines():
        if line.startswith("v "):
            verts.append(tuple(map(float, line.split()[1:4])))
        elif line.startswith("f "):
            faces.append(tuple(int(t.split("/")[0]) - 1 for t in line.split()[1:4]))
    return verts, faces


def read_stl(path):
    data = slurp(path)
    n = struct.unpack_from("<I", data, 80)[0]
    assert len(data) == 84 + 50 * n, "binary STL size"
    return [struct.unpack_from("<12f", data, 84 + 50 * i) for i in range(n)]


def edge_counts(faces):
    counts = {}
    for a, b, c in faces:
        for u, v in ((a, b), (b, c), (c, a)):
            k = (min(u, v), max(u, v))
            counts[k] = counts.get(k, 0) + 1
    return counts


class TestIsomesh(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def out(self, name):
        return os.path.join(self.dir, name)

    def assert_closed_sphere(self, verts, faces, r):
        counts = edge_counts(faces)
        self.assertTrue(all(c == 2 for c in counts.values()), "every edge in two triangles")
        used = {i for f in faces for i in f}
        self.assertEqual(len(used) - len(counts) + len(faces), 2, "Euler characteristic")
        for i in used:
            x, y, z = verts[i][:3]
            self.assertAlmostEqual((x * x + y * y + z * z) ** 0.5, r, delta=0.02 * r)

    def test_extension_in_any_case(self):
        path = self.out("S.OBJ")
        p = run("-e", "x^2 + y^2 + z^2 - 0.8", "-d", "2:4", "-o", path)
        self.assertEqual(p.returncode, 0, p.stderr)
        verts, faces = read_obj(path)
        self.assert_closed_sphere(verts, faces, 0.8 ** 0.5)

    def test_ply_obj_stl_of_a_sphere(self):
        for ext in ("ply", "obj", "stl"):
            path = self.out("s." + ext)
            p = run("-e", "x^2 + y^2 + z^2 - 1", "-b", "-1.5,-1.5,-1.5,1.5,1.5,1.5",
                    "-d", "3:6", "-o", path)
            self.assertEqual(p.returncode, 0, p.stderr)
            if ext == "ply":
                verts, faces = read_ply(path)
                self.assert_closed_sphere(verts, faces, 1.0)
                for x, y, z, nx, ny, nz in verts:  # normals from ∇f point outwards
                    self.assertGreater(x * nx + y * ny + z * nz, 0.9)
            elif ext == "obj":
                verts, faces = read_obj(path)
                self.assert_closed_sphere(verts, faces, 1.0)
            else:
                tris = read_stl(path)
                self.assertGreater(len(tris), 500)
                for t in tris:  # facet normal agrees with the outward direction
                    n, c = t[0:3], [sum(t[3 + 3 * k + j] for k in range(3)) / 3 for j in range(3)]
                    self.assertGreater(sum(n[j] * c[j] for j in range(3)), 0)

    def test_stats_json(self):
        p = run("-e", "x^2 + y^2 + z^2 - 1", "-b", "-1.5,-1.5,-1.5,1.5,1.5,1.5", "-d", "3:6",
                "--stats")
        self.assertEqual(p.returncode, 0, p.stderr)
        s = json.loads(p.stdout)
        self.assertEqual(s["analysis"]["euler"], 2)
        self.assertEqual(s["analysis"]["boundary_edges"], 0)
        self.assertGreater(s["polygoniser"]["triangles"], 500)
        self.assertEqual(s["polygoniser"]["triangles"], s["mesh"]["triangles"])
        for k in ("nodes_visited", "nodes_excluded", "plotting_nodes", "unresolved_nodes",
                  "edges_double_root", "edges_many_roots", "polygons", "degenerate_polygons",
                  "cracks_repaired", "evals_point", "evals_interval", "evals_gradient"):
            self.assertIn(k, s["polygoniser"])

    def test_expression_error_names_the_column(self):
        path = self.out("bad.ply")
        p = run("-e", "x^2 + sinn(y)", "-o", path)
        self.assertEqual(p.returncode, 2)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
        self.assertIn("col 7", p.stderr)
        self.assertIn("sinn", p.stderr)
        self.assertFalse(os.path.exists(path))
        self.assertEqual(os.listdir(self.dir), [], "no temporary file left behind")

    def test_bad_flags_are_one_line_errors(self):
        cases = [
            (["-e", "x", "-b", "1,2,3", "-o", "a.ply"], "--box"),
            (["-e", "x", "-b", "1,1,1,0,2,2", "-o", "a.ply"], "--box"),
            (["-e", "x", "-d", "5:3", "-o", "a.ply"], "--depth"),
            (["-e", "x", "-d", "3:17", "-o", "a.ply"], "--depth"),
            (["-e", "x", "-p", "r", "-o", "a.ply"], "--param"),
            (["-e", "x", "-p", "r=nan", "-o", "a.ply"], "--param"),
            (["-e", "x", "-o", "a.xyz"], "extension"),
            (["-e", "x"], "nothing to do"),
            (["--surface", "nope", "-o", "a.ply"], "nope"),
            # a parameter the built-in surface does not have (the API refuses it too)
            (["--surface", "torus", "-p", "Q=1", "-o", "a.ply"],
             "--param Q: the surface 'torus' has no parameter Q (it has R, r)"),
            (["--frobnicate"], "unknown option"),
            ([], "usage: isomesh --surface NAME -o FILE"),
            (["-e", "x", "--threads", "-1", "-o", "a.ply"], "--threads"),
            (["-e", "x", "--max-error", "-1", "-o", "a.ply"], "--max-error"),
            (["-e", "x", "--max-error", "abc", "-o", "a.ply"], "--max-error"),
            (["-e", "x", "--max-triangles", "0", "-o", "a.ply"], "--max-triangles"),
            (["-e", "x", "--quality", "best", "-o", "a.ply"], "--quality"),
            (["-e", "x", "--let", "=x", "-o", "a.ply"], "--let"),
            # a flag's value forgotten: the next flag is not taken as its value
            (["--surface", "-o", "a.ply"], "missing value for --surface"),
            # every short flag getopt knows, and not the ':' that starts its option string
            *((["--surface", f, "-o", "a.ply"],
               f"missing value for --surface (the next word, '{f}', is a flag)")
              for f in ("-e", "-p", "-b", "-d", "-h")),
            (["--surface", "-:", "-o", "a.ply"], "no built-in surface named '-:'"),
            (["-e", "x", "-o", "--stats"], "missing value for --output"),
            (["-e", "x", "--features", "--stats", "-o", "a.ply"], "missing value for --features"),
            # a surfaces file without the name of the surface to take from it
            (["-e", "x", "--surfaces", "examples/surfaces.json", "-o", "a.ply"], "--surface NAME"),
            # --dual, --simplify, --straddle: only under a bound, and not beside --no-dual
            (["-e", "x", "--max-error", "off", "--dual", "-o", "a.ply"],
             "--dual needs a bound, not --max-error off"),
            (["-e", "x", "--simplify", "--max-error", "off", "-o", "a.ply"],
             "--simplify needs a bound, not --max-error off"),
            (["-e", "x", "--max-error", "0", "--straddle", "-o", "a.ply"],
             "--straddle needs a bound, not --max-error off"),
            (["-e", "x", "--max-error", "-1e-3", "-o", "a.ply"], "below 0"),
            # a request's range (proto/request.c ism_request_error_in_range), once the box is
            # known (default box: diagonal 2 sqrt 3); the CLI once meshed 1e-12 until the budget
            (["-e", "x", "--max-error", "nan", "-o", "a.ply"], "--max-error: 'nan' is not a finite"),
            (["-e", "x", "--max-error", "1e-12", "-o", "a.ply"],
             "--max-error: 1e-12 is below the minimum 3.47e-09 (1e-09 of the box diagonal 3.46)"),
            (["-e", "x", "--max-error", "3.5", "-o", "a.ply"],
             "--max-error: 3.5 is above the limit 3.46 (the box diagonal)"),
            (["-e", "x", "--max-error", "of", "-o", "a.ply"], "--max-error"),
            (["-e", "x", "--max-error", "0.1", "--dual", "--no-dual", "-o", "a.ply"],
             "--dual and --no-dual"),
        ]
        for args, needle in cases:
            p = run(*[a if not a.startswith("a.") else self.out(a) for a in args])
            self.assertEqual(p.returncode, 2, f"{args}: {p.stderr}")
            self.assertEqual(len(p.stderr.strip().splitlines()), 1, f"{args}: {p.stderr}")
            self.assertIn(needle, p.stderr, args)
        self.assertEqual(os.listdir(self.dir), [])

    def test_budget_failure_leaves_no_file(self):
        path = self.out("big.ply")
        # the depth path's knob, then the bound's (the default one: 1e-3 x the diagonal)
        for flags, knob in ((("--max-error", "off"), "a smaller -d MAX makes fewer"),
                            ((), "a larger --max-error makes fewer")):
            p = run("--surface", "gyroid-ball", "-d", "3:8", *flags, "--max-triangles", "1000",
                    "-o", path)
            self.assertEqual(p.returncode, 1)
            self.assertIn("budget", p.stderr)
            self.assertIn(f"MiB): --max-triangles raises it, {knob}", p.stderr)
            self.assertEqual(os.listdir(self.dir), [])

    def test_a_bound_over_the_budget_names_an_error_that_fits(self):
        # issue 15: under --max-error, the budget's message names a --max-error that fits,
        # found by coarse passes. The sphere takes 5016 triangles under 1e-3, 1128 under 4e-3,
        # 828 under 8e-3: the smallest E that fits 1000 lies in (4e-3, 8e-3]. The suggestion
        # meshes; a quarter of it does not (within 4x of the smallest that fits).
        path = self.out("s.ply")
        p = run("--surface", "sphere", "--max-error", "1e-3", "--max-triangles", "1000",
                "-o", path)
        self.assertEqual(p.returncode, 1, p.stderr)
        m = re.search(r"\(--max-error ([0-9.e+-]+) fits\)", p.stderr)
        self.assertTrue(m, p.stderr)
        fit = float(m.group(1))
        self.assertGreater(fit, 1e-3)
        p = run("--surface", "sphere", "--max-error", m.group(1), "--max-triangles", "1000",
                "-o", path)
        self.assertEqual(p.returncode, 0, p.stderr)
        p = run("--surface", "sphere", "--max-error", repr(fit / 4), "--max-triangles", "1000",
                "-o", path)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("budget", p.stderr)
        # the depth path names no E
        p = run("--surface", "sphere", "--max-error", "off", "-d", "3:8", "--max-triangles",
                "1000", "-o", path)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertNotIn("fits", p.stderr)

    def test_surfaces_file(self):
        path = self.out("ring.ply")
        p = run("--surface", "ring", "--surfaces", FIXTURE, "-d", "3:6", "-o", path)
        self.assertEqual(p.returncode, 0, p.stderr)
        verts, faces = read_ply(path)
        counts = edge_counts(faces)
        used = {i for f in faces for i in f}
        self.assertEqual(len(used) - len(counts) + len(faces), 0, "a torus")
        p = run("--surface", "ball", "--surfaces", FIXTURE, "-p", "r=0.5", "-d", "3:6", "-o", path)
        self.assertEqual(p.returncode, 0, p.stderr)
        verts, faces = read_ply(path)
        self.assert_closed_sphere(verts, faces, 0.5)  # -p overrides the file's parameter
        p = run("--surface", "broken", "--surfaces", FIXTURE, "-o", path)
        self.assertEqual(p.returncode, 2)
        self.assertIn("sinn", p.stderr)

    def test_builtin_surfaces_listed(self):
        p = run("--list")
        self.assertEqual(p.returncode, 0)
        for name in ("kummer-4-nodes", "kummer-16-nodes", "horn-cyclide", "klein-bottle",
                     "steiner-roman", "sphere", "torus", "gyroid-ball"):
            self.assertIn(name, p.stdout)

    def test_one_and_two_threads_write_the_same_file(self):
        a, b = self.out("a.ply"), self.out("b.ply")
        self.assertEqual(run("--surface", "klein-bottle", "-d", "3:6", "--threads", "1", "-o", a).returncode, 0)
        self.assertEqual(run("--surface", "klein-bottle", "-d", "3:6", "--threads", "2", "-o", b).returncode, 0)
        self.assertEqual(slurp(a), slurp(b))

    def test_one_two_and_four_threads_write_the_same_files_and_figures(self):
        """Barth's sextic (30 nodes in the ball), Kummer's quartic (16 nodes) and the gyroid
        ball (the thread-scaling goal's surface, a crease), each in the three placements: the
        PLY, the features file and every figure of the stats (the analysis's edge table,
        triangle quality, medians and percentiles run on the threads) are the same on 1, 2
        and 4 threads; only the times and the evaluation counts (each thread's own memo of
        f) may differ. No run has more threads at once than --threads says (the analysis's
        side thread and the PLY writer are counted in it)."""
        barth = ["-e", "max(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
                       "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)",
                 "-p", "phi=1.6180339887498949"]
        # (surface, box, whether it has non-manifold points)
        cases = [(barth, [-1.6, -1.6, -1.6, 1.6, 1.6, 1.6], True),
                 (["--surface", "kummer-16-nodes"], [-3, -3, -3, 3, 3, 3], True),
                 (["--surface", "gyroid-ball"], [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5], False)]
        for surface, box, nodes in cases:
            # the own box, 1e-3 off, and boxes.IRR_CELLS of a depth-6 cell off
            for shifted in placements(box, (box[3] - box[0]) / 64):
                self.same_on_1_2_4_threads(surface, shifted, nodes)

    def same_on_1_2_4_threads(self, surface, box, nodes):
        def figures(stats):
            if isinstance(stats, dict):
                return {k: figures(v) for k, v in stats.items()
                        if not (k.endswith("_ms") or k.startswith("evals_") or
                                k in ("timings_ms", "time_ms", "threads"))}
            return stats

        runs = []
        for threads in ("1", "2", "4"):
            ply, feats = self.out("t%s.ply" % threads), self.out("t%s.json" % threads)
            p, peak = run_counting_threads(
                *surface, "-b", ",".join(repr(v) for v in box), "-d", "3:6",
                "--threads", threads, "--stats", "-o", ply, "--features", feats)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertLessEqual(peak, int(threads), (surface, box))
            stats = json.loads(p.stdout)
            self.assertEqual(stats["analysis"]["nonmanifold_points"] > 0, nodes, surface)
            self.assertGreater(stats["mesh"]["triangles"], 8192)  # the analysis's pool runs
            runs.append((slurp(ply), slurp(feats), figures(stats)))
        for other in runs[1:]:
            self.assertEqual(runs[0][0], other[0], (surface, box))
            self.assertEqual(runs[0][1], other[1], (surface, box))
            self.assertEqual(runs[0][2], other[2], (surface, box))

    def test_a_request_file_keeps_to_its_threads(self):
        """The service pipeline (a daemon worker's run; here through a request file) on 1, 2
        and 4 threads, in the three placements: the same PLY and stats figures, and never
        more threads at once than --threads (its analysis evaluates f at every vertex, so its
        pool and its connectivity passes' side thread run; they share the worker's limit)."""
        box = [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5]
        for shifted in placements(box, (box[3] - box[0]) / 64):
            req = self.out("req.json")
            with open(req, "w") as f:
                json.dump({"preset": "gyroid-ball", "box": shifted,
                           "depth": {"min": 3, "max": 6}}, f)
            runs = []
            for threads in ("1", "2", "4"):
                ply = self.out("r%s.ply" % threads)
                p, peak = run_counting_threads(req, "--threads", threads, "--stats", "-o", ply)
                self.assertEqual(p.returncode, 0, p.stderr)
                self.assertLessEqual(peak, int(threads), shifted)
                stats = json.loads(p.stdout)
                self.assertGreater(stats["mesh"]["triangles"], 8192)
                runs.append((slurp(ply), stats["analysis"], stats["mesh"]))
            for other in runs[1:]:
                self.assertEqual(runs[0], other, shifted)

    def test_request_file_through_the_pipeline(self):
        req = self.out("req.json")
        with open(req, "w") as f:
            json.dump({"preset": "sphere", "depth": {"min": 3, "max": 5}}, f)
        path = self.out("s.ply")
        p = run(req, "-o", path)
        self.assertEqual(p.returncode, 0, p.stderr)
        verts, faces = read_ply(path)
        self.assert_closed_sphere(verts, faces, 1.0)
        with open(req, "w") as f:
            json.dump({"preset": "sphere", "depht": {"min": 3}}, f)
        p = run(req, "-o", path)
        self.assertEqual(p.returncode, 2)
        self.assertIn("depht", p.stderr)
        # the file says everything about the surface: a surface flag beside it is refused
        # (it used to be ignored without a word), naming the flag; -o --stats --threads apply
        os.remove(path)
        for flags, needle in ((("--max-error", "0.1"), "--max-error"),
                              (("-d", "1:2"), "--depth"),
                              (("--quality", "good"), "--quality"),
                              (("--no-dual",), "--no-dual"),
                              (("--flat-plane", "0.1"), "--flat-plane")):
            p = run(req, *flags, "-o", path)
            self.assertEqual(p.returncode, 2, flags)
            self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
            self.assertIn(needle + ": not with a request file", p.stderr)
            self.assertFalse(os.path.exists(path))
        p = run(req, path)
        self.assertEqual(p.returncode, 2)
        self.assertIn(f"unexpected argument '{path}'", p.stderr)
        # the extension names the format in any case; an unknown one is the -o's fault
        with open(req, "w") as f:
            json.dump({"preset": "sphere", "depth": {"min": 3, "max": 5}}, f)
        upper = self.out("S.PLY")
        p = run(req, "-o", upper)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(slurp(upper)[:4], b"ply\n")
        p = run(req, "-o", self.out("s.xyz"))
        self.assertEqual(p.returncode, 2)
        self.assertIn("-o " + self.out("s.xyz") + ": unknown extension '.xyz' (a request file "
                      "writes .drc, .glb, .ply, .obj, .stl, .png)", p.stderr)

    def test_dual_means_the_dual_mesh_or_a_failure_saying_why(self):
        """--dual: the dual mesh, or exit status 1 with the dual mesher's reason (the stats'
        dual_declined name and its sentence) and no file; without --dual the same runs make
        the primal polygons."""
        path = self.out("m.ply")
        sphere = ("-e", "x^2 + y^2 + z^2 - 1", "-b", "-1.5,-1.5,-1.5,1.5,1.5,1.5")

        def placed(box6):
            """-b of box6 in each of its placements (tests/cli/boxes.py; cell: a 64th)."""
            cell = tuple((box6[a + 3] - box6[a]) / 64 for a in range(3))
            return [("-b", ",".join(map(repr, b))) for b in placements(box6, cell)]
        # the sphere, and the sphere cut by the box (meshed in a larger box and clipped:
        # core/octree/dual_box.h; one boundary loop), in the lattice boxes and off them (the
        # cut plane x = -0.5 a lattice plane, then not)
        for box6, loops in (([-1.5] * 3 + [1.5] * 3, 0), ([-0.5, -1.5, -1.5, 1.5, 1.5, 1.5], 1)):
            for box in placed(box6):
                p = run(*sphere[:2], *box, "--max-error", "0.01", "--dual", "-o", path, "--stats")
                self.assertEqual(p.returncode, 0, (box, p.stderr))
                s = json.loads(p.stdout)
                self.assertEqual(s["polygoniser"]["mesher"], "dual", box)
                self.assertEqual(s["analysis"]["boundary_loops"], loops, box)
                self.assertTrue(os.path.exists(path), box)
                os.remove(path)
        # declined before meshing (min/max in f), by the locus (a double line: in the box
        # +-1 it lies on lattice planes, off them in the shifted boxes), by the box (it cuts
        # a cone, whose node the dual mesher fans, but depth.max 3 leaves no level for the
        # grown box's margin)
        for args, why in ((("-e", "max(x^2 + y^2 + z^2 - 1, z - 0.5)", *sphere[2:]), "min_max"),
                          *((("-e", "x*y", "-d", "2:6", *box), "singular_locus")
                            for box in placed([-1] * 3 + [1] * 3)),
                          (("-e", "x^2 + y^2 - z^2", "-b", "-1,-1.1,-1.2,1.3,1.1,1", "-d",
                            "2:3"), "box_cut")):
            extra = ("--max-error", "0.05")
            p = run(*args, *extra, "--dual", "-o", path, "--stats")
            self.assertEqual(p.returncode, 1, (args, p.stderr))
            self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
            self.assertIn(f"--dual: the dual mesher declined ({why}: ", p.stderr)
            self.assertEqual(p.stdout, "", "no stats for a failed run")
            self.assertFalse(os.path.exists(path), "no file for a failed run")
            q = run(*args, *extra, "--stats")
            self.assertEqual(q.returncode, 0, q.stderr)
            poly = json.loads(q.stdout)["polygoniser"]
            self.assertEqual((poly["mesher"], poly["dual_declined"]), ("primal", why), args)

    def sphere_between_vertices(self, path, r=1.0):
        """The largest exact distance |p| - r at triangle centroids and edge midpoints."""
        verts, faces = read_ply(path)
        worst = 0.0
        for f in faces:
            v = [verts[i][:3] for i in f]
            pts = [[sum(c) / 3 for c in zip(*v)]]
            pts += [[(a + b) / 2 for a, b in zip(v[k], v[(k + 1) % 3])] for k in range(3)]
            for x, y, z in pts:
                worst = max(worst, abs((x * x + y * y + z * z) ** 0.5 - r))
        return worst

    def check_met(self, sphere, path):
        """The unit sphere under --max-error 0.01 with the box in `sphere`: within E (measured
        from the closed form), the dual mesh by default, the flags' meshers."""
        # met: no warning, and the mesh is within E (measured here, from the closed form)
        p = run(*sphere, "--max-error", "0.01", "-o", path, "--stats")
        self.assertEqual(p.returncode, 0, p.stderr)
        s = json.loads(p.stdout)
        acc = s["analysis"]["accuracy"]
        self.assertEqual(acc["max_error"], 0.01)
        self.assertIs(acc["met"], True)
        self.assertEqual(s["warnings"], [])
        # the default under a bound: the dual mesh, not simplified
        self.assertEqual((s["polygoniser"]["mesher"], s["polygoniser"]["dual_declined"]),
                         ("dual", None))
        self.assertNotIn("simplify", s)
        worst = self.sphere_between_vertices(path)
        self.assertLessEqual(worst, 0.01 + 1e-6)  # float32 positions in the PLY
        self.assertAlmostEqual(max(acc["max_dist_centroid"], acc["max_dist_midpoint"]), worst,
                               delta=0.05 * worst)
        for k in ("vertex", "midpoint", "centroid"):
            self.assertLessEqual(acc[f"p99_dist_{k}"], acc[f"max_dist_{k}"])
        # one policy for every mesher: simplified only with --simplify (--no-simplify is
        # the default, kept for scripts)
        for flags, mesher, why, simplified in ((("--no-dual",), "primal", "off", False),
                                               (("--simplify",), "dual", None, True),
                                               (("--no-dual", "--simplify"), "primal", "off",
                                                True),
                                               (("--no-dual", "--no-simplify"), "primal", "off",
                                                False)):
            p = run(*sphere, "--max-error", "0.01", *flags, "--stats")
            self.assertEqual(p.returncode, 0, p.stderr)
            s = json.loads(p.stdout)
            self.assertEqual((s["polygoniser"]["mesher"], s["polygoniser"]["dual_declined"]),
                             (mesher, why), flags)
            self.assertEqual("simplify" in s, simplified, flags)
            self.assertIs(s["analysis"]["accuracy"]["met"], True, flags)

    def test_max_error_met_and_missed(self):
        sphere = ["-e", "x^2 + y^2 + z^2 - 1", "-b", "-1.5,-1.5,-1.5,1.5,1.5,1.5"]
        path = self.out("s.ply")
        # met, in the lattice box and off it (depth 10's cells, the bound's safety limit)
        for box in placements([-1.5] * 3 + [1.5] * 3, 3 / 2 ** 10):
            with self.subTest(box=box):
                self.check_met(["-e", "x^2 + y^2 + z^2 - 1", "-b", ",".join(map(repr, box))],
                               path)
        # missed: depth 4 cannot reach 1e-3; one warning with the count and the worst (in the
        # lattice box and off it, as above)
        for box in placements([-1.5] * 3 + [1.5] * 3, 3 / 2 ** 10):
            with self.subTest(box=box, bound="missed"):
                p = run("-e", "x^2 + y^2 + z^2 - 1", "-b", ",".join(map(repr, box)),
                        "--max-error", "0.001", "-d", "3:4", "-o", path, "--stats")
                self.assertEqual(p.returncode, 0, p.stderr)
                s = json.loads(p.stdout)
                acc = s["analysis"]["accuracy"]
                self.assertIs(acc["met"], False)
                worst = self.sphere_between_vertices(path)
                self.assertGreater(worst, 0.001)
                self.assertEqual(len(s["warnings"]), 1, s["warnings"])
                self.assertIn("max_error 0.001 was not met", s["warnings"][0])
                self.assertIn(f"{s['polygoniser']['error_missed_nodes']} cells could not be "
                              "split further", s["warnings"][0])
                self.assertGreater(s["polygoniser"]["error_missed_nodes"], 0)
                # depth 4 is too coarse for the dual mesh as well: the primal polygons, and why
                self.assertEqual(s["polygoniser"]["mesher"], "primal")
                self.assertEqual(s["polygoniser"]["dual_declined"], "error_at_max_depth")
        # no bound (off, or 0 as before): met and max_error are null, the primal polygons
        for off in ("off", "0"):
            p = run(*sphere, "-d", "3:5", "--max-error", off, "--stats")
            s = json.loads(p.stdout)
            acc = s["analysis"]["accuracy"]
            self.assertIsNone(acc["max_error"])
            self.assertIsNone(acc["met"])
            self.assertEqual(s["polygoniser"]["dual_declined"], "no_bound")
            self.assertEqual(s["warnings"], [])

    def test_default_bound_is_a_thousandth_of_the_box_diagonal(self):
        """Without --max-error the bound is 1e-3 x the box diagonal, as a request's: the stats
        say it and whether it was met, the mesh is the same as with that E written out, and
        the triangles' centroids and edge midpoints lie within it (closed form); in the box
        +-1.5's placements (boxes.py; the finest cell at the safety depth, 10) and in a box that
        is not a cube."""
        cell = 3.0 / 2 ** 10
        for box in placements([-1.5] * 3 + [1.5] * 3, cell) + [[-1.0, -2.0, -0.9, 1.3, 1.1, 0.95]]:
            d = math.dist(box[:3], box[3:])
            b = ",".join(map(repr, box))
            with self.subTest(box=box):
                path, again = self.out("d.ply"), self.out("e.ply")
                p = run("-e", "x^2 + y^2 + z^2 - 0.64", "-b", b, "-o", path, "--stats")
                self.assertEqual(p.returncode, 0, p.stderr)
                s = json.loads(p.stdout)
                acc = s["analysis"]["accuracy"]
                self.assertAlmostEqual(acc["max_error"], 1e-3 * d, delta=1e-15)
                self.assertIs(acc["met"], True)
                self.assertEqual(s["polygoniser"]["mesher"], "dual")
                worst = self.sphere_between_vertices(path, 0.8)
                self.assertLessEqual(worst, 1e-3 * d + 1e-6)  # float32 positions
                p = run("-e", "x^2 + y^2 + z^2 - 0.64", "-b", b, "--max-error", repr(1e-3 * d),
                        "-o", again)
                self.assertEqual(p.returncode, 0, p.stderr)
                with open(path, "rb") as f, open(again, "rb") as g:
                    self.assertEqual(f.read(), g.read(), "explicit E equal to the default")

    def test_help(self):
        p = run("--help")
        self.assertEqual(p.returncode, 0)
        for flag in ("--expr", "--param", "--let", "--box", "--depth", "--surface", "--surfaces",
                     "--stats", "--output", "--worker", "--threads", "--max-error",
                     "--no-dual", "--dual", "--simplify", "--no-simplify",
                     "--gradient-test", "--double-root-eps", "--double-root-iters",
                     "--stitch-tol", "--flat-normal", "--flat-plane"):
            self.assertIn(flag, p.stdout)

    def test_help_gives_the_published_tolerance_defaults(self):
        """--help's line for each tolerance says the default proto/request.schema.json
        publishes for requests (issue 15: one table, core/octree/tolerances.h, drives both;
        the comments and help once said 0.8 / 0.1 where the code used 0.9 / 0.05)."""
        p = run("--help")
        with open(os.path.join(ROOT, "proto", "request.schema.json")) as f:
            tol = json.load(f)["properties"]["tolerances"]["properties"]
        flags = {"gradient": "--gradient-test", "stitch": "--stitch-tol"}
        for key, spec in tol.items():
            flag = flags.get(key, "--" + key.replace("_", "-"))
            line = next((ln for ln in p.stdout.splitlines() if ln.split()[:1] == [flag]), None)
            self.assertIsNotNone(line, flag)
            m = re.search(r"\(default ([-+0-9.e]+)\)", line)
            self.assertIsNotNone(m, line)
            self.assertEqual(float(m.group(1)), spec["default"], line)

    def test_tolerances_have_the_published_ranges(self):
        """The CLI accepts each tolerance at the limits proto/request.schema.json publishes for
        requests and refuses a value past them, naming the flag (one range for both)."""
        with open(os.path.join(ROOT, "proto", "request.schema.json")) as f:
            tol = json.load(f)["properties"]["tolerances"]["properties"]
        flags = {"gradient": "--gradient-test", "stitch": "--stitch-tol"}
        sphere = ("-e", "x^2 + y^2 + z^2 - 0.8", "-d", "1:2")
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "s.ply")
            for key, spec in tol.items():
                flag = flags.get(key, "--" + key.replace("_", "-"))
                step = 1 if spec["type"] == "integer" else max(abs(spec["maximum"]), 1e-9) / 10
                ok = run(*sphere, flag, str(spec["maximum"]), "-o", out)
                self.assertEqual(ok.returncode, 0, f"{flag} {spec['maximum']}: {ok.stderr}")
                bad = run(*sphere, flag, repr(spec["maximum"] + step), "-o", out)
                self.assertEqual(bad.returncode, 2, f"{flag} above {spec['maximum']}")
                self.assertIn(flag, bad.stderr)
                bad = run(*sphere, flag, repr(spec["minimum"] - step), "-o", out)
                self.assertEqual(bad.returncode, 2, f"{flag} below {spec['minimum']}")


if __name__ == "__main__":
    unittest.main()
