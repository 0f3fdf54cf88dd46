#!/usr/bin/env python3
"""mesh_identity.py — the check that a speed change changes no mesh: the PLY md5 of every preset
of the gallery (its own box and depths, one thread), of a set of presets in boxes shifted off the
octree lattice (tests/cli/boxes.py: by 1e-3, and by irrational fractions of a finest cell) on
two threads, and of max_error runs of the primal polygons (several rounds, lattice and shifted
boxes, 1 and 2 threads) and of the dual mesh (the default under a bound; also where the box cuts
the surface), and of quality-pass runs (`--quality good`, QUALITY_RUNS: at the default bound
in the lattice and shifted boxes, and on the depth path), through the CLI. Those PLYs are core's writer's (positions, ∇f normals); the
"wire" runs write every preset's PLY as the service sends it (a request file with every
attribute: proto/mesh_files.c's writer, the crease rows, curvature and class), so a change to
what the downloads carry shows there.
`--save FILE` records them; `--check FILE` runs again and names every run whose mesh differs.
Not part of `make test` (a few minutes on two cores); run it before and after a change:

  mesh_identity.py --build build/release --save /tmp/before.json
  (change, rebuild)
  mesh_identity.py --build build/release --check /tmp/before.json

The PLY holds positions, normals and faces as the polygoniser's pipeline made them (locus,
conformance included), so equal md5s mean byte-identical meshes."""
import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep_singular import boxes, presets  # noqa: E402  (the gallery and the shifted boxes)

# Presets also run in the shifted boxes, on two threads: smooth, crease, singular, lattice-plane.
SHIFTED = ("sphere", "torus", "gyroid-ball", "klein-bottle", "steiner-roman", "kummer-16-nodes",
           "cube-minus-ball", "helicoid", "double-torus", "whitney-umbrella")
# max_error runs of the primal polygons (preset, E, depth.max; --no-dual: under a bound the
# dual mesh is the default where it applies): one to five refinement rounds each.
ERROR_RUNS = (("sphere", 1e-3, 10), ("torus", 3e-3, 10), ("torus", 6e-4, 10),
              ("gyroid-ball", 1e-2, 10), ("klein-bottle", 1e-2, 9), ("double-torus", 3e-3, 9))
# ... and of the default under a bound, the dual mesh (core/octree/dual.h) where it applies.
DUAL_RUNS = (("sphere", 1e-3, 10), ("torus", 3e-3, 10), ("double-torus", 3e-3, 9))
# ... and of the dual mesh clipped by a box that cuts the surface (core/octree/dual_box.c):
# E = 2e-3 and 2e-3 / 3 of the box's largest width (the presets' own checks), depth.max 10.
CUT_RUNS = ("hyperboloid", "catenoid", "scherk", "helicoid", "clebsch-cubic")
CUT_REL = (2e-3, 2e-3 / 3)
# The quality pass (`--quality good`, core/remesh/): smooth, crease and singular presets at the
# default bound in the lattice and shifted boxes, and on the depth path in the preset's box.
QUALITY_RUNS = ("sphere", "torus", "pretzel-genus2", "gyroid-ball", "cube-minus-ball",
                "klein-bottle", "steiner-roman", "kummer-16-nodes", "cross-cap", "three-balls",
                "cube")


# The service's PLY with every attribute (the viewer's download link).
WIRE_ATTRIBUTES = ["normal", "mean_curvature", "gauss_curvature", "class"]


