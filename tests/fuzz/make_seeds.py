#!/usr/bin/env python3
"""make_seeds.py — writes the committed seed corpora tests/fuzz/corpus/<target>/ (run it again
after changing an input layout; the files are small and reviewed like code).

  expr        fuzz_text.h layout: "$name=value" parameters, "@name=source" lets, the rest
              is the expression
  polygonise  8 option bytes (see fuzz_polygonise.c) + the expr layout
  request     JSON request bodies
  frame       1 mode byte (see fuzz_frame.c) + a stream of worker frames (real CRC-32C)
"""
import json
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

EXPRS = [
    "x^2 + y^2 + z^2 - r^2\n$r=1",
    "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)\n$R=1\n$r=0.3",
    "(x*(x-1)^2*(x-2) + y^2)^2 + z^2 - t\n$t=0.03",
    "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)\n$k=4",
    "(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s\n$mu2=0.6667\n$w=1\n@lambda=(3*mu2 - 1)/(3 - mu2)\n"
    "@p=w - z - sqrt(2)*x\n@q=w - z + sqrt(2)*x\n@r=w + z + sqrt(2)*y\n@s=w + z - sqrt(2)*y",
    "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + 16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
    "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z",
    "let a = x^2 + y^2\nlet b = a - z; c = b*b\nmin(c - 0.1, abs(z) - 0.5, max(x, y, z))",
    "tan(x) + log(y) - exp(z)/pow(x, 3) + x^-2 - 2^3^2*pi*e",
    "sqrt(x*x + y*y) - 0.5 + 1/(z - 0.25) - log(abs(x*y*z))",
    "min(x, -x) + max(y, 2) - min(z, 1e300*z, -1e-300)",
    "sin(1e30*x) + cos(y)^64 - exp(1000*z)",
    "x ^ 2 + (y",          # error: expected ')'
    "sinn(x)",             # error: unknown function
    "let let = 1\nx",      # error: keyword
    "x + q\n$q=nan",       # error: non-finite parameter
    "a + b\n@a=x*2\n@b=a^3 - y",
    "x*y*z - w\n$w=-0.125\n$x=1",  # error: shadows a variable
]

# Option bytes for the polygoniser: min depth, max depth, box size, box centre, gradient
# test, flatness, stitch/root iterations, root eps/triangle budget/cancel/threads.
POLY = [
    (bytes([2, 3, 4, 0, 0, 0, 0, 0]), EXPRS[0]),
    (bytes([2, 3, 4, 0, 0, 0, 0, 0]), EXPRS[1]),
    (bytes([1, 4, 5, 2, 0, 8, 0, 0]), EXPRS[2].replace("t=0.03", "t=0.03")),
    (bytes([2, 2, 4, 0, 0, 0, 0, 0]), EXPRS[3]),
    (bytes([2, 2, 6, 0, 0, 0, 0, 0]), EXPRS[4].replace("mu2=0.6667", "mu2=2")),
    (bytes([2, 3, 4, 1, 0, 0, 0, 0]), EXPRS[5]),
    (bytes([2, 3, 3, 0, 0, 0, 0, 0]), EXPRS[6]),
    (bytes([0, 5, 3, 0, 1, 2, 3, 0x40]), "x*y"),
    (bytes([3, 3, 3, 0, 0, 0, 0, 0x80]), "x^2 + y^2 - z^2"),
    (bytes([1, 5, 0, 5, 0, 0, 0, 0x18]), "(x^2 + y^2 + z^2)^2 - x^2 + y^2"),
    (bytes([2, 4, 3, 3, 0, 0, 0, 0x20]), "min(x^2 + y^2 + z^2 - 0.5, abs(z) - 0.1)"),
    (bytes([2, 3, 4, 0, 0, 0, 0, 0xc1]), "(x^2 + y^2 + z^2 - 1)^2"),
]

