"""isomesh_client — a small client for the isomesh service, Python standard library only.

    from isomesh_client import Client
    c = Client("http://127.0.0.1:8080")            # token="..." with --tokens
    m = c.mesh({"preset": "kummer-4-nodes"})        # computes (or finds) the mesh
    m.key, m.stats["mesh"]["vertices"], m.urls["ply"]
    ply = m.load("ply")                             # Mesh: vertices, faces, per-vertex props
    j = c.job({"preset": "torus"}).wait()           # a job, followed until done -> MeshRef
    for j in c.sweep({"expr": "x^2+y^2+z^2-r", "params": {"r": 1}}, {"r": [0.5, 1, 2]}):
        print(j.params, j.wait().stats["mesh"]["triangles"])

Every format of a key is computed once on the service (one polygonisation per surface):
asking for m.load("obj") after m.load("ply") only encodes the stored surface.
Errors from the service raise IsomeshError with its status, code and message."""
import json
import struct
import time
import urllib.error
import urllib.parse
import urllib.request

__all__ = ["Client", "MeshRef", "Job", "Mesh", "IsomeshError", "load_ply", "load_obj"]

POLL_S = 0.1        # job polling interval
DEFAULT_TIMEOUT_S = 300


class IsomeshError(Exception):
    def __init__(self, status, code, message):
        super().__init__("%s %s: %s" % (status, code, message))
        self.status, self.code, self.message = status, code, message


class Mesh:
    """A loaded mesh: vertices [(x, y, z)], faces [(a, b, c)] (0-based), props {name: [per
    vertex]} (PLY: nx ny nz, and mean_curvature gauss_curvature class when the request's
    output.attributes names them), lines [[vertex indices]]
    (OBJ `l` lines: the features)."""

    def __init__(self, vertices, faces, props=None, lines=None):
        self.vertices, self.faces = vertices, faces
        self.props = props or {}
        self.lines = lines or []


class MeshRef:
    """A mesh on the service: its key, stats, and the URLs of every format."""

    def __init__(self, client, info):
        self.client = client
        self.key = info["key"]
        self.format = info.get("format")
        self.urls = info.get("urls") or {}
        self._stats = info.get("stats")

    @property
    def stats(self):
        if self._stats is None:
            self._stats = self.client._json("GET", self.urls["stats"])
        return self._stats

    def features(self):
        return self.client._json("GET", self.urls["features"])

    def fetch(self, fmt=None):
        """The file's bytes in format fmt (default: the one asked for)."""
        return self.client._request("GET", self.urls[fmt or self.format])[1]

    def load(self, fmt="ply"):
        """The mesh as a Mesh (fmt: "ply" or "obj")."""
        data = self.fetch(fmt)
        return load_ply(data) if fmt == "ply" else load_obj(data)


class Job:
    def __init__(self, client, info, params=None):
        self.client = client
        self.id = info["id"]
        self.info = info
        self.params = params if params is not None else info.get("params")

    @property
    def state(self):
        return self.info["state"]

    def refresh(self):
        self.info = self.client._json("GET", "/v1/jobs/" + self.id)
        return self

    def wait(self, timeout=DEFAULT_TIMEOUT_S):
        """Polls until the job ends: its MeshRef when done, IsomeshError when it failed."""
        deadline = time.monotonic() + timeout
        while self.info["state"] in ("queued", "running"):
            if time.monotonic() > deadline:
                raise TimeoutError("job %s still %s" % (self.id, self.info["state"]))
            time.sleep(POLL_S)
            self.refresh()
        if self.info["state"] != "done":
            err = self.info.get("error") or {}
            raise IsomeshError(self.info.get("status", 500), err.get("code", self.info["state"]),
                               err.get("message", "the job did not finish"))
        key, fmt = self.info["key"], self.info["format"]
        urls = {f: "/v1/meshes/%s.%s" % (key, f) for f in ("drc", "glb", "ply", "obj", "stl", "png")}
        urls.update(stats=self.info.get("stats_url", "/v1/meshes/%s/stats" % key),
                    features=self.info.get("features_url", "/v1/meshes/%s/features" % key))
        return MeshRef(self.client, {"key": key, "format": fmt, "urls": urls,
                                     "stats": self.info.get("stats")})


