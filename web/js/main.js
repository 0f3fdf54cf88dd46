// main.js — the viewer's wiring: state from the URL (or the default preset), the controls,
// when to compute (Compute / Ctrl+Enter for the editor, debounced slider and box changes,
// instantly for results this page already holds), what to show when the mesh arrives, and
// how each server error reads (inline expression errors with their column, limits, busy
// with its retry time, the token prompt on 401).
import { Viewer } from './viewer.js';
import { POINT_TYPE_COLORS, CURVE_KIND_COLORS } from './features.js';
import { ARR_VERTEX_COLORS, CUT_KIND_COLORS, MAX_CURVE_REQUESTS, curveRequest, describeCurve, cellFace } from './curves.js';
import * as api from './api.js';
import * as loader from './loader.js';
import { checkExpression, presetSource } from './expr.js';
import { defaultState, requestBody, encodeState, decodeState, sensibleRange, bounded, defaultMaxError, COLOR_MODES, COLOR_ATTRIBUTES } from './state.js';
import { renderParams } from './params_ui.js';
import { showStats, clearStats, showLegend } from './stats_ui.js';
import { niceStep, sig } from './format.js';
import { Gallery } from './gallery.js';
import { Previewer, ticket, claim } from './live.js';
import * as timeline from './timeline.js';

const DEFAULT_PRESET = 'steiner-roman';
const DEBOUNCE_MS = 250;
const BUSY_DELAY_MS = 120;
const MAX_AUTO_RETRIES = 3;
const AXIS_INDEX = { x: 0, y: 1, z: 2 };

const $ = (id) => document.getElementById(id);

let viewer = null;
let presets = [];
let state = defaultState();
let paramNames = [];         // the parameters the current expression uses, in order
let ranges = {};             // name -> [min, max] of its slider
let exprOk = true;
let running = null;          // {controller, body}
let debounceTimer = 0;
let busyTimer = 0;
let retry = { timer: 0, count: 0, body: null };
let pendingView = null;      // a view from the URL, applied to the first mesh
let shownIdentity = null;    // what the mesh on screen is (refit when it changes)
let afterToken = null;       // the request to resend once a token is given
let loads = 0;               // refined meshes shown
let previews = 0;            // coarse previews shown (live.js)
let previewer = null;
let basePreset = null;       // the preset last chosen (the editor may drift from its text)
let shownBody = null;        // the request of the mesh on screen
let refineTurn = 0;          // the newest request change: a refinement waiting for an older one is dropped

const presetByName = (name) => presets.find((p) => p.name === name) || null;

// ---- messages -------------------------------------------------------------------------

function message(text, kind = 'info', action = null) {
  const box = $('message');
  box.textContent = text;
  box.className = `message ${kind}`;
  box.setAttribute('role', kind === 'error' ? 'alert' : 'status');
  if (action) {
    const b = document.createElement('button');
    b.type = 'button';
    b.textContent = action.label;
    b.addEventListener('click', action.run);
    box.append(b);
  }
  box.hidden = !text;
}

function clearMessage() {
  message('');
}

function setBusy(on) {
  clearTimeout(busyTimer);
  document.body.dataset.busy = on ? '1' : '0';
  if (!on) {
    $('busy').hidden = true;
    return;
  }
  $('progress').value = 0;
  // Over a live preview the refinement is announced quietly: the picture is already there.
  const quiet = document.body.dataset.shown === 'preview';
  $('busy').classList.toggle('quiet', quiet);
  $('progress-label').textContent = quiet ? 'Refining…' : 'Sending…';
  busyTimer = setTimeout(() => { $('busy').hidden = false; }, BUSY_DELAY_MS);
}

function setProgress(fraction, jobState) {
  $('progress').value = fraction;
  if ($('busy').classList.contains('quiet')) return;
  $('progress-label').textContent = jobState === 'queued' ? 'Queued: waiting for a worker…'
    : `Computing… ${Math.round(100 * fraction)}%`;
}

// ---- expression and parameters --------------------------------------------------------

function showExprError(err, fromServer) {
  const box = $('expr-error');
  const editor = $('expr');
  if (!err) {
    box.hidden = true;
    box.textContent = '';
    editor.removeAttribute('aria-invalid');
    delete box.dataset.line;
    delete box.dataset.column;
    return;
  }
  editor.setAttribute('aria-invalid', 'true');
  box.hidden = false;
  box.textContent = '';
  box.dataset.line = String(err.line || 0);
  box.dataset.column = String(err.column || 0);
  box.dataset.source = fromServer ? 'server' : 'client';
  const head = document.createElement('div');
  head.className = 'where';
  const where = err.line ? (err.line > 1 || state.expr.includes('\n') ? `line ${err.line}, column ${err.column}` : `column ${err.column}`) : '';
  head.textContent = (where ? `${where}: ` : '') + err.message;
  box.append(head);
  if (err.line) {
    const lines = state.expr.split('\n');
    const text = lines[err.line - 1] ?? '';
    const pre = document.createElement('pre');
    const caret = document.createElement('span');
    caret.className = 'caret';
    caret.textContent = ' '.repeat(Math.max(0, err.column - 1)) + '^';
    pre.append(document.createTextNode(text + '\n'), caret);
    box.append(pre);
  }
  if (fromServer) {
    const src = document.createElement('div');
    src.className = 'source';
    src.textContent = 'reported by the server';
    box.append(src);
  }
}

// Re-reads the editor's text: error or parameter list; rebuilds sliders when the names change.
function refreshExpression() {
  const preset = presetByName(state.preset);
  const check = checkExpression(state.expr, state.params);
  exprOk = check.ok;
  if (!check.ok) {
    showExprError(check, false);
    return false;
  }
  showExprError(null);
  const names = check.params;
  for (const n of names) {
    const pp = preset && preset.params.find((q) => q.name === n);
    if (!Number.isFinite(state.params[n])) state.params[n] = pp ? pp.default : 1;
    if (!ranges[n]) ranges[n] = pp ? [pp.min, pp.max] : sensibleRange(state.params[n]);
  }
  if (names.join('\n') !== paramNames.join('\n')) {
    paramNames = names;
    renderSliders();
  }
  return true;
}

function renderSliders() {
  const list = paramNames.map((n) => ({ name: n, value: state.params[n], min: ranges[n][0], max: ranges[n][1] }));
  renderParams($('params'), list, (name, value, fromSlider) => {
    state.params[name] = value;
    requestChanged({ live: fromSlider });
  });
}

