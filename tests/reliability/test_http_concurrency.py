"""test_http_concurrency.py — the HTTP front under concurrency, asserted as properties (its
speed is measured beside nginx by tests/bench/bench_http.py, never here):

1. 256 connections opened at once (a burst past the 128 events one epoll_wait returns, which
   stalled libmicrohttpd's epoll loop), each fetching a cached mesh three times over
   keep-alive: every answer is 200 and byte for byte what the `isomesh` command writes for
   the same request (a second program, not the daemon's own earlier answer).
2. 450 slow readers (issue 17) in the middle of an 8.3 MB answer each, reading 16 KB per
   0.2 s, while a probe in its own process asks for /healthz on fresh connections: /healthz
   never waits behind the readers — its p99 from their first connection on is at most
   100 ms more than 8x its p99 just before they came, in the same run (so the bound is the
   issue's 100 ms on an idle machine and scales with what a loaded one does to /healthz
   alone). The readers come within a second or two of their mesh's store, as right after a
   computation. One polling thread without the kernel bound below fails it (0.9-1.3 s against
   9-16 ms before the readers). Another client still gets its mesh intact, none of the
   readers' answers has been handed whole to the kernel (each connection may queue only
   256 KB unsent there; before that bound the kernel took up to 4 MB of each, 1.8 GB in
   all), and a reader that reads on gets its whole answer, byte for byte what a client
   reading at once got.

Both end with a clean exit (status 0, no sanitizer report: run them against build/asan too).
Timeouts are generous bounds against hanging, not speed goals."""
import http.client
import json
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import ISOMESH, Daemon, check_mesh, request  # noqa: E402

REQ = {"preset": "sphere", "depth": {"max": 8}, "max_error": None}  # 47 KB of Draco
# The slow readers' mesh: 8.3 MB as OBJ (issue 17 had 7 MB), more than the kernel's largest
# send buffer (tcp_wmem, 4 MB) takes for one connection, so its sending is never over at once.
BIG_REQ = {"preset": "gyroid-ball", "depth": {"max": 7}, "max_error": None}
BURST = 256
ROUNDS = 3
SLOW_READERS = 450  # issue 17's count
READER_RCVBUF = 16 << 10  # a small window: most of each answer stays with the server
TRICKLE_BYTES = 16 << 10  # what each reader takes per pass ...
TRICKLE_PAUSE_S = 0.2     # ... once per this: ~80 KB/s each, 36 MB/s in all
BEFORE_S = 1.0            # /healthz alone, before the readers come
READING_S = 1.5           # /healthz beside the readers reading (after they all connected)
# Issue 17: /healthz p99 under 100 ms beside the readers. It was 155-251 ms in 5 of 10 idle
# runs (2026-11-26) because the readers came within 2 s of their mesh's store: its cache file
# could not be remembered as checked yet, so every GET compared the whole 8.3 MB file with
# the daemon's bytes on a polling thread (fixed: such a file is not sent from, file_memo.h).
# What the bound guards: that compare (each polling thread 130-280 ms per pass), one polling
# thread stuck copying for the readers (0.9-1.3 s), the daemon (1.7-10.7 s).
HEALTHZ_P99_MS = 100
# How much worse than /healthz alone a loaded machine may make it beside the readers: they
# cost some CPU themselves (450 connections, 36 MB/s); one polling thread stuck copying for
# them made it 60-150x worse (0.9-1.3 s beside them against 9-16 ms before, load ~22).
LOAD_FACTOR = 8
PROBE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "probe_latency.py")
BOUND_S = 60  # per request: far beyond any normal answer, short of a hung test


def command_output(req, fmt):
    """The mesh the `isomesh` command writes for req in format fmt."""
    with tempfile.TemporaryDirectory() as d:
        src, dst = os.path.join(d, "req.json"), os.path.join(d, "out." + fmt)
        with open(src, "w") as f:
            json.dump(req, f)
        subprocess.run([ISOMESH, src, "-o", dst], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, timeout=120)
        with open(dst, "rb") as f:
            return f.read()


def fetch_rounds(port, path, want, start, errors):
    """ROUNDS GETs of path on one keep-alive connection; appends what went wrong."""
    try:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=BOUND_S)
        start.wait(BOUND_S)
        for _ in range(ROUNDS):
            conn.request("GET", path)
            r = conn.getresponse()
            body = r.read()
            if r.status != 200 or body != want:
                errors.append((r.status, len(body)))
        conn.close()
    except Exception as e:  # judged by the test
        errors.append(repr(e))


