// section.js — the section curve where the clipping plane cuts the surface: for every triangle
// whose corners lie on both sides of the plane coordinate[axis] = offset, the segment between
// the two points where its edges cross the plane (linear interpolation along each edge).
// Drawn as fat lines on the plane, so the cut reads as a curve even on open or non-manifold
// surfaces (a stencil cap needs a closed surface).
import { LineSegments2 } from 'three/addons/lines/LineSegments2.js';
import { LineSegmentsGeometry } from 'three/addons/lines/LineSegmentsGeometry.js';
import { LineMaterial } from 'three/addons/lines/LineMaterial.js';

const SECTION_RGB = 0xfff3b0;
const SECTION_WIDTH = 3;

// Segment end points (x0 y0 z0 x1 y1 z1 ...) of the section of the indexed triangles.
export function sectionSegments(position, index, axis, offset) {
  const out = [];
  const d = (v) => position[3 * v + axis] - offset;
  const cross = (a, b) => {
    const t = d(a) / (d(a) - d(b));
    for (let k = 0; k < 3; k++) out.push(k === axis ? offset : position[3 * a + k] + t * (position[3 * b + k] - position[3 * a + k]));
  };
  for (let i = 0; i + 2 < index.length; i += 3) {
    const v = [index[i], index[i + 1], index[i + 2]];
    const s = v.map((x) => d(x) > 0);
    if (s[0] === s[1] && s[1] === s[2]) continue;
    // The corner alone on its side, then the two edges from it.
    const lone = s[0] === s[1] ? 2 : s[0] === s[2] ? 1 : 0;
    const a = v[lone], b = v[(lone + 1) % 3], c = v[(lone + 2) % 3];
    cross(a, b);
    cross(a, c);
  }
  return out;
}

// The line object for segments (null when there are none).
export function sectionLines(segments, width, height) {
  if (!segments.length) return null;
  const g = new LineSegmentsGeometry();
  g.setPositions(segments);
  const m = new LineMaterial({ color: SECTION_RGB, linewidth: SECTION_WIDTH });
  m.resolution.set(width, height);
  const lines = new LineSegments2(g, m);
  lines.name = 'section';
  lines.renderOrder = 4;
  lines.frustumCulled = false;
  return lines;
}
