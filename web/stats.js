// "Where the time goes": the stage-time bar of a render's statistics (with the
// image options' stages, anti-aliasing, feature lines and the shadow map, when
// they ran) and the iteration histograms of the method comparison.

// In the order they run; the service marks them end to end, so they sum to the total.
const STAGES = [
  ['upload', 'request', '#c9ced6'],
  ['cache', 'scene cache', '#a7b3c4'],
  ['queue', 'queue', '#b0b7c3'],
  ['prescan', 'pre-scan', '#9fb4d3'],
  ['isolation', 'import process', '#8fa6c9'],
  ['read', 'read', '#6c8ebf'],
  ['nurbs_convert', 'NURBS conversion', '#4a6fa5'],
  ['mesh', 'meshing', '#82b366'],
  ['transfer', 'scene transfer', '#a3c494'],
  ['prepare', 'prepare', '#5a8f47'],
  ['frame_setup', 'frame set-up', '#e6d38f'],
  ['preliminary_map', 'preliminary map', '#d6b656'],
  ['newton', 'Newton', '#d0542e'],
  ['shadow_map', 'shadow map', '#8c6d3f'],
  ['shade', 'shading', '#9673a6'],
  ['antialias', 'anti-aliasing', '#c27ba0'],
  ['edges', 'feature lines', '#3d3d3d'],
  ['statistics', 'statistics', '#b5a1c2'],
  ['encode', 'encoding', '#7aa6a6'],
  ['response', 'answer', '#a9c9c9'],
];

// Below this the rest is the rounding of the stages' sum, not time.
const OTHER_MIN_MS = 0.05;

const fmt = (ms) => (ms >= 100 ? ms.toFixed(0) : ms >= 10 ? ms.toFixed(1) : ms.toFixed(2));

function el(tag, props = {}, ...children) {
  const e = document.createElement(tag);
  Object.assign(e, props);
  e.append(...children);
  return e;
}

// The bar (`bar`, flex children sized by time) and its legend list (`list`).
export function showStages(bar, list, statistics) {
  const t = statistics.timings_ms || {};
  const total = t.total || 0;
  const parts = STAGES.map(([key, label, colour]) => ({ key, label, colour, ms: t[key] || 0 }));
  // Stages this page does not know (a newer service): shown as one rest, not lost.
  const other = total - parts.reduce((s, p) => s + p.ms, 0);
  if (other >= OTHER_MIN_MS) parts.push({ key: 'other', label: 'other stages', colour: '#e3e6ea', ms: other });
  bar.replaceChildren();
  list.replaceChildren();
  for (const p of parts) {
    if (p.ms <= 0) continue;
    const seg = el('div', { title: `${p.label}: ${fmt(p.ms)} ms` });
    seg.style.flexGrow = String(p.ms);
    seg.style.background = p.colour;
    seg.dataset.stage = p.key;
    bar.append(seg);
    const swatch = el('span', { className: 'swatch' });
    swatch.style.background = p.colour;
    list.append(el('li', {}, swatch, `${p.label} ${fmt(p.ms)} ms`));
  }
  const aa = statistics.antialias, sh = statistics.shadows;
  if (aa && aa.rays_per_edge_pixel > 0)
    list.append(el('li', { className: 'look-antialias' }, `anti-aliasing: ${aa.rays} rays over ${aa.pixels} edge pixels`));
  if (sh && sh.enabled)
    list.append(el('li', { className: 'look-shadows' },
      `shadows: ${sh.shadowed_pixels} of ${statistics.pixels_hit} hit pixels in shadow (light map ${sh.map_size}², ${sh.rays} light rays)`));
  list.append(el('li', {}, `total ${fmt(total)} ms (${statistics.cache === 'hit' ? 'cached scene' : 'imported'})`));
  bar.setAttribute('aria-label', `Stage times of the last render, total ${fmt(total)} ms`);
}

// Histogram bars of {iterations: count}, scaled to `maxCount` so that two
// histograms side by side compare.
export function showHistogram(box, histogram, maxCount, maxK) {
  box.replaceChildren();
  const parts = [];
  for (let k = 0; k <= maxK; k++) {
    const n = histogram[String(k)] || 0;
    const bar = el('div', { title: `${k} iterations: ${n} pixels` }, el('span', {}, String(k)));
    bar.style.height = `${(100 * n) / (maxCount || 1)}%`;
    box.append(bar);
    if (n) parts.push(`${k}: ${n}`);
  }
  box.setAttribute('aria-label', `${box.getAttribute('aria-label').split(':')[0]}: ${parts.join(', ')}`);
}

export function histogramBounds(...histograms) {
  let maxCount = 0, maxK = 0;
  for (const h of histograms)
    for (const [k, n] of Object.entries(h)) {
      maxCount = Math.max(maxCount, n);
      maxK = Math.max(maxK, Number(k));
    }
  return { maxCount, maxK };
}

export { fmt };
