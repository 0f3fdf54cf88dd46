#!/usr/bin/env python3
"""bench_live.py — the viewer's live exploration (issue 18): from a slider move to a changed
picture on every preset with a parameter, measured in headless Chromium by
tests/bench/live_preview.mjs (goal 300 ms), with the server's time for the last preview and the
load average (the figures mean little on a loaded machine); then how long the render mode's
occlusion holds the page on a large mesh (tests/bench/occlusion_pauses.mjs, long tasks).
Printed, never asserted.

  bench_live.py --build build/release"""
import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    args = ap.parse_args()
    env = dict(os.environ, ISOMESH_BUILD=os.path.relpath(args.build, ROOT))
    print("live preview: slider move -> changed picture (pixel difference in the page), goal 300 ms")
    r = subprocess.run(["node", os.path.join(HERE, "live_preview.mjs")], cwd=os.path.join(ROOT, "tests"),
                       env=env, timeout=1800)
    print("render mode on a large mesh: main-thread tasks over 50 ms while the occlusion is computed and shown")
    o = subprocess.run(["node", os.path.join(HERE, "occlusion_pauses.mjs")], cwd=os.path.join(ROOT, "tests"),
                       env=env, timeout=1800)
    return r.returncode or o.returncode


if __name__ == "__main__":
    sys.exit(main())
