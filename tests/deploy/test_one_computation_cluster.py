"""test_one_computation_cluster.py — one polygonisation per surface across daemons sharing
Redis (issue 18, item 5): daemon A computes a drc; daemon B, asked for the ply, the obj and a
12-bit drc of the same surface, encodes them from the computed surface A stored in Redis
("<surface key>.mesh"): the polygonisations counted by both daemons add up to one. The same
with --cluster, where the cluster queue picks the daemon that encodes.

A daemon answers before its Redis writes go out (they follow on its Redis thread, in the order
they were made: the mesh, its stats, features and request, then the computed surface, which
its worker sends after the answer in a SURFACE frame of its own: proto/frame.h), so B is asked
only once the mesh's entries and the surface are in Redis (stack.wait_stored, then the one
"<surface key>.mesh"): asked sooner, B would find no stored surface and polygonise again, and
the count would be two."""
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack  # noqa: E402

SKIP = stack.missing_programs()

BASE = {"expr": "x^2 + y^2 - z^2 - 0.2 + b*x*y*z", "params": {"b": 1.3},
        "box": [-1.1, -1.1, -1.1, 1.1, 1.1, 1.1], "depth": {"min": 3, "max": 6}}
TWELVE = dict(BASE, output={"position_bits": 12})


def polygonisations(ds):
    return sum(d.metric("isomesh_polygonisations_total") for d in ds)


def encodings(ds):
    return sum(d.metric("isomesh_stored_encodings_total") for d in ds)


@unittest.skipIf(SKIP, SKIP)
class OneComputationClusterTest(unittest.TestCase):
    def run_on(self, args, tag):
        s = stack.Stack(n=2, daemon_args=args, with_nginx=False).start()
        try:
            a, b = s.daemons
            base = dict(BASE, params={"b": tag})
            twelve = dict(TWELVE, params={"b": tag})
            r = a.post("/v1/mesh", base)
            self.assertEqual(r.status, 200, r.body[:300])
            self.assertEqual(polygonisations(s.daemons), 1)
            self.assertTrue(stack.wait_stored(s.redis, r.header("ETag").strip('"')))
            self.assertTrue(stack.wait_until(
                lambda: len(s.redis.command("KEYS", "isomesh:v1:*.mesh")) == 1, 30))
            for req, fmt in ((base, "ply"), (base, "obj"), (twelve, "drc")):
                r = b.post("/v1/mesh?format=" + fmt, req)
                self.assertEqual(r.status, 200, r.body[:300])
                self.assertGreater(len(r.body), 1000)
            self.assertEqual(polygonisations(s.daemons), 1, a.log()[-2000:] + b.log()[-2000:])
            self.assertEqual(encodings(s.daemons), 3)
        finally:
            s.cleanup()

    def test_two_daemons_sharing_redis(self):
        self.run_on([], 1.31)

    def test_cluster_queue(self):
        self.run_on(["--cluster"], 1.37)


if __name__ == "__main__":
    unittest.main()