// ---- presets --------------------------------------------------------------------------

function fillPresetMenu() {
  const sel = $('preset');
  sel.textContent = '';
  for (const p of presets) {
    const o = document.createElement('option');
    o.value = p.name;
    o.textContent = p.title;
    o.title = p.about;
    sel.append(o);
  }
  const custom = document.createElement('option');
  custom.value = '';
  custom.textContent = 'Custom expression';
  sel.append(custom);
  gallery.fill(presets);
  gallery.watch($('gallery-pictures').open);
  filterGallery();
}

// The pictures' strip (gallery.js): a click picks the preset like the menu does.
const gallery = new Gallery($('thumbs'), {
  load: (name) => api.getThumbnail(name),
  pick: (name) => {
    if (name === state.preset) return;
    $('preset').value = name;
    $('preset').dispatchEvent(new Event('change'));
  },
});

function usePreset(name) {
  const p = presetByName(name);
  if (!p) return false;
  state.preset = p.name;
  state.expr = presetSource(p);
  state.params = Object.fromEntries(p.params.map((q) => [q.name, q.default]));
  ranges = Object.fromEntries(p.params.map((q) => [q.name, [q.min, q.max]]));
  paramNames = [];
  state.box = p.box.slice();
  state.depth = { min: p.depth.min, max: p.depth.max };
  return true;
}

const FACT_LABELS = { nodes: 'nodes', euler: 'χ', components: 'components', singular_points: 'singular points' };

// "Source: ...; checked: 4 nodes, χ = 2" for a gallery entry.
function presetFacts(p) {
  const facts = Object.entries(p.facts || {}).map(([k, v]) => (k === 'euler' ? `χ = ${v}` : `${v} ${FACT_LABELS[k] || k}`));
  return `Source: ${p.source || '–'}` + (facts.length ? `; checked on the mesh: ${facts.join(', ')}` : '');
}

// The gallery search: keeps the presets whose name, title, description or source hold every
// word typed (case-insensitive); the current choice stays listed.
function filterGallery() {
  const words = $('gallery-search').value.toLowerCase().split(/\s+/).filter(Boolean);
  let shown = 0;
  const keep = (p) => words.every((w) => `${p.name} ${p.title} ${p.about} ${p.source || ''}`.toLowerCase().includes(w));
  for (const o of $('preset').options) {
    const p = presetByName(o.value);
    if (!p) continue;
    o.hidden = !keep(p) && o.value !== $('preset').value;
    if (!o.hidden) shown++;
  }
  gallery.filter((name) => keep(presetByName(name)), $('preset').value);
  $('gallery-count').textContent = words.length ? `${shown} of ${presets.length}` : `${presets.length} surfaces`;
  document.body.dataset.galleryShown = String(shown);
}

function showPresetChoice() {
  const p = presetByName(state.preset);
  $('preset').value = p ? p.name : '';
  $('preset-about').textContent = p ? p.about : 'Your own expression: every name that is not x, y, z, a function, a constant or a let is a parameter.';
  $('preset-source').textContent = p ? presetFacts(p) : '';
  $('reset-box').disabled = !p;
  filterGallery();
}

// ---- controls <-> state ---------------------------------------------------------------

const BOX_IDS = ['box-xmin', 'box-ymin', 'box-zmin', 'box-xmax', 'box-ymax', 'box-zmax'];

// The controls that follow the bound: depth max is only the server's safety limit under
// one; the meshers and the simplification need one; the field's placeholder is the default
// bound for the box (1e-3 x its diagonal).
function showBound() {
  const on = bounded(state);
  $('depth-max').disabled = on;
  $('mesher').disabled = !on;  // the meshers differ only under a bound
  $('simplify').disabled = !on;  // the bound keeps it honest
  const auto = defaultMaxError(state.box);
  $('max-error').placeholder = Number.isFinite(auto) && auto > 0
    ? `auto: ${sig(auto)} (1e-3 × diagonal)` : 'auto (1e-3 × diagonal)';
}

function syncControls() {
  showPresetChoice();
  if ($('expr').value !== state.expr) $('expr').value = state.expr;
  BOX_IDS.forEach((id, i) => { $(id).value = String(state.box[i]); $(id).removeAttribute('aria-invalid'); });
  $('depth-min').value = String(state.depth.min);
  $('depth-max').value = String(state.depth.max);
  $('max-error').value = state.maxError > 0 ? String(state.maxError) : state.maxError === 'off' ? 'off' : '';
  showBound();
  $('quality-good').checked = state.quality === 'good';
  $('mesher').value = state.mesher;
  $('simplify').checked = state.simplify;
  $('color-mode').value = state.color;
  $('show-edges').checked = state.show.edges;
  $('show-points').checked = state.show.points;
  $('show-boundary').checked = state.show.boundary;
  $('show-curves').checked = state.show.curves !== false;
  $('show-box').checked = state.show.box !== false;
  $('show-axes').checked = !!state.show.axes;
  $('keep-box').checked = !!state.keepBox;
  $('wireframe').checked = state.wire;
  $('occlusion').checked = !!state.occlusion;
  $('shadows').checked = !!state.shadows;
  $('clip-on').checked = state.clip.on;
  $('clip-axis').value = state.clip.axis;
  $('clip-flip').checked = state.clip.flip;
  $('clip-cap').checked = state.clip.cap !== false;
  syncClipSlider();
  syncFeatureKey();
  renderCurveList();
}

function syncClipSlider() {
  const k = AXIS_INDEX[state.clip.axis];
  const lo = state.box[k], hi = state.box[k + 3];
  const s = $('clip-offset');
  s.min = String(lo);
  s.max = String(hi);
  s.step = String(niceStep(lo, hi));
  s.value = String(state.clip.offset);
  s.disabled = !state.clip.on;
  $('clip-axis').disabled = !state.clip.on;
  $('clip-flip').disabled = !state.clip.on;
  $('clip-cap').disabled = !state.clip.on;
  $('clip-offset-value').textContent = state.clip.on ? `${state.clip.axis} = ${sig(state.clip.offset)}` : 'off';
}

