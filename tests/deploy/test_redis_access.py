"""test_redis_access.py — who may use the service's Redis, and two services in one Redis:

* --redis-password-file: the daemon authenticates as the ACL user named in the file (Redis's
  CLIENT LIST shows it) and shares meshes; a wrong password leaves Redis unusable to it (it
  keeps serving on its own, logging the outage with what=auth); a password file others may
  read is refused at start;
* --redis-namespace: a daemon of another namespace sees none of the first one's meshes (it
  computes the same mesh itself) and writes its own keys under its own name;
* TLS: Redis with only a TLS port for the daemon, reached through stunnel run with
  deploy/redis/stunnel-isomesh.conf (its addresses, CA file and host name pointed at this
  machine, nothing else changed): the daemon connects and shares its mesh, and the same
  configuration expecting another host name lets nothing through (the certificate is
  checked)."""
import os
import re
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
        try:  # tearDown does not run when setUp fails: never leave Redis behind
            self.redis.command("ACL", "SETUSER", "isomesh", "on", ">s3cret", "~*", "&*", "+@all")
        except BaseException:
            self.redis.cleanup()
            raise
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


STUNNEL_CONF = os.path.join(stack.DEPLOY, "redis", "stunnel-isomesh.conf")
TLS_HOST = "redis.isomesh.test"


def stunnel_conf(tmp, accept, connect, cafile, host, name):
    """The shipped stunnel configuration with only what names this machine replaced."""
    with open(STUNNEL_CONF) as f:
        text = f.read()
    for pattern, value in ((r"^foreground = .*$", "foreground = yes"),
                           (r"^pid = .*$", "pid = " + os.path.join(tmp, name + ".pid")),
                           (r"^accept = .*$", "accept = 127.0.0.1:%d" % accept),
                           (r"^connect = .*$", "connect = 127.0.0.1:%d" % connect),
                           (r"^CAfile = .*$", "CAfile = " + cafile),
                           (r"^checkHost = .*$", "checkHost = " + host)):
        text, n = re.subn(pattern, value, text, flags=re.M)
        if n != 1:
            raise AssertionError("%s: no single line %s" % (STUNNEL_CONF, pattern))
    path = os.path.join(tmp, name + ".conf")
    with open(path, "w") as f:
        f.write(text)
    return path


@unittest.skipIf(SKIP or not stack.STUNNEL or not stack.OPENSSL,
                 SKIP or "stunnel4 or openssl is missing (deploy/install-deps.sh test)")
class RedisTlsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.procs = []
        t = self.tmp.name
        self.cert, key = os.path.join(t, "redis.crt"), os.path.join(t, "redis.key")
        r = subprocess.run([stack.OPENSSL, "req", "-x509", "-newkey", "rsa:2048", "-nodes",
                            "-keyout", key, "-out", self.cert, "-days", "2",
                            "-subj", "/CN=" + TLS_HOST, "-addext",
                            "subjectAltName=DNS:" + TLS_HOST],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stdout)
        os.chmod(key, 0o644)  # redis-server may run as another user than the test's files
        self.tls_port = stack.free_port()
        # the plain port is the test's own view into Redis; the daemon only gets the tunnel
        self.redis = stack.Redis(extra=["--tls-port", str(self.tls_port), "--tls-cert-file",
                                        self.cert, "--tls-key-file", key, "--tls-ca-cert-file",
                                        self.cert, "--tls-auth-clients", "no"]).start()

    def tearDown(self):
        for p in self.procs:
            stack.stop_process(p)
        self.redis.cleanup()
        self.tmp.cleanup()

    def tunnel(self, host, name):
        """stunnel on a free port to Redis's TLS port, expecting host; returns the port."""
        port = stack.free_port()
        conf = stunnel_conf(self.tmp.name, port, self.tls_port, self.cert, host, name)
        self.procs.append(harness.spawn_owned([stack.STUNNEL, conf], stdin=subprocess.DEVNULL,
                                              stdout=subprocess.DEVNULL,
                                              stderr=subprocess.DEVNULL))

        def listening():
            try:
                stack.socket.create_connection(("127.0.0.1", port), timeout=1).close()
                return True
            except OSError:
                return False
        self.assertTrue(stack.wait_until(listening, 10), "stunnel never listened")
        return port

    def test_the_daemon_reaches_redis_through_the_shipped_stunnel_configuration(self):
        wrong = self.tunnel("another.isomesh.test", "wrong")
        with self.assertRaises((OSError, stack.RedisError)):
            stack.redis_command(wrong, "PING", timeout=10)  # the host name is checked
        right = self.tunnel(TLS_HOST, "right")
        self.assertEqual(stack.redis_command(right, "PING", timeout=10), "PONG")
        with harness.Daemon("--workers", "1", "--redis", "127.0.0.1:%d" % right) as d:
            self.assertTrue(stack.wait_until(lambda: d.metric("isomesh_redis_up") == 1, 10),
                            d.log())
            r = d.post("/v1/mesh", harness.sphere(0.79))
            self.assertEqual(r.status, 200)
            self.assertTrue(stack.wait_stored(self.redis, r.header("ETag").strip('"')))


if __name__ == "__main__":
    unittest.main()
