"""test_slowloris.py — hundreds of slow connections (request headers trickled a byte at a time,
from four other loopback addresses) against isomeshd while a normal user, from 127.0.0.1, keeps
computing and fetching meshes. --client-conns caps what one address may hold (the rest are
refused: a request on them would get 503, and one that sends none is closed within 2 s), the
normal user sees only successes, and once the attacker stops trickling,
--conn-timeout closes every one of its connections. (Latency under this attack is measured by
tests/bench/bench_load.py, not asserted here.)"""
import os
import socket
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reltools import (QUICK, Daemon, OtherUser, request, server_closed, sphere,  # noqa: E402
                      wait_until)

ATTACKERS = ["127.0.0.2", "127.0.0.3", "127.0.0.4", "127.0.0.5"]
PER_ADDRESS = 60 if QUICK else 100
LIMIT = 32


def open_slow(port, source):
    """A connection that has sent only the start of a request."""
    s = socket.create_connection(("127.0.0.1", port), timeout=5, source_address=(source, 0))
    s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
    s.setblocking(False)
    return s


class SlowlorisTest(unittest.TestCase):
    def test_slow_connections_are_capped_and_timed_out_while_others_are_served(self):
        with Daemon("--workers", "2", "--client-conns", str(LIMIT), "--conn-timeout", "2s") as d:
            status, _, _ = request(d.port, "POST", "/v1/mesh", sphere(0.77))
            self.assertEqual(status, 200)
            socks = []
            try:
                with OtherUser(d.port, tag=0.3) as other:
                    self.assertTrue(other.wait_for(2))
                    for source in ATTACKERS:
                        for _ in range(PER_ADDRESS):
                            try:
                                socks.append(open_slow(d.port, source))
                            except OSError:
                                pass  # refused outright: counted as not held
                    stop = threading.Event()

                    def trickle():
                        i = 0
                        while not stop.is_set():
                            for s in socks:
                                try:
                                    s.send(b"X-Slow-%d: 1\r\n" % i)
                                except OSError:
                                    pass
                            i += 1
                            stop.wait(0.5)
                    t = threading.Thread(target=trickle, daemon=True)
                    t.start()
                    # while the attack goes on, the normal user keeps working
                    n = len(other.results)
                    self.assertTrue(other.wait_for(n + (5 if QUICK else 15)))
                    for _ in range(5):
                        self.assertEqual(request(d.port, "GET", "/healthz", timeout=10)[0], 200)
                        self.assertEqual(request(d.port, "POST", "/v1/mesh", sphere(0.77),
                                                 timeout=30)[0], 200)
                    # the refused ones waited 2 s for a request that never came
                    held = wait_until("the refused connections closed", lambda: (
                        lambda h: h if len(h) <= LIMIT * len(ATTACKERS) else None)(
                            [s for s in socks if not server_closed(s)]), timeout=20)
                    self.assertGreater(len(held), 0)
                    stop.set()
                    t.join(10)
                self.assertEqual(other.failures(), [])
                # idle now: the connection timeout closes every slow connection
                deadline = time.time() + 30
                while time.time() < deadline and not all(server_closed(s) for s in held):
                    time.sleep(0.1)
                self.assertEqual([s for s in held if not server_closed(s)], [])
                self.assertEqual(request(d.port, "GET", "/healthz", timeout=10)[0], 200)
            finally:
                for s in socks:
                    s.close()


if __name__ == "__main__":
    unittest.main()
