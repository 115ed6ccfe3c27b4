// "Look inside": the AOVs of a render (RenderResponse.aovs: raw little-endian
// arrays in base64) decoded into typed arrays, drawn as false-colour images,
// and read back under the pointer.

import { base64Bytes } from './api.js';

const ARRAY_TYPES = { float32: Float32Array, uint32: Uint32Array, uint8: Uint8Array };

export function decodeAovs(aovs) {
  const out = {};
  for (const [name, a] of Object.entries(aovs || {})) {
    const bytes = base64Bytes(a.data);
    out[name] = new ARRAY_TYPES[a.type](bytes.buffer, 0, bytes.byteLength / ARRAY_TYPES[a.type].BYTES_PER_ELEMENT);
  }
  return out;
}

// The views of "Look inside", [value, label]: the shaded image, then one per AOV
// that paint() draws; the page's select is filled from this list.
export const LOOKS = [['shaded', 'shaded'], ['depth', 'depth'], ['face', 'face id'], ['normal', 'normals'],
  ['uv', '(u, v)'], ['iterations', 'Newton iterations']];

// The AOVs a frame comes with: hovering reads z, face, uv and iterations;
// measuring z, face and normal (and the hover readout then shows those only:
// uv and iterations would make every frame 9 bytes a pixel larger); each
// false-colour view adds its own.
export const HOVER_AOVS = ['z', 'face', 'uv', 'iterations'];
export const MEASURE_AOVS = ['z', 'face', 'normal'];
const LOOK_AOV = { depth: 'z', face: 'face', normal: 'normal', uv: 'uv', iterations: 'iterations' };
export function aovsFor(look, measuring = false) {
  const base = measuring ? MEASURE_AOVS : HOVER_AOVS, own = LOOK_AOV[look];
  return own && !base.includes(own) ? [...base, own] : base;
}

// Whether decoded AOVs can paint the view `look` (the shaded view needs none).
export function hasAovsFor(look, aov) {
  const own = LOOK_AOV[look];
  return !own || !!(aov && aov.face && aov[own]);
}

// Perceptual heat map stops (the endpoints and quartiles of matplotlib's
// "inferno" colour map by van der Walt and Smith).
const INFERNO = [[0, 0, 4], [87, 16, 110], [188, 55, 84], [249, 142, 9], [252, 255, 164]];
export function heat(t) {
  const x = Math.min(Math.max(t, 0), 1) * (INFERNO.length - 1);
  const i = Math.min(Math.floor(x), INFERNO.length - 2), f = x - i;
  const a = INFERNO[i], b = INFERNO[i + 1];
  return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f];
}

// Distinct colours for face ids: hues by the golden angle, so neighbouring
// ids get far-apart hues; two lightness levels double the distinct set.
export function faceColour(id) {
  const h = (id * 137.50776) % 360;
  const l = id % 2 ? 0.55 : 0.42;
  const c = (1 - Math.abs(2 * l - 1)) * 0.85;
  const hp = h / 60, x = c * (1 - Math.abs((hp % 2) - 1));
  const [r, g, b] = hp < 1 ? [c, x, 0] : hp < 2 ? [x, c, 0] : hp < 3 ? [0, c, x] : hp < 4 ? [0, x, c] : hp < 5 ? [x, 0, c] : [c, 0, x];
  const m = l - c / 2;
  return [(r + m) * 255, (g + m) * 255, (b + m) * 255];
}

