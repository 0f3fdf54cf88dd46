#!/usr/bin/env python3
"""bench_fairness.py — sharing one isomeshd (issue 10), with one worker so the order of service
is plain, the fair queue beside the fifo order (the reference) in the same run:

1. One user (127.0.0.1) floods N distinct jobs (gyroid ball, depth 7: a fraction of a second
   each); right after, a second user (127.0.0.2) submits one job. Figures: the second user's
   wait from submission to start (the job's queue_ms), how many flood jobs started before it,
   and the flood's job time (median worker time, from the job stats).
2. During the flood, the second user asks for a mesh that is already cached, many times in a
   row: latency of those cache hits (p50, p99, max) beside the same hits on an idle daemon
   and beside the job time.

Prints figures; asserts nothing."""
import argparse
import http.client
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
QUICK = os.environ.get("ISOMESH_TEST_QUICK") == "1"


def flood_request(i):
    return {"preset": "gyroid-ball", "params": {"k": 4 + i / 1000}, "depth": {"max": 7}}


HIT = {"preset": "sphere"}


def call(port, method, path, body=None, source="127.0.0.1"):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120, source_address=(source, 0))
    try:
        hdrs = {}
        if body is not None:
            body = json.dumps(body).encode()
            hdrs["Content-Type"] = "application/json"
        conn.request(method, path, body=body, headers=hdrs)
        r = conn.getresponse()
        return r.status, r.read()
    finally:
        conn.close()


def hit_latencies(port, n):
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        status, _ = call(port, "POST", "/v1/mesh", HIT, source="127.0.0.2")
        out.append((time.perf_counter() - t0) * 1e3)
        if status != 200:
            raise RuntimeError("cache hit answered %d" % status)
    return out


def pct(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]


def job(port, url, source="127.0.0.1"):
    return json.loads(call(port, "GET", url, source=source)[1])


def run(order, n_flood, n_hits):
    from harness import Daemon  # noqa: E402 (ISOMESH_BUILD set by main)
    with Daemon("--workers", "1", "--queue", str(n_flood + 10), "--user-jobs", str(n_flood + 10),
                "--queue-order", order) as d:
        if call(d.port, "POST", "/v1/mesh", HIT, source="127.0.0.2")[0] != 200:
            raise RuntimeError("warm-up failed")
        idle = hit_latencies(d.port, n_hits)
        flood = []
        for i in range(n_flood):
            status, body = call(d.port, "POST", "/v1/jobs", flood_request(i))
            flood.append(json.loads(body))
        status, body = call(d.port, "POST", "/v1/jobs", flood_request(10000), source="127.0.0.2")
        single = json.loads(body)
        busy = hit_latencies(d.port, n_hits)
        deadline = time.time() + 600
        while time.time() < deadline:
            single = job(d.port, single["url"], source="127.0.0.2")
            if single["state"] not in ("queued", "running"):
                break
            time.sleep(0.01)
        listed = {j["id"]: j for j in json.loads(call(d.port, "GET", "/v1/jobs")[1])["jobs"]}
        before = sum(1 for j in flood if "started" in listed[j["id"]] and
                     listed[j["id"]]["started"] < single["started"])
        times = []
        for j in flood:
            full = job(d.port, j["url"])
            if full["state"] == "done":
                times.append(full["stats"]["timings_ms"]["total"])
        for j in flood:
            if listed[j["id"]]["state"] in ("queued", "running"):
                call(d.port, "DELETE", j["url"])
        return {"order": order, "wait_ms": single.get("queue_ms", float("nan")),
                "before": before, "job_ms": statistics.median(times) if times else float("nan"),
                "idle": idle, "busy": busy}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(HERE, "..", "..", "build", "release"))
    args = ap.parse_args()
    os.environ["ISOMESH_BUILD"] = os.path.abspath(args.build)
    sys.path.insert(0, os.path.join(HERE, "..", "http"))
    n_flood = 10 if QUICK else 30
    n_hits = 50 if QUICK else 200
    rows = [run("fair", n_flood, n_hits), run("fifo", n_flood, n_hits)]
    print("One worker; user A floods %d jobs, then user B submits one; B asks for a cached mesh "
          "%d times during the flood." % (n_flood, n_hits))
    print("%-6s %10s %12s %14s | %-26s | %-26s" % ("order", "job (ms)", "B waits (ms)",
                                               "A's jobs first", "hit idle p50/p99/max (ms)",
                                               "hit in flood p50/p99/max"))
    for r in rows:
        print("%-6s %10.0f %12.0f %14d | %7.2f %7.2f %8.2f  | %7.2f %7.2f %8.2f" % (
            r["order"], r["job_ms"], r["wait_ms"], r["before"],
            pct(r["idle"], 50), pct(r["idle"], 99), max(r["idle"]),
            pct(r["busy"], 50), pct(r["busy"], 99), max(r["busy"])))
    fair, fifo = rows
    print("B's wait: %.1f job times with the fair queue, %.1f with fifo; cache hits in a flood: "
          "p99 %.2f ms = %.4f job times" % (
              fair["wait_ms"] / fair["job_ms"], fifo["wait_ms"] / fifo["job_ms"],
              pct(fair["busy"], 99), pct(fair["busy"], 99) / fair["job_ms"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
