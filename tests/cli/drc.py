"""drc.py — a .drc payload decoded by an independent reader (npm draco3d through
tests/cli/decode_drc.mjs), for the CLI tests that check what the encoder wrote. A module of its
own, not a test module, so that importing it does not run another file's tests twice."""
import json
import os
import subprocess

DECODE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "decode_drc.mjs")  # npm draco3d


def decode_drc(data, tmp):
    path = os.path.join(tmp, "decode.drc")
    with open(path, "wb") as f:
        f.write(data)
    r = subprocess.run(["node", DECODE, path], capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        raise AssertionError("decode_drc.mjs failed: " + r.stderr)
    return json.loads(r.stdout)
