// page.mjs — small helpers over a viewer page: wait for the next mesh, read the stats panel,
// screenshot the 3D view, count the API requests the page made.
import fs from 'node:fs';
import { decodePng } from './png.mjs';
import { artifact, watchErrors } from './harness.mjs';

export async function loads(page) {
  return page.evaluate(() => Number(document.body.dataset.loads || 0));
}

// Waits until the page has shown more than `after` meshes and is idle; returns the mesh key.
export async function waitForMesh(page, after, timeout = 60000) {
  await page.waitForFunction((n) => Number(document.body.dataset.loads || 0) > n && document.body.dataset.busy !== '1',
    after, { timeout, polling: 50 });
  return page.evaluate(() => document.body.dataset.meshKey);
}

export async function openViewer(context, url) {
  const page = await context.newPage();
  const requests = [];
  const errors = watchErrors(page);
  page.on('request', (r) => requests.push({ method: r.method(), url: r.url(), headers: r.headers(), body: r.postData() }));
  await page.goto(url);
  await waitForMesh(page, 0);
  return { page, requests, errors };
}

// POST /v1/jobs the page made; refinedOnly: leave out live previews ("preview": true,
// web/js/live.js).
export function jobPosts(requests, { refinedOnly = false } = {}) {
  return requests.filter((r) => r.method === 'POST' && new URL(r.url).pathname === '/v1/jobs' &&
    (!refinedOnly || !r.body || !JSON.parse(r.body).preview)).length;
}

// The panel's cells: {name: {text, value}}.
export async function statsPanel(page) {
  return page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#stats dd')]
    .map((d) => [d.dataset.stat, { text: d.textContent, value: d.dataset.value }])));
}

// A PNG screenshot of the 3D view, decoded; saved under tests/artifacts/ when name is given.
export async function viewShot(page, name) {
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const buf = await page.locator('#view').screenshot();
  if (name) fs.writeFileSync(artifact(name), buf);
  return decodePng(buf);
}

// Waits until the page has written the current view into the URL (it does so shortly after
// the camera stops moving) and the URL holds still; returns it.
export async function settledHref(page, timeout = 20000) {
  const deadline = Date.now() + timeout;
  let last = null;
  for (;;) {
    await page.waitForFunction(() => document.body.dataset.urlPending !== '1', null, { timeout: Math.max(1000, deadline - Date.now()) });
    const now = await page.evaluate(() => location.href);
    if (now === last) return now;
    if (Date.now() > deadline) throw new Error('the URL kept changing');
    last = now;
    await page.waitForTimeout(300);
  }
}

// The stats panel's labels and values whose text takes more than one line (the histogram
// aside): a value split over two lines misreads, so each row should fit the panel's width.
// Lines are counted from the text's own boxes (a cell stretches to its row's height).
export async function wrappedStats(page) {
  return page.evaluate(() => [...document.querySelectorAll('#stats dt, #stats dd:not(.hist)')]
    .filter((e) => {
      const r = document.createRange();
      r.selectNodeContents(e);
      return new Set([...r.getClientRects()].map((b) => Math.round(b.bottom))).size > 1;
    }).map((e) => e.textContent));
}
