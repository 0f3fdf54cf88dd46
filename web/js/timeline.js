// timeline.js — where the time between a request and its picture goes, per mesh shown: marks
// (performance.now() in ms) taken by loader.js (asked, job posted, job done, bytes fetched,
// decoded), main.js (handed to the viewer) and viewer.js (first frame drawn with it, and
// done by the GPU). The last
// KEPT entries are readable as window.isomeshTimeline (the browser tests and make bench print
// them: queueing, server, transfer, decode, draw).

// Entries kept (a drag makes a handful; the oldest go first).
const KEPT = 64;

const entries = [];

// A new entry {key, preview, marks: {asked}} for a request asked for now.
export function start(preview) {
  return { key: '', preview, marks: { asked: performance.now() } };
}

export function mark(entry, name) {
  if (entry && entry.marks[name] === undefined) entry.marks[name] = performance.now();
}

// Records an entry whose result was handed to the viewer now (its last mark, 'drawn', comes
// with the next frame: viewer.js calls drawn()).
export function shown(entry) {
  if (!entry) return;
  mark(entry, 'shown');
  entries.push(entry);
  if (entries.length > KEPT) entries.shift();
}

// The first frame after the newest shown entry was drawn (issued to the GPU); returns that
// entry (or null) for gpuDone.
export function drawn() {
  const e = entries[entries.length - 1];
  if (!e || e.marks.drawn !== undefined) return null;
  mark(e, 'drawn');
  return e;
}

// The GPU has done the frame that first drew entry (from drawn()).
export function gpuDone(entry) {
  mark(entry, 'gpu');
}

export function list() {
  return entries;
}

window.isomeshTimeline = entries;
