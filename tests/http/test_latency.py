"""test_latency.py — a computed answer leaves as soon as its computation ends: it does not wait
for the polling threads' sleep bound (MAX_WAIT_MS, 1,000 ms, server/common/http_loops.c).

A request that needs a computation is suspended; the thread that receives the worker's result
resumes it, and only a wake-up of the polling thread that owns the connection sends the answer.
Without that wake-up (libmicrohttpd in external-epoll mode does not give one) every computed
answer waited up to the full bound while all other tests passed. Measured here on the three
resume paths, each with the server's own account of the computation subtracted from the wall
time the client sees:
  - POST /v1/mesh of a fresh surface (flight_wait.c: the request's own flight);
  - two identical requests at once, the second joining the first's flight;
  - a job's event stream (jobs.c: the final event of a job that ends while the stream waits).
The bound: a sample's excess stays under EXCESS_MAX_MS, half the sleep bound; the old code gave
1,000 ms minus the computation (900+ ms for these). One sample of each group may exceed it (a
machine at a load of 20 can stall a process that long); the others may not."""
import json
import os
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Daemon, open_get, sphere  # noqa: E402

# Half the polling threads' sleep bound (1,000 ms): an answer that waited for the bound
# instead of a wake-up exceeds it by the bound minus its computation time.
EXCESS_MAX_MS = 500
# Samples per group; all but one must stay under EXCESS_MAX_MS.
SAMPLES = 4


def fresh_sphere(i, depth=None, deeper=None):
    """A sphere no earlier request asked for (a distinct radius: a distinct cache key); depth
    pins the octree depth (6: some 70-400 ms of computation, so that a second request reliably
    arrives while it runs); deeper, a depth every cell is split to (depth.min is capped at 6;
    6..8: ~0.5 s, for an event stream opened by a second round trip)."""
    req = sphere(0.6 + 0.01 * i + (time.time() % 1) * 1e-4)
    if depth:
        req["depth"] = {"min": depth, "max": deeper or depth}
    if deeper:  # an error no depth reaches: every cell goes down to `deeper`
        req["max_error"] = 1e-6
    return req


def timing(header):
    """Server-Timing "a;dur=1.5, b;desc=x, c;dur=2" -> {"a": 1.5, "c": 2.0}."""
    out = {}
    for entry in header.split(","):
        parts = [p.strip() for p in entry.split(";")]
        for p in parts[1:]:
            if p.startswith("dur="):
                out[parts[0]] = float(p[4:])
    return out


class LatencyTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.d = Daemon.started("--workers", "2")
        cls.n = 0

    @classmethod
    def tearDownClass(cls):
        rc = cls.d.stop()
        cls.d.cleanup()
        assert rc == 0, "isomeshd did not stop cleanly (exit %r)" % rc

    def next_id(self):
        LatencyTest.n += 1
        return LatencyTest.n

    def assert_excess(self, what, excess):
        over = [e for e in excess if e >= EXCESS_MAX_MS]
        self.assertLessEqual(len(over), 1, "%s: wall minus the server's computation, ms: %s "
                             "(bound %d)" % (what, ["%.0f" % e for e in excess], EXCESS_MAX_MS))

    def post_mesh(self, req):
        """POST /v1/mesh -> (the response, the wall ms it took, the server's computation ms:
        parse + queue + worker from Server-Timing; None for a cache hit)."""
        t0 = time.monotonic()
        r = self.d.post("/v1/mesh", req)
        wall = (time.monotonic() - t0) * 1e3
        self.assertEqual(r.status, 200, r.body[:300])
        if r.header("X-Cache") == "hit":
            return r, wall, None
        t = timing(r.header("Server-Timing") or "")
        for phase in ("parse", "queue", "worker"):
            self.assertIn(phase, t, r.header("Server-Timing"))
        return r, wall, t["parse"] + t["queue"] + t["worker"]

    def test_computed_mesh_answers_without_waiting(self):
        excess = []
        for _ in range(SAMPLES):
            r, wall, computed = self.post_mesh(fresh_sphere(self.next_id()))
            self.assertEqual(r.header("X-Cache"), "miss")
            excess.append(wall - computed)
        self.assert_excess("POST /v1/mesh", excess)

    def test_request_joining_a_flight_answers_without_waiting(self):
        excess, rounds = [], 0
        for _ in range(3 * SAMPLES // 2):
            if rounds == SAMPLES // 2:
                break
            req = fresh_sphere(self.next_id(), depth=6)
            before = self.d.metric("isomesh_computations_started_total")
            go = threading.Barrier(2)
            out = [None, None]

            def one(i):
                go.wait()
                out[i] = self.post_mesh(req)
            threads = [threading.Thread(target=one, args=(i,)) for i in range(2)]
            for t in threads:
                t.start()
            for t in threads:
                t.join(120)
            self.assertTrue(all(out), "a request did not answer")
            # A round counts when one computation served both, neither from the cache: one
            # waited for the other's flight (a second request held up past the computation by
            # a loaded machine finds the mesh cached instead).
            if ([o[0].header("X-Cache") for o in out] == ["miss", "miss"] and
                    self.d.metric("isomesh_computations_started_total") == before + 1):
                rounds += 1
                excess += [wall - computed for _, wall, computed in out]
        self.assertEqual(rounds, SAMPLES // 2, "the second request never joined the first's")
        self.assert_excess("two requests, one flight", excess)

    def job_final_event(self, req):
        """POST /v1/jobs, then its event stream read as events arrive -> (the wall ms from the
        post to the final event, the server's computation ms: queue + the pipeline's total,
        whether the stream saw the job before it ended)."""
        t0 = time.monotonic()
        r = self.d.post("/v1/jobs", req)
        self.assertEqual(r.status, 202, r.body[:300])
        job = r.json()
        conn, resp = open_get(self.d.port, job["events_url"])
        try:
            self.assertEqual(resp.status, 200)
            names, data = [], None
            while True:
                line = resp.readline()
                self.assertTrue(line, "the stream ended before a final event: %s" % names)
                line = line.decode().rstrip("\n")
                if line.startswith("event: "):
                    names.append(line[7:])
                elif line.startswith("data: ") and names[-1] != "progress":
                    data = json.loads(line[6:])
                    break
            wall = (time.monotonic() - t0) * 1e3
        finally:
            conn.close()
        self.assertEqual(names[-1], "done", data)
        computed = data["queue_ms"] + data["stats"]["timings_ms"]["total"]
        return wall, computed, len(names) > 1

    def test_job_event_stream_sends_the_end_without_waiting(self):
        # Depth 8 (~0.5 s of computation): at depth 6 (0.07 s since empty leaves above depth.min
        # stopped being split) two of four jobs ended before a loaded CI machine opened their
        # streams. A job that ended first is retried, up to 3x the samples, as the flight test does.
        excess, live = [], 0
        for _ in range(3 * SAMPLES):
            if live == SAMPLES:
                break
            wall, computed, seen_running = self.job_final_event(fresh_sphere(self.next_id(), 6, 8))
            if seen_running:  # the final event came through a resume of the waiting stream
                live += 1
                excess.append(wall - computed)
        self.assertGreaterEqual(live, SAMPLES - 1, "jobs ended before their streams opened")
        self.assert_excess("job event stream", excess)


if __name__ == "__main__":
    unittest.main()
