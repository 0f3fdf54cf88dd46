// pick.mjs — clicks every singular point the viewer draws (at its projection on the canvas)
// and reads what the page says about it: #pick-info's data (type, xyz, certified, the
// server's probe of f and |grad f| there) and text. Shared by the Cayley and Kummer tests.

// The pick of each drawn singular point: [{type, xyz: [x, y, z], certified, probe, text}].
export async function pickSingularPoints(page) {
  const spots = await page.evaluate(() => {
    const v = window.isomeshViewer;
    const r = v.canvas.getBoundingClientRect();
    return v.features.pickables.filter((p) => p.what === 'point').map((p) => {
      const q = new v.camera.position.constructor(...p.at[0]).project(v.camera);
      return [r.left + (q.x + 1) / 2 * r.width, r.top + (1 - q.y) / 2 * r.height];
    });
  });
  const picks = [];
  for (const [x, y] of spots) {
    await page.evaluate(() => { delete document.getElementById('pick-info').dataset.probe; });
    await page.mouse.click(x, y);
    await page.waitForSelector('#pick-info[data-probe]:not([hidden])');
    const info = await page.$eval('#pick-info', (e) => ({ ...e.dataset, text: e.textContent }));
    picks.push({ type: info.type, xyz: info.xyz.split(',').map(Number), certified: info.certified,
      probe: JSON.parse(info.probe), text: info.text });
  }
  return picks;
}

// Distance from xyz to the nearest of points.
export function nearest(points, xyz) {
  return Math.min(...points.map((p) => Math.hypot(p[0] - xyz[0], p[1] - xyz[1], p[2] - xyz[2])));
}
