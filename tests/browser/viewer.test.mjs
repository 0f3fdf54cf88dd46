// viewer.test.mjs — the isomesh viewer end to end: a real isomeshd (its own port and cache
// directory) and headless Chromium. Load the page, pick the Kummer surface, check the canvas
// really shows a surface, the stats panel against the stats endpoint, its 16 nodes picked
// (type and closed-form coordinates within 1e-6), a slider that computes a
// new mesh and comes back from the page's cache, expression errors at their column (the
// viewer's own check and the server's), curvature colours against the decoded attributes,
// the clipping plane, each download, a shared link, keyboard access, a narrow screen, and
// screenshots of the paper's four surfaces under tests/artifacts/.
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import { startDaemon, stopDaemon, startBrowser, stopBrowser, watchErrors, artifact } from './lib/harness.mjs';
import { waitForMesh, loads, openViewer, jobPosts, statsPanel, viewShot, settledHref, wrappedStats } from './lib/page.mjs';
import { pixelStats, changedShare } from './lib/png.mjs';
import { decodeDraco, ATTRIBUTE_IDS } from './lib/draco.mjs';
import { pickSingularPoints, nearest } from './lib/pick.mjs';
import { checkExpression } from '../../web/js/expr.js';

const require = createRequire(import.meta.url);
const gltfValidator = require('gltf-validator');

let daemon = null;
let browser = null;
let page = null;
let requests = [];
let errors = [];

async function api(path, init) {
  const r = await fetch(daemon.base + path, init);
  return r;
}

async function getJSON(path) {
  const r = await api(path);
  assert.equal(r.status, 200, `${path}: HTTP ${r.status}`);
  return r.json();
}

async function meshKey() {
  return page.evaluate(() => document.body.dataset.meshKey);
}

function assertRendered(img, what) {
  const s = pixelStats(img);
  assert.ok(s.foreground > 0.04, `${what}: only ${(100 * s.foreground).toFixed(1)}% of the view differs from the background`);
  assert.ok(s.distinct > 40, `${what}: only ${s.distinct} distinct colours (flat or blank canvas)`);
  assert.ok(s.lumaStd > 8, `${what}: luminance spread ${s.lumaStd.toFixed(1)} (no shading)`);
  return s;
}

// CAP_RGB of web/js/cap.js as the canvas shows it (sRGB)
const CAP_RGB = [0xc9, 0x8a, 0x5a];

async function choosePreset(name) {
  const before = await loads(page);
  await page.selectOption('#preset', name);
  return waitForMesh(page, before);
}

function finiteRange(values) {
  let min = Infinity, max = -Infinity;
  for (const v of values) if (Number.isFinite(v)) { min = Math.min(min, v); max = Math.max(max, v); }
  return [min, max];
}

