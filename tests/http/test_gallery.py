"""test_gallery.py — the gallery of GET /v1/presets (proto/presets.c): at least 40 entries,
each with a source, parameters, a box and depths; every entry meshes without error at its own
settings; and every fact an entry states (nodes: singular points of type node in the features
JSON v2; Euler characteristic; components) holds on the mesh — in the entry's box and in the
placements of tests/cli/boxes.py off the octree lattice (moved by (1e-3, -1e-3, 0.7e-3) and by
irrational fractions of a finest cell, IRR_CELLS). Also POST /v1/box, and
the thumbnails the daemon renders itself (GET /v1/presets/{name}/thumbnail.png)."""
import json
import os
import struct
import sys
import unittest
import zlib
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import BUILD, Daemon  # noqa: E402
from boxes import IRR_CELLS, placements  # noqa: E402  (tests/cli; path set by harness)

MIN_ENTRIES = 40
# Against the sanitizer build (5-10x slower) the daemon's memory safety is what is tested:
# only the entries with facts, only in the box off the lattice by IRR_CELLS; the release
# run covers the entries with facts in every placement, the others in their own box.
SANITIZED = os.path.basename(os.path.normpath(BUILD)) == "asan"


def entry_boxes(p):
    """The boxes an entry is meshed in: boxes.placements of its box with its finest cell per
    axis (its own box first, the irrational placement last)."""
    boxes = placements(p["box"], tuple((p["box"][a + 3] - p["box"][a]) / 2 ** p["depth"]["max"]
                                       for a in range(3)))
    if SANITIZED:
        return boxes[-1:] if p["facts"] else []
    return boxes if p["facts"] else boxes[:1]


