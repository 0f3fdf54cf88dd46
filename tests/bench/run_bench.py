#!/usr/bin/env python3
"""run_bench.py — runs every benchmark script tests/bench/bench_*.py in turn, passing the build
directory, and prints their tables. Benchmarks print figures beside a reference tool measured
in the same run; they assert nothing (speed is never a unit test on a shared machine)."""
import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--only", default="")
    args = ap.parse_args()
    build = os.path.join(ROOT, args.build)
    rc = 0
    for f in sorted(os.listdir(HERE)):
        if f.startswith("bench_") and f.endswith(".py") and args.only in f:
            print(f"\n##### {f}", flush=True)
            r = subprocess.run([sys.executable, os.path.join(HERE, f), "--build", build], cwd=ROOT)
            rc = rc or r.returncode
    return rc


if __name__ == "__main__":
    sys.exit(main())
