"""test_config.py — isomeshd's settings and logs: --help names every flag, a bad flag or value
is a one-line error with exit status 2, --config FILE is read (and command-line flags win over
it), its errors name the file and line, and --log-format json writes one JSON object per line
with one request line per request (method, path, status, bytes, ms, cache, key); the defaults
that README.md's prose and deploy/README.md's limits table state are --help's, and the values
that table gives for deploy/isomeshd.conf are the file's."""
import json
import os
import http.client
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ISOMESHD, Daemon, sphere  # noqa: E402

FLAGS = ["--listen", "--workers", "--queue", "--client-jobs", "--cache-dir", "--cache-mem",
         "--job-timeout", "--job-memory", "--max-body", "--max-depth", "--max-triangles",
         "--web-root", "--data-dir", "--cors-origin", "--log-format", "--config"]


ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
UNITS = {"": 1, "k": 1 << 10, "kib": 1 << 10, "kb": 1 << 10, "m": 1 << 20, "mib": 1 << 20,
         "mb": 1 << 20, "g": 1 << 30, "gib": 1 << 30, "gb": 1 << 30, "t": 1 << 40,
         "ms": 1e-3, "s": 1, "min": 60, "h": 3600}
QUANTITY = re.compile(r"^(\d[\d ,\u2009\u202f]*(?:\.\d+)?)\s*([A-Za-z]*)$")


def quantity(text):
    """A number written as in the docs or in a flag value ("4 000 000", "4,000", "256 KiB",
    "64M", "60 s", "10s") in bytes, seconds or units; None when it is words."""
    m = QUANTITY.match(text.strip())
    if not m or m.group(2).lower() not in UNITS:
        return None
    digits = re.sub(r"[ ,\u2009\u202f]", "", m.group(1))
    return float(digits) * UNITS[m.group(2).lower()]


def help_defaults():
    """{flag name: the default --help prints in brackets at the end of its line}."""
    text = run("--help").stdout
    return {m.group(1): m.group(2)
            for m in re.finditer(r"^  --([a-z-]+) .*\[([^\]\n]*)\]$", text, re.M)}


def limits_table_pairs(text, flags):
    """(flag, documented default, isomeshd.conf's value or None) for each quantity in
    deploy/README.md's limits table: the i-th flag named in a row's `where` cell goes with
    the i-th comma-separated item of its default cell (items after "`isomeshd.conf`:" are
    the settings file's)."""
    table = text[text.index("| limit | where | default |"):]
    for row in table.splitlines()[2:]:
        if not row.startswith("|"):
            break
        cells = [c.strip() for c in row.strip("|").split("|")]
        named = [n for n in re.findall(r"`([a-z-]+)`", cells[1]) if n in flags]
        named = list(dict.fromkeys(named))
        own, _, conf = cells[2].partition("; `isomeshd.conf`:")
        own, conf = own.split(","), conf.split(",") if conf else []
        for i, name in enumerate(named):
            if i < len(own) and quantity(own[i]) is not None:
                yield name, own[i], conf[i] if i < len(conf) else None


def conf_values(path):
    """{name: value} of a `name = value` settings file."""
    out = {}
    with open(path) as f:
        for line in f:
            line = line.split("#")[0].strip()
            if "=" in line:
                k, v = line.split("=", 1)
                out[k.strip()] = v.strip()
    return out


def run(*args, timeout=10):
    return subprocess.run([ISOMESHD] + list(args), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=timeout)


