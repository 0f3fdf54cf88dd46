#!/usr/bin/python3
"""skimage_mc.py — the scikit-image reference of the polygoniser benchmark: samples a built-in
surface with numpy on a uniform grid of (N+1)^3 points over its box, runs scikit-image's
marching cubes (Lewiner, default options, level 0) and writes the mesh as binary PLY
(double x y z, int32 faces). Prints one JSON line with the phase times. Run it with the
Debian interpreter /usr/bin/python3 (python3-numpy, python3-skimage); bench_polygonise.py
times the whole process, imports and sampling included.

The formulas are proto/presets.c's, written for numpy; bench_polygonise.py checks them against
isomesh's compiled tape at sample points (--eval) before it trusts a single timing.

  skimage_mc.py --surface NAME --box X0,Y0,Z0,X1,Y1,Z1 --cells N [--param NAME=V]... --out F.ply
  skimage_mc.py --surface NAME [--param NAME=V]... --eval=X,Y,Z[;X,Y,Z...]
(write --box= and --eval= with "=": their values may start with a minus sign)
"""
import argparse
import json
import sys
import time

import numpy as np

SLAB_BYTES = 32 << 20  # float64 temporaries per slab of x-planes
MAX_CELLS = 1024


def sphere(x, y, z, p):
    return x**2 + y**2 + z**2 - p["r"]**2


def torus(x, y, z, p):
    R, r = p["R"], p["r"]
    return (x**2 + y**2 + z**2 + R**2 - r**2)**2 - 4 * R**2 * (x**2 + y**2)


def gyroid_ball(x, y, z, p):
    k = p["k"]
    g = np.sin(k * x) * np.cos(k * y) + np.sin(k * y) * np.cos(k * z) + np.sin(k * z) * np.cos(k * x)
    return np.maximum(g, x**2 + y**2 + z**2 - 1.96)


def kummer(x, y, z, p):
    mu2, w = p["mu2"], p["w"]
    lam = (3 * mu2 - 1) / (3 - mu2)
    s2 = np.sqrt(2.0)
    pp = w - z - s2 * x
    q = w - z + s2 * x
    r = w + z + s2 * y
    s = w + z - s2 * y
    return (x**2 + y**2 + z**2 - mu2)**2 - lam * pp * q * r * s


def klein_bottle(x, y, z, p):
    a = x**2 + y**2 + z**2 + 2 * y - 1
    b = x**2 + y**2 + z**2 - 2 * y - 1
    return a * (b**2 - 8 * z**2) + 16 * x * z * b


def steiner_roman(x, y, z, p):
    return x**2 * y**2 + y**2 * z**2 + z**2 * x**2 + x * y * z


SURFACES = {
    "sphere": sphere,
    "torus": torus,
    "gyroid-ball": gyroid_ball,
    "kummer-4-nodes": kummer,
    "kummer-16-nodes": kummer,
    "klein-bottle": klein_bottle,
    "steiner-roman": steiner_roman,
}


def sample(f, params, box, n):
    """f on (n+1)^3 grid points, as the float32 volume marching cubes works on (x is axis 0)."""
    axes = [np.linspace(box[k], box[k + 3], n + 1) for k in range(3)]
    y = axes[1][None, :, None]
    z = axes[2][None, None, :]
    vol = np.empty((n + 1, n + 1, n + 1), dtype=np.float32)
    slab = max(1, SLAB_BYTES // (8 * (n + 1) * (n + 1)))
    for i in range(0, n + 1, slab):
        x = axes[0][i:i + slab, None, None]
        vol[i:i + slab] = f(x, y, z, params)
    return vol


def write_ply(path, verts, faces):
    head = ("ply\nformat binary_little_endian 1.0\ncomment skimage marching cubes\n"
            f"element vertex {len(verts)}\n"
            "property double x\nproperty double y\nproperty double z\n"
            f"element face {len(faces)}\n"
            "property list uchar int vertex_indices\nend_header\n")
    rec = np.empty(len(faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    rec["n"] = 3
    rec["v"] = faces
    with open(path, "wb") as out:
        out.write(head.encode("ascii"))
        out.write(np.ascontiguousarray(verts, dtype="<f8").tobytes())
        out.write(rec.tobytes())


def parse_params(items):
    params = {}
    for item in items:
        name, _, value = item.partition("=")
        if not name or not value:
            raise SystemExit(f"skimage_mc: bad --param {item!r} (want NAME=VALUE)")
        params[name] = float(value)
    return params


def parse_triple(text, what, count=3):
    vals = [float(v) for v in text.split(",")]
    if len(vals) != count or not all(np.isfinite(vals)):
        raise SystemExit(f"skimage_mc: bad {what} {text!r}")
    return vals


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--surface", required=True, choices=sorted(SURFACES))
    ap.add_argument("--param", action="append", default=[])
    ap.add_argument("--box")
    ap.add_argument("--cells", type=int)
    ap.add_argument("--out")
    ap.add_argument("--eval", metavar="X,Y,Z[;X,Y,Z...]")
    args = ap.parse_args()
    f = SURFACES[args.surface]
    params = parse_params(args.param)
    if args.eval:
        pts = np.array([parse_triple(t, "point") for t in args.eval.split(";")])
        vals = f(pts[:, 0], pts[:, 1], pts[:, 2], params)
        print(json.dumps([float(v) for v in vals]))
        return 0
    if not (args.box and args.cells and args.out):
        raise SystemExit("skimage_mc: give --box, --cells and --out (or --eval)")
    if not 1 <= args.cells <= MAX_CELLS:
        raise SystemExit(f"skimage_mc: --cells must be in 1..{MAX_CELLS}")
    box = parse_triple(args.box, "box", 6)
    from skimage.measure import marching_cubes

    t0 = time.perf_counter()
    vol = sample(f, params, box, args.cells)
    t1 = time.perf_counter()
    spacing = tuple((box[k + 3] - box[k]) / args.cells for k in range(3))
    verts, faces, _normals, _values = marching_cubes(vol, level=0.0, spacing=spacing)
    t2 = time.perf_counter()
    verts = verts.astype(np.float64) + np.array(box[:3])
    write_ply(args.out, verts, faces)
    t3 = time.perf_counter()
    print(json.dumps({"sample_s": t1 - t0, "mc_s": t2 - t1, "write_s": t3 - t2,
                      "vertices": int(len(verts)), "triangles": int(len(faces))}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
