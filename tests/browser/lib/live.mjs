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
        if (done) { resolve({ ms, coverage, t0 }); return; }
      }
      if (now - t0 > timeoutMs) { resolve({ ms, coverage, t0 }); return; }
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }), { name, target, steps: DRAG_STEPS, stepMs: DRAG_STEP_MS, share: CHANGED_SHARE, delta: CHANGE_DELTA, timeoutMs, before });
  const finalKey = await waitForMesh(page, before);
  const info = await page.evaluate((t0) => ({
    previews: Number(document.body.dataset.previews || 0), previewKey: document.body.dataset.previewKey || '',
    shown: document.body.dataset.shown,
    timeline: (window.isomeshTimeline || []).filter((e) => e.marks.asked >= t0),
  }), timed.t0);
  return { ...timed, finalKey, ...info };
}

// Where the time to the first picture after a drag went (web/js/timeline.js marks of the mesh
// whose frame was the last drawn before the picture was seen to change), as text: "wait 0 + post 12 + job 80 + fetch 9 + decode 15 +
// hand 30 + draw 20 + screen 90", each in ms ('screen': from the frame issued to the GPU to the
// pixel change seen by the page: the GPU's work and the compositor's).
export function breakdown(r) {
  const seenAt = r.ms === null ? Infinity : r.t0 + r.ms;
  const drawnBefore = r.timeline.filter((x) => x.marks.drawn !== undefined && x.marks.drawn <= seenAt);
  const e = drawnBefore.at(-1) || r.timeline.find((x) => x.marks.shown !== undefined);
  if (!e) return 'no mesh shown';
  const m = e.marks;
  const steps = [['wait', r.t0, m.asked], ['post', m.asked, m.posted], ['job', m.posted, m.done],
    ['fetch', m.done, m.fetched], ['decode', m.fetched, m.decoded], ['hand', m.decoded ?? m.asked, m.shown],
    ['draw', m.shown, m.drawn], ['screen', m.drawn, r.ms === null ? undefined : r.t0 + r.ms]];
  const nth = r.timeline.filter((x) => x.marks.shown !== undefined).indexOf(e) + 1;
  return `${e.preview ? 'preview' : 'refined'} #${nth}: ` + steps.filter(([, a, b]) => a !== undefined && b !== undefined)
    .map(([name, a, b]) => `${name} ${Math.round(b - a)}`).join(' + ');
}
