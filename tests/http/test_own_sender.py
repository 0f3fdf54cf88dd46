"""test_own_sender.py — isomeshd --own-sender (server/common/http_front.c,
server/isomeshd/own_sender.c): a cached mesh GET is answered by the daemon's own sender (header
block held back, then sendfile) with the same header block libmicrohttpd writes for it (Date and
the Server-Timing durations aside) and the same body; several requests on one connection, also
pipelined, are answered in order, and one the own sender does not take (HEAD, If-None-Match, an
unknown header) hands the connection to libmicrohttpd mid-stream without losing a byte; a reader
that stops reading holds up nobody and is closed after --conn-timeout, also when it keeps sending
bytes; an idle connection goes to libmicrohttpd's connection table."""
import email.utils
import os
import re
import socket
import sys
import tempfile
import shutil
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Daemon, http_request, parse_metrics, sphere, wait_until  # noqa: E402

SENT = "isomesh_sendfile_responses_total"  # the own sender's answers count here
BIG = {"preset": "gyroid-ball", "depth": {"max": 6}, "output": {"format": "stl"}}  # 2.9 MB


def read_answer(s, buf, head_only=False):
    """One answer from socket s (buf: bytes already read) -> (status, header block, body, rest)."""
    while b"\r\n\r\n" not in buf:
        more = s.recv(65536)
        if not more:
            raise AssertionError("connection closed mid-answer: %r" % buf[:200])
        buf += more
    head, _, buf = buf.partition(b"\r\n\r\n")
    status = int(head.split(b" ", 2)[1])
    m = re.search(rb"\r\ncontent-length: *(\d+)", head, re.I)
    n = 0 if head_only or status == 304 or not m else int(m.group(1))
    while len(buf) < n:
        more = s.recv(1 << 20)
        if not more:
            raise AssertionError("connection closed mid-body")
        buf += more
    return status, head, buf[:n], buf[n:]


def strip_varying(head):
    return re.sub(rb"Date: [^\r]*|dur=[0-9.]+", b"", head)


class OwnSenderTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="isomeshd_own_")
        cls.d = Daemon("--workers", "1", "--own-sender", "--conn-timeout", "3",
                       "--cors-origin", "https://viewer.example",
                       cache_dir=os.path.join(cls.tmp, "cache")).start()
        first = cls.d.post("/v1/mesh", sphere(0.77))
        assert first.status == 200, first.body[:200]
        cls.body = first.body
        cls.key = first.header("ETag").strip('"')
        cls.path = "/v1/meshes/%s.drc" % cls.key
        cls.get = b"GET %s HTTP/1.1\r\nHost: t\r\n\r\n" % cls.path.encode()

        def by_own_sender():  # once the cache file has settled (file_memo.h)
            before = cls.d.metric(SENT)
            s = socket.create_connection(("127.0.0.1", cls.d.port), timeout=30)
            s.sendall(cls.get)
            read_answer(s, b"")
            s.close()
            return cls.d.metric(SENT) == before + 1
        wait_until("an answer by the own sender", by_own_sender)

    @classmethod
    def tearDownClass(cls):
        cls.d.stop()
        cls.d.cleanup()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def connect(self):
        return socket.create_connection(("127.0.0.1", self.d.port), timeout=30)

    def test_header_block_and_body_are_libmicrohttpds(self):
        s = socket.create_connection(("127.0.0.1", self.d.port), timeout=30,
                                     source_address=("127.0.0.3", 0))
        before = self.d.metric(SENT)
        s.sendall(self.get)
        status, own_head, own_body, rest = read_answer(s, b"")
        self.assertEqual(self.d.metric(SENT), before + 1)
        # its log line names the address its connection's entry was opened with
        wait_until("the own sender's log line", lambda: re.search(
            r"request method=GET path=%s status=200 .*client=127\.0\.0\.3 .*end=ok" % (
                re.escape(self.path)), self.d.log()))
        # an unknown header leaves the request to libmicrohttpd (from memory: no sendfile)
        s.sendall(self.get.replace(b"\r\n\r\n", b"\r\nX-Probe: 1\r\n\r\n"))
        status2, mhd_head, mhd_body, rest = read_answer(s, rest)
        s.close()
        self.assertEqual(self.d.metric(SENT), before + 1)
        self.assertEqual((status, status2), (200, 200))
        self.assertEqual(own_body, self.body)
        self.assertEqual(mhd_body, self.body)
        self.assertEqual(strip_varying(own_head), strip_varying(mhd_head))
        self.assertIn(b"Access-Control-Allow-Origin: https://viewer.example", own_head)
        self.assertRegex(own_head, rb"\r\nDate: \w{3}, \d\d \w{3} \d{4} \d\d:\d\d:\d\d GMT\r\n")
        # the Date line is formatted once a second per polling thread: the clock's, and a
        # later one a second on (4 connections: whichever threads they land on)
        def date_of(head):
            text = re.search(rb"\r\nDate: ([^\r]*)", head).group(1).decode()
            return email.utils.parsedate_to_datetime(text).timestamp()
        self.assertLess(abs(date_of(own_head) - time.time()), 5)
        time.sleep(1.1)
        for _ in range(4):
            s = self.connect()
            s.sendall(self.get)
            status, later_head, _, _ = read_answer(s, b"")
            s.close()
            self.assertGreaterEqual(date_of(later_head) - date_of(own_head), 1,
                                    (own_head, later_head))
        self.assertEqual(self.d.metric(SENT), before + 5)
        self.assertTrue(own_head.endswith(b"\r\nContent-Length: %d" % len(self.body)))
        wait_until("the own sender's log line", lambda: re.search(
            r"request method=GET path=%s status=200 bytes=%d .*end=ok" % (
                re.escape(self.path), len(self.body)), self.d.log()))

    def test_pipelined_requests_then_a_handover(self):
        s = self.connect()
        before = self.d.metric(SENT)
        head = b"HEAD %s HTTP/1.1\r\nHost: t\r\n\r\n" % self.path.encode()
        inm = b"GET %s HTTP/1.1\r\nHost: t\r\nIf-None-Match: \"%s\"\r\n\r\n" % (
            self.path.encode(), self.key.encode())
        s.sendall(self.get * 3 + head + inm + self.get)
        rest = b""
        for _ in range(3):
            status, _, body, rest = read_answer(s, rest)
            self.assertEqual((status, body), (200, self.body))
        status, hh, body, rest = read_answer(s, rest, head_only=True)
        self.assertEqual((status, body), (200, b""))
        self.assertIn(b"Content-Length: %d" % len(self.body), hh)
        status, _, _, rest = read_answer(s, rest)
        self.assertEqual(status, 304)
        status, _, body, rest = read_answer(s, rest)
        self.assertEqual((status, body, rest), (200, self.body, b""))
        s.close()
        self.assertEqual(self.d.metric(SENT), before + 3)  # the rest were libmicrohttpd's

    def test_long_pipelines_and_large_answers_arrive_whole(self):
        """Past a wake-up's share (http_front.c: 8 answers, 2 MB) the connection is queued
        again: 20 pipelined answers and two 2.9 MB ones arrive whole and in order, all the own
        sender's. A 4 MB window lets more than 2 MB go in one wake-up."""
        big = self.d.post("/v1/mesh", BIG)
        self.assertEqual(big.status, 200)
        self.assertGreater(len(big.body), 2 << 20)
        get_big = b"GET /v1/meshes/%s.stl HTTP/1.1\r\nHost: t\r\n\r\n" % (
            big.header("ETag").strip('"').encode())
        time.sleep(0.2)  # the file settles (file_memo.h: 50 ms)
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
        s.settimeout(30)
        s.connect(("127.0.0.1", self.d.port))
        before = self.d.metric(SENT)
        s.sendall(self.get * 20 + get_big * 2 + self.get)
        rest = b""
        for _ in range(20):
            status, _, body, rest = read_answer(s, rest)
            self.assertEqual((status, body), (200, self.body))
        for _ in range(2):
            status, _, body, rest = read_answer(s, rest)
            self.assertEqual(status, 200)
            self.assertEqual(body, big.body)
        status, _, body, rest = read_answer(s, rest)
        self.assertEqual((status, body, rest), (200, self.body, b""))
        s.close()
        self.assertEqual(self.d.metric(SENT), before + 23)

    def test_a_reader_that_stops_reading_blocks_nobody(self):
        big = self.d.post("/v1/mesh", BIG)
        self.assertEqual(big.status, 200)
        path = "/v1/meshes/%s.stl" % big.header("ETag").strip('"')
        get = b"GET %s HTTP/1.1\r\nHost: t\r\n\r\n" % path.encode()
        time.sleep(0.2)  # the file settles (file_memo.h: 50 ms)
        stalled = []
        try:
            for _ in range(12):
                s = socket.socket()
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # a tiny window
                s.connect(("127.0.0.1", self.d.port))
                s.sendall(get)
                stalled.append(s)
            time.sleep(0.3)
            for _ in range(5):
                t0 = time.time()
                s = self.connect()
                s.sendall(self.get)
                status, _, body, _ = read_answer(s, b"")
                s.close()
                self.assertEqual((status, body), (200, self.body))
                self.assertLess(time.time() - t0, 1.0)
                self.assertEqual(http_request(self.d.port, "GET", "/healthz").status, 200)
            # no byte moves for --conn-timeout (3 s): closed, logged as aborted
            wait_until("the stalled answers ended", lambda: len(re.findall(
                r"path=%s status=200 .*end=aborted" % re.escape(path), self.d.log())) >= 12,
                timeout=20)
        finally:
            for s in stalled:
                s.close()

    def test_trickled_bytes_do_not_hold_a_stalled_answer(self):
        """Bytes arriving while an answer does not move leave its stall deadline alone: pipelined
        GETs fill the socket (one answer stalls, often before its first byte), then one byte a
        second comes in and nothing is read; each connection is closed within --conn-timeout
        (3 s) of its last moved byte, plus slack for the 0.1 s deadline scan and the load."""
        get = self.get * 400  # 400 answers: far more than the socket buffers hold
        conns = []
        try:
            # where an answer stalls follows the socket buffers' sizes: over these windows
            # some stall between two answers (the case that was held for ever)
            for window in (32768, 65536, 100000, 131072, 200000, 262144, 400000, 600000):
                s = socket.socket()
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, window)
                s.settimeout(30)
                s.connect(("127.0.0.1", self.d.port))
                s.sendall(get)
                conns.append(s)
            t0 = time.time()
            limit = 3 + 4  # --conn-timeout + slack

            def established(s):  # tcp_info's first byte: tcpi_state (1: ESTABLISHED)
                return s.getsockopt(socket.IPPROTO_TCP, socket.TCP_INFO, 8)[0] == 1
            while time.time() - t0 < limit and any(established(s) for s in conns):
                time.sleep(1.0)
                for s in conns:
                    if established(s):
                        try:
                            s.send(b"X")  # a head that never ends, one byte a second
                        except OSError:
                            pass  # closed meanwhile
            open_ = sum(established(s) for s in conns)
            self.assertEqual(open_, 0, "%d connections still held after %.1f s" % (
                open_, time.time() - t0))
        finally:
            for s in conns:
                s.close()

    def test_an_idle_connection_goes_to_libmicrohttpd(self):
        s = self.connect()
        sent = self.d.metric(SENT)
        s.sendall(self.get)
        status, _, body, _ = read_answer(s, b"")
        self.assertEqual((status, body), (200, self.body))
        self.assertEqual(self.d.metric(SENT), sent + 1)
        # held by the own sender until idle for 0.5 s (http.c OWN_SENDER_IDLE_S; deadlines
        # checked every 0.1 s), then libmicrohttpd's (its table's rules hold it)
        time.sleep(1.5)
        sent = self.d.metric(SENT)
        s.sendall(self.get)
        status, _, body, _ = read_answer(s, b"")
        s.close()
        self.assertEqual((status, body), (200, self.body))
        self.assertEqual(self.d.metric(SENT), sent)  # libmicrohttpd's now, from memory


