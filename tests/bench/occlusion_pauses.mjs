// occlusion_pauses.mjs — how long the render mode's ambient occlusion holds the page on a large
// mesh (gyroid-ball, 59k vertices; web/js/occlusion.js): main-thread tasks over 50 ms (Long
// Tasks API) from checking "render mode" until the occluded picture is drawn, beside the GPU
// time of one plain frame of the same mesh (in software GL the compositor reads every frame
// back, so the frame that shows the result holds the page about that long). Printed by
// tests/bench/bench_live.py, never asserted.
import { startDaemon, stopDaemon, startBrowser, stopBrowser } from '../browser/lib/harness.mjs';
import { openViewer } from '../browser/lib/page.mjs';

const preset = process.argv[2] || 'gyroid-ball';
const daemon = await startDaemon();
const browser = await startBrowser();
try {
  const { page } = await openViewer(browser.context, `${daemon.base}/#preset=${preset}`);
  await page.evaluate(() => {
    window.longTasks = [];
    new PerformanceObserver((l) => {
      for (const e of l.getEntries()) window.longTasks.push({ t: e.startTime, ms: e.duration });
    }).observe({ type: 'longtask' });
  });
  const t0 = await page.evaluate(() => performance.now());
  await page.check('#occlusion');
  await page.waitForFunction(() => document.getElementById('view').dataset.look === 'occlusion', null, { timeout: 600000 });
  await page.evaluate(() => window.isomeshViewer.settled());
  const r = await page.evaluate(() => ({ tasks: window.longTasks, bake: window.isomeshViewer.occlusionMs,
    frame: window.isomeshViewer.frameMs, n: window.isomeshViewer.surface.geometry.attributes.position.count }));
  const tasks = r.tasks.filter((x) => x.t >= t0);
  console.log(`${preset}: ${r.n} vertices, occlusion computed in ${r.bake.toFixed(0)} ms; one frame's GPU time ${r.frame.toFixed(0)} ms`);
  console.log(`  long tasks: ${tasks.map((x) => `${x.ms.toFixed(0)} ms at +${(x.t - t0).toFixed(0)}`).join(', ') || 'none'}`);
} finally {
  await stopBrowser(browser);
  await stopDaemon(daemon);
}
