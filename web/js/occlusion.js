// occlusion.js — ambient occlusion of a mesh, computed once per mesh in the browser (on the GPU)
// and kept per vertex, for the viewer's render mode: folds, necks, corners and the insides of
// tunnels darken and the shape reads as in a rendered figure. Being a property of the mesh,
// not of the view, it costs nothing while the camera moves, and it sees occluders a
// screen-space method cannot (those behind the point as seen from the camera).
//
// Method ("obscurance by depth maps"): for DIRECTIONS directions d spread evenly over the
// sphere (a Fibonacci lattice), the mesh is drawn from far along d into a depth map
// (orthographic, both sides of every triangle); then every vertex, drawn as one point into a
// pixel of its own in an accumulation target, looks itself up in that map: it sees d when
// nothing lies in front of it along d. Each side of the surface collects its own sums:
//     outside (along the normal n = grad f / |grad f|):  sum vis * max(d.n, 0), sum max(d.n, 0)
//     inside:                                             sum vis * max(-d.n, 0), sum max(-d.n, 0)
// (cosine-weighted visibility of the hemisphere). Their ratios are the light each side keeps
// (1: open, 0: shut in); the viewer's material multiplies its light by the side it shows. A
// finite set of directions gives each one's shadow edge as a step: SMOOTHING passes averaging
// each vertex with its mesh neighbours blur those steps out.
// What the clipping plane cuts away is left out of the depth maps: it occludes nothing.
//
// The page stays responsive meanwhile (software GL takes seconds for a large mesh): the
// directions go to the GPU a few at a time, each batch followed by a fence that is polled
// between tasks, so input events and animation frames run while the GPU works; batches grow
// or shrink to take about CHUNK_MS each. The read-back values are turned into light and
// smoothed SLICE at a time, in tasks of their own.
import * as THREE from 'three';
import { gpuDone } from './gpu.js';

// Directions over the whole sphere (each side's hemisphere gets half): enough that a corner
// or a neck is sampled by several, few enough to stay one short pause in software GL.
const DIRECTIONS = 64;
// Depth map side (texels): a texel is 1/DEPTH_RES of the mesh's bounding diameter.
const DEPTH_RES = 384;
// A vertex counts as seen when it lies at most this many texel widths behind the map's
// nearest surface (its own triangles are in the map too), plus a slope term for directions
// that graze its surface.
const BIAS_TEXELS = 1.5;
// Vertices per row of the accumulation target.
const ACC_WIDTH = 1024;
// Neighbour-averaging passes over the result (each reaches one ring of triangles further).
const SMOOTHING = 2;
// GPU time one batch of directions should take: short enough that a frame or an input event
// waits at most about this long, long enough that the fence round trips stay a small overhead.
const CHUNK_MS = 40;
// Directions per batch at most (a fast GPU does all 64 in a few batches).
const MAX_CHUNK = 16;
// Vertices or triangles read back and smoothed in one task: a few ms of script (the whole of it
// took 100-180 ms for the gyroid ball's 59k vertices at load 15, in one task, before).
const SLICE = 8192;