const FEATURE_LABELS = { edges: 'singular curve segments', points: 'singular points', boundary: 'boundary edges' };
// The key's words for a point type or curve kind: one, and more than one ("1 double curve").
const TYPE_LABELS = {
  node: ['node', 'nodes'], isolated: ['isolated point', 'isolated points'], cusp: ['cusp', 'cusps'],
  degenerate: ['degenerate point', 'degenerate points'], pinch: ['pinch point', 'pinch points'],
  triple: ['triple point', 'triple points'], double: ['double curve', 'double curves'],
  whisker: ['whisker', 'whiskers'], section: ['section', 'sections'], level: ['level curve', 'level curves'],
  intersection: ['intersection', 'intersections'], silhouette: ['silhouette', 'silhouettes'],
  crease: ['crease', 'creases'], crossing: ['curve crossing', 'curve crossings'],
  branch: ['curve branch point', 'curve branch points'], end: ['curve end at the box', 'curve ends at the box'],
  loop: ['closed curve meeting nothing', 'closed curves meeting nothing'],
  double_curve: ['curve point on a double curve', 'curve points on a double curve'],
  singular_point: ['singular point on the curves', 'singular points on the curves'],
};
const typeLabel = (t, n) => (TYPE_LABELS[t] ? TYPE_LABELS[t][n === 1 ? 0 : 1] : t);
const hex = (c) => `#${c.toString(16).padStart(6, '0')}`;

// The feature key: counts per layer, the point types and curve kinds present (each with its
// colour), and the artefacts (mesh structure off the locus) when there are any.
function syncFeatureKey(counts, made) {
  const key = $('feature-key');
  for (const k of Object.keys(FEATURE_LABELS)) {
    const item = key.querySelector(`.key-${k}`);
    if (counts) {
      item.dataset.count = String(counts[k]);
      item.textContent = `${FEATURE_LABELS[k]} (${counts[k].toLocaleString('en-US')})`;
    }
    item.hidden = !state.show[k];
  }
  const art = key.querySelector('.key-artefacts');
  if (counts) {
    art.dataset.count = String(counts.artefacts || 0);
    art.textContent = `off the locus (${(counts.artefacts || 0).toLocaleString('en-US')})`;
    art.hidden = !counts.artefacts;
  }
  if (made) {
    const types = $('key-types');
    types.replaceChildren();
    const cuts = viewer.curves ? viewer.curves.kinds : {};
    const ends = viewer.curves ? viewer.curves.vertexTypes : {};
    const entries = [
      ...Object.entries(made.types).map(([t, n]) => [t, n, POINT_TYPE_COLORS[t]]),
      ...Object.entries(made.kinds).map(([t, n]) => [t, n, CURVE_KIND_COLORS[t]]),
      ...Object.entries(cuts).map(([t, n]) => [t, n, CUT_KIND_COLORS[t]]),
      ...Object.entries(ends).map(([t, n]) => [t, n, ARR_VERTEX_COLORS[t]]),
    ];
    for (const [t, n, color] of entries) {
      const span = document.createElement('span');
      span.className = `key-type-${t}`;
      span.dataset.count = String(n);
      span.style.setProperty('--swatch', hex(color ?? 0xffffff));
      span.textContent = `${n} ${typeLabel(t, n)}`;
      types.append(span);
    }
    const sheets = viewer.data && viewer.data.mesh && viewer.data.mesh.attributes.double_sheet;
    const flagged = sheets ? sheets.reduce((n, v) => n + (v ? 1 : 0), 0) : 0;
    key.querySelector('.key-sheets').hidden = !flagged;
    key.querySelector('.key-sheets').dataset.count = String(flagged);
  }
}

// How a singular point was certified (the method, the enclosure's radius, and for a cusp the
// perturbation it was proved under), or why it could not be.
function certificateText(p) {
  if (!p.certified)
    return ` (not certified${p.uncertified_reason ? ': ' + p.uncertified_reason : ''})`;
  const eps = p.perturbation ? `, |ε| ≤ ${sig(p.perturbation, 2)}` : '';
  return ` (certified${p.certificate ? ' by ' + p.certificate : ''} within ${sig(p.radius, 2)}${eps})`;
}

// The same for a singular curve: every point certified (the largest square's half-width), or
// how many points failed and the first of them with its residuals. An older server's JSON
// has no certified field: nothing is said.
function curveCertificateText(c) {
  if (c.certified === undefined) return '';
  if (c.certified) return ` (certified within ${sig(c.certificate_radius, 2)})`;
  const n = c.uncertified_points || 0;
  const first = c.first_uncertified;
  const at = first ? `, first at point ${first.index}: |f| ${sig(first.residual_f, 2)}, ` +
    `|∇f| ${sig(first.residual_grad, 2)}` : '';
  return ` (not certified: ${n} point${n === 1 ? '' : 's'} failed${at})`;
}

// Clicking near a singular point or curve says what it is.
function pickAt(e) {
  const info = $('pick-info');
  const r = $('view').getBoundingClientRect();
  const hit = viewer.pick(e.clientX - r.left, e.clientY - r.top);
  if (!hit) {
    pickSurfaceAt(e.clientX - r.left, e.clientY - r.top);
    return;
  }
  const xyz = hit.xyz.map((v) => sig(v, 7)).join(', ');
  if (hit.what === 'point') {
    const p = hit.p;
    const eig = (p.hessian_eigenvalues || []).map((v) => sig(v)).join(', ');
    info.textContent = `${p.type} point${certificateText(p)}\n(${xyz})\n` +
      `Hessian eigenvalues ${eig}; ${p.cones} cone${p.cones === 1 ? '' : 's'} of faces`;
  } else if (hit.what === 'cut') {
    const c = hit.p;
    const ends = c.closed ? 'closed' : `${(c.ends || []).length} ends on the box`;
    info.textContent = `${c.kind} curve (entry ${c.source + 1}, value ${c.index + 1}): length ${sig(c.length, 6)}, ` +
      `${c.arcs.length} arc${c.arcs.length === 1 ? '' : 's'}, ${ends}\nnear (${xyz})`;
    info.dataset.length = String(c.length);
  } else {
    const c = hit.p;
    const ends = c.closed ? 'closed' : (c.ends || []).map((e) => e.type).join(' – ');
    info.textContent = `${c.kind} curve${curveCertificateText(c)}, ${c.xyz.length / 3} points, ` +
      `${ends}\nnear (${xyz})`;
  }
  info.dataset.what = hit.what;
  info.dataset.xyz = hit.xyz.join(',');
  info.dataset.type = hit.what === 'point' ? hit.p.type : hit.p.kind;
  if (hit.what === 'point' || (hit.what === 'curve' && hit.p.certified !== undefined))
    info.dataset.certified = String(!!hit.p.certified);
  else delete info.dataset.certified;
  delete info.dataset.cell;
  delete info.dataset.probe;
  info.hidden = false;
  probeInto(info, hit.xyz, info.textContent + '\n');
}

