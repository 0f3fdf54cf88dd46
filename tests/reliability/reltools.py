"""reltools.py — helpers shared by the reliability tests (tests/reliability/test_*.py): the HTTP
harness of tests/http (a real isomeshd on a free port, always stopped), a background "other
user" who keeps asking for meshes while a test attacks the daemon and records every answer,
raw sockets, and checks that a served mesh decodes."""
import os
import socket
import struct
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "http"))
from harness import (BUILD, QUICK, ROOT, SLOW, Daemon, draco_counts, http_request,  # noqa: E402,F401
                     metric_key, parse_metrics, process_alive, sphere, wait_until)

ISOMESH = os.path.join(BUILD, "isomesh")

# Slow but resolvable work: the gyroid ball plus a tiny sum of 400 sines, so that every
# evaluation walks a tape of ~1,200 operations. At depth 10 it runs minutes of CPU on any
# machine, so it holds a worker until its deadline or its cancel. (A hopeless expression
# such as sin(1e300*x) + y is refused at once with 422 unresolvable since the daemon probes
# for it: it no longer pins a worker.)
_SINES = "+".join("sin(%d*x+y)" % i for i in range(1, 401))


def busy_work(k):
    """A request holding a worker for minutes; distinct k, distinct computations."""
    return {"expr": "max(sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x), "
                    "x^2 + y^2 + z^2 - 1.96) + 1e-9*(%s) + %g*1e-12" % (_SINES, k),
            "box": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5], "depth": {"max": 10}, "max_error": None}


def sanitizer_build(path):
    """True when the program at path was built with AddressSanitizer."""
    try:
        out = subprocess.run(["nm", "-D", "--defined-only", path], stdout=subprocess.PIPE,
                             stderr=subprocess.DEVNULL, timeout=30).stdout
        out += subprocess.run(["nm", "-D", "--undefined-only", path], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, timeout=30).stdout
    except (OSError, subprocess.TimeoutExpired):
        return False
    return b"__asan_init" in out


def server_closed(s):
    """True when the server closed (or reset) the non-blocking socket s; False while it is
    open with nothing to read."""
    try:
        return s.recv(4096) == b""
    except BlockingIOError:
        return False
    except OSError:
        return True


def read_answer(s):
    """(status, headers with lower-case names, body) of one answer read from socket s (framed
    by its Content-Length, else read until the server closes); status None when the server
    closed without one."""
    got = b""
    while b"\r\n\r\n" not in got:
        chunk = s.recv(65536)
        if not chunk:
            return None, {}, b""
        got += chunk
    head, body = got.split(b"\r\n\r\n", 1)
    lines = head.decode("latin-1").split("\r\n")
    headers = {}
    for line in lines[1:]:
        name, _, value = line.partition(":")
        headers[name.strip().lower()] = value.strip()
    size = int(headers.get("content-length", -1))
    while size < 0 or len(body) < size:
        chunk = s.recv(65536)
        if not chunk:
            break
        body += chunk
    return int(lines[0][9:12]), headers, body


def raw_answer(port, data, timeout=30):
    """Sends raw bytes on a new connection and reads one answer (read_answer)."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(data)
        return read_answer(s)


def raw_status(port, data, timeout=10):
    """Sends raw bytes on a new connection; the status code of the answer, or None when the
    server closed without one."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(data)
        got = b""
        while b"\r\n" not in got:
            try:
                chunk = s.recv(4096)
            except ConnectionResetError:
                break
            if not chunk:
                break
            got += chunk
    if got.startswith(b"HTTP/1.") and len(got) >= 12:
        return int(got[9:12])
    return None


def request(port, method, path, body=None, headers=None, timeout=60):
    """One request on its own connection -> (status, headers dict lowercased, body bytes)."""
    r = http_request(port, method, path, body, headers, timeout)
    return r.status, {k.lower(): v for k, v in r.headers}, r.body


class OtherUser:
    """Another user of the daemon: a thread that keeps asking for small meshes (a cached one
    and, every few requests, a new one) until stopped, recording each answer. A test attacks
    the daemon meanwhile and then checks that this user saw only successes."""

    def __init__(self, port, tag=0.0, new_every=4, pause=0.02):
        self.port = port
        self.tag = tag
        self.new_every = new_every
        self.pause = pause
        self.results = []          # (status, error text or None)
        self.stop_flag = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop()

    def _run(self):
        i = 0
        while not self.stop_flag.is_set():
            i += 1
            fresh = self.new_every and i % self.new_every == 0
            r = 0.5 + self.tag + (i / 1e5 if fresh else 0.0)
            try:
                status, _, body = request(self.port, "POST", "/v1/mesh", sphere(round(r, 6)),
                                          timeout=120)
                ok = status == 200 and draco_counts(body)[1] > 0
                self.results.append((status, None if ok else body[:200]))
            except Exception as e:  # recorded, judged by the test
                self.results.append((None, repr(e)))
            self.stop_flag.wait(self.pause)

    def stop(self):
        self.stop_flag.set()
        self.thread.join(180)

    def failures(self):
        return [r for r in self.results if r[0] != 200 or r[1] is not None]

    def wait_for(self, n, timeout=120):
        """Waits until at least n answers arrived (bounded)."""
        deadline = time.time() + timeout
        while len(self.results) < n and time.time() < deadline:
            time.sleep(0.02)
        return len(self.results) >= n


def check_mesh(fmt, body):
    """Raises AssertionError unless body is a well-formed, non-empty mesh file of fmt."""
    if fmt == "drc":
        verts, faces = draco_counts(body)
        assert verts > 0 and faces > 0, "empty Draco mesh"
    elif fmt == "glb":
        assert body[:4] == b"glTF", "not glb"
        (length,) = struct.unpack("<I", body[8:12])
        assert length == len(body), "glb length %d != %d" % (length, len(body))
    elif fmt == "ply":
        assert body.startswith(b"ply\n"), "not ply"
        head = body[:body.index(b"end_header")]
        assert b"element vertex 0\n" not in head
    elif fmt == "obj":
        assert b"\nv " in body or body.startswith(b"v "), "obj without vertices"
        assert b"\nf " in body, "obj without faces"
    elif fmt == "stl":
        (n,) = struct.unpack("<I", body[80:84])
        assert n > 0 and len(body) == 84 + 50 * n, "stl size does not match its count"
    else:
        raise AssertionError("unknown format " + fmt)
