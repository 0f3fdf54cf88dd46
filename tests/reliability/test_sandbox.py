"""test_sandbox.py — the worker's seccomp sandbox (server/isomesh/sandbox.h). Through
`isomesh --worker --sandbox-selftest WHAT`, which enters the very sandbox a worker enters and
then tries one thing: opening or creating a file fails with EACCES; a socket, exec, fork,
executable memory and writing to a descriptor the daemon did not hand over each kill the
process with SIGSYS after a line naming the refused call; threads, large allocations and the
clock work. The
daemon's workers run with the filter and no_new_privs, and every preset in every format is
computed under it without a worker dying."""
import glob
import os
import signal
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import ISOMESH, QUICK, Daemon, check_mesh, request  # noqa: E402

KILLED = {  # check -> the system call the sandbox must name as it kills the worker
    "socket": "socket",
    "exec": "execve",
    "fork": "clone",
    "exec-memory": "mmap",
    "write-fd": "write",
}
REFUSED = ("open", "create")  # fail with EACCES (glibc probes /proc and copes)
FORMATS = ("drc", "glb", "ply", "obj", "stl")


def selftest(what):
    return subprocess.run([ISOMESH, "--worker", "--sandbox-selftest", what],
                          stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=60)


def proc_status(pid):
    with open("/proc/%d/status" % pid) as f:
        return dict(line.rstrip("\n").split(":\t", 1) for line in f if ":\t" in line)


class SelftestTest(unittest.TestCase):
    def test_forbidden_calls_kill_the_worker_and_are_named(self):
        for what, call in KILLED.items():
            with self.subTest(what=what):
                r = selftest(what)
                self.assertIn("sandbox entered", r.stdout)  # it got as far as trying
                self.assertNotIn("SUCCEEDED", r.stdout)
                self.assertEqual(r.returncode, -signal.SIGSYS, r.stdout + r.stderr)
                self.assertIn("the sandbox refused system call", r.stderr)
                self.assertIn("(%s)" % call, r.stderr)

    def test_files_cannot_be_opened_or_created(self):
        for what in REFUSED:
            with self.subTest(what=what):
                before = set(glob.glob("/tmp/isomesh-sandbox-selftest.*"))
                r = selftest(what)
                self.assertIn("sandbox entered", r.stdout)
                self.assertIn("selftest %s: refused: Permission denied" % what, r.stdout)
                self.assertNotIn("SUCCEEDED", r.stdout)
                self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
                self.assertEqual(set(glob.glob("/tmp/isomesh-sandbox-selftest.*")), before)

    def test_what_the_pipeline_needs_still_works(self):
        r = selftest("allowed")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("threads, 128 MiB allocations, clock and stdout work", r.stdout)

    def test_unknown_check_is_refused(self):
        r = selftest("nothing-like-this")
        self.assertEqual(r.returncode, 2)
        self.assertIn("unknown check", r.stderr)


class DaemonWorkersTest(unittest.TestCase):
    def test_workers_run_filtered_without_new_privileges(self):
        with Daemon("--workers", "2") as d:
            self.assertTrue(d.wait_metric("isomesh_workers_ready", 2))  # past start-up
            pids = d.workers()
            self.assertEqual(len(pids), 2)
            for pid in pids:
                st = proc_status(pid)
                self.assertEqual(st["Seccomp"].strip(), "2", "worker %d is not filtered" % pid)
                self.assertEqual(st["NoNewPrivs"].strip(), "1")
            self.assertEqual(d.post("/v1/mesh", {"preset": "sphere"}).status, 200)

    def test_every_preset_in_every_format_under_the_filter(self):
        # One worker gets every core, so the polygoniser runs its threads. Each preset at depth
        # 5, computed once: the other four formats are written, in the sandboxed worker, from
        # the computed surface the daemon stored. Every preset at its full depth under the
        # filter is tests/http/test_gallery.py's run (same daemon, same sandbox, and it checks
        # no worker died); the large computation below is this test's own.
        with Daemon("--workers", "1", "--job-timeout", "600s") as d:
            presets = [p["name"] for p in d.get("/v1/presets").json()["presets"]]
            self.assertGreaterEqual(len(presets), 9)
            if QUICK:  # sanitizer build: the paper's and the classic surfaces (the first 9
                presets = presets[:9]  # cover every stage); the release run does all of them
            for name in presets:
                for fmt in FORMATS:
                    req = {"preset": name, "depth": {"max": 5}, "output": {"format": fmt}}
                    with self.subTest(preset=name, format=fmt):
                        status, _, body = request(d.port, "POST", "/v1/mesh", req, timeout=660)
                        self.assertEqual(status, 200, body[:300])
                        check_mesh(fmt, body)
            # a large computation: threads grow and trim their own heaps (glibc then probes
            # /proc/sys/vm/overcommit_memory, which the sandbox must refuse without killing)
            big = {"preset": "gyroid-ball", "depth": {"max": 8 if QUICK else 10},
                   "max_error": None}
            status, _, body = request(d.port, "POST", "/v1/mesh", big, timeout=660)
            self.assertEqual(status, 200, body[:300])
            check_mesh("drc", body)
            self.assertEqual(d.metric("isomesh_worker_restarts_total", reason="crash"), 0)
            self.assertNotIn("sandbox refused", d.log())
            self.assertEqual(d.stop(), 0)


if __name__ == "__main__":
    unittest.main()
