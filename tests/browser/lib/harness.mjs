// harness.mjs — what every browser test needs: a real isomeshd on 127.0.0.1 and a port it
// picks itself (read back from its log), with its own temporary cache directory, and headless
// Chromium (Debian's /usr/bin/chromium driven by playwright-core) in a fresh profile. Every
// wait is bounded; stop() ends both, also after a failure.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const { chromium } = require('playwright-core');

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');
export const ARTIFACTS = path.join(ROOT, 'tests', 'artifacts');
const BUILD = path.resolve(ROOT, process.env.ISOMESH_BUILD || 'build/release');

const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];

function sleep(ms) {
  return new Promise((r) => setTimeout(r, ms));
}

// Starts isomeshd; resolves {base, proc, cacheDir, log()} once /readyz says ready.
export async function startDaemon(extraArgs = []) {
  const exe = path.join(BUILD, 'isomeshd');
  if (!fs.existsSync(exe)) throw new Error(`${exe} is missing: run make build`);
  if (!fs.existsSync(path.join(ROOT, 'web', 'node_modules', 'three', 'build', 'three.module.js'))) {
    throw new Error('web/node_modules/three is missing: run make web-deps');
  }
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'isomesh-browser-'));
  const cacheDir = path.join(tmp, 'cache');
  const proc = spawn(exe, ['--listen', '127.0.0.1:0', '--web-root', path.join(ROOT, 'web'),
    '--cache-dir', cacheDir, '--workers', '2', ...extraArgs], { stdio: ['ignore', 'ignore', 'pipe'] });
  let log = '';
  proc.stderr.on('data', (d) => { log += d.toString(); });
  const daemon = { proc, tmp, cacheDir, base: null, log: () => log };
  const deadline = Date.now() + 15000;
  while (!daemon.base) {
    const m = /listening host=\S+ port=(\d+)/.exec(log);
    if (m) daemon.base = `http://127.0.0.1:${m[1]}`;
    else if (proc.exitCode !== null) throw new Error(`isomeshd exited (${proc.exitCode}):\n${log}`);
    else if (Date.now() > deadline) { await stopDaemon(daemon); throw new Error(`isomeshd did not start:\n${log}`); }
    else await sleep(50);
  }
  while (true) {
    try {
      const r = await fetch(`${daemon.base}/readyz`);
      if (r.ok) break;
    } catch { /* not yet */ }
    if (Date.now() > deadline) { await stopDaemon(daemon); throw new Error(`isomeshd never became ready:\n${log}`); }
    await sleep(100);
  }
  return daemon;
}

export async function stopDaemon(daemon) {
  if (!daemon) return;
  const { proc } = daemon;
  if (proc.exitCode === null && proc.signalCode === null) {
    const exited = new Promise((r) => proc.once('exit', r));
    proc.kill('SIGTERM');
    const timer = new Promise((r) => setTimeout(() => r('timeout'), 8000));
    if ((await Promise.race([exited, timer])) === 'timeout') {
      proc.kill('SIGKILL');
      await Promise.race([exited, sleep(3000)]);
    }
  }
  fs.rmSync(daemon.tmp, { recursive: true, force: true });
}

// A fresh headless Chromium profile. Returns {context, profile}.
export async function startBrowser({ width = 1280, height = 800 } = {}) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'isomesh-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: '/usr/bin/chromium',
    headless: true,
    args: CHROMIUM_ARGS,
    viewport: { width, height },
    acceptDownloads: true,
    timeout: 30000,
  });
  context.setDefaultTimeout(30000);
  return { context, profile };
}

export async function stopBrowser(b) {
  if (!b) return;
  try {
    await Promise.race([b.context.close(), sleep(10000)]);
  } finally {
    fs.rmSync(b.profile, { recursive: true, force: true });
  }
}

// Collects page errors and console errors (minus Chromium's harmless GPU noise).
export function watchErrors(page) {
  const errors = [];
  page.on('pageerror', (e) => errors.push(`pageerror: ${e.message}`));
  page.on('console', (m) => {
    if (m.type() === 'error' && !/GPU stall due to ReadPixels|Failed to load resource/.test(m.text())) errors.push(`console: ${m.text()}`);
  });
  return errors;
}

export function artifact(name) {
  fs.mkdirSync(ARTIFACTS, { recursive: true });
  return path.join(ARTIFACTS, name);
}