let picks = 0;   // the newest pick: a probe answering an older one is dropped

// f, |grad f| and curvature at xyz (POST /v1/point: the server evaluates the same f) appended
// to the pick's text; data-probe holds the answer. Resolves true when it was shown, false when
// the probe failed (the pick's own facts stay), null when a newer pick came meanwhile.
async function probeInto(info, xyz, head) {
  const mine = ++picks;
  const body = currentBody();
  if (!body) return false;
  try {
    const p = await api.probePoint(body, xyz);
    if (mine !== picks) return null;
    const v = (n) => (n === null ? 'undefined' : sig(n, 4));
    info.textContent = head + `f = ${v(p.f)}, |∇f| = ${v(p.grad_norm)}, distance ≈ ${v(p.distance)}\n` +
      `H = ${v(p.mean_curvature)}, K = ${v(p.gauss_curvature)}`;
    info.dataset.probe = JSON.stringify(p);
    return true;
  } catch {
    return mine === picks ? false : null;
  }
}

// The arrangement cell of a picked triangle as text ('' when there are no cells).
function cellText(face, info) {
  const id = viewer.cellOf(face);
  const f = id === null ? null : cellFace(viewer.data.features, id);
  delete info.dataset.cell;
  if (!f) return '';
  info.dataset.cell = String(id);
  info.dataset.cellArea = String(f.area);
  info.dataset.cellEuler = String(f.euler);
  return `cell ${id}: area ${sig(f.area, 6)}, χ = ${f.euler}, ${f.boundary} boundary cycle${f.boundary === 1 ? '' : 's'}, ` +
    `${f.triangles.toLocaleString('en-US')} triangles\n`;
}

// Clicking the surface: the point, its triangle, and f, |grad f| and curvature there (asked
// of the server, which evaluates the same f: POST /v1/point).
async function pickSurfaceAt(x, y) {
  const info = $('pick-info');
  const hit = viewer.pickSurface(x, y);
  const body = currentBody();
  if (!hit || !body) {
    picks++;                       // a probe still on its way is for a pick no longer shown
    info.hidden = true;
    return;
  }
  const cell = cellText(hit.face, info);
  delete info.dataset.probe;
  if (cell) {                      // the cell's facts at once; f and curvature follow
    info.textContent = cell.trim();
    info.dataset.what = 'cell';
    info.dataset.type = 'cell';
    info.hidden = false;
  }
  const head = cell + `surface point (${hit.xyz.map((c) => sig(c, 7)).join(', ')}), triangle ${hit.face}\n`;
  const shown = await probeInto(info, hit.xyz, head);
  if (shown) {
    info.dataset.what = 'surface';
    info.dataset.type = 'surface';
    info.dataset.xyz = hit.xyz.join(',');
    info.hidden = false;
  } else if (shown === false) {
    info.hidden = !cell;
  }
}

function applyDisplay() {
  const legend = viewer.setColorMode(state.color);
  showLegend(state.color, legend);
  viewer.setVisibility(state.show);
  viewer.setWireframe(state.wire);
  viewer.setClip(state.clip);
  viewer.setOcclusion(!!state.occlusion);
  viewer.setShadows(!!state.shadows);
}

// The URL follows the state, at most once every URL_INTERVAL_MS (browsers refuse a flood of
// history updates while a slider or the camera is dragged); body[data-url-pending] says a
// write is due.
const URL_INTERVAL_MS = 150;
let urlTimer = 0;
let lastUrlWrite = -Infinity;

function updateUrl() {
  clearTimeout(urlTimer);
  const wait = URL_INTERVAL_MS - (performance.now() - lastUrlWrite);
  if (wait <= 0) {
    writeUrl();
  } else {
    document.body.dataset.urlPending = '1';
    urlTimer = setTimeout(writeUrl, wait);
  }
}

function writeUrl() {
  lastUrlWrite = performance.now();
  if (shownIdentity !== null) state.view = viewer.getView();
  history.replaceState(null, '', `#${encodeState(state, paramNames)}`);
  $('share-url').value = location.href;
  document.body.dataset.urlPending = '0';
}

// ---- computing ------------------------------------------------------------------------

function identity() {
  return `${state.preset || state.expr}|${state.box.join(',')}`;
}

function currentBody() {
  if (!exprOk) return null;
  return requestBody(state, paramNames);
}

// The request changed (slider, box, depth, preset, Compute). Cached results show at once;
// others wait for the debounce unless now. live (a slider moving): a coarse preview is asked
// for at once and the refined mesh once the slider has rested for the debounce.
function requestChanged({ now = false, live = false } = {}) {
  updateUrl();
  if (!exprOk) {
    message('Fix the expression first: nothing was sent.', 'error');
    return;
  }
  const body = currentBody();
  clearTimeout(debounceTimer);
  const turn = ++refineTurn;
  // The refined mesh once the slider has rested and the last preview is on screen: its
  // computation (or its full-resolution frame) would otherwise take the CPU the preview's
  // frame needs.
  const whenRested = (then) => {
    debounceTimer = setTimeout(async () => {
      await previewer.idle();
      await viewer.settled();
      if (turn === refineTurn) then();
    }, DEBOUNCE_MS);
  };
  const hit = loader.cached(body);
  if (hit) {
    stopRunning();
    // A mesh this page holds, met while the slider moves, is drawn like a preview (at once,
    // reduced when frames are slow); as the final mesh once the slider rests.
    show(hit, body, ticket(), live, false);
    if (live) {
      document.body.dataset.refinePending = '1';
      whenRested(() => {
        document.body.dataset.refinePending = '0';
        show(loader.cached(body) || hit, body, ticket());
      });
    }
    return;
  }
  if (live) {
    stopRunning();
    document.body.dataset.refinePending = '1';
    previewer.want(body);
    whenRested(() => compute(body));
    return;
  }
  previewer.stop();
  if (now) compute(body);
  else debounceTimer = setTimeout(() => compute(body), DEBOUNCE_MS);
}

// A typed expression gets its box fitted (POST /v1/box over FIT_CUBE) before it is computed,
// unless the user keeps the box; a fit is asked once per expression and parameters.
const FIT_CUBE = [-10, -10, -10, 10, 10, 10];
let fittedFor = null;

