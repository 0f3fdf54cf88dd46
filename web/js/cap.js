// cap.js — the cap where the clipping plane cuts the solid f < 0: a quad spanning the box's
// cross-section at the plane, whose fragment shader evaluates f itself (the GLSL that
// expr.js writes alongside its checks) and keeps the pixels where f < 0. Drawn from f, not
// from the mesh, it is right for open, non-manifold and self-intersecting surfaces alike,
// where a stencil cap (which counts the mesh's front and back faces) is not.
//
//       box cross-section at coordinate[axis] = offset
//      +---------------------------+
//      |      ######               |   # : f(p) < 0, drawn in CAP_RGB
//      |    ##########     ###     |
//      |     ########     #####    |     : f(p) >= 0, discarded
//      +---------------------------+
//
// Precision is the GPU's float: enough for a picture, and the section curve (section.js)
// still marks the mesh's own cut. In the render mode the same test runs on a lit material
// (shaded and shadowed like the surface) and on the depth material of the shadow map, so the
// cap casts the shadow of the solid's cut face.
import * as THREE from 'three';

const CAP_RGB = new THREE.Color(0xc98a5a);   // the inside tint of the two-sided shading
const AXIS = { x: 0, y: 1, z: 2 };

// ipow: x^n for 0 <= n <= 64 by squaring (GLSL's pow() is undefined for x < 0).
const PRELUDE = `
float ipow(float x, int n) {
  float r = 1.0;
  float b = x;
  for (int i = 0; i < 7; i++) {
    if ((n & 1) == 1) r *= b;
    n >>= 1;
    if (n == 0) break;
    b *= b;
  }
  return r;
}
`;

// f as GLSL: surface(p), with ipow before it.
function surfaceFunction(glsl) {
  return `${PRELUDE}
float surface(vec3 p) {
  ${glsl.lets.join('\n  ')}
  return ${glsl.f};
}
`;
}

function fragmentShader(glsl) {
  return `
precision highp float;
varying vec3 vWorld;
uniform vec3 capColor;
${surfaceFunction(glsl)}
void main() {
  float f = surface(vWorld);
  if (!(f < 0.0)) discard;
  gl_FragColor = vec4(capColor, 1.0);
  #include <colorspace_fragment>
}
`;
}

const VERTEX = `
varying vec3 vWorld;
void main() {
  vec4 w = modelMatrix * vec4(position, 1.0);
  vWorld = w.xyz;
  gl_Position = projectionMatrix * viewMatrix * w;
}
`;

// The quad of box (x0 y0 z0 x1 y1 z1) at coordinate[axis] = offset, two triangles facing
// out of the kept solid: along +axis when the side above the offset is cut away (no flip),
// along -axis with flip; its normals say the same (the render mode lights and shadows it).
function quad(box, axis, offset, flip) {
  const u = (axis + 1) % 3, v = (axis + 2) % 3;
  const corners = [[box[u], box[v]], [box[u + 3], box[v]], [box[u + 3], box[v + 3]], [box[u], box[v + 3]]];
  const pos = new Float32Array(12), normal = new Float32Array(12);
  corners.forEach(([a, b], i) => {
    pos[3 * i + axis] = offset;
    pos[3 * i + u] = a;
    pos[3 * i + v] = b;
    normal[3 * i + axis] = flip ? -1 : 1;
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('normal', new THREE.BufferAttribute(normal, 3));
  g.setIndex(flip ? [0, 2, 1, 0, 3, 2] : [0, 1, 2, 0, 2, 3]);   // (u, v, axis) is right-handed
  return g;
}

// f < 0 as a test on a three.js built-in material (onBeforeCompile): the vertex shader passes
// the world position on, the fragment shader discards where f >= 0. Its program is keyed by
// f's GLSL (three.js keys onBeforeCompile programs by the function's text, the same for every f).
function discardOutside(material, glsl) {
  const body = surfaceFunction(glsl);
  material.onBeforeCompile = (shader) => {
    shader.vertexShader = shader.vertexShader.replace('void main() {',
      'varying vec3 vCapWorld;\nvoid main() {\n\tvCapWorld = (modelMatrix * vec4(position, 1.0)).xyz;');
    shader.fragmentShader = shader.fragmentShader.replace('void main() {',
      `varying vec3 vCapWorld;\n${body}void main() {\n\tif (!(surface(vCapWorld) < 0.0)) discard;`);
  };
  material.customProgramCacheKey = () => `cap|${body}`;
  return material;
}

// A cap mesh, or null when there is nothing to draw (no clip or cap, no f, plane outside the
// box). clip: as Viewer.setClip takes it.
// glsl: {lets, f} from checkExpression (expr.js).
// Its material is flat CAP_RGB (userData.flat); the render mode swaps in userData.lit, the same
// colour lit and shadowed like the surface. It casts shadows where f < 0 (customDepthMaterial).
export function buildCap(clip, box, glsl) {
  if (!clip || !clip.on || clip.cap === false || !box || !glsl) return null;
  const axis = AXIS[clip.axis] ?? 2;
  if (!(clip.offset > box[axis] && clip.offset < box[axis + 3])) return null;
  const material = new THREE.ShaderMaterial({
    vertexShader: VERTEX,
    fragmentShader: fragmentShader(glsl),
    uniforms: {
      capColor: { value: CAP_RGB },
    },
    side: THREE.DoubleSide,
    // drawn just behind the section curve and the surface where they meet the plane
    polygonOffset: true,
    polygonOffsetFactor: 1,
    polygonOffsetUnits: 1,
  });
  const lit = discardOutside(new THREE.MeshStandardMaterial({
    color: CAP_RGB, side: THREE.DoubleSide, roughness: 0.7, metalness: 0,
    polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
  }), glsl);
  const mesh = new THREE.Mesh(quad(box, axis, clip.offset, !!clip.flip), material);
  mesh.name = 'clip-cap';
  mesh.userData.flat = material;
  mesh.userData.lit = lit;
  mesh.customDepthMaterial = discardOutside(new THREE.MeshDepthMaterial({ depthPacking: THREE.RGBADepthPacking }), glsl);
  mesh.castShadow = true;
  mesh.receiveShadow = true;
  return mesh;
}

// Frees what buildCap made.
export function disposeCap(mesh) {
  mesh.geometry.dispose();
  for (const m of [mesh.userData.flat, mesh.userData.lit, mesh.customDepthMaterial]) m.dispose();
}
