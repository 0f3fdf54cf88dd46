#!/usr/bin/env python3
"""bench_singular.py — the singular stage's time (the locus from f, the conformance pass, double
sheets) beside the polygoniser's on every preset at its default box and depth, both measured
inside one ism_mesh_surface call (bench_singular.c; shortest of 3 runs each), in wall time and in
process CPU time (the CPU ratio is what the load of a shared machine does not distort).
The issue's goal: the stage adds at most 25% to polygonise time on every preset. Printed,
never asserted (speed is not a unit test on a shared machine).

  bench_singular.py --build build/release [--threads N]"""
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
    exe = os.path.join(args.build, "bench", "bench_singular")
    if not os.path.exists(exe):
        sys.exit(f"bench_singular.py: {exe} is missing (make bench builds it)")
    proc = subprocess.run([exe, "--threads", str(args.threads)], stdout=subprocess.PIPE,
                          text=True, timeout=1800, check=True)
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]
    worst = [r for r in rows if "worst" in r]
    rows = [r for r in rows if "preset" in r]
    print(f"{'preset':<18}{'depth':>6}{'polygonise ms':>15}{'singular ms':>13}{'ratio':>8}"
          f"{'cpu ratio':>10}{'conform ms':>12}{'points':>8}{'cert':>6}{'boxes':>7}  goal <= 25%")
    for r in rows:
        # CPU first: on a loaded machine the wall ratio says more about the other jobs
        flag = ("  OVER" if r["cpu_ratio"] > 0.25 else
                "  over (wall only)" if r["ratio"] > 0.25 else "")
        print(f"{r['preset']:<18}{r['depth']:>6}{r['polygonise_ms']:>15.1f}"
              f"{r['singular_ms']:>13.1f}{100 * r['ratio']:>7.1f}%{100 * r['cpu_ratio']:>9.1f}%"
              f"{r['conform_ms']:>12.1f}{r['points']:>8}{r['certified']:>6}{r['boxes']:>7}{flag}")
    for w in worst:
        print(f"worst: {w['worst']} {100 * w['ratio']:.1f}% wall, {w['worst_cpu']} "
              f"{100 * w['cpu_ratio']:.1f}% CPU (goal <= 25%)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
