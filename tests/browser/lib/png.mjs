// png.mjs — reads the 8-bit RGB/RGBA non-interlaced PNGs that Chromium's screenshots are (with
// node's zlib) and summarises their pixels, so a test can tell a rendered surface from a blank
// or single-colour canvas, and measure how much two renderings differ.
import zlib from 'node:zlib';

export function decodePng(buf) {
  if (buf.readUInt32BE(0) !== 0x89504e47) throw new Error('not a PNG');
  let pos = 8, width = 0, height = 0, colorType = 0, depth = 0, interlace = 0;
  const idat = [];
  while (pos < buf.length) {
    const len = buf.readUInt32BE(pos);
    const type = buf.toString('ascii', pos + 4, pos + 8);
    const data = buf.subarray(pos + 8, pos + 8 + len);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      depth = data[8];
      colorType = data[9];
      interlace = data[12];
    } else if (type === 'IDAT') {
      idat.push(data);
    } else if (type === 'IEND') {
      break;
    }
    pos += 12 + len;
  }
  if (depth !== 8 || interlace !== 0 || (colorType !== 2 && colorType !== 6)) {
    throw new Error(`unsupported PNG (depth ${depth}, colour type ${colorType}, interlace ${interlace})`);
  }
  const bpp = colorType === 6 ? 4 : 3;
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * bpp;
  const out = Buffer.alloc(width * height * 4);
  let prev = Buffer.alloc(stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = Buffer.from(raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1)));
    for (let i = 0; i < stride; i++) {
      const a = i >= bpp ? line[i - bpp] : 0;
      const b = prev[i];
      const c = i >= bpp ? prev[i - bpp] : 0;
      let add = 0;
      if (filter === 1) add = a;
      else if (filter === 2) add = b;
      else if (filter === 3) add = (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c;
        const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        add = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      } else if (filter !== 0) throw new Error(`bad PNG filter ${filter}`);
      line[i] = (line[i] + add) & 255;
    }
    for (let x = 0; x < width; x++) {
      const o = (y * width + x) * 4;
      out[o] = line[x * bpp];
      out[o + 1] = line[x * bpp + 1];
      out[o + 2] = line[x * bpp + 2];
      out[o + 3] = bpp === 4 ? line[x * bpp + 3] : 255;
    }
    prev = line;
  }
  return { width, height, rgba: out };
}

// Pixel statistics: distinct colours (quantised to 4 bits a channel), the share of pixels far
// from the most common colour (the background), luminance spread, and the share of clearly
// coloured pixels (channels at least 60 apart: the curvature maps, not the grey shading).
export function pixelStats(img) {
  const n = img.width * img.height;
  const counts = new Map();
  let sum = 0, sum2 = 0, saturated = 0;
  for (let i = 0; i < n; i++) {
    const r = img.rgba[4 * i], g = img.rgba[4 * i + 1], b = img.rgba[4 * i + 2];
    const q = ((r >> 4) << 8) | ((g >> 4) << 4) | (b >> 4);
    counts.set(q, (counts.get(q) || 0) + 1);
    const l = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    sum += l;
    sum2 += l * l;
    if (Math.max(r, g, b) - Math.min(r, g, b) > 60) saturated++;
  }
  let bgKey = 0, bgCount = -1;
  for (const [k, c] of counts) if (c > bgCount) { bgKey = k; bgCount = c; }
  const bg = [(bgKey >> 8) << 4, ((bgKey >> 4) & 15) << 4, (bgKey & 15) << 4];
  let foreground = 0;
  for (let i = 0; i < n; i++) {
    const d = Math.abs(img.rgba[4 * i] - bg[0]) + Math.abs(img.rgba[4 * i + 1] - bg[1]) + Math.abs(img.rgba[4 * i + 2] - bg[2]);
    if (d > 100) foreground++;
  }
  const mean = sum / n;
  return {
    distinct: counts.size,
    foreground: foreground / n,
    lumaStd: Math.sqrt(Math.max(0, sum2 / n - mean * mean)),
    saturated: saturated / n,
  };
}

// Share of pixels whose colour moved by more than 30 (sum of channel differences).
export function changedShare(a, b) {
  if (a.width !== b.width || a.height !== b.height) return 1;
  let changed = 0;
  const n = a.width * a.height;
  for (let i = 0; i < n; i++) {
    const d = Math.abs(a.rgba[4 * i] - b.rgba[4 * i]) + Math.abs(a.rgba[4 * i + 1] - b.rgba[4 * i + 1]) +
      Math.abs(a.rgba[4 * i + 2] - b.rgba[4 * i + 2]);
    if (d > 30) changed++;
  }
  return changed / n;
}
