// auth.test.mjs — the viewer against a real isomeshd that wants bearer tokens (--tokens, made
// with `isomeshd token add`): without a token the compute request is refused with 401 and the
// viewer asks for one; once it is given the mesh appears and the token is kept in
// localStorage. With --private even the presets need the token: the viewer asks first, then
// shows the preset menu and the mesh.
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ROOT, startDaemon, stopDaemon, startBrowser, stopBrowser, watchErrors } from './lib/harness.mjs';
import { waitForMesh } from './lib/page.mjs';

const BUILD = path.resolve(ROOT, process.env.ISOMESH_BUILD || 'build/release');

function addToken(file, name) {
  const r = spawnSync(path.join(BUILD, 'isomeshd'), ['token', 'add', name, '--file', file], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`token add failed: ${r.stderr}`);
  return r.stdout.trim();
}

async function giveToken(page, token) {
  await page.waitForSelector('#token-dialog[open]');
  await page.fill('#token-input', token);
  await page.click('#token-dialog button[value=save]');
  await page.waitForSelector('#token-dialog', { state: 'hidden' });
}

// Answers of the API as the page saw them: [{path, status}].
function watchApi(page) {
  const seen = [];
  page.on('response', (r) => {
    const u = new URL(r.url());
    if (u.pathname.startsWith('/v1/')) seen.push({ path: u.pathname, method: r.request().method(), status: r.status() });
  });
  return seen;
}

let tmp = null;
let tokens = null;
let browser = null;

describe('viewer with bearer tokens', { timeout: 150000 }, () => {
  before(async () => {
    tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'isomesh-auth-'));
    tokens = path.join(tmp, 'tokens');
    browser = await startBrowser();
  });

  after(async () => {
    try {
      await stopBrowser(browser);
    } finally {
      fs.rmSync(tmp, { recursive: true, force: true });
    }
  });

  it('asks for a token on 401, then computes with it and keeps it', async () => {
    const token = addToken(tokens, 'alice');
    const daemon = await startDaemon(['--tokens', tokens]);
    const page = await browser.context.newPage();
    const errors = watchErrors(page);
    const seen = watchApi(page);
    try {
      await page.goto(daemon.base + '/#preset=sphere');
      await page.waitForSelector('#token-dialog[open]');
      const refused = seen.filter((s) => s.method === 'POST' && s.path === '/v1/jobs');
      assert.deepEqual(refused.map((s) => s.status), [401]);
      assert.ok(seen.some((s) => s.path === '/v1/presets' && s.status === 200), 'presets are open');
      await giveToken(page, token);
      const key = await waitForMesh(page, 0);
      assert.match(key, /^[0-9a-f]{64}$/);
      assert.equal(await page.evaluate(() => localStorage.getItem('isomesh.token')), token);
      assert.deepEqual(seen.filter((s) => s.method === 'POST').map((s) => s.status), [401, 202]);
      assert.match(daemon.log(), /status=202 .*user=alice/);
      assert.deepEqual(errors.filter((e) => !/401/.test(e)), []);
    } finally {
      await page.close();
      await stopDaemon(daemon);
    }
  });

  it('with --private, asks for the token before anything and then shows presets and the mesh', async () => {
    const token = addToken(tokens, 'bob');
    const daemon = await startDaemon(['--tokens', tokens, '--private']);
    const page = await browser.context.newPage();
    const seen = watchApi(page);
    try {
      await page.goto(daemon.base + '/#preset=torus');
      await page.waitForSelector('#token-dialog[open]');
      assert.ok(seen.some((s) => s.path === '/v1/presets' && s.status === 401));
      await giveToken(page, token);
      await waitForMesh(page, 0);
      assert.equal(await page.inputValue('#preset'), 'torus');
      const menu = await page.locator('#preset option').count();
      assert.ok(menu > 5, `the preset menu has ${menu} entries`);
      assert.ok(seen.some((s) => s.path === '/v1/presets' && s.status === 200));
      assert.ok(seen.some((s) => s.path.endsWith('.drc') && s.status === 200), 'the mesh came with the token');
    } finally {
      await page.close();
      await stopDaemon(daemon);
    }
  });
});
