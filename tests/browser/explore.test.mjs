// explore.test.mjs — the box and inspection in the viewer: a typed expression gets a box
// fitted around its zero set (POST /v1/box) that contains the whole surface (closed form:
// an off-centre sphere) and the mesh is not cut (no boundary edges); the box outline and
// the axes with ticks change the picture; a box typed by hand is kept; the gallery search and
// its thumbnails (loaded only when in view);
// picking a node of the Cayley cubic gives its type, its closed-form coordinates within
// 1e-6 and f = 0, grad f = 0 there, and so does picking the double curve of two planes; a PNG
// export has the size asked for; the Curves panel cuts the sphere into cells
// (curves drawn, areas 2 pi h, a picked cell's facts) and adds a level curve, an
// intersection (Viviani's node of degree 4) and the view's silhouette (closed forms); a cone
// cut through its node: the vertex there typed singular_point, drawn and counted in the key;
// double
// sheets are tinted; the render mode's ambient occlusion of two spheres matches its closed
// form (5/9 of the light where they face each other, all of it opposite, none inside).
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startDaemon, stopDaemon, startBrowser, stopBrowser } from './lib/harness.mjs';
import { openViewer, waitForMesh, loads, viewShot, settledHref } from './lib/page.mjs';
import fs from 'node:fs';
import { changedShare, decodePng, pixelStats } from './lib/png.mjs';
import { artifact } from './lib/harness.mjs';
import { pickSingularPoints, nearest } from './lib/pick.mjs';

let daemon = null;
let browser = null;
let page = null;
let errors = [];

function assertChanged(a, b) {
  assert.ok(changedShare(a, b) > 0.01, `the picture changed (${changedShare(a, b)})`);
}

// The sphere preset shown (when a test runs alone) and the Curves panel open.
async function sphereWithCurvesPanel() {
  if (await page.inputValue('#preset') !== 'sphere') {
    const k = await loads(page);
    await page.selectOption('#preset', 'sphere');
    await waitForMesh(page, k);
  }
  await page.evaluate(() => { document.getElementById('curves-section').open = true; });
}

async function boxFields() {
  return page.evaluate(() => ['xmin', 'ymin', 'zmin', 'xmax', 'ymax', 'zmax'].map((k) => Number(document.getElementById(`box-${k}`).value)));
}