// A hang guard, not a speed test: 171 s idle; at a load of 32 on 2 cores (8 sessions building
// and testing) the suite ran 653 s, so the guard allows 20 minutes.
describe('isomesh viewer', { timeout: 1200000 }, () => {
  before(async () => {
    daemon = await startDaemon();
    browser = await startBrowser();
    ({ page, requests, errors } = await openViewer(browser.context, daemon.base + '/'));
  });

  after(async () => {
    try {
      await stopBrowser(browser);
    } finally {
      await stopDaemon(daemon);
    }
  });

  it('loads everything from the daemon itself (three.js under /vendor, no CDN)', async () => {
    const origins = new Set(requests.map((r) => new URL(r.url).origin));
    assert.deepEqual([...origins], [daemon.base]);
    const paths = requests.map((r) => new URL(r.url).pathname);
    assert.ok(paths.includes('/vendor/three/build/three.module.js'));
    assert.ok(paths.includes('/vendor/three/examples/jsm/controls/OrbitControls.js'));
    assert.ok(paths.includes('/vendor/three/examples/jsm/libs/draco/draco_decoder.wasm'));
    const map = await page.evaluate(() => JSON.parse(document.querySelector('script[type=importmap]').textContent));
    assert.equal(map.imports.three, '/vendor/three/build/three.module.js');
    const presets = await getJSON('/v1/presets');
    const options = await page.$$eval('#preset option', (os) => os.map((o) => [o.value, o.title]));
    for (const p of presets.presets) assert.ok(options.some(([v, t]) => v === p.name && t === p.about), `preset ${p.name} listed with its description`);
  });

  it('renders the Kummer surface on the canvas', async () => {
    const key = await choosePreset('kummer-16-nodes');
    assert.match(key, /^[0-9a-f]{64}$/);
    const img = await viewShot(page, 'kummer-16-nodes.png');
    assertRendered(img, 'Kummer surface');
    const about = await page.textContent('#preset-about');
    assert.match(about, /Kummer/);
    const sliders = await page.$$eval('#params input[type=range]', (s) => s.map((e) => e.dataset.param));
    assert.deepEqual(sliders, ['mu2', 'w']);
  });

  it('shows the stats of the stats endpoint, and the features of the features endpoint', async () => {
    const key = await meshKey();
    const stats = await getJSON(`/v1/meshes/${key}/stats`);
    const panel = await statsPanel(page);
    const int = (name) => Number(panel[name].text.replace(/,/g, ''));
    assert.equal(int('triangles'), stats.mesh.triangles);
    assert.equal(int('vertices'), stats.mesh.vertices);
    assert.equal(int('euler'), stats.analysis.euler);
    assert.equal(int('components'), stats.analysis.components);
    assert.equal(int('nonmanifold_edges'), stats.analysis.nonmanifold_edges);
    assert.equal(int('nonmanifold_points'), stats.analysis.nonmanifold_points);
    assert.equal(int('nonmanifold_curves'), stats.analysis.nonmanifold_curves);
    assert.equal(int('boundary_edges'), stats.analysis.boundary_edges);
    const close = (text, want) => {
      const got = Number(text.replace(/[^0-9eE+.-]/g, ''));
      assert.ok(Math.abs(got - want) <= 0.006 * Math.abs(want) + 1e-300, `${text} vs ${want}`);
    };
    close(panel.min_angle.text, stats.analysis.quality.min_angle);
    close(panel.max_dist.text, stats.analysis.accuracy.max_dist_vertex);
    assert.equal(Number(panel.compute_ms.value), stats.timings_ms.total);
    assert.equal(Number(panel.draco_bytes.value), stats.bytes);
    assert.equal(panel.cache.value, 'miss');
    assert.ok(Number(panel.bytes.value) >= stats.bytes, 'at least the mesh was transferred');

    const features = await getJSON(`/v1/meshes/${key}/features`);
    const segs = (lines) => lines.reduce((n, l) => n + l.xyz.length / 3 - 1, 0);
    const counts = await page.$$eval('#feature-key [data-count]', (es) => Object.fromEntries(es.map((e) => [e.className, Number(e.dataset.count)])));
    const closing = features.curves.filter((c) => c.closed).length;
    assert.equal(counts['key-edges'], segs(features.curves) + closing);
    assert.equal(counts['key-points'], features.singular_points.length);
    assert.equal(counts['key-points'], features.counts.singular_points);
    assert.equal(counts['key-boundary'], features.counts.boundary_edges);
    const off = features.nonmanifold_points.filter((p) => !p.on_locus).length +
      features.nonmanifold_edges.reduce((n, c) => n + c.off_edges.length, 0);
    assert.equal(counts['key-artefacts'], off);
    assert.equal(counts['key-artefacts'], features.counts.artefacts);
  });

  it('picking a Kummer node shows its type and coordinates within 1e-6 of the closed form', async () => {
    // f = (|X|^2 - mu2)^2 - lambda p q r s with the planes p, q = w - z -+ sqrt2 x and r, s =
    // w + z +- sqrt2 y (mu2 = 2, w = 1: the preset's defaults). Where two of the planes and the
    // sphere |X|^2 = mu2 meet, both terms vanish to second order: a node on each of the
    // tetrahedron's 6 edges, twice (12). The other 4, (+-1/sqrt2, 0, -1/2) and
    // (0, +-1/sqrt2, 1/2), are zeros of f and grad f too (exact substitution; checked below).
    const mu2 = 2, w = 1, r2 = Math.SQRT2;
    const planes = [[[r2, 0, 1], w], [[-r2, 0, 1], w], [[0, r2, 1], -w], [[0, -r2, 1], -w]];   // n . X = c
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const nodes = [[r2 / 2, 0, -0.5], [-r2 / 2, 0, -0.5], [0, r2 / 2, 0.5], [0, -r2 / 2, 0.5]];
    for (let i = 0; i < 4; i++) {
      for (let j = i + 1; j < 4; j++) {
        const [[a, ca], [b, cb]] = [planes[i], planes[j]];
        const d = cross(a, b), dd = dot(d, d), ab = dot(a, b);
        const x0 = [0, 1, 2].map((k) => ((ca * dot(b, b) - cb * ab) * a[k] + (cb * dot(a, a) - ca * ab) * b[k]) / dd);
        // |x0 + t d|^2 = mu2, x0 . d = 0
        const t = Math.sqrt((mu2 - dot(x0, x0)) / dd);
        for (const s of [t, -t]) nodes.push(x0.map((v, k) => v + s * d[k]));
      }
    }
    const f = ([x, y, z]) => {
      const lambda = (3 * mu2 - 1) / (3 - mu2);
      const p = w - z - r2 * x, q = w - z + r2 * x, r = w + z + r2 * y, s = w + z - r2 * y;
      return (x * x + y * y + z * z - mu2) ** 2 - lambda * p * q * r * s;
    };
    const h = 1e-5, grad = (X) => [0, 1, 2].map((k) => {
      const a = [...X], b = [...X];
      a[k] += h; b[k] -= h;
      return (f(a) - f(b)) / (2 * h);
    });
    for (const X of nodes) assert.ok(Math.abs(f(X)) < 1e-12 && Math.hypot(...grad(X)) < 1e-8, `(${X}) is a node`);

    const picks = await pickSingularPoints(page);
    assert.equal(picks.length, 16, 'sixteen singular points drawn');
    const seen = new Set();
    for (const p of picks) {
      assert.equal(p.type, 'node');
      const shown = p.text.split('\n')[1].match(/^\((.*)\)$/)[1].split(', ').map(Number);   // as the panel prints it
      assert.ok(nearest(nodes, shown) < 1e-6, `shown as (${shown})`);
      const err = nearest(nodes, p.xyz);
      assert.ok(err < 1e-6, `picked (${p.xyz}) is ${err} from the nearest closed-form node`);
      assert.ok(Math.abs(p.probe.f) < 1e-9, `the server's f = ${p.probe.f} there`);
      seen.add(nodes.findIndex((X) => Math.hypot(X[0] - p.xyz[0], X[1] - p.xyz[1], X[2] - p.xyz[2]) === err));
    }
    console.log(`# Kummer: ${picks.length} picks, ${seen.size} different nodes, worst distance to the closed form ${Math.max(...picks.map((p) => nearest(nodes, p.xyz))).toExponential(2)}`);
    // A click picks the point drawn nearest to it: two nodes may share a pixel from this view.
    assert.ok(seen.size >= 12, `${seen.size} different nodes picked`);
  });

  it('moving a slider computes a new mesh; moving it back is instant, from the page', async () => {
    // (tests/browser/live.test.mjs times the live previews shown while the slider moves)
    const first = await meshKey();
    const slider = page.locator('#param-mu2');
    const v0 = Number(await page.inputValue('#param-mu2-value'));
    await slider.focus();
    let before = await loads(page);
    for (let i = 0; i < 5; i++) await page.keyboard.press('ArrowRight');
    const second = await waitForMesh(page, before);
    const v1 = Number(await page.inputValue('#param-mu2-value'));
    assert.ok(v1 > v0, `mu2 went from ${v0} to ${v1}`);
    assert.notEqual(second, first);
    assert.match(await settledHref(page), new RegExp(`p\\.mu2=${v1}`));
    const stats = await getJSON(`/v1/meshes/${second}/stats`);
    assert.equal(Number((await statsPanel(page)).triangles.value), stats.mesh.triangles);

    const posts = jobPosts(requests, { refinedOnly: true });
    before = await loads(page);
    // Five steps back at once (as a held arrow key repeats): separate key presses on a loaded
    // machine may rest longer than the debounce between two of them, and a value the slider
    // rests on is rightly computed.
    await page.evaluate(() => {
      const s = document.getElementById('param-mu2');
      for (let i = 0; i < 5; i++) {
        s.stepDown();
        s.dispatchEvent(new Event('input', { bubbles: true }));
      }
    });
    const third = await waitForMesh(page, before);
    assert.equal(third, first);
    assert.equal(Number(await page.inputValue('#param-mu2-value')), v0);
    assert.equal((await statsPanel(page)).cache.value, 'viewer');
    await page.waitForTimeout(400); // past the debounce: nothing may be sent late either
    assert.equal(jobPosts(requests, { refinedOnly: true }), posts, 'no request for a result the page holds (live previews of the values in between aside)');
  });

  it('points at a syntax error before sending anything, at the column the server gives', async () => {
    const expr = 'x^2 + y^2 + sinn(z) - 1';
    const posts = jobPosts(requests);
    await page.fill('#expr', expr);
    await page.waitForSelector('#expr-error:not([hidden])');
    const shown = await page.$eval('#expr-error', (e) => ({ ...e.dataset, text: e.textContent }));
    assert.equal(shown.source, 'client');
    assert.equal(Number(shown.column), expr.indexOf('sinn') + 1);
    assert.match(shown.text, /unknown function 'sinn'/);
    assert.match(shown.text, /\n {12}\^/, 'a caret under the column');
    await page.click('#render');
    await page.keyboard.press('Control+Enter');
    await page.waitForTimeout(300);
    assert.equal(jobPosts(requests), posts, 'nothing sent');
    assert.equal(await page.getAttribute('#expr', 'aria-invalid'), 'true');
    const r = await api('/v1/mesh', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify({ expr }) });
    assert.equal(r.status, 400);
    const err = (await r.json()).error;
    assert.equal(err.column, Number(shown.column));
    assert.equal(err.line, Number(shown.line));
  });

  it("shows the server's error at its column when the viewer's check passes", async () => {
    const expr = '('.repeat(201) + 'x' + ')'.repeat(201) + '^2 + y^2 + z^2 - 1';
    assert.equal(checkExpression(expr).ok, true, 'the viewer does not check nesting');
    await page.fill('#expr', expr);
    await page.click('#render');
    await page.waitForSelector('#expr-error[data-source=server]');
    const shown = await page.$eval('#expr-error', (e) => ({ ...e.dataset, text: e.textContent }));
    assert.equal(Number(shown.column), 201);
    assert.match(shown.text, /nests too deeply/);
  });

  it('the viewer and the server agree on where expressions go wrong', async () => {
    const bad = ['x^2 + y^2 +', '2x + y', 'sin x', 'x**2', 'x^2.5 + y', '(x + 1', 'x + $', 'y = 3', 'max(x)',
      'let a = 1', 'let x = 2\nx', 'let a = b\nlet b = 1\na + x', 'let a = 2\nx^2 + y^2 - a b', '1/0 + x',
      'foo(x)', 'x(2)', 'x^y', 'let s = 2*z - y\ns(x^2 + y^2 - 1)^2'];
    for (const expr of bad) {
      const mine = checkExpression(expr);
      assert.equal(mine.ok, false, `viewer accepts ${JSON.stringify(expr)}`);
      const r = await api('/v1/mesh', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify({ expr }) });
      const body = await r.json();
      assert.equal(r.status, 400, `${JSON.stringify(expr)}: ${JSON.stringify(body)}`);
      assert.deepEqual([mine.line, mine.column], [body.error.line, body.error.column], `${JSON.stringify(expr)}: ${mine.message} / ${body.error.message}`);
    }
    const good = ['x^2 + y^2 + z^2 - r^2', 'let s = w + z - y;\n(x^2 + y^2 - 1)^2 - s',
      'let s = 2*z - y\n(x^2 + y^2 - 1)^2 - s', 'sqrt(-1) + x', 'let p = x*x\nlet q = p + y^2; q + z^2 - 1', 'pow(x, 2) + abs(y) - exp(-z)',
      'min(x, y, z) + max(x, 1) - pi + e', '-x^2 + 2^3^2*y - x^-2'];
    for (const expr of good) {
      const mine = checkExpression(expr);
      assert.equal(mine.ok, true, `${JSON.stringify(expr)}: ${mine.message}`);
      const params = Object.fromEntries(mine.params.map((n) => [n, 0.7]));
      const r = await api('/v1/mesh', { method: 'POST', headers: { 'Content-Type': 'application/json' },
        body: JSON.stringify({ expr, params, depth: { min: 1, max: 2 } }) });
      assert.equal(r.status, 200, `${JSON.stringify(expr)}: ${await r.text()}`);
    }
  });

  it('a typed expression gets a slider for each new name and computes', async () => {
    const before = await loads(page);
    await page.fill('#expr', 'let rho = x^2 + y^2 + z^2\n(rho + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)');
    await page.waitForSelector('#expr-error', { state: 'hidden' });
    const sliders = await page.$$eval('#params input[type=range]', (s) => s.map((e) => e.dataset.param));
    assert.deepEqual(sliders, ['R', 'r']);
    assert.equal(await page.inputValue('#preset'), '');
    await page.fill('#param-R-value', '1');
    await page.fill('#param-r-value', '0.4');
    await page.locator('#param-r-value').press('Enter');
    await page.keyboard.press('Tab');
    await page.focus('#expr');
    await page.keyboard.press('Control+Enter');
    await waitForMesh(page, before);
    const an = (await getJSON(`/v1/meshes/${await meshKey()}/stats`)).analysis;
    assert.equal(an.euler, 0, 'a torus');
    assert.equal(Number((await statsPanel(page)).euler.value), 0);
  });

  it('says clearly when a request is over a limit (422)', async () => {
    await page.click('#box-section summary');
    // depth max is the request's only on the depth path (under a bound it is the server's)
    const off = await loads(page);
    await page.fill('#max-error', 'off');
    await page.locator('#max-error').press('Tab');
    await waitForMesh(page, off);
    await page.fill('#depth-max', '12');
    await page.locator('#depth-max').press('Tab');
    await page.waitForSelector('#message.error:not([hidden])');
    const text = await page.textContent('#message');
    assert.match(text, /Over a limit/);
    assert.match(text, /depth\.max: 12 is above the limit 10/);
    const before = await loads(page);
    await page.fill('#depth-max', '7');
    await page.locator('#depth-max').press('Tab');
    await waitForMesh(page, before);
    assert.equal(await page.isHidden('#message'), true);
  });

  it('every stats row fits one line of the panel, at the widest values', async () => {
    // the page's own stats_ui.js module (the same URL: the same instance) fed the widest figures
    // each row can show, with every reason the dual mesher can give; the panel put back after
    const saved = await page.evaluate(() => ['stats', 'warnings'].map((id) => document.getElementById(id).innerHTML));
    const reasons = await page.evaluate(async () => Object.keys((await import('/js/stats_ui.js')).DUAL_DECLINED));
    for (const why of ['no_bound', 'off', 'singular_locus', 'min_max', 'box_cut', 'not_plain',
      'error_at_max_depth', 'open_edge', 'point_type', 'point_fan']) assert.ok(reasons.includes(why), why);
    for (const why of [null, ...reasons]) {
      for (const viewerCache of [false, true]) {
        await page.evaluate(async ({ why, viewerCache }) => {
          const { showStats } = await import('/js/stats_ui.js');
          const n = 4000000, d = 1.23e-11, a = 1.23e-4; // the triangle budget; distances are >= 0
          showStats({
            stats: {
              mesh: { triangles: n, vertices: n },
              analysis: {
                euler: -123456, components: n, nonmanifold_edges: n, nonmanifold_points: n,
                nonmanifold_curves: n, boundary_edges: n,
                quality: { min_angle: a, share_under_10: 0.999, angle_hist: Array(18).fill(1), aspect_max: 1.23e12, aspect_p99: 1.23e12 },
                accuracy: { max_error: 1.23e-11, met: false, max_dist_vertex: d, max_dist_midpoint: d, max_dist_centroid: d, p99_dist_midpoint: d, p99_dist_centroid: d },
              },
              remesh: { min_angle_before: a, min_angle_after: a, flips: n, moves: n },
              polygoniser: { mesher: 'straddle', dual_declined: why },
              timings_ms: { total: 123456 }, warnings: [],
            },
            viewerCache, serverCache: 'miss', transferred: 999e6, drcBytes: 999e6,
          });
        }, { why, viewerCache });
        assert.deepEqual(await wrappedStats(page), [], `dual_declined ${why}, viewer cache ${viewerCache}`);
      }
    }
    await page.evaluate((html) => ['stats', 'warnings'].forEach((id, i) => { document.getElementById(id).innerHTML = html[i]; }), saved);
    // the checkboxes' own words on one line, their hints below them (they were squeezed into a
    // column one word wide beside the hint)
    await page.evaluate(() => { document.getElementById('box-section').open = true; });
    const words = await page.evaluate(() => ['simplify', 'quality-good'].map((id) => {
      const text = [...document.getElementById(id).parentElement.childNodes].find((c) => c.nodeType === 3 && c.textContent.trim());
      const r = document.createRange();
      r.selectNodeContents(text);
      return [text.textContent.trim(), new Set([...r.getClientRects()].map((b) => Math.round(b.bottom))).size];
    }));
    assert.deepEqual(words, [['simplify within the bound', 1], ['quality: good', 1]]);
  });

  it('line colours of different meanings are far apart (CIE76 ΔE ≥ 30)', async () => {
    // the cube's creases were drawn 0xfa5708, ΔE 25 from the boundary edges' orange and 22
    // from the artefacts' red: on a CSG surface they read as boundary edges
    const colours = await page.evaluate(async () => {
      const f = await import('/js/features.js');
      const c = await import('/js/curves.js');
      return { boundary: f.FEATURE_COLORS.boundary, artefacts: f.FEATURE_COLORS.artefacts,
        singular: f.FEATURE_COLORS.edges, whisker: f.CURVE_KIND_COLORS.whisker, ...c.CUT_KIND_COLORS };
    });
    const lab = (h) => {
      const lin = (v) => (v <= 0.04045 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4);
      const [r, g, b] = [16, 8, 0].map((s) => lin(((h >> s) & 255) / 255));
      const t = (v) => (v > 0.008856 ? Math.cbrt(v) : 7.787 * v + 16 / 116);
      const x = t((0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047), y = t(0.2126 * r + 0.7152 * g + 0.0722 * b);
      const z = t((0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883);
      return [116 * y - 16, 500 * (x - y), 200 * (y - z)];
    };
    const names = Object.keys(colours);
    assert.ok(names.includes('crease') && names.includes('section'), names.join());
    for (let i = 0; i < names.length; i++) {
      for (let j = i + 1; j < names.length; j++) {
        const [a, b] = [lab(colours[names[i]]), lab(colours[names[j]])];
        const d = Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
        assert.ok(d >= 30, `${names[i]} and ${names[j]}: ΔE ${d.toFixed(1)}`);
      }
    }
  });

  it('asks for a max error and shows what was reached', async () => {
    await choosePreset('sphere');
    await page.evaluate(() => { document.getElementById('box-section').open = true; });
    const before = await loads(page);
    await page.fill('#max-error', '0.004');
    await page.locator('#max-error').press('Tab');
    await waitForMesh(page, before);
    assert.equal(await page.isDisabled('#depth-max'), true, 'depth max is only a safety limit');
    const s = await getJSON(`/v1/meshes/${await meshKey()}/stats`);
    const acc = s.analysis.accuracy;
    assert.equal(acc.max_error, 0.004);
    assert.equal(acc.met, Math.max(acc.max_dist_midpoint, acc.max_dist_centroid, acc.max_dist_vertex) <= 0.004);
    const panel = await statsPanel(page);
    assert.equal(Number(panel.max_error.value), 0.004);
    assert.match(panel.max_error.text, acc.met ? /\(met\)/ : /\(not met\)/);
    assert.equal(Number(panel.max_dist_between.value), Math.max(acc.max_dist_midpoint, acc.max_dist_centroid));
    assert.match(await settledHref(page), /err=0\.004/);
    // under a bound the server's default mesher is the dual one on the sphere; the panel says so
    assert.equal(s.polygoniser.mesher, 'dual');
    assert.equal(panel.mesher.text, 'dual');
    assert.equal(panel.mesher.value, 'dual');
    assert.equal(panel.dual_declined.text, '–');
    assert.deepEqual(await wrappedStats(page), [], 'every stats row on one line');
    assert.equal(await page.isDisabled('#mesher'), false);
    // asking for the primal polygons: another mesh, and the panel gives the reason
    const primal = await loads(page);
    await page.selectOption('#mesher', 'primal');
    await waitForMesh(page, primal);
    const sp = await getJSON(`/v1/meshes/${await meshKey()}/stats`);
    assert.equal(sp.polygoniser.mesher, 'primal');
    assert.equal(sp.polygoniser.dual_declined, 'off');
    assert.equal(sp.simplify, undefined, 'the primal polygons are not simplified unless asked');
    const sp2 = await statsPanel(page);
    assert.equal(sp2.mesher.text, 'primal');
    assert.equal(sp2.dual_declined.text, 'dual off');
    assert.equal(sp2.dual_declined.value, 'off');
    assert.match(await settledHref(page), /mesher=primal/);
    await page.evaluate(() => document.getElementById('stats-section').scrollIntoView());
    fs.writeFileSync(artifact('stats-mesher-primal.png'), await page.locator('#stats-section').screenshot());
    fs.writeFileSync(artifact('box-mesher-control.png'), await page.locator('#box-section').screenshot());
    const straddle = await loads(page);
    await page.selectOption('#mesher', 'straddle');
    await waitForMesh(page, straddle);
    assert.equal((await getJSON(`/v1/meshes/${await meshKey()}/stats`)).polygoniser.mesher, 'straddle');
    const ss = await statsPanel(page);
    assert.equal(ss.mesher.text, 'straddle');
    assert.equal(ss.dual_declined.text, 'dual off');
    const dual = await loads(page);
    await page.selectOption('#mesher', 'dual');
    await waitForMesh(page, dual);
    const sd = await statsPanel(page);
    assert.equal(sd.mesher.text, 'dual');
    assert.equal(sd.dual_declined.text, '–');
    // simplify: off by default for every mesher (the mesher's own triangles); checked, the
    // stats carry the simplification's block and fewer triangles, still within the bound
    assert.equal(await page.isChecked('#simplify'), false);
    assert.equal(await page.isDisabled('#simplify'), false);
    const sdj = await getJSON(`/v1/meshes/${await meshKey()}/stats`);
    assert.equal(sdj.simplify, undefined);
    const simp = await loads(page);
    await page.check('#simplify');
    await waitForMesh(page, simp);
    const ssj = await getJSON(`/v1/meshes/${await meshKey()}/stats`);
    assert.ok(ssj.simplify, 'the simplification ran');
    assert.ok(ssj.mesh.triangles < sdj.mesh.triangles, `${ssj.mesh.triangles} < ${sdj.mesh.triangles}`);
    const sacc = ssj.analysis.accuracy;
    assert.ok(Math.max(sacc.max_dist_midpoint, sacc.max_dist_centroid, sacc.max_dist_vertex) <= 0.004);
    assert.match(await settledHref(page), /simplify=1/);
    const unsimp = await loads(page);
    await page.uncheck('#simplify');
    await waitForMesh(page, unsimp);
    assert.doesNotMatch(await settledHref(page), /simplify=/);
    // empty: the server's default bound, 1e-3 x the box diagonal (the placeholder says how
    // much for this box: the sphere's +-1.5, 3 sqrt 3 across); the request leaves it out
    const auto = await loads(page);
    await page.fill('#max-error', '');
    await page.locator('#max-error').press('Tab');
    await waitForMesh(page, auto);
    assert.equal(await page.getAttribute('#max-error', 'placeholder'), 'auto: 0.0052 (1e-3 × diagonal)');
    assert.equal(await page.isDisabled('#depth-max'), true, 'still under a bound');
    assert.equal(await page.isDisabled('#mesher'), false);
    const sa = await getJSON(`/v1/meshes/${await meshKey()}/stats`);
    assert.ok(Math.abs(sa.analysis.accuracy.max_error - 3e-3 * Math.sqrt(3)) < 1e-15, `${sa.analysis.accuracy.max_error}`);
    assert.equal(sa.analysis.accuracy.met, true);
    const pa = await statsPanel(page);
    assert.equal(Number(pa.max_error.value), sa.analysis.accuracy.max_error);
    assert.equal(pa.max_error.text, '0.0052 (met)');
    assert.doesNotMatch(await settledHref(page), /err=/);
    // off: no bound, the depth decides ("max_error": null)
    const back = await loads(page);
    await page.fill('#max-error', 'off');
    await page.locator('#max-error').press('Tab');
    await waitForMesh(page, back);
    assert.equal(await page.isDisabled('#depth-max'), false);
    assert.equal(await page.isDisabled('#mesher'), true, 'the meshers differ only under a bound');
    assert.equal(await page.isDisabled('#simplify'), true, 'only a bound keeps it honest');
    assert.equal((await statsPanel(page)).max_error.text, 'off');
    assert.match(await settledHref(page), /err=off/);
    const sn = await statsPanel(page);
    assert.equal(sn.mesher.text, 'primal');
    assert.equal(sn.dual_declined.text, 'no max error');
    // the primal sphere's "between vertices (max, p99)" value wrapped to two lines (NOTE11)
    assert.deepEqual(await wrappedStats(page), [], 'every stats row on one line');
  });

  it('asks for the quality pass and shows the triangles\' shape', async () => {
    await choosePreset('sphere');
    await page.evaluate(() => { document.getElementById('box-section').open = true; });
    const before = await loads(page);
    await page.check('#quality-good');
    await waitForMesh(page, before);
    const s = await getJSON(`/v1/meshes/${await meshKey()}/stats`);
    const q = s.analysis.quality;
    assert.ok(q.min_angle >= 20, `smallest angle ${q.min_angle}`);
    assert.ok(s.remesh.min_angle_before < s.remesh.min_angle_after);
    const panel = await statsPanel(page);
    assert.deepEqual(JSON.parse(panel.angle_hist.value), q.angle_hist);
    assert.equal(q.angle_hist.reduce((a, b) => a + b, 0), s.mesh.triangles - q.degenerate_triangles);
    assert.equal(Number(panel.remesh.value), s.remesh.min_angle_after);
    assert.equal(panel.remesh_edits.text, `${s.remesh.flips.toLocaleString('en-US')}, ${s.remesh.moves.toLocaleString('en-US')}`);
    assert.deepEqual(await wrappedStats(page), [], 'every stats row on one line');
    assert.equal(Number(panel.aspect.value), q.aspect_max);
    assert.equal(Number(panel.share_under_10.value), q.share_under_10);
    assert.match(await settledHref(page), /quality=good/);
    const back = await loads(page);
    await page.uncheck('#quality-good');
    await waitForMesh(page, back);
    assert.equal((await statsPanel(page)).remesh.text, 'off');
    assert.equal((await statsPanel(page)).remesh_edits.text, '–');
  });

  it('the clip cap fills the cut where f < 0, computed from f', async () => {
    // the sphere x² + y² + z² = 1 (the preset at r = 1) cut by y = c: a disc of radius
    // √(1 − c²) where f < 0, nothing for |c| > 1
    const capPixels = (img) => {
      let n = 0;
      for (let i = 0; i < img.width * img.height; i++) {
        const [r, g, b] = [img.rgba[4 * i], img.rgba[4 * i + 1], img.rgba[4 * i + 2]];
        n += Math.abs(r - CAP_RGB[0]) <= 6 && Math.abs(g - CAP_RGB[1]) <= 6 && Math.abs(b - CAP_RGB[2]) <= 6;
      }
      return n / (img.width * img.height);
    };
    const cutAt = async (c) => {
      await page.$eval('#clip-offset', (e, v) => { e.value = String(v); e.dispatchEvent(new Event('input', { bubbles: true })); }, c);
      return capPixels(await viewShot(page));
    };
    await page.check('#clip-on');
    await page.selectOption('#clip-axis', 'y');
    const whole = await cutAt(0), small = await cutAt(0.8), none = await cutAt(1.2);
    assert.ok(whole > 0.01, `the cap of the unit disc covers ${whole} of the view`);
    assert.ok(small > 0.002 && small < whole, `the disc of radius 0.6 (${small}) is smaller than the unit disc (${whole})`);
    assert.ok(whole / small > 1.5 && whole / small < 6, `area ratio ${whole / small}, 1/0.36 = 2.8 up to perspective`);
    assert.ok(none < 1e-4, `no cap beyond the sphere (${none})`);
    await page.uncheck('#clip-cap');
    assert.ok(await cutAt(0) < 1e-4, 'no cap when it is switched off');
    await page.check('#clip-cap');
    await page.uncheck('#clip-on');
  });

  it('says so when the surface does not cross the box', async () => {
    const before = await loads(page);
    await page.fill('#expr', 'x^2 + y^2 + z^2 + 1');
    await page.click('#render');
    await waitForMesh(page, before);
    assert.match(await page.textContent('#message'), /does not cross this box/);
    assert.equal(Number((await statsPanel(page)).triangles.value), 0);
    assert.equal(await page.getAttribute('#downloads a[data-format=glb]', 'aria-disabled'), 'true');
    assert.equal(await page.getAttribute('#downloads a[data-format=glb]', 'href'), null);
  });

  it('asks only for the attributes its colouring draws; curvature colours come from the stored surface and their legend is the decoded attribute', async () => {
    await choosePreset('kummer-16-nodes');
    const key = await meshKey();
    // Shaded: the request the page sent and the mesh it got carry no curvature.
    const sent = requests.filter((r) => r.method === 'POST' && new URL(r.url).pathname === '/v1/jobs').map((r) => JSON.parse(r.body));
    assert.deepEqual(sent.at(-1).output, { attributes: ['normal'] }, 'the shaded view asks for normals only');
    const drcOf = async (k) => Buffer.from(await (await api(`/v1/meshes/${k}.drc`)).arrayBuffer());
    const plainDrc = await drcOf(key);
    const plain = await decodeDraco(plainDrc);
    assert.deepEqual(Object.keys(plain.attributes).sort(), ['normal', 'position']);
    const shaded = await viewShot(page);
    const sShaded = pixelStats(shaded);
    const polygonisations = async () => Number((await (await api('/metrics')).text()).match(/^isomesh_polygonisations_total (\d+)/m)[1]);
    const computed = await polygonisations();
    const bytes = { shaded: plainDrc.length };
    for (const [mode, attr, file] of [['mean', 'mean_curvature', 'kummer-16-nodes-mean.png'], ['gauss', 'gauss_curvature', 'kummer-16-nodes-gauss.png']]) {
      const n = await loads(page);
      const posts = jobPosts(requests);
      await page.selectOption('#color-mode', mode);
      const colouredKey = await waitForMesh(page, n);
      await page.waitForSelector(`#legend[data-mode=${mode}]:not([hidden])`);
      // A new request for the same surface with this curvature, encoded from the stored
      // surface: no new polygonisation.
      assert.equal(jobPosts(requests), posts + 1);
      const body = JSON.parse(requests.filter((r) => r.method === 'POST' && new URL(r.url).pathname === '/v1/jobs').at(-1).body);
      assert.deepEqual(body.output, { attributes: ['normal', attr] });
      assert.notEqual(colouredKey, key);
      assert.equal(await polygonisations(), computed, `${mode}: no polygonisation for another attribute set`);
      const drc = await drcOf(colouredKey);
      const decoded = await decodeDraco(drc);
      bytes[mode] = drc.length;
      assert.equal(decoded.faces, plain.faces);
      const img = await viewShot(page, file);
      const s = assertRendered(img, `${mode} curvature`);
      assert.ok(changedShare(shaded, img) > 0.03, `${mode}: the canvas changed`);
      assert.ok(s.saturated > sShaded.saturated + 0.005, `${mode}: colours appear (${s.saturated} vs ${sShaded.saturated})`);
      const legend = await page.$eval('#legend', (e) => ({ ...e.dataset }));
      const [lo, hi] = finiteRange(decoded.attributes[attr].values);
      assert.equal(decoded.attributes[attr].uniqueId, ATTRIBUTE_IDS[attr]);
      assert.ok(Math.abs(Number(legend.min) - lo) <= 1e-6 * Math.max(1, Math.abs(lo)), `${mode} min ${legend.min} vs ${lo}`);
      assert.ok(Math.abs(Number(legend.max) - hi) <= 1e-6 * Math.max(1, Math.abs(hi)), `${mode} max ${legend.max} vs ${hi}`);
      assert.ok(Number(legend.lo) < Number(legend.hi));
      assert.ok(Number(legend.lo) >= lo && Number(legend.hi) <= hi, 'the bar lies within the data');
      const other = mode === 'mean' ? 'gauss_curvature' : 'mean_curvature';
      assert.equal(decoded.attributes[other], undefined, `${mode}: ${other} is not sent`);
    }
    console.log(`# kummer-16-nodes drc bytes: shaded ${bytes.shaded}, mean ${bytes.mean}, gauss ${bytes.gauss}`);
    // Back to shaded: the mesh held with more attributes serves it, nothing is sent.
    const posts = jobPosts(requests);
    await page.selectOption('#color-mode', 'shaded');
    await page.waitForSelector('#legend', { state: 'hidden' });
    await page.waitForTimeout(300);
    assert.equal(jobPosts(requests), posts, 'no request for shading');
  });

  it('the clipping plane cuts the surface open', async () => {
    const whole = await viewShot(page);
    await page.check('#clip-on');
    await page.selectOption('#clip-axis', 'y');
    const cut = await viewShot(page, 'kummer-16-nodes-cut.png');
    assertRendered(cut, 'cut Kummer surface');
    assert.ok(changedShare(whole, cut) > 0.02, 'the cut changed the view');
    assert.ok(pixelStats(cut).foreground < pixelStats(whole).foreground, 'less surface is drawn');
    // The cut removes the half nearer the camera (here at y < 0), opening the surface towards us.
    assert.equal(await page.isChecked('#clip-flip'), true);
    assert.match(await settledHref(page), /clip=y,0,flip/);
    await page.uncheck('#clip-flip');
    const flipped = await viewShot(page);
    assert.ok(changedShare(cut, flipped) > 0.02, 'flipping shows the other half');
    assert.match(await settledHref(page), /clip=y,0(&|$)/);
    await page.uncheck('#clip-on');
  });

  it('every download link gives a valid file of this mesh, with every attribute', async () => {
    // The view holds normals only (shaded); the first click asks for the same surface with
    // every attribute and points the links there.
    const shownKey = await meshKey();
    const hrefs = () => page.$$eval('#downloads a[data-format]', (as) => as.map((a) => [a.dataset.format, a.getAttribute('href')]));
    const formats = await hrefs();
    assert.deepEqual(formats.map((f) => f[0]), ['drc', 'glb', 'ply', 'obj', 'stl']);
    for (const [fmt, href] of formats) assert.equal(href, `/v1/meshes/${shownKey}.${fmt}`);
    let key = null, stats = null;
    for (const [fmt] of formats) {
      const [download] = await Promise.all([page.waitForEvent('download'), page.click(`#downloads a[data-format=${fmt}]`)]);
      if (!key) {
        key = new URL(download.url()).pathname.match(/^\/v1\/meshes\/([0-9a-f]{64})\.drc$/)[1];
        assert.notEqual(key, shownKey);
        for (const [f, href] of await hrefs()) assert.equal(href, `/v1/meshes/${key}.${f}`);
        stats = await getJSON(`/v1/meshes/${key}/stats`);
        assert.equal(stats.mesh.triangles, (await getJSON(`/v1/meshes/${shownKey}/stats`)).mesh.triangles, 'the same surface');
      }
      assert.match(download.suggestedFilename(), new RegExp(`^kummer-16-nodes-[0-9a-f]{8}\\.${fmt}$`));
      const bytes = fs.readFileSync(await download.path());
      if (fmt === 'drc') {
        const d = await decodeDraco(bytes);
        assert.equal(d.faces, stats.mesh.encoded_faces);
        assert.equal(d.points, stats.mesh.encoded_points);
        for (const [name, id] of Object.entries(ATTRIBUTE_IDS)) assert.equal(d.attributes[name].uniqueId, id, name);
      } else if (fmt === 'glb') {
        const report = await gltfValidator.validateBytes(new Uint8Array(bytes));
        assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
        const json = JSON.parse(bytes.subarray(20, 20 + bytes.readUInt32LE(12)).toString('utf8'));
        const prim = json.meshes[0].primitives.find((p) => p.extensions && p.extensions.KHR_draco_mesh_compression);
        const view = json.bufferViews[prim.extensions.KHR_draco_mesh_compression.bufferView];
        const binStart = 20 + bytes.readUInt32LE(12) + 8;
        const d = await decodeDraco(bytes.subarray(binStart + (view.byteOffset || 0), binStart + (view.byteOffset || 0) + view.byteLength));
        assert.equal(d.faces, stats.mesh.triangles);
      } else if (fmt === 'ply') {
        const head = bytes.subarray(0, 600).toString('latin1');
        assert.match(head, /^ply\n/);
        assert.match(head, new RegExp(`element vertex ${stats.mesh.vertices}\n`));
        assert.match(head, new RegExp(`element face ${stats.mesh.triangles}\n`));
        assert.match(head, /property float mean_curvature\nproperty float gauss_curvature\n/, 'the PLY carries the curvature');
      } else if (fmt === 'obj') {
        const text = bytes.toString('utf8');
        assert.equal((text.match(/^v /gm) || []).length, stats.mesh.vertices);
        assert.equal((text.match(/^f /gm) || []).length, stats.mesh.triangles);
      } else if (fmt === 'stl') {
        assert.equal(bytes.readUInt32LE(80), stats.mesh.triangles);
        assert.equal(bytes.length, 84 + 50 * stats.mesh.triangles);
      }
    }
  });

  it('a shared link reopens the same surface, parameters, view, colours and cut', async () => {
    let before = await loads(page);
    await page.fill('#param-w-value', '1.2');
    await page.locator('#param-w-value').press('Enter');
    await waitForMesh(page, before);
    before = await loads(page);
    await page.selectOption('#color-mode', 'gauss');
    await waitForMesh(page, before);   // the same surface with its Gaussian curvature
    await page.check('#clip-on');
    await page.selectOption('#clip-axis', 'x');
    await page.$eval('#clip-offset', (e) => { e.value = '0.5'; e.dispatchEvent(new Event('input', { bubbles: true })); });
    await page.uncheck('#show-boundary');
    await page.check('#wireframe');
    await page.focus('#view');
    for (let i = 0; i < 6; i++) await page.keyboard.press('Shift+ArrowLeft');
    await page.keyboard.press('+');
    const url = await settledHref(page); // the URL follows the view after a short pause
    assert.match(url, /cam=/);
    assert.match(url, /p\.w=1\.2/);
    const key = await meshKey();
    await page.evaluate(() => document.activeElement.blur());
    const original = await viewShot(page, 'shared-original.png');

    const twin = await browser.context.newPage();
    const twinErrors = watchErrors(twin);
    try {
      await twin.goto(url);
      await waitForMesh(twin, 0);
      assert.equal(await twin.evaluate(() => document.body.dataset.meshKey), key);
      assert.equal(await twin.inputValue('#preset'), 'kummer-16-nodes');
      assert.equal(await twin.inputValue('#param-w-value'), '1.2');
      assert.equal(await twin.inputValue('#color-mode'), 'gauss');
      assert.equal(await twin.isChecked('#clip-on'), true);
      assert.equal(await twin.inputValue('#clip-axis'), 'x');
      assert.equal(Number(await twin.inputValue('#clip-offset')), 0.5);
      assert.equal(await twin.isChecked('#show-boundary'), false);
      assert.equal(await twin.isChecked('#wireframe'), true);
      const cam = (u) => new URL(u).hash.match(/cam=([^&]*)/)[1];
      assert.equal(cam(await settledHref(twin)), cam(url));
      const copy = await viewShot(twin, 'shared-reopened.png');
      assert.ok(changedShare(original, copy) < 0.01, `the reopened view matches (${changedShare(original, copy)})`);
      assert.deepEqual(twinErrors, []);
    } finally {
      await twin.close();
    }
    await page.uncheck('#wireframe');
    await page.uncheck('#clip-on');
    await page.check('#show-boundary');
    await page.selectOption('#color-mode', 'shaded');
  });

  it('every control can be reached and used from the keyboard', async () => {
    await page.$$eval('details', (ds) => ds.forEach((d) => { d.open = true; }));
    const unreachable = await page.$$eval('input, select, textarea, button, a[href], summary, #view', (els) => els
      .filter((e) => e.offsetParent !== null && !e.disabled)
      .filter((e) => { e.focus(); return document.activeElement !== e; })
      .map((e) => e.id || e.outerHTML.slice(0, 60)));
    assert.deepEqual(unreachable, []);
    await page.focus('body');
    // Tab on until every control below has had the focus (bounded: the page has fewer than
    // 200 focusable controls with every section open)
    const wanted = ['view', 'preset', 'expr', 'render', 'param-mu2', 'color-mode', 'show-edges', 'wireframe', 'occlusion', 'clip-on', 'fit', 'drc'];
    const seen = new Set();
    for (let i = 0; i < 200 && !wanted.every((id) => seen.has(id)); i++) {
      await page.keyboard.press('Tab');
      seen.add(await page.evaluate(() => document.activeElement.id || document.activeElement.dataset.format || document.activeElement.tagName));
    }
    for (const id of wanted) {
      assert.ok(seen.has(id), `Tab reaches ${id}`);
    }
    const href0 = await settledHref(page);
    await page.focus('#view');
    await page.keyboard.press('Shift+ArrowUp');
    await page.keyboard.press('-');
    assert.notEqual(await settledHref(page), href0, 'the keyboard moved the camera');
  });

  it("saves the paper's four surfaces as screenshots", async () => {
    // The paper shows the 4-node Kummer surface cut away and the Klein bottle in cross-section.
    for (const [name, extra] of [['horn-cyclide'], ['klein-bottle', 'y'], ['steiner-roman', 'z'], ['kummer-4-nodes', 'y']]) {
      await choosePreset(name);
      await page.evaluate(() => document.activeElement && document.activeElement.blur());
      assertRendered(await viewShot(page, `${name}.png`), name);
      // the key counts in words that agree with the count ("1 double curve", "4 nodes")
      const key = await page.evaluate(() => [...document.querySelectorAll('#key-types span')].map((e) => [e.dataset.count, e.textContent]));
      for (const [n, text] of key) assert.equal(/^1 \S+s\b/.test(text), false, `${text} (${n})`);
      if (name === 'klein-bottle') assert.ok(key.some(([n, t]) => n === '1' && t === '1 double curve'), JSON.stringify(key));
      // the points layer's swatch is no point type's colour (the points are drawn by type)
      const swatch = await page.evaluate(() => getComputedStyle(document.querySelector('#feature-key .key-points'), '::before').backgroundColor);
      assert.equal(swatch, 'rgba(0, 0, 0, 0)', `${name}: the singular points layer's swatch ${swatch}`);
      if (name === 'kummer-4-nodes') assert.ok(key.some(([n, t]) => n === '4' && t === '4 nodes'), JSON.stringify(key));
      if (extra) {
        await page.check('#clip-on');
        await page.selectOption('#clip-axis', extra);
        assertRendered(await viewShot(page, `${name}-cut-${extra}.png`), `${name} cut`);
        await page.uncheck('#clip-on');
      }
    }
    assert.deepEqual(errors, []);
  });

  it('works on a narrow screen', async () => {
    const narrow = await browser.context.newPage();
    try {
      await narrow.setViewportSize({ width: 390, height: 844 });
      await narrow.goto(daemon.base + '/#preset=steiner-roman');
      await waitForMesh(narrow, 0);
      const view = await narrow.locator('#view').boundingBox();
      const panel = await narrow.locator('#panel').boundingBox();
      assert.ok(view.width <= 390 && view.width > 300, `view width ${view.width}`);
      assert.ok(view.height > 250, `view height ${view.height}`);
      assert.ok(panel.y >= view.y + view.height - 1, 'the panel is below the view');
      assert.ok(await narrow.evaluate(() => document.documentElement.scrollWidth <= window.innerWidth + 1), 'no sideways scrolling');
      assertRendered(await viewShot(narrow, 'narrow-steiner-roman.png'), 'narrow view');
      await narrow.locator('#downloads a[data-format=glb]').scrollIntoViewIfNeeded();
      assert.equal(await narrow.locator('#downloads a[data-format=glb]').isVisible(), true);
    } finally {
      await narrow.close();
    }
  });
});
