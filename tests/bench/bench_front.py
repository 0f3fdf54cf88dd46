#!/usr/bin/env python3
"""bench_front.py — the shipped nginx front (deploy/nginx/isomesh.conf, as tests/deploy/stack.py
generates it: every upstream pointed at one daemon, one nginx worker per core) beside the
daemon it fronts, in the same run: wrk fetching one cached mesh by key
(/v1/meshes/{key}.drc, kummer-16-nodes at depth 8, ~310 KB) at 16, 64 and 256 connections,
directly and through nginx (its proxy_cache answers every request after the first).

Goal (issue 17): through nginx >= 80% of the daemon's direct req/s. Also the servers' CPU
microseconds and voluntary context switches (wake-ups) per request (nginx's workers; the
daemon's threads), the figures a loaded machine distorts least: with a load average far above
the core count the req/s ratio measures how the scheduler shares the cores (the daemon runs
two polling threads per core beside its other threads, nginx a worker per core),
and the CPU ratio says what the same throughput would cost on an idle machine; the cores
column (server + wrk CPU per second of the run) shows the share each run got, and
req/s = cores / (server + wrk CPU per request) gives the ratio at an equal share (on the
lead's idle run, 2 cores / (95 + 104 us) = 10k req/s, what both servers reached at 16). Also prints
how many of the daemon's answers went out by sendfile from the disk cache (issue 16: bodies
of 1 MB or more, so none for this mesh). Prints the load average before and after, and ends
with one line, the req/s ratio beside both loads and whether the machine was idle (the goal is
judged on an idle machine only: load average below the core count throughout). The lead's idle
run: `make bench BENCH_ONLY=bench_front` (or `python3 tests/bench/bench_front.py --build
build/release`). Asserts nothing."""
import argparse
import os
import shutil
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "deploy"))
import bench_http  # noqa: E402
import stack  # noqa: E402

QUICK = os.environ.get("ISOMESH_TEST_QUICK") == "1"
CONNS = (16, 64, 256)
GOAL = 0.8


def load_text():
    return " ".join("%.1f" % x for x in os.getloadavg())


def idle():
    """The machine counts as idle while the 1-minute load average is below its core count."""
    return os.getloadavg()[0] < (os.cpu_count() or 1)


def nginx_front(daemon_port):
    """stack.Nginx on the shipped site, with a worker per core as Debian's nginx.conf has."""
    n = stack.Nginx([daemon_port])
    with open(n.conf) as f:
        text = f.read()
    with open(n.conf, "w") as f:
        f.write(text.replace("worker_processes 1;", "worker_processes auto;")
                    .replace("worker_connections 512;", "worker_connections 2048;"))
    return n.start()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    args = ap.parse_args()
    build = os.path.abspath(args.build)
    if not shutil.which("wrk") or not stack.NGINX:
        print("skipped: wrk or nginx missing")
        return 0
    tmp = tempfile.mkdtemp(prefix="isomesh_bench_front_")
    d = bench_http.start_daemon(build, tmp, "--workers", "2")
    n = None
    try:
        url, body = bench_http.cached_url(d, bench_http.MESH_REQ)
        n = nginx_front(d.port)
        nurl = url.replace(":%d/" % d.port, ":%d/" % n.port)
        # Fill nginx's cache before timing: the first timed run would otherwise include the
        # miss, with every other connection waiting on proxy_cache_lock (nginx re-checks a
        # lock every 500 ms). Measured here: cache hits only.
        bench_http.http_get(nurl)
        secs = 2 if QUICK else 8
        load_before, idle_before = load_text(), idle()
        print("load average %s on %d cores" % (load_before, os.cpu_count()))
        print("%-34s %6s %10s %9s %9s %7s %8s %8s %8s %6s" % (
            "server", "conns", "req/s", "p50 ms", "p99 ms", ">2 s", "CPU/req", "wake/req",
            "wrk/req", "cores"))
        print("(CPU/req, wrk/req: CPU microseconds per request of the server, of wrk; wake/req: "
              "the server's voluntary context switches per request (/proc); cores: the CPU the "
              "two got per second of the run)")
        ratios, cpu_ratios, share_ratios, equal_share, wakes = [], [], [], [], []
        for conns in CONNS:
            direct = bench_http.wrk(url, conns, secs, pid=d.proc.pid)
            front = bench_http.wrk(nurl, conns, secs, pid=bench_http.nginx_workers(n.proc.pid))
            for name, r in (("isomeshd direct", direct), ("nginx front (shipped config)", front)):
                print("%-34s %6d %10.0f %9.3f %9.3f %7d %8.0f %8.2f %8.0f %6.2f%s" % (
                    name, conns, r["rps"], r["p50"], r["p99"], r["over2s"], r["cpu_us"],
                    r["vcs"], r["client_cpu_us"], r["cores"],
                    "  (%d non-2xx, %d socket errors)" % (r["bad"], r["errors"])
                    if r["bad"] or r["errors"] else ""))
            ratios.append(front["rps"] / direct["rps"])
            cpu_ratios.append(front["cpu_us"] / direct["cpu_us"])
            share_ratios.append(front["cores"] / direct["cores"])
            equal_share.append(bench_http.equal_share(front, direct))
            wakes.append((direct["vcs"], front["vcs"]))
        print("nginx front / daemon req/s: %s; goal >= %.0f%%: %s" % (
            ", ".join("%d conns %.2f" % (c, q) for c, q in zip(CONNS, ratios)), GOAL * 100,
            "met" if min(ratios) >= GOAL else "NOT met"))
        print("nginx front / daemon CPU per request (lower: the front costs less): %s" % ", ".join(
            "%d conns %.2f" % (c, q) for c, q in zip(CONNS, cpu_ratios)))
        print("wake-ups (voluntary context switches) per request, daemon / nginx front: %s"
              % ", ".join("%d conns %.2f / %.2f" % (c, w[0], w[1]) for c, w in zip(CONNS, wakes)))
        print("nginx front / daemon cores obtained (server + wrk; below 1: the front's run got "
              "less of the machine, which lowers its req/s whatever its cost): %s" % ", ".join(
                  "%d conns %.2f" % (c, q) for c, q in zip(CONNS, share_ratios)))
        print("nginx front / daemon req/s at an equal share of the machine (req/s = cores / "
              "(server + wrk CPU per request); on idle cores both runs are CPU-bound): %s; "
              "goal >= %.0f%%: %s" % (", ".join("%d conns %.2f" % (c, q)
                                                for c, q in zip(CONNS, equal_share)),
                                      GOAL * 100, "met" if min(equal_share) >= GOAL else
                                      "NOT met"))
        print("daemon answers sent from the disk cache file (sendfile): %d"
              % d.metric("isomesh_sendfile_responses_total"))
        was_idle = idle_before and idle()
        print("RESULT nginx front / daemon req/s: min %.2f (%s), goal >= %.2f: %s; at an equal "
              "share min %.2f; load average %s before, %s after, %d cores: %s" % (
                  min(ratios), ", ".join("%d conns %.2f" % (c, q) for c, q in zip(CONNS, ratios)),
                  GOAL, "met" if min(ratios) >= GOAL else "NOT met", min(equal_share),
                  load_before, load_text(),
                  os.cpu_count(), "idle machine, the ratio counts" if was_idle else
                  "NOT idle: compare the equal-share and CPU ratios, rerun idle for the goal"))
    finally:
        if n:
            n.cleanup()
        d.cleanup()
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
