#!/usr/bin/env python3
"""bench_load.py — isomeshd under sustained load (a soak), on 127.0.0.1:

1. The mix: wrk (Debian) at 256 connections for 60 s (--seconds) running tests/bench/
   load_mix.lua — GETs of 64 cached meshes and, one request in ten, a POST of a new small
   surface (a computation each). Every status is counted: the only refusals allowed are the
   designed ones (503 queue full, 429); anything else, and every socket error, is an error.
   Latency percentiles from wrk. Beside it, in the same run, the reference: the same wrk
   against the same daemon with cached GETs only (what the mix costs the cached path).
2. Memory: the daemon's resident set (VmRSS, /proc) sampled every 2 s from start to end of
   the mix, printed as a series with its growth after the first quarter (the memory cache is
   capped at --cache-mem 8M, full within seconds, so that a filling cache is not mistaken for
   a leak).
3. Slowloris: latency of a normal client (sequential GETs of a cached mesh, and POSTs of new
   surfaces) alone, then while 400 connections from four other loopback addresses trickle
   request headers a byte at a time (--client-conns 64).

`make soak` runs only this; `make bench` runs it with the others. tests/reliability/
test_load.py runs the mix for 10 s and asserts what can be asserted robustly (no errors beside
designed refusals, bounded RSS growth). Prints figures; asserts nothing."""
import argparse
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "http"))
import harness  # noqa: E402

MIX = os.path.join(HERE, "load_mix.lua")
DESIGNED = {503, 429}
CACHED_KEYS = 64


def start_daemon(build, tmp, *args):
    """A started isomeshd (tests/http/harness.py) with its log and cache in files under tmp: a
    soak logs 100k+ lines, which a reader thread would take CPU and memory to collect."""
    n = len(os.listdir(tmp))
    d = harness.Daemon(*args, binary=os.path.join(build, "isomeshd"), web_root="",
                       log_file=os.path.join(tmp, "isomeshd-%d.log" % n),
                       cache_dir=os.path.join(tmp, "cache-%d" % n))
    try:
        return d.start(timeout=30)
    except BaseException:
        d.cleanup()
        raise


def sphere(r):
    return {"expr": "x^2 + y^2 + z^2 - r^2", "params": {"r": r},
            "box": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5], "depth": {"max": 6}}


def parse_wrk(out):
    def num(pattern, default=0.0):
        m = re.search(pattern, out, re.M)
        return float(m.group(1)) if m else default

    def pct(p):
        m = re.search(r"^\s+%s%%\s+([\d.]+)(us|ms|s)\s*$" % p, out, re.M)
        if not m:
            return float("nan")
        v = float(m.group(1))
        return v / 1000 if m.group(2) == "us" else v * 1000 if m.group(2) == "s" else v

    statuses = {}
    m = re.search(r"^status (.*)$", out, re.M)
    for part in (m.group(1).split() if m else []):
        code, n = part.split("=")
        statuses[int(code)] = int(n)
    sock = {}
    m = re.search(r"Socket errors: connect (\d+), read (\d+), write (\d+), timeout (\d+)", out)
    if m:
        sock = dict(zip(("connect", "read", "write", "timeout"), map(int, m.groups())))
    return {"rps": num(r"Requests/sec:\s+([\d.]+)"), "requests": int(num(r"(\d+) requests in")),
            "p50": pct(50), "p75": pct(75), "p90": pct(90), "p99": pct(99),
            "statuses": statuses, "socket_errors": sock, "raw": out}


def run_wrk(port, keys_file, conns, seconds, new_share):
    env = dict(os.environ, KEYS=keys_file, NEW_SHARE=str(new_share))
    cmd = ["wrk", "-t2", "-c%d" % conns, "-d%ds" % seconds, "--timeout", "60s", "--latency",
           "-s", MIX, "http://127.0.0.1:%d" % port]
    out = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         env=env, timeout=seconds + 120).stdout
    return parse_wrk(out)


def errors_of(result):
    """Responses that are neither a success nor a designed refusal, plus socket errors."""
    bad = sum(n for code, n in result["statuses"].items() if code >= 400 and code not in DESIGNED)
    return bad + sum(result["socket_errors"].values())


def warm(d, tmp, n=CACHED_KEYS):
    keys = []
    for i in range(n):
        r = d.post("/v1/mesh", sphere(round(0.5 + i / 200, 4)))
        if r.status != 200:
            raise RuntimeError("warm-up request failed with %d" % r.status)
        keys.append(r.header("ETag").strip('"'))
    path = os.path.join(tmp, "keys-%d.txt" % len(os.listdir(tmp)))
    with open(path, "w") as f:
        f.write("\n".join(keys) + "\n")
    return path


def soak(build, tmp, seconds, conns, new_share, sample_s=2.0, cache_mem="32M"):
    """Runs the mix against a fresh daemon; returns the wrk figures and the RSS series."""
    d = start_daemon(build, tmp, "--workers", "2", "--queue", "64", "--user-jobs", "100000",
                     "--cache-mem", cache_mem, "--client-conns", "0")
    try:
        keys_file = warm(d, tmp)
        series = [(0.0, d.rss_mib())]
        box = {}
        t = threading.Thread(target=lambda: box.update(
            r=run_wrk(d.port, keys_file, conns, seconds, new_share)))
        t0 = time.time()
        t.start()
        while t.is_alive():
            t.join(sample_s)
            series.append((time.time() - t0, d.rss_mib()))
        result = box.get("r") or {"statuses": {}, "socket_errors": {"wrk": 1}, "rps": 0,
                                  "requests": 0, "raw": "wrk did not finish"}
        m = d.get("/metrics", timeout=120)
        result["metrics"] = m.body.decode() if m.status == 200 else ""
        result["rss"] = series
        result["exit"] = d.stop(timeout=60)
        return result
    finally:
        d.cleanup()