class ConfigTest(unittest.TestCase):
    def test_help_documents_every_flag(self):
        r = run("--help")
        self.assertEqual(r.returncode, 0)
        for flag in FLAGS:
            self.assertIn(flag, r.stdout)
        self.assertIn("/v1/mesh", r.stdout)
        v = run("--version")
        self.assertEqual(v.returncode, 0)
        self.assertIn("isomeshd", v.stdout)

    def test_documented_defaults_are_the_daemons(self):
        defaults = help_defaults()
        self.assertEqual(quantity(defaults["queue"]), 64.0)  # the parse sees --help's table
        with open(os.path.join(ROOT, "deploy", "README.md")) as f:
            pairs = list(limits_table_pairs(f.read(), defaults))
        conf = conf_values(os.path.join(ROOT, "deploy", "isomeshd.conf"))
        checked = set()
        for name, own, in_conf in pairs:
            self.assertEqual(quantity(own), quantity(defaults[name]),
                             "deploy/README.md says --%s defaults to %s, --help [%s]"
                             % (name, own, defaults[name]))
            if in_conf is not None:
                self.assertEqual(quantity(in_conf), quantity(conf[name]),
                                 "deploy/README.md says isomeshd.conf sets %s = %s, the file %s"
                                 % (name, in_conf, conf[name]))
            checked.add(name)
        for name in ("queue", "user-jobs", "cache-mem", "job-memory", "max-body",
                     "upload-memory", "max-depth", "max-triangles", "job-timeout",
                     "redis-lock-ttl"):
            self.assertIn(name, checked, "deploy/README.md's limits table lost --" + name)
        # a settings file value the table omits would go unnoticed: every conf value that
        # differs from --help's default is named in the table
        for name, value in conf.items():
            if quantity(value) is not None and quantity(value) != quantity(defaults[name]):
                self.assertTrue(any(n == name and c for n, _, c in pairs),
                                "isomeshd.conf changes %s; the limits table does not say" % name)
        # README.md's prose: "`--FLAG` ... (VALUE;" gives the default
        with open(os.path.join(ROOT, "README.md")) as f:
            readme = f.read()
        said = re.findall(r"`--([a-z-]+)`[^`()]{0,40}\((\d[\d,.]*(?: ?[A-Za-z]+)?)(?=[;,)])",
                          readme)
        for name, value in said:
            self.assertEqual(quantity(value), quantity(defaults[name]),
                             "README.md says --%s defaults to %s, --help [%s]"
                             % (name, value, defaults[name]))
        self.assertGreaterEqual(len({n for n, _ in said}), 7, said)

    def test_bad_values_are_one_line_and_exit_2(self):
        cases = [
            ("--workers", "abc"), ("--workers", "0"), ("--workers", "100000"), ("--queue", "-1"),
            ("--cache-mem", "12Q"), ("--cache-mem", "-5"), ("--job-timeout", "soon"),
            ("--job-timeout", "0"), ("--max-body", "10"), ("--max-depth", "17"),
            ("--listen", "nohost"), ("--listen", "1.2.3.4:99999"), ("--listen", "::1:80"),
            ("--log-format", "xml"), ("--max-triangles", "1e6"), ("--cache-dir", ""),
            ("--tcp-congestion", "Cubic"), ("--tcp-congestion", "a" * 16),
            ("--tcp-congestion", ""),
        ]
        for flag, value in cases:
            r = run(flag, value)
            self.assertEqual(r.returncode, 2, (flag, value, r.stderr))
            lines = r.stderr.strip().splitlines()
            self.assertEqual(len(lines), 1, (flag, value, r.stderr))
            self.assertIn(flag, lines[0])
        for args in (["--bogus", "1"], ["--workers"], ["stray"]):
            r = run(*args)
            self.assertEqual(r.returncode, 2, args)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, args)
        # a value forgotten: the next flag is not taken as it (it was, and then its own value
        # was called an unexpected argument)
        r = run("--listen", "--cache-dir", "/tmp/x")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertEqual(r.stderr.strip(),
                         "isomeshd: --listen needs a value (the next word, '--cache-dir', is a flag)")

    def test_config_file_and_flags_override_it(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "isomeshd.conf")
            with open(conf, "w") as f:
                f.write("# test configuration\n"
                        "workers = 1\n"
                        "max-depth = 7   # trailing comment\n"
                        "cors-origin = \"https://conf.example\"\n"
                        "\n"
                        "queue = 5\n")
            with Daemon("--config", conf, "--max-depth", "8") as d:
                ready = d.get("/readyz").json()
                self.assertEqual(ready["workers"], 1)
                self.assertEqual(d.get("/healthz").header("Access-Control-Allow-Origin"),
                                 "https://conf.example")
                self.assertEqual(d.metric("isomesh_queue_capacity"), 5)
                # max-depth 8 from the command line beats 7 from the file
                ok = d.post("/v1/mesh", {"preset": "sphere", "depth": {"max": 8}})
                self.assertEqual(ok.status, 200)
                self.assertEqual(d.post("/v1/mesh", {"preset": "sphere", "depth": {"max": 9}}).status, 422)

    def test_config_file_errors_name_file_and_line(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "bad.conf")
            for text, what in (("workers = 2\nworkers: 3\n", ":2:"),
                               ("workers = 2\n\nspeed = fast\n", ":3:"),
                               ("cache-mem = lots\n", ":1:")):
                with open(conf, "w") as f:
                    f.write(text)
                r = run("--config", conf)
                self.assertEqual(r.returncode, 2, text)
                self.assertIn(conf + what, r.stderr)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1)
            r = run("--config", os.path.join(tmp, "missing.conf"))
            self.assertEqual(r.returncode, 2)

    def test_tcp_congestion_is_the_accepted_sockets(self):
        """--tcp-congestion NAME: the daemon's end of a connection uses NAME (read back with
        ss, the kernel's view), a name the kernel lacks stops the start with a message."""
        try:
            with open("/proc/sys/net/ipv4/tcp_allowed_congestion_control") as f:
                allowed = f.read().split()
            with open("/proc/sys/net/ipv4/tcp_congestion_control") as f:
                system = f.read().strip()
        except OSError:
            self.skipTest("no /proc/sys/net/ipv4")
        other = [n for n in allowed if n != system]  # so the option, not the default, shows
        if not other or not shutil.which("ss"):
            self.skipTest("no congestion control besides the system's, or no ss")
        with Daemon("--workers", "1", "--tcp-congestion", other[0]) as d:
            conn = http.client.HTTPConnection("127.0.0.1", d.port, timeout=30)
            try:
                conn.request("GET", "/healthz")
                r = conn.getresponse()
                r.read()
                self.assertEqual(r.status, 200)
                mine = conn.sock.getsockname()[1]
                out = subprocess.run(
                    ["ss", "-tinH", "state", "established",
                     "( sport = :%d and dport = :%d )" % (d.port, mine)],
                    stdout=subprocess.PIPE, text=True, timeout=10).stdout
            finally:
                conn.close()
            self.assertRegex(out, r"\b%s\b" % other[0], out)
            self.assertNotRegex(out, r"\b%s\b" % system, out)
        d = Daemon("--workers", "1", "--tcp-congestion", "nosuchcontrol")
        try:
            with self.assertRaises(Exception):
                d.start(timeout=10)
            self.assertIn("--tcp-congestion nosuchcontrol", d.log())
        finally:
            d.cleanup()

    def test_json_log_lines(self):
        d = Daemon("--workers", "1", log_format="json")
        try:
            d.start()
            key = d.post("/v1/mesh", sphere(0.52)).header("ETag").strip('"')
            d.post("/v1/mesh", sphere(0.52))
            d.get("/nothing-here")
            self.assertEqual(d.stop(), 0)
            records = [json.loads(line) for line in d.lines if line.strip()]
            requests = [r for r in records if r["event"] == "request"]
            self.assertGreaterEqual(len(requests), 4)
            for r in requests:
                for field in ("method", "path", "status", "bytes", "ms", "cache", "key", "ts"):
                    self.assertIn(field, r)
            mesh = [r for r in requests if r["path"] == "/v1/mesh"]
            # one miss, one hit: a request's line is written when its answer completes, so
            # the second's may come first (seen at load 30)
            self.assertEqual(sorted(r["cache"] for r in mesh), ["hit", "miss"])
            self.assertTrue(all(r["key"] == key and r["status"] == 200 and r["bytes"] > 0 for r in mesh))
            miss = [r for r in requests if r["path"] == "/nothing-here"]
            self.assertEqual(miss[0]["status"], 404)
            self.assertTrue(any(r["event"] == "stopped" for r in records))
        finally:
            d.cleanup()


if __name__ == "__main__":
    unittest.main()
