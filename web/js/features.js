// features.js — the singular structure drawn over the surface, from the features JSON that
// travels beside the Draco mesh (proto/features.h, version 2) and never from Draco's
// connectivity, which splits vertices along non-manifold edges: the singular curves found
// from f (double curves and whiskers, fat lines coloured by kind), the singular points
// (spheres coloured by type; uncertified ones hollow-looking, half transparent), the mesh's
// non-manifold edges and points that lie off that locus (artefacts, in red), and boundary
// chains. Each is also drawn faintly through the surface, so that structure inside a
// closed-looking surface is not lost. pickFeature finds the point or curve under the mouse.
import * as THREE from 'three';
import { LineSegments2 } from 'three/addons/lines/LineSegments2.js';
import { LineSegmentsGeometry } from 'three/addons/lines/LineSegmentsGeometry.js';
import { LineMaterial } from 'three/addons/lines/LineMaterial.js';

export const FEATURES_VERSION = 2;

export const FEATURE_COLORS = { edges: 0x39e26a, points: 0xffd21f, boundary: 0xff8c1a, artefacts: 0xff2d2d };

// One colour per singular point type and curve kind (the legend shows the ones present).
export const POINT_TYPE_COLORS = {
  node: 0xffd21f, isolated: 0xf4f4f4, cusp: 0x2ec4ff, degenerate: 0xff5fd2, pinch: 0xb07cff, triple: 0xff7a1a,
};
export const CURVE_KIND_COLORS = { double: 0x39e26a, whisker: 0x22d3ee };

// Segment end points (x0 y0 z0 x1 y1 z1 ...) of a list of polylines {closed, xyz}.
function segments(polylines) {
  const out = [];
  for (const line of polylines || []) {
    const p = line.xyz || [];
    for (let i = 0; i + 5 < p.length; i += 3) out.push(p[i], p[i + 1], p[i + 2], p[i + 3], p[i + 4], p[i + 5]);
    const n = p.length;
    if (line.closed && line.kind && n >= 9) out.push(p[n - 3], p[n - 2], p[n - 1], p[0], p[1], p[2]);
  }
  return out;
}

// Structure hidden behind the surface still shows, faintly: each feature is drawn twice, once
// depth-tested at full strength and once through the surface at HIDDEN_OPACITY.
const HIDDEN_OPACITY = 0.3;

export function fatLines(positions, color, width, clippingPlanes) {
  const geometry = new LineSegmentsGeometry();
  geometry.setPositions(positions);
  const group = new THREE.Group();
  const front = new LineSegments2(geometry, new LineMaterial({ color, linewidth: width, clippingPlanes }));
  front.renderOrder = 3;
  const hidden = new LineSegments2(geometry, new LineMaterial({
    color, linewidth: width * 0.7, clippingPlanes, depthTest: false, depthWrite: false,
    transparent: true, opacity: HIDDEN_OPACITY,
  }));
  hidden.renderOrder = 2;
  group.add(hidden, front);
  return group;
}

// Spheres at points [{xyz}], one colour; opacity < 1 for uncertified points.
export function markers(points, radius, color, clippingPlanes, opacity = 1) {
  const sphere = new THREE.SphereGeometry(radius, 16, 12);
  const front = new THREE.MeshStandardMaterial({
    color, emissive: color, emissiveIntensity: 0.35, roughness: 0.4, clippingPlanes,
    transparent: opacity < 1, opacity,
  });
  const hidden = new THREE.MeshBasicMaterial({ color, clippingPlanes, depthTest: false, depthWrite: false, transparent: true, opacity: HIDDEN_OPACITY * opacity });
  const group = new THREE.Group();
  const m = new THREE.Matrix4();
  for (const [material, order] of [[hidden, 2], [front, 3]]) {
    const inst = new THREE.InstancedMesh(sphere, material, points.length);
    points.forEach((p, i) => inst.setMatrixAt(i, m.makeTranslation(p.xyz[0], p.xyz[1], p.xyz[2])));
    inst.instanceMatrix.needsUpdate = true;
    inst.renderOrder = order;
    group.add(inst);
  }
  return group;
}

const valid = (p) => p && Array.isArray(p.xyz) && p.xyz.length === 3;

// Counts of points by type and curves by kind, for the legend.
function tally(list, field) {
  const out = {};
  for (const item of list) out[item[field]] = (out[item[field]] || 0) + 1;
  return out;
}

