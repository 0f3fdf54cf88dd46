#!/usr/bin/env python3
"""sweep_singular.py — issue 13's lattice-independence sweep: every preset of the gallery in its
own box and shifted off the octree lattice (tests/cli/boxes.py's placements: by 1e-3, and by
sqrt(2) - 1 / -(sqrt(5) - 1)/4 / 1/e of a finest cell), at depths 6-9, through `isomesh --stats`.
Prints one row per (preset, depth) with the singular counts, χ, components, non-manifold
vertices/edges and artefacts of each box, and lists every preset whose counts differ between
boxes or that has artefacts. Not part of `make test` (hundreds of runs, minutes each at depth 9).

A shifted box may cut the surface where the preset's own box holds it whole (the box 0.37 of a
cell off, the irrational placement's predecessor, at depth 3 cut the horn cyclide at x = -13.52,
its extreme point being x = -a - r - f = -14).
The truth then differs between boxes, so each box's expected boundary loops come from f itself
(sign regions of f on the box's faces, see box_cut.py), and where a box cuts caps that the other
boxes keep whole, χ + caps and boundary loops - caps are what must agree.

  sweep_singular.py [--build build/release] [--depths 6,7,8,9] [--presets a,b] [--jobs 2]
                    [--cache FILE.jsonl] [--max-error-rel R] [--extra ARG ...]

--max-error-rel R runs the path users get under an error bound: --max-error E with E = R x the
largest width of each box (the dual mesher where it applies, the singular stage sized from E).
Each row then also shows which mesher ran (d dual / p primal and why not dual) and the accuracy
block's verdict (worst of vertex, midpoint and centroid distance over E; met); a row is flagged
when the mesher differs between boxes (MESHER), E is missed (MISS), or `met` disagrees with the
measured worst distance (METBAD).

--cache keeps finished runs (keyed by preset, box, depth, extra arguments and the binary's
mtime), so an interrupted sweep resumes where it stopped."""
import argparse
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import box_cut

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "cli"))
from boxes import PLACEMENTS as SHIFTS  # noqa: E402  (label, shift per axis, in finest cells?)


def presets(build):
    """The gallery: GET /v1/presets of a daemon started for the purpose (build's isomeshd, or
    the repository's when build holds only isomesh)."""
    if os.path.exists(os.path.join(build, "isomeshd")):
        os.environ.setdefault("ISOMESH_BUILD", os.path.abspath(build))
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                    "http"))
    from harness import Daemon
    d = Daemon()
    d.start()
    try:
        return d.get("/v1/presets").json()["presets"]
    finally:
        d.stop()
        d.cleanup()


def boxes(box, depth):
    out = []
    for label, s, in_cells in SHIFTS:
        cell = [(box[a + 3] - box[a]) / 2 ** depth for a in range(3)]
        d = [s[a] * cell[a] if in_cells else s[a] for a in range(3)]
        out.append((label, [box[a] + d[a % 3] for a in range(6)]))
    return out


def summary(stats):
    """What a run keeps (cached): the singular stats and the mesh's analysis, without times
    and the accuracy/quality blocks."""
    an = {k: v for k, v in stats["analysis"].items() if k not in ("quality", "accuracy")}
    return {"singular": stats["singular"], "analysis": an,
            "thin_found": stats["polygoniser"]["thin_found"],
            "mesher": stats["polygoniser"].get("mesher"),
            "why": stats["polygoniser"].get("dual_declined"),
            "acc": {k: stats["analysis"]["accuracy"].get(k) for k in
                    ("max_dist_vertex", "max_dist_midpoint", "max_dist_centroid", "max_error",
                     "met")},
            "ms": round(stats["timings_ms"]["total"])}


def counts(r):
    """The facts that must not depend on the box (KEYS) and a few more to show: singular
    points by type, curves by kind, double sheets, χ, components, non-manifold points and
    curves of the mesh, boundary loops; artefacts, non-manifold edges, incomplete, thin."""
    sg, an = r["singular"], r["analysis"]
    pts = "".join(f"{k[0]}{v}" for k, v in sg["by_type"].items() if v) or "-"
    return {"pts": pts, "cert": sg["certified"], "dc": sg["double_curves"],
            "wc": sg["whisker_curves"], "ds": sg["double_sheets"], "chi": an["euler"],
            "comp": an["components"], "nmp": an["nonmanifold_points"],
            "nmc": an["nonmanifold_curves"], "bl": an["boundary_loops"],
            "art": sg["artefacts"], "nme": an["nonmanifold_edges"], "inc": sg["incomplete"],
            "thin": r["thin_found"], "ms": r["ms"], **bound(r)}


def bound(r):
    """Under --max-error-rel: which mesher ran and whether E was met (worst of vertices,
    midpoints, centroids over E; `met` as the stats say it; metbad when the two disagree)."""
    a = r.get("acc")
    if not a or not a.get("max_error"):
        return {}
    worst = max(a["max_dist_vertex"], a["max_dist_midpoint"], a["max_dist_centroid"])
    q = worst / a["max_error"]
    why = r.get("why")
    return {"mesher": (r.get("mesher") or "?")[0] + (f":{why}" if why else ""),
            "met": a["met"], "q": q, "metbad": bool(a["met"]) != (q <= 1)}


