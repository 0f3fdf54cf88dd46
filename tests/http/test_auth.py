"""test_auth.py — bearer tokens on a real isomeshd: `isomeshd token add` prints a token once and
the file keeps only its BLAKE2b-256 hash (checked with Python's own hashlib), `token remove`
and `token list`; computing without a token or with a wrong one is 401 with WWW-Authenticate,
with a good one 200; reading computed meshes, presets and health stays open unless --private;
a token removed from the file stops working after SIGHUP while open connections carry on; a
file that does not parse on SIGHUP keeps the old tokens; GET /v1/jobs lists the caller's own
jobs (every job for an admin) and only the owner or an admin may cancel."""
import hashlib
import http.client
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ISOMESHD, SLOW, Daemon, draco_counts, sphere  # noqa: E402

TOKEN_RE = re.compile(r"^ism_[A-Za-z0-9_-]{43}$")


def token_cmd(*args, env=None):
    return subprocess.run([ISOMESHD, "token"] + list(args), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=30, env=env)


def add_token(path, name, *opts):
    r = token_cmd("add", name, "--file", path, *opts)
    if r.returncode != 0:
        raise AssertionError("token add failed: " + r.stderr)
    return r.stdout.strip()


def bearer(token):
    return {"Authorization": "Bearer " + token}


def blake2b_hex(token):
    return hashlib.blake2b(token.encode(), digest_size=32).hexdigest()