REQUESTS = [
    {"expr": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1}},
    {"preset": "torus", "params": {"r": 0.25}, "depth": {"max": 6}},
    {"preset": "kummer-4-nodes"},
    {"expr": "a*b - z", "let": {"a": "x + y", "b": "a^2"}, "box": [-2, -2, -2, 2, 2, 2]},
    {"expr": "p - 1", "let": [["p", "x^2 + y^2 + z^2"]], "depth": {"min": 2, "max": 5},
     "tolerances": {"gradient": 0.8, "double_root_eps": 1e-12, "double_root_iters": 30,
                    "stitch": 0.002, "flat_normal": 0.95, "flat_plane": 0.1},
     "output": {"format": "glb", "position_bits": 16, "normal_bits": 12, "curvature_bits": 0,
                "attributes": ["normal", "mean_curvature", "gauss_curvature", "class"]}},
    {"expr": "x", "output": {"format": "stl", "attributes": []}},
    {"preset": "gyroid-ball", "params": {"k": 2.5}, "box": [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5]},
]
BAD_REQUESTS = [
    '{"expr": "x",', '{"expr": "x", "expr": "y"}', '{"expr": "x"} x', '{}',
    '{"expr": "x", "depth": {"max": 14}}', '{"expr": "sin(", "box": [0, 0, 0, 1, 1, 1]}',
    '{"expr": "x", "box": [1, 0, 0, 0, 1, 1]}', '{"preset": "torus", "let": {"p": "x"}}',
    '{"expr": "x", "params": {"x": 1}}', '{"expr": "r", "params": {"r": "1"}}',
]

MAGIC = b"ISMF"


def crc32c(data, crc=0):
    crc ^= 0xFFFFFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0x82F63B78 if crc & 1 else crc >> 1
    return crc ^ 0xFFFFFFFF


def frame(ftype, job, payload):
    head = MAGIC + bytes([1, ftype, 0, 0]) + struct.pack("<QI", job, len(payload))
    return head + struct.pack("<I", crc32c(head + payload)) + payload


def u32(v): return struct.pack("<I", v)
def u64(v): return struct.pack("<Q", v)
def blob(b): return u32(len(b)) + b


def job_payload(json_text, fmt=b"", computed=b""):
    return (u32(8) + u32(1) + u64(100000) + u64(1 << 28) + blob(fmt) + blob(json_text) +
            blob(computed))


def result_payload(status, body, surface_len=0):
    return (u32(status) + u32(1234) + blob(b"ab" * 32) + blob(b"cd" * 32) + u32(1) +
            blob(b"drc") + blob(b"application/vnd.google.draco") + blob(b'{"triangles": 2}') +
            blob(b"{}") + blob(b'{"expr": "x"}') + blob(body) + u32(surface_len))


FRAMES = [
    (0x00, frame(1, 0, u32(4242) + blob(b"isomesh 0.1"))),
    (0x01, frame(2, 7, job_payload(b'{"expr": "x^2 + y^2 + z^2 - 1"}'))),
    (0x02, frame(3, 7, u32(500000)) + frame(3, 7, u32(1000000)) +
     frame(4, 7, result_payload(200, b"DRACO\x02\x02", 16)) +
     frame(6, 7, b"ISMS" + bytes(12))),  # the surface announced, in a SURFACE frame
    (0x23, frame(5, 9, u32(422) + blob(b'{"error": {"code": "over_limit"}}'))),
    (0x08, frame(2, 1, job_payload(b"{}", b"glb"))[:20] + b"\0\0\0\0" +
     job_payload(b"{}", b"glb")),  # checksum left for the harness to fix (mode bit 3)
    (0x10, result_payload(200, b"body")),    # payload-only mode
    (0x10, result_payload(200, b"body", 16)),  # announcing a computed surface
    (0x10, job_payload(b'{"preset": "sphere"}', b"ply", b"ISMS" + bytes(12))),
    (0x10, job_payload(b'{"preset": "torus"}', b"stl")),
    (0x44, frame(4, 3, result_payload(500, b""))[:40]),  # truncated
    (0x05, b"ISMF\x02" + bytes(19)),          # wrong version
    (0x06, frame(9, 1, b"")),                 # unknown type
]


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def main():
    for i, e in enumerate(EXPRS):
        write("expr", f"seed-{i:02d}", e)
    for i, (opts, e) in enumerate(POLY):
        write("polygonise", f"seed-{i:02d}", opts + e.encode())
    for i, r in enumerate(REQUESTS):
        write("request", f"seed-{i:02d}", json.dumps(r, indent=1 if i % 2 else None))
    for i, r in enumerate(BAD_REQUESTS):
        write("request", f"bad-{i:02d}", r)
    for i, (mode, data) in enumerate(FRAMES):
        write("frame", f"seed-{i:02d}", bytes([mode]) + data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