function finiteRange(values, mask) {
  let lo = Infinity, hi = -Infinity;
  for (let i = 0; i < values.length; i++) {
    if (!mask[i]) continue;
    const v = values[i];
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return lo <= hi ? [lo, hi] : [0, 1];
}

// Per-face (u, v) ranges, so that each face's parameters fill the colour range.
function uvRanges(uv, face) {
  const ranges = new Map();
  for (let i = 0; i < face.length; i++) {
    const id = face[i];
    if (!id) continue;
    const u = uv[2 * i], v = uv[2 * i + 1];
    const r = ranges.get(id);
    if (!r) ranges.set(id, [u, u, v, v]);
    else {
      if (u < r[0]) r[0] = u;
      if (u > r[1]) r[1] = u;
      if (v < r[2]) r[2] = v;
      if (v > r[3]) r[3] = v;
    }
  }
  return ranges;
}

// Fills `image` (ImageData of the frame's size) with the false-colour view
// `look` and returns its legend ({title, min, max, colour(t)}) or null.
// Background pixels keep `background` (RGBA 0-255).
export function paint(look, aov, image, background) {
  const px = image.data, face = aov.face, n = face.length;
  const mask = face;
  let legend = null;
  let colour;
  if (look === 'depth') {
    const [lo, hi] = finiteRange(aov.z, mask);
    colour = (i) => { const g = 255 * (1 - (aov.z[i] - lo) / (hi - lo || 1)) * 0.85 + 20; return [g, g, g]; };
    legend = { title: 'depth (mm, near → far)', min: lo, max: hi, colour: (t) => { const g = 255 * (1 - t) * 0.85 + 20; return [g, g, g]; } };
  } else if (look === 'face') {
    colour = (i) => faceColour(face[i]);
  } else if (look === 'normal') {
    colour = (i) => [(aov.normal[3 * i] * 0.5 + 0.5) * 255, (aov.normal[3 * i + 1] * 0.5 + 0.5) * 255, (aov.normal[3 * i + 2] * 0.5 + 0.5) * 255];
  } else if (look === 'uv') {
    const ranges = uvRanges(aov.uv, face);
    colour = (i) => {
      const r = ranges.get(face[i]);
      const u = (aov.uv[2 * i] - r[0]) / (r[1] - r[0] || 1), v = (aov.uv[2 * i + 1] - r[2]) / (r[3] - r[2] || 1);
      return [u * 255, v * 255, 60];
    };
  } else if (look === 'iterations') {
    let hi = 1;
    for (let i = 0; i < n; i++) if (face[i] && aov.iterations[i] > hi) hi = aov.iterations[i];
    colour = (i) => heat(aov.iterations[i] / hi);
    legend = { title: 'Newton iterations', min: 0, max: hi, colour: heat };
  } else {
    throw new Error(`unknown view ${look}`);
  }
  for (let i = 0; i < n; i++) {
    const c = face[i] ? colour(i) : null;
    px[4 * i] = c ? c[0] : background[0];
    px[4 * i + 1] = c ? c[1] : background[1];
    px[4 * i + 2] = c ? c[2] : background[2];
    px[4 * i + 3] = c ? 255 : background[3];
  }
  return legend;
}

export function drawLegend(canvas, legend) {
  const ctx = canvas.getContext('2d');
  for (let x = 0; x < canvas.width; x++) {
    const [r, g, b] = legend.colour(x / (canvas.width - 1));
    ctx.fillStyle = `rgb(${r | 0},${g | 0},${b | 0})`;
    ctx.fillRect(x, 0, 1, canvas.height);
  }
}

// What the AOVs say about pixel (x, y), as text.
export function describePixel(aov, width, x, y) {
  const i = y * width + x;
  if (!aov.face || !aov.face[i]) return `pixel (${x}, ${y}): background`;
  const f = (v, d) => Number(v).toFixed(d);
  // A frame fetched for measuring has no uv or iterations.
  return [
    `pixel (${x}, ${y})`,
    `face        ${aov.face[i]}`,
    aov.uv && `(u, v)      (${f(aov.uv[2 * i], 5)}, ${f(aov.uv[2 * i + 1], 5)})`,
    `depth       ${f(aov.z[i], 4)} mm`,
    aov.iterations && `iterations  ${aov.iterations[i]}`,
  ].filter(Boolean).join('\n');
}