def run(exe, name, box, depth, extra, timeout):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [exe, "--surface", name, "-b", ",".join(repr(v) for v in box), "-d", f"3:{depth}",
               "--stats", *extra]
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=tmp)
        except subprocess.TimeoutExpired:
            return {"error": "timeout"}
        if r.returncode != 0:
            return {"error": r.stderr.strip()[:200]}
        return summary(json.loads(r.stdout))


KEYS = ("pts", "cert", "dc", "wc", "ds", "chi", "comp", "nmp", "nmc", "bl")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--depths", default="6,7,8,9")
    ap.add_argument("--presets", default="")
    ap.add_argument("--skip", default="")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cache", default="")
    ap.add_argument("--timeout", type=float, default=900)
    ap.add_argument("--extra", nargs="*", default=[])
    ap.add_argument("--max-error-rel", type=float, default=0)
    args = ap.parse_args()
    exe = os.path.abspath(os.path.join(args.build, "isomesh"))  # the runs start in a temp dir
    stamp = os.path.getmtime(exe)
    ps = presets(args.build)
    if args.presets:
        want = args.presets.split(",")
        ps = [p for p in ps if p["name"] in want]
    if args.skip:
        ps = [p for p in ps if p["name"] not in args.skip.split(",")]
    depths = [int(d) for d in args.depths.split(",")]
    cache = {}
    if args.cache and os.path.exists(args.cache):
        with open(args.cache) as f:
            for line in f:
                e = json.loads(line)
                cache[e["k"]] = e["v"]
    jobs = []
    for p in ps:
        for d in depths:
            for label, box in boxes(p["box"], d):
                extra = list(args.extra)
                if args.max_error_rel:  # E from this box's own largest width
                    e = args.max_error_rel * max(box[a + 3] - box[a] for a in range(3))
                    extra += ["--max-error", repr(e)]
                elif "--max-error" not in extra:  # the depth path (0: off, any binary)
                    extra += ["--max-error", "0"]
                k = json.dumps([p["name"], box, d, extra, stamp])
                jobs.append((p["name"], d, label, box, k, extra))

    def one(j):
        name, d, label, box, k, extra = j
        if k in cache:
            return j, cache[k]
        v = run(exe, name, box, d, extra, args.timeout)
        if args.cache:
            with open(args.cache, "a") as f:
                f.write(json.dumps({"k": k, "v": v}) + "\n")
        return j, v

    res = {}
    with ThreadPoolExecutor(args.jobs) as ex:
        for (name, d, label, box, k, _), v in ex.map(one, jobs):
            res[(name, d, label)] = v

    def cut_caps(p, d):
        """Caps each box of the row cuts off (box_cut.py), or None (no correction)."""
        f = box_cut.evaluator(p)
        return f and box_cut.row_caps(f, [b for _, b in boxes(p["box"], d)])

    bad = []
    print(f"{'preset':<18}{'d':>2}  " + "  |  ".join(f"{l:<50}" for l, _, _ in SHIFTS))
    for p in ps:
        for d in depths:
            row = [v if "error" in v else counts(v)
                   for v in (res[(p["name"], d, l)] for l, _, _ in SHIFTS)]
            ok = [v for v in row if "error" not in v]
            diff = [k for k in KEYS if len({str(v[k]) for v in ok}) > 1]
            caps = cut_caps(p, d) if diff and len(ok) == len(row) else None
            if caps:  # a cut disc: χ - 1, one boundary loop more (raw values printed)
                for v, c in zip(row, caps):
                    v["cut"] = c
                fixed = [dict(v, chi=v["chi"] + c, bl=v["bl"] - c) for v, c in zip(row, caps)]
                diff = [k for k in KEYS if len({str(v[k]) for v in fixed}) > 1]
            cells = []
            for v in row:
                if "error" in v:
                    cells.append(f"ERR {v['error'][:40]}")
                    continue
                cells.append(f"{v['pts']:<9}c{v['cert']:<3}dc{v['dc']:<2}wc{v['wc']:<2}ds{v['ds']} "
                             f"χ{v['chi']:<4}k{v['comp']:<2}np{v['nmp']:<2}nc{v['nmc']:<2}b{v['bl']:<2}"
                             f"A{v['art']}" + (" INC" if v["inc"] else "") +
                             (f" T{v['thin']}" if v["thin"] else "") +
                             (f" cut{v['cut']}" if v.get("cut") else "") +
                             (f" {v['mesher']} q{v['q']:.2f}{'' if v['met'] else ' MISS'}"
                              if "mesher" in v else ""))
            art = any(v["art"] for v in ok)
            extra_flags = []
            if len({v.get("mesher") for v in ok}) > 1:
                extra_flags.append("MESHER")
            if any("met" in v and not v["met"] for v in ok):
                extra_flags.append("MISS")
            if any(v.get("metbad") for v in ok):
                extra_flags.append("METBAD")
            flag = ""
            if diff or art or len(ok) < len(row) or extra_flags:
                flag = " <-- " + ",".join(diff + extra_flags) + (" ART" if art else "") + \
                       (" ERR" if len(ok) < len(row) else "")
                bad.append((p["name"], d, diff + extra_flags, art))
            print(f"{p['name']:<18}{d:>2}  " + "  |  ".join(f"{c:<50}" for c in cells) + flag)
    print(f"\n{len(bad)} (preset, depth) rows disagree, have artefacts, change mesher or miss E:")
    for name, d, diff, art in bad:
        print(f"  {name} d{d}: {','.join(diff)}{' artefacts' if art else ''}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
