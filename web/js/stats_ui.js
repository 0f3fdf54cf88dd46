// stats_ui.js — the stats panel (from the stats JSON of proto/stats.h plus what this page
// measured: cache, bytes transferred) and the curvature legend. Every value cell also carries
// its raw number in data-value.
import * as fmt from './format.js';
import { cssGradient, valueAt } from './colormap.js';

function cell(name) {
  return document.querySelector(`#stats [data-stat="${name}"]`);
}

function put(name, text, raw) {
  const c = cell(name);
  if (!c) return;
  c.textContent = text;
  if (raw === undefined || raw === null) delete c.dataset.value;
  else c.dataset.value = String(raw);
}

// The smallest-angle histogram as a row of bars (heights relative to the fullest bin); the
// counts travel in data-value as a JSON list.
function showHistogram(hist) {
  const c = cell('angle_hist');
  if (!c) return;
  c.textContent = '';
  if (!Array.isArray(hist) || !hist.length) {
    c.textContent = '–';
    delete c.dataset.value;
    return;
  }
  c.dataset.value = JSON.stringify(hist);
  const top = Math.max(1, ...hist);
  hist.forEach((n, i) => {
    const bar = document.createElement('span');
    bar.className = 'bar';
    bar.style.height = `${Math.round(100 * n / top)}%`;
    bar.title = `${5 * i}–${5 * i + 5}°: ${n.toLocaleString('en-US')} triangles`;
    c.append(bar);
  });
}

export function clearStats() {
  for (const c of document.querySelectorAll('#stats dd')) {
    c.textContent = '–';
    delete c.dataset.value;
  }
  document.getElementById('warnings').textContent = '';
}

// Why the dual mesher did not make the mesh: a few words for the cell (short enough for one
// line of the panel: tests/browser/viewer.test.mjs) and a sentence for its tooltip (the
// reasons' table: core/octree/mesher.h, proto/openapi.yaml).
export const DUAL_DECLINED = {
  no_bound: ['no max error', 'no max error: the dual cells are sized by it'],
  off: ['dual off', 'asked for the primal polygons'],
  singular_locus: ['singular locus', 'singular points or curves: the primal polygons conform to them'],
  min_max: ['min/max in f', 'min/max/abs in f: creases, which one vertex per cell would round'],
  box_cut: ['box cuts surface', 'the surface meets the box: it is open there'],
  not_plain: ['not one sheet', 'a cell at depth max holds more than one sheet (close sheets or a singular point)'],
  error_at_max_depth: ['error at depth max', 'a triangle beyond the max error with its cells at depth max'],
  open_edge: ['open edge', 'a crossed edge without its cells\' vertices'],
  point_type: ['point not a node', 'a singular point that is not a certified node or isolated point (a cusp …)'],
  point_fan: ['no fan at a node', 'no two rim loops round a node, or its fan beyond the max error'],
};

// Why not the dual mesher, in words ('–' when it made the mesh or was not asked about), and
// the cell's tooltip; a row of its own, so the mesher's name stays one short line.
function showDeclined(why) {
  const words = why ? (DUAL_DECLINED[why] || [why.replace(/_/g, ' '), why]) : ['–', ''];
  put('dual_declined', words[0], why);
  const c = cell('dual_declined');
  if (c) c.title = words[1];
}

