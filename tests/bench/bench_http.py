#!/usr/bin/env python3
"""bench_http.py — isomeshd's speed over HTTP on 127.0.0.1, beside references measured in the
same run:

1. Cached mesh throughput: wrk (Debian) fetching a cached ~100k-triangle Draco mesh
   (kummer-16-nodes at depth 8, ~310 KB) from /v1/meshes/{key}.drc at 1, 16, 64 and 256
   connections — requests per second, latency percentiles, requests over wrk's 2 s timeout,
   errors, and the server's CPU microseconds and context switches per request (from /proc:
   what a loaded machine distorts least) — beside libmicrohttpd alone serving the same bytes
   from memory with isomeshd's thread model (build/bench/http_ceiling) and nginx serving them as a static file (sendfile;
   one worker process, and one per core). Then isomeshd's figures as ratios of both. Also the
   same mesh with positions only (~100 KB), and POST /v1/mesh of the request (decode + key +
   cache hit) at 16 connections. The same rows with isomeshd --own-sender (its one polling
   thread per core, and four), and a mesh over 1 MB (gyroid-ball at depth 9, ~1.55 MB of
   Draco, sent from the cache file in both modes) beside nginx.
2. Slow readers: 450 connections fetching the same mesh as OBJ (~7 MB) and reading 16 KB per
   0.2 s, while one client asks for /healthz every 50 ms: its latency (p50, p99, max),
   isomeshd beside nginx (a static /healthz file, the same OBJ).
3. Cold requests: the daemon's wall time for a new computation beside the `isomesh` command's
   for the same request file (process start to exit, same thread count), and the worker's
   own time: the service's overhead.

Goals (issue 6): >= 12,000 req/s at 16 connections for the cached mesh, p99 < 10 ms at 64
connections, cold-request overhead over the bare command <= 5 ms. Goals (issue 16), beside
nginx in the same run: req/s >= nginx's at 16, 64 and 256 connections, p99 <= 1.5x nginx's,
no request over 2 s; CPU and voluntary context switches per request <= nginx's. Prints
figures and the machine's load average (on a loaded machine
the ratios are what carries over); asserts nothing."""
import argparse
import http.client
import json
import os
import re
import resource
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "http"))
import harness  # noqa: E402

QUICK = os.environ.get("ISOMESH_TEST_QUICK") == "1"
# ~100k triangles with every attribute (normals, two curvatures, vertex class): ~310 KB;
# the same mesh with positions only: the size the 12,000 req/s goal was set for (~100 KB).
# On the depth path ("max_error": null): under the default bound (1e-3 x the diagonal) the same
# preset gives 37,836 triangles, 141 KB, and the figures would not compare with earlier runs.
MESH_REQ = {"preset": "kummer-16-nodes", "depth": {"max": 8}, "max_error": None}
MESH_REQ_POSITIONS = {"preset": "kummer-16-nodes", "depth": {"max": 8}, "max_error": None,
                      "output": {"attributes": []}}
# A mesh of over 1 MB of Draco (gyroid-ball at depth 9, ~1.5 MB): sent from the cache file in
# both modes (respond.c SENDFILE_MIN; the own sender always), where the header block differs.
MESH_REQ_BIG = {"preset": "gyroid-ball", "depth": {"max": 9}, "max_error": None}


def start_daemon(build, tmp, *args):
    """A started isomeshd (tests/http/harness.py) with its log in a file under tmp: a wrk run
    logs 100k+ lines, which a reader thread would take CPU from the benchmark to collect."""
    log = os.path.join(tmp, "isomeshd-%d.log" % len(os.listdir(tmp)))
    d = harness.Daemon(*args, binary=os.path.join(build, "isomeshd"), web_root="",
                       log_file=log, cache_dir=os.path.join(tmp, "cache"))
    try:
        return d.start()
    except BaseException:
        d.cleanup()
        raise


