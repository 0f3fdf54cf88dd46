// viewer.js — the three.js scene: z-up perspective camera with OrbitControls (orbit, pan, zoom,
// keyboard), two-sided lighting (a headlight riding with the camera plus a hemisphere light,
// on a DoubleSide material whose back faces get flipped normals, so a self-intersecting or
// one-sided surface is lit the same from either side), the surface with its colour modes, the
// wireframe overlay, the non-manifold features, the requested curves and their cells
// (curves.js), double sheets tinted, one clipping plane, fit-to-view, and the render mode
// with ambient occlusion (occlusion.js: computed in the background per mesh and cut when first
// shown in that mode, kept per vertex, each side its own; plain shading until then) and soft
// shadows from three.js's shadow mapping (shadows.js: a key light fixed in the world,
// self-shadowing and a ground plane; a toggle of its own). Draws on demand (at most once per
// animation frame), not in a loop.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { buildFeatures, disposeFeatures, pickFeature, setLineResolution } from './features.js';
import { buildCurves, cellColors } from './curves.js';
import { curvatureColors, curvatureRange, RANGE_CUTS } from './colormap.js';
import { buildBox, disposeBox } from './box_view.js';
import { sectionSegments, sectionLines } from './section.js';
import { buildCap, disposeCap } from './cap.js';
import { Shadows, HEADLIGHT_SCALE } from './shadows.js';
import { bakeOcclusion } from './occlusion.js';
import * as timeline from './timeline.js';
import { gpuDone } from './gpu.js';

const SURFACE_RGB = 0xb9c6d8;
// Two-sided colouring: triangles face along grad f (the outside, f > 0), so back faces show
// the inside; they are tinted warm (multiplies the surface colour in the shaded mode).
const INSIDE_TINT = [1.12, 0.82, 0.55];
// Double sheets (f = g², no sign change) in the shaded mode: a violet surface colour.
const SHEET_RGB = 0xb58cff;
const AXES = { x: new THREE.Vector3(1, 0, 0), y: new THREE.Vector3(0, 1, 0), z: new THREE.Vector3(0, 0, 1) };
const DEFAULT_DIRECTION = new THREE.Vector3(1.5, -2.1, 1.25).normalize();
// Largest exported image side (every WebGL2 implementation renders at least 4096; 8192 is
// common but not promised, so a larger request is clamped).
const MAX_EXPORT_PX = 4096;
// The render mode waits this long after the mesh or the cut last changed before it computes
// the occlusion (a dragged clip slider would otherwise restart it at every step).
const BAKE_SETTLE_MS = 200;
// Occlusions kept per mesh, one per cut (the whole mesh and the last few cuts).
const OCCLUSION_CUTS_KEPT = 3;
// A live preview is drawn at PREVIEW_SCALE of the pixel ratio when the last full-resolution
// frame kept the GPU busy longer than SLOW_FRAME_MS (software GL: ~100-250 ms a frame at
// 900x750 px, 2-3x less at half the side), so that the picture follows the slider; the
// refined mesh is drawn at full resolution again. A GPU draws a frame in a few ms: its
// previews stay sharp.
const SLOW_FRAME_MS = 50;
const PREVIEW_SCALE = 0.5;

