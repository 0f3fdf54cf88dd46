// box_view.js — the search box drawn in the 3-D view: its twelve edges as a thin outline, and
// optionally three axes along its lower edges with ticks at round values and their labels
// (sprites), so that a surface can be read against coordinates.
import * as THREE from 'three';
import { niceStep, sig } from './format.js';

const OUTLINE_RGB = 0x7d8aa0;
const AXIS_RGB = { x: 0xff6b6b, y: 0x6bdc6b, z: 0x6ba8ff };
// About this many ticks along each axis.
const TICKS_PER_AXIS = 5;
const LABEL_PX = 48;

function label(text, color, size) {
  const c = document.createElement('canvas');
  c.width = 4 * LABEL_PX;
  c.height = LABEL_PX;
  const g = c.getContext('2d');
  g.font = `${Math.round(LABEL_PX * 0.7)}px system-ui, sans-serif`;
  g.fillStyle = `#${color.toString(16).padStart(6, '0')}`;
  g.textAlign = 'center';
  g.textBaseline = 'middle';
  g.fillText(text, 2 * LABEL_PX, LABEL_PX / 2);
  const tex = new THREE.CanvasTexture(c);
  tex.colorSpace = THREE.SRGBColorSpace;
  const s = new THREE.Sprite(new THREE.SpriteMaterial({ map: tex, depthTest: false, transparent: true }));
  s.scale.set(4 * size, size, 1);
  s.renderOrder = 5;
  return s;
}

// The group for box [xmin ymin zmin xmax ymax zmax]; axes: with ticks and labels.
export function buildBox(box, axes) {
  const group = new THREE.Group();
  group.name = 'box';
  const min = new THREE.Vector3(box[0], box[1], box[2]);
  const max = new THREE.Vector3(box[3], box[4], box[5]);
  const helper = new THREE.Box3Helper(new THREE.Box3(min, max), OUTLINE_RGB);
  helper.material.transparent = true;
  helper.material.opacity = 0.6;
  helper.name = 'box-outline';
  group.add(helper);
  if (!axes) return group;
  const size = max.clone().sub(min);
  const tick = 0.02 * Math.max(size.x, size.y, size.z);
  const pos = [];
  const colors = [];
  const axisGroup = new THREE.Group();
  axisGroup.name = 'box-axes';
  ['x', 'y', 'z'].forEach((name, a) => {
    const lo = box[a], hi = box[a + 3];
    const color = new THREE.Color(AXIS_RGB[name]);
    const start = min.clone();
    const end = min.clone().setComponent(a, hi);
    pos.push(...start.toArray(), ...end.toArray());
    colors.push(...color.toArray(), ...color.toArray());
    // Ticks point away from the box along the next axis (z ticks along x).
    const out = new THREE.Vector3().setComponent((a + 1) % 3, -tick);
    const nice = niceStep(0, (hi - lo) * 200 / TICKS_PER_AXIS);   // about (hi - lo) / TICKS_PER_AXIS
    for (let v = Math.ceil(lo / nice) * nice; v <= hi + 1e-9 * nice; v += nice) {
      const p = min.clone().setComponent(a, v);
      pos.push(...p.toArray(), ...p.clone().add(out).toArray());
      colors.push(...color.toArray(), ...color.toArray());
      const l = label(sig(v), AXIS_RGB[name], 2.2 * tick);
      l.position.copy(p.clone().addScaledVector(out, 3.2));
      axisGroup.add(l);
    }
    const n = label(name, AXIS_RGB[name], 3 * tick);
    n.position.copy(end.clone().addScaledVector(out, 5));
    axisGroup.add(n);
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.Float32BufferAttribute(colors, 3));
  axisGroup.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true })));
  group.add(axisGroup);
  return group;
}

export function disposeBox(group) {
  group.traverse((o) => {
    if (o.geometry) o.geometry.dispose();
    if (o.material) {
      if (o.material.map) o.material.map.dispose();
      o.material.dispose();
    }
  });
}
