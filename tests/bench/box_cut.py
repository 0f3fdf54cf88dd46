"""box_cut.py — what f itself says about how a box cuts its surface, for sweep_singular.py.

A box's faces form a topological sphere; k disjoint simple closed curves of f = 0 on it split it
into k + 1 sign regions, so the loops in which the surface leaves the box are counted from f's
signs sampled on the faces (no mesh involved). Where the boxes of one sweep row disagree in
that count, each box's cut-away pieces are checked to be caps (discs): the slab between a face of
the box and the same face of the row's bounding box is sliced parallel to the face, and a cap
shows as closed loops (none touching the slice's border) whose number never grows outwards and
is 0 at the outer face (every loop closes off at a minimum of the height: a disc). Cutting a
disc off a surface lowers χ by 1 and adds one boundary loop, so χ + caps and boundary loops -
caps must agree between the boxes of a row; any other cut (a slab the surface crosses, a loop
over a box edge) is left unexplained and the row stays flagged."""
import math

FACE_SAMPLES = 96    # sample intervals per face side: the depth-3 cyclide caps are 8+ samples wide
SLICE_SAMPLES = 64   # per side of a slab slice; coarser than the faces, the caps only shrink outwards
SLICES = 12          # slices through a slab, face to outer face


def evaluator(preset):
    """f of a gallery preset (expr, lets, params at their defaults) as a Python function, or
    None when the expression is beyond Python's syntax. NaN where f is undefined."""
    env = {k: getattr(math, k) for k in dir(math) if not k.startswith("_")}
    env.update(abs=abs, min=min, max=max)
    for prm in preset.get("params", []):
        env[prm["name"]] = prm["default"]
    try:
        code = [(n, compile(e.replace("^", "**"), "<let>", "eval")) for n, e in preset["let"]]
        body = compile(preset["expr"].replace("^", "**"), "<f>", "eval")
    except SyntaxError:
        return None

    def f(x, y, z):
        env.update(x=x, y=y, z=z)
        try:
            for n, c in code:
                env[n] = eval(c, env)
            return float(eval(body, env))
        except (ArithmeticError, ValueError):
            return math.nan
    return f


def sign(v):
    return 1 if v > 0 else -1 if v < 0 else 0


def regions(signs, neighbours):
    """Connected regions of equal non-zero sign (zeros and NaN separate regions)."""
    seen, n = set(), 0
    for p, s in signs.items():
        if s == 0 or p in seen:
            continue
        n += 1
        seen.add(p)
        stack = [p]
        while stack:
            q = stack.pop()
            for r in neighbours(q):
                if r in signs and r not in seen and signs[r] == s:
                    seen.add(r)
                    stack.append(r)
    return n


def _at(box, ijk, n):
    return [box[a] + (box[a + 3] - box[a]) * ijk[a] / n for a in range(3)]


def face_loops(f, box):
    """Closed loops of f = 0 on the box's faces: sign regions of the face lattice - 1 (0 when f
    keeps one sign there)."""
    n = FACE_SAMPLES
    signs = {}
    for i in range(n + 1):
        for j in range(n + 1):
            for k in (0, n) if 0 < i < n and 0 < j < n else range(n + 1):
                signs[(i, j, k)] = sign(f(*_at(box, (i, j, k), n)))

    def neighbours(p):
        for a in range(3):
            for d in (-1, 1):
                q = list(p)
                q[a] += d
                yield tuple(q)
    return max(regions(signs, neighbours) - 1, 0)


def slice_loops(f, axis, t, rect):
    """Closed loops of f = 0 in the plane x[axis] = t over rect (the other two axes' ranges), or
    None when the zero set reaches the rectangle's border (not a cap's slice)."""
    m = SLICE_SAMPLES
    u, v = [a for a in range(3) if a != axis]
    signs = {}
    for i in range(m + 1):
        for j in range(m + 1):
            p = [0.0] * 3
            p[axis] = t
            p[u] = rect[0][0] + (rect[0][1] - rect[0][0]) * i / m
            p[v] = rect[1][0] + (rect[1][1] - rect[1][0]) * j / m
            signs[(i, j)] = sign(f(*p))
    border = {s for (i, j), s in signs.items() if i in (0, m) or j in (0, m)}
    if len(border) != 1 or 0 in border:
        return None

    def neighbours(p):
        i, j = p
        return ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1))
    return regions(signs, neighbours) - 1


def caps_cut(f, box, outer):
    """Discs the box cuts off the surface inside the larger box outer: the sum over faces of
    the loops in each face's slab, or None when a slab holds anything but caps."""
    caps = 0
    for a in range(3):
        rect = [(outer[b], outer[b + 3]) for b in range(3) if b != a]
        for near, far in ((box[a], outer[a]), (box[a + 3], outer[a + 3])):
            if near == far:
                continue
            counts = [slice_loops(f, a, near + (far - near) * s / SLICES, rect)
                      for s in range(SLICES + 1)]
            if None in counts or counts[-1] != 0 or \
                    any(counts[s + 1] > counts[s] for s in range(SLICES)):
                return None
            caps += counts[0]
    return caps


def row_caps(f, row_boxes):
    """For the boxes of one sweep row: each box's caps cut off relative to the row's bounding
    box, or None for every box when they need no correction (same face loops everywhere) or
    the cut is not explained by caps alone."""
    loops = [face_loops(f, b) for b in row_boxes]
    if len(set(loops)) == 1:
        return None
    outer = [min(b[a] for b in row_boxes) for a in range(3)] + \
            [max(b[a] for b in row_boxes) for a in range(3, 6)]
    caps = [caps_cut(f, b, outer) for b in row_boxes]
    if None in caps or len({lo - c for lo, c in zip(loops, caps)}) != 1:
        return None
    return caps
