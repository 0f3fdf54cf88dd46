"""stack.py — the service of deploy/ on loopback for the deploy tests: a redis-server started
with deploy/redis/isomesh.conf (its own port and directory, nothing saved), isomeshd daemons
(tests/http/harness.py's Daemon, each with its own port and cache directory) and nginx with a
configuration generated from deploy/nginx/isomesh.conf (the upstreams pointed at the daemons,
its own prefix, pid, logs and temporary directories). Every process is started and stopped
here, with bounded waits. Plus a minimal Redis client (RESP over a socket, stdlib only)."""
import codecs
import gzip
import os
import pwd
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "http"))
import harness  # noqa: E402  (the HTTP tests' daemon harness)

DEPLOY = os.path.join(ROOT, "deploy")
NGINX_CONF = os.path.join(DEPLOY, "nginx", "isomesh.conf")
REDIS_CONF = os.path.join(DEPLOY, "redis", "isomesh.conf")


def which(name, extra=("/usr/sbin", "/sbin", "/usr/bin")):
    found = shutil.which(name)
    if found:
        return found
    for d in extra:
        p = os.path.join(d, name)
        if os.access(p, os.X_OK):
            return p
    return None


REDIS_SERVER = which("redis-server")
NGINX = which("nginx")
SYSTEMD_ANALYZE = which("systemd-analyze")
OPENSSL = which("openssl")
STUNNEL = which("stunnel4") or which("stunnel")


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate, timeout, step=0.02):
    """Polls predicate until it is true or timeout seconds pass; returns its last value."""
    deadline = time.time() + timeout
    while True:
        value = predicate()
        if value or time.time() >= deadline:
            return value
        time.sleep(step)


def stop_process(proc, sig=signal.SIGTERM, timeout=10):
    if proc is None or proc.poll() is not None:
        return
    proc.send_signal(sig)
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=10)


# ---- Redis ------------------------------------------------------------------------------

class RedisError(Exception):
    pass


def _read_reply(f):
    line = f.readline()
    if not line:
        raise ConnectionError("redis closed the connection")
    kind, rest = line[:1], line[1:-2]
    if kind == b"+":
        return rest.decode()
    if kind == b"-":
        raise RedisError(rest.decode())
    if kind == b":":
        return int(rest)
    if kind == b"$":
        n = int(rest)
        if n < 0:
            return None
        data = f.read(n + 2)
        return data[:-2]
    if kind == b"*":
        n = int(rest)
        return None if n < 0 else [_read_reply(f) for _ in range(n)]
    raise RedisError("unexpected reply %r" % line)


def redis_command(port, *args, timeout=5):
    """Runs one Redis command on 127.0.0.1:port and returns its reply."""
    parts = [b"*%d\r\n" % len(args)]
    for a in args:
        b = a if isinstance(a, bytes) else str(a).encode()
        parts.append(b"$%d\r\n%s\r\n" % (len(b), b))
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(b"".join(parts))
        with s.makefile("rb") as f:
            return _read_reply(f)


