"""test_configs.py — the files of deploy/ as the tools that read them judge them:

* the systemd units (isomeshd.service, an instance of isomeshd@.service, isomesh.slice) pass
  `systemd-analyze verify` without a single warning (with ExecStart pointed at the built
  daemon), and `systemd-analyze security --offline` finds the sandbox the README promises;
* deploy/nginx/isomesh.conf passes `nginx -t` as shipped, and with its TLS lines enabled
  (a self-signed certificate made here) serves HTTPS in front of a daemon;
* Redis started with deploy/redis/isomesh.conf is a pure cache (LRU eviction, no saving);
* deploy/install.sh into a scratch directory gives a working installation: the ExecStart of
  the installed template unit, run as written, serves the viewer, three.js, the documents and
  meshes, with the installed settings file in effect."""
import os
import re
import shutil
import socket
import ssl
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack  # noqa: E402
from stack import harness  # noqa: E402

UNITS = os.path.join(stack.DEPLOY, "systemd")
ISOMESHD = os.path.abspath(harness.ISOMESHD)


def unit_copy(dirname, name, exec_path, instance=None):
    """A copy of deploy/systemd/name in dirname with ExecStart's program replaced by
    exec_path; an instance name for a template. Returns the copy's path."""
    with open(os.path.join(UNITS, name)) as f:
        text = f.read()
    text = text.replace("/usr/local/lib/isomesh/isomeshd", os.path.abspath(exec_path))
    target = name.replace("@.", "@%s." % instance) if instance else name
    path = os.path.join(dirname, target)
    with open(path, "w") as f:
        f.write(text)
    return path


def verify(path):
    r = subprocess.run([stack.SYSTEMD_ANALYZE, "verify", "--man=no", path],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60,
                       cwd=os.path.dirname(path))
    return r.returncode, r.stdout.strip()


@unittest.skipIf(not stack.SYSTEMD_ANALYZE, "systemd-analyze is missing (Debian package systemd)")
class SystemdTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="isomesh_units_")
        if not os.access(harness.ISOMESHD, os.X_OK):
            self.skipTest(harness.ISOMESHD + " is missing (make build)")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_units_pass_verify_without_warnings(self):
        unit_copy(self.tmp, "isomesh.slice", harness.ISOMESHD)
        for name, instance in (("isomesh.slice", None), ("isomeshd.service", None),
                               ("isomeshd@.service", "8081")):
            path = unit_copy(self.tmp, name, harness.ISOMESHD, instance)
            rc, out = verify(path)
            self.assertEqual(rc, 0, out)
            self.assertEqual(out, "", "%s: systemd-analyze had remarks" % name)
        # the check has teeth: a misspelt setting and a missing program are reported
        bad = unit_copy(self.tmp, "isomeshd.service", "/nonexistent/isomeshd")
        with open(bad, "a") as f:
            f.write("[Service]\nProtectSystem=strictly\n")
        rc, out = verify(bad)
        self.assertNotEqual(rc, 0)
        self.assertIn("strictly", out)

    def test_the_sandbox_is_what_the_readme_says(self):
        for name, instance in (("isomeshd.service", None), ("isomeshd@.service", "8082")):
            path = unit_copy(self.tmp, name, harness.ISOMESHD, instance)
            r = subprocess.run([stack.SYSTEMD_ANALYZE, "security", "--offline=yes", path],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               timeout=60)
            m = re.search(r"Overall exposure level for \S+: ([0-9.]+) (\w+)", r.stdout)
            self.assertIsNotNone(m, r.stdout[-2000:])
            self.assertLessEqual(float(m.group(1)), 2.0, r.stdout[-3000:])
            passed = {line.split()[1] for line in r.stdout.splitlines()
                      if line.startswith("\u2713") and len(line.split()) > 1}
            for setting in ("User=/DynamicUser=", "ProtectSystem=", "ProtectHome=",
                            "PrivateTmp=", "PrivateDevices=", "NoNewPrivileges=",
                            "RestrictNamespaces=~user", "LockPersonality=",
                            "MemoryDenyWriteExecute=", "RestrictRealtime=",
                            "SystemCallArchitectures=", "SystemCallFilter=~@privileged",
                            "SystemCallFilter=~@mount", "RestrictAddressFamilies=~AF_PACKET",
                            "ProtectKernelTunables=", "ProtectControlGroups=",
                            "CapabilityBoundingSet=~CAP_SYS_ADMIN", "RestrictSUIDSGID="):
                self.assertIn(setting, passed, "%s: %s not in place" % (name, setting))
            with open(path) as f:
                text = f.read()
            for setting in ("StateDirectory=isomesh", "Restart=on-failure", "MemoryMax=",
                            "TasksMax=", "SystemCallFilter=@system-service"):
                self.assertIn("\n" + setting, text)