async function computeTyped() {
  if (!exprOk || state.preset || state.keepBox) {
    requestChanged({ now: true });
    return;
  }
  const body = requestBody({ ...state, box: FIT_CUBE }, paramNames);
  if (fittedFor !== body) {
    try {
      const fit = await api.fitBox(body);
      fittedFor = body;
      state.box = fit.empty ? FIT_CUBE.slice() : fit.box;
      document.body.dataset.fittedBox = JSON.stringify(state.box);
      syncControls();
    } catch (e) {
      failed(e, body);
      return;
    }
  }
  requestChanged({ now: true });
}

function stopRunning() {
  if (running) {
    running.controller.abort();
    running = null;
  }
  setBusy(false);
}

function clearRetry() {
  clearTimeout(retry.timer);
  retry.timer = 0;
}

async function compute(body) {
  stopRunning();
  clearRetry();
  if (retry.body !== body) retry = { timer: 0, count: 0, body };
  const controller = new AbortController();
  const mine = { controller, body };
  running = mine;
  const seq = ticket();
  document.body.dataset.refinePending = '0';
  setBusy(true);
  let shown = false;
  try {
    const result = await loader.load(body, controller.signal, setProgress);
    if (running !== mine) return;
    retry.count = 0;
    show(result, body, seq);
    shown = true;
  } catch (e) {
    if (running !== mine) return;
    if (e.name === 'AbortError') message('Canceled.');
    else failed(e, body);
  } finally {
    if (running === mine) {
      running = null;
      setBusy(false);
      if (shown) fetchColourData();
    }
  }
}

// The mesh on screen was asked for without an attribute the colour mode now draws (the page
// asks only for what it colours by: state.js COLOR_ATTRIBUTES): ask for the same surface
// with them — held in the page, or encoded by the server from its stored surface. Waits while
// a computation runs (its end calls again), so that a running polygonisation is not canceled.
function fetchColourData() {
  const m = viewer.data && viewer.data.mesh;
  if (running || !m || !shownBody || shownBody === currentBody()) return;
  if (COLOR_ATTRIBUTES[state.color].every((a) => m.attributes[a])) return;
  requestChanged({ now: true });
}

// f of a request body as GLSL for the clip cap (cap.js), or null when it cannot be written.
function surfaceGlsl(sent) {
  const preset = sent.preset ? presetByName(sent.preset) : null;
  const source = sent.expr ?? (preset ? presetSource(preset) : null);
  if (source === null) return null;
  const defaults = preset ? Object.fromEntries(preset.params.map((q) => [q.name, q.default])) : {};
  const check = checkExpression(source, { ...defaults, ...(sent.params || {}) });
  return check.ok ? check.glsl : null;
}

// Draws result unless something newer (by sequence number seq, live.js) is on screen.
// preview: drawn while a slider moves (stats and downloads stay with the refined mesh);
// coarse: a live preview's coarse mesh (false for a held refined mesh met during a drag).
function show(result, body, seq, preview = false, coarse = preview) {
  if (!claim(seq)) return;
  shownBody = body;
  clearMessage();
  if (!result.mesh) message('The surface does not cross this box: the mesh is empty.');
  const sent = JSON.parse(body);
  viewer.setMesh(result, sent.box, surfaceGlsl(sent), preview);
  if (result.timing) {
    result.timing.key = result.key;
    result.timing.preview = preview;
    timeline.shown(result.timing);
  }
  const id = identity();
  const refit = id !== shownIdentity;
  shownIdentity = id;
  if (pendingView) {
    viewer.setView(pendingView);
    pendingView = null;
  } else if (refit) {
    viewer.fit();
  }
  applyDisplay();
  syncFeatureKey(viewer.features ? viewer.features.counts : { edges: 0, points: 0, boundary: 0, artefacts: 0 }, viewer.features);
  $('pick-info').hidden = true;
  showCurveFacts(result);
  document.body.dataset.shown = preview ? 'preview' : 'final';
  if (preview) {
    viewer.drawNow();
    previews++;
    document.body.dataset.previews = String(previews);
    if (coarse) document.body.dataset.previewKey = result.key;
    return;
  }
  showStats(result);
  setDownloads(result, body);
  if (exprOk) showExprError(null);
  loads++;
  updateUrl();
  document.body.dataset.meshKey = result.key;
  document.body.dataset.loads = String(loads);
}

function failed(e, body) {
  if (!(e instanceof api.ApiError)) {
    message(`Could not show the mesh: ${e.message}`, 'error');
    return;
  }
  if (e.status === 401) {
    afterToken = body;
    askToken('This server needs an access token to compute meshes.');
    message('An access token is needed.', 'error', { label: 'Enter token', run: () => askToken() });
    return;
  }
  if ((e.status === 400 || e.status === 422) && e.column && /^\$\.(expr|let)/.test(e.path)) {
    const msg = e.message.replace(/^\$\.[^:]*: (line \d+, )?column \d+: /, '');
    showExprError({ line: e.line || 1, column: e.column, message: msg }, true);
    message('The server did not accept the expression (see the editor).', 'error');
    return;
  }
  if (e.status === 400 && /^\$\.curves/.test(e.path || '')) {
    showCurveError(e.message);
    message('The server did not accept a curve (see the Curves panel).', 'error');
    return;
  }
  if (e.status === 422) {
    message(`Over a limit: ${e.message}`, 'error');
    return;
  }
  if (e.status === 503 || e.status === 429) {
    const wait = e.retryAfter || 5;
    const what = e.status === 503 ? 'The server is busy' : 'You have too many computations running';
    if (retry.count < MAX_AUTO_RETRIES) {
      retry.count++;
      countdown(`${what} (${e.message}).`, wait, body);
    } else {
      message(`${what} (${e.message}). Try again in ${wait} s.`, 'error', { label: 'Retry', run: () => compute(body) });
    }
    return;
  }
  if (e.status === 0) {
    message('The server cannot be reached.', 'error', { label: 'Retry', run: () => compute(body) });
    return;
  }
  if (e.status === 504) { // the job's deadline: say which knobs make a lighter mesh
    message(`Took too long: ${e.message}. A smaller depth max, a larger max error or a smaller box makes a lighter mesh.`, 'error');
    return;
  }
  message(`The server answered ${e.status}: ${e.message}`, 'error');
}

function countdown(text, seconds, body) {
  let left = seconds;
  const tick = () => {
    if (left <= 0) {
      compute(body);
      return;
    }
    message(`${text} Retrying in ${left} s…`, 'error', { label: 'Retry now', run: () => { clearRetry(); compute(body); } });
    left--;
    retry.timer = setTimeout(tick, 1000);
  };
  tick();
}

