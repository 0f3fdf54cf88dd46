"""test_config.py — isomeshd's settings and logs: --help names every flag, a bad flag or value
is a one-line error with exit status 2, --config FILE is read (and command-line flags win over
it), its errors name the file and line, and --log-format json writes one JSON object per line
with one request line per request (method, path, status, bytes, ms, cache, key)."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import ISOMESHD, Daemon, sphere  # noqa: E402

FLAGS = ["--listen", "--workers", "--queue", "--client-jobs", "--cache-dir", "--cache-mem",
         "--job-timeout", "--job-memory", "--max-body", "--max-depth", "--max-triangles",
         "--web-root", "--data-dir", "--cors-origin", "--log-format", "--config"]


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

    def test_bad_values_are_one_line_and_exit_2(self):
        cases = [
            ("--workers", "abc"), ("--workers", "0"), ("--workers", "100000"), ("--queue", "-1"),
            ("--cache-mem", "12Q"), ("--cache-mem", "-5"), ("--job-timeout", "soon"),
            ("--job-timeout", "0"), ("--max-body", "10"), ("--max-depth", "17"),
            ("--listen", "nohost"), ("--listen", "1.2.3.4:99999"), ("--listen", "::1:80"),
            ("--log-format", "xml"), ("--max-triangles", "1e6"), ("--cache-dir", ""),
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
            self.assertEqual([r["cache"] for r in mesh], ["miss", "hit"])
            self.assertTrue(all(r["key"] == key and r["status"] == 200 and r["bytes"] > 0 for r in mesh))
            miss = [r for r in requests if r["path"] == "/nothing-here"]
            self.assertEqual(miss[0]["status"], 404)
            self.assertTrue(any(r["event"] == "stopped" for r in records))
        finally:
            d.cleanup()


if __name__ == "__main__":
    unittest.main()
