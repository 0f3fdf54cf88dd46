"""test_hostile.py — careless and hostile input against one isomeshd while another user keeps
asking for meshes. Each hostile request gets a clear 4xx (a JSON error with its code where the
daemon answers; libmicrohttpd's own 414/431 for request lines and headers it will not hold),
none of them starts a computation or kills a worker, and the other user sees only successes:
  * expression bombs: nesting of 100k and of 5k, x^1000000000, a million-node sum, 65 lets,
    non-finite and overflowing numbers, a box of zero, astronomical or vanishing size, depth
    beyond the limit;
  * bodies: a 1 GB Content-Length is refused (413) before a byte of it is sent, an endless
    chunked body is cut off after a bounded number of bytes, conflicting framing headers, an
    unknown Transfer-Encoding (501, not a wait for the client to close); six slow uploads of
    the largest size held open at once never hold more than --upload-memory (the ones beyond
    it get 503 with Retry-After when their body is complete), and the other user's small
    bodies are never refused meanwhile;
  * content types other than JSON (415); invalid and overlong UTF-8, NUL, duplicate keys,
    trailing garbage, 100k-deep JSON (400);
  * oversized URLs and headers;
  * path traversal in every form against a web root with a secret beside it and symlinks
    pointing out of it: .., %2e%2e, %2f, %252e, doubled slashes, backslashes, NUL, overlong
    UTF-8 — the secret is never served.
A 64-deep chain of lets that doubles at each step (2^64 nodes if expanded) is valid: it is
computed within the normal bounds while the other user is served."""
import json
import os
import shutil
import socket
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import (QUICK, Daemon, OtherUser, raw_answer, raw_status, read_answer,  # noqa: E402
                      request, wait_until)

SECRET = b"TOPSECRET-isomesh-hostile-test"
MAX_BODY = 1 << 20
UPLOAD_MEMORY = 4 * MAX_BODY  # bodies being received at once: four of the largest size fit
# (the first 16 KB of each body are not counted: http.c's UPLOAD_FREE)


def expr(e, **extra):
    return json.dumps(dict({"expr": e}, **extra)).encode()