def decode_png(data):
    """(width, height, rows of RGBA bytes) of an 8-bit RGBA PNG, every chunk CRC checked, the
    rows unfiltered (all five filter types) — with Python's zlib, independent of the daemon."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "PNG signature"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        assert struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])[0] == zlib.crc32(kind + body)
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            assert (depth, colour) == (8, 6), "8-bit RGBA"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), 4 * w, [], bytearray(4 * w)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a, b, c = line[i - 4] if i >= 4 else 0, prev[i], prev[i - 4] if i >= 4 else 0
            pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
            pred = [0, a, b, (a + b) // 2, a if pa <= pb and pa <= pc else b if pb <= pc else c][f]
            line[i] = (line[i] + pred) & 255
        rows.append(line)
        prev = line
    return w, h, rows


class GalleryTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.d = Daemon("--workers", "2")
        try:  # tearDownClass does not run when setUpClass fails: never leave the daemon behind
            cls.d.start()
            r = cls.d.get("/v1/presets")
            assert r.status == 200
            cls.presets = r.json()["presets"]
        except BaseException:
            cls.d.cleanup()
            raise

    @classmethod
    def tearDownClass(cls):
        cls.d.stop()
        cls.d.cleanup()

    def mesh(self, body):
        """(stats, features) of one request, or the failure text."""
        r = self.d.post("/v1/mesh", json.dumps(body).encode(), timeout=600)
        if r.status != 200:
            return None, f"HTTP {r.status}: {r.body[:300]!r}"
        key = r.header("ETag").strip('"')
        stats = self.d.get(f"/v1/meshes/{key}/stats").json()
        features = self.d.get(f"/v1/meshes/{key}/features").json()
        return stats, features

    def test_thumbnails_rendered_cached_and_checked(self):
        # The torus (R 1, r 0.3) seen along (1.5, -2.1, 1.25): the line of sight through its
        # centre passes sin(25.8 deg) = 0.44 > r from the core circle, so the centre pixel
        # shows the hole; the Kummer surface fills more of its frame. Foreground: alpha > 0.
        for name, share in (("torus", (0.08, 0.5)), ("kummer-16-nodes", (0.15, 0.7))):
            before = self.d.metric("isomesh_polygonisations_total") or 0
            r = self.d.get(f"/v1/presets/{name}/thumbnail.png", timeout=300)
            self.assertEqual(r.status, 200, r.body[:200])
            self.assertEqual(r.header("Content-Type"), "image/png")
            w, h, rows = decode_png(r.body)
            self.assertEqual((w, h), (160, 120))
            fg = sum(1 for row in rows for x in range(w) if row[4 * x + 3]) / (w * h)
            self.assertTrue(share[0] <= fg <= share[1], f"{name}: foreground share {fg:.3f}")
            colours = {bytes(row[4 * x:4 * x + 3]) for row in rows for x in range(w) if row[4 * x + 3] == 255}
            self.assertGreater(len(colours), 50, f"{name}: shaded, not flat")
            if name == "torus":
                self.assertEqual(rows[h // 2][4 * (w // 2) + 3], 0, "the torus' hole at the centre")
            self.assertEqual(self.d.metric("isomesh_polygonisations_total"), before + 1)
            again = self.d.get(f"/v1/presets/{name}/thumbnail.png")
            self.assertEqual((again.status, again.header("X-Cache")), (200, "hit"))
            self.assertEqual(again.body, r.body)
            self.assertEqual(self.d.metric("isomesh_polygonisations_total"), before + 1)
        self.assertEqual(self.d.get("/v1/presets/no-such-surface/thumbnail.png").status, 404)
        self.assertEqual(self.d.get("/v1/presets/../thumbnail.png").status, 404)

    def test_box_endpoint_fits_the_zero_set(self):
        # A sphere of radius 1.2 about (3, -2, 0.5) in the cube ±10, centre shifted off the
        # 128-cell lattice by the irrational fractions of a cell (IRR_CELLS).
        cell = 20 / 128
        c = [3 + IRR_CELLS[0] * cell, -2 + IRR_CELLS[1] * cell, 0.5 + IRR_CELLS[2] * cell]
        body = {"expr": f"(x - {c[0]!r})^2 + (y - {c[1]!r})^2 + (z - {c[2]!r})^2 - 1.44",
                "box": [-10, -10, -10, 10, 10, 10]}
        r = self.d.post("/v1/box", json.dumps(body).encode())
        self.assertEqual(r.status, 200, r.body)
        a = r.json()
        self.assertFalse(a["empty"])
        self.assertTrue(a["complete"])
        for k in range(3):
            self.assertLessEqual(a["box"][k], c[k] - 1.2)
            self.assertGreaterEqual(a["box"][k + 3], c[k] + 1.2)
            self.assertLess(a["box"][k + 3] - a["box"][k], 2.4 + 5 * cell)
        r = self.d.post("/v1/box", json.dumps({"expr": "x^2 + y^2 + z^2 + 1", "box": body["box"]}).encode())
        self.assertTrue(r.json()["empty"])
        r = self.d.post("/v1/box", b'{"expr": "x^2 + sinn(y)"}')
        self.assertEqual(r.status, 400)
        self.assertEqual(r.json()["error"]["column"], 7)

    def test_entries_are_described(self):
        self.assertGreaterEqual(len(self.presets), MIN_ENTRIES)
        names = [p["name"] for p in self.presets]
        self.assertEqual(len(names), len(set(names)))
        for p in self.presets:
            with self.subTest(p["name"]):
                self.assertTrue(p["title"] and p["about"] and p["source"])
                self.assertEqual(len(p["box"]), 6)
                self.assertTrue(all(p["box"][a] < p["box"][a + 3] for a in range(3)))
                self.assertLessEqual(p["depth"]["min"], p["depth"]["max"])
                for q in p["params"]:
                    self.assertLessEqual(q["min"], q["default"])
                    self.assertLessEqual(q["default"], q["max"])

    def test_every_entry_meshes_and_its_facts_hold(self):
        jobs = []
        for p in self.presets:
            for box in entry_boxes(p):
                jobs.append((p, box, {"preset": p["name"], "box": box, "depth": p["depth"]}))
        with ThreadPoolExecutor(max_workers=2) as pool:
            results = list(pool.map(lambda j: self.mesh(j[2]), jobs))
        failures = []
        for (p, s, _), (stats, features) in zip(jobs, results):
            where = f"{p['name']} (box {s})"
            if stats is None:
                failures.append(f"{where}: {features}")
                continue
            got = {
                "nodes": sum(1 for q in features["singular_points"] if q["type"] == "node"),
                "euler": stats["analysis"]["euler"],
                "components": stats["analysis"]["components"],
                "singular_points": len(features["singular_points"]),
            }
            for fact, want in p["facts"].items():
                if got[fact] != want:
                    failures.append(f"{where}: {fact} {got[fact]}, the gallery says {want}")
        self.assertEqual(failures, [], "\n".join(failures))
        # every entry at its own depth ran in the seccomp-filtered workers without one dying
        # (tests/reliability/test_sandbox.py relies on this for full depths)
        self.assertEqual(self.d.metric("isomesh_worker_restarts_total", reason="crash"), 0)
        self.assertEqual(self.d.log_count("sandbox refused", 1, timeout=0), 0)


if __name__ == "__main__":
    unittest.main()