// The depth pass leaves out what the clipping plane removes: keep.xyz . p + keep.w < 0 (the
// mesh is drawn untransformed, so its positions are world positions).
const depthVertex = `
uniform vec4 keep;
varying float kept;
void main() {
  kept = dot(keep.xyz, position) + keep.w;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
const depthFragment = `
varying float kept;
void main() {
  if (kept < 0.0) discard;
  gl_FragColor = vec4(1.0);
}`;

const gatherVertex = `
attribute float vid;
uniform mat4 dirViewProjection;
uniform vec3 dir;
uniform sampler2D depthMap;
uniform vec2 accSize;
uniform float bias;
varying vec4 sums;
void main() {
  vec4 clip = dirViewProjection * vec4(position, 1.0);   // orthographic: w = 1
  vec3 ndc = clip.xyz / clip.w;
  float mapDepth = texture2D(depthMap, ndc.xy * 0.5 + 0.5).r;
  float c = dot(normalize(normal), dir);
  float slope = bias * min(4.0, sqrt(max(0.0, 1.0 - c * c)) / max(abs(c), 1e-3));
  float seen = (ndc.z * 0.5 + 0.5) <= mapDepth + bias + slope ? 1.0 : 0.0;
  float up = max(c, 0.0), down = max(-c, 0.0);
  sums = vec4(seen * up, up, seen * down, down);
  float x = mod(vid, accSize.x), y = floor(vid / accSize.x);
  gl_Position = vec4((x + 0.5) / accSize.x * 2.0 - 1.0, (y + 0.5) / accSize.y * 2.0 - 1.0, 0.0, 1.0);
  gl_PointSize = 1.0;
}`;
const gatherFragment = `
varying vec4 sums;
void main() { gl_FragColor = sums; }`;

// Unit vectors spread evenly over the sphere (golden-angle spiral).
function fibonacciDirections(n) {
  const out = [];
  const golden = Math.PI * (3 - Math.sqrt(5));
  for (let i = 0; i < n; i++) {
    const z = 1 - (2 * i + 1) / n;
    const r = Math.sqrt(1 - z * z);
    out.push(new THREE.Vector3(r * Math.cos(golden * i), r * Math.sin(golden * i), z));
  }
  return out;
}

// The light each vertex of geometry keeps on its outside and inside, interleaved
// (Float32Array, 2 per vertex, each in [0, 1]); geometry needs position and normal. keep: the
// THREE.Plane whose negative side the clipping removes (it then occludes nothing), or null.
// Resolves null, having stopped early, as soon as alive() turns false (checked between batches).
export async function bakeOcclusion(renderer, geometry, { keep = null, alive = () => true } = {}) {
  const n = geometry.attributes.position.count;
  const sphere = (geometry.boundingSphere || (geometry.computeBoundingSphere(), geometry.boundingSphere)).clone();
  const R = Math.max(sphere.radius, 1e-9);
  const rows = Math.max(1, Math.ceil(n / ACC_WIDTH));
  const made = [];   // GPU objects to dispose at the end
  const own = (o) => { made.push(o); return o; };

  const depthTarget = own(new THREE.WebGLRenderTarget(DEPTH_RES, DEPTH_RES, { depthBuffer: true }));
  depthTarget.depthTexture = own(new THREE.DepthTexture(DEPTH_RES, DEPTH_RES, THREE.FloatType));
  const acc = own(new THREE.WebGLRenderTarget(ACC_WIDTH, rows, {
    type: THREE.HalfFloatType, depthBuffer: false, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
  }));

  const depthScene = new THREE.Scene();
  const keepVector = keep ? new THREE.Vector4(keep.normal.x, keep.normal.y, keep.normal.z, keep.constant) : new THREE.Vector4(0, 0, 0, 1);
  const depthMaterial = own(new THREE.ShaderMaterial({
    vertexShader: depthVertex, fragmentShader: depthFragment, side: THREE.DoubleSide,
    uniforms: { keep: { value: keepVector } },
  }));
  depthScene.add(new THREE.Mesh(geometry, depthMaterial));

  const points = own(new THREE.BufferGeometry());
  points.setAttribute('position', geometry.attributes.position);
  points.setAttribute('normal', geometry.attributes.normal);
  points.setAttribute('vid', new THREE.BufferAttribute(Float32Array.from({ length: n }, (_, i) => i), 1));
  const gather = own(new THREE.ShaderMaterial({
    vertexShader: gatherVertex, fragmentShader: gatherFragment,
    uniforms: {
      dirViewProjection: { value: new THREE.Matrix4() }, dir: { value: new THREE.Vector3() },
      depthMap: { value: depthTarget.depthTexture }, accSize: { value: new THREE.Vector2(ACC_WIDTH, rows) },
      bias: { value: BIAS_TEXELS / DEPTH_RES },   // depth spans 2R, as does the map
    },
    blending: THREE.CustomBlending, blendEquation: THREE.AddEquation,
    blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor, blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneFactor,
    depthTest: false, depthWrite: false,
  }));
  const cloud = new THREE.Points(points, gather);
  cloud.frustumCulled = false;
  const gatherScene = new THREE.Scene();
  gatherScene.add(cloud);
  const gatherCamera = new THREE.OrthographicCamera();   // unused by the shader
  const camera = new THREE.OrthographicCamera(-R, R, R, -R, R, 3 * R);

  const pass = (d) => {
    camera.position.copy(sphere.center).addScaledVector(d, 2 * R);
    camera.up.set(Math.abs(d.z) < 0.9 ? 0 : 1, 0, Math.abs(d.z) < 0.9 ? 1 : 0);
    camera.lookAt(sphere.center);
    camera.updateMatrixWorld();
    camera.updateProjectionMatrix();
    renderer.setRenderTarget(depthTarget);
    renderer.clear(true, true, false);
    renderer.render(depthScene, camera);
    gather.uniforms.dirViewProjection.value.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
    gather.uniforms.dir.value.copy(d);
    renderer.setRenderTarget(acc);
    renderer.render(gatherScene, gatherCamera);
  };

  try {
    const gl = renderer.getContext();
    await renderer.compileAsync(depthScene, camera);
    await renderer.compileAsync(gatherScene, gatherCamera);
    if (!alive()) return null;
    withTargets(renderer, () => {
      renderer.setRenderTarget(acc);
      renderer.clear(true, false, false);
    });
    const directions = fibonacciDirections(DIRECTIONS);
    let next = 0, chunk = 1;
    while (next < directions.length) {
      const t0 = performance.now();
      const batch = directions.slice(next, next + chunk);
      next += batch.length;
      withTargets(renderer, () => batch.forEach(pass));
      await gpuDone(gl);
      if (!alive()) return null;
      const ms = performance.now() - t0;
      chunk = Math.max(1, Math.min(MAX_CHUNK, Math.round(batch.length * CHUNK_MS / Math.max(ms, 1))));
    }
    const raw = new Uint16Array(4 * ACC_WIDTH * rows);
    renderer.readRenderTargetPixels(acc, 0, 0, ACC_WIDTH, rows, raw);
    const light = new Float32Array(2 * n);
    const h = THREE.DataUtils.fromHalfFloat;
    await inSlices(n, (i) => {
      const w0 = h(raw[4 * i + 1]), w1 = h(raw[4 * i + 3]);
      light[2 * i] = w0 > 0 ? Math.min(1, h(raw[4 * i]) / w0) : 1;
      light[2 * i + 1] = w1 > 0 ? Math.min(1, h(raw[4 * i + 2]) / w1) : 1;
    });
    if (!alive()) return null;
    return geometry.index ? await smooth(light, geometry.index.array, SMOOTHING) : light;
  } finally {
    for (const o of made) o.dispose();
  }
}

// Runs draw with the renderer's target, clear colour, clipping and autoClear set for the bake,
// and puts the viewer's back afterwards (the viewer draws frames between batches).
function withTargets(renderer, draw) {
  const saved = {
    target: renderer.getRenderTarget(), color: renderer.getClearColor(new THREE.Color()), alpha: renderer.getClearAlpha(),
    clipping: renderer.localClippingEnabled, autoClear: renderer.autoClear,
  };
  renderer.localClippingEnabled = false;
  renderer.autoClear = false;
  renderer.setClearColor(0x000000, 0);
  try {
    draw();
  } finally {
    renderer.setRenderTarget(saved.target);
    renderer.setClearColor(saved.color, saved.alpha);
    renderer.localClippingEnabled = saved.clipping;
    renderer.autoClear = saved.autoClear;
  }
}

// Runs step(i) for i = 0 .. count - 1, SLICE at a time, each slice a task of its own: the page
// draws frames and answers input between them.
async function inSlices(count, step) {
  for (let start = 0; start < count; start += SLICE) {
    if (start > 0) await new Promise((r) => setTimeout(r, 0));
    const end = Math.min(count, start + SLICE);
    for (let i = start; i < end; i++) step(i);
  }
}

// passes rounds of: each vertex's pair of values becomes the mean over itself and the vertices
// it shares a triangle with (each shared edge counted once per triangle).
async function smooth(values, index, passes) {
  const n = values.length / 2;
  let cur = values;
  for (let p = 0; p < passes; p++) {
    const sum = Float32Array.from(cur), count = new Float32Array(n).fill(1);
    await inSlices(index.length / 3, (t) => {
      for (let k = 0; k < 3; k++) {
        const a = index[3 * t + k], b = index[3 * t + (k + 1) % 3];
        sum[2 * a] += cur[2 * b]; sum[2 * a + 1] += cur[2 * b + 1]; count[a]++;
        sum[2 * b] += cur[2 * a]; sum[2 * b + 1] += cur[2 * a + 1]; count[b]++;
      }
    });
    await inSlices(n, (i) => {
      sum[2 * i] /= count[i];
      sum[2 * i + 1] /= count[i];
    });
    cur = sum;
  }
  return cur;
}