class Redis:
    """redis-server with deploy/redis/isomesh.conf, on its own port and directory (extra:
    more command-line settings, e.g. a TLS port)."""

    def __init__(self, port=None, extra=()):
        self.tmp = tempfile.mkdtemp(prefix="isomesh_redis_")
        self.port = port or free_port()
        self.extra = list(extra)
        self.proc = None

    def start(self, timeout=10):
        cmd = [REDIS_SERVER, REDIS_CONF, "--port", str(self.port), "--bind", "127.0.0.1",
               "--dir", self.tmp, "--save", "", "--appendonly", "no",
               "--logfile", os.path.join(self.tmp, "redis.log"), "--daemonize", "no"] + self.extra
        self.proc = harness.spawn_owned(cmd, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        def ready():
            if self.proc.poll() is not None:
                raise RuntimeError("redis-server exited:\n" + self.log())
            try:
                return redis_command(self.port, "PING", timeout=1) == "PONG"
            except OSError:
                return False
        if not wait_until(ready, timeout):
            self.stop()
            raise RuntimeError("redis-server did not answer:\n" + self.log())
        return self

    def log(self):
        try:
            with open(os.path.join(self.tmp, "redis.log"), errors="replace") as f:
                return f.read()[-4000:]
        except OSError:
            return ""

    def command(self, *args):
        return redis_command(self.port, *args)

    def stop(self):
        stop_process(self.proc)
        self.proc = None

    def cleanup(self):
        if self.proc is not None and self.proc.poll() is None:
            try:
                os.kill(self.proc.pid, signal.SIGCONT)  # in case a test paused it
            except OSError:
                pass
        self.stop()
        shutil.rmtree(self.tmp, ignore_errors=True)


class RedisProxy:
    """A TCP relay in front of Redis for one daemon, which can hold back one exchange on a
    deleted:<daemon> set (cluster.c take_deletes): after hold(names, seconds), the first
    command on such a set named one of names (bytes, e.g. b"SRANDMEMBER") is kept from Redis
    (before=True), or Redis runs it and its answer, when not an empty list, is kept from the
    daemon (before=False), for `seconds` (past the daemon's command timeout,
    ISM_REDIS_COMMAND_TIMEOUT_MS); its connection is then closed: the daemon never hears
    back, as on a loaded machine. `held` is set once that happened."""

    def __init__(self, redis_port):
        self.redis_port = redis_port
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.armed = None  # (names, seconds, before) of the exchange to hold
        self.held = threading.Event()
        self.lock = threading.Lock()
        self.socks = []

    def start(self):
        threading.Thread(target=self._accept, daemon=True).start()
        return self

    def hold(self, names, seconds, before=False):
        with self.lock:
            self.held.clear()
            self.armed = (tuple(names), seconds, before)

    def _accept(self):
        while True:
            try:
                client, _ = self.listener.accept()
            except OSError:
                return  # closed
            try:
                server = socket.create_connection(("127.0.0.1", self.redis_port), timeout=5)
            except OSError:
                client.close()
                continue
            server.settimeout(None)
            watch = threading.Event()  # the command on its way is the one to hold the answer of
            with self.lock:
                self.socks += [client, server]
            threading.Thread(target=self._commands, args=(client, server, watch),
                             daemon=True).start()
            threading.Thread(target=self._answers, args=(server, client, watch),
                             daemon=True).start()

    def _take(self, data, before):
        """The seconds to hold data's exchange for (the hold disarmed), else None."""
        with self.lock:
            if not self.armed or self.armed[2] != before:
                return None
            names, seconds, _ = self.armed
            if before and not (b"deleted:" in data and any(n in data for n in names)):
                return None
            if not before and data.startswith(b"*0\r\n"):
                return None  # an empty set read: nothing to lose
            self.armed = None
            return seconds

    def _commands(self, client, server, watch):
        try:
            while True:
                data = client.recv(65536)
                if not data:
                    break
                hold = self._take(data, True)
                if hold is not None:
                    time.sleep(hold)
                    self.held.set()
                    break  # never sent to Redis
                with self.lock:
                    names = self.armed[0] if self.armed else ()
                if b"deleted:" in data and any(n in data for n in names):
                    watch.set()  # the daemon sends one command and waits for its answer
                server.sendall(data)
        except OSError:
            pass
        self._close(client, server)

    def _answers(self, server, client, watch):
        try:
            while True:
                data = server.recv(65536)
                if not data:
                    break
                if watch.is_set():
                    watch.clear()
                    hold = self._take(data, False)
                    if hold is not None:
                        time.sleep(hold)
                        self.held.set()
                        break  # never delivered
                client.sendall(data)
        except OSError:
            pass
        self._close(client, server)

    def _close(self, *socks):
        for s in socks:
            try:
                s.close()
            except OSError:
                pass

    def cleanup(self):
        self.listener.close()
        with self.lock:
            self._close(*self.socks)


def wait_stored(redis, key, fmt="drc", timeout=30):
    """Waits until a computed mesh's four entries (the mesh, its stats, features and request)
    are in redis: a daemon writes them after its answer. True when they all are."""
    names = ["isomesh:v1:%s.%s" % (key, ext)
             for ext in (fmt, "stats.json", "features.json", "request.json")]
    return wait_until(lambda: all(redis.command("EXISTS", n) == 1 for n in names), timeout)


# ---- the cluster queue's scripts ---------------------------------------------------------

def cluster_scripts():
    """name -> Lua text of every `static const char NAME[] = "...";` in
    server/isomeshd/cluster.c, through the C preprocessor: the daemon's own scripts."""
    src = os.path.join(ROOT, "server", "isomeshd", "cluster.c")
    out = subprocess.run(["gcc", "-E", "-P", "-D_GNU_SOURCE", "-I" + ROOT, "-I/usr/include/hiredis",
                          src], check=True, capture_output=True, text=True).stdout
    found = {}
    for m in re.finditer(r"static const char (\w+)\[\] =\s*((?:\"(?:[^\"\\]|\\.)*\"\s*)+);", out):
        parts = re.findall(r"\"((?:[^\"\\]|\\.)*)\"", m.group(2))
        found[m.group(1)] = codecs.decode("".join(parts), "unicode_escape")
    return found


# ---- nginx ------------------------------------------------------------------------------

def nginx_site(daemon_ports, listen_port, tls=None, cache_dir=None):
    """deploy/nginx/isomesh.conf with every upstream listing daemon_ports (None: as shipped),
    listening on 127.0.0.1:listen_port (and, with tls=(port, cert, key), its TLS lines
    enabled), its mesh cache in cache_dir (None: as shipped)."""
    with open(NGINX_CONF) as f:
        text = f.read()
    servers = re.findall(r"^(\s*)server 127\.0\.0\.1:8080 (.*);\n", text, re.M)
    if len(servers) != 2:
        raise AssertionError("expected two upstream server lines in " + NGINX_CONF)

    def upstream(m):
        return "".join("%sserver 127.0.0.1:%d %s;\n" % (m.group(1), p, m.group(2))
                       for p in daemon_ports)
    if daemon_ports is not None:
        text = re.sub(r"^(\s*)server 127\.0\.0\.1:8080 (.*);\n", upstream, text, flags=re.M)
    text = re.sub(r"^(\s*)listen 80( reuseport)?;$", r"\1listen 127.0.0.1:%d\2;" % listen_port, text,
                  flags=re.M)
    if cache_dir:
        text = text.replace("/var/cache/nginx/isomesh", cache_dir)
    text = re.sub(r"^\s*listen \[::\]:80( reuseport)?;\n", "", text, flags=re.M)
    if tls:
        port, cert, key = tls
        text = re.sub(r"^(\s*)# listen 443 ssl http2;$", r"\1listen 127.0.0.1:%d ssl http2;" % port,
                      text, flags=re.M)
        text = re.sub(r"^\s*# listen \[::\]:443 ssl http2;\n", "", text, flags=re.M)
        text = re.sub(r"^(\s*)# ssl_certificate (\s*)\S+;$", r"\1ssl_certificate \2%s;" % cert,
                      text, flags=re.M)
        text = re.sub(r"^(\s*)# ssl_certificate_key \S+;$", r"\1ssl_certificate_key %s;" % key,
                      text, flags=re.M)
        text = re.sub(r"^(\s*)# (ssl_\w+|add_header) ", r"\1\2 ", text, flags=re.M)
    return text


def nginx_main(prefix, site_path):
    """A whole nginx.conf for a test instance: everything under prefix, the site included."""
    user = ""
    if os.geteuid() == 0:  # workers would otherwise drop to nobody and miss the temp dirs
        user = "user %s;\n" % pwd.getpwuid(0).pw_name
    p = prefix
    return (
        "%sworker_processes 1;\npid %s/nginx.pid;\nerror_log %s/error.log notice;\n"
        "events { worker_connections 512; }\n"
        "http {\n"
        "    include /etc/nginx/mime.types;\n"
        "    default_type application/octet-stream;\n"
        "    access_log %s/access.log;\n"
        "    client_body_temp_path %s/tmp/body;\n    proxy_temp_path %s/tmp/proxy;\n"
        "    fastcgi_temp_path %s/tmp/fastcgi;\n    uwsgi_temp_path %s/tmp/uwsgi;\n"
        "    scgi_temp_path %s/tmp/scgi;\n"
        "    include %s;\n"
        "}\n" % (user, p, p, p, p, p, p, p, p, site_path))


def nginx_test(prefix, conf):
    """`nginx -t` on conf; returns (exit status, output)."""
    r = subprocess.run([NGINX, "-t", "-p", prefix, "-e", os.path.join(prefix, "error.log"),
                        "-c", conf], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True, timeout=30)
    return r.returncode, r.stdout


class Nginx:
    """nginx in the foreground with a generated configuration (see nginx_site)."""

    def __init__(self, daemon_ports, tls=None):
        self.prefix = tempfile.mkdtemp(prefix="isomesh_nginx_")
        os.makedirs(os.path.join(self.prefix, "tmp"))
        self.port = free_port()
        self.site = os.path.join(self.prefix, "isomesh.conf")
        self.conf = os.path.join(self.prefix, "nginx.conf")
        with open(self.site, "w") as f:
            f.write(nginx_site(daemon_ports, self.port, tls,
                               os.path.join(self.prefix, "tmp", "meshes")))
        with open(self.conf, "w") as f:
            f.write(nginx_main(self.prefix, self.site))
        self.proc = None

    def start(self, timeout=10):
        rc, out = nginx_test(self.prefix, self.conf)
        if rc != 0:
            raise RuntimeError("nginx -t failed:\n" + out)
        self.proc = harness.spawn_owned([NGINX, "-p", self.prefix, "-e",
                                         os.path.join(self.prefix, "error.log"), "-c", self.conf,
                                         "-g", "daemon off;"], stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        def ready():
            if self.proc.poll() is not None:
                raise RuntimeError("nginx exited:\n" + self.error_log())
            try:
                return self.get("/healthz", timeout=2).status == 200
            except OSError:
                return False
        if not wait_until(ready, timeout):
            self.stop()
            raise RuntimeError("nginx never answered /healthz:\n" + self.error_log())
        return self

    def error_log(self):
        try:
            with open(os.path.join(self.prefix, "error.log"), errors="replace") as f:
                return f.read()[-4000:]
        except OSError:
            return ""

    def request(self, method, path, body=None, headers=None, timeout=60, source="127.0.0.1"):
        return harness.http_request(self.port, method, path, body, headers, timeout, source)

    def get(self, path, headers=None, timeout=60, source="127.0.0.1"):
        return self.request("GET", path, headers=headers, timeout=timeout, source=source)

    def post(self, path, body, headers=None, timeout=120, source="127.0.0.1"):
        return self.request("POST", path, body=body, headers=headers, timeout=timeout,
                            source=source)

    def stop(self):
        stop_process(self.proc, signal.SIGQUIT)
        self.proc = None

    def cleanup(self):
        self.stop()
        shutil.rmtree(self.prefix, ignore_errors=True)


def gunzip(data):
    return gzip.decompress(data)


# ---- the whole service --------------------------------------------------------------------

# The counters Stack.story shows: who computed, who waited, what fell back or failed.
STORY_METRICS = ("isomesh_polygonisations_total", "isomesh_stored_encodings_total",
                 "isomesh_redis_lock_waits_total", "isomesh_redis_locks_acquired_total",
                 "isomesh_redis_fallbacks_total", "isomesh_redis_errors_total",
                 "isomesh_redis_outages_total", "isomesh_cluster_submitted_total",
                 "isomesh_cluster_taken_total", "isomesh_singleflight_joins_total",
                 "isomesh_workers_storing", "isomesh_flights_held")


class Stack:
    """Redis, n daemons sharing it, nginx in front. Stopped by cleanup() whatever happened."""

    def __init__(self, n=2, daemon_args=(), with_nginx=True, redis_for=None, env_for=None):
        """redis_for(i, port): the Redis port daemon i is given (default: Redis's own; a
        RedisProxy's to come between them); env_for(i): daemon i's environment (default, or
        None: this process's)."""
        self.redis = Redis()
        self.redis_for = redis_for or (lambda i, port: port)
        self.env_for = env_for or (lambda i: None)
        self.daemons = []
        self.nginx = None
        self.n = n
        self.daemon_args = list(daemon_args)
        self.with_nginx = with_nginx
        self.paused = []  # worker pids stopped by pause_workers

    def start(self):
        try:
            self.redis.start()
            for i in range(self.n):
                d = harness.Daemon("--redis", "127.0.0.1:%d" % self.redis_for(i, self.redis.port),
                                   "--workers", "2", *self.daemon_args, env=self.env_for(i))
                self.daemons.append(d)
                d.start()
            for d in self.daemons:
                if not wait_until(lambda: d.metric("isomesh_redis_up") == 1, 10):
                    raise RuntimeError("a daemon never connected to Redis:\n" + d.log())
            if self.with_nginx:
                self.nginx = Nginx([d.port for d in self.daemons]).start()
        except BaseException:
            self.cleanup()
            raise
        return self

    def story(self, last=60):
        """For a failure message: each daemon's counters of the shared stage and the cluster
        queue, then its log's last lines other than the scrapes of /metrics (harness's
        Daemon.story)."""
        out = []
        for i, d in enumerate(self.daemons):
            try:
                m = d.metrics()
                counts = " ".join("%s=%g" % (n[len("isomesh_"):], m.get(n, 0)) for n in STORY_METRICS)
            except OSError as e:
                counts = "(no metrics: %s)" % e
            out.append("--- daemon %d (port %s): %s\n%s" % (i, d.port, counts, d.story(last)))
        return "\n".join(out)

    def pause_workers(self, daemons=None, timeout=30):
        """SIGSTOPs the ready workers of daemons (default: all) not paused yet. A computation
        sent to a paused worker is dispatched (the worker is busy, the lock in Redis taken)
        and then waits, using no CPU, until resume_workers: a test observes that state for
        as long as it needs, whatever the machine's speed, with a small mesh."""
        for d in self.daemons if daemons is None else daemons:
            ready = wait_until(lambda: d.metric("isomesh_workers_ready")
                               == d.metric("isomesh_workers") > 0, timeout)
            if not ready:  # a starting worker paused would be killed as silent
                raise RuntimeError("the daemon's workers never became ready:\n" + d.log())
            for pid in d.workers():
                if pid not in self.paused:
                    os.kill(pid, signal.SIGSTOP)
                    self.paused.append(pid)

    def resume_workers(self):
        """SIGCONTs every worker pause_workers stopped (those gone since are skipped)."""
        for pid in self.paused:
            try:
                os.kill(pid, signal.SIGCONT)
            except ProcessLookupError:
                pass
        self.paused = []

    def cleanup(self):
        """Stops everything; returns the sanitizer or crash reports found in the daemons'
        logs (a sanitizer build reports leaks and memory errors when the daemon exits)."""
        self.resume_workers()  # a paused worker would hold its daemon's exit
        if self.nginx:
            self.nginx.cleanup()
        reports = []
        for d in self.daemons:
            d.stop()
            with d.lock:
                lines = list(d.lines)
            reports += [line for line in lines
                        if "ERROR: AddressSanitizer" in line or "ERROR: LeakSanitizer" in line
                        or "runtime error:" in line]
            d.cleanup()
        self.redis.cleanup()
        return reports


def missing_programs():
    """A sentence naming what the deploy tests need and cannot find, or None."""
    missing = [name for name, path in (("redis-server", REDIS_SERVER), ("nginx", NGINX))
               if not path]
    if not os.access(harness.ISOMESHD, os.X_OK):
        missing.append(harness.ISOMESHD + " (make build)")
    if not missing:
        return None
    return "missing: %s (deploy/install-deps.sh test installs the packages)" % ", ".join(missing)