// ---- the Curves panel -----------------------------------------------------------------

function showCurveError(text) {
  $('curve-error').textContent = text || '';
  $('curve-error').hidden = !text;
}

function renderCurveList() {
  const list = $('curve-list');
  list.replaceChildren();
  const kindOf = { plane: 'section', levels: 'level', surface: 'intersection', silhouette: 'silhouette' };
  state.curves.forEach((e, i) => {
    const li = document.createElement('li');
    li.style.setProperty('--swatch', hex(CUT_KIND_COLORS[kindOf[e.kind]] ?? 0xffffff));
    const label = document.createElement('span');
    label.textContent = describeCurve(e);
    const remove = document.createElement('button');
    remove.type = 'button';
    remove.textContent = '×';
    remove.title = 'Remove these curves';
    remove.setAttribute('aria-label', `Remove ${describeCurve(e)}`);
    remove.addEventListener('click', () => {
      state.curves.splice(i, 1);
      curvesChanged();
    });
    li.append(label, remove);
    list.append(li);
  });
  $('curve-add').disabled = state.curves.length >= MAX_CURVE_REQUESTS;
}

function curvesChanged() {
  showCurveError('');
  renderCurveList();
  requestChanged({ now: true });
}

// A g typed in the panel: its syntax checked here (the server checks it again, with the
// request's parameters). Returns the error text or ''.
function gProblem(text) {
  if (!text.trim()) return 'type an expression g(x, y, z)';
  const check = checkExpression(text, state.params);
  return check.ok ? '' : `g: column ${check.column}: ${check.message}`;
}

// The entry the panel's fields describe, or {error}.
function entryFromPanel() {
  const kind = $('curve-kind').value;
  if (kind === 'plane') {
    const axis = $('curve-axis').value === 'custom' ? $('curve-normal').value.trim() : $('curve-axis').value;
    const e = { kind, axis, count: Number($('curve-count').value) };
    return curveRequest(e, state.box) ? e : { error: 'the normal needs three numbers, not all 0, and 1 to 64 planes' };
  }
  if (kind === 'levels') {
    const e = { kind, expr: $('curve-level-expr').value.trim(), values: $('curve-level-values').value.trim() };
    const bad = gProblem(e.expr);
    if (bad) return { error: bad };
    return curveRequest(e, state.box) ? e : { error: 'values: 1 to 64 numbers, separated by commas' };
  }
  if (kind === 'surface') {
    const e = { kind, expr: $('curve-surface-expr').value.trim() };
    const bad = gProblem(e.expr);
    return bad ? { error: bad } : e;
  }
  const v = viewer.getView();    // the silhouette seen from here: along the view direction
  const d = v.pos.map((p, k) => p - v.target[k]);
  const len = Math.hypot(...d) || 1;
  return { kind: 'silhouette', direction: d.map((x) => Number((x / len).toPrecision(6))) };
}

function wireCurves() {
  const forms = { plane: 'curve-plane', levels: 'curve-levels', surface: 'curve-surface' };
  $('curve-kind').addEventListener('change', () => {
    for (const [k, id] of Object.entries(forms)) $(id).hidden = $('curve-kind').value !== k;
    showCurveError('');
  });
  $('curve-axis').addEventListener('change', () => { $('curve-normal').hidden = $('curve-axis').value !== 'custom'; });
  $('curve-add').addEventListener('click', () => {
    const e = entryFromPanel();
    if (e.error) {
      showCurveError(e.error);
      return;
    }
    if (state.curves.length >= MAX_CURVE_REQUESTS) return;
    state.curves.push(e);
    curvesChanged();
  });
}

// "1 vertex", "2 vertices".
const count = (n, one, many) => `${n} ${n === 1 ? one : many}`;

// What the panel says under the list: curves drawn, cells, the Euler check.
function showCurveFacts(result) {
  const f = result.features || {};
  const drawn = viewer.curves ? viewer.curves.count : 0;
  const a = f.arrangement;
  document.body.dataset.curvesDrawn = String(drawn);
  document.body.dataset.cells = String(a ? a.faces.length : 0);
  $('curve-facts').textContent = a
    ? `${count(drawn, 'curve', 'curves')} drawn; ${count(a.faces.length, 'cell', 'cells')}, ` +
      `${count(a.vertices.length, 'vertex', 'vertices')}, ${count(a.edges.length, 'edge', 'edges')}; ` +
      (a.euler.ok ? `V − E + F = χ = ${a.euler.mesh}` : `V − E + F = ${a.euler.arrangement} but χ = ${a.euler.mesh}: the check failed`) +
      '. Colour the cells with Display ▸ Colour; click a cell or a curve for its facts.'
    : '';
}

// ---- downloads ------------------------------------------------------------------------

// Downloads carry every attribute, though the view asks only for those it colours by: the
// links point at the mesh on screen when it has them all; else the first click asks the
// server for the same surface with every attribute (POST /v1/mesh?format=json: its key,
// encoded from the stored surface) and points the links there. downloads.pending: that
// request, while not yet asked.
let downloads = { key: null, pending: null };

function setDownloads(result, body) {
  const { surface, attributes } = loader.splitBody(body);
  const complete = loader.ALL_ATTRIBUTES.every((a) => attributes.includes(a));
  downloads = {
    key: result.mesh ? result.key : null,
    pending: result.mesh && !complete ? loader.withAttributes(surface, loader.ALL_ATTRIBUTES) : null,
  };
  linkDownloads(downloads.key);
}

function linkDownloads(key) {
  const base = state.preset || 'surface';
  for (const a of document.querySelectorAll('#downloads a')) {
    const fmt = a.dataset.format;
    if (!key) {
      a.removeAttribute('href');
      a.setAttribute('aria-disabled', 'true');
      continue;
    }
    a.href = `/v1/meshes/${key}.${fmt}`;
    a.download = `${base}-${key.slice(0, 8)}.${fmt}`;
    a.setAttribute('aria-disabled', 'false');
  }
}

async function download(event) {
  const a = event.target.closest('a[data-format]');
  if (!a || !a.href) return;
  if (downloads.pending) {
    event.preventDefault();
    const mine = downloads;
    try {
      const links = await api.meshLinks(mine.pending);
      if (downloads !== mine) return;       // another mesh came meanwhile
      downloads = { key: links.key, pending: null };
      linkDownloads(links.key);
      a.click();
    } catch (e) {
      failed(e, null);
    }
    return;
  }
  if (api.token.get()) downloadWithToken(event, a);
}