describe('box and inspection', { timeout: 300000 }, () => {
  before(async () => {
    daemon = await startDaemon();
    browser = await startBrowser();
    ({ page, errors } = await openViewer(browser.context, daemon.base + '/#preset=torus'));
  });

  after(async () => {
    try {
      await stopBrowser(browser);
    } finally {
      await stopDaemon(daemon);
    }
  });

  it('a typed expression gets a box fitted around its whole zero set', async () => {
    // A sphere of radius 1.5 about (3, 0.2, -1): outside the torus preset's box ±1.5.
    const c = [3, 0.2, -1], r = 1.5;
    const before = await loads(page);
    await page.fill('#expr', `(x - ${c[0]})^2 + (y - ${c[1]})^2 + (z + ${-c[2]})^2 - ${r * r}`);
    await page.click('#render');
    const key = await waitForMesh(page, before);
    const box = await boxFields();
    for (let a = 0; a < 3; a++) {
      assert.ok(box[a] <= c[a] - r && box[a + 3] >= c[a] + r, `axis ${a}: [${box[a]}, ${box[a + 3]}] contains the sphere`);
      assert.ok(box[a] >= -10 && box[a + 3] <= 10, 'within the default cube');
      assert.ok(box[a + 3] - box[a] < 2 * r + 1, `axis ${a}: fitted, not the cube (${box[a + 3] - box[a]})`);
    }
    const stats = await (await fetch(`${daemon.base}/v1/meshes/${key}/stats`)).json();
    assert.equal(stats.analysis.boundary_edges, 0, 'the sphere is not cut by the box');
    assert.equal(stats.analysis.euler, 2);
    assert.equal(await page.isChecked('#keep-box'), false);
  });

  it('the box outline and the axes with ticks are drawn', async () => {
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const withBox = await viewShot(page, 'fitted-box.png');
    await page.uncheck('#show-box');
    const without = await viewShot(page);
    assert.ok(changedShare(withBox, without) > 0.002, `the outline shows (${changedShare(withBox, without)})`);
    await page.check('#show-box');
    await page.check('#show-axes');
    const axes = await viewShot(page, 'fitted-box-axes.png');
    assert.ok(changedShare(withBox, axes) > 0.002, 'the axes show');
    await page.uncheck('#show-axes');
  });

  it('a box typed by hand is kept for the next expression', async () => {
    await page.click('#box-section summary');
    await page.fill('#box-xmax', '6');
    await page.locator('#box-xmax').press('Tab');
    assert.equal(await page.isChecked('#keep-box'), true);
    const kept = await boxFields();
    const before = await loads(page);
    await page.fill('#expr', 'x^2 + y^2 + z^2 - 0.25');
    await page.click('#render');
    await waitForMesh(page, before);
    assert.deepEqual(await boxFields(), kept);
  });

  it('the gallery is searchable and states facts the mesh has', async () => {
    const total = (await (await fetch(`${daemon.base}/v1/presets`)).json()).presets.length;
    assert.ok(total >= 40, `${total} gallery entries`);
    await page.fill('#gallery-search', 'cayley');
    const shown = Number(await page.evaluate(() => document.body.dataset.galleryShown));
    assert.ok(shown >= 1 && shown < total, `${shown} of ${total} kept`);
    const n = await loads(page);
    await page.locator('#gallery-search').press('Enter');
    await waitForMesh(page, n);
    assert.equal(await page.inputValue('#preset'), 'cayley-cubic');
    assert.match(await page.textContent('#preset-source'), /Cayley.*checked on the mesh: 4 nodes/);
    await page.fill('#gallery-search', '');
  });

  it('the gallery shows the daemon\'s own thumbnails, only those in view', async () => {
    // Searching first keeps one picture in the strip: opening it loads that one alone.
    await page.fill('#gallery-search', 'cayley');
    await page.click('#gallery-pictures summary');
    await page.waitForFunction(() => document.querySelector('.thumb[data-preset="cayley-cubic"]')?.dataset.loaded === 'yes', null, { timeout: 120000 });
    const got = await page.evaluate(() => {
      const b = document.querySelector('.thumb[data-preset="cayley-cubic"]');
      const img = b.querySelector('img');
      return { w: img.naturalWidth, h: img.naturalHeight, current: b.classList.contains('current'),
               asked: document.querySelectorAll('.thumb[data-loaded]').length,
               shown: [...document.querySelectorAll('.thumb')].filter((t) => !t.hidden).length };
    });
    assert.deepEqual([got.w, got.h], [160, 120]);
    assert.ok(got.current, 'the current preset is marked');
    assert.ok(got.asked <= got.shown && got.shown < 10, `${got.asked} pictures asked for, ${got.shown} shown`);
    await page.click('#gallery-pictures summary');
    await page.fill('#gallery-search', '');
    assert.deepEqual(errors, []);
  });

  it('picking a node of the Cayley cubic shows its type, coordinates (closed form) and f = 0, grad f = 0 there', async () => {
    const nodes = [[-0.5, -0.5, -0.5], [-0.5, 0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, -0.5]];
    const picks = await pickSingularPoints(page);
    assert.equal(picks.length, 4, 'four singular points drawn');
    for (const p of picks) {
      assert.equal(p.type, 'node');
      assert.match(p.text, /^node point \(certified by \w+ within [0-9.e-]+\)/);
      assert.equal(p.certified, 'true');
      assert.match(p.text, /^node point.*\n.*\n.*\nf = .*\|∇f\| = .*\nH = /s);
      const err = nearest(nodes, p.xyz);
      assert.ok(err < 1e-6, `picked (${p.xyz}) is ${err} from the nearest closed-form node`);
      // f and its gradient there, from the server: a node is a zero of both (|f| is quadratic
      // and |grad f| linear in the distance to it; |grad f|'s second derivatives are below 40).
      assert.ok(Math.abs(p.probe.f) < 1e-9, `f = ${p.probe.f} at the node`);
      assert.ok(p.probe.grad_norm < 40 * Math.max(err, 1e-12) + 1e-9, `|grad f| = ${p.probe.grad_norm} at the node`);
    }
  });

  it('saves the view as a PNG of the requested size, larger than the screen', async () => {
    // 1600 x 1000: larger than the browser window (1280 x 800; the view is smaller still), so
    // the export is drawn at its own resolution, not copied from the canvas on screen.
    await page.fill('#png-width', '1600');
    await page.fill('#png-height', '1000');
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#png-export')]);
    const bytes = fs.readFileSync(await download.path());
    fs.writeFileSync(artifact('export-cayley-cubic.png'), bytes);
    const img = decodePng(bytes);
    assert.deepEqual([img.width, img.height], [1600, 1000]);
    assert.ok(pixelStats(img).foreground > 0.03, 'the surface is in the picture');
    assert.match(download.suggestedFilename(), /^cayley-cubic\.png$/);
  });

  it('the clipping plane draws the section curve on the surface; inside and outside differ', async () => {
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const plain = await viewShot(page);
    await page.uncheck('#two-sided');
    const oneColour = await viewShot(page);
    assert.ok(changedShare(plain, oneColour) > 0.005, `the inside has its own colour (${changedShare(plain, oneColour)})`);
    await page.check('#two-sided');
    await page.check('#clip-on');
    await page.selectOption('#clip-axis', 'z');
    const cut = await viewShot(page, 'cayley-cubic-section.png');
    const seg = await page.evaluate(() => ({ s: window.isomeshViewer.sectionSegments, offset: window.isomeshViewer.clip.offset }));
    assert.ok(seg.s.length >= 6 * 20, `${seg.s.length / 6} section segments`);
    const f = (x, y, z) => 4 * (x * x + y * y + z * z) + 16 * x * y * z - 1;
    const grad = (x, y, z) => Math.hypot(8 * x + 16 * y * z, 8 * y + 16 * x * z, 8 * z + 16 * x * y);
    let worst = 0;
    for (let i = 0; i < seg.s.length; i += 3) {
      const [x, y, z] = seg.s.slice(i, i + 3);
      assert.equal(z, seg.offset, 'on the plane');
      worst = Math.max(worst, Math.abs(f(x, y, z)) / Math.max(grad(x, y, z), 1e-9));
    }
    assert.ok(worst < 0.01, `section points within ${worst} of the surface`);
    assertChanged(plain, cut);
    await page.uncheck('#clip-on');
  });

  it('picking a double curve shows its kind, that it is certified, a point on it (closed form) and f = 0, grad f = 0 there', async () => {
    // Two planes x = -0.3 z and y = 0.2 z (box off the lattice): they cross in the line
    // t (-0.3, 0.2, 1), where f = (x + 0.3 z)(y - 0.2 z) and its gradient vanish.
    const n = await loads(page);
    await page.evaluate(() => { location.hash = `expr=${encodeURIComponent('(x + 0.3*z)*(y - 0.2*z)')}&box=-1.0037,-0.9963,-1,1,1.0029,1&depth=3,5&err=off`; });
    await waitForMesh(page, n);
    const spot = await page.evaluate(() => {
      const v = window.isomeshViewer;
      const curves = v.features.pickables.filter((p) => p.what === 'curve');
      const at = curves[0].at[Math.floor(curves[0].at.length / 2)];
      const r = v.canvas.getBoundingClientRect();
      const q = new v.camera.position.constructor(...at).project(v.camera);
      return { count: curves.length, kind: curves[0].p.kind, x: r.left + (q.x + 1) / 2 * r.width, y: r.top + (1 - q.y) / 2 * r.height };
    });
    assert.equal(spot.count, 1, 'one singular curve');
    await page.mouse.click(spot.x, spot.y);
    await page.waitForSelector('#pick-info[data-what=curve][data-probe]:not([hidden])');
    const info = await page.$eval('#pick-info', (e) => ({ ...e.dataset, text: e.textContent }));
    assert.equal(info.type, 'double');
    // certified: every point of the line passed its certificate (core/singular/curve_cert.h),
    // within a square of half-width <= 0.5e-9 x the box diagonal (~1.7e-9)
    assert.equal(info.certified, 'true');
    const m = info.text.match(/^double curve \(certified within ([0-9.e-]+)\), \d+ points, box – box\nnear \(.*\)\nf = .*\|∇f\| = .*\nH = /);
    assert.ok(m, info.text);
    assert.ok(Number(m[1]) > 0 && Number(m[1]) <= 1.8e-9, `certificate radius ${m[1]}`);
    const p = info.xyz.split(',').map(Number);
    const d = [-0.3, 0.2, 1], dd = Math.hypot(...d);
    const t = (p[0] * d[0] + p[1] * d[1] + p[2] * d[2]) / dd;
    const off = Math.hypot(...p.map((v, k) => v - t * d[k] / dd));
    assert.ok(off < 1e-6, `picked (${p}) is ${off} from the line`);
    const probe = JSON.parse(info.probe);
    assert.ok(Math.abs(probe.f) < 1e-9 && probe.grad_norm < 1e-6, `f = ${probe.f}, |grad f| = ${probe.grad_norm} there`);
  });

  it('clicking the surface gives the point, f, |grad f| and curvature there', async () => {
    const n = await loads(page);
    await page.selectOption('#preset', 'sphere');
    await waitForMesh(page, n);
    const box = await page.locator('#view').boundingBox();
    await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
    await page.waitForSelector('#pick-info[data-what=surface]:not([hidden])');
    const info = await page.$eval('#pick-info', (e) => ({ ...e.dataset, text: e.textContent }));
    const p = JSON.parse(info.probe);
    const xyz = info.xyz.split(',').map(Number);
    const rho = Math.hypot(...xyz);
    assert.ok(Math.abs(rho - 1) < 0.01, `the point is on the unit sphere's mesh (|p| = ${rho})`);
    // f = |p|^2 - 1: closed forms at the picked point (the level set through it is a sphere).
    assert.ok(Math.abs(p.f - (rho * rho - 1)) < 1e-12);
    assert.ok(Math.abs(p.grad_norm - 2 * rho) < 1e-12);
    assert.ok(Math.abs(p.gauss_curvature * rho * rho - 1) < 1e-9, `K = ${p.gauss_curvature}`);
    assert.ok(Math.abs(Math.abs(p.mean_curvature) * rho - 1) < 1e-9, `H = ${p.mean_curvature}`);
    assert.match(info.text, /^surface point .*triangle \d+\nf = .*\|∇f\| = .*\nH = .*K = /);
  });

  it('the curvature colours span the chosen percentiles', async () => {
    await page.selectOption('#color-mode', 'gauss');
    await page.waitForSelector('#legend[data-mode=gauss]:not([hidden])');
    const spans = {};
    for (const cut of ['p2', 'p10', 'full']) {
      await page.selectOption('#color-range', cut);
      spans[cut] = await page.$eval('#legend', (e) => [Number(e.dataset.lo), Number(e.dataset.hi), Number(e.dataset.min), Number(e.dataset.max)]);
    }
    const [lo10, hi10] = spans.p10, [lo2, hi2] = spans.p2, [loF, hiF, min, max] = spans.full;
    assert.ok(lo2 <= lo10 && hi10 <= hi2, `10-90 % (${lo10}, ${hi10}) lies within 2-98 % (${lo2}, ${hi2})`);
    assert.ok(loF <= lo2 && hi2 <= hiF, 'the full range holds the others');
    assert.ok(loF <= min || hiF >= max, 'the full range reaches the data');
    // Each map keeps its own range: K at 10-90 %, H still at its 2-98 %, K's back.
    await page.selectOption('#color-range', 'p10');
    await page.selectOption('#color-mode', 'mean');
    await page.waitForSelector('#legend[data-mode=mean]:not([hidden])');
    assert.equal(await page.inputValue('#color-range'), 'p2');
    await page.selectOption('#color-mode', 'gauss');
    await page.waitForSelector('#legend[data-mode=gauss]:not([hidden])');
    assert.equal(await page.inputValue('#color-range'), 'p10');
    assert.deepEqual(await page.$eval('#legend', (e) => [Number(e.dataset.lo), Number(e.dataset.hi)]), spans.p10.slice(0, 2));
    await page.selectOption('#color-range', 'p2');
    await page.selectOption('#color-mode', 'shaded');
  });

  it('the Curves panel cuts the sphere into cells: curves drawn, cells coloured and picked', async () => {
    // The unit sphere (preset box ±1.5): 3 planes z = -0.75, 0, 0.75 cut 4 zones of area
    // 2 pi h (Archimedes): pi/2, 3 pi/2, 3 pi/2, pi/2.
    await sphereWithCurvesPanel();
    await page.selectOption('#curve-kind', 'plane');
    await page.selectOption('#curve-axis', 'z');
    await page.fill('#curve-count', '3');
    let n = await loads(page);
    await page.click('#curve-add');
    await waitForMesh(page, n);
    const facts = async () => page.evaluate(() => ({
      drawn: Number(document.body.dataset.curvesDrawn), cells: Number(document.body.dataset.cells),
      sections: window.isomeshViewer.data.features.curves.filter((c) => c.kind === 'section').length,
      faces: window.isomeshViewer.data.features.arrangement.faces.map((f) => f.area),
      hash: location.hash }));
    let f = await facts();
    assert.deepEqual([f.drawn, f.sections, f.cells], [3, 3, 4]);
    assert.match(await page.textContent('#curve-facts'), /; V − E \+ F = χ = 2\. /, 'the Euler check with its number');
    const zones = [Math.PI / 2, 1.5 * Math.PI];
    for (const a of f.faces) assert.ok(zones.some((z) => Math.abs(a - z) / z < 0.01), `cell area ${a} is a zone's 2 pi h`);
    assert.match(decodeURIComponent(f.hash), /curves=\[\{"kind":"plane","axis":"z","count":3\}\]/);

    await page.selectOption('#curve-axis', 'x');
    await page.fill('#curve-count', '1');
    n = await loads(page);
    await page.click('#curve-add');
    await waitForMesh(page, n);
    f = await facts();
    assert.deepEqual([f.drawn, f.cells], [4, 8], 'x = 0 halves every zone');
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const shaded = await viewShot(page, 'sphere-curves.png');
    await page.selectOption('#color-mode', 'cells');
    const cells = await viewShot(page, 'sphere-curves-cells.png');
    assertChanged(shaded, cells);

    const box = await page.locator('#view').boundingBox();
    await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
    await page.waitForSelector('#pick-info[data-cell]:not([hidden])');
    const info = await page.$eval('#pick-info', (e) => ({ ...e.dataset, text: e.textContent }));
    const area = Number(info.cellArea);
    assert.ok(zones.some((z) => Math.abs(area - z / 2) / (z / 2) < 0.01), `picked cell's area ${area} is half a zone`);
    assert.equal(info.cellEuler, '1', 'a cell of the cut sphere is a disk');
    assert.match(info.text, /^cell \d+: area .*χ = 1, 1 boundary cycle/);

    n = await loads(page);
    await page.click('#curve-list li:nth-child(2) button');
    await waitForMesh(page, n);
    assert.equal((await facts()).drawn, 3, 'removing the x plane leaves the z stack');
    await page.selectOption('#color-mode', 'shaded');
  });

  it('curves through a cone\'s node end there: the vertex typed, drawn and counted in the key', async () => {
    // x^2 + y^2 = z^2 cut by the plane x = 0 (the stack of one plane along x in a box
    // symmetric about the apex): the lines y = +-z through the node at the origin, one
    // singular_point vertex of degree 4 and four ends at the box.
    const url = `${daemon.base}/#expr=${encodeURIComponent('x^2 + y^2 - z^2')}&box=-1,-1,-1,1,1,1&depth=3,6&err=off` +
      `&curves=${encodeURIComponent(JSON.stringify([{ kind: 'plane', axis: 'x', count: 1 }]))}`;
    const cone = await openViewer(browser.context, url);
    try {
      const got = await cone.page.evaluate(() => {
        const a = window.isomeshViewer.data.features.arrangement;
        const key = (t) => { const e = document.querySelector(`#key-types .key-type-${t}`); return e ? [e.dataset.count, e.textContent] : null; };
        const drawn = window.isomeshViewer.curves.group.getObjectByName('curve-vertices-singular_point');
        return { types: a.vertices.map((v) => v.type).sort(), apex: a.vertices.find((v) => v.type === 'singular_point'),
          node: key('singular_point'), ends: key('end'), drawn: drawn ? drawn.children[1].count : 0 };
      });
      assert.deepEqual(got.types, ['end', 'end', 'end', 'end', 'singular_point']);
      assert.equal(got.apex.degree, 4);
      assert.ok(Math.hypot(...got.apex.xyz) < 1e-9, `the apex at the origin (${got.apex.xyz})`);
      assert.deepEqual(got.node, ['1', '1 singular point on the curves']); // one, in the singular
      assert.deepEqual(got.ends, ['4', '4 curve ends at the box']);
      assert.equal(got.drawn, 1, 'one marker at the node');
      assert.deepEqual(cone.errors, []);
    } finally {
      await cone.page.close();
    }
  });

  it('the panel adds level curves, an intersection and the silhouette of the view', async () => {
    // On the unit sphere (the z stack of the test above stays, when it ran): the level x = 0.5
    // is a circle; the cylinder (x - 1/2)^2 + y^2 = 1/4 meets it in Viviani's curve, which
    // crosses itself at (1, 0, 0); the silhouette along d is the great circle p . d = 0.
    await sphereWithCurvesPanel();
    const add = async (kind, fill) => {
      await page.selectOption('#curve-kind', kind);
      for (const [sel, v] of Object.entries(fill)) await page.fill(sel, v);
      const n = await loads(page);
      await page.click('#curve-add');
      await waitForMesh(page, n);
    };
    const curves = (kind) => page.evaluate((k) => window.isomeshViewer.data.features.curves
      .filter((c) => c.kind === k).map((c) => c.arcs.flatMap((a) => { const p = []; for (let i = 0; i < a.length; i += 3) p.push(a.slice(i, i + 3)); return p; })), kind);
    const onSphere = (p) => Math.abs(Math.hypot(...p) - 1) < 1e-6;
    const before = await viewShot(page);

    await add('levels', { '#curve-level-expr': 'x', '#curve-level-values': '0.5' });
    const level = await curves('level');
    assert.equal(level.length, 1, 'one level curve x = 0.5');
    assert.ok(level[0].length > 10 && level[0].every((p) => onSphere(p) && Math.abs(p[0] - 0.5) < 1e-6), 'on the sphere and at x = 0.5');

    await add('surface', { '#curve-surface-expr': '(x - 0.5)^2 + y^2 - 0.25' });
    const viviani = (await curves('intersection')).flat();
    assert.ok(viviani.length > 10 && viviani.every((p) => onSphere(p) && Math.abs((p[0] - 0.5) ** 2 + p[1] ** 2 - 0.25) < 1e-6), 'on the sphere and the cylinder');
    const near = (p) => Math.hypot(p[0] - 1, p[1], p[2]) < 1e-6;
    const node = await page.evaluate(() => window.isomeshViewer.data.features.arrangement.vertices
      .filter((v) => Math.hypot(v.xyz[0] - 1, v.xyz[1], v.xyz[2]) < 1e-6).map((v) => v.degree));
    const through = (await curves('section')).filter((c) => c.some(near)).length;  // z = 0 of the stack
    assert.deepEqual(node, [4 + 2 * through], `Viviani's curve crosses itself at (1, 0, 0): degree 4, + 2 per plane there (${through})`);

    const view = await page.evaluate(() => { const v = window.isomeshViewer.getView(); return v.pos.map((p, k) => p - v.target[k]); });
    await add('silhouette', {});
    const entry = JSON.parse(decodeURIComponent(await page.evaluate(() => location.hash)).match(/curves=(\[.*?\])(&|$)/)[1])
      .find((e) => e.kind === 'silhouette');
    const d = entry.direction, len = Math.hypot(...view);
    d.forEach((x, k) => assert.ok(Math.abs(x - view[k] / len) < 1e-5, `the direction is the view's (${d})`));
    const sil = (await curves('silhouette')).flat();
    assert.ok(sil.length > 10 && sil.every((p) => onSphere(p) && Math.abs(p[0] * d[0] + p[1] * d[1] + p[2] * d[2]) < 1e-5), 'the great circle across the view');
    const f = await page.evaluate(() => ({ list: document.querySelectorAll('#curve-list li').length,
      ok: window.isomeshViewer.data.features.arrangement.euler.ok, drawn: Number(document.body.dataset.curvesDrawn) }));
    assert.ok(f.ok, 'V - E + F = chi');
    assert.ok(f.list >= 3 && f.drawn >= 3, `three more entries listed and drawn (${f.list}, ${f.drawn})`);
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    assertChanged(before, await viewShot(page, 'sphere-level-intersection-silhouette.png'));
  });

  it('double sheets are tinted (the double_sheet attribute of the Draco mesh)', async () => {
    // s1 * s2^2: the sphere about (0.5, 0, 0) crosses zero, the one about (-0.5, 0, 0) is a
    // double sheet. The pixel at each centre's projection shows its colour.
    const n = await loads(page);
    const expr = '((x-0.5)^2+y^2+z^2-0.16) * ((x+0.5)^2+y^2+z^2-0.16)^2';
    await page.evaluate((e) => { location.hash = `expr=${encodeURIComponent(e)}&box=-1.1,-0.6,-0.6,1.1,0.6,0.6&depth=3,5&err=off&cam=0,-4,0,0,0,0`; }, expr);
    await waitForMesh(page, n);
    assert.equal(await page.$eval('.key-sheets', (e) => e.hidden), false, 'the key names the double sheets');
    const img = await viewShot(page, 'double-sheet-tint.png');
    const px = await page.evaluate(() => [[-0.5, -0.4, 0], [0.5, -0.4, 0]].map((p) => {
      const v = window.isomeshViewer;
      const q = new v.camera.position.constructor(...p).project(v.camera);
      return [Math.round((q.x + 1) / 2 * v.canvas.clientWidth), Math.round((1 - q.y) / 2 * v.canvas.clientHeight)];
    }));
    const [sheet, plain] = px.map(([x, y]) => Array.from(img.rgba.subarray(4 * (y * img.width + x), 4 * (y * img.width + x) + 3)));
    assert.ok(sheet[0] > sheet[1] + 25 && sheet[2] > sheet[1] + 25, `the double sheet is violet (${sheet})`);
    assert.ok(plain[2] >= plain[0] && plain[0] - plain[1] < 25, `the other sphere keeps the surface colour (${plain})`);

  });

  it('the render mode: ambient occlusion per vertex, as the closed form of two spheres says', async () => {
    // Two spheres of radius 0.4 about (-0.5, 0, 0) and (0.5, 0, 0). The point of the left one
    // nearest the right one, (-0.1, 0, 0), sees the right sphere as a cap of half-angle
    // asin(0.4 / 0.6) about its normal: the cosine-weighted light it keeps is
    // 1 - sin^2 = 1 - (0.4 / 0.6)^2 = 5/9. The point farthest from it, (-0.9, 0, 0), has
    // nothing over its hemisphere (light 1); inside a closed sphere every direction is shut
    // (light 0).
    const n = await loads(page);
    await page.evaluate(() => { location.hash = 'expr=((x-0.5)%5E2%2By%5E2%2Bz%5E2-0.16)*((x%2B0.5)%5E2%2By%5E2%2Bz%5E2-0.16)&box=-1.1,-0.6,-0.6,1.1,0.6,0.6&depth=3,5&err=off&cam=0.6,-3,2,0,0,0'; });
    await waitForMesh(page, n);
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const plain = await viewShot(page);
    await page.check('#occlusion');
    await page.waitForFunction(() => document.getElementById('view').dataset.look === 'occlusion', null, { timeout: 120000 });
    await page.waitForSelector('#message', { state: 'hidden' });   // 'Computing the ambient occlusion…' is gone
    const ao = await viewShot(page, 'spheres-occlusion.png');
    const got = await page.evaluate(() => {
      const g = window.isomeshViewer.surface.geometry;
      const p = g.attributes.position.array, light = g.attributes.occlusion.array;
      const nearest = (q) => {
        let best = 0, bd = Infinity;
        for (let i = 0; i < p.length / 3; i++) {
          const d = Math.hypot(p[3 * i] - q[0], p[3 * i + 1] - q[1], p[3 * i + 2] - q[2]);
          if (d < bd) { bd = d; best = i; }
        }
        return best;
      };
      let inside = 0;
      for (let i = 1; i < light.length; i += 2) inside = Math.max(inside, light[i]);
      return { gap: light[2 * nearest([-0.1, 0, 0])], open: light[2 * nearest([-0.9, 0, 0])], inside, ms: window.isomeshViewer.occlusionMs };
    });
    console.log(`# occlusion: light at the gap ${got.gap.toFixed(3)} (closed form ${(5 / 9).toFixed(3)}), opposite ${got.open.toFixed(3)}, inside at most ${got.inside.toFixed(3)}; computed in ${got.ms.toFixed(0)} ms`);
    assert.ok(Math.abs(got.gap - 5 / 9) < 0.12, `light at the gap ${got.gap}`);
    assert.ok(got.open > 0.95, `light opposite ${got.open}`);
    assert.ok(got.inside < 0.1, `inside ${got.inside}`);
    // The picture darkens where the spheres face each other, and keeps its outline: pixels
    // near the page's background colour (its corner) in one picture and not in the other are few.
    assert.ok(changedShare(plain, ao) > 0.002, `the picture changed (${changedShare(plain, ao)})`);
    const corner = 4 * (10 * plain.width + 10);
    const bg = Array.from(plain.rgba.subarray(corner, corner + 3));
    const isBg = (im, i) => Math.abs(im.rgba[i] - bg[0]) + Math.abs(im.rgba[i + 1] - bg[1]) + Math.abs(im.rgba[i + 2] - bg[2]) < 40;
    let flipped = 0, background = 0, darker = 0;
    for (let i = 0; i < plain.rgba.length; i += 4) {
      if (isBg(plain, i)) background++;
      if (isBg(plain, i) !== isBg(ao, i)) flipped++;
      darker += plain.rgba[i] + plain.rgba[i + 1] + plain.rgba[i + 2] - ao.rgba[i] - ao.rgba[i + 1] - ao.rgba[i + 2];
    }
    const pixels = plain.width * plain.height;
    assert.ok(background > 0.2 * pixels && background < 0.95 * pixels, `background ${background} of ${pixels} pixels`);
    assert.ok(flipped < 0.005 * pixels, `the same outline (${flipped} pixels changed sides)`);
    assert.ok(darker > 0, 'occlusion only darkens');
    assert.match(await settledHref(page), /[#&]ao=1(&|$)/);
    await page.uncheck('#occlusion');
  });

  it('the occlusion is computed in the background, plain first, and a clipped half occludes nothing', async () => {
    // The two spheres of the test before (its mesh is on screen). Cut at x = 0 keeping x < 0:
    // the left sphere stays whole and alone, and a lone sphere is convex — nothing over any
    // outside point's hemisphere — so its occluded picture must equal its plain one. Uncut, the
    // right sphere darkens the left one where they face each other (light 5/9 at the gap).
    const win = await page.evaluate(() => {
      // A point of the left sphere (centre (-0.5, 0, 0), radius 0.4) facing the right one and
      // the camera, projected to view pixels.
      const v = window.isomeshViewer;
      const n = new v.camera.position.constructor(1, -0.3, 0.15).normalize();
      const q = n.clone().multiplyScalar(0.4).add(new v.camera.position.constructor(-0.5, 0, 0)).project(v.camera);
      return [Math.round((q.x + 1) / 2 * v.canvas.clientWidth), Math.round((1 - q.y) / 2 * v.canvas.clientHeight)];
    });
    const mean = (img) => {           // mean RGB sum over a 7x7 window at win
      let s = 0;
      for (let dy = -3; dy <= 3; dy++) for (let dx = -3; dx <= 3; dx++) {
        const i = 4 * ((win[1] + dy) * img.width + win[0] + dx);
        s += img.rgba[i] + img.rgba[i + 1] + img.rgba[i + 2];
      }
      return s / 49;
    };
    const darkened = (plain, ao) => {  // share of pixels more than 10% darker with occlusion
      let k = 0;
      for (let i = 0; i < plain.rgba.length; i += 4) {
        const a = plain.rgba[i] + plain.rgba[i + 1] + plain.rgba[i + 2], b = ao.rgba[i] + ao.rgba[i + 1] + ao.rgba[i + 2];
        if (b < 0.9 * a - 6) k++;
      }
      return k / (plain.width * plain.height);
    };
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const plainWhole = await viewShot(page);
    await page.check('#occlusion');      // the uncut mesh's occlusion is held: no computation
    await page.waitForFunction(() => document.getElementById('view').dataset.look === 'occlusion', null, { timeout: 120000 });
    const aoWhole = await viewShot(page);
    await page.uncheck('#occlusion');
    await page.check('#clip-on');
    await page.selectOption('#clip-axis', 'x');
    assert.equal(await page.inputValue('#clip-offset'), '0');
    assert.equal(await page.isChecked('#clip-flip'), false, 'the half towards the camera (x > 0) is cut away');
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const plainCut = await viewShot(page, 'spheres-cut-plain.png');

    // Turn the render mode on with the cut: a new occlusion is computed. Record every animation
    // frame (its time and look) and answer a click while it runs. On a loaded machine the bake
    // (~1.5 s) can end before the test's click reaches the page: that attempt proves nothing
    // either way, so it is repeated with a new cut (each cut is baked anew; offsets down to
    // -0.02 still keep the whole left sphere, x <= -0.1, and cut the right one away).
    const attempt = async () => {
      await page.evaluate(() => {
        const rec = { frames: [], click: null, done: false, drawnBefore: window.isomeshViewer.frames, longTasks: [] };
        window.aoRecord = rec;
        // Main-thread tasks over 50 ms (the Long Tasks API), printed below.
        rec.observer = new PerformanceObserver((l) => {
          for (const e of l.getEntries()) rec.longTasks.push({ t: e.startTime, ms: e.duration });
        });
        rec.observer.observe({ type: 'longtask' });
        const view = document.getElementById('view');
        const tick = () => {
          rec.frames.push({ t: performance.now(), look: view.dataset.look, state: view.dataset.occlusion });
          if (view.dataset.look === 'occlusion') { rec.done = true; return; }
          requestAnimationFrame(tick);
        };
        requestAnimationFrame(tick);
      });
      await page.check('#occlusion');
      await page.waitForFunction(() => document.getElementById('view').dataset.occlusion === 'computing', null, { timeout: 30000, polling: 20 });
      await page.evaluate(() => document.addEventListener('click', () => {
        window.aoRecord.click = { t: performance.now(), state: document.getElementById('view').dataset.occlusion };
      }, { once: true }));
      await page.click('#preset-about');
      await page.waitForFunction(() => window.aoRecord.done, null, { timeout: 120000 });
      await page.waitForSelector('#message', { state: 'hidden' });
      return page.evaluate(() => {
        const r = window.aoRecord;
        r.observer.disconnect();
        delete r.observer;
        return { ...r, drawn: window.isomeshViewer.frames - r.drawnBefore };
      });
    };
    let rec = await attempt();
    for (const offset of ['-0.01', '-0.02']) {
      if (rec.click && rec.click.state === 'computing') break;
      console.log(`# the bake ended before the click arrived (${JSON.stringify(rec.click)}): again at x = ${offset}`);
      await page.uncheck('#occlusion');
      await page.$eval('#clip-offset', (e, v) => { e.value = v; e.dispatchEvent(new Event('input', { bubbles: true })); }, offset);
      rec = await attempt();
    }
    const busy = rec.frames.filter((f) => f.state === 'computing');
    const gaps = rec.frames.slice(1).map((f, i) => f.t - rec.frames[i].t);
    const span = busy.length ? busy.at(-1).t - busy[0].t : 0;
    const bakeMs = await page.evaluate(() => window.isomeshViewer.occlusionMs);
    console.log(`# occlusion in the background: computed in ${bakeMs.toFixed(0)} ms; ${busy.length} frames meanwhile, longest gap ${Math.max(...gaps).toFixed(0)} ms; click answered while computing: ${rec.click && rec.click.state === 'computing'}`);
    assert.equal(rec.frames[0].look, 'plain', 'the plain surface is drawn first');
    assert.ok(rec.click && rec.click.state === 'computing', `a click is answered while the occlusion is computed (${JSON.stringify(rec.click)})`);
    // A computation that held the page would leave at most one frame in the 'computing' state
    // (drawn before it started): three or more say it yielded between its batches. Gaps and
    // spans are printed only — on a loaded machine the scheduler sets them, not the page.
    assert.ok(busy.length >= 3, `${busy.length} frames while computing (span ${span.toFixed(0)} ms of ${bakeMs.toFixed(0)})`);
    // The surface is drawn (into the canvas) once, when the occlusion is there: while it is
    // computed the picture does not change, and in software GL each frame of a large mesh holds
    // the page until the GPU has drawn it (the compositor reads the canvas back).
    assert.equal(rec.drawn, 1, `${rec.drawn} frames of the surface drawn from the check to the occluded picture`);
    const tasks = rec.longTasks.filter((x) => x.t >= rec.frames[0].t);
    console.log(`# long tasks (> 50 ms) from the check to the occluded picture: ${tasks.length}, longest ${tasks.length ? Math.max(...tasks.map((x) => x.ms)).toFixed(0) : 0} ms (tests/bench/occlusion_pauses.mjs measures a large mesh)`);
    const aoCut = await viewShot(page, 'spheres-cut-occlusion.png');

    const whole = mean(aoWhole) / mean(plainWhole), cut = mean(aoCut) / mean(plainCut);
    const dWhole = darkened(plainWhole, aoWhole), dCut = darkened(plainCut, aoCut);
    console.log(`# occluded / plain brightness where the spheres face each other: ${whole.toFixed(3)} uncut, ${cut.toFixed(3)} with the right sphere cut away; pixels >10% darker: ${(100 * dWhole).toFixed(2)}% uncut, ${(100 * dCut).toFixed(2)}% cut`);
    assert.ok(whole < 0.92, `uncut, the right sphere darkens the left (${whole})`);
    assert.ok(cut > 0.97, `cut away, it darkens nothing (${cut})`);
    assert.ok(dWhole > 0.002, `uncut: ${dWhole} of the pixels darker`);
    assert.ok(dCut < 0.001, `cut: ${dCut} of the pixels darker`);
    await page.uncheck('#occlusion');
    await page.uncheck('#clip-on');
  });

  it('left no page errors', () => {
    assert.deepEqual(errors, []);
  });
});