def rss_growth(series):
    """RSS at the end minus RSS a quarter into the run (MiB): start-up and cache filling left
    out."""
    if len(series) < 3:
        return float("nan")
    start = series[max(1, len(series) // 4)][1]
    return series[-1][1] - start


def percentiles(samples):
    s = sorted(samples)
    return s[len(s) // 2], s[min(len(s) - 1, int(len(s) * 0.99))]


def normal_client(d, n, tag):
    """Latencies (ms) of n sequential cached GETs and n/10 new computations."""
    gets, posts = [], []
    key = d.post("/v1/mesh", sphere(0.777)).header("ETag").strip('"')
    for i in range(n):
        t = time.perf_counter()
        status = d.get("/v1/meshes/%s.drc" % key, timeout=120).status
        gets.append((time.perf_counter() - t) * 1e3)
        if status != 200:
            raise RuntimeError("normal GET failed: %d" % status)
        if i % 10 == 0:
            t = time.perf_counter()
            status = d.post("/v1/mesh", sphere(round(0.3 + tag + i / 1e5, 6))).status
            posts.append((time.perf_counter() - t) * 1e3)
            if status != 200:
                raise RuntimeError("normal POST failed: %d" % status)
    return percentiles(gets), percentiles(posts)


def slowloris(build, tmp, n):
    d = start_daemon(build, tmp, "--workers", "2", "--client-conns", "64", "--conn-timeout", "30s")
    socks = []
    stop = threading.Event()
    try:
        alone = normal_client(d, n, 0.0)
        for source in ("127.0.0.2", "127.0.0.3", "127.0.0.4", "127.0.0.5"):
            for _ in range(100):
                try:
                    s = socket.create_connection(("127.0.0.1", d.port), timeout=5,
                                                 source_address=(source, 0))
                    s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
                    s.setblocking(False)
                    socks.append(s)
                except OSError:
                    pass

        def trickle():
            i = 0
            while not stop.is_set():
                for s in socks:
                    try:
                        s.send(b"X-%d: 1\r\n" % i)
                    except OSError:
                        pass
                i += 1
                stop.wait(1.0)
        t = threading.Thread(target=trickle, daemon=True)
        t.start()
        time.sleep(1)
        held = 0
        for s in socks:
            try:
                held += s.recv(1) != b""
            except BlockingIOError:
                held += 1
            except OSError:
                pass
        attacked = normal_client(d, n, 0.1)
        stop.set()
        t.join(5)
        return alone, attacked, len(socks), held
    finally:
        stop.set()
        for s in socks:
            s.close()
        d.stop(timeout=60)
        d.cleanup()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--seconds", type=int, default=60)
    ap.add_argument("--conns", type=int, default=256)
    ap.add_argument("--new-share", type=float, default=0.1)
    args = ap.parse_args()
    if not shutil.which("wrk"):
        print("bench_load: wrk is not installed (deploy/install-deps.sh test)")
        return 0
    tmp = tempfile.mkdtemp(prefix="bench_load_")
    try:
        print("isomeshd under load: %d connections, %d s, %d%% new computations, 2 workers, "
              "%d cached keys (wrk -t2 --timeout 60s -s load_mix.lua)"
              % (args.conns, args.seconds, round(args.new_share * 100), CACHED_KEYS))
        ref = soak(args.build, tmp, max(10, args.seconds // 4), args.conns, 0.0)
        mix = soak(args.build, tmp, args.seconds, args.conns, args.new_share, cache_mem="8M")
        print("\n%-34s %9s %9s %8s %8s %8s %8s  %s" % ("run", "requests", "req/s", "p50 ms",
                                                      "p90 ms", "p99 ms", "errors",
                                                      "statuses"))
        for name, r in (("cached GETs only (reference)", ref), ("the mix", mix)):
            print("%-34s %9d %9.0f %8.2f %8.2f %8.2f %8d  %s %s" % (
                name, r["requests"], r["rps"], r.get("p50", float("nan")),
                r.get("p90", float("nan")), r.get("p99", float("nan")), errors_of(r),
                " ".join("%d=%d" % kv for kv in sorted(r["statuses"].items())),
                "socket errors %s" % r["socket_errors"] if any(r["socket_errors"].values())
                else ""))
        started = re.search(r"^isomesh_computations_started_total (\d+)", mix["metrics"], re.M)
        print("computations started during the mix (warm-up included): %s; daemon exit %s"
              % (started.group(1) if started else "?", mix["exit"]))
        print("\nisomeshd resident memory (MiB) every 2 s during the mix:")
        print("  " + " ".join("%.0f" % v for _, v in mix["rss"]))
        print("  start %.1f, max %.1f, end %.1f; growth after the first quarter %+.1f MiB"
              % (mix["rss"][0][1], max(v for _, v in mix["rss"]), mix["rss"][-1][1],
                 rss_growth(mix["rss"])))
        alone, attacked, opened, held = slowloris(args.build, tmp, 300)
        print("\nslowloris: %d slow connections opened from 4 addresses, %d held by the daemon "
              "(--client-conns 64)" % (opened, held))
        print("%-34s %12s %12s %14s %14s" % ("normal client", "GET p50 ms", "GET p99 ms",
                                            "new mesh p50", "new mesh p99"))
        for name, ((g50, g99), (p50, p99)) in (("alone", alone), ("during the attack", attacked)):
            print("%-34s %12.2f %12.2f %14.1f %14.1f" % (name, g50, g99, p50, p99))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
