// loader.js — from a request body to a decoded mesh with its stats and features. Every
// request goes through POST /v1/jobs: a cached result comes back as a job already "done"
// (one small round trip), anything else streams progress over the job's events and can be
// canceled with DELETE, which frees the worker (a dropped POST /v1/mesh would not). The mesh
// itself is then fetched from its immutable URL /v1/meshes/{key}.drc (browser-cacheable),
// decoded in a worker, and kept in a small in-page LRU so that dragging a slider back over
// values already seen redraws with no network at all. A request differs from another of the
// same surface only by its attributes (the colour mode's, state.js) is answered by a held mesh
// that has them all, and a new attribute set of a held surface reuses its features (the server
// encodes it from its stored surface: no polygonisation).
import * as api from './api.js';
import * as timeline from './timeline.js';

const MESH_LRU = 12;

let worker = null;
let nextId = 1;
const pending = new Map();

function decodeWorker() {
  if (!worker) {
    worker = new Worker(new URL('./draco_worker.js', import.meta.url));
    worker.onmessage = (e) => {
      const p = pending.get(e.data.id);
      if (!p) return;
      pending.delete(e.data.id);
      if (e.data.error) p.reject(new Error(e.data.error));
      else p.resolve(e.data.result);
    };
    worker.onerror = (e) => {
      for (const p of pending.values()) p.reject(new Error('the Draco decoder failed to start: ' + e.message));
      pending.clear();
    };
  }
  return worker;
}

export function decodeDraco(bytes) {
  return new Promise((resolve, reject) => {
    const id = nextId++;
    pending.set(id, { resolve, reject });
    decodeWorker().postMessage({ id, bytes }, [bytes]);
  });
}

const keyOfRequest = new Map();   // request body text -> mesh key
const meshes = new Map();         // mesh key -> loaded result (insertion order = LRU order)
const ofSurface = new Map();      // surface text (splitBody) -> [{key, attributes}] held

// What the server sends when a request leaves output.attributes out (proto/request.h
// ISM_ATTR_DEFAULT: what the shaded view draws).
const DEFAULT_ATTRIBUTES = ['normal'];
// Every attribute a request may ask for (the downloads carry them all).
export const ALL_ATTRIBUTES = ['normal', 'mean_curvature', 'gauss_curvature', 'class'];

// body (request JSON text) as {surface: the request without output.attributes, attributes}.
export function splitBody(body) {
  const b = JSON.parse(body);
  const attributes = (b.output && b.output.attributes) || DEFAULT_ATTRIBUTES;
  if (b.output) {
    delete b.output.attributes;
    if (!Object.keys(b.output).length) delete b.output;
  }
  return { surface: JSON.stringify(b), attributes };
}

// surface (splitBody's) as a request body asking for attributes.
export function withAttributes(surface, attributes) {
  const b = JSON.parse(surface);
  b.output = { ...(b.output || {}), attributes };
  return JSON.stringify(b);
}

function remember(result, body) {
  meshes.delete(result.key);
  meshes.set(result.key, result);
  while (meshes.size > MESH_LRU) meshes.delete(meshes.keys().next().value);
  if (!body) return;
  const { surface, attributes } = splitBody(body);
  const held = (ofSurface.get(surface) || []).filter((h) => h.key !== result.key && meshes.has(h.key));
  held.push({ key: result.key, attributes });
  ofSurface.delete(surface);
  ofSurface.set(surface, held);
  for (const [s, list] of ofSurface) {     // forget surfaces whose meshes all left the LRU
    if (ofSurface.size <= MESH_LRU) break;
    if (!list.some((h) => meshes.has(h.key))) ofSurface.delete(s);
  }
}

// A held mesh of body's surface with at least its attributes, or null.
function heldFor(body) {
  const { surface, attributes } = splitBody(body);
  const held = (ofSurface.get(surface) || []).find((h) => meshes.has(h.key) && attributes.every((a) => h.attributes.includes(a)));
  return held ? meshes.get(held.key) : null;
}

// The features of body's surface if a held mesh has them (they do not depend on attributes).
function heldFeatures(body) {
  const { surface } = splitBody(body);
  const held = (ofSurface.get(surface) || []).find((h) => meshes.has(h.key));
  return held ? meshes.get(held.key).features : null;
}

// The result for body if this page already holds it, or the same surface with more
// attributes (no network), else null.
export function cached(body) {
  const key = keyOfRequest.get(body);
  const hit = (key && meshes.get(key)) || heldFor(body);
  if (!hit) return null;
  remember(hit);
  return { ...hit, viewerCache: true, transferred: 0, wallMs: 0, timing: timeline.start() };
}

// Loads body (the request JSON text). onProgress(fraction, state) while the server works.
// Rejects with api.ApiError for HTTP errors, an AbortError when signal fires (the job is then
// canceled on the server).
export async function load(body, signal, onProgress) {
  const hit = cached(body);
  if (hit) return hit;
  const t0 = performance.now();
  const timing = timeline.start();
  const { job: submitted, bytes: jobBytes } = await api.submitJob(body, signal);
  timeline.mark(timing, 'posted');
  let job = submitted;
  let transferred = jobBytes;
  const serverCache = job.state === 'done' ? 'hit' : 'miss';
  if (!['done', 'failed', 'canceled'].includes(job.state)) {
    onProgress(job.progress || 0, job.state);
    const abort = () => api.cancelJob(job.id);
    signal.addEventListener('abort', abort, { once: true });
    try {
      job = await api.followJob(job, signal, (name, data) => {
        if (name === 'progress') onProgress(data.progress || 0, data.state);
      });
    } finally {
      signal.removeEventListener('abort', abort);
    }
  }
  if (job.state === 'failed') {
    throw new api.ApiError(job.status || 500, job.error || { message: 'the computation failed' }, null);
  }
  if (job.state === 'canceled') {
    throw new api.ApiError(499, { code: 'canceled', message: 'the computation was canceled' }, null);
  }
  if (job.state !== 'done') throw new api.ApiError(500, { message: 'the job stream ended early' }, null);
  onProgress(1, 'done');
  timeline.mark(timing, 'done');

  const key = job.key;
  const meshUrl = job.mesh_url || `/v1/meshes/${key}.drc`;
  const known = heldFeatures(body);
  const [mesh, features, stats] = await Promise.all([
    api.getBytes(meshUrl, signal),
    known ? Promise.resolve({ json: known, transferred: 0 })
      : api.getJSON(job.features_url || `/v1/meshes/${key}/features`, signal),
    job.stats ? Promise.resolve({ json: job.stats, transferred: 0 })
      : api.getJSON(job.stats_url || `/v1/meshes/${key}/stats`, signal),
  ]);
  timeline.mark(timing, 'fetched');
  transferred += mesh.transferred + features.transferred + stats.transferred;
  const drcBytes = mesh.bytes.byteLength;
  const decoded = drcBytes > 0 ? await decodeDraco(mesh.bytes) : null;
  if (decoded && stats.json.mesh && stats.json.mesh.encoded_faces !== undefined &&
      decoded.faces !== stats.json.mesh.encoded_faces) {
    throw new Error(`decoded ${decoded.faces} triangles, the server encoded ${stats.json.mesh.encoded_faces}`);
  }
  const result = {
    key, mesh: decoded, features: features.json, stats: stats.json, drcBytes,
    serverCache, viewerCache: false, transferred, wallMs: performance.now() - t0,
  };
  timeline.mark(timing, 'decoded');
  const fresh = { ...result, timing };
  keyOfRequest.set(body, key);
  remember(result, body);
  return fresh;
}
