#!/usr/bin/env python3
"""bench_wire.py — bytes on the wire and encode time of isomesh's Draco encoder, beside
reference figures measured in the same run: the raw arrays (float32 positions + uint32
indices), the binary PLY, the binary PLY through zlib (level 6), and Debian's own
`draco_encoder` program on the same PLY (same library, its own defaults for everything but the
quantisation; its time includes reading the PLY).

Meshes come from the polygoniser (bench_wire.c: torus ~16k triangles, sphere ~85k, gyroid
ball ~1M, plus Klein bottle, Steiner and Kummer for the non-manifold side data).

  bench_wire.py --build build/release [--quick]   (--quick: skip the 1M-triangle mesh)

The side-data table runs the CLI's request-file path (the service's pipeline: the singular
locus, certified curves) on the singular presets and prints the features JSON beside the
default .drc, as written and gzipped (what the daemon sends a client that accepts gzip).

Goals (from the tracker): at 14 position bits <= 1.5 B/triangle for positions and
connectivity, <= 2.5 with normals; non-manifold side data <= 10% of the payload; >= 2M
triangles/s at the default speed. Printed beside the figures, never asserted."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zlib


def run_bench(build, out_dir, quick):
    exe = os.path.join(build, "bench", "bench_wire")
    if not os.path.exists(exe):
        sys.exit(f"bench_wire.py: {exe} is missing (make bench builds it)")
    argv = [exe, "--out", out_dir] + (["--quick"] if quick else [])
    proc = subprocess.run(argv, stdout=subprocess.PIPE, text=True, timeout=1800, check=True)
    return [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]


def draco_cli(ply, bits, normals):
    """Debian's draco_encoder on the PLY: (bytes, seconds), or None when it is missing."""
    tool = shutil.which("draco_encoder")
    if not tool:
        return None
    out = ply + f".{bits}.{int(normals)}.drc"
    argv = [tool, "-i", ply, "-o", out, "-qp", str(bits), "-qn", "10" if normals else "-1"]
    t0 = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=600,
                   check=True)
    dt = time.perf_counter() - t0
    size = os.path.getsize(out)
    os.unlink(out)
    return size, dt


def print_tools(rows, meshes):
    """Draco's tool choices as ratios to speed 4 (the default until issue 16; its goal: within 5%
    of that size at <= 1/2 its encode time), on the default payload (normals) and on every
    attribute."""
    for payload, what in (("default", "the default payload: normals"),
                          ("all", "every attribute: normals, curvatures, class")):
        tools = [r for r in rows if r["kind"] == "tools" and r.get("payload") == payload]
        if not tools:
            continue
        names = list(dict.fromkeys(r["tools"] for r in tools))
        print(f"\nDraco tools on {what} (14 bits): size and encode time as ratios to speed 4 "
              "(before issue 16); * = the service's default now")
        print(f"{'mesh':<12}{'tris':>9}{'speed4 B':>10}{'ms':>8}" +
              "".join(f"{n + ('*' if any(r['default'] for r in tools if r['tools'] == n) else ''):>22}"
                      for n in names[1:]))
        for name, m in meshes.items():
            row = {r["tools"]: r for r in tools if r["case"] == name}
            base = row[names[0]]
            cells = "".join(f"{row[n]['bytes'] / base['bytes']:>11.3f}"
                            f"{row[n]['ms'] / base['ms']:>11.2f}" for n in names[1:])
            print(f"{name:<12}{m['triangles']:>9}{base['bytes']:>10}{base['ms']:>8.1f}{cells}")
    print("  each cell: size ratio, time ratio (fastest of several encodes; goal <= 1.05, <= 0.5)")


# The singular presets whose features JSON is largest beside their mesh (the first three:
# --quick), the other singular ones, then CSG presets, whose features carry every crease
# vertex (curves of kind crease: 95-99.9% of their bytes; gyroid-ball 1.26 MB beside a 239 KB
# .drc in session 19).
SIDE_PRESETS = ("klein-bottle", "steiner-roman", "kummer-16-nodes", "cross-cap",
                "whitney-umbrella", "crossing-spheres", "coordinate-planes", "kummer-4-nodes",
                "heart", "gyroid-ball", "cube-minus-ball", "three-balls", "schwarz-d")