def cpu_seconds(pids):
    """User + system CPU seconds the processes pids (all their threads) have used."""
    total = 0.0
    for pid in pids:
        try:
            with open("/proc/%d/stat" % pid) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        except (OSError, ValueError, IndexError):
            pass
    return total


def ctx_switches(pids):
    """Voluntary and involuntary context switches of the processes pids, all their threads
    summed (/proc/PID/task/TID/status): wake-ups (a thread that sleeps in epoll_wait and is
    woken switches voluntarily) and preemptions."""
    vol = invol = 0
    for pid in pids:
        try:
            tids = os.listdir("/proc/%d/task" % pid)
        except OSError:
            continue
        for tid in tids:
            try:
                with open("/proc/%d/task/%s/status" % (pid, tid)) as f:
                    for line in f:
                        if line.startswith("voluntary_ctxt_switches"):
                            vol += int(line.split()[1])
                        elif line.startswith("nonvoluntary_ctxt_switches"):
                            invol += int(line.split()[1])
            except (OSError, ValueError, IndexError):
                pass
    return vol, invol


def nginx_workers(master):
    """The pids of nginx's worker processes (the children of master), else [master]."""
    found = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open("/proc/%s/stat" % d) as f:
                    if int(f.read().rsplit(")", 1)[1].split()[1]) == master:
                        found.append(int(d))
            except (OSError, ValueError, IndexError):
                pass
    return found or [master]


def wrk(url, conns, seconds, script=None, pid=None):
    """wrk's figures for url; with pid (one, or a list of the server's processes), also the
    server's CPU microseconds per request (less sensitive to a loaded machine than req/s:
    the server's own cost), wrk's own (client_cpu_us), the cores the two got together
    over the run (cores: on a loaded machine the scheduler's share, which sets req/s) and the
    time the server's threads waited for a CPU per request (runq_us)."""
    pid = [pid] if isinstance(pid, int) else pid
    threads = 1 if conns == 1 else 2
    cmd = ["wrk", "-t%d" % threads, "-c%d" % conns, "-d%ds" % seconds, "--latency"]
    if script:
        cmd += ["-s", script]
    cpu0 = cpu_seconds(pid) if pid else 0.0
    cs0 = ctx_switches(pid) if pid else (0, 0)
    rq0 = run_delay(pid) if pid else 0.0
    kids0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(cmd + [url], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True, timeout=seconds + 60).stdout
    wall = time.perf_counter() - t0
    kids1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = cpu_seconds(pid) - cpu0 if pid else 0.0
    cs1 = ctx_switches(pid) if pid else (0, 0)
    rq1 = run_delay(pid) if pid else 0.0
    client = (kids1.ru_utime - kids0.ru_utime) + (kids1.ru_stime - kids0.ru_stime)
    done = re.search(r"(\d+) requests in", out)
    n = int(done.group(1)) if done else 0
    cpu_us = cpu / n * 1e6 if pid and n else float("nan")
    rps = float(re.search(r"Requests/sec:\s+([\d.]+)", out).group(1))

    def pct(p):
        m = re.search(r"^\s+%s%%\s+([\d.]+)(us|ms|s)\s*$" % p, out, re.M)
        v = float(m.group(1))
        return v / 1000 if m.group(2) == "us" else v * 1000 if m.group(2) == "s" else v

    errors = re.search(r"Non-2xx or 3xx responses: (\d+)", out)
    sock = re.search(r"Socket errors: connect (\d+), read (\d+), write (\d+), timeout (\d+)", out)
    counts = [int(x) for x in sock.groups()] if sock else [0, 0, 0, 0]
    return {"rps": rps, "p50": pct(50), "p90": pct(90), "p99": pct(99),
            "bad": int(errors.group(1)) if errors else 0, "errors": sum(counts[:3]),
            "over2s": counts[3], "cpu_us": cpu_us,
            "vcs": (cs1[0] - cs0[0]) / n if pid and n else float("nan"),
            "ics": (cs1[1] - cs0[1]) / n if pid and n else float("nan"),
            "runq_us": (rq1 - rq0) / n * 1e6 if pid and n else float("nan"),
            "client_cpu_us": client / n * 1e6 if n else float("nan"),
            "cores": (cpu + client) / wall if pid else float("nan")}


