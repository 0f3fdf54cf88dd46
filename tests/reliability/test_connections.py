"""test_connections.py — isomeshd's connection table (server/isomeshd/conns.h), issue 17:

- the global connection limit is fair across addresses: ten addresses, each under the
  per-address cap, fill --max-connections; a client from an eleventh address is still answered
  (not left in the listen backlog) within NEW_CLIENT_BOUND_S, the ten end up with near-equal
  shares, and a connection
  with a request in progress outlives the idle ones of its own address; a connection that
  nobody can give way to is answered 503 with Retry-After, not closed;
- request deadlines whatever the trickle rate: headers trickled under the idle timeout, and a
  body trickled a byte at a time, are cut off by --header-timeout / --body-timeout (the
  trickle keeps --conn-timeout from ever firing, so a close can only come from them);
- a synchronous request whose client leaves frees its worker unless another request waits
  for the same computation (single flight), seen in the metrics.

Every server binds 127.0.0.1 and is stopped; waits are bounded and no assertion depends on
how fast this machine is."""
import http.client
import json
import os
import resource
import socket
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import (Daemon, busy_work, http_request, metric_key, parse_metrics,  # noqa: E402
                      sanitizer_build, server_closed, sphere, wait_until)
from harness import ISOMESHD  # noqa: E402

# Issue 17's red-team case at its own scale: 4,800 connections from 10 addresses, each under
# the per-address cap (--client-conns 512), against the default --max-connections 4000.
# Measured here (load 34 on 2 cores): 4,800 connects 1.8 s, the daemon settles at the limit
# in 0.2 s, the new client is answered in 0.08 s; the whole test ~5 s.
ADDRESSES = ["127.0.0.%d" % i for i in range(2, 12)]
LIMIT = 4000        # --max-connections, its default
PER_ADDRESS = 480   # each address opens this many (under --client-conns 512): 4,800 > LIMIT
# The issue asks for an answer within 1 s. Without the fair limit the new client waits in the
# listen backlog until some connection's timeout frees a slot: 120 s here (the test's idle
# timeouts), 10 s in the measurement. 2 s is 25x the answer time measured at load 34
# yet far below any timeout path, so it fails on the old behaviour and not on a loaded
# machine; under AddressSanitizer (several times slower at everything) 10 s, still 12x under.
NEW_CLIENT_BOUND_S = 10.0 if sanitizer_build(ISOMESHD) else 2.0
FDS_NEEDED = LIMIT + PER_ADDRESS * len(ADDRESSES) + 1000  # the daemon's and this process's


