"""test_proxy.py — the client's identity behind a reverse proxy: with --trusted-proxy, the
address that a trusted proxy (nginx) names in X-Real-IP is the client for job lists, per-user
limits and fair scheduling; from anyone else, or when malformed, the header is ignored."""
import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ISOMESHD, Daemon, sphere  # noqa: E402


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

    def test_bad_flag_value(self):
        p = subprocess.run([ISOMESHD, "--trusted-proxy", "nginx.local"], capture_output=True,
                           text=True, timeout=10)
        self.assertEqual(p.returncode, 2)
        self.assertIn("trusted-proxy", p.stderr)


if __name__ == "__main__":
    unittest.main()
