"""test_workers.py — the worker pool under trouble, each case with its own daemon: a
computation past its deadline answers 504 and its worker is replaced; a worker killed with
SIGKILL mid-job answers that job 500 once and the next request succeeds; a full queue answers
503 with Retry-After; one client over its share answers 429; SIGTERM with a computation
running ends it within the bound and exits 0; workers are started with the memory limit."""
import os
import signal
import sys
import time
import unittest

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import SLOW, SLOWER, Daemon, draco_counts, in_background, process_alive, sphere  # noqa: E402
from boxes import placements  # noqa: E402  (tests/cli; path set by harness)


with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "proto",
                       "openapi.yaml")) as f:
    ERROR_FIELDS = yaml.safe_load(f)["components"]["schemas"]["Error"]["properties"]["error"][
        "properties"]


class WorkerTest(unittest.TestCase):
    def assert_error(self, r, status, code):
        self.assertEqual(r.status, status, r.body[:300])
        self.assertEqual(r.json()["error"]["code"], code)

    def test_deadline_gives_504_and_a_fresh_worker(self):
        # 5 s: far below SLOWER's time (gyroid, k = 8, depth 10, quality pass: 12 s and more), far
        # above the small sphere's even on a machine busy with other work.
        with Daemon("--workers", "1", "--job-timeout", "5s") as d:
            old = d.workers()
            self.assertEqual(len(old), 1)
            t0 = time.time()
            r = d.post("/v1/mesh", SLOWER)
            self.assert_error(r, 504, "deadline_exceeded")
            self.assertLess(time.time() - t0, 30)
            self.assertTrue(d.wait_metric("isomesh_worker_restarts_total", 1, reason="deadline"))
            d.wait_ready()
            ok = d.post("/v1/mesh", sphere(0.8))
            self.assertEqual(ok.status, 200)
            self.assertGreater(draco_counts(ok.body)[1], 0)
            new = d.workers()
            self.assertEqual(len(new), 1)
            self.assertNotEqual(new, old)
            self.assertEqual(d.metric("isomesh_computations_total", outcome="deadline"), 1)
            # the same slow request as a job fails the same way
            job = d.post("/v1/jobs", SLOWER).json()
            deadline = time.time() + 30
            while time.time() < deadline:
                j = d.get(job["url"]).json()
                if j["state"] not in ("queued", "running"):
                    break
                time.sleep(0.02)
            self.assertEqual(j["state"], "failed")
            self.assertEqual(j["status"], 504)
            self.assertEqual(j["error"]["code"], "deadline_exceeded")

    def test_sigkilled_worker_gives_one_500_then_service_continues(self):
        with Daemon("--workers", "1") as d:
            t, box = in_background(lambda: d.post("/v1/mesh", SLOW))
            self.assertTrue(d.wait_metric("isomesh_workers_busy", 1), "the worker never got busy")
            victims = d.workers()
            self.assertEqual(len(victims), 1)
            os.kill(victims[0], signal.SIGKILL)
            t.join(60)
            self.assertNotIn("error", box)
            r = box["result"]
            self.assert_error(r, 500, "worker_crashed")
            self.assertIn("signal 9", r.json()["error"]["message"])
            self.assertTrue(d.wait_metric("isomesh_worker_restarts_total", 1, reason="crash"))
            d.wait_ready()
            ok = d.post("/v1/mesh", sphere(0.81))
            self.assertEqual(ok.status, 200)
            self.assertGreater(draco_counts(ok.body)[0], 0)
            self.assertEqual(d.metric("isomesh_worker_restarts_total", reason="crash"), 1)
            self.assertEqual(d.metric("isomesh_computations_total", outcome="crash"), 1)
            self.assertNotIn(victims[0], d.workers())

    def test_full_queue_is_503_with_retry_after(self):
        with Daemon("--workers", "1", "--queue", "1", "--client-jobs", "10") as d:
            running = d.post("/v1/jobs", SLOW)
            self.assertEqual(running.status, 202)
            self.assertTrue(d.wait_metric("isomesh_workers_busy", 1))
            queued = d.post("/v1/jobs", {"preset": "gyroid-ball", "depth": {"max": 7},
                                         "max_error": None})
            self.assertEqual(queued.status, 202)
            self.assertEqual(queued.json()["state"], "queued")
            full = d.post("/v1/mesh", sphere(0.71))
            self.assert_error(full, 503, "queue_full")
            self.assertTrue(int(full.header("Retry-After")) > 0)
            self.assert_error(d.post("/v1/jobs", sphere(0.72)), 503, "queue_full")
            # an identical request joins the queued computation instead of being refused
            joined = d.post("/v1/jobs", {"preset": "gyroid-ball", "depth": {"max": 7},
                                         "max_error": None})
            self.assertEqual(joined.status, 202)
            self.assertEqual(d.metric("isomesh_queue_depth"), 1)
            # a cached mesh is still served while the queue is full
            for job in (running.json(), queued.json(), joined.json()):
                self.assertEqual(d.request("DELETE", job["url"]).json()["state"], "canceled")
            d.wait_idle()
            self.assertEqual(d.post("/v1/mesh", sphere(0.71)).status, 200)
            self.assertEqual(d.metric("isomesh_queue_depth"), 0)

    def test_queue_of_zero_still_runs_one_computation_per_idle_worker(self):
        with Daemon("--workers", "1", "--queue", "0") as d:
            self.assertEqual(d.post("/v1/mesh", sphere(0.73)).status, 200)
            running = d.post("/v1/jobs", SLOW)
            self.assertEqual(running.status, 202)
            self.assertTrue(d.wait_metric("isomesh_workers_busy", 1))
            self.assert_error(d.post("/v1/jobs", sphere(0.74)), 503, "queue_full")
            self.assertEqual(d.request("DELETE", running.json()["url"]).json()["state"], "canceled")
            d.wait_idle()
            self.assertEqual(d.post("/v1/mesh", sphere(0.74)).status, 200)

    def test_one_client_over_its_share_is_429(self):
        with Daemon("--workers", "1", "--queue", "8", "--client-jobs", "1") as d:
            first = d.post("/v1/jobs", SLOW)
            self.assertEqual(first.status, 202)
            r = d.post("/v1/mesh", sphere(0.61))
            self.assert_error(r, 429, "too_many_requests")
            self.assertTrue(int(r.header("Retry-After")) > 0)
            self.assert_error(d.post("/v1/jobs", sphere(0.62)), 429, "too_many_requests")
            # joining the computation already in flight is not a new one
            joined = d.post("/v1/jobs", SLOW)
            self.assertEqual(joined.status, 202)
            self.assertEqual(d.metric("isomesh_rejected_total", reason="client_limit"), 2)
            for job in (first.json(), joined.json()):
                d.request("DELETE", job["url"])

    def test_sigterm_with_a_running_computation_exits_cleanly(self):
        d = Daemon("--workers", "1", "--job-timeout", "2s")
        try:
            d.start()
            t, box = in_background(lambda: d.post("/v1/mesh", SLOW))
            self.assertTrue(d.wait_metric("isomesh_workers_busy", 1))
            workers = d.workers()
            t0 = time.time()
            rc = d.stop(timeout=30)
            self.assertEqual(rc, 0, d.log())
            self.assertLess(time.time() - t0, 20)
            t.join(30)
            if "result" in box:  # finished within the grace period, or stopped
                r = box["result"]
                self.assertIn(r.status, (200, 503, 504))
                if r.status == 200:
                    self.assertGreater(draco_counts(r.body)[1], 0)
                else:
                    self.assertIn(r.json()["error"]["code"], ("shutting_down", "deadline_exceeded"))
            for pid in workers:
                self.assertFalse(process_alive(pid), "worker %d outlived the daemon" % pid)
            self.assertIn("stopped", d.log())
        finally:
            d.cleanup()

    def test_workers_die_with_a_killed_daemon(self):
        with Daemon("--workers", "2") as d:
            pids = d.workers()
            self.assertEqual(len(pids), 2)
            d.proc.kill()  # SIGKILL: no clean-up code runs, PR_SET_PDEATHSIG must act
            d.proc.wait(timeout=10)
            deadline = time.time() + 10
            alive = pids
            while alive and time.time() < deadline:
                alive = [p for p in pids if process_alive(p)]
                time.sleep(0.02)
            self.assertEqual(alive, [], "workers outlived a SIGKILLed daemon")

    def skip_without_rlimit(self, d):
        if "job_memory_ignored" in d.log():
            self.skipTest("sanitizer build: workers run without RLIMIT_AS")

    def test_workers_run_under_the_memory_limit(self):
        with Daemon("--workers", "2", "--job-memory", "3G") as d:
            self.skip_without_rlimit(d)
            pids = d.workers()
            self.assertEqual(len(pids), 2)
            for pid in pids:
                with open("/proc/%d/limits" % pid) as f:
                    line = next(l for l in f if l.startswith("Max address space"))
                self.assertEqual(int(line.split()[3]), 3 << 30, line)
                with open("/proc/%d/cmdline" % pid, "rb") as f:
                    self.assertEqual(f.read().split(b"\0")[:2], [b"isomesh", b"--worker"])

    def test_a_worker_over_its_memory_limit_fails_its_job_not_the_daemon(self):
        # 128 MiB of address space is not enough for the gyroid at depth 10 (about 180 MB):
        # the job fails with an error answer (the polygoniser's budget is 3/4 of the limit, or
        # the worker dies), and the daemon keeps serving.
        with Daemon("--workers", "1", "--job-memory", "128M", "--job-timeout", "60s") as d:
            self.skip_without_rlimit(d)
            r = d.post("/v1/mesh", {"preset": "gyroid-ball", "depth": {"max": 10},
                                    "max_error": None})
            self.assertIn(r.status, (422, 500), r.body[:300])
            self.assertIn(r.json()["error"]["code"], ("no_memory", "too_big", "worker_crashed"))
            d.wait_ready()
            self.assertEqual(d.post("/v1/mesh", sphere(0.5)).status, 200)


    def test_a_bound_over_the_triangle_limit_is_refused_naming_the_limit_and_an_error_that_fits(self):
        # issue 15: a max_error that would need more triangles than the server's limit gets
        # 422 naming the limit and a max_error that fits, not a silently worse mesh. The sphere
        # preset takes 5016 triangles under E = 1e-3, 3660 under 2e-3, 1128 under 4e-3, 828
        # under 8e-3 (isomesh --surface sphere --stats): the smallest E that fits 1000 lies in
        # (4e-3, 8e-3]. The suggestion, sent back, is served; a quarter of it is not (so it is
        # within 4x of the smallest E that fits).
        with Daemon("--workers", "1", "--max-triangles", "1000") as d:
            # the preset's box and its placements off the lattice (tests/cli/boxes.py; the
            # finest cell at the safety depth the bound runs at, 10)
            for box in placements([-1.5] * 3 + [1.5] * 3, 3.0 / 2 ** 10):
                req = {"preset": "sphere", "max_error": 1e-3, "box": box}
                r = d.post("/v1/mesh", req)
                self.assertEqual(r.status, 422, r.body[:300])
                err = r.json()["error"]
                self.assertEqual(err["code"], "too_big")
                self.assertIn("1000 triangles", err["message"])
                self.assertNotIn("depth.max", err["message"])
                fit = err["max_error_that_fits"]
                self.assertIsInstance(fit, float)
                self.assertIn("max_error %s fits" % ("%.3g" % fit), err["message"])
                self.assertGreater(fit, 1e-3)
                # the answer is what openapi's Error documents, both ways: each field named
                # there (the new one as a number), and the new one named in it
                doc = ERROR_FIELDS
                self.assertEqual(sorted(k for k in err if k not in doc), [])
                self.assertEqual(doc["max_error_that_fits"]["type"], "number")
                self.assertEqual(d.post("/v1/mesh", dict(req, max_error=fit)).status, 200,
                                 (box, fit))
                r4 = d.post("/v1/mesh", dict(req, max_error=fit / 4))
                self.assertEqual(r4.status, 422, (box, fit, r4.body[:300]))
            # the depth path: no bound, so no E to suggest; depth.max is the knob
            r = d.post("/v1/mesh", {"preset": "sphere", "max_error": None, "depth": {"max": 8}})
            self.assertEqual(r.status, 422, r.body[:300])
            err = r.json()["error"]
            self.assertEqual(err["code"], "too_big")
            self.assertIn("lower depth.max", err["message"])
            self.assertNotIn("max_error_that_fits", err)

if __name__ == "__main__":
    unittest.main()