def get_ok(port, path, timeout):
    """True when GET path on 127.0.0.1:port answers 200 within timeout seconds."""
    try:
        c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
        c.request("GET", path)
        ok = c.getresponse().status == 200
        c.close()
        return ok
    except OSError:
        return False


def wait_serving(p, port, path):
    """(p, its URL) once process p answers GET path with 200 on 127.0.0.1:port (10 s at
    most); else p is killed and (None, None) returned."""
    deadline = time.time() + 10
    while time.time() < deadline:
        if get_ok(port, path, 2):
            return p, "http://127.0.0.1:%d%s" % (port, path)
        time.sleep(0.05)
    p.kill()
    p.wait()
    return None, None


def start_nginx(tmp, files, workers="1"):
    """nginx with `workers` worker processes serving files ({name: bytes}) from its root;
    (process, URL of the first)."""
    if not shutil.which("nginx"):
        return None, None
    root = os.path.join(tmp, "nginx-" + workers)
    os.makedirs(os.path.join(root, "html"))
    os.chmod(tmp, 0o755)
    os.chmod(root, 0o755)
    for name, data in files.items():
        with open(os.path.join(root, "html", name), "wb") as f:
            f.write(data)
    os.chmod(os.path.join(root, "html"), 0o755)
    import socket
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    conf = os.path.join(root, "nginx.conf")
    with open(conf, "w") as f:
        f.write("""worker_processes %(workers)s;
pid %(root)s/nginx.pid;
error_log %(root)s/error.log;
events { worker_connections 1024; }
http {
  access_log off;
  client_body_temp_path %(root)s/tmp;
  proxy_temp_path %(root)s/tmp;
  fastcgi_temp_path %(root)s/tmp;
  uwsgi_temp_path %(root)s/tmp;
  scgi_temp_path %(root)s/tmp;
  sendfile on;
  tcp_nopush on;
  keepalive_requests 1000000;
  server { listen 127.0.0.1:%(port)d; root %(root)s/html; }
}
""" % {"root": root, "port": port, "workers": workers})
    p = subprocess.Popen(["nginx", "-c", conf, "-p", root, "-g", "daemon off;"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return wait_serving(p, port, "/" + next(iter(files)))


def cached_url(d, req):
    r = d.post("/v1/mesh", req, timeout=300)
    assert r.status == 200, r.body[:200]
    key = r.header("ETag").strip('"')
    tris = d.get("/v1/meshes/%s/stats" % key, timeout=300).json()["mesh"]["triangles"]
    print("cached mesh: %s: %d triangles, %d bytes of Draco" % (json.dumps(req), tris,
                                                              len(r.body)))
    return "http://127.0.0.1:%d/v1/meshes/%s.drc" % (d.port, key), r.body


def row(name, conns, r):
    print("%-40s %6d %10.0f %9.3f %9.3f %9.3f %7d %8.0f %8.2f %8.2f%s" % (
        name, conns, r["rps"], r["p50"], r["p90"], r["p99"], r["over2s"], r["cpu_us"],
        r["vcs"], r["ics"],
        "".join("  (%d %s)" % (r[k], what)
                for k, what in (("bad", "non-2xx"), ("errors", "socket errors")) if r[k])))


def load_line():
    """The load average, and a warning when it is above the core count."""
    load = os.getloadavg()
    return "load average %s on %d cores%s" % (
        " ".join("%.1f" % x for x in load), os.cpu_count(),
        " (above the core count: req/s and latency follow the scheduler's share; compare the "
        "CPU and switches per request)" if load[0] > os.cpu_count() else "")


def run_delay(pids):
    """Seconds the threads of the processes pids have spent runnable but waiting for a CPU
    (/proc/PID/task/TID/schedstat, second field, ns): the scheduler's part of a latency."""
    total = 0
    for pid in pids:
        try:
            tids = os.listdir("/proc/%d/task" % pid)
        except OSError:
            continue
        for tid in tids:
            try:
                with open("/proc/%d/task/%s/schedstat" % (pid, tid)) as f:
                    total += int(f.read().split()[1])
            except (OSError, ValueError, IndexError):
                pass
    return total / 1e9


def equal_share(a, b):
    """a's req/s over b's had both runs got the same CPU: the inverse ratio of their server +
    wrk CPU per request (req/s = cores / CPU per request). On a loaded machine the runs get
    unequal shares (a server with dozens of runnable threads gets more than one with two)."""
    return (b["cpu_us"] + b["client_cpu_us"]) / (a["cpu_us"] + a["client_cpu_us"])


def versus_nginx(results, nginx, which):
    """isomeshd's figures as ratios of nginx's, per connection count, and the issue-16 goals."""
    print("\nisomeshd / nginx (%s), same run (req/s: higher is better; the rest: lower is better); "
          "%s" % (which, load_line()))
    print("%6s %12s %12s %16s %14s %14s %12s %14s %16s" % ("conns", "req/s ratio", "p99 ratio",
                                                           "over 2 s (nginx)", "CPU/req ratio",
                                                           "wake/req ratio", "cores ratio",
                                                           "equal share", "runq us/req"))
    met = cost_met = True
    for conns in sorted(set(nginx) & set(results)):
        i, n = results[conns], nginx[conns]
        rr, pr = i["rps"] / n["rps"], i["p99"] / n["p99"] if n["p99"] else float("inf")
        cr = i["cpu_us"] / n["cpu_us"]
        wr = i["vcs"] / n["vcs"] if n["vcs"] else float("inf")
        print("%6d %11.2fx %11.2fx %9d (%d) %13.2fx %8.2f/%.2f %11.2fx %13.2fx %9.0f/%.0f" % (
            conns, rr, pr, i["over2s"], n["over2s"], cr, i["vcs"], n["vcs"],
            i["cores"] / n["cores"], equal_share(i, n), i["runq_us"], n["runq_us"]))
        if conns >= 16:
            met = met and rr >= 1.0 and pr <= 1.5 and i["over2s"] == 0 and not i["errors"]
            cost_met = cost_met and cr <= 1.0 and i["vcs"] <= n["vcs"]
    print("goal (issue 16) beside nginx (%s): req/s >= nginx's, p99 <= 1.5x nginx's, no request "
          "over 2 s at 16, 64 and 256 connections: %s" % (which, "met" if met else "NOT met"))
    print("cost beside nginx (%s): CPU and wake-ups (voluntary context switches) per request "
          "<= nginx's at 16, 64 and 256 connections: %s" % (which, "met" if cost_met else
                                                            "NOT met"))
    print("(wake/req: isomeshd's voluntary context switches per request / nginx's; cores ratio: "
          "the CPU server + wrk got per second, isomeshd's run over nginx's; equal share: the "
          "req/s ratio had both got the same CPU; runq: microseconds per request isomeshd's / "
          "nginx's threads spent runnable but waiting for a CPU, the scheduler's part of the "
          "latency: a request's own time in isomeshd, first call to answer queued, is ~0.06 ms "
          "p50 and 0.2-0.35 ms p99 at 64 connections, 2026-11-27)")


SLOW_READERS = 450
SLOW_READ = 16 << 10       # bytes each slow reader takes per pass
SLOW_PAUSE = 0.2           # seconds between passes


def http_get(url):
    host, rest = url[len("http://"):].split("/", 1)
    c = http.client.HTTPConnection(*host.split(":"), timeout=300)
    c.request("GET", "/" + rest)
    r = c.getresponse()
    data = r.read()
    c.close()
    assert r.status == 200, (url, r.status)
    return data


def slow_readers(port, path, probe):
    """SLOW_READERS connections asking for path and reading SLOW_READ bytes per SLOW_PAUSE,
    while GET probe is timed every 50 ms on new connections: {n, failed, p50, p99, max} ms."""
    import socket
    import threading
    socks = []
    for _ in range(SLOW_READERS):
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 64 << 10)
        s.connect(("127.0.0.1", port))
        s.sendall(b"GET %s HTTP/1.1\r\nHost: x\r\n\r\n" % path.encode())
        s.setblocking(False)
        socks.append(s)
    stop = threading.Event()

    def trickle():
        while not stop.is_set():
            for s in socks:
                try:
                    s.recv(SLOW_READ)
                except OSError:
                    pass
            stop.wait(SLOW_PAUSE)
    t = threading.Thread(target=trickle, daemon=True)
    t.start()
    lat, failed = [], 0
    end = time.time() + (3 if QUICK else 8)
    try:
        while time.time() < end:
            t0 = time.perf_counter()
            if get_ok(port, probe, 30):
                lat.append((time.perf_counter() - t0) * 1e3)
            else:
                failed += 1
            time.sleep(0.05)
    finally:
        stop.set()
        t.join(10)
        for s in socks:
            s.close()
    lat.sort()
    def pick(q):
        return lat[min(len(lat) - 1, int(q * len(lat)))] if lat else float("nan")
    return {"n": len(lat), "failed": failed, "p50": pick(0.5), "p99": pick(0.99),
            "max": lat[-1] if lat else float("nan")}


def slow_row(name, r):
    print("%-40s %8d %8.1f %8.1f %8.1f%s" % (name, r["n"], r["p50"], r["p99"], r["max"],
                                             "  (%d failed)" % r["failed"] if r["failed"] else ""))


def free_port():
    import socket
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def non_pacing_congestion():
    """reno when the system's congestion control is bbr and reno may be chosen, else None."""
    try:
        with open("/proc/sys/net/ipv4/tcp_congestion_control") as f:
            system = f.read().strip()
        with open("/proc/sys/net/ipv4/tcp_allowed_congestion_control") as f:
            allowed = f.read().split()
    except OSError:
        return None
    return "reno" if system == "bbr" and "reno" in allowed else None


def start_ceiling(build, tmp, body):
    """build/bench/http_ceiling: libmicrohttpd alone serving the same bytes."""
    prog = os.path.join(build, "bench", "http_ceiling")
    if not os.path.exists(prog):
        return None, None
    path = os.path.join(tmp, "ceiling.drc")
    with open(path, "wb") as f:
        f.write(body)
    port = free_port()
    p = subprocess.Popen([prog, str(port), path], stdout=subprocess.DEVNULL)
    return wait_serving(p, port, "/")


def own_answers(d):
    """Answers the daemon's own sender sent (from the cache file or from memory)."""
    m = d.metrics()
    return m.get("isomesh_sendfile_responses_total", 0) + \
        m.get("isomesh_own_memory_responses_total", 0)


def variant_rows(build, tmp, args, label, conns_list, secs, nginx_all, req=MESH_REQ):
    """Rows of a daemon started with args beside nginx (a worker per core): {conns: figures}."""
    d = start_daemon(build, tmp, "--workers", "2", *args)
    out = {}
    try:
        url, _ = cached_url(d, req)
        for conns in conns_list:
            before = own_answers(d)
            r = out[conns] = wrk(url, conns, secs, pid=d.proc.pid)
            row(label, conns, r)
            # a connection the own sender declines is libmicrohttpd's for good: say whose
            # answers the row measured (the first row follows cached_url's computation)
            print("  answered by the own sender: %d of %d" % (
                own_answers(d) - before, round(r["rps"] * secs)))
            if conns in nginx_all:
                n = nginx_all[conns]
                print("  beside nginx (a worker per core): req/s %.2fx, p99 %.2fx, CPU/req "
                      "%.2fx, equal share %.2fx" % (
                          r["rps"] / n["rps"], r["p99"] / n["p99"] if n["p99"] else 0,
                          r["cpu_us"] / n["cpu_us"], equal_share(r, n)))
    finally:
        d.stop(timeout=30)
        d.cleanup()
    return out


def throughput(build, tmp):
    d = start_daemon(build, tmp, "--workers", "2")
    nginx = nginx_all = ceiling = None
    try:
        url, body = cached_url(d, MESH_REQ)
        url_pos, _ = cached_url(d, MESH_REQ_POSITIONS)
        url_big, big = cached_url(d, MESH_REQ_BIG)
        obj_url = url[:-len("drc")] + "obj"
        obj = http_get(obj_url)
        files = {"m.drc": body, "m.obj": obj, "healthz": b"ok\n", "big.drc": big}
        nginx, nurl = start_nginx(tmp, files)
        nginx_all, nurl_all = start_nginx(tmp, files, "auto")
        ceiling, curl = start_ceiling(build, tmp, body)
        secs = 2 if QUICK else 10
        short = 2 if QUICK else 5
        print(load_line())
        print("\n%-40s %6s %10s %9s %9s %9s %7s %8s %8s %8s" % (
            "server / route", "conns", "req/s", "p50 ms", "p90 ms", "p99 ms", ">2 s", "CPU/req",
            "wake/req", "prmt/req"))
        print("(CPU/req: the server's CPU microseconds per request, all its threads and "
              "processes; wake/req, prmt/req: their voluntary (a sleeping thread woken) and "
              "involuntary (preempted) context switches per request, from /proc)")
        results, nginx_results, nginx_all_results = {}, {}, {}
        sendfile = {}
        for conns in (1, 16, 64, 256):
            before = d.metric("isomesh_sendfile_responses_total")
            results[conns] = wrk(url, conns, secs, pid=d.proc.pid)
            sendfile[conns] = d.metric("isomesh_sendfile_responses_total") - before
            row("isomeshd GET mesh (all attributes)", conns, results[conns])
            if curl:
                row("libmicrohttpd alone, same bytes", conns, wrk(curl, conns, secs, pid=ceiling.pid))
            if nurl:
                nginx_results[conns] = wrk(nurl, conns, secs, pid=nginx_workers(nginx.pid))
                row("nginx (1 worker) the same file", conns, nginx_results[conns])
            if nurl_all:
                nginx_all_results[conns] = wrk(nurl_all, conns, secs,
                                               pid=nginx_workers(nginx_all.pid))
                row("nginx (a worker per core) the same file", conns, nginx_all_results[conns])
        alt = non_pacing_congestion()
        if alt:
            # isomesh's daemon with --tcp-congestion (http.c: bbr without fq paces every
            # socket with a kernel timer; nginx's one-sendfile answers barely pay it)
            variant_rows(build, tmp, ["--tcp-congestion", alt], "isomeshd --tcp-congestion " + alt,
                         (64, 256), secs, nginx_all_results)
        # the daemon's own sender (http_front.h): the header block held back, then sendfile
        own = variant_rows(build, tmp, ["--own-sender"], "isomeshd --own-sender", (16, 64, 256),
                           secs, nginx_all_results)
        # its threads as the default's (http.c: one per core with the own sender, two without):
        # fewer wake-ups per request against a larger share of a loaded machine's CPU
        own4 = variant_rows(build, tmp, ["--own-sender", "--http-threads", "4"],
                            "isomeshd --own-sender --http-threads 4", (16, 64, 256), secs,
                            nginx_all_results)
        if nurl_all:  # the >= 1 MB mesh: both modes send it from the cache file
            nbig = nurl_all.rsplit("/", 1)[0] + "/big.drc"
            big_d, big_n = {}, {}
            for conns in (16, 64, 256):
                big_d[conns] = wrk(url_big, conns, short, pid=d.proc.pid)
                row("isomeshd GET mesh of %.1f MB" % (len(big) / 1e6), conns, big_d[conns])
                big_n[conns] = wrk(nbig, conns, short, pid=nginx_workers(nginx_all.pid))
                row("nginx (a worker per core) the same file", conns, big_n[conns])
            big_own = variant_rows(build, tmp, ["--own-sender"],
                                   "isomeshd --own-sender %.1f MB" % (len(big) / 1e6),
                                   (16, 64, 256), short, big_n, req=MESH_REQ_BIG)
        print("(isomeshd's answers sent from the cache file, sendfile, at 1/16/64/256 "
              "connections: %s; respond.c: bodies from 1 MB, smaller ones from memory, "
              "where the header block leaves in the same send as the body)" % " / ".join("%d" % sendfile[c] for c in sorted(sendfile)))
        pos = {}
        for conns in (1, 16, 64, 256):
            pos[conns] = wrk(url_pos, conns, short, pid=d.proc.pid)
            row("isomeshd GET mesh (positions only)", conns, pos[conns])
        lua = os.path.join(tmp, "post.lua")
        with open(lua, "w") as f:
            f.write('wrk.method = "POST"\nwrk.body = %s\nwrk.headers["Content-Type"] = "application/json"\n'
                    % json.dumps(json.dumps(MESH_REQ)))
        row("isomeshd POST /v1/mesh (cache hit)", 16,
            wrk("http://127.0.0.1:%d/v1/mesh" % d.port, 16, short, script=lua, pid=d.proc.pid))
        if nginx_results:
            versus_nginx(results, nginx_results, "1 worker")
        if nginx_all_results:
            versus_nginx(results, nginx_all_results, "a worker per core")
            versus_nginx(own, nginx_all_results, "a worker per core; isomeshd --own-sender")
            versus_nginx(own4, nginx_all_results, "a worker per core; isomeshd --own-sender "
                         "--http-threads 4")
            versus_nginx(big_d, big_n, "a worker per core; the %.1f MB mesh" % (len(big) / 1e6))
            versus_nginx(big_own, big_n, "a worker per core; isomeshd --own-sender; the %.1f MB "
                         "mesh" % (len(big) / 1e6))
        print("\n" + load_line())
        print("/healthz every 50 ms while %d slow readers fetch the %.1f MB OBJ (16 KB per "
              "0.2 s each)" % (SLOW_READERS, len(obj) / 1e6))
        print("%-40s %8s %8s %8s %8s" % ("server", "answers", "p50 ms", "p99 ms", "max ms"))
        slow = slow_readers(d.port, obj_url[len("http://127.0.0.1:%d" % d.port):], "/healthz")
        slow_row("isomeshd", slow)
        d3 = start_daemon(build, tmp, "--workers", "2", "--own-sender")
        try:  # the slow readers held by the own sender, /healthz libmicrohttpd's
            url3, _ = cached_url(d3, MESH_REQ)
            obj3 = url3[:-len("drc")] + "obj"
            http_get(obj3)
            slow_row("isomeshd --own-sender",
                     slow_readers(d3.port, obj3[len("http://127.0.0.1:%d" % d3.port):], "/healthz"))
        finally:
            d3.stop(timeout=30)
            d3.cleanup()
        if nurl:
            nport = int(nurl.split(":")[2].split("/")[0])
            nslow = slow_readers(nport, "/m.obj", "/healthz")
            slow_row("nginx (1 worker) the same file", nslow)
            print("isomeshd / nginx: p99 %.2fx, max %.2fx" % (slow["p99"] / nslow["p99"],
                                                             slow["max"] / nslow["max"]))
        for name, res in (("all attributes", results), ("positions only", pos)):
            print("goal (%s): >= 12000 req/s at 16 connections: %.0f (%s); p99 < 10 ms at 64: "
                  "%.3f ms (%s)" % (name, res[16]["rps"], "met" if res[16]["rps"] >= 12000 else
                                    "NOT met", res[64]["p99"],
                                    "met" if res[64]["p99"] < 10 else "NOT met"))
    finally:
        if ceiling:
            ceiling.terminate()
            ceiling.wait(timeout=10)
        for p in (nginx, nginx_all):
            if p:
                p.send_signal(signal.SIGQUIT)
                try:
                    p.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    p.kill()
        d.stop(timeout=30)
        d.cleanup()


def cold(build, tmp):
    """Distinct requests (so every one computes) through the daemon and through the command."""
    d = start_daemon(build, tmp, "--workers", "1", "--job-timeout", "10m")
    rows = []
    try:
        n = 3 if QUICK else 11
        cases = [("sphere (small)", lambda i: {"preset": "sphere", "params": {"r": 1 + i * 1e-4}}),
                 ("kummer-16-nodes depth 8 (100k tri)",
                  lambda i: {"preset": "kummer-16-nodes", "depth": {"max": 8},
                             "max_error": None, "box": [-2 - i * 1e-4, -2, -2, 2, 2, 2]})]
        print("\n%-36s %12s %12s %12s %12s" % ("cold request (median of %d)" % n, "command ms",
                                               "daemon ms", "worker ms", "overhead ms"))
        d.post("/v1/mesh", {"preset": "sphere", "params": {"r": 0.5}}, timeout=300)  # warm-up
        for name, make in cases:
            cmd_t, dmn_t, wrk_t, tot_t = [], [], [], []
            for i in range(n):
                req_cmd = make(2 * i)
                req_dmn = make(2 * i + 1)
                path = os.path.join(tmp, "req.json")
                with open(path, "w") as f:
                    json.dump(req_cmd, f)
                out = os.path.join(tmp, "out.drc")
                t0 = time.perf_counter()
                subprocess.run([os.path.join(build, "isomesh"), path, "-o", out], check=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                cmd_t.append((time.perf_counter() - t0) * 1e3)
                t0 = time.perf_counter()
                r = d.post("/v1/mesh", req_dmn, timeout=300)
                dmn_t.append((time.perf_counter() - t0) * 1e3)
                assert r.status == 200 and r.header("X-Cache") == "miss", (r.status, r.body[:200])
                m = re.search(r"worker;dur=([\d.]+)", r.header("Server-Timing") or "")
                wrk_t.append(float(m.group(1)) if m else float("nan"))
                m = re.search(r"total;dur=([\d.]+)", r.header("Server-Timing") or "")
                tot_t.append(float(m.group(1)) if m else float("nan"))
            c, dm, w = statistics.median(cmd_t), statistics.median(dmn_t), statistics.median(wrk_t)
            inside = statistics.median(a - b for a, b in zip(dmn_t, wrk_t))
            # the daemon's own clock: its request's start to the answer queued, less the worker
            in_daemon = statistics.median(a - b for a, b in zip(tot_t, wrk_t))
            rows.append((name, c, dm, w, inside, in_daemon))
            print("%-36s %12.2f %12.2f %12.2f %12.2f" % (name, c, dm, w, dm - c))
        print("(overhead = daemon wall - command wall, where the command also starts a process;\n"
              " daemon wall - worker time, the service's own part (HTTP, queue, framing, copies): %s ms;\n"
              " of it inside the daemon, Server-Timing total - worker: %s ms, the rest the client's\n"
              " connection, upload and reading the answer)"
              % (", ".join("%.2f" % r[4] for r in rows), ", ".join("%.2f" % r[5] for r in rows)))
        vs_cmd = max(r[2] - r[1] for r in rows)
        own = max(r[4] for r in rows)
        print("goal: cold-request overhead <= 5 ms: daemon - command worst %.2f ms (%s); the "
              "service's own part worst %.2f ms (%s)" % (vs_cmd, "met" if vs_cmd <= 5 else "NOT met",
                                                         own, "met" if own <= 5 else "NOT met"))
        print("(the command and the daemon run one after the other: on a loaded machine their "
              "difference is mostly noise; the service's own part is measured inside one request)")
    finally:
        d.stop(timeout=30)
        d.cleanup()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    args = ap.parse_args()
    build = os.path.abspath(args.build)
    if not shutil.which("wrk"):
        print("bench_http: wrk is not installed (deploy/install-deps.sh test)")
        return 1
    tmp = tempfile.mkdtemp(prefix="bench_http_")
    try:
        throughput(build, tmp)
        cold(build, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