export class Viewer {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.baseRatio = Math.min(window.devicePixelRatio || 1, 2);
    this.renderer.setPixelRatio(this.baseRatio);
    this.frameMs = 0;          // GPU time of the last full-resolution frame (measureFrame)
    this.measuring = false;
    this.settledWaiters = [];
    this.renderer.localClippingEnabled = true;
    this.renderer.setClearColor(0x000000, 0);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1000);
    this.camera.up.set(0, 0, 1);
    this.camera.position.copy(DEFAULT_DIRECTION).multiplyScalar(5);
    this.scene.add(this.camera);

    this.scene.add(new THREE.HemisphereLight(0xf2f5ff, 0x39404c, 1.1));
    const head = new THREE.DirectionalLight(0xffffff, 1.9);
    head.position.set(0.35, 0.55, 1);      // camera space: above and right of the eye
    this.camera.add(head);
    this.camera.add(head.target);
    head.target.position.set(0, 0, -1);
    const fill = new THREE.DirectionalLight(0xcfd8ff, 0.45);
    fill.position.set(-0.6, -0.3, 0.4);
    this.camera.add(fill);
    this.camera.add(fill.target);
    fill.target.position.set(0, 0, -1);
    this.headLights = [head, fill];
    this.shadows = new Shadows(this.scene, this.renderer);

    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false;
    this.controls.screenSpacePanning = true;
    this.controls.listenToKeyEvents(canvas);
    this.controls.addEventListener('change', () => {
      this.render();
      if (this.onViewChange) this.onViewChange();
    });
    canvas.addEventListener('keydown', (e) => this.onKey(e));

    this.clipPlane = new THREE.Plane(new THREE.Vector3(0, 0, -1), 0);
    this.clipping = [];
    this.material = new THREE.MeshStandardMaterial({
      color: SURFACE_RGB, side: THREE.DoubleSide, roughness: 0.55, metalness: 0.05,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
      clipShadows: true,   // what the clipping plane removes casts no shadow
    });
    this.backTint = { value: new THREE.Color(1, 1, 1) };
    this.twoSided = true;
    // The render mode: the light each side of a vertex keeps (attribute occlusion: outside,
    // inside; occlusion.js) multiplies the shading when occlusionStrength is 1.
    this.occlusionStrength = { value: 0 };
    this.material.onBeforeCompile = (shader) => {
      shader.uniforms.backTint = this.backTint;
      shader.uniforms.occlusionStrength = this.occlusionStrength;
      shader.vertexShader = shader.vertexShader
        .replace('void main() {', 'attribute vec2 occlusion;\nvarying vec2 vOcclusion;\nvoid main() {\n\tvOcclusion = occlusion;');
      shader.fragmentShader = shader.fragmentShader
        .replace('void main() {', 'uniform vec3 backTint;\nuniform float occlusionStrength;\nvarying vec2 vOcclusion;\nvoid main() {')
        .replace('#include <color_fragment>', '#include <color_fragment>\n\tif (!gl_FrontFacing) diffuseColor.rgb *= backTint;')
        .replace('#include <opaque_fragment>', 'outgoingLight *= mix(1.0, gl_FrontFacing ? vOcclusion.x : vOcclusion.y, occlusionStrength);\n\t#include <opaque_fragment>');
    };
    this.section = null;
    this.wireMaterial = new THREE.MeshBasicMaterial({
      color: 0x0c1016, wireframe: true, transparent: true, opacity: 0.45, depthWrite: false,
    });
    this.surface = null;
    this.wire = null;
    this.features = null;
    this.curves = null;
    this.data = null;
    this.colorMode = 'shaded';
    // Per colour map, the colormap.RANGE_CUTS key of the percentiles its colours span: each
    // map keeps its own (H and K differ in how heavy their tails are).
    this.rangeCuts = { mean: 'p2', gauss: 'p2' };
    this.show = { edges: true, points: true, boundary: true, curves: true };
    this.wireframe = false;
    this.bounds = new THREE.Box3(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
    this.frames = 0;
    this.framePending = false;
    this.occlusion = false;    // the render mode (ambient occlusion)

    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  resize() {
    const w = Math.max(1, this.canvas.clientWidth);
    const h = Math.max(1, this.canvas.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.setLineResolution(w, h);
    if (this.section) this.section.material.resolution.set(w, h);
    this.render();
  }

  setLineResolution(w, h) {
    if (this.features) setLineResolution(this.features, w, h);
    if (this.curves) setLineResolution(this.curves, w, h);
  }

  // Asks for a frame; any number of changes within one animation frame draw once.
  render() {
    this.dirty = true;
    if (this.framePending) return;
    this.framePending = true;
    requestAnimationFrame(() => {
      this.framePending = false;
      if (this.dirty) this.draw();
      else this.releaseSettled();
    });
  }

  // Draws now rather than at the next animation frame (a live preview: when the GPU is slow the
  // next frame may be long in coming); a frame already asked for then draws only if something
  // changes meanwhile.
  drawNow() {
    this.draw();
  }

  draw() {
    this.dirty = false;
    this.fitResolution();
    this.updateClipRange();
    this.applyOcclusion();
    this.renderer.render(this.scene, this.camera);
    this.frames++;
    this.measureFrame(timeline.drawn());
  }

  // The drawing buffer's pixel ratio for this frame: reduced for a live preview when frames
  // are slow (SLOW_FRAME_MS). Changed here, right before drawing, so no script or compositor
  // ever sees the cleared buffer a resize leaves.
  fitResolution() {
    if (this.exporting) return;           // exportPng has set its own size
    const ratio = this.preview && this.frameMs > SLOW_FRAME_MS ? this.baseRatio * PREVIEW_SCALE : this.baseRatio;
    if (ratio === this.renderer.getPixelRatio()) return;
    this.renderer.setPixelRatio(ratio);
    this.renderer.setSize(Math.max(1, this.canvas.clientWidth), Math.max(1, this.canvas.clientHeight), false);
  }

  // Times the frame just issued until the GPU has done it (a fence: the page runs meanwhile);
  // one fence at a time: a frame issued meanwhile gets the next one. Full-resolution frames
  // set frameMs. entry: the timeline entry this frame first drew, or null.
  measureFrame(entry) {
    if (entry) gpuDone(this.renderer.getContext()).then(() => timeline.gpuDone(entry));
    if (this.measuring) {
      this.unmeasured = true;
      return;
    }
    this.measuring = true;
    const full = this.renderer.getPixelRatio() === this.baseRatio;
    const t0 = performance.now();
    gpuDone(this.renderer.getContext()).then(() => {
      this.measuring = false;
      if (full) this.frameMs = performance.now() - t0;
      if (this.unmeasured) {
        this.unmeasured = false;
        this.measureFrame(null);
        return;
      }
      this.releaseSettled();
    });
  }

  // Resolves once the frames asked for so far are drawn and done by the GPU.
  settled() {
    if (!this.measuring && !this.dirty) return Promise.resolve();
    return new Promise((resolve) => this.settledWaiters.push(resolve));
  }

  releaseSettled() {
    if (this.measuring || this.dirty) return;   // a frame is still to come or on the GPU
    const waiters = this.settledWaiters;
    this.settledWaiters = [];
    for (const w of waiters) w();
  }

  // The render mode: ambient occlusion over the shading (true) or the plain shading.
  // A frame is drawn only when the look changes: until the occlusion is computed the surface
  // stays plain, and in software GL every frame of a large mesh holds the page (the compositor
  // reads it back) for as long as the GPU takes to draw it.
  setOcclusion(on) {
    this.occlusion = on;
    if (this.applyOcclusion()) this.render();
  }

  // The render mode's occlusion of the shown mesh, computed in the background (occlusion.js:
  // batches on the GPU between which the page runs) the first time the mesh is drawn in that
  // mode with the current cut, and kept with the decoded mesh per cut; until it is there the
  // surface is drawn plain. A live preview is always drawn plain. canvas[data-look] says which
  // look the last frame has, canvas[data-occlusion] 'computing' while a bake runs. Returns
  // whether the look changed (then a frame must show it).
  applyOcclusion() {
    const g = this.surface && this.surface.geometry;
    const m = this.data && this.data.mesh;
    const want = this.occlusion && !this.preview && g && g.attributes.normal;
    const cut = this.cutKey();
    let swapped = false;
    if (want) {
      const light = m.occlusion && m.occlusion.get(cut);
      if (light && g.userData.occlusionCut !== cut) {
        g.setAttribute('occlusion', new THREE.BufferAttribute(light, 2));
        g.userData.occlusionCut = cut;
        swapped = true;
      } else if (!light && !(this.bake && this.bake.mesh === m && this.bake.cut === cut)) {
        this.startBake(m, g, cut);
      }
    } else if (this.bake) {
      this.bake = null;           // the running bake stops at its next batch
    }
    const on = !!(want && g.attributes.occlusion && g.userData.occlusionCut === cut);
    const changed = this.occlusionStrength.value !== (on ? 1 : 0) || swapped;
    this.occlusionStrength.value = on ? 1 : 0;
    this.canvas.dataset.look = on ? 'occlusion' : 'plain';
    this.canvas.dataset.occlusion = this.bake ? 'computing' : (on ? 'done' : 'off');
    return changed;
  }

  // The render mode's soft shadows (shadows.js) on or off: the key light and the ground, the
  // headlights dimmed meanwhile, the cap lit (and shadowed) or flat to match.
  setShadows(on) {
    if (this.shadows.setOn(on)) {
      for (const l of this.headLights) {
        if (l.userData.base === undefined) l.userData.base = l.intensity;
        l.intensity = l.userData.base * (on ? HEADLIGHT_SCALE : 1);
      }
      this.render();
    }
    if (this.cap) this.cap.material = on ? this.cap.userData.lit : this.cap.userData.flat;
  }

  // What the clipping removes, as a key of the occlusion computed without it ('' for nothing).
  cutKey() {
    const p = this.clipping[0];
    return p ? `${p.normal.toArray().join(',')}|${p.constant}` : '';
  }

  // Computes m's occlusion for cut once the cut has held still for BAKE_SETTLE_MS (a clip
  // slider being dragged starts nothing); a newer bake, another mesh or leaving the render
  // mode abandons it. onOcclusion(computing) tells the page.
  startBake(m, g, cut) {
    const mine = { mesh: m, cut };
    this.bake = mine;
    const plane = this.clipping[0] ? this.clipping[0].clone() : null;
    const alive = () => this.bake === mine;
    setTimeout(async () => {
      if (!alive()) return;
      if (this.onOcclusion) this.onOcclusion(true);
      const t0 = performance.now();
      let light = null;
      try {
        light = await bakeOcclusion(this.renderer, g, { keep: plane, alive });
      } finally {
        if (alive()) this.bake = null;
        if (this.onOcclusion) this.onOcclusion(false);
      }
      if (!light) return;
      this.occlusionMs = performance.now() - t0;
      if (!m.occlusion) m.occlusion = new Map();
      m.occlusion.delete(cut);
      m.occlusion.set(cut, light);
      while (m.occlusion.size > OCCLUSION_CUTS_KEPT) m.occlusion.delete(m.occlusion.keys().next().value);
      this.render();
    }, BAKE_SETTLE_MS);
    this.canvas.dataset.occlusion = 'computing';
  }

  onKey(e) {
    // OrbitControls' "dolly out" shrinks the orbit radius: closer, a zoom in.
    if (e.key === '+' || e.key === '=') this.controls.dollyOut(1.15);
    else if (e.key === '-' || e.key === '_') this.controls.dollyIn(1.15);
    else if (e.key === 'f' || e.key === 'F') this.fit();
    else return;
    e.preventDefault();
    this.controls.update();
  }

  // Shows a decoded mesh (loader.js) with its features; box: the request's search box;
  // glsl: f as GLSL ({lets, f} from expr.js) for the clip cap, or null; preview: a coarse live
  // preview (drawn plain in the render mode: its occlusion would slow the drag down).
  setMesh(result, box, glsl = null, preview = false) {
    this.clearMesh();
    this.data = result;
    this.preview = preview;
    this.glsl = glsl;
    this.bounds = new THREE.Box3(new THREE.Vector3(box[0], box[1], box[2]), new THREE.Vector3(box[3], box[4], box[5]));
    this.setBox(box);
    const m = result.mesh;
    if (m) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(m.attributes.position, 3));
      if (m.attributes.normal) g.setAttribute('normal', new THREE.BufferAttribute(m.attributes.normal, 3));
      else g.computeVertexNormals();
      g.setIndex(new THREE.BufferAttribute(m.index, 1));
      g.computeBoundingBox();
      g.computeBoundingSphere();
      this.surface = new THREE.Mesh(g, this.material);
      this.surface.name = 'surface';
      this.surface.castShadow = this.surface.receiveShadow = true;
      this.wire = new THREE.Mesh(g, this.wireMaterial);
      this.wire.name = 'wireframe';
      this.wire.renderOrder = 1;
      this.scene.add(this.surface, this.wire);
      if (!g.boundingBox.isEmpty()) this.bounds = g.boundingBox.clone();
    }
    this.shadows.fit(this.bounds);
    const size = this.bounds.getSize(new THREE.Vector3()).length();
    this.features = buildFeatures(result.features, 0.009 * size, this.clipping);
    this.features.group.traverse((o) => { o.frustumCulled = false; });
    this.curves = buildCurves(result.features, this.clipping, 0.009 * size);
    this.setLineResolution(Math.max(1, this.canvas.clientWidth), Math.max(1, this.canvas.clientHeight));
    this.scene.add(this.features.group, this.curves.group);
    this.applyColor();
    this.applyVisibility();
    this.applyClip();
    this.render();
  }

  // The search box drawn as an outline (show.box), with axes and ticks (show.axes).
  setBox(box) {
    if (box) this.box = box.slice();
    const want = this.box && this.show.box !== false ? `${this.box.join(',')}|${!!this.show.axes}` : '';
    if (want === this.boxDrawn) return;
    if (this.boxGroup) {
      this.scene.remove(this.boxGroup);
      disposeBox(this.boxGroup);
      this.boxGroup = null;
    }
    this.boxDrawn = want;
    if (want) {
      this.boxGroup = buildBox(this.box, !!this.show.axes);
      this.scene.add(this.boxGroup);
    }
    this.render();
  }

  clearMesh() {
    if (this.surface) {
      this.scene.remove(this.surface, this.wire);
      this.surface.geometry.dispose();
    }
    for (const made of [this.features, this.curves]) {
      if (!made) continue;
      this.scene.remove(made.group);
      disposeFeatures(made);
    }
    this.surface = this.wire = this.features = this.curves = this.data = null;
  }

  // Colour mode 'shaded' | 'mean' | 'gauss'. Returns the legend's range (null when shaded or
  // when the mesh carries no such attribute).
  setColorMode(mode) {
    this.colorMode = mode;
    const legend = this.applyColor();
    this.render();
    return legend;
  }

  // Per-point colours that are not a curvature scale: cells (colour mode 'cells'), or the
  // shaded surface with its double sheets tinted; null when the mesh has no such attribute.
  labelColors() {
    const m = this.data.mesh;
    const cache = m.colors || (m.colors = {});
    if (this.colorMode === 'cells') {
      if (!m.attributes.cell) return null;
      return cache.cells || (cache.cells = cellColors(m.attributes.cell));
    }
    const sheet = m.attributes.double_sheet;
    if (this.colorMode !== 'shaded' || !sheet || !sheet.some((v) => v)) return null;
    if (!cache.sheets) {
      const base = new THREE.Color(SURFACE_RGB), tint = new THREE.Color(SHEET_RGB);
      const rgb = new Float32Array(sheet.length * 3);
      for (let i = 0; i < sheet.length; i++) (sheet[i] ? tint : base).toArray(rgb, 3 * i);
      cache.sheets = rgb;
    }
    return cache.sheets;
  }

  applyColor() {
    if (!this.surface) return null;
    const g = this.surface.geometry;
    const attr = { mean: 'mean_curvature', gauss: 'gauss_curvature' }[this.colorMode];
    const values = attr && this.data.mesh.attributes[attr];
    const labels = values ? null : this.labelColors();
    const tint = this.twoSided && !values && this.colorMode !== 'cells' ? INSIDE_TINT : [1, 1, 1];
    this.backTint.value.setRGB(tint[0], tint[1], tint[2]);
    if (labels) {
      g.setAttribute('color', new THREE.BufferAttribute(labels, 3));
      this.material.vertexColors = true;
      this.material.color.setHex(0xffffff);
      this.material.needsUpdate = true;
      return null;
    }
    if (!values) {
      g.deleteAttribute('color');
      this.material.vertexColors = false;
      this.material.color.setHex(SURFACE_RGB);
      this.material.needsUpdate = true;
      return null;
    }
    const cache = this.data.mesh.colors || (this.data.mesh.colors = {});
    const cut = this.rangeCutOf(this.colorMode);
    const slot = `${attr}|${cut}`;
    if (!cache[slot]) {
      const range = curvatureRange(values, RANGE_CUTS[cut] ?? RANGE_CUTS.p2);
      cache[slot] = { range, rgb: curvatureColors(values, range) };
    }
    cache[attr] = cache[slot];
    g.setAttribute('color', new THREE.BufferAttribute(cache[attr].rgb, 3));
    this.material.vertexColors = true;
    this.material.color.setHex(0xffffff);
    this.material.needsUpdate = true;
    return cache[attr].range;
  }

  // The range cut (colormap.RANGE_CUTS key) colour mode mode uses.
  rangeCutOf(mode) {
    return this.rangeCuts[mode] || 'p2';
  }

  // The percentiles the current curvature map's colours span (colormap.RANGE_CUTS key; the
  // map keeps it); returns the legend.
  setRangeCut(cut) {
    if (this.colorMode in this.rangeCuts) this.rangeCuts[this.colorMode] = cut;
    const legend = this.applyColor();
    this.render();
    return legend;
  }

  // Inside and outside in two colours (shaded mode).
  setTwoSided(on) {
    this.twoSided = on;
    this.applyColor();
    this.render();
  }

  setVisibility(show) {
    this.show = { ...show };
    this.setBox();
    this.applyVisibility();
    this.render();
  }

  applyVisibility() {
    if (!this.features) return;
    for (const k of ['edges', 'points', 'boundary']) if (this.features[k]) this.features[k].visible = !!this.show[k];
    if (this.curves) this.curves.group.visible = this.show.curves !== false;
  }

  // The singular point, singular curve or requested curve ('cut') under canvas pixel (x, y),
  // or null (features.js pickFeature). Hidden layers are not picked.
  pick(x, y) {
    if (!this.features) return null;
    const pickables = [...this.features.pickables.filter((p) => (p.what === 'point' ? this.show.points : this.show.edges) !== false),
      ...(this.curves && this.show.curves !== false ? this.curves.pickables : [])];
    return pickFeature({ pickables }, this.camera, this.canvas.clientWidth, this.canvas.clientHeight, x, y);
  }

  // The arrangement cell of triangle face (its points all carry it), or null.
  cellOf(face) {
    const m = this.data && this.data.mesh;
    if (!m || !m.attributes.cell || face === undefined) return null;
    return m.attributes.cell[m.index[3 * face]];
  }

  // The surface point under canvas pixel (x, y): {xyz, face (triangle index)} or null. Points
  // removed by the clipping plane are skipped.
  pickSurface(x, y) {
    if (!this.surface) return null;
    const ndc = new THREE.Vector2(2 * x / this.canvas.clientWidth - 1, 1 - 2 * y / this.canvas.clientHeight);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const hits = ray.intersectObject(this.surface, false);
    const kept = hits.find((h) => this.clipping.every((p) => p.distanceToPoint(h.point) >= 0));
    return kept ? { xyz: kept.point.toArray(), face: kept.faceIndex } : null;
  }

  setWireframe(on) {
    this.wireframe = on;
    if (this.wire) this.wire.visible = on;
    this.render();
  }

  // clip: {on, axis 'x'|'y'|'z', offset (world units), flip, cap}. Keeps the side where the
  // coordinate is below the offset (above with flip).
  setClip(clip) {
    this.clip = { ...clip };
    this.applyClip();
    this.render();
  }

  applyClip() {
    const c = this.clip || { on: false };
    this.clipping.length = 0;
    if (c.on) {
      const n = AXES[c.axis] || AXES.z;
      if (c.flip) this.clipPlane.set(n.clone(), -c.offset);
      else this.clipPlane.set(n.clone().negate(), c.offset);
      this.clipping.push(this.clipPlane);
    }
    this.material.clippingPlanes = this.clipping.length ? this.clipping : null;
    this.wireMaterial.clippingPlanes = this.material.clippingPlanes;
    if (this.wire) this.wire.visible = this.wireframe;
    for (const made of [this.features, this.curves]) {
      if (!made) continue;
      made.group.traverse((o) => {
        if (o.material) {
          o.material.clippingPlanes = this.material.clippingPlanes;
          o.material.needsUpdate = true;
        }
      });
    }
    this.material.needsUpdate = true;
    this.wireMaterial.needsUpdate = true;
    this.updateSection();
    this.updateCap();
    this.shadows.markDirty();
  }

  // The cap of the clipping plane (cap.js), drawn from f; rebuilt when the cut moves.
  updateCap() {
    if (this.cap) {
      this.scene.remove(this.cap);
      disposeCap(this.cap);
      this.cap = null;
    }
    if (!this.data) return; // an empty mesh still has a cap when the box lies inside f < 0
    this.cap = buildCap(this.clip, this.box, this.glsl);
    if (this.cap) {
      if (this.shadows.on) this.cap.material = this.cap.userData.lit;
      this.scene.add(this.cap);
    }
  }

  // The section curve of the clipping plane (section.js), rebuilt when the cut moves.
  updateSection() {
    if (this.section) {
      this.scene.remove(this.section);
      this.section.geometry.dispose();
      this.section.material.dispose();
      this.section = null;
    }
    const c = this.clip || { on: false };
    if (!c.on || !this.data || !this.data.mesh) return;
    const m = this.data.mesh;
    const axis = { x: 0, y: 1, z: 2 }[c.axis] ?? 2;
    this.sectionSegments = sectionSegments(m.attributes.position, m.index, axis, c.offset);
    this.section = sectionLines(this.sectionSegments, Math.max(1, this.canvas.clientWidth), Math.max(1, this.canvas.clientHeight));
    if (this.section) this.scene.add(this.section);
  }

  updateClipRange() {
    const d = this.camera.position.distanceTo(this.controls.target);
    const r = Math.max(1e-6, this.bounds.getSize(new THREE.Vector3()).length() / 2);
    this.camera.near = Math.max(d - 4 * r, d / 1000, 1e-4);
    this.camera.far = d + 4 * r;
    this.camera.updateProjectionMatrix();
  }

  // Frames the surface (or the box when empty), keeping the current viewing direction.
  fit() {
    const sphere = this.bounds.getBoundingSphere(new THREE.Sphere());
    const dir = this.camera.position.clone().sub(this.controls.target);
    if (dir.lengthSq() < 1e-12) dir.copy(DEFAULT_DIRECTION);
    dir.normalize();
    const fov = THREE.MathUtils.degToRad(this.camera.fov);
    const fovMin = Math.min(fov, 2 * Math.atan(Math.tan(fov / 2) * this.camera.aspect));
    const dist = (sphere.radius / Math.sin(fovMin / 2)) * 1.02;
    this.controls.target.copy(sphere.center);
    this.camera.position.copy(sphere.center).addScaledVector(dir, dist);
    this.controls.update();
  }

  // The current view rendered at width x height pixels (the camera's framing kept, its aspect
  // taken from the new size) as a PNG Blob; the canvas is restored afterwards.
  async exportPng(width, height) {
    const w = Math.max(16, Math.min(MAX_EXPORT_PX, Math.round(width)));
    const h = Math.max(16, Math.min(MAX_EXPORT_PX, Math.round(height)));
    this.renderer.setPixelRatio(1);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.setLineResolution(w, h);
    this.exporting = true;
    try {
      this.draw();
    } finally {
      this.exporting = false;
    }
    const blob = await new Promise((resolve) => this.canvas.toBlob(resolve, 'image/png'));
    this.renderer.setPixelRatio(this.baseRatio);
    this.resize();
    return blob;
  }

  resetDirection() {
    this.camera.position.copy(this.controls.target).addScaledVector(DEFAULT_DIRECTION, 1);
  }

  getView() {
    return { pos: this.camera.position.toArray(), target: this.controls.target.toArray() };
  }

  setView(view) {
    this.camera.position.fromArray(view.pos);
    this.controls.target.fromArray(view.target);
    this.controls.update();
  }
}
