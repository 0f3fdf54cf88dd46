// live.js — live exploration while a slider moves: coarse previews of the surface (the same
// request at a low depth, computed by the same workers and cached like any mesh), at most one
// in flight and always for the newest value, so the picture follows the slider; the refined
// mesh (main.js, once the slider rests) replaces the preview. Every request carries a sequence
// number from `ticket()` taken when it was asked for (a preview: at the slider's move, even if
// it waits for the one in flight), and a result is shown only if no newer one is already on
// screen, so a late preview never covers the refined mesh.

// Previews stop at depth 4 (a few thousand triangles: the shape change is plain) while they
// come back within PREVIEW_BUDGET_MS (the 150 ms), else at depth 3 (~3x cheaper on
// the Kummer surface, ~1000 triangles) until they are fast again (below a third of it).
export const PREVIEW_DEPTHS = [3, 4];
const PREVIEW_BUDGET_MS = 150;
// ... and start no deeper than this, so that the unconditional subdivision stays small.
export const PREVIEW_MIN_DEPTH = 3;
let previewDepth = PREVIEW_DEPTHS[1];

function adapt(wallMs) {
  if (wallMs > PREVIEW_BUDGET_MS) previewDepth = PREVIEW_DEPTHS[0];
  else if (wallMs < PREVIEW_BUDGET_MS / 3) previewDepth = PREVIEW_DEPTHS[1];
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

// The preview request for a request body (JSON text): the same with depth capped; null when
// the request is already that coarse.
export function previewBody(body) {
  const b = JSON.parse(body);
  const d = b.depth || { min: 3, max: 7 };
  if (d.max <= previewDepth && b.max_error === undefined && b.quality === undefined) return null;
  b.depth = { min: Math.min(d.min, PREVIEW_MIN_DEPTH), max: previewDepth };
  delete b.max_error;   // a preview is coarse by depth, whatever the error bound asks
  delete b.quality;     // ... and shows the raw triangles: the pass is for the final mesh
  return JSON.stringify(b);
}

// Runs previews: want(body) asks for the preview of body; load(body, signal) fetches it;
// show(result, body, seq) draws it. While one is in flight, only the newest wanted body is
// kept and sent when it ends.
export class Previewer {
  constructor({ load, cached, show, failed }) {
    this.load = load;
    this.cached = cached;
    this.show = show;
    this.failed = failed;
    this.inFlight = null;   // {body, controller}
    this.next = null;       // body waiting for the one in flight
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
      if (!result.viewerCache) adapt(result.wallMs);
      if (this.inFlight === mine) this.show(result, pb, seq);
    } catch (e) {
      if (e.name !== 'AbortError' && this.inFlight === mine) this.failed(e);
    } finally {
      if (this.inFlight === mine) {
        this.inFlight = null;
        const next = this.next;
        this.next = null;
        if (next) this.request(next.pb, next.seq);
      }
    }
  }

  // Drops what is waiting and aborts what is in flight (a new surface, Cancel).
  stop() {
    this.next = null;
    if (this.inFlight) this.inFlight.controller.abort();
    this.inFlight = null;
  }
}