# (name, body bytes, content type, expected status, expected error code)
BAD_BODIES = [
    ("nesting of 100k", expr("(" * 100000 + "x" + ")" * 100000), None, 422, "over_limit"),
    ("nesting of 5k", expr("(" * 5000 + "x" + ")" * 5000), None, 422, "over_limit"),
    ("x^1000000000", expr("x^1000000000 - 1"), None, 422, "over_limit"),
    ("x^-1000000000", expr("x^-1000000000 - 1"), None, 422, "over_limit"),
    ("a million-node sum", expr("+".join(["x"] * 400000)), None, 422, "too_large"),
    ("65 lets", json.dumps({"expr": "a64", "let": [["a%d" % i, "x + %d" % i]
                                                   for i in range(65)]}).encode(),
     None, 422, "over_limit"),
    ("NaN parameter", b'{"expr": "x - r", "params": {"r": NaN}}', None, 400, "bad_json"),
    ("Infinity parameter", b'{"expr": "x - r", "params": {"r": Infinity}}', None, 400,
     "bad_json"),
    ("overflowing number", b'{"expr": "x - r", "params": {"r": 1e400}}', None, 400, "bad_json"),
    ("-1e999 in the box", b'{"expr": "x", "box": [-1e999, 0, 0, 1, 1, 1]}', None, 400,
     "bad_json"),
    ("a box of zero size", expr("x", box=[0, 0, 0, 0, 0, 0]), None, 400, "bad_request"),
    ("an inverted box", expr("x", box=[1, 1, 1, -1, -1, -1]), None, 400, "bad_request"),
    ("an astronomical box", expr("x", box=[-1e300, -1e300, -1e300, 1e300, 1e300, 1e300]), None,
     422, "over_limit"),
    ("a vanishing box", expr("x", box=[0, 0, 0, 1e-300, 1e-300, 1e-300]), None, 422,
     "over_limit"),
    ("depth beyond the limit", expr("x", depth={"max": 11}), None, 422, "over_limit"),
    ("depth 99", expr("x", depth={"max": 99}), None, 422, "over_limit"),
    ("negative depth", expr("x", depth={"min": -1}), None, 422, "over_limit"),
    ("invalid UTF-8", b'{"expr": "x\xff\xfe"}', None, 400, "bad_json"),
    ("overlong UTF-8", b'{"expr": "x\xc0\xaf"}', None, 400, "bad_json"),
    ("UTF-16 surrogate in UTF-8", b'{"expr": "x\xed\xa0\x80"}', None, 400, "bad_json"),
    ("invalid UTF-8 in a key", b'{"ex\xffpr": "x"}', None, 400, "bad_json"),
    ("NUL in a string", b'{"expr": "x\\u0000 + 1"}', None, 400, "bad_json"),
    ("duplicate keys", b'{"expr": "x", "expr": "y"}', None, 400, "bad_json"),
    ("trailing garbage", b'{"expr": "x"} {"expr": "y"}', None, 400, "bad_json"),
    ("100k-deep JSON", b"[" * 100000 + b"]" * 100000, None, 400, "bad_json"),
    ("not an object", b'"x^2 + y^2 + z^2 - 1"', None, 400, "bad_json"),
    ("an array", b'[{"expr": "x"}]', None, 400, "bad_request"),
    ("unknown field", b'{"expr": "x", "shell": "rm -rf /"}', None, 400, "bad_request"),
    ("text/plain", b'{"expr": "x"}', "text/plain", 415, "unsupported_media_type"),
    ("application/xml", b'<expr>x</expr>', "application/xml", 415, "unsupported_media_type"),
    ("multipart", b'--b\r\n\r\n{"expr": "x"}\r\n--b--', "multipart/form-data; boundary=b", 415,
     "unsupported_media_type"),
]


def unread_by_daemon(port):
    """Bytes waiting in the receive queues of the daemon's established connections on port
    (Linux /proc/net/tcp{,6}: local address, state 01, rx_queue): 0 when the daemon has read
    everything its clients sent."""
    total = 0
    for name in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            with open(name) as f:
                rows = f.read().splitlines()[1:]
        except OSError:
            continue
        for row in rows:
            col = row.split()
            if col[3] == "01" and int(col[1].rsplit(":", 1)[1], 16) == port:
                total += int(col[4].split(":")[1], 16)
    return total


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


class HostileTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="isomesh_hostile_")
        web = os.path.join(cls.tmp, "web")
        write(os.path.join(web, "index.html"), b"<!doctype html><title>viewer</title>\n")
        write(os.path.join(web, "js", "app.js"), b"export const a = 1;\n")
        write(os.path.join(cls.tmp, "secret.txt"), SECRET + b"\n")
        write(os.path.join(web, "node_modules", "three", "build", "three.module.js"), b"//\n")
        os.symlink(os.path.join(cls.tmp, "secret.txt"), os.path.join(web, "leak.txt"))
        os.symlink(cls.tmp, os.path.join(web, "up"))
        os.symlink("/", os.path.join(web, "rootdir"))
        cls.d = Daemon("--workers", "2", "--max-body", str(MAX_BODY),
                       "--upload-memory", str(UPLOAD_MEMORY), web_root=web)
        try:
            cls.d.start()
        except Exception:
            cls.d.cleanup()
            shutil.rmtree(cls.tmp, ignore_errors=True)
            raise

    @classmethod
    def tearDownClass(cls):
        rc = cls.d.stop()
        cls.d.cleanup()
        shutil.rmtree(cls.tmp, ignore_errors=True)
        assert rc == 0, "isomeshd did not stop cleanly (exit %r)" % rc

    def under_attack(self):
        """The other user, asking for the same cached mesh (so that every computation the
        daemon starts meanwhile is the attacker's)."""
        other = OtherUser(self.d.port, tag=0.123, new_every=0)
        other.thread.start()
        self.assertTrue(other.wait_for(2))
        return other

    def assert_unharmed(self, other, started, restarts):
        n = len(other.results)
        self.assertTrue(other.wait_for(n + 3))
        other.stop()
        self.assertEqual(other.failures(), [])
        self.assertEqual(self.d.metric("isomesh_computations_started_total"), started,
                         "a hostile request reached a worker")
        self.assertEqual(self.d.metric("isomesh_worker_restarts_total", reason="crash"),
                         restarts)

    def baseline(self):
        return (self.d.metric("isomesh_computations_started_total"),
                self.d.metric("isomesh_worker_restarts_total", reason="crash"))

    def test_bad_bodies_get_clear_errors_without_computing(self):
        other = self.under_attack()
        started, restarts = self.baseline()
        for name, body, ctype, status, code in BAD_BODIES:
            for route in ("/v1/mesh", "/v1/jobs"):
                with self.subTest(name=name, route=route):
                    got, h, answer = request(self.d.port, "POST", route, body, timeout=30,
                                             headers={"Content-Type": ctype or "application/json"})
                    self.assertEqual(got, status, answer[:300])
                    self.assertEqual(h.get("content-type"), "application/json")
                    err = json.loads(answer)["error"]
                    self.assertEqual(err["code"], code, err)
                    self.assertTrue(err["message"])
        self.assert_unharmed(other, started, restarts)

    def test_a_huge_content_length_is_refused_before_the_body(self):
        other = self.under_attack()
        started, restarts = self.baseline()
        with socket.create_connection(("127.0.0.1", self.d.port), timeout=10) as s:
            s.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                      b"Content-Length: 1000000000\r\n\r\n")  # and not one byte of it
            answer = b""
            while b"\r\n\r\n" not in answer:
                chunk = s.recv(4096)
                if not chunk:
                    break
                answer += chunk
        self.assertTrue(answer.startswith(b"HTTP/1.1 413 "), answer[:200])
        self.assertIn(b"body_too_large", answer + b"")
        status = raw_status(self.d.port, b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\n"
                            b"Content-Type: application/json\r\nContent-Length: %d\r\n\r\n"
                            % (MAX_BODY + 1))
        self.assertEqual(status, 413)  # one byte over --max-body, again before the body
        for cl in (b"99999999999999999999999", b"-1", b"12abc"):
            status = raw_status(self.d.port, b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\n"
                                b"Content-Type: application/json\r\nContent-Length: " + cl +
                                b"\r\n\r\n")
            self.assertIn(status, (400, 413), cl)
        self.assert_unharmed(other, started, restarts)

    def test_an_endless_chunked_body_is_cut_off(self):
        other = self.under_attack()
        started, restarts = self.baseline()
        sent = 0
        limit = 64 << 20
        chunk = b"a" * 65536
        with socket.create_connection(("127.0.0.1", self.d.port), timeout=10) as s:
            s.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                      b"Transfer-Encoding: chunked\r\n\r\n")
            try:
                while sent < limit:
                    s.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
                    sent += len(chunk)
            except OSError:
                pass  # the daemon closed the connection
        self.assertLess(sent, limit, "the daemon read 64 MB of a body limited to 1 MB")
        self.assertLessEqual(sent, 16 * MAX_BODY)
        self.assert_unharmed(other, started, restarts)

    def test_conflicting_framing_headers(self):
        body = b'{"preset": "sphere"}'
        for extra in (b"Content-Length: %d\r\nContent-Length: 5\r\n" % len(body),
                      b"Content-Length: 5\r\nTransfer-Encoding: chunked\r\n"):
            data = (b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
                    b"Content-Type: application/json\r\n" + extra + b"\r\n" + body)
            self.assertEqual(raw_status(self.d.port, data), 400, extra)

    def test_an_unknown_transfer_encoding_is_not_implemented(self):
        body = b'{"preset": "sphere"}'
        for te in (b"gzip", b"gzip, chunked", b"chunked, gzip", b"identity", b"x"):
            data = (b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                    b"Transfer-Encoding: " + te + b"\r\n\r\n" + body)
            got, h, answer = raw_answer(self.d.port, data)
            self.assertEqual(got, 501, te)
            self.assertEqual(json.loads(answer)["error"]["code"], "not_implemented")
        chunked = (b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
                   b"Content-Type: application/json\r\nTransfer-Encoding: Chunked\r\n\r\n"
                   b"%x\r\n%s\r\n0\r\n\r\n" % (len(body), body))
        self.assertEqual(raw_status(self.d.port, chunked), 200)  # the one coding understood

    def test_slow_uploads_hold_at_most_the_upload_memory(self):
        other = self.under_attack()
        started, restarts = self.baseline()
        socks = []
        try:
            for _ in range(6):  # each sends all but the last byte of a largest-size body
                s = socket.create_connection(("127.0.0.1", self.d.port), timeout=30)
                s.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
                          b"Content-Type: application/json\r\nContent-Length: %d\r\n\r\n"
                          % MAX_BODY + b" " * (MAX_BODY - 1))
                socks.append(s)
            # the daemon has read them: four bodies' buffers (MAX_BODY + 1 bytes each, 16 KB
            # of them free) fit, six never do
            # ... every byte of them (not only the first three bodies: under load the last
            # two could still be unread when the first is finished below, and fit in the room
            # it leaves — ci12 at load 30 saw one 503)
            wait_until("the pending bodies read", lambda: self.d.metric(
                "isomesh_upload_bytes") >= 3 * MAX_BODY and unread_by_daemon(self.d.port) == 0)
            self.assertLessEqual(self.d.metric("isomesh_upload_bytes"), UPLOAD_MEMORY)
            answers = []
            for s in socks:
                s.sendall(b" ")
                answers.append(read_answer(s))
            statuses = sorted(a[0] for a in answers)
            self.assertGreaterEqual(statuses.count(503), 2, statuses)
            # the others were read whole and refused as requests (a body of blanks)
            self.assertTrue(all(st in (400, 422, 503) for st in statuses), statuses)
            for got, h, answer in answers:
                if got == 503:
                    self.assertEqual(json.loads(answer)["error"]["code"], "uploads_full")
                    self.assertIsNotNone(h.get("retry-after"))
        finally:
            for s in socks:
                s.close()
        wait_until("the bodies freed", lambda: self.d.metric("isomesh_upload_bytes") == 0)
        self.assert_unharmed(other, started, restarts)

    def test_oversized_urls_and_headers(self):
        other = self.under_attack()
        started, restarts = self.baseline()
        cases = [
            (b"GET /" + b"a" * 100000 + b" HTTP/1.1\r\nHost: x\r\n\r\n", (414,)),
            (b"GET /v1/meshes/" + b"f" * 60000 + b".drc HTTP/1.1\r\nHost: x\r\n\r\n", (404, 414)),
            (b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Big: " + b"a" * 100000 + b"\r\n\r\n", (431,)),
            (b"GET /healthz HTTP/1.1\r\nHost: x\r\n" +
             b"".join(b"X-H%d: v\r\n" % i for i in range(10000)) + b"\r\n", (431,)),
            (b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json; " +
             b"x=" * 50000 + b"\r\nContent-Length: 2\r\n\r\n{}", (431,)),
        ]
        for data, statuses in cases:
            self.assertIn(raw_status(self.d.port, data), statuses, data[:60])
        self.assertEqual(self.d.get("/healthz").status, 200)
        self.assert_unharmed(other, started, restarts)

    def test_path_traversal_never_reaches_outside_the_web_root(self):
        other = self.under_attack()
        started, restarts = self.baseline()
        attempts = [
            "/../secret.txt", "/js/../../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E/secret.txt",
            "/.%2e/secret.txt", "/%2e./secret.txt", "/js/%2e%2e/%2e%2e/secret.txt",
            "/..%2fsecret.txt", "/js%2f..%2f..%2fsecret.txt", "/%2f%2e%2e%2fsecret.txt",
            "/%252e%252e/secret.txt", "/%252e%252e%252fsecret.txt", "//secret.txt",
            "//../secret.txt", "/js//../../secret.txt", "/..\\secret.txt", "/%5c..%5csecret.txt",
            "/js\\..\\..\\secret.txt", "/..%00/secret.txt", "/index.html%00/../../secret.txt",
            "/%c0%ae%c0%ae/secret.txt", "/%c0%2e%c0%2e/secret.txt", "/%e0%80%ae%e0%80%ae/secret.txt",
            "/%c1%9c..%c1%9csecret.txt", "/leak.txt", "/up/secret.txt", "/up/web/index.html",
            "/rootdir/etc/passwd", "/rootdir/proc/self/environ", "/./secret.txt",
            "/js/./../../secret.txt", "/vendor/three/build/../../../../secret.txt",
            "/vendor/three/build/%2e%2e/%2e%2e/%2e%2e/%2e%2e/secret.txt",
            "/vendor/three/../../../secret.txt", "/v1/meshes/../../secret.txt",
            "/v1/meshes/%2e%2e%2f%2e%2e%2fsecret.txt", "/v1/../secret.txt",
            "/node_modules/three/build/three.module.js", "/%", "/%zz", "/%%32%65%%32%65/secret.txt",
        ]
        for path in attempts:
            with self.subTest(path=path):
                with socket.create_connection(("127.0.0.1", self.d.port), timeout=10) as s:
                    s.sendall(b"GET " + path.encode() + b" HTTP/1.1\r\nHost: x\r\n"
                              b"Connection: close\r\n\r\n")
                    answer = b""
                    while True:
                        chunk = s.recv(65536)
                        if not chunk:
                            break
                        answer += chunk
                self.assertNotIn(SECRET, answer)
                self.assertNotIn(b"root:", answer)
                self.assertRegex(answer[:12], rb"^HTTP/1\.1 (400|404)$")
        # a raw NUL byte in the request line: never the secret either
        with socket.create_connection(("127.0.0.1", self.d.port), timeout=10) as s:
            s.sendall(b"GET /..\x00/secret.txt HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
            answer = s.recv(65536)
        self.assertNotIn(SECRET, answer)
        self.assertEqual(self.d.get("/js/app.js").status, 200)  # the root still serves
        self.assert_unharmed(other, started, restarts)


class BoundedWorkTest(unittest.TestCase):
    def test_a_let_chain_that_would_explode_is_computed_within_bounds(self):
        chain = [["a0", "x*x + y*y + z*z - 0.5"]]
        chain += [["a%d" % i, "a%d * a%d + a%d" % (i - 1, i - 1, i - 1)] for i in range(1, 64)]
        req = {"expr": "a63", "let": chain, "depth": {"max": 5 if QUICK else 6}}
        with Daemon("--workers", "2", "--job-timeout", "60s") as d:
            with OtherUser(d.port, tag=0.2) as other:
                self.assertTrue(other.wait_for(2))
                status, _, body = request(d.port, "POST", "/v1/mesh", req, timeout=120)
                self.assertIn(status, (200, 422, 504), body[:300])
                n = len(other.results)
                self.assertTrue(other.wait_for(n + 3))
            self.assertEqual(other.failures(), [])
            self.assertEqual(d.metric("isomesh_worker_restarts_total", reason="crash"), 0)


if __name__ == "__main__":
    unittest.main()