class CapCounts:
    """--client-conns and isomesh_connections see the connections the own sender holds as they
    see libmicrohttpd's (server/isomeshd/own_conns.c): beyond the cap a connection is refused
    (503), the count is exact, a connection handed to libmicrohttpd is not counted twice, and
    closed ones leave the count. The same assertions hold without the flag (OWN = False)."""
    CAP = 4
    OWN = True

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="isomeshd_cap_")
        flags = ("--own-sender",) if cls.OWN else ()
        cls.d = Daemon("--workers", "1", "--client-conns", str(cls.CAP), *flags,
                       cache_dir=os.path.join(cls.tmp, "cache")).start()
        first = cls.d.post("/v1/mesh", sphere(0.77))
        assert first.status == 200, first.body[:200]
        cls.body = first.body
        cls.get = b"GET /v1/meshes/%s.drc HTTP/1.1\r\nHost: t\r\n\r\n" % (
            first.header("ETag").strip('"').encode())
        time.sleep(0.2)  # the cache file settles (file_memo.h: 50 ms)

    @classmethod
    def tearDownClass(cls):
        cls.d.stop()
        cls.d.cleanup()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def metrics(self):
        """Over one kept-alive connection from another address (under its own cap, counted
        as one throughout; a connection per scrape would linger in the count)."""
        if not hasattr(self, "scraper"):
            self.scraper = socket.create_connection(("127.0.0.1", self.d.port), timeout=30,
                                                    source_address=("127.0.0.2", 0))
        self.scraper.sendall(b"GET /metrics HTTP/1.1\r\nHost: t\r\n\r\n")
        status, _, body, _ = read_answer(self.scraper, b"")
        self.assertEqual(status, 200)
        return parse_metrics(body.decode())

    def tearDown(self):
        if hasattr(self, "scraper"):
            self.scraper.close()

    def test_the_address_cap_and_the_count_see_every_connection(self):
        refused = 'isomesh_connections_closed_total{reason="refused"}'
        wait_until("only the scraper connected", lambda: self.metrics()["isomesh_connections"] == 1)
        m0 = self.metrics()
        held = []
        try:
            for _ in range(self.CAP):  # each answered, then held (the own sender's: idle < 0.5 s)
                s = socket.create_connection(("127.0.0.1", self.d.port), timeout=30)
                s.sendall(self.get)
                status, _, body, _ = read_answer(s, b"")
                self.assertEqual((status, body), (200, self.body))
                held.append(s)
            extra = socket.create_connection(("127.0.0.1", self.d.port), timeout=30)
            extra.sendall(self.get)
            status, head, _, _ = read_answer(extra, b"")
            self.assertEqual(status, 503, head)  # as libmicrohttpd refuses beyond the cap
            self.assertIn(b"Retry-After", head)
            self.assertEqual(extra.recv(1), b"")  # and closed
            extra.close()
            m = self.metrics()
            if self.OWN:  # the held ones were the own sender's answers
                self.assertEqual(m.get(SENT, 0) - m0.get(SENT, 0), self.CAP)
            self.assertEqual(m[refused] - m0.get(refused, 0), 1)
            self.assertEqual(m["isomesh_connections"], self.CAP + 1)  # + the scraper
            # idle past 0.5 s the own sender's go to libmicrohttpd with their entry
            time.sleep(1.2)
            self.assertEqual(self.metrics()["isomesh_connections"], self.CAP + 1)
            for s in held:  # and still answer
                s.sendall(self.get)
                status, _, body, _ = read_answer(s, b"")
                self.assertEqual((status, body), (200, self.body))
        finally:
            for s in held:
                s.close()
        wait_until("the closed connections left the count",
                   lambda: self.metrics()["isomesh_connections"] == 1)


class OwnSenderCapTest(CapCounts, unittest.TestCase):
    OWN = True


class LibmicrohttpdCapTest(CapCounts, unittest.TestCase):
    OWN = False


if __name__ == "__main__":
    unittest.main()
