"""drawn.py — checks of proto/features.h's drawing rule for the mesh polylines the features
JSON prints (crease arcs, nonmanifold_edges, boundaries), against the mesh's own chains in the
.obj (`l` lines: every vertex, %.9g), for test_curves.

The rule, restated here: with the features' "tolerance" t, every number is printed with at
most d decimals, d the fewest with (sqrt 3 / 2) 10^-d <= t / 2; every printed point is a mesh
vertex of its chain rounded (within that rounding); a thinned chain keeps its ends and every
vertex it drops lies within t of the printed segment across it."""
import decimal
import json
import math


def obj_chains(path, group):
    """The `l` lines of one group of an .obj as lists of (point, its rounding bound): %.9g
    keeps 9 significant digits, so a coordinate x is off by <= 0.5e-8 x 10^floor(log10 |x|)."""
    verts, chains, at = [], [], None
    with open(path) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "v":
                p = tuple(map(float, w[1:4]))
                r = math.sqrt(sum((0.5e-8 * 10 ** math.floor(math.log10(abs(x)))) ** 2
                                  for x in p if x != 0))
                verts.append((p, r))
            elif w and w[0] == "g":
                at = w[1]
            elif w and w[0] == "l" and at == group:
                chains.append([verts[int(t) - 1] for t in w[1:]])
    return chains


def printed_text(path):
    """The features JSON with every number as printed (decimal.Decimal, int)."""
    with open(path) as f:
        return json.load(f, parse_float=decimal.Decimal)


def decimals(tol):
    """The fewest decimals d with (sqrt 3 / 2) 10^-d <= tol / 2, and that rounding."""
    d = 0
    while math.sqrt(3) / 2 * 10 ** -d > tol / 2:
        d += 1
    return d, math.sqrt(3) / 2 * 10 ** -d


def seg_dist(p, a, b):
    ab = [b[k] - a[k] for k in range(3)]
    l2 = sum(v * v for v in ab)
    t = 0 if l2 == 0 else max(0, min(1, sum((p[k] - a[k]) * ab[k] for k in range(3)) / l2))
    return math.dist(p, [a[k] + t * ab[k] for k in range(3)])


def points(xyz, tc, d):
    """A printed x0, y0, z0, ... list as points, each number checked to have <= d decimals."""
    for v in xyz:
        tc.assertLessEqual(-decimal.Decimal(v).as_tuple().exponent, d, v)
    xyz = [float(v) for v in xyz]
    return [xyz[i:i + 3] for i in range(0, len(xyz), 3)]


def check_thinned(tc, printed, chains, tol):
    """printed: the printed polylines (lists of numbers as printed), chains: the mesh's
    (obj_chains) of the same polylines, in any order. Checks the rule for thinned chains;
    returns (the printed points, their rounding bound)."""
    d, rounding = decimals(tol)
    pts = [p for line in printed for p in points(line, tc, d)]
    unit = 10 ** -d

    def keys(p):  # p rounded to d decimals, and one unit of the last decimal either side
        return [(round(p[0] + dx * unit, d), round(p[1] + dy * unit, d),
                 round(p[2] + dz * unit, d))
                for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)]

    rounded = {tuple(round(x, d) for x in q) for q in pts}
    meshed = {}
    for p, r in (v for ch in chains for v in ch):
        meshed.setdefault(tuple(round(x, d) for x in p), []).append((p, r))
    for q in pts:  # each printed point a vertex of the mesh's chains, rounded
        tc.assertTrue(any(math.dist(p, q) <= rounding + r
                          for k in keys(q) for p, r in meshed.get(k, ())), q)

    def printed_of(p, r):  # the printed point nearest to p, if it may be p's rounding
        near = [q for q in keys(p) if q in rounded and math.dist(p, q) <= rounding + r]
        return min(near, key=lambda q: math.dist(p, q)) if near else None

    worst = 0.0
    for ch in chains:  # every dropped vertex within tol of its printed segment
        kept = [(i, printed_of(p, r)) for i, (p, r) in enumerate(ch)]
        kept = [(i, q) for i, q in kept if q]
        tc.assertEqual((kept[0][0], kept[-1][0]), (0, len(ch) - 1))
        for (i, a), (j, b) in zip(kept, kept[1:]):
            for p, r in ch[i + 1:j]:
                worst = max(worst, seg_dist(p, a, b) - r)
    tc.assertLessEqual(worst, tol, "a vertex of the mesh's chain off the printed polyline")
    tc.assertLess(len(pts), sum(len(ch) for ch in chains))
    return pts, rounding

