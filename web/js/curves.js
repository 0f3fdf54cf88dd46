// curves.js — the requested curves on the surface and the cells they cut (issue 14), from the
// features JSON ("curves" entries with "arcs", and "arrangement") and the Draco "cell"
// attribute: the curves as fat lines coloured by kind, the arrangement's vertices as small
// markers coloured by type (where curves cross, branch, end at the box, meet a double curve
// or a singular point), the arrangement's cells as distinct colours, picking a curve or a
// cell, and the panel's list of curve requests (what each entry sends as the request's
// "curves").
import * as THREE from 'three';
import { fatLines, markers, CURVE_KIND_COLORS, FEATURE_COLORS } from './features.js';

// One colour per kind of requested curve (proto/glb.c uses the same).
export const CUT_KIND_COLORS = {
  section: 0xff4fa3, level: 0x3b87ff, intersection: 0xffbf0a, silhouette: 0xe6e6e6, crease: 0xa855f7,
};
// One colour per arrangement vertex type (features JSON arrangement.vertices[].type); the
// two on the singular locus take the colours of the double curves and singular points.
export const ARR_VERTEX_COLORS = {
  crossing: 0xffffff, branch: 0x9fb4ff, end: 0x8a94a6, loop: 0x5d6b82,
  double_curve: CURVE_KIND_COLORS.double, singular_point: FEATURE_COLORS.points,
};
// Vertex markers drawn at most (a stack of 64 planes on a busy surface makes thousands of
// crossings; the legend still counts them all). Radius relative to the singular points'.
const MAX_VERTEX_MARKERS = 20000;
const VERTEX_MARKER_SCALE = 0.55;
const CURVE_WIDTH = 3;
export const MAX_CURVE_REQUESTS = 32;   // entries the panel keeps (the server allows 256)
export const MAX_STACK = 64;            // planes or levels in one entry

const isCut = (c) => Array.isArray(c.arcs);

// The arrangement's vertices as markers of radius r, one colour per type; their counts by
// type into made.vertexTypes.
function vertexMarkers(f, r, clippingPlanes, made) {
  const vertices = ((f && f.arrangement && f.arrangement.vertices) || []).filter((v) => Array.isArray(v.xyz));
  let budget = MAX_VERTEX_MARKERS;
  for (const [type, color] of Object.entries(ARR_VERTEX_COLORS)) {
    const some = vertices.filter((v) => v.type === type);
    if (some.length) made.vertexTypes[type] = some.length;
    const drawn = some.slice(0, Math.max(0, budget));
    budget -= drawn.length;
    if (drawn.length) {
      const g = markers(drawn, r, color, clippingPlanes);
      g.name = `curve-vertices-${type}`;
      made.group.add(g);
    }
  }
}

// The requested curves of features f: {group, count (curves drawn), kinds {kind: n},
// vertexTypes {type: n}, pickables [{what: 'cut', p, at}]}. radius: the singular points'
// marker size (the curves' vertices are drawn smaller).
export function buildCurves(f, clippingPlanes, radius = 0.01) {
  const group = new THREE.Group();
  group.name = 'requested-curves';
  const made = { group, count: 0, kinds: {}, vertexTypes: {}, pickables: [] };
  const curves = ((f && f.curves) || []).filter(isCut);
  for (const [kind, color] of Object.entries(CUT_KIND_COLORS)) {
    const pos = [];
    for (const c of curves.filter((x) => x.kind === kind)) {
      for (const a of c.arcs) for (let i = 0; i + 5 < a.length; i += 3) pos.push(...a.slice(i, i + 6));
    }
    if (pos.length) group.add(fatLines(pos, color, CURVE_WIDTH, clippingPlanes));
  }
  for (const c of curves) {
    made.kinds[c.kind] = (made.kinds[c.kind] || 0) + 1;
    const at = [];
    for (const a of c.arcs) for (let i = 0; i + 2 < a.length; i += 3) at.push([a[i], a[i + 1], a[i + 2]]);
    made.pickables.push({ what: 'cut', p: c, at });
  }
  made.count = curves.length;
  vertexMarkers(f, VERTEX_MARKER_SCALE * radius, clippingPlanes, made);
  group.traverse((o) => { o.frustumCulled = false; });
  return made;
}