class Client:
    def __init__(self, base_url="http://127.0.0.1:8080", token=None, timeout=DEFAULT_TIMEOUT_S):
        self.base = base_url.rstrip("/")
        self.token = token
        self.timeout = timeout

    def _request(self, method, path, body=None, query=None):
        url = self.base + path
        if query:
            url += ("&" if "?" in url else "?") + urllib.parse.urlencode(query)
        headers = {"Accept": "application/json"} if path in ("/v1/mesh",) else {}
        data = None
        if body is not None:
            data = json.dumps(body).encode()
            headers["Content-Type"] = "application/json"
        if self.token:
            headers["Authorization"] = "Bearer " + self.token
        req = urllib.request.Request(url, data=data, method=method, headers=headers)
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as r:
                return r.status, r.read()
        except urllib.error.HTTPError as e:
            raw = e.read()
            try:
                err = json.loads(raw)["error"]
            except (ValueError, KeyError, TypeError):
                err = {"code": "http_%d" % e.code, "message": raw[:200].decode("utf-8", "replace")}
            raise IsomeshError(e.code, err.get("code"), err.get("message")) from None

    def _json(self, method, path, body=None, query=None):
        return json.loads(self._request(method, path, body, query)[1])

    def mesh(self, request, format=None):
        """Computes (or finds) the mesh of request (a dict: proto/request.schema.json) and
        returns its MeshRef; format ("drc", "glb", "ply", "obj", "stl", "png") overrides the
        request's."""
        query = {"format": format} if format else None
        return MeshRef(self, self._json("POST", "/v1/mesh", request, query))

    def job(self, request, format=None):
        """Starts a job for request; .wait() for its MeshRef."""
        query = {"format": format} if format else None
        return Job(self, self._json("POST", "/v1/jobs", request, query))

    def sweep(self, request, grid, format=None):
        """One job per point of grid ({param: [values]}, at most 64 points) on the base
        request; returns the Jobs in grid order (the first parameter varies slowest)."""
        query = {"format": format} if format else None
        answer = self._json("POST", "/v1/sweep", {"request": request, "grid": grid}, query)
        return [Job(self, j, j.get("params")) for j in answer["jobs"]]


# ---- loaders ---------------------------------------------------------------------------

_PLY_TYPES = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
              "float": "f", "double": "d", "int8": "b", "uint8": "B", "int16": "h",
              "uint16": "H", "int32": "i", "uint32": "I", "float32": "f", "float64": "d"}


def _ply_header(data):
    end = data.index(b"end_header")
    body_at = data.index(b"\n", end) + 1
    lines = data[:end].decode("ascii").splitlines()
    if not lines or lines[0] != "ply":
        raise ValueError("not a PLY file")
    fmt, elements = None, []
    for line in lines[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "format":
            fmt = w[1]
        elif w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property":
            elements[-1][2].append(tuple(w[1:]))
    return fmt, elements, body_at


def _read_binary_element(data, at, count, props, endian):
    rows = []
    for _ in range(count):
        row = []
        for p in props:
            if p[0] == "list":
                nfmt, ifmt = endian + _PLY_TYPES[p[1]], endian + _PLY_TYPES[p[2]]
                (n,) = struct.unpack_from(nfmt, data, at)
                at += struct.calcsize(nfmt)
                row.append(struct.unpack_from(endian + _PLY_TYPES[p[2]] * n, data, at))
                at += struct.calcsize(ifmt) * n
            else:
                f = endian + _PLY_TYPES[p[0]]
                row.append(struct.unpack_from(f, data, at)[0])
                at += struct.calcsize(f)
        rows.append(row)
    return rows, at


def load_ply(data):
    """A PLY file (binary little/big endian or ASCII) as a Mesh; every vertex property other
    than x y z goes into props by name."""
    fmt, elements, at = _ply_header(data)
    endian = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    text = data[at:].decode("ascii").split() if fmt == "ascii" else None
    got = {}
    for name, count, props in elements:
        if endian:
            rows, at = _read_binary_element(data, at, count, props, endian)
        else:
            rows = []
            for _ in range(count):
                row = []
                for p in props:
                    if p[0] == "list":
                        n = int(text.pop(0))
                        row.append(tuple(int(text.pop(0)) for _ in range(n)))
                    else:
                        row.append(float(text.pop(0)))
                rows.append(row)
        got[name] = (props, rows)
    vprops, vrows = got.get("vertex", ([], []))
    names = [p[-1] for p in vprops]
    ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
    vertices = [(r[ix], r[iy], r[iz]) for r in vrows]
    props = {n: [r[i] for r in vrows] for i, n in enumerate(names) if n not in ("x", "y", "z")}
    fprops, frows = got.get("face", ([], []))
    faces = [tuple(r[0]) for r in frows]
    return Mesh(vertices, faces, props)


def load_obj(data):
    """An OBJ file as a Mesh: v, f (any vertex/texture/normal form, 1-based or negative) and
    l lines (polylines: the features isomesh writes)."""
    vertices, faces, lines = [], [], []

    def index(tok):
        i = int(tok.split("/")[0])
        return i - 1 if i > 0 else len(vertices) + i

    for line in data.decode("utf-8").splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            vertices.append(tuple(float(t) for t in w[1:4]))
        elif w[0] == "f":
            idx = [index(t) for t in w[1:]]
            for k in range(1, len(idx) - 1):
                faces.append((idx[0], idx[k], idx[k + 1]))
        elif w[0] == "l":
            lines.append([index(t) for t in w[1:]])
    return Mesh(vertices, faces, lines=lines)