def md5_of_run(exe, name, box, depth, extra, timeout):
    """extra: the CLI's flags (a list), or a dict: then a request file with those fields."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "m.ply")
        if isinstance(extra, dict):
            req = os.path.join(tmp, "r.json")
            lo, hi = depth.split(":")
            with open(req, "w") as f:
                json.dump({"preset": name, "box": box, "depth": {"min": int(lo), "max": int(hi)},
                           **extra}, f)
            cmd = [exe, req, "-o", out]
        else:
            cmd = [exe, "--surface", name, "-b", ",".join(repr(v) for v in box), "-d", depth,
                   "-o", out, *extra]
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=tmp)
        except subprocess.TimeoutExpired:
            return "timeout"
        if r.returncode != 0:
            return "error: " + r.stderr.strip()[:200]
        with open(out, "rb") as f:
            return hashlib.md5(f.read()).hexdigest()


def runs(ps):
    """(key, name, box, depth, extra) of every run."""
    out = []
    by_name = {p["name"]: p for p in ps}
    # the depth path at the preset's depth: --max-error 0 (off; "0" also reads on binaries
    # from before the default bound, so before and after compare the same runs)
    off = ["--max-error", "0"]
    for p in ps:
        d = f"{p['depth']['min']}:{p['depth']['max']}"
        out.append((f"{p['name']} own d{d} t1", p["name"], p["box"], d, ["--threads", "1", *off]))
    for p in ps:  # the same meshes as the service writes them
        d = f"{p['depth']['min']}:{p['depth']['max']}"
        out.append((f"{p['name']} own d{d} wire", p["name"], p["box"], d,
                    {"max_error": None, "output": {"attributes": WIRE_ATTRIBUTES}}))
    for name in SHIFTED:
        p = by_name[name]
        d = f"{p['depth']['min']}:{p['depth']['max']}"
        for label, box in boxes(p["box"], p["depth"]["max"])[1:]:
            out.append((f"{name} {label} d{d} t2", name, box, d, ["--threads", "2", *off]))
    for name, e, dmax in ERROR_RUNS:
        p = by_name[name]
        d = f"{p['depth']['min']}:{dmax}"
        for label, box in boxes(p["box"], dmax):
            for t in ("1", "2") if label != "1e-3" else ("2",):
                out.append((f"{name} {label} E{e:g} d{d} t{t}", name, box, d,
                            ["--max-error", repr(e), "--threads", t, "--no-dual"]))
    for name, e, dmax in DUAL_RUNS:
        p = by_name[name]
        d = f"{p['depth']['min']}:{dmax}"
        for label, box in boxes(p["box"], dmax):
            out.append((f"{name} {label} E{e:g} d{d} t1 dual", name, box, d,
                        ["--max-error", repr(e), "--threads", "1"]))
    for name in CUT_RUNS:
        p = by_name[name]
        d = f"{p['depth']['min']}:10"
        for label, box in boxes(p["box"], 10):
            for rel in CUT_REL:
                e = rel * max(box[a + 3] - box[a] for a in range(3))
                out.append((f"{name} {label} E{rel:.3g}w d{d} t1 cut", name, box, d,
                            ["--max-error", repr(e), "--threads", "1"]))
    for name in QUALITY_RUNS:
        p = by_name[name]
        d = f"{p['depth']['min']}:{p['depth']['max']}"
        for label, box in boxes(p["box"], p["depth"]["max"]):
            out.append((f"{name} {label} d{d} t1 quality", name, box, d,
                        ["--quality", "good", "--threads", "1"]))
        out.append((f"{name} own d{d} t1 quality off", name, p["box"], d,
                    ["--quality", "good", "--threads", "1", *off]))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--save", default="")
    ap.add_argument("--check", default="")
    ap.add_argument("--only", default="", help="run only keys containing this text")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900)
    args = ap.parse_args()
    if bool(args.save) == bool(args.check):
        ap.error("give one of --save FILE, --check FILE")
    exe = os.path.abspath(os.path.join(args.build, "isomesh"))
    todo = [r for r in runs(presets(args.build)) if args.only in r[0]]
    with ThreadPoolExecutor(args.jobs) as pool:
        sums = list(pool.map(lambda r: md5_of_run(exe, r[1], r[2], r[3], r[4], args.timeout),
                             todo))
    got = {r[0]: s for r, s in zip(todo, sums)}
    if args.save:
        with open(args.save, "w") as f:
            json.dump(got, f, indent=1, sort_keys=True)
        bad = [k for k, s in got.items() if len(s) != 32]
        for k in bad:
            print(f"FAILED {k}: {got[k]}")
        print(f"{len(got)} runs saved to {args.save}")
        return 1 if bad else 0
    with open(args.check) as f:
        want = json.load(f)
    same = differ = 0
    for k, s in got.items():
        if k not in want:
            print(f"NEW     {k}")
        elif want[k] == s and len(s) == 32:
            same += 1
        else:
            differ += 1
            print(f"DIFFERS {k}: {want[k]} -> {s}")
    print(f"{same} identical, {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
