"""test_proxy.py — the client's identity behind a reverse proxy: with --trusted-proxy, the
address that a trusted proxy (nginx) names in X-Real-IP, or else the rightmost address of
X-Forwarded-For that no trusted proxy wrote, is the client for job lists, per-user limits and
fair scheduling; from anyone else, or when malformed, the headers are ignored. A trusted
proxy's connections are exempt from the per-address cap (--client-conns), which anyone else
meets with a 503 and Retry-After."""
import os
import socket
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ISOMESHD, Daemon, http_request, sphere, wait_until  # noqa: E402


def real_ip(addr):
    return {"X-Real-IP": addr}


class ProxyTest(unittest.TestCase):
    def submit(self, d, r, addr):
        job = d.post("/v1/jobs", sphere(r), headers=real_ip(addr))
        self.assertIn(job.status, (200, 202), job.body)
        return job.json()["id"]

    def listed(self, d, addr):
        r = d.get("/v1/jobs", headers=real_ip(addr))
        self.assertEqual(r.status, 200, r.body)
        return r.json()

    def test_trusted_proxy_names_the_client(self):
        with Daemon("--workers", "1", "--trusted-proxy", "127.0.0.1,::1") as d:
            a = self.submit(d, 0.61, "10.0.0.1")
            b = self.submit(d, 0.62, "10.0.0.2")
            seen_a = self.listed(d, "10.0.0.1")
            self.assertEqual(seen_a["user"], "10.0.0.1")
            self.assertEqual([j["id"] for j in seen_a["jobs"]], [a])
            self.assertEqual([j["id"] for j in self.listed(d, "10.0.0.2")["jobs"]], [b])
            # not an address: the proxy itself is the client
            self.assertEqual(self.listed(d, "10.0.0.1, evil")["user"], "127.0.0.1")

    def test_untrusted_peers_cannot_choose_their_identity(self):
        with Daemon("--workers", "1") as d:
            a = self.submit(d, 0.63, "10.0.0.1")
            b = self.submit(d, 0.64, "10.0.0.2")
            seen = self.listed(d, "10.0.0.3")
            self.assertEqual(seen["user"], "127.0.0.1")
            self.assertEqual(sorted(j["id"] for j in seen["jobs"]), sorted([a, b]))

    def test_forwarded_for_names_the_client_past_trusted_hops(self):
        with Daemon("--workers", "1", "--trusted-proxy", "127.0.0.1,10.9.9.9") as d:
            def user(headers, source=None):
                r = http_request(d.port, "GET", "/v1/jobs", headers=headers, source=source)
                self.assertEqual(r.status, 200, r.body)
                return r.json()["user"]
            xff = lambda v: {"X-Forwarded-For": v}  # noqa: E731
            self.assertEqual(user(xff("10.0.0.7")), "10.0.0.7")
            self.assertEqual(user(xff("6.6.6.6, 10.0.0.8")), "10.0.0.8")  # left: forgeable
            self.assertEqual(user(xff("10.0.0.9,10.9.9.9")), "10.0.0.9")  # a trusted hop
            self.assertEqual(user(xff("2001:db8::1, 10.9.9.9")), "2001:db8::1")
            self.assertEqual(user(xff("10.0.0.1, evil, 10.9.9.9")), "10.9.9.9")
            self.assertEqual(user(xff("evil")), "127.0.0.1")
            self.assertEqual(user(dict(xff("10.0.0.5"), **real_ip("10.0.0.6"))), "10.0.0.6")
            # from an untrusted peer both headers are the client's own words: ignored
            self.assertEqual(user(dict(xff("10.0.0.5"), **real_ip("10.0.0.6")),
                                  source="127.0.0.2"), "127.0.0.2")

    def test_the_per_address_cap_spares_the_proxy_and_answers_the_others(self):
        with Daemon("--workers", "1", "--trusted-proxy", "127.0.0.1",
                    "--client-conns", "2") as d:
            held = []
            try:
                for source, n in (("127.0.0.2", 2), ("127.0.0.1", 3)):
                    for _ in range(n):
                        held.append(socket.create_connection(("127.0.0.1", d.port), timeout=10,
                                                             source_address=(source, 0)))
                # the daemon accepts in its own time (the scrape is one more connection)
                wait_until("the connections held",
                           lambda: d.metric("isomesh_connections") >= len(held) + 1)
                r = http_request(d.port, "GET", "/healthz", source="127.0.0.2")
                self.assertEqual(r.status, 503, r.body)
                self.assertEqual(r.json()["error"]["code"], "too_many_connections")
                self.assertIsNotNone(r.header("Retry-After"))
                self.assertEqual(http_request(d.port, "GET", "/healthz").status, 200)
                self.assertEqual(d.metric("isomesh_connections_closed_total", reason="refused"),
                                 1)
            finally:
                for s in held:
                    s.close()

    def test_bad_flag_value(self):
        p = subprocess.run([ISOMESHD, "--trusted-proxy", "nginx.local"], capture_output=True,
                           text=True, timeout=10)
        self.assertEqual(p.returncode, 2)
        self.assertIn("trusted-proxy", p.stderr)


if __name__ == "__main__":
    unittest.main()
