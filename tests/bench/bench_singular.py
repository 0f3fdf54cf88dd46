#!/usr/bin/env python3
"""bench_singular.py — the singular stage's time (the locus from f, the conformance pass, double
sheets) beside the polygoniser's on every preset at its default box, on the two paths a preset is
meshed by: under the default error bound (1e-3 x the box diagonal, the dual mesher: what
`isomesh --surface P` and a request without "max_error" do; the "bound" columns) and on the
depth path at the preset's depth (max_error null; the "depth" columns). Both are measured inside
one ism_mesh_surface call (bench_singular.c; shortest of 3 runs each), in wall time and in process
CPU time (the CPU ratio is what the load of a shared machine does not distort).
The issue's goal: the stage adds at most 25% to polygonise time on every preset, on either path:
a row over it is flagged (OVER: CPU ratio; "over (wall only)"), with the path(s). Printed, never
asserted (speed is not a unit test on a shared machine). Instruction counts (callgrind,
`bench_singular --preset P --path bound --threads 1 --repeats 1`) are the repeatable figure.

  bench_singular.py --build build/release [--threads N] [--path bound|depth|both] [--preset P]"""
import argparse
import json
import os
import subprocess
import sys


GOAL = 0.25  # the bound on singular / polygonise


def flag(rows):
    """OVER when a path's CPU ratio is over the goal, "over (wall only)" when only its wall
    ratio is; the paths named."""
    cpu = [r["path"] for r in rows if r and r["cpu_ratio"] > GOAL]
    wall = [r["path"] for r in rows if r and r["ratio"] > GOAL and r["path"] not in cpu]
    out = ""
    if cpu:
        out += "  OVER (" + ", ".join(cpu) + ")"
    if wall:
        out += "  over (wall only: " + ", ".join(wall) + ")"
    return out


def cells(r):
    if not r:
        return f"{'':>8}{'':>13}{'':>11}{'':>8}{'':>8}{'':>11}"
    return (f"{r['depth']:>8}{r['polygonise_ms']:>13.1f}{r['singular_ms']:>11.1f}"
            f"{100 * r['ratio']:>7.1f}%{100 * r['cpu_ratio']:>7.1f}%{r['conform_ms']:>11.1f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--path", choices=["bound", "depth", "both"], default="both")
    ap.add_argument("--preset", help="this preset only")
    args = ap.parse_args()
    exe = os.path.join(args.build, "bench", "bench_singular")
    if not os.path.exists(exe):
        sys.exit(f"bench_singular.py: {exe} is missing (make bench builds it)")
    cmd = [exe, "--threads", str(args.threads), "--path", args.path]
    if args.preset:
        cmd += ["--preset", args.preset]
    proc = subprocess.run(cmd,
                          stdout=subprocess.PIPE, text=True, timeout=3600, check=True)
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]
    worst = [r for r in rows if "worst" in r]
    by = {}
    for r in rows:
        if "preset" in r:
            by.setdefault(r["preset"], {})[r["path"]] = r
    head = f"{'depth':>8}{'polygon. ms':>13}{'sing. ms':>11}{'ratio':>8}{'cpu':>8}{'conform ms':>11}"
    print(f"{'':<18}{'--- default bound (1e-3 x diagonal) ---':^59}"
          f"{'--- depth path ---':^59}")
    print(f"{'preset':<18}{head}{head}{'points':>8}{'cert':>6}  goal <= {100 * GOAL:.0f}%")
    for name, pr in by.items():
        b, d = pr.get("bound"), pr.get("depth")
        some = b or d
        print(f"{name:<18}{cells(b)}{cells(d)}{some['points']:>8}{some['certified']:>6}"
              f"{flag([b, d])}")
    for w in worst:
        print(f"worst ({w['path']}): {w['worst']} {100 * w['ratio']:.1f}% wall, {w['worst_cpu']} "
              f"{100 * w['cpu_ratio']:.1f}% CPU (goal <= {100 * GOAL:.0f}%)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
