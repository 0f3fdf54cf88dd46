"""test_cache_disk.py — the disk cache's size bound and its housekeeping. With
--cache-disk-max, the directory stays under the bound: the least recently used keys go first,
all files of a key together (a key read again stays), the removals are counted and logged, an
evicted mesh is simply computed again (the same bytes), and after a restart the size gauge is
what the directory holds. Temporary files left by a writer that died mid-write are removed at
start; those of a live process stay."""
import glob
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import Daemon, draco_counts, request  # noqa: E402
from reltools import sphere as bounded_sphere  # noqa: E402

KINDS = ("drc", "stats.json", "features.json", "request.json")
SURFACE_KINDS = ("mesh",)  # the computed surface every format is encoded from, its own key
FILES_PER_MESH = len(KINDS) + len(SURFACE_KINDS)
# A sphere's mesh key is about 18 KB (drc, stats, features, request) and its computed surface
# about 250 KB: the bound holds about five of each.
LIMIT = 1600 * 1024


def sphere(r):
    """The sphere of radius r on the depth path ("max_error": null): the sizes above are its
    (the default bound's dual sphere is a few times smaller and never fills the bound)."""
    return dict(bounded_sphere(r), max_error=None)


def entries(cache):
    """{key: {kind: size}} of the entry files under cache/v1/<shard>/."""
    out = {}
    for path in glob.glob(os.path.join(cache, "v1", "??", "*")):
        name = os.path.basename(path)
        key, kind = name[:64], name[65:]
        out.setdefault(key, {})[kind] = os.path.getsize(path)
    return out


def total(cache):
    return sum(sum(k.values()) for k in entries(cache).values())


def wait_until(cond, timeout=30):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if cond():
            return True
        time.sleep(0.05)
    return cond()


class DiskBoundTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="isomesh_disk_")
        self.cache = os.path.join(self.tmp, "cache")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_least_recently_used_keys_go_and_the_bound_holds(self):
        args = ("--workers", "2", "--cache-mem", "0", "--cache-disk-max", str(LIMIT))
        with Daemon(*args, cache_dir=self.cache) as d:
            status, h, hot_body = request(d.port, "POST", "/v1/mesh", sphere(0.5))
            self.assertEqual(status, 200)
            hot = h["etag"].strip('"')
            cold = []
            bodies = {}
            for i in range(24):
                status, h, body = request(d.port, "POST", "/v1/mesh", sphere(0.6 + i / 100))
                self.assertEqual(status, 200)
                cold.append(h["etag"].strip('"'))
                bodies[cold[-1]] = body
                # once the new key is on disk (writes are queued; a file's mtime is its write)
                # the hot key is read: from disk (no memory tier), so it is the latest used
                self.assertTrue(wait_until(lambda: d.metric(
                    "isomesh_cache_tier_stores_total", tier="disk") >= FILES_PER_MESH * (i + 2)))
                status, h, body = request(d.port, "GET", "/v1/meshes/%s.drc" % hot)
                self.assertEqual((status, h["x-cache"]), (200, "hit"))
                self.assertEqual(body, hot_body)
            # every file of the 25 keys written (writes are queued): the cache is at rest
            self.assertTrue(wait_until(lambda: d.metric("isomesh_cache_tier_stores_total",
                                                        tier="disk") >= FILES_PER_MESH * 25))
            self.assertTrue(wait_until(lambda: d.metric("isomesh_cache_evictions_total",
                                                        tier="disk") > 0), d.log()[-2000:])
            self.assertTrue(wait_until(lambda: total(self.cache) <= LIMIT),
                            "the directory holds %d bytes, over %d" % (total(self.cache), LIMIT))
            self.assertTrue(wait_until(
                lambda: d.metric("isomesh_cache_bytes", tier="disk") == total(self.cache)))
            self.assertLessEqual(d.metric("isomesh_cache_bytes", tier="disk"), LIMIT)
            # the log comes through a pipe read by a thread: awaited
            self.assertTrue(wait_until(lambda: "cache_pruned" in d.log()), d.log()[-2000:])
            held = entries(self.cache)
            # whole keys only: every key on disk has all its files, the hot one among them
            for key, kinds in held.items():
                self.assertIn(sorted(kinds), (sorted(KINDS), sorted(SURFACE_KINDS)), key)
            self.assertIn(hot, held)
            self.assertNotIn(cold[0], held)  # the oldest, never read again
            self.assertEqual(d.metric("isomesh_cache_entries", tier="disk"),
                             sum(len(kinds) for kinds in held.values()))
            # an evicted mesh is computed again, byte for byte the same
            status, h, body = request(d.port, "GET", "/v1/meshes/%s.drc" % cold[0])
            self.assertIn(status, (200, 404))  # 404 when its request went with it
            status, h, body = request(d.port, "POST", "/v1/mesh", sphere(0.6))
            self.assertEqual((status, h["x-cache"]), (200, "miss"))
            self.assertEqual(body, bodies[cold[0]])
            self.assertGreater(draco_counts(body)[1], 0)
            self.assertEqual(d.stop(), 0)
        # after a restart the gauges say what the directory holds (and it is pruned if over)
        with Daemon(*args, cache_dir=self.cache) as d:
            self.assertTrue(wait_until(
                lambda: d.metric("isomesh_cache_bytes", tier="disk") == total(self.cache) > 0))
            self.assertLessEqual(total(self.cache), LIMIT)
            self.assertEqual(d.get("/v1/meshes/%s.drc" % hot).body, hot_body)

    def test_no_bound_keeps_everything(self):
        with Daemon("--workers", "2", "--cache-disk-max", "0", cache_dir=self.cache) as d:
            for i in range(6):
                self.assertEqual(d.post("/v1/mesh", sphere(0.7 + i / 100)).status, 200)
            self.assertEqual(d.stop(), 0)
        held = entries(self.cache)
        self.assertEqual(sum(1 for kinds in held.values() if sorted(kinds) == sorted(KINDS)), 6)
        self.assertEqual(sum(1 for kinds in held.values() if sorted(kinds) == ["mesh"]), 6)

    def test_leftover_temporary_files_of_dead_writers_are_removed(self):
        tmpdir = os.path.join(self.cache, "v1", "tmp")
        os.makedirs(tmpdir)
        gone = subprocess.Popen(["true"])
        gone.wait()  # a pid that no longer runs
        name = "a" * 64 + ".drc"
        dead = os.path.join(tmpdir, "%s.%d.1.tmp" % (name, gone.pid))
        dead_probe = os.path.join(tmpdir, "probe.%d" % gone.pid)
        live = os.path.join(tmpdir, "%s.%d.1.tmp" % (name, os.getpid()))
        foreign = os.path.join(tmpdir, "notes.txt")
        for path in (dead, dead_probe, live, foreign):
            with open(path, "wb") as f:
                f.write(b"partial")
        with Daemon("--workers", "1", cache_dir=self.cache) as d:
            self.assertTrue(wait_until(lambda: not os.path.exists(dead)), d.log())
            self.assertFalse(os.path.exists(dead_probe))
            self.assertTrue(os.path.exists(live))      # its writer (this test) is alive
            self.assertTrue(os.path.exists(foreign))   # not a name the cache writes
            # the log comes through a pipe read by a thread: awaited
            self.assertTrue(wait_until(lambda: "cache_tmp_cleaned" in d.log()), d.log()[-2000:])


if __name__ == "__main__":
    unittest.main()
