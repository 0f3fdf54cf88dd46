// api.js — isomeshd's HTTP API as the viewer uses it: jobs (POST /v1/jobs, their server-sent
// events read through fetch so the bearer token can travel with them, DELETE to cancel), the
// immutable mesh and its features/stats documents, presets; the error document
// {"error": {code, message, path?, line?, column?}} turned into an ApiError; the bearer token
// kept in localStorage.

const TOKEN_KEY = 'isomesh.token';

export const token = {
  get() {
    try { return localStorage.getItem(TOKEN_KEY) || ''; } catch { return ''; }
  },
  set(value) {
    try {
      if (value) localStorage.setItem(TOKEN_KEY, value);
      else localStorage.removeItem(TOKEN_KEY);
    } catch { /* storage refused (private mode): the token lives for this page only */ }
  },
};

export class ApiError extends Error {
  constructor(status, error, retryAfter) {
    super(error && error.message ? error.message : `HTTP ${status}`);
    this.status = status;
    this.code = (error && error.code) || '';
    this.path = (error && error.path) || '';
    this.line = (error && error.line) || 0;
    this.column = (error && error.column) || 0;
    this.retryAfter = retryAfter;
  }
}

function headers(extra) {
  const h = new Headers(extra || {});
  const t = token.get();
  if (t) h.set('Authorization', `Bearer ${t}`);
  return h;
}

async function errorFrom(response) {
  let error = null;
  try {
    const body = await response.json();
    error = body && body.error;
  } catch { /* not JSON: a proxy's page, say */ }
  const ra = response.headers.get('Retry-After');
  const retryAfter = ra && /^\d+$/.test(ra) ? Number(ra) : null;
  if (!error) error = { code: 'http_' + response.status, message: `${response.status} ${response.statusText}`.trim() };
  return new ApiError(response.status, error, retryAfter);
}

async function call(url, options = {}) {
  let response;
  try {
    response = await fetch(url, { ...options, headers: headers(options.headers) });
  } catch (e) {
    if (e.name === 'AbortError') throw e;
    throw new ApiError(0, { code: 'network', message: 'the server cannot be reached' }, null);
  }
  if (!response.ok) throw await errorFrom(response);
  return response;
}

// Bytes the network really carried for url (0 when the browser cache answered), else fallback.
function transferred(url, fallback) {
  const abs = new URL(url, location.href).href;
  const entries = performance.getEntriesByName(abs);
  const last = entries[entries.length - 1];
  return last && typeof last.transferSize === 'number' && last.responseEnd > 0 ? last.transferSize : fallback;
}

export async function getPresets() {
  const r = await call('/v1/presets');
  return (await r.json()).presets;
}

// GET /v1/presets/{name}/thumbnail.png: the daemon's own picture of a preset (a Blob).
export async function getThumbnail(name, signal) {
  const r = await call(`/v1/presets/${encodeURIComponent(name)}/thumbnail.png`, { signal });
  return r.blob();
}

// POST /v1/jobs: the job as JSON (202; state "done" at once when the server had it cached).
export async function submitJob(body, signal) {
  const r = await call('/v1/jobs', {
    method: 'POST', body, signal, headers: { 'Content-Type': 'application/json' },
  });
  const text = await r.text();
  return { job: JSON.parse(text), bytes: text.length };
}

// POST /v1/mesh?format=json: {key, urls, stats} of body's mesh (computed or encoded if needed).
export async function meshLinks(body, signal) {
  const r = await call('/v1/mesh?format=json', {
    method: 'POST', body, signal, headers: { 'Content-Type': 'application/json' },
  });
  return r.json();
}

export function cancelJob(id) {
  return call(`/v1/jobs/${encodeURIComponent(id)}`, { method: 'DELETE' }).catch(() => {});
}

// Follows a job's event stream; calls onEvent(name, data) for each event and resolves with the
// last job JSON once the job is done, failed or canceled.
export async function followJob(job, signal, onEvent) {
  const r = await call(job.events_url || `/v1/jobs/${job.id}/events`, {
    signal, headers: { Accept: 'text/event-stream' },
  });
  const reader = r.body.getReader();
  const utf8 = new TextDecoder();
  let buffer = '';
  let last = job;
  for (;;) {
    const { value, done } = await reader.read();
    if (value) buffer += utf8.decode(value, { stream: true });
    let cut;
    while ((cut = buffer.search(/\r?\n\r?\n/)) >= 0) {
      const block = buffer.slice(0, cut);
      buffer = buffer.slice(cut).replace(/^\r?\n\r?\n/, '');
      let name = 'message';
      const data = [];
      for (const line of block.split(/\r?\n/)) {
        if (line.startsWith('event:')) name = line.slice(6).trim();
        else if (line.startsWith('data:')) data.push(line.slice(5).replace(/^ /, ''));
      }
      if (!data.length) continue;
      const parsed = JSON.parse(data.join('\n'));
      last = parsed;
      onEvent(name, parsed);
      if (['done', 'failed', 'canceled'].includes(parsed.state)) {
        reader.cancel().catch(() => {});
        return parsed;
      }
    }
    if (done) return last;
  }
}

// POST /v1/box: {box, cube, empty, complete, level} — the box around f = 0 within the
// request's box (proto/box_fit.h).
export async function fitBox(body, signal) {
  const r = await call('/v1/box', { method: 'POST', body, signal, headers: { 'Content-Type': 'application/json' } });
  return r.json();
}

// POST /v1/point?at=X,Y,Z: f, gradient and level-set curvature there (proto/point_probe.h).
export async function probePoint(body, xyz, signal) {
  const at = xyz.map((v) => String(v)).join(',');
  const r = await call(`/v1/point?at=${at}`, { method: 'POST', body, signal, headers: { 'Content-Type': 'application/json' } });
  return r.json();
}

export async function getBytes(url, signal) {
  const r = await call(url, { signal });
  const bytes = await r.arrayBuffer();
  return { bytes, cache: r.headers.get('X-Cache'), transferred: transferred(url, bytes.byteLength) };
}

export async function getJSON(url, signal) {
  const r = await call(url, { signal });
  const text = await r.text();
  return { json: JSON.parse(text), transferred: transferred(url, text.length) };
}