def wait_log(d, pattern, count=1, timeout=10):
    """Waits until pattern appears count times in the daemon's log."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        with d.lock:
            n = sum(1 for line in d.lines if pattern in line)
        if n >= count:
            return True
        time.sleep(0.02)
    return False


def sighup(d, expect, count=1):
    d.proc.send_signal(signal.SIGHUP)
    if not wait_log(d, expect, count):
        raise AssertionError("no %r in the log after SIGHUP:\n%s" % (expect, d.log()))


def wait_job(d, job, token, timeout=60):
    deadline = time.time() + timeout
    while time.time() < deadline:
        j = d.get(job["url"], headers=bearer(token)).json()
        if j["state"] not in ("queued", "running"):
            return j
        time.sleep(0.02)
    raise AssertionError("job never finished: %r" % job)


class TokenCommandTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.tmp.name, "tokens")

    def tearDown(self):
        self.tmp.cleanup()

    def test_add_prints_a_token_once_and_the_file_keeps_only_its_hash(self):
        first = token_cmd("add", "alice", "--file", self.path, "--jobs", "4")
        self.assertEqual(first.returncode, 0, first.stderr)
        lines = first.stdout.splitlines()
        self.assertEqual(len(lines), 1, first.stdout)  # the token, once, and nothing else
        alice = lines[0]
        self.assertRegex(alice, TOKEN_RE)
        self.assertNotIn(alice, first.stderr)
        bob = add_token(self.path, "bob", "--admin")
        self.assertNotEqual(alice, bob)
        with open(self.path) as f:
            text = f.read()
        for token in (alice, bob):
            self.assertNotIn(token, text)
            self.assertNotIn(token[4:], text)  # not even without its prefix
        entries = [l.split() for l in text.splitlines() if l and not l.startswith("#")]
        self.assertEqual(entries, [["blake2b:" + blake2b_hex(alice), "alice", "jobs=4"],
                                   ["blake2b:" + blake2b_hex(bob), "bob", "admin"]])
        self.assertEqual(stat.S_IMODE(os.stat(self.path).st_mode), 0o600)
        self.assertFalse(os.path.exists(self.path + ".new"))
        # a second token for alice takes her options; conflicting ones are refused
        alice2 = add_token(self.path, "alice")
        self.assertNotEqual(alice2, alice)
        conflict = token_cmd("add", "alice", "--file", self.path, "--jobs", "9")
        self.assertEqual(conflict.returncode, 1)
        self.assertEqual(conflict.stdout, "")
        listing = token_cmd("list", "--file", self.path)
        self.assertEqual(listing.returncode, 0, listing.stderr)
        self.assertIn("alice tokens=2 jobs=4", listing.stdout)
        self.assertIn("bob tokens=1", listing.stdout)
        self.assertIn("admin", listing.stdout)
        # remove drops every line of the user and keeps the rest (comments too)
        removed = token_cmd("remove", "alice", "--file", self.path)
        self.assertEqual(removed.returncode, 0, removed.stderr)
        with open(self.path) as f:
            after = f.read()
        self.assertNotIn(" alice", after)
        self.assertIn(blake2b_hex(bob) + " bob admin", after)
        self.assertTrue(after.startswith("#"))
        self.assertEqual(token_cmd("remove", "alice", "--file", self.path).returncode, 1)

    def test_bad_names_usage_and_a_broken_file_are_refused(self):
        for name in ("", "white space", "a/b", "x" * 49, "semi;colon"):
            r = token_cmd("add", name, "--file", self.path)
            self.assertEqual(r.returncode, 2, name)
            self.assertEqual(r.stdout, "")
        self.assertFalse(os.path.exists(self.path))
        self.assertEqual(token_cmd().returncode, 2)
        self.assertEqual(token_cmd("grant", "x").returncode, 2)
        self.assertEqual(token_cmd("add", "x", "--jobs", "0", "--file", self.path).returncode, 2)
        with open(self.path, "w") as f:
            f.write("not a token line\n")
        r = token_cmd("add", "carol", "--file", self.path)
        self.assertEqual(r.returncode, 1)
        self.assertEqual(r.stdout, "")  # no token printed for a file that was not changed
        self.assertIn(":1:", r.stderr)
        with open(self.path) as f:
            self.assertEqual(f.read(), "not a token line\n")
        # a stale FILE.new (an interrupted command) is the lock: nothing happens
        os.remove(self.path)
        open(self.path + ".new", "w").close()
        r = token_cmd("add", "carol", "--file", self.path)
        self.assertEqual(r.returncode, 1)
        self.assertIn(".new", r.stderr)
        self.assertFalse(os.path.exists(self.path))

    def test_default_file_under_xdg_config_home(self):
        env = dict(os.environ, XDG_CONFIG_HOME=self.tmp.name)
        r = token_cmd("add", "dave", env=env)
        self.assertEqual(r.returncode, 0, r.stderr)
        path = os.path.join(self.tmp.name, "isomesh", "tokens")
        with open(path) as f:
            self.assertIn(blake2b_hex(r.stdout.strip()) + " dave", f.read())


class AuthConfigTest(unittest.TestCase):
    def test_help_documents_the_sharing_flags_and_the_token_command(self):
        r = subprocess.run([ISOMESHD, "--help"], stdout=subprocess.PIPE, text=True, timeout=10)
        self.assertEqual(r.returncode, 0)
        for flag in ("--tokens FILE", "--private", "--user-jobs N", "--user-running N",
                     "--queue-order fair|fifo", "--client-jobs", "SIGHUP", "token add NAME"):
            self.assertIn(flag, r.stdout)

    def test_private_in_a_config_file_and_bad_values(self):
        with tempfile.TemporaryDirectory() as tmp:
            tokens = os.path.join(tmp, "tokens")
            add_token(tokens, "alice")
            conf = os.path.join(tmp, "isomeshd.conf")
            with open(conf, "w") as f:
                f.write("tokens = %s\nprivate = yes\nuser-jobs = 2\nqueue-order = fifo\n" % tokens)
            with Daemon("--workers", "1", "--config", conf) as d:
                self.assertEqual(d.get("/v1/presets").status, 401)
                # logged after "listening" (which start() waited for), maybe in a later batch
                self.assertEqual(d.log_count("private=yes", 1), 1, d.log())
            for args in (["--private=maybe"], ["--queue-order", "lifo"], ["--user-jobs", "0"],
                         ["--user-running", "-1"]):
                r = subprocess.run([ISOMESHD] + args, stderr=subprocess.PIPE, text=True, timeout=10)
                self.assertEqual(r.returncode, 2, args)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


class AuthDaemonTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.tmp.name, "tokens")
        self.alice = add_token(self.path, "alice")
        self.bob = add_token(self.path, "bob")
        self.root = add_token(self.path, "root", "--admin")

    def tearDown(self):
        self.tmp.cleanup()

    def assert_401(self, r, code):
        self.assertEqual(r.status, 401, r.body[:300])
        self.assertEqual(r.json()["error"]["code"], code)
        self.assertTrue(r.header("WWW-Authenticate").startswith('Bearer realm="isomesh"'))

    def test_compute_needs_a_valid_token_and_reading_stays_open(self):
        with Daemon("--workers", "1", "--tokens", self.path) as d:
            self.assert_401(d.post("/v1/mesh", sphere(0.5)), "unauthorized")
            self.assert_401(d.post("/v1/jobs", sphere(0.5)), "unauthorized")
            wrong = d.post("/v1/mesh", sphere(0.5), headers=bearer("ism_" + "A" * 43))
            self.assert_401(wrong, "invalid_token")
            self.assertIn('error="invalid_token"', wrong.header("WWW-Authenticate"))
            self.assert_401(d.post("/v1/mesh", sphere(0.5), headers={"Authorization": "Basic eDp5"}),
                            "unauthorized")
            self.assert_401(d.post("/v1/mesh", sphere(0.5), headers=bearer(self.alice + "x")),
                            "invalid_token")
            self.assert_401(d.post("/v1/mesh", sphere(0.5), headers=bearer(self.alice[:-1])),
                            "invalid_token")
            self.assertEqual(d.metric("isomesh_computations_started_total"), 0)
            ok = d.post("/v1/mesh", sphere(0.5), headers=bearer(self.alice))
            self.assertEqual(ok.status, 200, ok.body[:300])
            self.assertGreater(draco_counts(ok.body)[1], 0)
            # the scheme is case-insensitive
            lower = d.post("/v1/mesh", sphere(0.5), headers={"Authorization": "bearer " + self.bob})
            self.assertEqual(lower.status, 200)
            # reading what is computed, presets, documents, health, metrics and the viewer: open
            for path in (ok.header("Location"), "/v1/presets", "/v1/openapi.yaml", "/healthz",
                         "/readyz", "/metrics", "/", "/v1/meshes/%s/stats" % ok.header("ETag")[1:-1]):
                self.assertEqual(d.get(path).status, 200, path)
            # another format of that mesh is a computation: it needs a token
            key = ok.header("ETag")[1:-1]
            self.assert_401(d.get("/v1/meshes/%s.ply" % key), "unauthorized")
            self.assertEqual(d.get("/v1/meshes/%s.ply" % key, headers=bearer(self.bob)).status, 200)
            self.assertEqual(d.get("/v1/meshes/%s.ply" % key).status, 200)  # now computed
            self.assertEqual(d.metric("isomesh_rejected_total", reason="unauthorized"), 7)
            self.assertEqual(d.metric("isomesh_http_requests_total", route="/v1/mesh",
                                      status="401"), 5)
            # the log's writer thread gathers lines for 50 ms (server/common/log.c): await it
            deadline = time.monotonic() + 30
            while "user=alice" not in d.log() and time.monotonic() < deadline:
                time.sleep(0.05)
            self.assertIn("user=alice", d.log())

    def test_revoked_token_after_sighup_is_401_and_connections_carry_on(self):
        with Daemon("--workers", "1", "--tokens", self.path) as d:
            self.assertEqual(d.post("/v1/mesh", sphere(0.6), headers=bearer(self.bob)).status, 200)
            # a keep-alive connection opened before the reload
            conn = http.client.HTTPConnection("127.0.0.1", d.port, timeout=30)
            try:
                conn.request("GET", "/healthz")
                self.assertEqual(conn.getresponse().read(), b'{"status":"ok"}')
                sock = conn.sock
                r = token_cmd("remove", "bob", "--file", self.path)
                self.assertEqual(r.returncode, 0, r.stderr)
                sighup(d, "tokens_reloaded")
                conn.request("GET", "/healthz")  # same socket, still served
                self.assertEqual(conn.getresponse().read(), b'{"status":"ok"}')
                conn.request("POST", "/v1/mesh", body=b'{"preset": "sphere"}',
                             headers=bearer(self.bob))
                resp = conn.getresponse()
                self.assertEqual(resp.status, 401)
                resp.read()
                self.assertIs(conn.sock, sock)  # no reconnection happened
            finally:
                conn.close()
            self.assert_401(d.post("/v1/mesh", sphere(0.6), headers=bearer(self.bob)),
                            "invalid_token")
            self.assertEqual(d.post("/v1/mesh", sphere(0.6), headers=bearer(self.alice)).status, 200)
            # a token added while running works after the next SIGHUP, not before
            carol = add_token(self.path, "carol")
            self.assert_401(d.post("/v1/mesh", sphere(0.61), headers=bearer(carol)), "invalid_token")
            sighup(d, "tokens_reloaded", count=2)
            self.assertEqual(d.post("/v1/mesh", sphere(0.61), headers=bearer(carol)).status, 200)

    def test_a_file_with_a_syntax_error_on_sighup_keeps_the_old_tokens(self):
        with Daemon("--workers", "1", "--tokens", self.path) as d:
            with open(self.path) as f:
                good = f.read()
            dave = add_token(self.path, "dave")
            with open(self.path, "a") as f:
                f.write("blake2b:1234 eve\n")  # a hash that is too short
            sighup(d, "tokens_reload_failed")
            self.assertIn(":9:", d.log())  # file and line of the error
            self.assertEqual(d.post("/v1/mesh", sphere(0.62), headers=bearer(self.alice)).status, 200)
            self.assert_401(d.post("/v1/mesh", sphere(0.62), headers=bearer(dave)), "invalid_token")
            # an unreadable (here: missing) file keeps them too
            os.rename(self.path, self.path + ".away")
            sighup(d, "tokens_reload_failed", count=2)
            self.assertEqual(d.post("/v1/mesh", sphere(0.63), headers=bearer(self.bob)).status, 200)
            with open(self.path, "w") as f:
                f.write(good)
            sighup(d, "tokens_reloaded")
            self.assertEqual(d.post("/v1/mesh", sphere(0.64), headers=bearer(self.root)).status, 200)
            self.assert_401(d.post("/v1/mesh", sphere(0.64), headers=bearer(dave)), "invalid_token")

    def test_the_daemon_refuses_to_start_with_a_bad_tokens_file(self):
        bad = os.path.join(self.tmp.name, "bad")
        with open(bad, "w") as f:
            f.write("blake2b:%s alice frobnicate\n" % ("0" * 64))
        for args, status in ((["--tokens", bad], 1),
                             (["--tokens", os.path.join(self.tmp.name, "missing")], 1),
                             (["--private"], 2)):
            r = subprocess.run([ISOMESHD, "--listen", "127.0.0.1:0", "--workers", "1",
                                "--cache-dir", os.path.join(self.tmp.name, "c")] + args,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
            self.assertEqual(r.returncode, status, r.stderr)
            self.assertNotIn("listening", r.stderr)
        self.assertIn("frobnicate", subprocess.run(
            [ISOMESHD, "--listen", "127.0.0.1:0", "--tokens", bad], stderr=subprocess.PIPE,
            text=True, timeout=30).stderr)

    def test_a_fifo_or_a_writable_tokens_file_is_refused_and_sigterm_still_works(self):
        # at start: a FIFO (nobody ever writes it: a blocking open would hang forever) and a
        # file others may write are refused at once with a line saying why
        fifo = os.path.join(self.tmp.name, "fifo")
        os.mkfifo(fifo)
        loose = os.path.join(self.tmp.name, "loose")
        with open(self.path) as f, open(loose, "w") as g:
            g.write(f.read())
        for mode, what in ((0o666, "writable by group or others"), (0o620, "writable by group")):
            os.chmod(loose, mode)
            for path, expect in ((fifo, "not a regular file"), (loose, what)):
                t0 = time.monotonic()
                r = subprocess.run([ISOMESHD, "--listen", "127.0.0.1:0", "--workers", "1",
                                    "--cache-dir", os.path.join(self.tmp.name, "c"), "--tokens", path],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
                self.assertLess(time.monotonic() - t0, 10)
                self.assertEqual(r.returncode, 1, r.stderr)
                self.assertIn(expect, r.stderr)
        # `token add` refuses to edit them too (it would hang on the FIFO otherwise)
        self.assertNotEqual(token_cmd("add", "eve", "--file", fifo).returncode, 0)
        self.assertNotEqual(token_cmd("add", "eve", "--file", loose).returncode, 0)
        # while running: a FIFO swapped in, then a writable file; SIGHUP keeps the old tokens
        with Daemon("--workers", "1", "--tokens", self.path) as d:
            os.rename(self.path, self.path + ".good")
            os.mkfifo(self.path)
            sighup(d, "tokens_reload_failed")
            self.assertIn("not a regular file", d.log())
            self.assertEqual(d.post("/v1/mesh", sphere(0.65), headers=bearer(self.alice)).status, 200)
            os.unlink(self.path)
            shutil.copy(self.path + ".good", self.path)
            os.chmod(self.path, 0o646)
            sighup(d, "tokens_reload_failed", count=2)
            self.assertEqual(d.post("/v1/mesh", sphere(0.66), headers=bearer(self.bob)).status, 200)
            # and SIGTERM after all that stops it promptly
            os.unlink(self.path)
            os.mkfifo(self.path)
            sighup(d, "tokens_reload_failed", count=3)
            t0 = time.monotonic()
            d.proc.send_signal(signal.SIGTERM)
            d.proc.wait(timeout=10)
            self.assertLess(time.monotonic() - t0, 2.0)
            self.assertEqual(d.proc.returncode, 0)

    def test_private_mode_closes_reading_but_not_the_viewer_or_health(self):
        with Daemon("--workers", "1", "--tokens", self.path, "--private") as d:
            ok = d.post("/v1/mesh", sphere(0.5), headers=bearer(self.alice))
            self.assertEqual(ok.status, 200)
            key = ok.header("ETag")[1:-1]
            job = d.post("/v1/jobs", sphere(0.5), headers=bearer(self.alice)).json()
            for path in (ok.header("Location"), "/v1/meshes/%s/stats" % key, "/v1/presets",
                         "/v1/openapi.yaml", "/metrics", job["url"], job["events_url"]):
                self.assert_401(d.get(path), "unauthorized")
                self.assertEqual(d.get(path, headers=bearer(self.alice)).status, 200, path)
            for path in ("/healthz", "/readyz", "/", "/js/main.js"):
                self.assertEqual(d.get(path).status, 200, path)
            # someone else's job: forbidden, except for an admin
            self.assertEqual(d.get(job["url"], headers=bearer(self.bob)).status, 403)
            self.assertEqual(d.get(job["url"], headers=bearer(self.root)).status, 200)

    def test_jobs_list_shows_the_callers_jobs_and_an_admin_sees_all(self):
        with Daemon("--workers", "1", "--tokens", self.path) as d:
            self.assert_401(d.get("/v1/jobs"), "unauthorized")
            a1 = d.post("/v1/jobs", sphere(0.51), headers=bearer(self.alice)).json()
            a2 = d.post("/v1/jobs", sphere(0.52), headers=bearer(self.alice)).json()
            b1 = d.post("/v1/jobs", sphere(0.53), headers=bearer(self.bob)).json()
            for job, token in ((a1, self.alice), (a2, self.alice), (b1, self.bob)):
                self.assertEqual(wait_job(d, job, token)["state"], "done")
            mine = d.get("/v1/jobs", headers=bearer(self.alice)).json()
            self.assertEqual(mine["user"], "alice")
            self.assertFalse(mine["admin"])
            self.assertEqual([j["id"] for j in mine["jobs"]], [a2["id"], a1["id"]])  # newest first
            self.assertTrue(all(j["user"] == "alice" and j["state"] == "done" for j in mine["jobs"]))
            self.assertTrue(all("stats" not in j for j in mine["jobs"]))
            self.assertEqual([j["id"] for j in d.get("/v1/jobs", headers=bearer(self.bob)).json()["jobs"]],
                             [b1["id"]])
            every = d.get("/v1/jobs", headers=bearer(self.root)).json()
            self.assertTrue(every["admin"])
            self.assertEqual({j["id"]: j["user"] for j in every["jobs"]},
                             {a1["id"]: "alice", a2["id"]: "alice", b1["id"]: "bob"})
            # only the owner or an admin cancels
            slow = d.post("/v1/jobs", SLOW, headers=bearer(self.alice)).json()
            self.assert_401(d.request("DELETE", slow["url"]), "unauthorized")
            nope = d.request("DELETE", slow["url"], headers=bearer(self.bob))
            self.assertEqual(nope.status, 403)
            self.assertEqual(nope.json()["error"]["code"], "not_your_job")
            self.assertIn(d.get(slow["url"]).json()["state"], ("queued", "running"))
            done = d.request("DELETE", slow["url"], headers=bearer(self.root))
            self.assertEqual(done.json()["state"], "canceled")

    def test_jobs_list_without_tokens_is_per_client_address(self):
        with Daemon("--workers", "1") as d:
            job = d.post("/v1/jobs", sphere(0.55)).json()
            self.assertEqual(job["user"], "127.0.0.1")
            listed = d.get("/v1/jobs").json()
            self.assertEqual(listed["user"], "127.0.0.1")
            self.assertEqual([j["id"] for j in listed["jobs"]], [job["id"]])
            other = http.client.HTTPConnection("127.0.0.1", d.port, timeout=30,
                                               source_address=("127.0.0.2", 0))
            try:
                other.request("GET", "/v1/jobs")
                r = other.getresponse()
                body = r.read()
            finally:
                other.close()
            self.assertEqual(r.status, 200)
            self.assertIn(b'"jobs":[]', body)
            self.assertIn(b'"user":"127.0.0.2"', body)


if __name__ == "__main__":
    unittest.main()
