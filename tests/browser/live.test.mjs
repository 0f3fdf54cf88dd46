// live.test.mjs — live exploration in the viewer: dragging a parameter slider shows a coarse
// preview (a low-depth mesh from the same workers) before the slider rests, then the refined
// mesh replaces it with no blank frame in between. The time from the first move to a changed
// picture is measured in the page by pixel difference and printed; the 300 ms goal is the
// benchmark's (tests/bench/live_preview.mjs), here only a generous bound is asserted, since
// this machine is shared.
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startDaemon, stopDaemon, startBrowser, stopBrowser } from './lib/harness.mjs';
import { openViewer, waitForMesh, loads } from './lib/page.mjs';
import { dragAndTime, breakdown } from './lib/live.mjs';

// Loose: a loaded 2-core machine may be far slower than the goal; a preview that never comes
// (the picture changing only with the refined mesh, seconds later) still fails.
const LOOSE_MS = 4000;
const GOAL_MS = 300;

let daemon = null;
let browser = null;
let page = null;
let errors = [];

async function stats(key) {
  const r = await fetch(`${daemon.base}/v1/meshes/${key}/stats`);
  assert.equal(r.status, 200);
  return r.json();
}

describe('live exploration', { timeout: 300000 }, () => {
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

  for (const [preset, param, target] of [['torus', 'r', 0.45], ['kummer-16-nodes', 'mu2', 2.5], ['horn-cyclide', 'r', 3]]) {
    it(`${preset}: dragging ${param} shows a preview at once, then the refined mesh without a flash`, async () => {
      if ((await page.inputValue('#preset')) !== preset) {
        const n = await loads(page);
        await page.selectOption('#preset', preset);
        await waitForMesh(page, n);
      }
      const previewsBefore = Number(await page.evaluate(() => document.body.dataset.previews || 0));
      const r = await dragAndTime(page, param, target);
      const fine = await stats(r.finalKey);
      const coarse = await stats(r.previewKey);
      console.log(`# ${preset}: slider move -> changed picture ${r.ms === null ? 'never' : r.ms.toFixed(0) + ' ms'} (goal ${GOAL_MS} ms); ${r.previews - previewsBefore} previews, the last computed in ${coarse.timings_ms.total.toFixed(0)} ms (${coarse.mesh.triangles} triangles)\n#   ${breakdown(r)}`);
      assert.notEqual(r.ms, null, 'the picture changed');
      assert.ok(r.ms < LOOSE_MS, `${r.ms} ms to a changed picture`);
      assert.ok(r.previews > previewsBefore, 'a preview was shown before the refined mesh');
      assert.equal(r.shown, 'final');
      assert.ok(r.coverage.min > 0.5 * r.coverage.max, `no blank frame while the preview is replaced (${JSON.stringify(r.coverage)})`);
      assert.ok(coarse.preview && coarse.preview.skipped.includes('singular'), 'the preview was asked for in the server\'s preview mode');
      assert.ok(coarse.mesh.triangles < fine.mesh.triangles, `preview ${coarse.mesh.triangles} < refined ${fine.mesh.triangles} triangles`);
      assert.equal(Number(await page.inputValue(`#param-${param}-value`)), target);
    });
  }

  it('left no page errors', () => {
    assert.deepEqual(errors, []);
  });
});
