// explore.test.mjs — the box and inspection in the viewer: a typed expression gets a box
// fitted around its zero set (POST /v1/box) that contains the whole surface (closed form:
// an off-centre sphere) and the mesh is not cut (no boundary edges); the box outline and
// the axes with ticks change the picture; a box typed by hand is kept.
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startDaemon, stopDaemon, startBrowser, stopBrowser } from './lib/harness.mjs';
import { openViewer, waitForMesh, loads, viewShot } from './lib/page.mjs';
import { changedShare } from './lib/png.mjs';

let daemon = null;
let browser = null;
let page = null;
let errors = [];

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

  it('left no page errors', () => {
    assert.deepEqual(errors, []);
  });
});
