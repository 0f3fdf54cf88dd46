// render.test.mjs — the render mode's soft shadows (three.js shadow mapping, web/js/shadows.js),
// checked against closed forms in screenshots. The scene: a sphere of radius 0.5 about the
// origin and a small sphere of radius 0.15 whose centre lies 1.2 along the light direction L
// (f = product of the two), under the key light's parallel rays.
//  - Ground: the shadow of a ball under parallel light on the plane z = g is the ellipse
//    centred at c - L (c_z - g) / L_z with semi-axes r (across L) and r / L_z (along L's
//    horizontal part). Visible ground pixels well inside it are darker than visible ground
//    pixels well outside it.
//  - Self-shadowing: the big sphere's point q = 0.5 L faces the light, but the small sphere
//    lies on its ray towards the light, so q is in the small sphere's shadow. Cutting the
//    small sphere away with the clipping plane must take its shadow away too (three.js clips
//    the shadow depth pass): q brightens by a clear margin, while points of the big sphere
//    outside that shadow keep their brightness.
// Every sample point is checked visible from the camera (ray against both balls) first.
import { describe, it, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startDaemon, stopDaemon, startBrowser, stopBrowser } from './lib/harness.mjs';
import { openViewer, waitForMesh, loads, viewShot, settledHref } from './lib/page.mjs';

let daemon = null;
let browser = null;
let page = null;
let errors = [];

const R_BIG = 0.5, R_SMALL = 0.15, SMALL_AT = 1.2;

const add = (a, b, s = 1) => a.map((v, i) => v + s * b[i]);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const norm = (a) => a.map((v) => v / Math.hypot(...a));

// Whether the segment from eye to p (exclusive of p's own neighbourhood) meets the ball.
function hidesBall(eye, p, centre, r) {
  const d = add(p, eye, -1), len = Math.hypot(...d), u = d.map((v) => v / len);
  const oc = add(eye, centre, -1), b = dot(oc, u), c = dot(oc, oc) - r * r;
  const disc = b * b - c;
  if (disc <= 0) return false;
  const t = -b - Math.sqrt(disc);
  return t > 0 && t < len - 1e-3;
}

// Mean RGB sum over a 5x5 window of img at view pixel px.
function brightness(img, px) {
  let s = 0;
  for (let dy = -2; dy <= 2; dy++) for (let dx = -2; dx <= 2; dx++) {
    const i = 4 * ((px[1] + dy) * img.width + px[0] + dx);
    s += img.rgba[i] + img.rgba[i + 1] + img.rgba[i + 2];
  }
  return s / 25;
}

// Sets the camera, waits for the frame, returns {eye, px(points)} in view pixels.
async function look(pos, target, points) {
  return page.evaluate(({ pos, target, points }) => {
    const v = window.isomeshViewer;
    v.setView({ pos, target });
    v.camera.updateMatrixWorld();
    const V = v.camera.position.constructor;
    return {
      eye: v.camera.position.toArray(),
      px: points.map((p) => {
        const q = new V(...p).project(v.camera);
        return [Math.round((q.x + 1) / 2 * v.canvas.clientWidth), Math.round((1 - q.y) / 2 * v.canvas.clientHeight)];
      }),
    };
  }, { pos, target, points });
}

// Waits until the frames asked for are drawn and done by the GPU.
async function drawn() {
  await page.evaluate(() => window.isomeshViewer.settled());
}

