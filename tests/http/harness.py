"""harness.py — a real isomeshd for the HTTP tests: started on 127.0.0.1 with a free port (it
binds port 0 and logs the port it got), with its own temporary cache directory, its stderr
collected line by line (or, for the benchmarks, written to a file: log_file=), bounded waits
everywhere, and always stopped (SIGTERM, then SIGKILL after a bound). Plus small helpers:
requests with http.client, /metrics parsing, Draco decoding with Debian's draco_decoder, the
daemon's worker processes and resident memory from /proc."""
import collections
import ctypes
import http.client
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# tests/cli/boxes.py (the placements every geometric test meshes in) importable as `boxes`
sys.path.insert(0, os.path.join(ROOT, "tests", "cli"))
BUILD = os.environ.get("ISOMESH_BUILD", os.path.join(ROOT, "build", "release"))
ISOMESHD = os.path.join(BUILD, "isomeshd")
QUICK = os.environ.get("ISOMESH_TEST_QUICK") == "1"
# Flags every daemon of the tests gets before its own (which override them): a whole suite in
# another mode, e.g. ISOMESHD_TEST_ARGS=--own-sender=off for libmicrohttpd alone.
EXTRA_ARGS = os.environ.get("ISOMESHD_TEST_ARGS", "").split()

# Requests used across the tests. SLOW takes seconds (gyroid ball at depth 10: about 1.5 s with
# two threads on an idle machine, 2026-11-27 — it was 3 s before the evaluators got faster):
# long enough to hold a worker while a test looks, not to outlast a deadline. SLOWER does outlast
# the 5 s deadline of the deadline tests with a wide margin (k = 8 gives 2.5M triangles, below the
# daemon's 4M limit, and the quality pass: 12 s for the command alone on that machine, two
# threads; the daemon adds the analysis and the encoding) — a faster polygoniser must not turn
# a deadline test into a 200.
SPHERE = {"preset": "sphere"}
# Slow requests are the depth path at depth 10 ("max_error": null): under the default bound
# (1e-3 x the box diagonal) the gyroid ball takes a fraction of a second.
SLOW = {"preset": "gyroid-ball", "depth": {"max": 10}, "max_error": None}
SLOWER = {"preset": "gyroid-ball", "params": {"k": 8}, "depth": {"max": 10}, "quality": "good",
          "max_error": None}


# Linux prctl(2): PR_SET_PDEATHSIG asks the kernel for a signal when the parent thread ends.
_PRCTL = ctypes.CDLL(None, use_errno=True).prctl
PR_SET_PDEATHSIG = 1


def spawn_owned(cmd, **kwargs):
    """subprocess.Popen(cmd, **kwargs) for a server the test runs (isomeshd, redis-server,
    nginx, stunnel): in a session of its own, and sent SIGTERM when the thread that started it
    ends (call it from the test's main thread), then stopped by the pid the test holds.

    Its own session: a test that SIGSTOPs a daemon's worker (or Redis) must not share a process
    group with the shell or runner above it. When that group loses its last tie to the session
    (the wrapper running the test ends or is killed) while one of its processes is stopped, the
    kernel sends SIGHUP and then SIGCONT to every process in it (POSIX _exit(), "orphaned
    process group"): both daemons log `reload_ignored` and the paused worker runs on — what
    qflake's loop saw in session 17, with no one signalling by name. In a session of its own
    the server's group is orphaned from the start, so that can never happen to it; and a
    terminal's SIGINT or SIGHUP reaches only the test, which stops its servers itself.
    The death signal: out of the test's process group, a server would outlive a test that is
    killed (run_suites.py's timeout, a job stopped with kill) where it used to share its fate."""
    parent = os.getpid()

    def tie():
        if _PRCTL(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) != 0 or os.getppid() != parent:
            os._exit(127)  # the test is already gone, or the kernel refused: do not run
    return subprocess.Popen(cmd, start_new_session=True, preexec_fn=tie, **kwargs)


