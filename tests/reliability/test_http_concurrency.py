"""test_http_concurrency.py — the HTTP front under concurrency, asserted as properties (its
speed is measured beside nginx by tests/bench/bench_http.py, never here):

1. 256 connections opened at once (a burst past the 128 events one epoll_wait returns, which
   stalled libmicrohttpd's epoll loop), each fetching a cached mesh three times over
   keep-alive: every answer is 200 and byte for byte what the `isomesh` command writes for
   the same request (a second program, not the daemon's own earlier answer).
2. 300 slow readers hold connections in the middle of a 1.3 MB answer (they read nothing):
   /healthz still answers, another client still gets its mesh intact, none of the readers'
   answers has been handed whole to the kernel (each connection may queue only 256 KB unsent
   there; before that bound the kernel took all 300 answers, ~1.3 MB each, at once), and a
   reader that starts reading gets its whole answer, byte for byte.

Both end with a clean exit (status 0, no sanitizer report: run them against build/asan too).
Timeouts are generous bounds against hanging, not speed goals."""
import http.client
import os
import socket
import subprocess
import sys
import tempfile
import threading
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import ISOMESH, QUICK, Daemon, request  # noqa: E402

REQ = {"preset": "sphere", "depth": {"max": 8}}  # 47 KB of Draco, 1.3 MB as OBJ
BURST = 256
ROUNDS = 3
SLOW_READERS = 150 if QUICK else 300
READER_RCVBUF = 16 << 10  # a small window: most of each answer stays with the server
BOUND_S = 60  # per request: far beyond any normal answer, short of a hung test


def command_output(fmt):
    """The mesh the `isomesh` command writes for REQ in format fmt."""
    with tempfile.TemporaryDirectory() as d:
        src, dst = os.path.join(d, "req.json"), os.path.join(d, "out." + fmt)
        with open(src, "w") as f:
            f.write('{"preset": "sphere", "depth": {"max": 8}}')
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


def read_answer(s):
    """The body of the one answer on s (Content-Length framing)."""
    data = b""
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


class HttpConcurrencyTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.drc = command_output("drc")
        cls.obj = command_output("obj")

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
            key = headers["etag"].strip('"')
            obj_path, drc_path = "/v1/meshes/%s.obj" % key, "/v1/meshes/%s.drc" % key
            status, _, body = request(d.port, "GET", obj_path, timeout=120)  # cached now
            self.assertEqual((status, body), (200, self.obj))
            readers = []
            try:
                for _ in range(SLOW_READERS):
                    readers.append(open_reader(d.port, obj_path))
                for _ in range(5):
                    self.assertEqual(request(d.port, "GET", "/healthz", timeout=BOUND_S)[0], 200)
                    status, _, body = request(d.port, "GET", drc_path, timeout=BOUND_S)
                    self.assertEqual((status, body), (200, self.drc))
                # the readers' answers are still being sent: nothing of theirs completed
                self.assertEqual(d.metric("isomesh_http_requests_total",
                                          route="/v1/meshes/{key}.{format}", status="200"), 6)
                self.assertEqual(read_answer(readers[0]), self.obj)
                self.assertEqual(read_answer(readers[-1]), self.obj)
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
