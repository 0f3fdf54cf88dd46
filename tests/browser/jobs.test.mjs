// jobs.test.mjs — the viewer while the server works or refuses: a real isomeshd with one worker
// and no queue. The progress bar follows a long job's event stream and Cancel stops it on the
// server; a request refused with 503 (busy) says so, counts down the Retry-After and succeeds
// once the workers are free; a bearer token set in the dialog is kept in localStorage and sent
// with the compute requests (and the downloads), and can be forgotten.
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { startDaemon, stopDaemon, startBrowser, stopBrowser, watchErrors } from './lib/harness.mjs';
import { waitForMesh, loads } from './lib/page.mjs';

// Slow enough to watch (seconds on two cores), cheap to describe: the depth path at depth
// 10 (under the default bound the gyroid ball takes a fraction of a second).
const SLOW = { preset: 'gyroid-ball', depth: { min: 3, max: 10 }, max_error: null };
const SLOW_FRAGMENT = '#preset=gyroid-ball&depth=3,10&err=off';

let daemon = null;
let browser = null;

async function post(path, body) {
  return fetch(daemon.base + path, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
}

async function jobState(id) {
  const r = await fetch(`${daemon.base}/v1/jobs/${id}`);
  return (await r.json()).state;
}

async function waitFor(what, check, timeout = 20000) {
  const deadline = Date.now() + timeout;
  for (;;) {
    const v = await check();
    if (v) return v;
    if (Date.now() > deadline) throw new Error(`timed out waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

// A canceled computation's worker is stopped and replaced: wait for the pool to be whole again.
async function workerReady() {
  await waitFor('a ready worker', async () => {
    const r = await fetch(`${daemon.base}/readyz`);
    const body = await r.json();
    return r.status === 200 && body.workers_ready === 1 ? 'yes' : null;
  });
}

describe('viewer and jobs', { timeout: 150000 }, () => {
  before(async () => {
    daemon = await startDaemon(['--workers', '1', '--queue', '1']);
    browser = await startBrowser();
  });

  after(async () => {
    try {
      await stopBrowser(browser);
    } finally {
      await stopDaemon(daemon);
    }
  });

  it('shows the progress of a long job from its events, and Cancel stops it on the server', async () => {
    const page = await browser.context.newPage();
    const errors = watchErrors(page);
    const jobs = [];
    page.on('response', async (r) => {
      if (r.request().method() === 'POST' && new URL(r.url()).pathname === '/v1/jobs' && r.status() === 202) jobs.push((await r.json()).id);
    });
    const deletes = [];
    page.on('request', (r) => { if (r.method() === 'DELETE') deletes.push(new URL(r.url()).pathname); });
    try {
      await page.goto(daemon.base + '/' + SLOW_FRAGMENT);
      await page.waitForSelector('#busy:not([hidden])');
      await page.waitForFunction(() => Number(document.getElementById('progress').value) > 0, null, { timeout: 30000 });
      const label = await page.textContent('#progress-label');
      assert.match(label, /Computing… \d+%/);
      await page.click('#cancel');
      await page.waitForSelector('#busy', { state: 'hidden' });
      assert.match(await page.textContent('#message'), /Canceled/);
      assert.equal(jobs.length, 1);
      await waitFor('the DELETE', () => deletes.includes(`/v1/jobs/${jobs[0]}`));
      assert.equal(await waitFor('the cancel', async () => ((await jobState(jobs[0])) === 'canceled' ? 'yes' : null)), 'yes');
      assert.equal(await page.evaluate(() => document.body.dataset.loads || '0'), '0', 'no mesh was shown');
      assert.deepEqual(errors, []);
    } finally {
      await page.close();
    }
  });

  it('a job past its deadline says which knobs make a lighter mesh', async () => {
    // a daemon of its own whose deadline the slow request passes
    const strict = await startDaemon(['--workers', '1', '--job-timeout', '300ms']);
    const page = await browser.context.newPage();
    const errors = watchErrors(page);
    try {
      await page.goto(strict.base + '/' + SLOW_FRAGMENT);
      await page.waitForFunction(() => /deadline/.test(document.getElementById('message').textContent), null, { timeout: 30000 });
      const text = await page.textContent('#message');
      assert.match(text, /^Took too long: .*deadline.*\. A smaller depth max, a larger max error or a smaller box makes a lighter mesh\./);
      assert.deepEqual(errors, []);
    } finally {
      await page.close();
      await stopDaemon(strict);
    }
  });

  it('says the server is busy, counts down its Retry-After, and retries', async () => {
    // Occupy the only worker and the only queue place: the next computation gets 503.
    const blockers = [];
    const page = await browser.context.newPage();
    try {
      await workerReady();
      for (const k of [4, 5]) {
        const r = await post('/v1/jobs', { ...SLOW, params: { k } });
        assert.equal(r.status, 202);
        blockers.push((await r.json()).id);
        // the first holds the queue's only place until the worker takes it (a loaded
        // machine: a while): the second would be refused if posted before
        if (k === 4) await waitFor('a blocker to run', async () => ((await jobState(blockers[0])) === 'running' ? 'yes' : null));
      }
      await page.goto(daemon.base + '/#preset=torus');
      await page.waitForSelector('#message.error:not([hidden])');
      const text = await page.textContent('#message');
      assert.match(text, /server is busy/);
      assert.match(text, /Retrying in \d s/);
      assert.equal(await page.evaluate(() => document.body.dataset.loads || '0'), '0');
      for (const id of blockers.splice(0)) await fetch(`${daemon.base}/v1/jobs/${id}`, { method: 'DELETE' });
      await waitForMesh(page, 0, 30000);
      assert.equal(await page.isHidden('#message'), true);
      assert.equal(await page.inputValue('#preset'), 'torus');
    } finally {
      // a failure above must not leave the worker busy for the next test
      for (const id of blockers) await fetch(`${daemon.base}/v1/jobs/${id}`, { method: 'DELETE' });
      await page.close();
    }
  });

  it('keeps a bearer token from the dialog and sends it with compute requests and downloads', async () => {
    const page = await browser.context.newPage();
    const seen = [];
    page.on('request', (r) => {
      const u = new URL(r.url());
      if (u.pathname.startsWith('/v1/')) seen.push({ path: u.pathname, method: r.method(), auth: r.headers().authorization || '' });
    });
    await workerReady();
    try {
      await page.goto(daemon.base + '/#preset=sphere');
      await waitForMesh(page, 0);
      assert.ok(seen.every((s) => s.auth === ''), 'no token yet');

      await page.click('#token-button');
      await page.waitForSelector('#token-dialog[open]');
      await page.fill('#token-input', 'test-token-42');
      await page.click('#token-dialog button[value=save]');
      await page.waitForSelector('#token-dialog', { state: 'hidden' });
      // The dialog's close event (which stores the token) is a task queued after it hides.
      await page.waitForFunction((v) => localStorage.getItem('isomesh.token') === v, 'test-token-42', { timeout: 5000 })
        .catch(() => {});
      assert.equal(await page.evaluate(() => localStorage.getItem('isomesh.token')), 'test-token-42');

      seen.length = 0;
      const before = await loads(page);
      await page.fill('#param-r-value', '0.9');
      await page.locator('#param-r-value').press('Enter');
      await waitForMesh(page, before);
      const posts = seen.filter((s) => s.method === 'POST' && s.path === '/v1/jobs');
      assert.equal(posts.length, 1);
      assert.ok(seen.length > 1 && seen.every((s) => s.auth === 'Bearer test-token-42'), JSON.stringify(seen));

      seen.length = 0;
      const [download] = await Promise.all([page.waitForEvent('download'), page.click('#downloads a[data-format=stl]')]);
      assert.match(download.suggestedFilename(), /^sphere-[0-9a-f]{8}\.stl$/);
      const stl = fs.readFileSync(await download.path());
      assert.equal(stl.length, 84 + 50 * stl.readUInt32LE(80));
      assert.deepEqual(seen.filter((s) => s.path.endsWith('.stl')).map((s) => s.auth), ['Bearer test-token-42']);

      // A reload keeps the token; "Forget token" drops it.
      await page.reload();
      await waitForMesh(page, 0);
      assert.equal(await page.evaluate(() => localStorage.getItem('isomesh.token')), 'test-token-42');
      await page.click('#token-button');
      await page.click('#token-dialog button[value=clear]');
      await page.waitForSelector('#token-dialog', { state: 'hidden' });
      await page.waitForFunction(() => localStorage.getItem('isomesh.token') === null, null, { timeout: 5000 })
        .catch(() => {});
      assert.equal(await page.evaluate(() => localStorage.getItem('isomesh.token')), null);
    } finally {
      await page.close();
    }
  });
});
