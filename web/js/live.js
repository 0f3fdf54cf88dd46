// live.js — live exploration while a slider moves: coarse previews of the surface (the same
// request at a low depth in the server's preview mode, `"preview": true`: the polygoniser's
// mesh alone, without the singular stage, analysis and features; computed by the same
// workers and cached like any mesh, under its own key), at most one
// in flight and always for the newest value, so the picture follows the slider; the refined
// mesh (main.js, once the slider rests and the last preview is drawn: idle()) replaces the
// preview. Every request carries a sequence
// number from `ticket()` taken when it was asked for (a preview: at the slider's move, even if
// it waits for the one in flight), and a result is shown only if no newer one is already on
// screen, so a late preview never covers the refined mesh.

// Previews stop at depth 4 (a few thousand triangles: the shape change is plain) while the
// server computes them within PREVIEW_BUDGET_MS (the 150 ms), else at whichever of
// depth 3 and 4 the server computed faster for that surface (depth 3 is ~2-3x cheaper on
// most, but not all: the mesher may refine more around nodes it cannot resolve at depth 3 —
// kummer-4-nodes takes ~700 ms at depth 3 and ~60 ms at 4). Timed by the server's own
// timings_ms.total, not the wall time, which is mostly the machine's load.
export const PREVIEW_DEPTHS = [3, 4];
const PREVIEW_BUDGET_MS = 150;
// ... and start no deeper than this, so that the unconditional subdivision stays small.
export const PREVIEW_MIN_DEPTH = 3;
// Surfaces whose preview times are remembered (the oldest are forgotten first).
const SURFACES_KEPT = 64;
const serverMs = new Map();   // surface -> {depth: the server's ms for its last preview there}

// What a preview's cost depends on besides the depth: the surface and its box.
function surfaceOf(b) {
  return JSON.stringify([b.preset ?? null, b.expr ?? null, b.let ?? null, b.box ?? null]);
}

function depthFor(b) {
  const [coarse, fine] = PREVIEW_DEPTHS;
  const t = serverMs.get(surfaceOf(b)) || {};
  if (t[fine] === undefined || t[fine] <= PREVIEW_BUDGET_MS) return fine;
  if (t[coarse] === undefined) return coarse;
  return t[coarse] < t[fine] ? coarse : fine;
}

// Remembers the server's time for the preview pb (request text) from its result's stats.
function adapt(pb, result) {
  const ms = result.stats && result.stats.timings_ms && result.stats.timings_ms.total;
  if (!(ms >= 0)) return;   // a cached result's stats still hold the time it cost
  const b = JSON.parse(pb);
  const key = surfaceOf(b);
  const t = serverMs.get(key) || {};
  t[b.depth.max] = ms;
  serverMs.delete(key);
  serverMs.set(key, t);
  while (serverMs.size > SURFACES_KEPT) serverMs.delete(serverMs.keys().next().value);
}

let issued = 0;
let onScreen = 0;

// A new sequence number (each request and each instant redraw takes one).
export function ticket() {
  return ++issued;
}

// True (and the screen now belongs to seq) when seq is newer than what is shown.
export function claim(seq) {
  if (seq <= onScreen) return false;
  onScreen = seq;
  return true;
}

// The preview request for a request body (JSON text): the same with depth capped, in the
// server's preview mode (normals only; no curves, no quality pass: the server refuses them
// in a preview); null when the request is already that coarse.
export function previewBody(body) {
  const b = JSON.parse(body);
  const d = b.depth || { min: 3, max: 7 };
  const previewDepth = depthFor(b);
  if (d.max <= previewDepth && b.max_error === null && b.quality === undefined) return null;
  b.depth = { min: Math.min(d.min, PREVIEW_MIN_DEPTH), max: previewDepth };
  b.max_error = null;   // a preview is coarse by depth, whatever the error bound asks
  delete b.dual;        // ... so the bound's meshers do not apply (refused without it)
  delete b.straddle;
  delete b.quality;     // ... and shows the raw triangles: the pass is for the final mesh
  delete b.curves;      // the curves are drawn on the refined mesh
  b.output = { ...(b.output || {}), attributes: ['normal'] };   // a preview is shaded
  b.preview = true;
  return JSON.stringify(b);
}

// Runs previews: want(body) asks for the preview of body; load(body, signal) fetches it;
// show(result, body, seq) draws it; settled() resolves once it is drawn. While one is in
// flight (or its picture still being drawn), only the newest wanted body is kept and sent
// when it ends.
export class Previewer {
  constructor({ load, cached, show, failed, settled = () => Promise.resolve() }) {
    this.load = load;
    this.cached = cached;
    this.show = show;
    this.failed = failed;
    this.settled = settled;   // resolves once the picture shown is drawn (viewer.settled)
    this.inFlight = null;   // {body, controller}
    this.next = null;       // body waiting for the one in flight
    this.idleWaiters = [];
  }

  // Resolves once no preview is in flight or waiting (at once when none is).
  idle() {
    if (!this.inFlight && !this.next) return Promise.resolve();
    return new Promise((resolve) => this.idleWaiters.push(resolve));
  }

  wake() {
    if (this.inFlight || this.next) return;
    const waiters = this.idleWaiters;
    this.idleWaiters = [];
    for (const w of waiters) w();
  }

  want(body) {
    const pb = previewBody(body);
    if (pb) this.request(pb, ticket());
  }

  request(pb, seq) {
    const hit = this.cached(pb);
    if (hit) {
      this.next = null;
      this.show(hit, pb, seq);
      return;
    }
    if (this.inFlight) {
      if (this.inFlight.body !== pb) this.next = { pb, seq };
      return;
    }
    this.run(pb, seq);
  }

  async run(pb, seq) {
    const controller = new AbortController();
    const mine = { body: pb, controller };
    this.inFlight = mine;
    try {
      const result = await this.load(pb, controller.signal);
      adapt(pb, result);
      if (this.inFlight === mine) {
        this.show(result, pb, seq);
        // The next preview's computation would take the CPU this one's frame needs (in
        // software GL a frame costs 100+ ms): it starts once the frame is drawn.
        await this.settled();
      }
    } catch (e) {
      if (e.name !== 'AbortError' && this.inFlight === mine) this.failed(e);
    } finally {
      if (this.inFlight === mine) {
        this.inFlight = null;
        const next = this.next;
        this.next = null;
        if (next) this.request(next.pb, next.seq);
        this.wake();
      }
    }
  }

  // Drops what is waiting and aborts what is in flight (a new surface, Cancel).
  stop() {
    this.next = null;
    if (this.inFlight) this.inFlight.controller.abort();
    this.inFlight = null;
    this.wake();
  }
}
