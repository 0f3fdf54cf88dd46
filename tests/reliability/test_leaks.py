"""test_leaks.py — no memory leak in isomeshd. The daemon runs through a realistic mix of
requests (new meshes and cache hits in every format, stats, features, revalidation, jobs
polled, streamed and cancelled, clients that leave mid-computation, a worker killed
mid-job, every client error, static files, documents, metrics), is stopped with SIGTERM while
a computation still runs, and its leak report must be clean:
  * against an AddressSanitizer build (ISOMESH_BUILD=build/asan) LeakSanitizer checks at exit;
  * against a release build the daemon runs under valgrind --leak-check=full.
Workers are not checked here: they end with _exit inside their sandbox (the unit and CLI
suites cover the pipeline's memory)."""
import json
import os
import re
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import (QUICK, SLOW, Daemon, check_mesh, request,  # noqa: E402
                      sanitizer_build, sphere)
from harness import ISOMESHD  # noqa: E402

ORIGIN = "https://viewer.example"


def slow(i):
    """SLOW with a distinct cache key (a tolerance no one else asks for)."""
    return dict(SLOW, tolerances={"gradient": 0.9 + i / 1e4})


def run_mix(t, d):
    """The request mix; t is the TestCase (assertions), d the running daemon."""
    port = d.port
    keys = []
    for i in range(4 if QUICK else 8):
        status, h, body = request(port, "POST", "/v1/mesh", sphere(0.6 + i / 100))
        t.assertEqual(status, 200)
        keys.append(h["etag"].strip('"'))
        status, h, _ = request(port, "POST", "/v1/mesh", sphere(0.6 + i / 100))  # memory hit
        t.assertEqual(h["x-cache"], "hit")
    key = keys[0]
    for fmt in ("drc", "glb", "ply", "obj", "stl"):
        status, h, body = request(port, "GET", "/v1/meshes/%s.%s" % (key, fmt))
        t.assertEqual(status, 200)
        check_mesh(fmt, body)
        status, _, _ = request(port, "GET", "/v1/meshes/%s.%s" % (key, fmt),
                               headers={"If-None-Match": h["etag"]})
        t.assertEqual(status, 304)
        t.assertEqual(request(port, "HEAD", "/v1/meshes/%s.%s" % (key, fmt))[0], 200)
    for what in ("stats", "features"):
        t.assertEqual(request(port, "GET", "/v1/meshes/%s/%s" % (key, what))[0], 200)
    # jobs: polled to the end, streamed, cancelled while running, listed
    job = json.loads(request(port, "POST", "/v1/jobs", sphere(0.71))[2])
    deadline = time.time() + 60
    while time.time() < deadline:
        j = json.loads(request(port, "GET", job["url"])[2])
        if j["state"] not in ("queued", "running"):
            break
        time.sleep(0.02)
    t.assertEqual(j["state"], "done")
    job = json.loads(request(port, "POST", "/v1/jobs", {"preset": "torus"})[2])
    status, _, text = request(port, "GET", job["events_url"], timeout=120)
    t.assertIn(b"event: done", text)
    running = json.loads(request(port, "POST", "/v1/jobs", slow(1))[2])
    t.assertTrue(d.wait_metric("isomesh_workers_busy", 1))
    t.assertEqual(json.loads(request(port, "DELETE", running["url"])[2])["state"], "canceled")
    t.assertEqual(request(port, "GET", "/v1/jobs")[0], 200)
    d.wait_ready()
    # a client that leaves while its computation runs, and one that leaves mid-upload
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        body = json.dumps({"preset": "gyroid-ball", "depth": {"max": 8},
                           "max_error": None}).encode()
        s.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: %d\r\n\r\n%s" % (len(body), body))
        t.assertTrue(d.wait_metric("isomesh_suspended_connections", 1))
    # its leaving is noticed (a peek a second) and its computation stopped: else the worker
    # killed below could be this one's, and the next request would run its depth-10 gyroid
    # to the job deadline (30 s of CPU under the sanitizer)
    t.assertTrue(d.wait_metric("isomesh_clients_left_total", 1))
    d.wait_idle()
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 1000\r\n\r\n{\"expr\": ")
    # a worker killed mid-job: its request gets a 500, the next one succeeds
    box = {}
    started = d.metric("isomesh_computations_started_total")
    th = threading.Thread(target=lambda: box.update(r=request(port, "POST", "/v1/mesh",
                                                              slow(2), timeout=120)))
    th.start()
    t.assertTrue(d.wait_metric("isomesh_computations_started_total", started + 1))
    time.sleep(0.2)
    for pid in d.workers():
        os.kill(pid, signal.SIGKILL)
    th.join(120)
    # 500: the worker died under it (a depth-10 gyroid does not finish in 0.2 s)
    t.assertEqual(box["r"][0], 500)
    d.wait_ready()
    # every client error
    t.assertEqual(request(port, "POST", "/v1/mesh", b"{bad json")[0], 400)
    t.assertEqual(request(port, "POST", "/v1/mesh", {"expr": "x^1000000000"})[0], 422)
    t.assertEqual(request(port, "POST", "/v1/mesh", {"expr": "x", "depth": {"max": 99}})[0], 422)
    t.assertEqual(request(port, "POST", "/v1/mesh", b"x" * 70000)[0], 413)
    t.assertEqual(request(port, "POST", "/v1/mesh", b"{}", {"Content-Type": "text/plain"})[0], 415)
    t.assertEqual(request(port, "DELETE", "/v1/mesh")[0], 405)
    t.assertEqual(request(port, "GET", "/v1/meshes/" + "0" * 64 + ".drc")[0], 404)
    t.assertEqual(request(port, "GET", "/nothing/here")[0], 404)
    t.assertEqual(request(port, "GET", "/../../etc/passwd")[0], 404)
    t.assertEqual(request(port, "OPTIONS", "/v1/mesh", headers={"Origin": ORIGIN})[0], 204)
    # static files, documents, health, metrics
    d.wait_ready()
    for path in ("/", "/v1/presets", "/v1/openapi.yaml", "/v1/request.schema.json",
                 "/healthz", "/metrics"):
        t.assertEqual(request(port, "GET", path)[0], 200, path)
    # still computing when SIGTERM comes (once the daemon has started this computation)
    started = d.metric("isomesh_computations_started_total")
    def last():
        try:
            box["last"] = request(port, "POST", "/v1/mesh", slow(3), timeout=120)
        except OSError as e:
            box["last_error"] = repr(e)
    th = threading.Thread(target=last, daemon=True)
    th.start()
    t.assertTrue(d.wait_metric("isomesh_computations_started_total", started + 1))
    # held, not computing, through the stop's grace period: the answer is the same 503, and
    # the sanitizer build does not spend that period's CPU on a mesh nobody keeps
    for pid in d.workers():
        os.kill(pid, signal.SIGSTOP)
    return th, box