// result: loader.js's result.
export function showStats(result) {
  const s = result.stats || {};
  const mesh = s.mesh || {};
  const an = s.analysis || {};
  const q = an.quality || {};
  const acc = an.accuracy || {};
  const t = s.timings_ms || {};
  put('triangles', fmt.count(mesh.triangles), mesh.triangles);
  put('vertices', fmt.count(mesh.vertices), mesh.vertices);
  put('euler', Number.isFinite(an.euler) ? String(an.euler) : '–', an.euler);
  put('components', fmt.count(an.components), an.components);
  put('nonmanifold_edges', fmt.count(an.nonmanifold_edges), an.nonmanifold_edges);
  put('nonmanifold_points', fmt.count(an.nonmanifold_points), an.nonmanifold_points);
  put('nonmanifold_curves', fmt.count(an.nonmanifold_curves), an.nonmanifold_curves);
  put('boundary_edges', fmt.count(an.boundary_edges), an.boundary_edges);
  put('min_angle', Number.isFinite(q.min_angle) ? `${fmt.sig(q.min_angle)}°` : '–', q.min_angle);
  put('share_under_10', Number.isFinite(q.share_under_10) ? `${fmt.sig(100 * q.share_under_10)} %` : '–',
      q.share_under_10);
  showHistogram(q.angle_hist);
  put('aspect', Number.isFinite(q.aspect_max) ? `${fmt.sig(q.aspect_max)}, ${fmt.sig(q.aspect_p99)}` : '–',
      Number.isFinite(q.aspect_max) ? q.aspect_max : null);
  const rm = s.remesh;
  put('remesh', rm ? `${fmt.sig(rm.min_angle_before)}° → ${fmt.sig(rm.min_angle_after)}°` : 'off',
      rm ? rm.min_angle_after : null);
  put('remesh_edits', rm ? `${fmt.count(rm.flips)}, ${fmt.count(rm.moves)}` : '–',
      rm ? rm.flips + rm.moves : null);
  put('max_dist', fmt.sig(acc.max_dist_vertex), acc.max_dist_vertex);
  const between = Math.max(acc.max_dist_midpoint, acc.max_dist_centroid);
  const p99 = Math.max(acc.p99_dist_midpoint, acc.p99_dist_centroid);
  put('max_dist_between', Number.isFinite(between) ? `${fmt.sig(between)}, ${fmt.sig(p99)}` : '–',
      Number.isFinite(between) ? between : null);
  const met = acc.met === true ? ' (met)' : acc.met === false ? ' (not met)' : '';
  put('max_error', acc.max_error > 0 ? `${fmt.sig(acc.max_error)}${met}` : 'off', acc.max_error);
  const poly = s.polygoniser || {};
  put('mesher', poly.mesher || '–', poly.mesher);
  showDeclined(poly.dual_declined);
  put('compute_ms', fmt.ms(t.total), t.total);
  const cache = result.viewerCache ? 'this page' : `server ${result.serverCache}`; // page: no request
  put('cache', cache, result.viewerCache ? 'viewer' : result.serverCache);
  put('bytes', fmt.bytes(result.transferred), result.transferred);
  put('draco_bytes', fmt.bytes(result.drcBytes), result.drcBytes);
  const list = document.getElementById('warnings');
  list.textContent = '';
  for (const w of s.warnings || []) {
    const li = document.createElement('li');
    li.textContent = w;
    list.append(li);
  }
}

const TITLES = { mean: 'Mean curvature H', gauss: 'Gaussian curvature K' };

// range: colormap.curvatureRange's result, or null to hide the legend.
export function showLegend(mode, range) {
  const legend = document.getElementById('legend');
  if (!range || !TITLES[mode]) {
    legend.hidden = true;
    return;
  }
  legend.hidden = false;
  legend.dataset.mode = mode;
  legend.dataset.min = String(range.min);
  legend.dataset.max = String(range.max);
  legend.dataset.lo = String(range.lo);
  legend.dataset.hi = String(range.hi);
  document.getElementById('legend-title').textContent = TITLES[mode];
  document.getElementById('legend-bar').style.background = cssGradient(range);
  document.getElementById('legend-min').textContent = fmt.sig(valueAt(range, 0));
  document.getElementById('legend-mid').textContent = fmt.sig(valueAt(range, 0.5));
  document.getElementById('legend-max').textContent = fmt.sig(valueAt(range, 1));
  legend.dataset.scale = range.scale;
  const sym = mode === 'mean' ? 'H' : 'K';
  const scale = { linear: 'linear scale', log: 'logarithmic scale', symlog: `symmetric log scale (linear within ±${fmt.sig(range.s)})` }[range.scale];
  let note = `${scale}; ${sym} from ${fmt.sig(range.min)} to ${fmt.sig(range.max)}`;
  if (range.clamped) note += `; ${range.clamped.toLocaleString('en-US')} vertices beyond the bar take its end colours`;
  if (range.nonfinite) note += `; ${range.nonfinite} vertices undefined (grey)`;
  document.getElementById('legend-note').textContent = note;
}
