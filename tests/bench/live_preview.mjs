// live_preview.mjs — the viewer's live exploration, timed on every preset that has a
// parameter: a real isomeshd (2 workers) and headless Chromium; drag the first slider over a
// third of its range and measure, in the page by pixel difference, the time from the first
// move to a changed picture (goal 300 ms), beside the server's time for the last preview (its
// stats' timings_ms.total: the rest is queueing, transfer, decoding and drawing) and the time
// the refined mesh took. Prints one line per drag, a summary and the load average at both
// ends (on a shared machine the figures mean little without it); asserts nothing
// (bench_live.py runs it for `make bench`).
import { startDaemon, stopDaemon, startBrowser, stopBrowser } from '../browser/lib/harness.mjs';
import { openViewer, waitForMesh, loads } from '../browser/lib/page.mjs';
import { dragAndTime, breakdown } from '../browser/lib/live.mjs';
import os from 'node:os';

const GOAL_MS = 300;
const ROUNDS = 2;   // two drags a preset (the second starts from a warm page)

const loadAtStart = os.loadavg()[0];
const daemon = await startDaemon();
const browser = await startBrowser();
const rows = [];
try {
  // LIVE_PRESETS=a,b limits the run to those presets (a quick look), else every one with a parameter.
  const only = (process.env.LIVE_PRESETS || '').split(',').filter(Boolean);
  const presets = (await (await fetch(`${daemon.base}/v1/presets`)).json()).presets
    .filter((p) => p.params.length && (!only.length || only.includes(p.name)));
  const { page } = await openViewer(browser.context, `${daemon.base}/#preset=${presets[0].name}`);
  for (const p of presets) {
    if ((await page.inputValue('#preset')) !== p.name) {
      const n = await loads(page);
      await page.selectOption('#preset', p.name);
      await waitForMesh(page, n, 120000);
    }
    const q = p.params[0];
    for (let round = 0; round < ROUNDS; round++) {
      const from = Number(await page.inputValue(`#param-${q.name}-value`));
      const span = (q.max - q.min) / 3;
      const target = Number((from + span <= q.max ? from + span : from - span).toPrecision(6));
      const t0 = Date.now();
      const r = await dragAndTime(page, q.name, target, 20000);
      rows.push({ preset: p.name, param: q.name, ms: r.ms, refinedMs: Date.now() - t0 });
      const shown = r.ms === null ? 'never' : `${r.ms.toFixed(0)} ms`;
      const preview = r.previewKey ? await (await fetch(`${daemon.base}/v1/meshes/${r.previewKey}/stats`)).json() : null;
      const server = preview ? `${preview.timings_ms.total.toFixed(0)} ms` : '–';
      console.log(`${p.name.padEnd(18)} ${q.name.padEnd(4)} -> ${String(target).padEnd(8)} changed picture ${shown.padStart(8)}` +
        `${r.ms !== null && r.ms <= GOAL_MS ? '' : '  (over the goal)'}   last preview computed in ${server.padStart(7)}` +
        `   refined mesh on screen after ${(rows.at(-1).refinedMs / 1000).toFixed(1)} s\n    ${breakdown(r)}`);
    }
  }
} finally {
  await stopBrowser(browser);
  await stopDaemon(daemon);
}
const times = rows.map((r) => (r.ms === null ? Infinity : r.ms)).sort((a, b) => a - b);
const median = times[Math.floor(times.length / 2)];
console.log(`live preview: ${rows.length} drags, median ${median.toFixed(0)} ms, worst ${times.at(-1).toFixed(0)} ms, ` +
  `${times.filter((t) => t <= GOAL_MS).length}/${rows.length} within the ${GOAL_MS} ms goal; ` +
  `load average ${loadAtStart.toFixed(1)} at the start, ${os.loadavg()[0].toFixed(1)} at the end (${os.cpus().length} cores)`);
