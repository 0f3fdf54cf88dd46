"""test_load.py — a short soak (tests/bench/bench_load.py's mix for 10 s): wrk at 128
connections, GETs of cached meshes and one request in ten a new computation. Asserted: every
answer is a success or a designed refusal (503 queue full, 429), no socket error, the daemon
exits cleanly, and its resident memory grows by less than 24 MiB after the first quarter of
the run (memory cache capped at 4 MiB). Skipped against sanitizer builds (their allocators
hold freed memory on purpose) and without wrk. Figures: `make soak`."""
import os
import shutil
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "bench"))
from reltools import BUILD, sanitizer_build  # noqa: E402
from harness import ISOMESHD  # noqa: E402
import bench_load  # noqa: E402


class ShortSoakTest(unittest.TestCase):
    def test_ten_seconds_of_mixed_load(self):
        if not shutil.which("wrk"):
            self.skipTest("wrk is not installed")
        if sanitizer_build(ISOMESHD):
            self.skipTest("sanitizer build: resident memory says nothing about leaks")
        tmp = tempfile.mkdtemp(prefix="isomesh_load_")
        try:
            r = bench_load.soak(BUILD, tmp, 10, 128, 0.1, sample_s=1.0, cache_mem="4M")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        self.assertGreater(r["requests"], 0, r["raw"][-2000:])
        self.assertGreater(r["statuses"].get(200, 0), 0, r["raw"][-2000:])
        self.assertEqual(bench_load.errors_of(r), 0, "%s %s" % (r["statuses"], r["socket_errors"]))
        self.assertEqual(r["exit"], 0)
        growth = bench_load.rss_growth(r["rss"])
        self.assertLess(growth, 24.0, "RSS series (MiB): %s" % [round(v) for _, v in r["rss"]])


if __name__ == "__main__":
    unittest.main()