// Builds {group, edges, points, boundary, counts, types, kinds, pickables} for features f.
// radius: marker size. edges: singular curves + artefact edges; points: singular points +
// artefact points.
export function buildFeatures(f, radius, clippingPlanes) {
  const group = new THREE.Group();
  group.name = 'features';
  const made = {
    group, edges: null, points: null, boundary: null,
    counts: { edges: 0, points: 0, boundary: 0, artefacts: 0 }, types: {}, kinds: {}, pickables: [],
  };
  if (!f) return made;
  if (f.version !== FEATURES_VERSION) throw new Error(`features JSON version ${f.version} is not understood (expected ${FEATURES_VERSION})`);

  made.edges = new THREE.Group();
  made.edges.name = 'singular-curves';
  const curves = (f.curves || []).filter((c) => Array.isArray(c.xyz) && c.xyz.length >= 6);
  for (const [kind, color] of Object.entries(CURVE_KIND_COLORS)) {
    const pos = segments(curves.filter((c) => c.kind === kind));
    if (pos.length) made.edges.add(fatLines(pos, color, kind === 'whisker' ? 2.5 : 3.5, clippingPlanes));
    made.counts.edges += pos.length / 6;
  }
  made.kinds = tally(curves, 'kind');
  // Only the edges the check counts (off_edges: an end off the locus), so the key's number
  // equals counts.artefacts; a whole chain when the JSON lists no off_edges.
  const offEdges = (f.nonmanifold_edges || []).filter((c) => c.on_locus === false)
    .flatMap((c) => (Array.isArray(c.off_edges) ? c.off_edges.map((j) => ({ xyz: c.xyz.slice(3 * j, 3 * j + 6) })) : [c]));
  const offPos = segments(offEdges);
  if (offPos.length) made.edges.add(fatLines(offPos, FEATURE_COLORS.artefacts, 2, clippingPlanes));
  group.add(made.edges);

  const boundPos = segments(f.boundaries);
  if (boundPos.length) {
    made.boundary = fatLines(boundPos, FEATURE_COLORS.boundary, 2.5, clippingPlanes);
    made.boundary.name = 'boundary-edges';
    group.add(made.boundary);
  }
  // the mesh's boundary edges: the JSON draws its chains thinned (features.h's tolerance)
  made.counts.boundary = f.counts && Number.isInteger(f.counts.boundary_edges) ? f.counts.boundary_edges : boundPos.length / 6;

  made.points = new THREE.Group();
  made.points.name = 'singular-points';
  const pts = (f.singular_points || []).filter(valid);
  for (const [type, color] of Object.entries(POINT_TYPE_COLORS)) {
    for (const certified of [true, false]) {
      const some = pts.filter((p) => p.type === type && !!p.certified === certified);
      if (some.length) made.points.add(markers(some, radius, color, clippingPlanes, certified ? 1 : 0.45));
    }
  }
  made.types = tally(pts, 'type');
  made.counts.points = pts.length;
  const offPts = (f.nonmanifold_points || []).filter((p) => valid(p) && p.on_locus === false);
  if (offPts.length) made.points.add(markers(offPts, radius * 0.6, FEATURE_COLORS.artefacts, clippingPlanes));
  group.add(made.points);
  made.counts.artefacts = offPts.length + offPos.length / 6;

  made.pickables = [
    ...pts.map((p) => ({ what: 'point', p, at: [p.xyz] })),
    ...curves.map((c) => {
      const at = [];
      for (let i = 0; i + 2 < c.xyz.length; i += 3) at.push([c.xyz[i], c.xyz[i + 1], c.xyz[i + 2]]);
      return { what: 'curve', p: c, at };
    }),
  ];
  return made;
}

// The singular point or curve drawn within maxPx pixels of (px, py) on a canvas of the given
// size, or null: {what: 'point'|'curve', p (its JSON), xyz (the nearest vertex)}. Points win
// over curves at equal distance.
export function pickFeature(made, camera, width, height, px, py, maxPx = 10) {
  let best = null;
  let bestD = maxPx;
  const v = new THREE.Vector3();
  for (const item of made ? made.pickables : []) {
    for (const xyz of item.at) {
      v.set(xyz[0], xyz[1], xyz[2]).project(camera);
      if (v.z < -1 || v.z > 1) continue;
      const sx = (v.x + 1) / 2 * width, sy = (1 - v.y) / 2 * height;
      const d = Math.hypot(sx - px, sy - py) - (item.what === 'point' ? 1 : 0);
      if (d < bestD) {
        bestD = d;
        best = { what: item.what, p: item.p, xyz };
      }
    }
  }
  return best;
}

export function setLineResolution(made, width, height) {
  made.group.traverse((o) => {
    if (o.material && o.material.isLineMaterial) o.material.resolution.set(width, height);
  });
}

export function disposeFeatures(made) {
  made.group.traverse((o) => {
    if (o.geometry) o.geometry.dispose();
    if (o.material) o.material.dispose();
    if (o.isInstancedMesh) o.dispose();
  });
}
