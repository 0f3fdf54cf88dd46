// features.js — the non-manifold structure drawn over the surface, from the features JSON that
// travels beside the Draco mesh (proto/features.h) and never from Draco's connectivity, which
// splits vertices along non-manifold edges: non-manifold curves as fat lines, non-manifold
// points as small spheres, boundary chains as fat lines in another colour; each also faintly
// through the surface, so that structure inside a closed-looking surface is not lost.
import * as THREE from 'three';
import { LineSegments2 } from 'three/addons/lines/LineSegments2.js';
import { LineSegmentsGeometry } from 'three/addons/lines/LineSegmentsGeometry.js';
import { LineMaterial } from 'three/addons/lines/LineMaterial.js';

export const FEATURE_COLORS = { edges: 0x39e26a, points: 0xffd21f, boundary: 0xff8c1a };

// Segment end points (x0 y0 z0 x1 y1 z1 ...) of a list of polylines {closed, xyz}.
function segments(polylines) {
  const out = [];
  for (const line of polylines || []) {
    const p = line.xyz || [];
    for (let i = 0; i + 5 < p.length; i += 3) out.push(p[i], p[i + 1], p[i + 2], p[i + 3], p[i + 4], p[i + 5]);
  }
  return out;
}

// Structure hidden behind the surface still shows, faintly: each feature is drawn twice, once
// depth-tested at full strength and once through the surface at HIDDEN_OPACITY.
const HIDDEN_OPACITY = 0.3;

function fatLines(positions, color, width, clippingPlanes) {
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

function markers(points, radius, clippingPlanes) {
  const sphere = new THREE.SphereGeometry(radius, 16, 12);
  const color = FEATURE_COLORS.points;
  const front = new THREE.MeshStandardMaterial({ color, emissive: color, emissiveIntensity: 0.35, roughness: 0.4, clippingPlanes });
  const hidden = new THREE.MeshBasicMaterial({ color, clippingPlanes, depthTest: false, depthWrite: false, transparent: true, opacity: HIDDEN_OPACITY });
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

// Builds {group, edges, points, boundary, counts} for features f. radius: marker size.
export function buildFeatures(f, radius, clippingPlanes) {
  const group = new THREE.Group();
  group.name = 'features';
  const made = { group, edges: null, points: null, boundary: null, counts: { edges: 0, points: 0, boundary: 0 } };
  if (!f) return made;
  if (f.version !== 1) throw new Error(`features JSON version ${f.version} is not understood (expected 1)`);

  const edgePos = segments(f.curves);
  if (edgePos.length) {
    made.edges = fatLines(edgePos, FEATURE_COLORS.edges, 3.5, clippingPlanes);
    made.edges.name = 'nonmanifold-edges';
    group.add(made.edges);
  }
  made.counts.edges = edgePos.length / 6;

  const boundPos = segments(f.boundaries);
  if (boundPos.length) {
    made.boundary = fatLines(boundPos, FEATURE_COLORS.boundary, 2.5, clippingPlanes);
    made.boundary.name = 'boundary-edges';
    group.add(made.boundary);
  }
  made.counts.boundary = boundPos.length / 6;

  const pts = (f.points || []).filter((p) => p.xyz && p.xyz.length === 3);
  if (pts.length) {
    made.points = markers(pts, radius, clippingPlanes);
    made.points.name = 'nonmanifold-points';
    group.add(made.points);
  }
  made.counts.points = pts.length;
  return made;
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