def sphere(r):
    """A distinct small request per radius (a distinct cache key)."""
    return {"expr": "x^2 + y^2 + z^2 - r^2", "params": {"r": r},
            "box": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5]}


class Response:
    def __init__(self, status, headers, body):
        self.status = status
        self.headers = headers
        self.body = body

    def header(self, name):
        for k, v in self.headers:
            if k.lower() == name.lower():
                return v
        return None

    def json(self):
        return json.loads(self.body)


def wait_until(what, check, timeout=60):
    """Polls check until it gives something true (returned) or timeout seconds pass (an
    AssertionError naming what)."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        v = check()
        if v:
            return v
        time.sleep(0.02)
    raise AssertionError("timed out waiting for " + what)


def http_request(port, method, path, body=None, headers=None, timeout=60, source=None):
    """One request on its own connection to 127.0.0.1:port -> Response. A dict or list body
    goes as JSON; source: the local address to send from (another client, as the daemon
    sees it)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout,
                                      source_address=(source, 0) if source else None)
    try:
        hdrs = dict(headers or {})
        if isinstance(body, (dict, list)):
            body = json.dumps(body).encode()
            hdrs.setdefault("Content-Type", "application/json")
        conn.request(method, path, body=body, headers=hdrs)
        r = conn.getresponse()
        return Response(r.status, r.getheaders(), r.read())
    finally:
        conn.close()


