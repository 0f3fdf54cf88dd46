// colormap.js — curvature as colour. Curvature on these surfaces spans orders of magnitude (it
// is infinite at a Kummer node or a cone apex), so the scale is chosen from the data:
//   * values of both signs: a diverging blue–grey–red map with zero in the middle, over
//     ±L where L is the larger of the 2nd/98th percentiles' magnitudes; symmetric-log
//     (asinh) when L is far above the typical magnitude, linear otherwise;
//   * values of one sign: a sequential (viridis-like) map from the 2nd to the 98th
//     percentile; logarithmic when that span covers more than a factor 30.
// Values beyond the range take the end colours; the legend says so, and gives the true range.

const DIVERGING = [[59, 76, 192], [141, 176, 254], [221, 221, 221], [244, 154, 123], [180, 4, 38]];
const SEQUENTIAL = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
export const NONFINITE_RGB = [90, 90, 90];
const LOG_SPAN = 30;

function srgbToLinear(c) {
  const v = c / 255;
  return v <= 0.04045 ? v / 12.92 : Math.pow((v + 0.055) / 1.055, 2.4);
}

function ramp(stops, t) {
  const u = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(u));
  const f = u - i;
  return stops[i].map((v, k) => Math.round(v + f * (stops[i + 1][k] - v)));
}

function quantile(sorted, p) {
  return sorted[Math.min(sorted.length - 1, Math.max(0, Math.round(p * (sorted.length - 1))))];
}

// The percentile pairs the viewer offers for the coloured range (share cut at each end).
export const RANGE_CUTS = { p2: 0.02, p5: 0.05, p10: 0.10, full: 0 };

// Chooses the scale for values, the coloured range running from the cut-th to the
// (1 - cut)-th percentile (default 2 %). Returns {min, max (true finite range), lo, hi (the
// coloured range), kind 'diverging'|'sequential', scale 'linear'|'log'|'symlog', s (symlog
// knee), clamped, nonfinite}.
export function curvatureRange(values, cut = RANGE_CUTS.p2) {
  const finite = [];
  let nonfinite = 0;
  for (let i = 0; i < values.length; i++) {
    if (Number.isFinite(values[i])) finite.push(values[i]);
    else nonfinite++;
  }
  if (!finite.length) {
    return { min: 0, max: 0, lo: -1, hi: 1, kind: 'diverging', scale: 'linear', s: 1, clamped: 0, nonfinite };
  }
  const sorted = Float64Array.from(finite).sort();
  const min = sorted[0], max = sorted[sorted.length - 1];
  let p2 = quantile(sorted, cut), p98 = quantile(sorted, 1 - cut);
  const r = { min, max, nonfinite, s: 1, clamped: 0 };
  if (p2 < 0 && p98 > 0) {
    const L = Math.max(-p2, p98);
    const abs = Float64Array.from(finite, Math.abs).sort();
    // The knee sits well below the typical magnitude, so that most of the surface is coloured.
    const s = 0.1 * quantile(abs, 0.5) || L / LOG_SPAN;
    Object.assign(r, { kind: 'diverging', lo: -L, hi: L, s, scale: L / s > LOG_SPAN ? 'symlog' : 'linear' });
  } else {
    if (p2 === p98) { p2 = min; p98 = max; }
    if (p2 === p98) { p2 -= 1; p98 += 1; }
    const span = p2 > 0 ? p98 / p2 : p98 < 0 ? p2 / p98 : 0;
    Object.assign(r, { kind: 'sequential', lo: p2, hi: p98, scale: span > LOG_SPAN ? 'log' : 'linear' });
  }
  for (const v of finite) if (v < r.lo || v > r.hi) r.clamped++;
  return r;
}

const signedLog = (v) => Math.sign(v) * Math.log(Math.abs(v));

// Position in [0, 1] of value v on range's colour bar.
export function position(range, v) {
  const { lo, hi } = range;
  let t;
  if (range.scale === 'symlog') {
    t = 0.5 + 0.5 * Math.asinh(v / range.s) / Math.asinh(hi / range.s);
  } else if (range.scale === 'log') {
    const c = Math.min(hi, Math.max(lo, v));
    t = (signedLog(c) - signedLog(lo)) / (signedLog(hi) - signedLog(lo));
  } else {
    t = (v - lo) / (hi - lo);
  }
  return Math.min(1, Math.max(0, t));
}

// The value at position t of the colour bar (for the legend's ticks).
export function valueAt(range, t) {
  const { lo, hi } = range;
  if (range.scale === 'symlog') return range.s * Math.sinh((2 * t - 1) * Math.asinh(hi / range.s));
  if (range.scale === 'log') {
    const sgn = lo > 0 ? 1 : -1;
    return sgn * Math.exp(signedLog(lo) * sgn + t * (signedLog(hi) - signedLog(lo)) * sgn);
  }
  return lo + t * (hi - lo);
}

// sRGB 0..255 colour at bar position t.
export function rampColor(range, t) {
  return ramp(range.kind === 'diverging' ? DIVERGING : SEQUENTIAL, t);
}

export function cssGradient(range) {
  const stops = [];
  for (let i = 0; i <= 8; i++) stops.push(`rgb(${rampColor(range, i / 8).join(',')}) ${(i * 100) / 8}%`);
  return `linear-gradient(to right, ${stops.join(', ')})`;
}

// Linear-space RGB per vertex (three.js colour attributes are linear).
export function curvatureColors(values, range) {
  const lut = [];
  for (let i = 0; i <= 255; i++) lut.push(rampColor(range, i / 255).map(srgbToLinear));
  const bad = NONFINITE_RGB.map(srgbToLinear);
  const out = new Float32Array(values.length * 3);
  for (let i = 0; i < values.length; i++) {
    const v = values[i];
    const c = Number.isFinite(v) ? lut[Math.round(255 * position(range, v))] : bad;
    out[3 * i] = c[0];
    out[3 * i + 1] = c[1];
    out[3 * i + 2] = c[2];
  }
  return out;
}