def make_certificate(dirname):
    cert, key = os.path.join(dirname, "cert.pem"), os.path.join(dirname, "key.pem")
    r = subprocess.run([stack.OPENSSL, "req", "-x509", "-newkey", "rsa:2048", "-nodes",
                        "-keyout", key, "-out", cert, "-days", "2", "-subj", "/CN=localhost"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
    if r.returncode != 0:
        raise AssertionError("openssl: " + r.stdout)
    return cert, key


@unittest.skipIf(not stack.NGINX, "nginx is missing (Debian package nginx)")
class NginxTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="isomesh_nginx_t_")
        os.makedirs(os.path.join(self.tmp, "tmp"))

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def nginx_t(self, site_path):
        conf = os.path.join(self.tmp, "nginx.conf")
        with open(conf, "w") as f:
            f.write(stack.nginx_main(self.tmp, site_path))
        return stack.nginx_test(self.tmp, conf)

    def test_the_site_as_shipped_passes_nginx_t(self):
        # As shipped but for the listening port (nginx -t binds it: port 80 needs root and
        # may be taken on the test machine) and the mesh cache's directory (nginx -t creates
        # it; install.sh does on a server).
        site = os.path.join(self.tmp, "site.conf")
        with open(site, "w") as f:
            f.write(stack.nginx_site(None, stack.free_port(),
                                     cache_dir=os.path.join(self.tmp, "meshes")))
        rc, out = self.nginx_t(site)
        self.assertEqual(rc, 0, out)
        self.assertIn("syntax is ok", out)
        self.assertNotIn("[warn]", out)
        # and nginx -t does reject a broken copy
        broken = os.path.join(self.tmp, "broken.conf")
        with open(site) as f, open(broken, "w") as g:
            g.write(f.read().replace("client_max_body_size 256k;", "client_max_body_size;"))
        rc, out = self.nginx_t(broken)
        self.assertNotEqual(rc, 0)

    @unittest.skipIf(not stack.OPENSSL, "openssl is missing")
    def test_tls_lines_enabled_serve_https(self):
        if stack.missing_programs():
            self.skipTest(stack.missing_programs())
        cert, key = make_certificate(self.tmp)
        with harness.Daemon("--workers", "1") as d:
            tls_port = stack.free_port()
            ng = stack.Nginx([d.port], tls=(tls_port, cert, key))
            try:
                with open(ng.site) as f:
                    site = f.read()
                self.assertRegex(site, r"\n\s*ssl_certificate\s+%s;" % re.escape(cert))
                self.assertIn("listen 127.0.0.1:%d ssl http2;" % tls_port, site)
                ng.start()
                ctx = ssl.create_default_context(cafile=cert)
                ctx.check_hostname = False
                import http.client
                conn = http.client.HTTPSConnection("127.0.0.1", tls_port, context=ctx, timeout=30)
                try:
                    conn.request("POST", "/v1/mesh", body=b'{"preset": "sphere"}',
                                 headers={"Content-Type": "application/json"})
                    r = conn.getresponse()
                    body = r.read()
                    self.assertEqual(r.status, 200)
                    self.assertEqual(r.getheader("Strict-Transport-Security"), "max-age=31536000")
                    self.assertGreater(harness.draco_counts(body)[1], 0)
                finally:
                    conn.close()
            finally:
                ng.cleanup()


@unittest.skipIf(not stack.REDIS_SERVER, "redis-server is missing (Debian package redis-server)")
class RedisSettingsTest(unittest.TestCase):
    def test_redis_is_a_pure_cache(self):
        # Only the port and directory are given here; the rest comes from the file.
        port = stack.free_port()
        tmp = tempfile.mkdtemp(prefix="isomesh_redis_conf_")
        proc = harness.spawn_owned([stack.REDIS_SERVER, stack.REDIS_CONF, "--port", str(port),
                                    "--dir", tmp], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        try:
            def ping():
                try:
                    return stack.redis_command(port, "PING", timeout=1) == "PONG"
                except OSError:
                    return False
            self.assertTrue(stack.wait_until(ping, 10))

            def get(name):
                return stack.redis_command(port, "CONFIG", "GET", name)[1].decode()
            self.assertEqual(get("maxmemory-policy"), "allkeys-lru")
            self.assertEqual(get("save"), "")
            self.assertEqual(get("appendonly"), "no")
            self.assertEqual(int(get("maxmemory")), 2 << 30)
            self.assertIn("127.0.0.1", get("bind"))
        finally:
            stack.stop_process(proc)
            shutil.rmtree(tmp, ignore_errors=True)


class InstallTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="isomesh_install_")
        if not os.access(harness.ISOMESHD, os.X_OK):
            self.skipTest(harness.ISOMESHD + " is missing (make build)")
        if not os.path.isdir(os.path.join(stack.ROOT, "web", "node_modules", "three", "build")):
            self.skipTest("web/node_modules/three is missing (make web-deps)")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_installed_files_run_as_the_template_unit_says(self):
        dest = os.path.join(self.tmp, "root")
        r = subprocess.run(["sh", os.path.join(stack.DEPLOY, "install.sh"), "--build",
                            os.path.abspath(harness.BUILD), "--destdir", dest], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=300)
        self.assertEqual(r.returncode, 0, r.stdout)
        lib = os.path.join(dest, "usr/local/lib/isomesh")
        share = os.path.join(dest, "usr/local/share/isomesh")
        for p in ("usr/local/lib/isomesh/isomeshd", "usr/local/lib/isomesh/isomesh",
                  "usr/local/bin/isomesh", "usr/local/sbin/isomeshd",
                  "etc/systemd/system/isomeshd.service", "etc/systemd/system/isomeshd@.service",
                  "etc/systemd/system/isomesh.slice", "etc/isomesh/isomeshd.conf",
                  "etc/nginx/sites-enabled/isomesh", "etc/redis/isomesh.conf",
                  "usr/local/share/isomesh/deploy/README.md"):
            self.assertTrue(os.path.exists(os.path.join(dest, p)), p)
        self.assertEqual(os.stat(os.path.join(dest, "etc/isomesh/tokens")).st_mode & 0o777, 0o644)

        # ExecStart of the installed template unit, with systemd's specifiers and the
        # installation's paths resolved for this scratch directory.
        with open(os.path.join(dest, "etc/systemd/system/isomeshd@.service")) as f:
            exec_start = re.search(r"^ExecStart=(.*)$", f.read(), re.M).group(1)
        port = stack.free_port()
        state = os.path.join(self.tmp, "state")
        argv = [a.replace("%S", state).replace("%i", str(port))
                 .replace("/usr/local/", dest + "/usr/local/").replace("/etc/isomesh/", dest + "/etc/isomesh/")
                for a in exec_start.split()]
        with open(os.path.join(dest, "etc/isomesh/isomeshd.conf")) as f:
            conf = f.read()
        conf = conf.replace("/usr/local/", dest + "/usr/local/")
        with open(os.path.join(dest, "etc/isomesh/isomeshd.conf"), "w") as f:
            f.write(conf)
        self.assertEqual(argv[0], os.path.join(lib, "isomeshd"))

        d = harness.Daemon()
        d.proc = harness.spawn_owned(argv + ["--workers", "1"], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                     text=True, errors="replace")
        d.reader = threading.Thread(target=d._read_stderr, daemon=True)
        d.reader.start()
        d.port = port
        try:
            d.wait_ready(timeout=30)
            self.assertTrue(stack.wait_until(lambda: " listening " in d.log(), 10), d.log())
            log = d.log()
            self.assertIn("cache_dir=%s/isomesh" % state, log)
            self.assertNotIn("document_missing", log)
            self.assertNotIn("vendor_missing", log)
            page = d.get("/")
            self.assertEqual(page.status, 200)
            self.assertIn(b"<html", page.body.lower())
            self.assertEqual(d.get("/vendor/three/build/three.module.js").status, 200)
            self.assertEqual(d.get("/v1/openapi.yaml").status, 200)
            self.assertEqual(d.get("/v1/request.schema.json").status, 200)
            mesh = d.post("/v1/mesh", {"preset": "torus"})
            self.assertEqual(mesh.status, 200)
            self.assertGreater(harness.draco_counts(mesh.body)[1], 0)
            # the installed settings file is the one in effect
            self.assertEqual(d.metric("isomesh_queue_capacity"), 128)
            self.assertTrue(os.path.isdir(os.path.join(state, "isomesh", "v1")))
        finally:
            rc = d.stop()
            d.cleanup()
        self.assertEqual(rc, 0)


if __name__ == "__main__":
    unittest.main()
