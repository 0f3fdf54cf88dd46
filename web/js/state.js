// state.js — the viewer's whole state as plain data, the request body it implies, and its
// round trip through the URL fragment, so that a shared link reopens the same surface,
// parameters, box, depth, view, colour mode, clipping and toggles.
//
// Fragment keys (URLSearchParams): preset=NAME | expr=TEXT, p.NAME=VALUE per parameter,
// box=xmin,ymin,zmin,xmax,ymax,zmax, depth=MIN,MAX, err=MAX_ERROR|off (absent: the server's
// default bound), mesher=primal|straddle,
// simplify=1, quality=good, cam=px,py,pz,tx,ty,tz,
// color=shaded|mean|gauss|cells, clip=AXIS,OFFSET[,flip], hide=edges,points,boundary,box,curves,
// wire=1, axes=1, ao=1 (the render mode with ambient occlusion), shadows=1 (the render mode's
// soft shadows), curves=JSON list of the
// Curves panel's entries (curves.js).
import { curveRequest, validEntries } from './curves.js';

export const COLOR_MODES = ['shaded', 'mean', 'gauss', 'cells'];
// The per-vertex attributes (request output.attributes) each colour mode draws: normals for
// the shading, a curvature only while its map is shown (the two curvatures are about a third
// of the bytes of a curved surface). Cells and double sheets travel whenever the surface has
// them. A mesh holding more than this serves the mode too (loader.js).
export const COLOR_ATTRIBUTES = {
  shaded: ['normal'], cells: ['normal'],
  mean: ['normal', 'mean_curvature'], gauss: ['normal', 'gauss_curvature'],
};
const FEATURES = ['edges', 'points', 'boundary', 'box', 'curves'];
// The meshers a request under a bound may ask for (proto/request.schema.json "dual",
// "straddle"); the first is the default.
export const MESHERS = ['dual', 'primal', 'straddle'];
const DEFAULT_BOX = [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5];
// The server's error bound when a request gives none: this times the box diagonal
// (proto/request.h ISM_REQ_DEFAULT_ERROR_REL; the Max error field's placeholder shows it).
export const DEFAULT_ERROR_REL = 1e-3;

// The server's default bound for a box.
export function defaultMaxError(box) {
  return DEFAULT_ERROR_REL * Math.hypot(box[3] - box[0], box[4] - box[1], box[5] - box[2]);
}

// Is the mesh made under a bound (the default one or a given one)?
export function bounded(state) {
  return state.maxError !== 'off';
}

export function defaultState() {
  return {
    preset: null,           // preset name when the expression is the preset's own text
    expr: '',
    params: {},             // name -> value
    box: DEFAULT_BOX.slice(),
    depth: { min: 3, max: 7 },
    maxError: null,         // the error bound (model units); null: the server's default
                            // (DEFAULT_ERROR_REL x the box diagonal); 'off': no bound, the
                            // depth decides ("max_error": null)
    quality: 'raw',         // 'good': the server's quality pass after meshing
    mesher: 'dual',         // under maxError: 'dual' (the server's default: the dual mesh
                            // where it applies), 'primal' ("dual": false) or 'straddle'
                            // (the primal polygons with straddled vertices)
    simplify: false,        // under maxError: "simplify": true, the fewest triangles within
                            // it (the server's default, for every mesher: the mesher's own)
    view: null,             // {pos: [3], target: [3]}
    color: 'shaded',
    clip: { on: false, axis: 'z', offset: 0, flip: false, cap: true },
    show: { edges: true, points: true, boundary: true, box: true, axes: false, curves: true },
    curves: [],             // the Curves panel's entries (curves.js)
    keepBox: false,         // a typed expression keeps the box (else it is fitted, POST /v1/box)
    wire: false,
    occlusion: false,       // the render mode: ambient occlusion over the shading (occlusion.js)
    shadows: false,         // the render mode: soft shadows from a key light (shadows.js)
  };
}

// The request JSON text for state (params: only the names the expression uses; the
// attributes its colour mode draws).
export function requestBody(state, paramNames) {
  const body = {};
  if (state.preset) body.preset = state.preset;
  else body.expr = state.expr;
  const params = {};
  for (const n of paramNames) if (Number.isFinite(state.params[n])) params[n] = state.params[n];
  if (Object.keys(params).length) body.params = params;
  body.box = state.box.slice();
  if (bounded(state)) {
    body.depth = { min: state.depth.min };  // depth.max: the server's limit, a safety net
    if (state.maxError > 0) body.max_error = state.maxError;  // else the server's default
    if (state.mesher !== 'dual') body.dual = false;  // the dual mesh is the server's default
    if (state.mesher === 'straddle') body.straddle = true;
    if (state.simplify) body.simplify = true;  // off: the server's default
  } else {
    body.depth = { min: state.depth.min, max: state.depth.max };
    body.max_error = null;  // the depth path: no bound (left out, the server's default)
  }
  if (state.quality === 'good') body.quality = 'good';
  const curves = (state.curves || []).map((e) => curveRequest(e, state.box)).filter(Boolean);
  if (curves.length) body.curves = curves;
  body.output = { attributes: COLOR_ATTRIBUTES[state.color] || COLOR_ATTRIBUTES.shaded };
  return JSON.stringify(body);
}

// Shortest text that reads back as the same double.
function num(v) {
  return String(v);
}

function short(v) {
  return String(Number(v.toPrecision(7)));
}