// A distinct colour per cell id (golden-angle hues), linear RGB per point.
export function cellColors(cells) {
  const rgb = new Float32Array(cells.length * 3);
  const c = new THREE.Color();
  for (let i = 0; i < cells.length; i++) {
    const id = cells[i];
    c.setHSL((id * 0.381966) % 1, 0.62, id % 2 ? 0.52 : 0.64, THREE.SRGBColorSpace);
    rgb[3 * i] = c.r; rgb[3 * i + 1] = c.g; rgb[3 * i + 2] = c.b;
  }
  return rgb;
}

// The arrangement face of cell id (features JSON), or null.
export function cellFace(f, id) {
  const faces = f && f.arrangement && f.arrangement.faces;
  return (faces || []).find((x) => x.id === id) || null;
}

// ---- the panel's curve requests -------------------------------------------------------
// An entry: {kind: 'plane', axis: 'x'|'y'|'z'|'a,b,c', count} | {kind: 'levels', expr,
// values: 'c1, c2'} | {kind: 'surface', expr} | {kind: 'silhouette', direction: [3]}.

export const AXIS_NORMALS = { x: [1, 0, 0], y: [0, 1, 0], z: [0, 0, 1] };

function parseNormal(axis) {
  if (AXIS_NORMALS[axis]) return AXIS_NORMALS[axis];
  const v = String(axis).split(',').map(Number);
  return v.length === 3 && v.every(Number.isFinite) && v.some((x) => x !== 0) ? v : null;
}

// count planes n·p = d evenly inside the box's extent along n (the planes at i / (count + 1)
// of the way, so one plane cuts the middle).
export function stackOffsets(normal, count, box) {
  let lo = 0, hi = 0;
  for (let k = 0; k < 3; k++) {
    lo += normal[k] * (normal[k] > 0 ? box[k] : box[k + 3]);
    hi += normal[k] * (normal[k] > 0 ? box[k + 3] : box[k]);
  }
  const out = [];
  for (let i = 1; i <= count; i++) out.push(Number((lo + (hi - lo) * i / (count + 1)).toPrecision(12)));
  return out;
}

function parseValues(text) {
  const v = String(text).split(/[\s,]+/).filter(Boolean).map(Number);
  return v.length && v.length <= MAX_STACK && v.every(Number.isFinite) ? v : null;
}

// The request's "curves" item of a panel entry in box, or null when the entry is not valid.
export function curveRequest(e, box) {
  if (e.kind === 'plane') {
    const n = parseNormal(e.axis);
    const count = Math.round(Number(e.count));
    if (!n || !(count >= 1 && count <= MAX_STACK)) return null;
    return { kind: 'plane', normal: n, offsets: stackOffsets(n, count, box) };
  }
  if (e.kind === 'levels') {
    const values = parseValues(e.values);
    return e.expr && values ? { kind: 'levels', expr: e.expr, values } : null;
  }
  if (e.kind === 'surface') return e.expr ? { kind: 'surface', expr: e.expr } : null;
  if (e.kind === 'silhouette') {
    const d = e.direction;
    return Array.isArray(d) && d.length === 3 && d.every(Number.isFinite) ? { kind: 'silhouette', direction: d } : null;
  }
  return null;
}

// A short label of an entry for the list.
export function describeCurve(e) {
  if (e.kind === 'plane') return `${e.count} plane${Number(e.count) === 1 ? '' : 's'} ⊥ ${AXIS_NORMALS[e.axis] ? e.axis : `(${e.axis})`}`;
  if (e.kind === 'levels') return `${e.expr} = ${e.values}`;
  if (e.kind === 'surface') return `∩ ${e.expr} = 0`;
  if (e.kind === 'silhouette') return `silhouette along (${e.direction.map((v) => Number(v.toFixed(3))).join(', ')})`;
  return e.kind;
}

// Validates entries read from a link: the valid ones (at most MAX_CURVE_REQUESTS).
export function validEntries(list, box) {
  return (Array.isArray(list) ? list : []).filter((e) => e && curveRequest(e, box)).slice(0, MAX_CURVE_REQUESTS);
}
