// decode_drc.mjs — test helper: decodes a .drc with npm draco3d (a decoder independent of
// the libdraco that encoded it) and prints {"faces", "points", "index", "position", "normal"
// (when sent), the curvatures "mean_curvature" and "gauss_curvature" (when sent), the integer
// attributes "cell" and "double_sheet" when present, and "attributes": {name: unique id} of
// every attribute decoded} as JSON, for Python tests.
// Usage: node tests/cli/decode_drc.mjs FILE.drc
import fs from 'node:fs';
import { decodeDraco } from '../browser/lib/draco.mjs';

const m = await decodeDraco(fs.readFileSync(process.argv[2]));
const out = { faces: m.faces, points: m.points, index: Array.from(m.index),
  position: Array.from(m.attributes.position.values) };
for (const name of ['normal', 'mean_curvature', 'gauss_curvature']) {
  if (m.attributes[name]) out[name] = Array.from(m.attributes[name].values);
}
out.attributes = Object.fromEntries(Object.entries(m.attributes).map(([n, a]) => [n, a.uniqueId]));
for (const name of ['cell', 'double_sheet']) {
  const a = m.attributes[name];
  if (a) out[name] = { unique_id: a.uniqueId, values: Array.from(a.values) };
}
process.stdout.write(JSON.stringify(out));
