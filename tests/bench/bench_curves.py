#!/usr/bin/env python3
"""bench_curves.py — issue 14's benchmark: an ellipsoid cut by 200 seeded random quadrics
(bench_curves.c), the arrangement's size, its Euler check and the time per half-edge pair
(cut + arrangement, wall and CPU) beside the seed paper's CGAL figure (399.8 s for 155,176
edges: 2.58 ms per pair). Goal: at most 1/100 of the seed's time per pair. Printed, never
asserted (speed is not a unit test on a shared machine).

  bench_curves.py --build build/release [--threads N]"""
import argparse
import json
import os
import subprocess
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--threads", type=int, default=0)
    args = ap.parse_args()
    exe = os.path.join(args.build, "bench", "bench_curves")
    if not os.path.exists(exe):
        sys.exit(f"bench_curves.py: {exe} is missing (make bench builds it)")
    out = subprocess.run([exe, "--quadrics", "200", "--depth", "8", "--threads",
                          str(args.threads)], stdout=subprocess.PIPE, text=True, timeout=1800,
                         check=True).stdout
    r = json.loads(out)
    cpu_pair = r["cut_cpu_ms"] / max(r["edges"], 1)
    print(f"ellipsoid x 200 quadrics (depth {r['depth']}): V {r['vertices']}  E {r['edges']}  "
          f"F {r['faces']}  Euler ok {r['euler_ok']} (chi {r['euler']})  unrefined {r['unrefined']}")
    print(f"  triangles {r['triangles_before']} -> {r['triangles']}; cut + arrangement "
          f"{r['cut_ms']:.0f} ms wall, {r['cut_cpu_ms']:.0f} ms CPU")
    print(f"  per half-edge pair: {r['ms_per_pair']:.4f} ms wall, {cpu_pair:.4f} ms CPU; "
          f"seed (CGAL, exact) {r['seed_ms_per_pair']:.3f} ms; ratio {r['ratio']:.4f} wall, "
          f"{cpu_pair / r['seed_ms_per_pair']:.4f} CPU  (goal <= 0.01)")
    print(f"  result hash {r['hash']}, arrangement hash {r['arrangement_hash']}; curve vertices "
          f"within {r['worst_f']:.2e} of f = 0, {r['worst_g']:.2e} of their g = 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