def side_data(build, tmp, preset):
    """(default .drc bytes, features JSON text) of one preset as the service makes it: the
    request file path of the CLI, default bound, the daemon's depth limit 10."""
    req = os.path.join(tmp, preset + ".req.json")
    with open(req, "w") as f:
        json.dump({"preset": preset, "depth": {"max": 10}}, f)
    drc, feats = (os.path.join(tmp, preset + ext) for ext in (".drc", ".features.json"))
    subprocess.run([os.path.join(build, "isomesh"), req, "-o", drc, "--features", feats],
                   stdout=subprocess.DEVNULL, timeout=600, check=True)
    with open(feats, "rb") as f:
        return os.path.getsize(drc), f.read()


def field_bytes(doc):
    """{top-level field: its compact JSON bytes}, the largest first."""
    sizes = {k: len(json.dumps(v, separators=(",", ":"))) for k, v in doc.items()}
    return dict(sorted(sizes.items(), key=lambda kv: -kv[1]))


def print_side_data(build, tmp, quick):
    """The features JSON the viewer fetches beside the default .drc (the goal: <= 10% of the
    payload): as written, and gzipped as the daemon sends it to a client whose
    Accept-Encoding takes gzip (browsers' fetch always does: server/common/gzip_body.h)."""
    print("\nFeatures JSON beside the default .drc (normals), as the service makes them "
          "(default bound, depth.max 10); gz = gzip level 6, what the daemon sends a browser")
    print(f"{'preset':<18}{'drc':>9}{'features':>10}{'share':>7}{'gz':>8}{'share':>7}  "
          "largest fields (bytes)")
    for preset in SIDE_PRESETS[:3] if quick else SIDE_PRESETS:
        drc, text = side_data(build, tmp, preset)
        gz = len(zlib.compress(text, 6)) + 12  # gzip's header and trailer beside zlib's
        top = ", ".join(f"{k} {v}" for k, v in list(field_bytes(json.loads(text)).items())[:3])
        flag = "" if gz <= 0.10 * drc else "  over 10%"
        print(f"{preset:<18}{drc:>9}{len(text):>10}{100 * len(text) / drc:>6.1f}%{gz:>8}"
              f"{100 * gz / drc:>6.1f}%  {top}{flag}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--quick", action="store_true",
                    default=os.environ.get("ISOMESH_BENCH_QUICK") == "1")
    args = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="isomesh-bench-wire-")
    try:
        rows = run_bench(args.build, tmp, args.quick)
        meshes = {r["case"]: r for r in rows if r["kind"] == "mesh"}
        by = {}
        for r in rows:
            if r["kind"] == "bits":
                by[(r["case"], r["bits"], r["attributes"])] = r

        print("Draco encoding of polygoniser meshes (isomesh speed "
              "= default; B/tri = bytes per triangle; Mtri/s = triangles per CPU second of the "
              "fastest of several runs)")
        head = (f"{'mesh':<12}{'tris':>9}{'bits':>5} | {'pos':>6}{'+nrm':>6}{'+all':>6}"
                f"{'Mtri/s':>8} | {'raw':>6}{'PLY':>6}{'PLY+z':>7} | {'cli pos':>8}{'cli +nrm':>9}"
                f"{'cli s':>7}")
        print(head)
        print("-" * len(head))
        for name, m in meshes.items():
            t = m["triangles"]
            ply = os.path.join(tmp, name + ".ply")
            with open(ply, "rb") as f:
                zbytes = len(zlib.compress(f.read(), 6))
            for bits in (11, 14, 16):
                p = by[(name, bits, "positions")]
                n = by[(name, bits, "normals")]
                a = by[(name, bits, "all")]
                cli_p = draco_cli(ply, bits, False)
                cli_n = draco_cli(ply, bits, True)
                cli = (f"{cli_p[0] / t:8.3f}{cli_n[0] / t:9.3f}{cli_n[1]:7.2f}"
                       if cli_p and cli_n else f"{'-':>8}{'-':>9}{'-':>7}")
                print(f"{name:<12}{t:>9}{bits:>5} | {p['bytes'] / t:6.3f}{n['bytes'] / t:6.3f}"
                      f"{a['bytes'] / t:6.3f}{t / n['ms'] / 1000:8.2f} | "
                      f"{m['raw_bytes'] / t:6.2f}{m['ply_bytes'] / t:6.2f}{zbytes / t:7.2f} | {cli}")
        print("  pos = positions + connectivity; +nrm = with 10-bit normals (the default "
              "attributes); +all = every attribute (normals, 14-bit mean and Gaussian curvature, "
              "class); Mtri/s for +nrm;\n"
              "  raw = float32 xyz + uint32 indices; PLY+z = binary PLY through zlib -6; cli = "
              "Debian draco_encoder on the PLY (its -cl 7, i.e. speed 3; time incl. PLY read)")

        print("\nEncoder speed setting (14 position bits): B/tri and Mtri/s, positions | +normals")
        speeds = sorted({r["speed"] for r in rows if r["kind"] == "speed"})
        print(f"{'mesh':<12}" + "".join(f"{'speed ' + str(s):>21}" for s in speeds))
        for name, m in meshes.items():
            t = m["triangles"]
            cells = []
            for s in speeds:
                p = next(r for r in rows if r["kind"] == "speed" and r["case"] == name
                         and r["speed"] == s and r["attributes"] == "positions")
                n = next(r for r in rows if r["kind"] == "speed" and r["case"] == name
                         and r["speed"] == s and r["attributes"] == "normals")
                cells.append(f"{p['bytes'] / t:.2f}/{t / p['ms'] / 1000:.1f}|"
                             f"{n['bytes'] / t:.2f}/{t / n['ms'] / 1000:.1f}")
            print(f"{name:<12}" + "".join(f"{c:>21}" for c in cells))

        print_tools(rows, meshes)

        print("\nCurvature quantisation (14 position bits, all attributes): B/tri")
        cb = sorted({r["curvature_bits"] for r in rows if r["kind"] == "curvature"})
        print(f"{'mesh':<12}" + "".join(f"{('float' if b == 0 else str(b) + ' bits'):>10}"
                                        for b in cb))
        for name, m in meshes.items():
            t = m["triangles"]
            vals = [next(r["bytes"] for r in rows if r["kind"] == "curvature"
                         and r["case"] == name and r["curvature_bits"] == b) / t for b in cb]
            print(f"{name:<12}" + "".join(f"{v:>10.3f}" for v in vals))

        print("\nThe mesh's own non-manifold elements beside the default Draco payload (14 bits, "
              "normals; polygoniser meshes without the singular locus: see the next table)")
        print(f"{'mesh':<12}{'nm edges':>9}{'points':>7}{'bnd edges':>10}{'payload':>10}"
              f"{'elements':>10}{'share':>7}{'glb side':>10}{'share':>7}")
        for name, m in meshes.items():
            payload = by[(name, 14, "normals")]["bytes"]
            fj, gs = m["features_json_bytes"], m["glb_side_bytes"]
            print(f"{name:<12}{m['nonmanifold_edges']:>9}{m['nonmanifold_points']:>7}"
                  f"{m['boundary_edges']:>10}{payload:>10}{fj:>10}{100 * fj / payload:>6.1f}%"
                  f"{gs:>10}{100 * gs / payload:>6.1f}%")

        print_side_data(args.build, tmp, args.quick)

        print("\nGoals at 14 bits, default speed:")
        for name, m in meshes.items():
            t = m["triangles"]
            p = by[(name, 14, "positions")]["bytes"] / t
            n = by[(name, 14, "normals")]
            print(f"  {name:<12} positions {p:.2f} B/tri (goal 1.5), with normals "
                  f"{n['bytes'] / t:.2f} (goal 2.5), {t / n['ms'] / 1000:.2f} Mtri/s (goal 2)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