describe('render mode: soft shadows', { timeout: 600000 }, () => {
  before(async () => {
    daemon = await startDaemon();
    browser = await startBrowser({ width: 1100, height: 800 });
    ({ page, errors } = await openViewer(browser.context, daemon.base + '/#preset=sphere'));
  });

  after(async () => {
    try {
      await stopBrowser(browser);
    } finally {
      await stopDaemon(daemon);
    }
  });

  it('a ball shadows the ground where the closed form says, and itself, and a cut part casts nothing', async () => {
    const L = await page.evaluate(() => {
      const l = window.isomeshViewer.shadows.light;
      return l.position.clone().sub(l.target.position).normalize().toArray();
    });
    assert.ok(L[2] > 0.5, `the key light is above (${L})`);
    const s = L.map((v) => SMALL_AT * v);
    const expr = `(x^2+y^2+z^2-${R_BIG * R_BIG})*((x-(${s[0]}))^2+(y-(${s[1]}))^2+(z-(${s[2]}))^2-${R_SMALL * R_SMALL})`;
    // A box off the lattice of round numbers, holding both balls.
    const box = [-0.6137, -0.9021, -0.5871, 0.6213, 0.6049, 1.2233];
    const n = await loads(page);
    await page.evaluate(({ expr, box }) => {
      location.hash = `expr=${encodeURIComponent(expr)}&box=${box.join(',')}&depth=3,6&err=off`;
    }, { expr, box });
    await waitForMesh(page, n);
    await page.uncheck('#show-box');   // its outline would cross the samples
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    await page.check('#shadows');
    await drawn();
    assert.match(await settledHref(page), /[#&]shadows=1(&|$)/);
    const g = await page.evaluate(() => window.isomeshViewer.shadows.groundZ);
    assert.ok(g < -R_BIG && g > -R_BIG - 0.3, `the ground (z = ${g}) lies just below the mesh`);

    // --- the ground: ellipse centred at -L g / L_z... from the big ball's centre (origin)
    const drop = (0 - g) / L[2];
    const centre = [-L[0] * drop, -L[1] * drop, g];
    const along = norm([L[0], L[1], 0]), across = [-along[1], along[0], 0];
    const a = R_BIG / L[2], b = R_BIG;       // semi-axes along and across
    const ground = (t, k) => [centre[0] + t * a * along[0] + k * b * across[0], centre[1] + t * a * along[1] + k * b * across[1], g];
    const inside = [], outside = [];
    for (let i = 0; i < 16; i++) {
      const th = (2 * Math.PI * i) / 16;
      inside.push(ground(0.6 * Math.cos(th), 0.6 * Math.sin(th)));
      outside.push(ground(1.45 * Math.cos(th), 1.45 * Math.sin(th)));
    }
    inside.push(centre);
    // Seen from the side the shadow falls to (away from the light), from above.
    const eyeDir = norm([-along[0], -along[1], 1.1]);
    const view = await look(add(centre, eyeDir, 6), centre, [...inside, ...outside]);
    const img = await viewShot(page, 'render-shadow-ground.png');
    const balls = [[[0, 0, 0], R_BIG], [s, R_SMALL]];
    const inView = ([x, y]) => x >= 2 && y >= 2 && x < img.width - 2 && y < img.height - 2;
    const seen = (p, px) => inView(px) && !balls.some(([c, r]) => hidesBall(view.eye, p, c, r));
    const light = (pts, off) => pts.map((p, i) => ({ p, px: view.px[off + i] })).filter((x) => seen(x.p, x.px)).map((x) => brightness(img, x.px));
    const inB = light(inside, 0), outB = light(outside, inside.length);
    const mean = (xs) => xs.reduce((u, v) => u + v, 0) / xs.length;
    console.log(`# ground: ${inB.length} visible samples inside the closed-form shadow, mean ${mean(inB).toFixed(1)} (max ${Math.max(...inB).toFixed(1)}); ${outB.length} outside, mean ${mean(outB).toFixed(1)} (min ${Math.min(...outB).toFixed(1)})`);
    assert.ok(inB.length >= 6 && outB.length >= 8, 'enough visible ground samples');
    assert.ok(Math.max(...inB) < 0.85 * Math.min(...outB), 'every sample inside the shadow is darker than every sample outside it');

    // --- self-shadowing: q = 0.5 L lies in the small ball's shadow
    const q = L.map((v) => R_BIG * v);
    // Control points of the big ball 60 degrees from q (far outside the small ball's shadow
    // cylinder of radius 0.15) on the camera's side.
    const side = norm([L[1], -L[0], 0]);
    const eye = add(q.map((v) => 6 * v), side, 3.5);
    const ctrl = [side, norm(add(side, [0, 0, 1])), norm(add(side, L))].map((d) => norm(add(L.map((v) => 0.5 * v), d, 0.866)).map((v) => R_BIG * v));
    const onBall = [q, ...ctrl];
    const v2 = await look(eye, [0, 0, 0], onBall);
    const seen2 = (p) => !balls.some(([c, r]) => hidesBall(v2.eye, p, c, r));
    onBall.forEach((p) => assert.ok(seen2(p), `sample ${p} is visible`));
    const uncut = await viewShot(page, 'render-shadow-self.png');
    // Cut the small ball away: clip z at 0.7 keeps z < 0.7 (the small ball lies above 0.8).
    assert.ok(s[2] - R_SMALL > 0.75 && R_BIG < 0.65, 'the plane z = 0.7 separates the balls');
    await page.check('#clip-on');
    await page.selectOption('#clip-axis', 'z');
    await page.$eval('#clip-offset', (e) => { e.value = '0.7'; e.dispatchEvent(new Event('input', { bubbles: true })); });
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    await drawn();
    const cut = await viewShot(page, 'render-shadow-self-cut.png');
    const ratios = v2.px.map((px) => brightness(cut, px) / brightness(uncut, px));
    console.log(`# self-shadow: brightness cut / uncut at q ${ratios[0].toFixed(3)}, at the control points ${ratios.slice(1).map((r) => r.toFixed(3)).join(' ')}`);
    assert.ok(ratios[0] > 1.2, `q brightens when the ball shadowing it is cut away (${ratios[0]})`);
    for (const r of ratios.slice(1)) assert.ok(Math.abs(r - 1) < 0.06, `a point outside that shadow keeps its brightness (${r})`);

    // --- the cap, lit in the render mode: cut at z = 0 keeping z < 0, seen from above; the
    // cap is the disc of radius 0.5 (f < 0 on the plane), facing the light.
    await page.$eval('#clip-offset', (e) => { e.value = '0'; e.dispatchEvent(new Event('input', { bubbles: true })); });
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const rim = (k) => [0.5 * k * Math.cos(0.7), 0.5 * k * Math.sin(0.7), 0];
    const v3 = await look([0.8, -1.9, 4.4], [0, 0, 0], [[0, 0, 0], rim(0.9), rim(1.15)]);
    await drawn();
    const capImg = await viewShot(page, 'render-cap.png');
    const rgb = (px) => Array.from(capImg.rgba.subarray(4 * (px[1] * capImg.width + px[0]), 4 * (px[1] * capImg.width + px[0]) + 3));
    const [mid, inRim, outRim] = v3.px.map(rgb);
    console.log(`# cap: centre ${mid}, at 0.9 r ${inRim}, at 1.15 r ${outRim}`);
    const capHue = ([r, g, b]) => r > g + 20 && g > b + 10;   // cap.js CAP_RGB c98a5a, lit
    assert.ok(capHue(mid) && capHue(inRim), 'the cap is drawn inside the disc');
    assert.ok(!capHue(outRim), 'and not beyond it');
    await page.uncheck('#clip-on');
    await page.uncheck('#shadows');
  });

  it('left no page errors', () => {
    assert.deepEqual(errors, []);
  });
});
