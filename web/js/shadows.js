// shadows.js — the render mode's soft shadows, from three.js's own shadow mapping: a key light
// fixed in the world (above the surface, z up) casts PCF shadows (filtered over a disk of
// RADIUS texels: soft edges) onto the surface itself and onto a ground plane just below the
// mesh that shows nothing but the shadow (THREE.ShadowMaterial).
//
//              light (KEY_DIRECTION, parallel rays)
//                 \  \  \
//                  (surface)        the shadow camera is an orthographic box around the
//                    \  \  \        surface's bounding sphere, seen along the light, reaching
//     ________________\##\##\___    down to the ground: every shadow falls inside it
//        ground plane   shadow
//
// What the clipping plane removes casts nothing: the surface material sets clipShadows, so
// three.js clips its shadow depth pass with the same planes. The light is fixed in the world,
// so the shadow map is redrawn only when the mesh, the cut or the cap changes (markDirty), not
// when the camera moves.
import * as THREE from 'three';

// Towards the light (world, z up): from above, in front and to the left of the default view
// (the camera's default direction is (1.5, -2.1, 1.25)), so that the lit side faces the
// camera and the shadows fall behind and to the right, where a paper figure has them.
export const KEY_DIRECTION = new THREE.Vector3(-0.3, -1, 1.4).normalize();
// The key light's strength in the render mode; the camera's headlight and fill are dimmed by
// HEADLIGHT_SCALE meanwhile, so that the shadowed side reads as shadowed.
const KEY_INTENSITY = 1.7;
export const HEADLIGHT_SCALE = 0.45;
// Shadow map side (texels): over the bounding sphere's diameter plus margin, a texel is about
// 1/400 of the surface's size — finer costs fill rate in software GL for no visible gain.
const MAP_SIZE = 1024;
// PCF filter radius in texels: the penumbra's width (three.js samples a Vogel disk).
const RADIUS = 4;
// Depth bias (in the light's normalised depth) and normal offset (in texels along the
// surface normal) against self-shadowing "acne" on surfaces lit at grazing angles.
const DEPTH_BIAS = -0.0004;
const NORMAL_BIAS_TEXELS = 4;
// The ground lies this share of the bounding diameter below the mesh's lowest point.
export const GROUND_GAP = 0.04;
// The ground plane's half-side, in bounding-sphere radii: it holds the shadow of the whole
// bounding sphere for any light at least 35 degrees above the horizon.
const GROUND_HALF = 4;
// Darkness of a full shadow on the ground (ShadowMaterial's opacity).
const GROUND_OPACITY = 0.45;

export class Shadows {
  // scene: where the light and the ground go; renderer: its shadow map is switched per frame.
  constructor(scene, renderer) {
    this.renderer = renderer;
    renderer.shadowMap.type = THREE.PCFShadowMap;
    renderer.shadowMap.autoUpdate = false;
    this.light = new THREE.DirectionalLight(0xffffff, KEY_INTENSITY);
    this.light.name = 'key-light';
    this.light.castShadow = true;
    this.light.shadow.mapSize.set(MAP_SIZE, MAP_SIZE);
    this.light.shadow.radius = RADIUS;
    this.light.shadow.bias = DEPTH_BIAS;
    this.light.visible = false;
    this.ground = new THREE.Mesh(new THREE.PlaneGeometry(1, 1),
      new THREE.ShadowMaterial({ opacity: GROUND_OPACITY, depthWrite: false }));
    this.ground.name = 'ground';
    this.ground.receiveShadow = true;
    this.ground.visible = false;
    scene.add(this.light, this.light.target, this.ground);
    this.on = false;
  }

  // Places the light, its shadow camera and the ground around box (a THREE.Box3 of the mesh).
  fit(box) {
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const r = Math.max(sphere.radius, 1e-6);
    const groundZ = box.min.z - GROUND_GAP * 2 * r;
    this.groundZ = groundZ;
    // The ground centred under the bounding sphere's shadow.
    const drop = (sphere.center.z - groundZ) / KEY_DIRECTION.z;
    this.ground.position.set(sphere.center.x - KEY_DIRECTION.x * drop, sphere.center.y - KEY_DIRECTION.y * drop, groundZ);
    this.ground.scale.set(2 * GROUND_HALF * r, 2 * GROUND_HALF * r, 1);
    this.ground.updateMatrixWorld();
    const light = this.light;
    light.position.copy(sphere.center).addScaledVector(KEY_DIRECTION, 2 * r);
    light.target.position.copy(sphere.center);
    light.updateMatrixWorld();
    light.target.updateMatrixWorld();
    const cam = light.shadow.camera;
    const half = 1.05 * r;       // the bounding sphere seen along the light, and a margin
    cam.left = -half; cam.right = half; cam.top = half; cam.bottom = -half;
    cam.near = 0.5 * r;
    cam.far = 2 * r + drop + 2 * r;   // past the ground under the far side of the sphere
    cam.updateProjectionMatrix();
    light.shadow.normalBias = NORMAL_BIAS_TEXELS * (2 * half / MAP_SIZE);
    this.markDirty();
  }

  // Shadows on or off (the render mode's look); returns whether anything changed.
  setOn(on) {
    if (on === this.on) return false;
    this.on = on;
    this.renderer.shadowMap.enabled = on;
    this.light.visible = on;
    this.ground.visible = on;
    this.markDirty();
    return true;
  }

  // The next frame redraws the shadow map (the mesh, the cut or the cap changed).
  markDirty() {
    this.renderer.shadowMap.needsUpdate = true;
  }
}