def check_last_answer(t, th, box, story=""):
    """The computation running at SIGTERM was answered: finished in the grace period, or 503."""
    th.join(60)
    t.assertIn("last", box, "the request running at SIGTERM got no answer: %s"
               % box.get("last_error"))
    t.assertIn(box["last"][0], (200, 503), "%r\n%s" % (box["last"][2][:400], story))


class LeakTest(unittest.TestCase):
    def test_request_mix_then_sigterm_leaves_no_leak(self):
        tmp = tempfile.mkdtemp(prefix="isomesh_leaks_")
        try:
            if sanitizer_build(ISOMESHD):
                self.check_with_leak_sanitizer()
            elif shutil.which("valgrind"):
                self.check_with_valgrind(tmp)
            else:
                self.skipTest("neither a sanitizer build nor valgrind")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)

    def daemon_args(self):
        return ("--workers", "2", "--job-timeout", "30s", "--max-body", "64K",
                "--cors-origin", ORIGIN)

    def check_with_leak_sanitizer(self):
        env = dict(os.environ)
        # the report on stderr (not a log_path file), so this test reads it itself
        env["ASAN_OPTIONS"] = "detect_leaks=1:abort_on_error=0:exitcode=23"
        d = Daemon(*self.daemon_args(), env=env)
        try:
            d.start()
            th, box = run_mix(self, d)
            rc = d.stop(timeout=60)
            log = d.log()
            check_last_answer(self, th, box, d.story(80))
        finally:
            d.cleanup()
        self.assertNotIn("LeakSanitizer", log)
        self.assertNotIn("ERROR: AddressSanitizer", log)
        self.assertEqual(rc, 0, log[-3000:])
        self.assertIn("clean shutdown", log)

    def check_with_valgrind(self, tmp):
        vlog = os.path.join(tmp, "valgrind.log")
        prefix = ["valgrind", "--leak-check=full", "--num-callers=30", "--show-leak-kinds=definite,indirect,possible",
                  "--errors-for-leak-kinds=definite,indirect,possible", "--error-exitcode=99",
                  "--trace-children=no", "--log-file=" + vlog]
        d = Daemon(*self.daemon_args(), prefix=prefix)
        try:
            d.start(timeout=120)
            th, box = run_mix(self, d)
            rc = d.stop(timeout=120)
            log = d.log()
            check_last_answer(self, th, box, d.story(80))
        finally:
            d.cleanup()
        with open(vlog) as f:
            report = f.read()
        self.assertIn("LEAK SUMMARY", report, report[-3000:])
        losses = "\n".join(b for b in report.split("\n==") if " lost in loss record " in b)
        for kind in ("definitely lost", "indirectly lost", "possibly lost"):
            m = re.search(kind + r": ([\d,]+) bytes", report)
            self.assertTrue(m, kind)
            self.assertEqual(m.group(1), "0", losses[:6000] or report[-4000:])
        self.assertRegex(report, r"ERROR SUMMARY: 0 errors")
        self.assertEqual(rc, 0, log[-3000:])
        self.assertIn("clean shutdown", log)


if __name__ == "__main__":
    unittest.main()
