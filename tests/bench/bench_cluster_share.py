#!/usr/bin/env python3
"""bench_cluster_share.py — what the cluster queue's scripts (server/isomeshd/cluster.c) cost
Redis as the number of users grows: U users with J queued entries each (put there by the
daemon's own enqueue script), one user holding two of them running on a daemon; then Redis's
own time (INFO commandstats: a script call's microseconds) for the heartbeat of a running
entry (its fair-share check on), the heartbeat that gives the entry back (every worker busy),
a take of the next entry, and the service-wide depth count.

The scripts are the daemon's: taken from cluster.c through the C preprocessor, so the bench
follows the code. The reference is the same scripts at 10 users in the same run: a cost that
grows with the users shows in the ratio. Prints one line per user count and figure; asserts
nothing.

    python3 tests/bench/bench_cluster_share.py [--users 10,100,1000] [--jobs 10] [--reps 50]
"""
import argparse
import os
import re
import socket
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "deploy"))
import stack  # noqa: E402  (redis-server with the shipped configuration)

P = "isomesh:v1:"          # the default namespace's prefix
DAEMON = "bench/1/0"       # the daemon running the entries
STATE_TTL_MS = "3600000"
LIMIT_JOBS = "1000000"     # --user-jobs: never the limit here


class Conn:
    """One connection, pipelined commands (stack.py's reply reader)."""

    def __init__(self, port):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=60)
        self.f = self.sock.makefile("rb")

    def pipeline(self, commands):
        buf = []
        for args in commands:
            buf.append(b"*%d\r\n" % len(args))
            for a in args:
                b = a if isinstance(a, bytes) else str(a).encode()
                buf.append(b"$%d\r\n%s\r\n" % (len(b), b))
        self.sock.sendall(b"".join(buf))
        return [stack._read_reply(self.f) for _ in commands]

    def __call__(self, *args):
        return self.pipeline([args])[0]


def fill(r, lua, users, jobs):
    """users x jobs entries through the enqueue script (KEYS stream, job hash, ulim)."""
    sha = r("SCRIPT", "LOAD", lua["ENQUEUE_LUA"])
    batch = []
    for u in range(users):
        for j in range(jobs):
            name = "k%05d%03d.drc" % (u, j)
            batch.append(["EVALSHA", sha, 3, P + "q:u%05d" % u, P + "job:" + name, P + "ulim",
                          "u%05d" % u, LIMIT_JOBS, name, "k", "drc", "{}", "0", STATE_TTL_MS,
                          DAEMON, P])
            if len(batch) >= 1000:
                r.pipeline(batch)
                batch = []
    if batch:
        r.pipeline(batch)


def timed(r, commands):
    """Redis's own microseconds for each script call: its EVALSHA time in INFO commandstats,
    reset before each call (SLOWLOG would do, but Redis 7 logs a script's inner commands too)."""
    out = []
    for c in commands:
        info = r.pipeline([["CONFIG", "RESETSTAT"], c, ["INFO", "commandstats"]])[2].decode()
        m = re.search(r"^cmdstat_evalsha:calls=1,usec=(\d+),", info, re.M)
        if not m:
            raise RuntimeError("no evalsha time in INFO commandstats:\n" + info)
        out.append(int(m.group(1)))
    return out


def one_scale(port, lua, users, jobs, reps):
    r = Conn(port)
    r("FLUSHALL")
    fill(r, lua, users, jobs)
    r("SET", P + "alive:" + DAEMON, "1")
    r("HSET", P + "nworkers", DAEMON, "64")   # room left: the check runs to its end
    s = P + "q:u00000"
    got = r("XREADGROUP", "GROUP", "workers", DAEMON, "COUNT", 2, "STREAMS", s, ">")
    ids = [e[0].decode() for e in got[0][1]]
    # the user's counts told of the two taken (the drop script with no entry: its refresh)
    r("EVAL", lua["DROPPED_LUA"], 2, s, P + "job:none", "0-1", P)
    hb = r("SCRIPT", "LOAD", lua["HEARTBEAT_LUA"])
    # KEYS stream, job hash; ARGV consumer, id, progress, ttl, prefix, name, now, give back, user
    beat = ["EVALSHA", hb, 2, s, P + "job:k00000000.drc", DAEMON, ids[0], "0.5", STATE_TTL_MS, P,
            "k00000000.drc", "0", "1", "u00000"]
    beats = timed(r, [beat] * reps)
    r("HSET", P + "nworkers", DAEMON, "2")    # every worker busy: the user gives one back
    back = timed(r, [beat])
    if r("HGET", P + "job:k00000000.drc", "state") != b"queued":
        raise RuntimeError("the heartbeat did not give the entry back")
    dp = r("SCRIPT", "LOAD", lua["DEPTH_LUA"])
    depth = timed(r, [["EVALSHA", dp, 1, P + "nwait"]] * reps)
    tk = r("SCRIPT", "LOAD", lua["TAKE_LUA"])
    takes = timed(r, [["EVALSHA", tk, 2, P + "wait", P + "run", P, DAEMON, "3000", i, "0",
                       STATE_TTL_MS] for i in range(reps)])
    r.sock.close()
    return {"heartbeat": beats, "give-back": back, "take": takes, "depth": depth}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--users", default="10,100,1000")
    ap.add_argument("--jobs", type=int, default=10)
    ap.add_argument("--reps", type=int, default=50)
    ap.add_argument("--build", help="run_bench.py's; unused (the scripts come from the source)")
    a = ap.parse_args()
    lua = stack.cluster_scripts()
    red = stack.Redis()
    red.start()
    try:
        for users in [int(x) for x in a.users.split(",")]:
            res = one_scale(red.port, lua, users, a.jobs, a.reps)
            for what, us in res.items():
                print("users=%d jobs=%d %-10s median %8.1f us  p90 %8.1f us  (n=%d, Redis's commandstats)"
                      % (users, a.jobs, what, statistics.median(us),
                         sorted(us)[int(0.9 * (len(us) - 1))], len(us)), flush=True)
    finally:
        red.cleanup()


if __name__ == "__main__":
    main()
