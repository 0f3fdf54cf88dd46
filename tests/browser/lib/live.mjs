// live.mjs — measures live exploration in a viewer page: moves a parameter slider the way a
// drag does (a series of input events) and times, inside the page, how long the canvas takes
// to show a changed picture (pixel difference against the picture before the move), then
// waits for the refined mesh. Shared by tests/browser/live.test.mjs and the benchmark
// tests/bench/live_preview.mjs.
import { waitForMesh, loads } from './page.mjs';

// A picture has changed when this share of its pixels moved by more than CHANGE_DELTA (sum of
// channel differences): well above antialiasing noise, well below what a reshaped surface does.
export const CHANGED_SHARE = 0.001;
const CHANGE_DELTA = 30;
// How long a drag lasts and how often it moves the slider (a hand moves it ~30 times a second).
const DRAG_STEPS = 6;
const DRAG_STEP_MS = 35;

// Drags slider #param-NAME from its value towards target in DRAG_STEPS input events; returns
// {ms (first move to a changed canvas, or null within timeoutMs), coverage {min, max} (share
// of drawn pixels in every frame from the first change until the refined mesh is on screen:
// a flash would show as a dip), previews, finalKey, previewKey}. The refined mesh must arrive
// afterwards (waited for here).
export async function dragAndTime(page, name, target, timeoutMs = 20000) {
  const before = await loads(page);
  const timed = await page.evaluate(({ name, target, steps, stepMs, share, delta, timeoutMs, before }) => new Promise((resolve) => {
    const view = document.getElementById('view');
    const w = 200, h = Math.max(1, Math.round(200 * view.height / view.width));
    const probe = document.createElement('canvas');
    probe.width = w;
    probe.height = h;
    const ctx = probe.getContext('2d', { willReadFrequently: true });
    const grab = () => { ctx.clearRect(0, 0, w, h); ctx.drawImage(view, 0, 0, w, h); return ctx.getImageData(0, 0, w, h).data; };
    const base = grab();
    const changed = (img) => {
      let n = 0;
      for (let i = 0; i < img.length; i += 4) {
        if (Math.abs(img[i] - base[i]) + Math.abs(img[i + 1] - base[i + 1]) + Math.abs(img[i + 2] - base[i + 2]) > delta) n++;
      }
      return n / (w * h);
    };
    const slider = document.getElementById(`param-${name}`);
    const v0 = Number(slider.value);
    const t0 = performance.now();
    for (let k = 1; k <= steps; k++) {
      setTimeout(() => {
        slider.value = String(v0 + (target - v0) * k / steps);
        slider.dispatchEvent(new Event('input', { bubbles: true }));
      }, (k - 1) * stepMs);
    }
    const drawn = (img) => {
      let n = 0;
      for (let i = 3; i < img.length; i += 4) if (img[i] > 0) n++;
      return n / (w * h);
    };
    let ms = null;
    const coverage = { min: Infinity, max: 0 };
    const tick = () => {
      const now = performance.now();
      const img = grab();
      if (ms === null && changed(img) > share) ms = now - t0;
      if (ms !== null) {
        const c = drawn(img);
        coverage.min = Math.min(coverage.min, c);
        coverage.max = Math.max(coverage.max, c);
        const done = Number(document.body.dataset.loads || 0) > before && document.body.dataset.shown === 'final';
        if (done) { resolve({ ms, coverage }); return; }
      }
      if (now - t0 > timeoutMs) { resolve({ ms, coverage }); return; }
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }), { name, target, steps: DRAG_STEPS, stepMs: DRAG_STEP_MS, share: CHANGED_SHARE, delta: CHANGE_DELTA, timeoutMs, before });
  const finalKey = await waitForMesh(page, before);
  const info = await page.evaluate(() => ({
    previews: Number(document.body.dataset.previews || 0), previewKey: document.body.dataset.previewKey || '',
    shown: document.body.dataset.shown,
  }));
  return { ...timed, finalKey, ...info };
}