export function encodeState(state, paramNames) {
  const q = new URLSearchParams();
  if (state.preset) q.set('preset', state.preset);
  else q.set('expr', state.expr);
  for (const n of paramNames) if (Number.isFinite(state.params[n])) q.set('p.' + n, num(state.params[n]));
  q.set('box', state.box.map(num).join(','));
  q.set('depth', `${state.depth.min},${state.depth.max}`);
  if (state.maxError > 0) q.set('err', num(state.maxError));
  else if (state.maxError === 'off') q.set('err', 'off');
  if (state.quality === 'good') q.set('quality', 'good');
  if (state.mesher !== 'dual') q.set('mesher', state.mesher);
  if (state.simplify) q.set('simplify', '1');
  if (state.view) q.set('cam', [...state.view.pos, ...state.view.target].map(short).join(','));
  if (state.color !== 'shaded') q.set('color', state.color);
  if (state.clip.on) q.set('clip', [state.clip.axis, short(state.clip.offset)].concat(state.clip.flip ? ['flip'] : []).join(','));
  const hidden = FEATURES.filter((k) => !state.show[k]);
  if (hidden.length) q.set('hide', hidden.join(','));
  if (state.wire) q.set('wire', '1');
  if (state.occlusion) q.set('ao', '1');
  if (state.shadows) q.set('shadows', '1');
  if (state.show.axes) q.set('axes', '1');
  if (state.curves && state.curves.length) q.set('curves', JSON.stringify(state.curves));
  return q.toString().replace(/%2C/g, ',');  // commas read fine in a fragment
}

function numbers(text, count) {
  if (typeof text !== 'string') return null;
  const parts = text.split(',');
  if (parts.length !== count) return null;
  const v = parts.map((s) => (s.trim() === '' ? NaN : Number(s)));
  return v.every(Number.isFinite) ? v : null;
}

// Reads a fragment (with or without '#') into a partial state: only what it says, validated;
// unreadable entries are left out (and listed in .problems).
export function decodeState(fragment) {
  const q = new URLSearchParams(fragment.replace(/^#/, ''));
  const s = { problems: [] };
  if (q.has('preset')) s.preset = q.get('preset');
  else if (q.has('expr')) s.expr = q.get('expr');
  const params = {};
  for (const [k, v] of q) {
    if (!k.startsWith('p.')) continue;
    const x = Number(v);
    if (v.trim() !== '' && Number.isFinite(x)) params[k.slice(2)] = x;
    else s.problems.push(`parameter ${k.slice(2)}`);
  }
  if (Object.keys(params).length) s.params = params;
  if (q.has('box')) {
    const b = numbers(q.get('box'), 6);
    if (b) s.box = b; else s.problems.push('box');
  }
  if (q.has('depth')) {
    const d = numbers(q.get('depth'), 2);
    if (d && d.every(Number.isInteger)) s.depth = { min: d[0], max: d[1] }; else s.problems.push('depth');
  }
  if (q.has('err')) {
    const e = Number(q.get('err'));
    if (q.get('err') === 'off') s.maxError = 'off';
    else if (e > 0 && Number.isFinite(e)) s.maxError = e; else s.problems.push('err');
  }
  if (q.has('quality')) {
    if (['raw', 'good'].includes(q.get('quality'))) s.quality = q.get('quality'); else s.problems.push('quality');
  }
  if (q.has('mesher')) {
    if (MESHERS.includes(q.get('mesher'))) s.mesher = q.get('mesher'); else s.problems.push('mesher');
  }
  if (q.has('simplify')) {
    if (['0', '1'].includes(q.get('simplify'))) s.simplify = q.get('simplify') === '1'; else s.problems.push('simplify');
  }
  if (q.has('cam')) {
    const c = numbers(q.get('cam'), 6);
    if (c) s.view = { pos: c.slice(0, 3), target: c.slice(3) }; else s.problems.push('cam');
  }
  if (q.has('color')) {
    if (COLOR_MODES.includes(q.get('color'))) s.color = q.get('color'); else s.problems.push('color');
  }
  if (q.has('clip')) {
    const parts = q.get('clip').split(',');
    const off = Number(parts[1]);
    if (['x', 'y', 'z'].includes(parts[0]) && parts[1] !== undefined && Number.isFinite(off) &&
        (parts.length === 2 || (parts.length === 3 && parts[2] === 'flip'))) {
      s.clip = { on: true, axis: parts[0], offset: off, flip: parts[2] === 'flip' };
    } else {
      s.problems.push('clip');
    }
  }
  if (q.has('hide')) {
    const hidden = q.get('hide').split(',');
    s.show = Object.fromEntries(FEATURES.map((k) => [k, !hidden.includes(k)]));
  }
  if (q.has('axes')) s.show = { ...(s.show || Object.fromEntries(FEATURES.map((k) => [k, true]))), axes: q.get('axes') === '1' };
  if (q.has('wire')) s.wire = q.get('wire') === '1';
  if (q.has('ao')) s.occlusion = q.get('ao') === '1';
  if (q.has('shadows')) s.shadows = q.get('shadows') === '1';
  if (q.has('curves')) {
    let list = null;
    try { list = JSON.parse(q.get('curves')); } catch { list = null; }
    const box = s.box || DEFAULT_BOX;
    const kept = validEntries(list, box);
    if (Array.isArray(list) && kept.length === list.length) s.curves = kept;
    else { s.curves = kept; s.problems.push('curves'); }
  }
  return s;
}

// A slider range for a parameter the user typed (no preset range): around its value.
export function sensibleRange(value) {
  if (value > 0) return [0, 2 * value];
  if (value < 0) return [2 * value, 0];
  return [-1, 1];
}