def open_reader(port, path):
    """A connection that asked for path and reads nothing yet."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, READER_RCVBUF)
    s.settimeout(BOUND_S)
    s.connect(("127.0.0.1", port))
    s.sendall(b"GET " + path.encode() + b" HTTP/1.1\r\nHost: x\r\n\r\n")
    return s


def read_answer(s, data=b""):
    """The body of the one answer on s (Content-Length framing), data its bytes read already."""
    while b"\r\n\r\n" not in data:
        chunk = s.recv(65536)
        if not chunk:
            raise AssertionError("closed before the headers")
        data += chunk
    head, body = data.split(b"\r\n\r\n", 1)
    assert head.startswith(b"HTTP/1.1 200"), head[:80]
    length = [int(line.split(b":")[1]) for line in head.split(b"\r\n")
              if line.lower().startswith(b"content-length:")][0]
    while len(body) < length:
        chunk = s.recv(1 << 20)
        if not chunk:
            break
        body += chunk
    return body


def percentile(values, q):
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))]


def trickle(readers, kept, until):
    """Until time.monotonic() reaches until, each reader takes TRICKLE_BYTES every
    TRICKLE_PAUSE_S (kept[i] collects reader i's bytes, for the readers kept names).
    Returns the bytes read."""
    got = 0
    while time.monotonic() < until:
        for i, s in enumerate(readers):
            try:
                chunk = s.recv(TRICKLE_BYTES, socket.MSG_DONTWAIT)
            except BlockingIOError:
                continue
            got += len(chunk)
            if i in kept:
                kept[i] += chunk
        time.sleep(max(0, min(TRICKLE_PAUSE_S, until - time.monotonic())))
    return got


def healthz_beside_readers(port, path, readers, kept):
    """/healthz latencies (ms) from a probe process for BEFORE_S, then while SLOW_READERS
    readers of path connect (appended to readers) and read for READING_S:
    (before, beside, bytes the readers read)."""
    probe = subprocess.Popen([sys.executable, PROBE, str(port), "/healthz"],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        first = json.loads(probe.stdout.readline())  # the probe runs: its first sample
        time.sleep(BEFORE_S)
        came = time.monotonic()
        for _ in range(SLOW_READERS):
            readers.append(open_reader(port, path))
        got = trickle(readers, kept, time.monotonic() + READING_S)
        samples = json.loads(probe.communicate("", timeout=BOUND_S)[0])
    finally:
        if probe.poll() is None:
            probe.kill()
            probe.wait()
    before, beside = [], []
    for start, seconds, ok in [first] + samples:
        assert ok, "/healthz was not answered 200"
        (before if start < came else beside).append(seconds * 1e3)
    return before, beside, got


class HttpConcurrencyTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.drc = command_output(REQ, "drc")

    def test_a_burst_of_connections_all_get_the_right_bytes(self):
        with Daemon("--workers", "1") as d:
            status, headers, body = request(d.port, "POST", "/v1/mesh", REQ, timeout=120)
            self.assertEqual((status, body), (200, self.drc))
            path = "/v1/meshes/%s.drc" % headers["etag"].strip('"')
            start, errors = threading.Event(), []
            threads = [threading.Thread(target=fetch_rounds,
                                        args=(d.port, path, self.drc, start, errors))
                       for _ in range(BURST)]
            for t in threads:
                t.start()
            start.set()
            for t in threads:
                t.join(BOUND_S * (ROUNDS + 1))
            self.assertFalse(any(t.is_alive() for t in threads), "a client hung")
            self.assertEqual(errors, [])
            served = d.metric("isomesh_http_requests_total", route="/v1/meshes/{key}.{format}",
                              status="200")
            self.assertEqual(served, BURST * ROUNDS)
            self.assert_clean_exit(d)

    def test_slow_readers_hold_up_no_one(self):
        with Daemon("--workers", "1") as d:
            status, headers, _ = request(d.port, "POST", "/v1/mesh", REQ, timeout=120)
            self.assertEqual(status, 200)
            drc_path = "/v1/meshes/%s.drc" % headers["etag"].strip('"')
            status, headers, _ = request(d.port, "POST", "/v1/mesh", BIG_REQ, timeout=120)
            self.assertEqual(status, 200)
            obj_path = "/v1/meshes/%s.obj" % headers["etag"].strip('"')
            status, _, obj = request(d.port, "GET", obj_path, timeout=120)  # cached now
            self.assertEqual(status, 200)
            check_mesh("obj", obj)
            readers = []
            try:
                kept = {0: b"", SLOW_READERS - 1: b""}
                before, beside, got = healthz_beside_readers(d.port, obj_path, readers, kept)
                # the readers did read: each pass takes up to TRICKLE_BYTES from each of them
                self.assertGreater(got, SLOW_READERS * TRICKLE_BYTES)
                self.assertTrue(before and beside, (len(before), len(beside)))
                b99, r99 = percentile(before, 0.99), percentile(beside, 0.99)
                self.assertLessEqual(r99, HEALTHZ_P99_MS + LOAD_FACTOR * b99,
                                     "/healthz p99 %.1f ms beside %d slow readers (n=%d), "
                                     "%.1f ms before them (n=%d)"
                                     % (r99, SLOW_READERS, len(beside), b99, len(before)))
                for _ in range(5):
                    self.assertEqual(request(d.port, "GET", "/healthz", timeout=BOUND_S)[0], 200)
                    status, _, body = request(d.port, "GET", drc_path, timeout=BOUND_S)
                    self.assertEqual((status, body), (200, self.drc))
                # every reader's request is answered (counted when its answer is queued) but
                # none has ended (a duration is observed when the answer has left): the
                # route's 6 ends are the first .obj and the five .drc. Each .drc's log line
                # follows its duration, and an end may trail its bytes: await their lines
                route = "/v1/meshes/{key}.{format}"
                self.assertTrue(d.wait_metric("isomesh_http_requests_total", 6 + SLOW_READERS,
                                              timeout=BOUND_S, route=route, status="200"))
                self.assertEqual(d.metric("isomesh_http_requests_total", route=route,
                                          status="200"), 6 + SLOW_READERS)
                self.assertEqual(d.log_count("path=%s " % drc_path, 5, timeout=BOUND_S), 5)
                self.assertEqual(d.metric("isomesh_http_request_duration_seconds_count",
                                          route=route), 6)
                for i, data in kept.items():
                    readers[i].settimeout(BOUND_S)  # blocking again, and a wider window:
                    readers[i].setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
                    self.assertEqual(read_answer(readers[i], data), obj)
            finally:
                for s in readers:
                    s.close()
            self.assert_clean_exit(d)

    def assert_clean_exit(self, d):
        """SIGTERM ends the daemon with status 0 and no sanitizer report (ASan builds)."""
        self.assertEqual(d.stop(), 0)
        log = d.log()
        self.assertNotIn("ERROR: AddressSanitizer", log)
        self.assertNotIn("runtime error:", log)


if __name__ == "__main__":
    unittest.main()