// With a token set, a plain link would go without it: fetch with the header instead.
async function downloadWithToken(event, a) {
  event.preventDefault();
  try {
    const { bytes } = await api.getBytes(a.getAttribute('href'));
    const url = URL.createObjectURL(new Blob([bytes]));
    const tmp = document.createElement('a');
    tmp.href = url;
    tmp.download = a.download;
    document.body.append(tmp);
    tmp.click();
    tmp.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
  } catch (e) {
    failed(e, null);
  }
}

// The view as a PNG of the size asked for (viewer.exportPng), downloaded.
async function savePng() {
  const blob = await viewer.exportPng(Number($('png-width').value) || 1920, Number($('png-height').value) || 1080);
  const url = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = url;
  a.download = `${state.preset || 'surface'}.png`;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

// ---- token ----------------------------------------------------------------------------

function askToken(why) {
  const dlg = $('token-dialog');
  $('token-why').textContent = why || 'Set the bearer token sent with compute requests, or forget the stored one.';
  $('token-input').value = api.token.get();
  if (!dlg.open) dlg.showModal();
}

function tokenClosed() {
  const dlg = $('token-dialog');
  if (dlg.returnValue === 'save') api.token.set($('token-input').value.trim());
  else if (dlg.returnValue === 'clear') api.token.set('');
  $('token-input').value = '';
  if (beginAfterToken && dlg.returnValue === 'save') {
    beginAfterToken = false;
    clearMessage();
    begin();
    return;
  }
  if (afterToken && dlg.returnValue === 'save') {
    const body = afterToken;
    afterToken = null;
    compute(body);
  }
}

// ---- URL state ------------------------------------------------------------------------

function applyFragment(fragment) {
  const s = decodeState(fragment || '');
  const fresh = defaultState();
  state = fresh;
  ranges = {};
  paramNames = [];
  let note = '';
  if (s.preset && presetByName(s.preset)) {
    usePreset(s.preset);
  } else if (s.expr !== undefined) {
    state.preset = null;
    state.expr = s.expr;
  } else {
    if (s.preset) note = `Unknown preset '${s.preset}': showing ${DEFAULT_PRESET}.`;
    if (!usePreset(DEFAULT_PRESET) && presets.length) usePreset(presets[0].name);
  }
  if (s.params) {
    for (const [k, v] of Object.entries(s.params)) {
      state.params[k] = v;
      if (ranges[k]) ranges[k] = [Math.min(ranges[k][0], v), Math.max(ranges[k][1], v)];
    }
  }
  for (const k of ['box', 'depth', 'maxError', 'quality', 'mesher', 'simplify', 'color', 'clip', 'show', 'wire', 'occlusion', 'shadows', 'curves']) if (s[k] !== undefined) state[k] = s[k];
  pendingView = s.view || null;
  state.view = s.view || null;
  shownIdentity = null;
  basePreset = state.preset;
  if (s.problems.length) note += ` Ignored unreadable link parts: ${s.problems.join(', ')}.`;
  $('expr').value = state.expr;
  refreshExpression();
  renderSliders();
  syncControls();
  applyDisplay();
  if (note.trim()) message(note.trim(), 'error');
  requestChanged({ now: true });
}

// ---- events ---------------------------------------------------------------------------

function readBox() {
  const v = BOX_IDS.map((id) => Number($(id).value));
  let ok = true;
  BOX_IDS.forEach((id, i) => {
    const bad = $(id).value.trim() === '' || !Number.isFinite(v[i]) || (i < 3 ? v[i] >= v[i + 3] : v[i] <= v[i - 3]);
    $(id).toggleAttribute('aria-invalid', bad);
    if (bad) ok = false;
  });
  return ok ? v : null;
}

function wire() {
  $('preset').addEventListener('change', () => {
    const name = $('preset').value;
    if (!name) {
      state.preset = null;
      showPresetChoice();
      return;
    }
    usePreset(name);
    basePreset = name;
    refreshExpression();
    renderSliders();
    syncControls();
    requestChanged({ now: true });
  });

  $('gallery-search').addEventListener('input', filterGallery);
  $('gallery-pictures').addEventListener('toggle', () => gallery.watch($('gallery-pictures').open));
  $('gallery-search').addEventListener('keydown', (e) => {
    // Enter picks the first surface the search keeps.
    if (e.key !== 'Enter') return;
    const first = [...$('preset').options].find((o) => o.value && !o.hidden);
    if (!first || first.value === state.preset) return;
    $('preset').value = first.value;
    $('preset').dispatchEvent(new Event('change'));
  });
  $('expr').addEventListener('input', () => {
    state.expr = $('expr').value;
    const p = presetByName(basePreset);
    state.preset = p && presetSource(p) === state.expr ? p.name : null;
    showPresetChoice();
    refreshExpression();
    updateUrl();
  });
  $('expr').addEventListener('keydown', (e) => {
    if (e.key === 'Enter' && (e.ctrlKey || e.metaKey)) {
      e.preventDefault();
      computeTyped();
    }
  });
  $('render').addEventListener('click', () => computeTyped());
  $('keep-box').addEventListener('change', () => { state.keepBox = $('keep-box').checked; });

  for (const id of BOX_IDS) {
    $(id).addEventListener('change', () => {
      const box = readBox();
      if (!box) {
        message('Each min must be below its max.', 'error');
        return;
      }
      state.box = box;
      state.keepBox = true;       // a box typed by hand is kept
      $('keep-box').checked = true;
      showBound();                // the default bound follows the box
      syncClipSlider();
      requestChanged();
    });
  }
  for (const id of ['depth-min', 'depth-max']) {
    $(id).addEventListener('change', () => {
      const min = Number($('depth-min').value), max = Number($('depth-max').value);
      if (!Number.isInteger(min) || !Number.isInteger(max)) return;
      state.depth = { min, max };
      requestChanged();
    });
  }
  $('max-error').addEventListener('change', () => {
    const text = $('max-error').value.trim(), off = text.toLowerCase() === 'off', e = Number(text);
    if (text !== '' && !off && !(e > 0 && Number.isFinite(e))) {
      $('max-error').setAttribute('aria-invalid', 'true');
      message('Max error must be a positive distance, off (the depth decides) or empty (the default).', 'error');
      return;
    }
    $('max-error').removeAttribute('aria-invalid');
    state.maxError = text === '' ? null : off ? 'off' : e;
    if (off) $('max-error').value = 'off';
    showBound();
    requestChanged();
  });
  $('mesher').addEventListener('change', () => {
    state.mesher = $('mesher').value;
    requestChanged();
  });
  $('simplify').addEventListener('change', () => {
    state.simplify = $('simplify').checked;
    requestChanged();
  });
  $('quality-good').addEventListener('change', () => {
    state.quality = $('quality-good').checked ? 'good' : 'raw';
    requestChanged();
  });
  $('reset-box').addEventListener('click', () => {
    const p = presetByName(state.preset);
    if (!p) return;
    state.box = p.box.slice();
    state.depth = { ...p.depth };
    syncControls();
    requestChanged({ now: true });
  });

  $('color-mode').addEventListener('change', () => {
    state.color = COLOR_MODES.includes($('color-mode').value) ? $('color-mode').value : 'shaded';
    $('color-range').value = viewer.rangeCutOf(state.color);   // each map keeps its own range
    showLegend(state.color, viewer.setColorMode(state.color));
    updateUrl();
    fetchColourData();
  });
  for (const k of ['edges', 'points', 'boundary', 'box', 'axes', 'curves']) {
    $(`show-${k}`).addEventListener('change', () => {
      state.show[k] = $(`show-${k}`).checked;
      viewer.setVisibility(state.show);
      syncFeatureKey();
      updateUrl();
    });
  }
  wireCurves();
  $('two-sided').addEventListener('change', () => viewer.setTwoSided($('two-sided').checked));
  $('occlusion').addEventListener('change', () => {
    state.occlusion = $('occlusion').checked;
    updateUrl();
    viewer.setOcclusion(state.occlusion);
  });
  $('shadows').addEventListener('change', () => {
    state.shadows = $('shadows').checked;
    updateUrl();
    viewer.setShadows(state.shadows);
  });
  $('color-range').addEventListener('change', () => showLegend(state.color, viewer.setRangeCut($('color-range').value)));
  $('wireframe').addEventListener('change', () => {
    state.wire = $('wireframe').checked;
    viewer.setWireframe(state.wire);
    updateUrl();
  });
  const clipChanged = () => {
    viewer.setClip(state.clip);
    syncClipSlider();
    updateUrl();
  };
  // A new cut removes the half nearer the camera, so that it opens the surface towards you.
  const cutAway = () => {
    const k = AXIS_INDEX[state.clip.axis];
    state.clip.flip = viewer.camera.position.getComponent(k) < state.clip.offset;
  };
  $('clip-on').addEventListener('change', () => {
    state.clip.on = $('clip-on').checked;
    const k = AXIS_INDEX[state.clip.axis];
    if (state.clip.on && (state.clip.offset < state.box[k] || state.clip.offset > state.box[k + 3])) {
      state.clip.offset = (state.box[k] + state.box[k + 3]) / 2;
    }
    if (state.clip.on) cutAway();
    $('clip-flip').checked = state.clip.flip;
    clipChanged();
  });
  $('clip-axis').addEventListener('change', () => {
    state.clip.axis = $('clip-axis').value;
    const k = AXIS_INDEX[state.clip.axis];
    state.clip.offset = (state.box[k] + state.box[k + 3]) / 2;
    cutAway();
    $('clip-flip').checked = state.clip.flip;
    clipChanged();
  });
  $('clip-cap').addEventListener('change', () => {
    state.clip.cap = $('clip-cap').checked;
    clipChanged();
  });
  $('clip-flip').addEventListener('change', () => {
    state.clip.flip = $('clip-flip').checked;
    clipChanged();
  });
  $('clip-offset').addEventListener('input', () => {
    state.clip.offset = Number($('clip-offset').value);
    clipChanged();
  });
  $('fit').addEventListener('click', () => viewer.fit());

  $('cancel').addEventListener('click', () => {
    clearTimeout(debounceTimer);
    refineTurn++;
    previewer.stop();
    stopRunning();
    message('Canceled.');
  });
  document.addEventListener('keydown', (e) => {
    if (e.key === 'Escape' && running && !$('token-dialog').open) {
      stopRunning();
      message('Canceled.');
    }
  });

  $('copy-link').addEventListener('click', async () => {
    updateUrl();
    try {
      await navigator.clipboard.writeText(location.href);
      message('Link copied.');
    } catch {
      $('share-url').focus();
      $('share-url').select();
      message('Copy the selected link (Ctrl+C).');
    }
  });
  $('share-url').addEventListener('focus', () => $('share-url').select());
  $('png-export').addEventListener('click', savePng);
  $('token-button').addEventListener('click', () => askToken());
  $('token-dialog').addEventListener('close', tokenClosed);
  $('downloads').addEventListener('click', download);

  window.addEventListener('hashchange', () => applyFragment(location.hash));
  performance.setResourceTimingBufferSize(1000);
  performance.addEventListener('resourcetimingbufferfull', () => performance.clearResourceTimings());
}

// The render mode's occlusion is computed in the background (seconds in software GL for a
// large mesh; the page stays usable and shows the plain surface meanwhile): say so.
const OCCLUSION_NOTE = 'Computing the ambient occlusion…';
function occlusionStatus(computing) {
  if (computing && $('message').hidden) message(OCCLUSION_NOTE);
  else if (!computing && $('message').textContent === OCCLUSION_NOTE) clearMessage();
}

// A private server (isomeshd --private) refuses even the presets without a token: ask for it
// first, and begin once it is given.
let beginAfterToken = false;

async function begin() {
  try {
    presets = await api.getPresets();
  } catch (e) {
    presets = [];
    if (e.status === 401) {
      beginAfterToken = true;
      askToken('This server is private: it needs an access token.');
      message('An access token is needed.', 'error', { label: 'Enter token', run: () => askToken() });
      return;
    }
    message(`The presets could not be loaded: ${e.message}`, 'error');
  }
  fillPresetMenu();
  applyFragment(location.hash);
  document.body.dataset.ready = '1';
}

async function start() {
  viewer = new Viewer($('view'));
  window.isomeshViewer = viewer;   // for the console and the browser tests
  previewer = new Previewer({
    load: (body, signal) => loader.load(body, signal, () => {}),
    cached: (body) => loader.cached(body),
    show: (result, body, seq) => show(result, body, seq, true),
    failed: () => {},   // the refined request reports errors
    settled: () => viewer.settled(),
  });
  $('view').addEventListener('click', pickAt);
  viewer.onViewChange = updateUrl;
  viewer.onOcclusion = occlusionStatus;
  wire();
  clearStats();
  await begin();
}

start();
