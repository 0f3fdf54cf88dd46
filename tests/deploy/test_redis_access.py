"""test_redis_access.py — who may use the service's Redis, and two services in one Redis:

* --redis-password-file: the daemon authenticates as the ACL user named in the file (Redis's
  CLIENT LIST shows it) and shares meshes; a wrong password leaves Redis unusable to it (it
  keeps serving on its own, logging the outage with what=auth); a password file others may
  read is refused at start;
* --redis-namespace: a daemon of another namespace sees none of the first one's meshes (it
  computes the same mesh itself) and writes its own keys under its own name."""
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack  # noqa: E402
from stack import harness  # noqa: E402

SKIP = stack.missing_programs()


@unittest.skipIf(SKIP, SKIP)
class RedisAccessTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.redis = stack.Redis().start()
        self.redis.command("ACL", "SETUSER", "isomesh", "on", ">s3cret", "~*", "&*", "+@all")
        self.addr = "127.0.0.1:%d" % self.redis.port

    def tearDown(self):
        self.redis.cleanup()
        self.tmp.cleanup()

    def secret(self, name, text, mode=0o600):
        path = os.path.join(self.tmp.name, name)
        with open(path, "w") as f:
            f.write(text)
        os.chmod(path, mode)
        return path

    def test_password_file_namespaces_and_refusals(self):
        good = self.secret("good", "isomesh s3cret\n")
        req = harness.sphere(0.77)
        with harness.Daemon("--workers", "1", "--redis", self.addr,
                            "--redis-password-file", good) as a:
            self.assertTrue(stack.wait_until(lambda: a.metric("isomesh_redis_up") == 1, 10), a.log())
            r = a.post("/v1/mesh", req)
            self.assertEqual(r.status, 200)
            key = r.header("ETag").strip('"')
            self.assertTrue(stack.wait_until(
                lambda: self.redis.command("EXISTS", "isomesh:v1:%s.drc" % key) == 1, 10))
            self.assertIn(b"user=isomesh", self.redis.command("CLIENT", "LIST"))
            # another namespace in the same Redis: nothing shared, its own keys
            with harness.Daemon("--workers", "1", "--redis", self.addr, "--redis-password-file",
                                good, "--redis-namespace", "lab-b") as b:
                self.assertTrue(stack.wait_until(lambda: b.metric("isomesh_redis_up") == 1, 10))
                again = b.post("/v1/mesh", req)
                self.assertEqual(again.status, 200)
                self.assertEqual(again.body, r.body)
                self.assertEqual(again.header("X-Cache"), "miss", "computed, not shared")
                self.assertEqual(b.metric("isomesh_computations_started_total"), 1)
                self.assertTrue(stack.wait_until(
                    lambda: self.redis.command("EXISTS", "lab-b:v1:%s.drc" % key) == 1, 10))
        # a wrong password: Redis is unusable to this daemon, which still serves on its own
        wrong = self.secret("wrong", "isomesh nope\n")
        with harness.Daemon("--workers", "1", "--redis", self.addr,
                            "--redis-password-file", wrong) as c:
            self.assertTrue(stack.wait_until(lambda: "what=auth" in c.log(), 10), c.log())
            self.assertEqual(c.metric("isomesh_redis_up"), 0)
            self.assertEqual(c.post("/v1/mesh", harness.sphere(0.78)).status, 200)
            self.assertNotIn("nope", c.log())
        # a password file others may read: refused at start, and a bad namespace
        loose = self.secret("loose", "isomesh s3cret\n", 0o644)
        for args, expect in ((["--redis-password-file", loose], "readable or writable by others"),
                             (["--redis-namespace", "a:b"], "redis-namespace")):
            p = subprocess.run([harness.ISOMESHD, "--listen", "127.0.0.1:0", "--workers", "1",
                                "--cache-dir", os.path.join(self.tmp.name, "c"),
                                "--redis", self.addr] + args,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
            self.assertNotEqual(p.returncode, 0)
            self.assertIn(expect, p.stderr)


if __name__ == "__main__":
    unittest.main()
