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


def barth_sextic(x, y, z, p):
    """Barth's sextic (65 nodes) cut by the ball of radius 1.5 (bench_error.c's formula)."""
    phi = p["phi"]
    r2 = x**2 + y**2 + z**2
    b = 4 * (phi**2 * x**2 - y**2) * (phi**2 * y**2 - z**2) * (phi**2 * z**2 - x**2) \
        - (1 + 2 * phi) * (r2 - 1)**2
    return np.maximum(b, r2 - 2.25)


SURFACES = {
    "sphere": sphere,
    "torus": torus,
    "gyroid-ball": gyroid_ball,
    "kummer-4-nodes": kummer,
    "kummer-16-nodes": kummer,
    "klein-bottle": klein_bottle,
    "steiner-roman": steiner_roman,
    "barth-sextic": barth_sextic,
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
    ap.add_argument("--tool", choices=["skimage", "vtk"], default="skimage")
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
    contour = load_flying_edges() if args.tool == "vtk" else load_marching_cubes()
    c0 = time.process_time()
    t0 = time.perf_counter()
    vol = sample(f, params, box, args.cells)
    t1 = time.perf_counter()
    spacing = tuple((box[k + 3] - box[k]) / args.cells for k in range(3))
    verts, faces = contour(vol, spacing)
    t2 = time.perf_counter()
    cpu = time.process_time() - c0
    verts = verts.astype(np.float64) + np.array(box[:3])
    write_ply(args.out, verts, faces)
    t3 = time.perf_counter()
    print(json.dumps({"sample_s": t1 - t0, "mc_s": t2 - t1, "write_s": t3 - t2, "cpu_s": cpu,
                      "vertices": int(len(verts)), "triangles": int(len(faces))}))
    return 0


def load_marching_cubes():
    """scikit-image's marching cubes (imported before the clock starts)."""
    from skimage.measure import marching_cubes

    def contour(vol, spacing):
        verts, faces, _normals, _values = marching_cubes(vol, level=0.0, spacing=spacing)
        return verts, faces
    return contour


def load_flying_edges():
    """VTK's flying edges (vtkFlyingEdges3D, Debian's python3-vtk9) on the same samples, one
    thread (the sequential SMP back end), no normals or gradients computed."""
    from vtkmodules.vtkCommonCore import vtkSMPTools
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    vtkSMPTools.SetBackend("Sequential")
    return lambda vol, spacing: flying_edges(vol, spacing, vtkImageData, vtkFlyingEdges3D,
                                             numpy_to_vtk, vtk_to_numpy)


def flying_edges(vol, spacing, vtkImageData, vtkFlyingEdges3D, numpy_to_vtk, vtk_to_numpy):
    img = vtkImageData()
    img.SetDimensions(*vol.shape)
    img.SetSpacing(*spacing)
    # VTK's point order runs x fastest: the (x, y, z)-indexed volume in Fortran order
    scalars = numpy_to_vtk(np.ravel(vol, order="F"), deep=False)
    img.GetPointData().SetScalars(scalars)
    fe = vtkFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, 0.0)
    fe.ComputeNormalsOff()
    fe.ComputeGradientsOff()
    fe.ComputeScalarsOff()
    fe.Update()
    out = fe.GetOutput()
    verts = vtk_to_numpy(out.GetPoints().GetData()) if out.GetNumberOfPoints() else np.zeros((0, 3))
    cells = vtk_to_numpy(out.GetPolys().GetConnectivityArray()) if out.GetNumberOfCells() \
        else np.zeros(0, dtype=np.int64)
    return verts, cells.reshape(-1, 3)


if __name__ == "__main__":
    sys.exit(main())