def open_get(port, path, timeout=60):
    """GET path on its own connection to 127.0.0.1:port, the body left unread (a stream read
    as it arrives) -> (the connection, for the caller to close; the response)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        conn.request("GET", path)
        return conn, conn.getresponse()
    except Exception:
        conn.close()
        raise


class Daemon:
    def __init__(self, *args, cache_dir=None, web_root=None, log_format="text", binary=None,
                 prefix=(), env=None, log_file=None):
        """binary: another isomeshd (default: ISOMESH_BUILD's); prefix: a command to run it
        under (valgrind, unshare); env: its environment (default: this process's); log_file:
        a path to write its stderr to instead of collecting it through a pipe and a reader
        thread (benchmarks: one log line per request, no Python thread taking CPU from the
        measurement, no log growing in memory)."""
        self.binary = binary or ISOMESHD
        self.prefix = list(prefix)
        self.env = env
        self.tmp = tempfile.mkdtemp(prefix="isomeshd_test_")
        self.cache_dir = cache_dir or os.path.join(self.tmp, "cache")
        self.args = list(args)
        self.web_root = web_root if web_root is not None else os.path.join(ROOT, "web")
        self.log_format = log_format
        self.log_file = log_file
        self.log_fh = None
        self.reader = None
        self.lines = []
        self.lock = threading.Lock()
        self.proc = None
        self.port = None

    # ---- life cycle ------------------------------------------------------------------
    def start(self, timeout=15):
        cmd = self.prefix + [self.binary, "--listen", "127.0.0.1:0", "--cache-dir", self.cache_dir,
                             "--web-root", self.web_root, "--log-format", self.log_format] + \
            EXTRA_ARGS + self.args
        if self.log_file is None:
            self._spawn_piped(cmd)
        else:
            self._spawn_to_file(cmd)
        deadline = time.time() + timeout
        while time.time() < deadline and self.port is None:
            if self.proc.poll() is not None:
                self._log_drained()
                raise RuntimeError("isomeshd exited at start:\n" + self.log())
            for line in self._log_lines():
                m = re.search(r'"event":"listening".*"port":(\d+)|listening .*port=(\d+)', line)
                if m:
                    self.port = int(m.group(1) or m.group(2))
            time.sleep(0.02)
        if self.port is None:
            self.stop()
            raise RuntimeError("isomeshd did not report its port:\n" + self.log())
        try:
            self.wait_ready(timeout=max(1, deadline - time.time()))
        except RuntimeError:
            self.stop()  # never leave a daemon behind a failed start
            raise
        return self

    def wait_ready(self, timeout=15):
        deadline = time.time() + timeout
        while time.time() < deadline:
            try:
                if self.get("/readyz").status == 200:
                    return
            except OSError:
                pass
            time.sleep(0.02)
        raise RuntimeError("isomeshd never became ready:\n" + self.log())

    def wait_idle(self, timeout=30):
        """Ready, and no worker computing. After a cancel or a deadline the pool kills the old
        worker on its own thread, a moment after the answer: until then /readyz still counts it,
        busy, and a request that needs an idle worker (--queue 0) would be refused."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            try:
                m = self.metrics()  # one scrape: both gauges from the same moment
                if m.get("isomesh_workers_ready", 0) >= 1 and m.get("isomesh_workers_busy", 0) == 0:
                    return
            except OSError:
                pass
            time.sleep(0.02)
        raise RuntimeError("isomeshd never became idle:\n" + self.log())

    def _spawn_piped(self, cmd):
        """stderr through a pipe, read line by line into self.lines by a thread."""
        self.proc = spawn_owned(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, errors="replace", env=self.env)
        self.reader = threading.Thread(target=self._read_stderr, daemon=True)
        self.reader.start()

    def _spawn_to_file(self, cmd):
        """stderr straight into log_file: no thread, nothing kept in memory."""
        self.log_fh = open(self.log_file, "w")
        self.proc = spawn_owned(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=self.log_fh, env=self.env)

    def _log_drained(self, timeout=5):
        """After the daemon exited: its last lines read (the reader thread reaches the pipe's
        end; bounded, since a child that outlived it could hold the pipe). A test that reads the
        log of a failed start once found it empty: the exit was seen before the thread read."""
        if self.reader is not None:
            self.reader.join(timeout)

    def _read_stderr(self):
        for line in self.proc.stderr:
            with self.lock:
                self.lines.append(line.rstrip("\n"))

    def _log_lines(self, last=None):
        """The log so far (its last lines only, when last is given), as a list of lines."""
        if self.log_file is None:
            with self.lock:
                return self.lines[-last:] if last else list(self.lines)
        try:
            with open(self.log_file, errors="replace") as f:
                return [line.rstrip("\n") for line in collections.deque(f, last)]
        except OSError:
            return []

    def log(self):
        return "\n".join(self._log_lines(last=200))

    def story(self, last=60):
        """The log's last lines other than the scrapes of /metrics (a test polling a metric
        writes one every 20 ms: log()'s tail is then nothing else), for failure messages."""
        lines = [line for line in self._log_lines() if "path=/metrics " not in line
                 and '"path":"/metrics"' not in line]
        return "\n".join(lines[-last:])

    def log_count(self, text, want, timeout=10):
        """How often text occurs in the whole log, waiting (bounded) until it reaches want:
        a line is written after the counter it goes with, and log() sees only the tail."""
        deadline = time.time() + timeout
        while True:
            n = sum(text in line for line in self._log_lines())
            if n >= want or time.time() > deadline:
                return n
            time.sleep(0.05)

    def stop(self, timeout=20):
        """SIGTERM, wait (bounded), SIGKILL if need be. Returns the exit status."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=10)
        if self.reader is not None:
            self.reader.join(timeout=5)
            self.proc.stderr.close()
        if self.log_fh is not None:
            self.log_fh.close()
            self.log_fh = None
        rc = self.proc.returncode
        self.proc = None
        return rc

    def cleanup(self):
        self.stop()
        shutil.rmtree(self.tmp, ignore_errors=True)

    @classmethod
    def started(cls, *args, **kwargs):
        """A started daemon (cleaned up, and the error raised, when it does not start)."""
        d = cls(*args, **kwargs)
        try:
            return d.start()
        except Exception:
            d.cleanup()
            raise

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.cleanup()

    # ---- requests --------------------------------------------------------------------
    def request(self, method, path, body=None, headers=None, timeout=60):
        return http_request(self.port, method, path, body, headers, timeout)

    def get(self, path, headers=None, timeout=60):
        return self.request("GET", path, headers=headers, timeout=timeout)

    def post(self, path, body, headers=None, timeout=120):
        return self.request("POST", path, body=body, headers=headers, timeout=timeout)

    def raw(self, data, timeout=10):
        """Sends raw bytes (one request) and returns the status code of the answer."""
        import socket
        with socket.create_connection(("127.0.0.1", self.port), timeout=timeout) as s:
            s.sendall(data)
            got = b""
            while b"\r\n" not in got:
                chunk = s.recv(4096)
                if not chunk:
                    break
                got += chunk
        m = re.match(rb"HTTP/1\.[01] (\d{3})", got)
        return int(m.group(1)) if m else None

    # ---- introspection ---------------------------------------------------------------
    def metrics(self):
        return parse_metrics(self.get("/metrics").body.decode())

    def metric(self, name, **labels):
        return self.metrics().get(metric_key(name, labels), 0.0)

    def wait_metric(self, name, value, timeout=30, **labels):
        deadline = time.time() + timeout
        while time.time() < deadline:
            if self.metric(name, **labels) >= value:
                return True
            time.sleep(0.02)
        return False

    def workers(self):
        """Pids of the daemon's child processes (its workers)."""
        pids = []
        task_dir = "/proc/%d/task" % self.proc.pid
        for tid in os.listdir(task_dir):
            try:
                with open(os.path.join(task_dir, tid, "children")) as f:
                    pids += [int(p) for p in f.read().split()]
            except OSError:
                pass
        return pids

    def rss_mib(self):
        """Resident set of the process started, in MiB."""
        return rss_kib(self.proc.pid) / 1024.0


def rss_kib(pid):
    """Resident set size of pid in KiB (VmRSS of /proc/PID/status)."""
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def in_background(fn):
    """Runs fn() on a daemon thread -> (thread, box): after joining, box holds "result" or
    the "error" it raised."""
    box = {}

    def run():
        try:
            box["result"] = fn()
        except Exception as e:  # reported by the test that joins
            box["error"] = e

    t = threading.Thread(target=run, daemon=True)
    t.start()
    return t, box


def process_alive(pid):
    """True while pid runs (a zombie, already dead but not reaped, counts as gone)."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def metric_key(name, labels):
    if not labels:
        return name
    inner = ",".join('%s="%s"' % (k, labels[k]) for k in sorted(labels))
    return "%s{%s}" % (name, inner)


_SAMPLE = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{((?:[^"}]|"(?:[^"\\]|\\.)*")*)\})? '
                     r'(-?[0-9.eE+-]+|\+Inf|NaN)$')


def parse_metrics(text):
    """Prometheus text format -> {name or name{k="v",...} (labels sorted): value}. Raises on a
    line that is not a comment or a sample."""
    out = {}
    for line in text.splitlines():
        if not line or line.startswith("#"):
            continue
        m = _SAMPLE.match(line)
        if not m:
            raise ValueError("bad metrics line: %r" % line)
        labels = {}
        if m.group(3):
            for part in re.findall(r'([a-zA-Z_][a-zA-Z0-9_]*)="((?:[^"\\]|\\.)*)"', m.group(3)):
                labels[part[0]] = part[1]
        out[metric_key(m.group(1), labels)] = float(m.group(4))
    return out


def draco_counts(data):
    """Decodes Draco bytes with draco_decoder; returns (vertices, faces) from the PLY it
    writes."""
    with tempfile.TemporaryDirectory() as d:
        src, dst = os.path.join(d, "m.drc"), os.path.join(d, "m.ply")
        with open(src, "wb") as f:
            f.write(data)
        r = subprocess.run(["draco_decoder", "-i", src, "-o", dst], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=60)
        if r.returncode != 0 or not os.path.exists(dst):
            raise AssertionError("draco_decoder failed: " + r.stdout)
        with open(dst, "rb") as f:
            head = f.read(4096)
        v = re.search(rb"element vertex (\d+)", head)
        t = re.search(rb"element face (\d+)", head)
        return int(v.group(1)) if v else 0, int(t.group(1)) if t else 0