def raise_nofile():
    """Raises this process's open-file limit (the daemon inherits it) to FDS_NEEDED; False
    when the hard limit is below it."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and hard < FDS_NEEDED:
        return False
    if soft != resource.RLIM_INFINITY and soft < FDS_NEEDED:
        resource.setrlimit(resource.RLIMIT_NOFILE, (FDS_NEEDED, hard))
    return True


def connect(port, source):
    s = socket.create_connection(("127.0.0.1", port), timeout=10, source_address=(source, 0))
    s.setblocking(False)
    return s


def post_raw(port, body, source="127.0.0.1"):
    """A socket that has sent a whole POST /v1/mesh and not read anything."""
    data = json.dumps(body).encode()
    s = socket.create_connection(("127.0.0.1", port), timeout=10, source_address=(source, 0))
    s.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
              b"Content-Length: %d\r\n\r\n" % len(data) + data)
    return s


class Scraper:
    """/metrics read over one kept-alive connection from 127.0.0.1: one steady slot under the
    limit, never a victim (an address holding one connection gives none up), where a new
    connection per scrape would come and go and take part in the admissions."""

    def __init__(self, port):
        self.conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)

    def metrics(self):
        self.conn.request("GET", "/metrics")
        r = self.conn.getresponse()
        return parse_metrics(r.read().decode())

    def metric(self, name, **labels):
        return self.metrics().get(metric_key(name, labels), 0.0)

    def alone(self):
        """Connects, then waits until the daemon holds no connection but this one: the
        harness's readiness probes can still be open in its table (on a loaded machine their
        close is seen late), and one of them taking a slot makes the admissions a test counts
        go otherwise (a post's slot given to this scraper: evicted_idle instead of busy)."""
        wait_until("the readiness probes' connections closed",
                   lambda: self.metric("isomesh_connections") == 1)
        return self

    def close(self):
        self.conn.close()


def conn_metrics(m):
    """The connection table's metrics out of a scrape (printed when an admission goes
    otherwise than a test expects)."""
    return {k: v for k, v in m.items() if "connection" in k or "clients_left" in k}


class FairLimitTest(unittest.TestCase):
    def test_a_new_address_gets_in_when_ten_others_fill_the_limit(self):
        if not raise_nofile():
            self.skipTest("RLIMIT_NOFILE's hard limit is under %d" % FDS_NEEDED)
        with Daemon("--workers", "1", "--conn-timeout", "120s", "--header-timeout", "120s",
                    "--job-timeout", "120s") as d:
            # one connection of the first address has a request in progress (it waits for a
            # computation); everything else only connects
            scraper = Scraper(d.port).alone()
            busy = post_raw(d.port, busy_work(1), source=ADDRESSES[0])
            busy.setblocking(False)
            wait_until("the computation running",
                       lambda: scraper.metric("isomesh_workers_busy") == 1)
            socks = {a: [] for a in ADDRESSES}
            try:
                for a in ADDRESSES:
                    for _ in range(PER_ADDRESS):
                        socks[a].append(connect(d.port, a))

                def held():
                    return {a: [s for s in ss if not server_closed(s)] for a, ss in socks.items()}
                # the daemon accepts in its own time: wait until it has settled at the limit
                # (the busy connection and the scraper's are two of the LIMIT)
                wait_until("the limit filled", lambda: sum(map(len, held().values())) == LIMIT - 2)
                shares = {a: len(ss) for a, ss in held().items()}
                # every address keeps a near-equal share (LIMIT / 10, the busy one aside)
                self.assertTrue(all(abs(n - LIMIT // 10) <= 2 for n in shares.values()), shares)
                self.assertLessEqual(max(shares.values()) - min(shares.values()), 2, shares)
                self.assertFalse(server_closed(busy))  # idle ones of its address went first
                # an eleventh address is answered at once, in place of an idle connection
                start = time.monotonic()
                r = http_request(d.port, "GET", "/healthz", timeout=30, source="127.0.0.99")
                took = time.monotonic() - start
                self.assertEqual(r.status, 200)
                self.assertLess(took, NEW_CLIENT_BOUND_S)
                self.assertFalse(server_closed(busy))
                m = scraper.metrics()
                closed = m['isomesh_connections_closed_total{reason="evicted_idle"}']
                self.assertEqual(closed, len(ADDRESSES) * PER_ADDRESS - (LIMIT - 2) + 1)
                self.assertEqual(m['isomesh_connections_closed_total{reason="evicted_busy"}'], 0)
                self.assertLessEqual(m["isomesh_connections"], LIMIT)
            finally:
                scraper.close()
                for ss in socks.values():
                    for s in ss:
                        s.close()
                busy.close()

    def test_at_the_limit_a_busy_connection_of_the_largest_holder_gives_way(self):
        # one address holds every connection, each waiting for the same computation (one
        # flight); a newcomer takes the place of the newest, which leaves the flight
        with Daemon("--workers", "1", "--max-connections", "16", "--client-conns", "20",
                    "--job-timeout", "120s") as d:
            scraper = Scraper(d.port).alone()  # one of the 16
            waiting = []
            try:
                for _ in range(15):
                    waiting.append(post_raw(d.port, busy_work(3), source=ADDRESSES[0]))
                    waiting[-1].setblocking(False)
                wait_until("every request waiting, the computation running",
                           lambda: scraper.metric("isomesh_suspended_connections") == 15
                           and scraper.metric("isomesh_workers_busy") == 1)
                before = conn_metrics(scraper.metrics())
                r = http_request(d.port, "GET", "/healthz", timeout=10, source="127.0.0.99")
                self.assertEqual(r.status, 200)
                self.assertEqual(sum(server_closed(s) for s in waiting), 1)
                m = scraper.metrics()
                self.assertEqual(m['isomesh_connections_closed_total{reason="evicted_busy"}'], 1,
                                 (before, conn_metrics(m), d.log()))
                self.assertEqual(m["isomesh_clients_left_total"], 1)
                self.assertEqual(m["isomesh_suspended_connections"], 14)
                # the computation goes on for the others
                self.assertEqual(m["isomesh_workers_busy"], 1)
                self.assertEqual(m['isomesh_worker_restarts_total{reason="cancel"}'], 0)
                # the limit again, every connection busy, the largest holder asks for more:
                # nobody gives way, and the newcomer is told so (503, Retry-After), not closed.
                # First the daemon must have seen the /healthz client hang up (scraper + 14):
                # on a loaded machine its close can come after the next connect, which then
                # meets a full table with nobody to give way and is refused (CI, stop 25)
                wait_until("the /healthz connection closed",
                           lambda: scraper.metric("isomesh_connections") == 15)
                waiting.append(post_raw(d.port, busy_work(3), source=ADDRESSES[0]))
                waiting[-1].setblocking(False)
                wait_until("the limit filled with busy connections",
                           lambda: scraper.metric("isomesh_suspended_connections") == 15)
                r = http_request(d.port, "GET", "/healthz", timeout=10, source=ADDRESSES[0])
                self.assertEqual(r.status, 503, r.body[:200])
                self.assertEqual(r.json()["error"]["code"], "too_many_connections")
                self.assertIsNotNone(r.header("Retry-After"))
                self.assertEqual(scraper.metric("isomesh_connections_closed_total",
                                                reason="refused"), 1)
                self.assertEqual(sum(server_closed(s) for s in waiting), 1)  # the one evicted
            finally:
                scraper.close()
                for s in waiting:
                    s.close()


class DeadlineTest(unittest.TestCase):
    def test_trickled_headers_and_bodies_are_cut_off(self):
        with Daemon("--workers", "1", "--header-timeout", "2s", "--body-timeout", "2s",
                    "--conn-timeout", "60s") as d:
            heads = socket.create_connection(("127.0.0.1", d.port), timeout=10)
            heads.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
            body = socket.create_connection(("127.0.0.1", d.port), timeout=10)
            body.sendall(b"POST /v1/mesh HTTP/1.1\r\nHost: x\r\nContent-Type: application/json"
                         b"\r\nContent-Length: 100000\r\n\r\n")
            heads.setblocking(False)
            body.setblocking(False)
            try:
                # a header line, and a body byte, every half second: never idle for MHD's
                # 60 s timeout; the test gives up (fails) long before that
                deadline = time.time() + 40
                i = 0
                while time.time() < deadline and not (server_closed(heads) and
                                                      server_closed(body)):
                    for s, data in ((heads, b"X-Slow-%d: 1\r\n" % i), (body, b" ")):
                        try:
                            s.send(data)
                        except OSError:
                            pass
                    i += 1
                    time.sleep(0.5)
                self.assertTrue(server_closed(heads), "headers trickled forever")
                self.assertTrue(server_closed(body), "body trickled forever")
                self.assertEqual(d.metric("isomesh_connections_closed_total",
                                          reason="header_deadline"), 1)
                self.assertEqual(d.metric("isomesh_connections_closed_total",
                                          reason="body_deadline"), 1)
                d.log_count("status=408", 1)
                self.assertIn("closed=body_deadline", d.log())
            finally:
                heads.close()
                body.close()
            # a request sent in pieces, but within the deadline, is served
            s = socket.create_connection(("127.0.0.1", d.port), timeout=30)
            try:
                for part in (b"GET /healthz HTTP/1.1\r\n", b"Host: x\r\n", b"\r\n"):
                    s.sendall(part)
                    time.sleep(0.2)
                self.assertTrue(s.recv(64).startswith(b"HTTP/1.1 200"))
            finally:
                s.close()


class ClientLeftTest(unittest.TestCase):
    def test_a_request_whose_client_left_frees_its_worker_unless_another_waits(self):
        # one worker, and a job deadline far beyond this test's bounds: only cancelling frees it
        with Daemon("--workers", "1", "--job-timeout", "600s") as d:
            # alone: the client leaves, its computation stops, the worker is free again
            a = post_raw(d.port, busy_work(1))
            wait_until("the computation running", lambda: d.metric("isomesh_workers_busy") == 1)
            a.close()
            wait_until("the client seen gone", lambda: d.metric("isomesh_clients_left_total") == 1)
            wait_until("its worker stopped",
                       lambda: d.metric("isomesh_worker_restarts_total", reason="cancel") == 1)
            wait_until("a worker ready", lambda: d.metric("isomesh_workers_ready") == 1
                       and d.metric("isomesh_workers_busy") == 0)
            # shared: two requests wait for the same computation; one leaves, it carries on
            b1 = post_raw(d.port, busy_work(2))
            wait_until("the computation running", lambda: d.metric("isomesh_workers_busy") == 1)
            joins = d.metric("isomesh_singleflight_joins_total")
            b2 = post_raw(d.port, busy_work(2), source="127.0.0.2")
            wait_until("the second request joined",
                       lambda: d.metric("isomesh_singleflight_joins_total") == joins + 1)
            b1.close()
            wait_until("the first client seen gone",
                       lambda: d.metric("isomesh_clients_left_total") == 2)
            self.assertEqual(d.metric("isomesh_worker_restarts_total", reason="cancel"), 1)
            self.assertEqual(d.metric("isomesh_workers_busy"), 1)
            b2.settimeout(0.5)
            with self.assertRaises(socket.timeout):  # still waiting, not closed
                b2.recv(1)
            b2.close()
            wait_until("the second client seen gone",
                       lambda: d.metric("isomesh_clients_left_total") == 3)
            wait_until("the worker stopped",
                       lambda: d.metric("isomesh_worker_restarts_total", reason="cancel") == 2)
            # the worker serves another user's small mesh
            r = http_request(d.port, "POST", "/v1/mesh", sphere(0.61), timeout=120,
                             source="127.0.0.3")
            self.assertEqual(r.status, 200)
            self.assertEqual(d.metric("isomesh_computations_total", outcome="canceled"), 2)
            d.log_count("closed=client_left", 3)


if __name__ == "__main__":
    unittest.main()
