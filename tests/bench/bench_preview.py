#!/usr/bin/env python3
"""bench_preview.py — the server's time for a live preview (issue 18: ≤ 150 ms on every
preset), per preset with a parameter: the request the viewer sends while a slider moves
(web/js/live.js: the preset at depth 4, normals only), as a full request and with
"preview": true. Each request is a cache miss (a parameter value not asked for before); the
time is the worker's own (stats timings_ms.total), not the wall time, which at a load of
10-20 on 2 cores is mostly waiting. A measurement, not a test.

  bench_preview.py [--build build/release] [--depth 4] [--values 3] [--presets a,b]"""
import argparse
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "http"))
from harness import Daemon  # noqa: E402


def server_ms(d, body):
    r = d.post("/v1/mesh", body)
    if r.status != 200:
        raise SystemExit("%s: %d %s" % (body, r.status, r.body[:200]))
    key = r.header("ETag").strip('"')
    s = d.get("/v1/meshes/%s/stats" % key).json()
    return s["timings_ms"], s["mesh"]["triangles"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=None)
    ap.add_argument("--depth", type=int, default=4)
    ap.add_argument("--values", type=int, default=3)
    ap.add_argument("--presets", default="")
    a = ap.parse_args()
    binary = os.path.join(a.build, "isomeshd") if a.build else None
    only = [p for p in a.presets.split(",") if p]
    with Daemon("--workers", "1", binary=binary) as d:
        presets = [p for p in d.get("/v1/presets").json()["presets"]
                   if p["params"] and (not only or p["name"] in only)]
        print("preset               full ms (tri)        preview ms (tri)   [median of %d, depth %d,"
              " load %.1f]" % (a.values, a.depth, os.getloadavg()[0]))
        for p in presets:
            q = p["params"][0]
            rows = {False: [], True: []}
            for i in range(a.values):
                v = q["min"] + (q["max"] - q["min"]) * (0.31 + 0.17 * i)
                for preview in (False, True):
                    body = {"preset": p["name"], "params": {q["name"]: v},
                            "depth": {"min": 3, "max": a.depth},
                            "output": {"attributes": ["normal"]}}
                    if preview:
                        body["preview"] = True
                    t, tri = server_ms(d, body)
                    rows[preview].append((t["total"], tri, t))
            full = statistics.median(r[0] for r in rows[False])
            prev = statistics.median(r[0] for r in rows[True])
            print("%-18s %8.0f (%6d) %12.0f (%6d)" % (p["name"], full, rows[False][0][1], prev,
                                                    rows[True][0][1]))
        print("load average at the end %.1f" % os.getloadavg()[0])


if __name__ == "__main__":
    main()
