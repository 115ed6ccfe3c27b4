// The page: a file in, the exact render out, then orbit/pan/zoom (previews at
// a quarter of the size while the pointer moves, the full size when it stops),
// the image options (anti-aliasing, feature lines, shadows), AOV views, stage
// times, the method comparison, jobs and conversions. Only the public REST API
// is used (api.js).

import { apiKey, setApiKey, call, render, storeFile, storedFile, base64Bytes, saveBlob } from './api.js';
import { CadControls } from './cad.js';
import { Camera } from './camera.js';
import { RenderScheduler } from './scheduler.js';
import { bindInteraction } from './interaction.js';
import { decodeAovs, aovsFor, hasAovsFor, paint, drawLegend, describePixel, LOOKS } from './aov.js';
import { showStages, showHistogram, histogramBounds, fmt } from './stats.js';
import { bindJobs, bindConversions } from './jobs.js';
import { Measure } from './measure.js';
import { bindStoredFiles } from './stored_files.js';

const $ = (id) => document.getElementById(id);
for (const [value, label] of LOOKS) $('look').append(new Option(label, value));
const PREVIEW_DIVISOR = 4;
// The service's range of edge_width, px (api_schema/openapi.json).
const EDGE_WIDTH_MIN = 0.25, EDGE_WIDTH_MAX = 16;
const canvas = $('view');
// file: the File picked (for conversions); fileId: its stored copy, which every frame names.
const state = { file: null, fileId: null, fileName: '', camera: null, view: 'iso', frame: null, dirty: false };

// ---- messages ---------------------------------------------------------------
function report(error) {
  const box = $('messages');
  const text = error.status ? `${error.message} (HTTP ${error.status}${error.code ? `, ${error.code}` : ''})`
    : error instanceof TypeError ? `No answer from the service (${error.message}): is it running and reachable?`
    : error.message;
  const dismiss = document.createElement('button');
  dismiss.type = 'button';
  dismiss.textContent = 'Dismiss';
  const message = document.createElement('div');
  message.className = 'message';
  message.append(document.createTextNode(text), dismiss);
  dismiss.addEventListener('click', () => message.remove());
  box.append(message);
  while (box.children.length > 3) box.firstChild.remove();
}

const setStatus = (text) => { $('status').textContent = text; };

// ---- options ------------------------------------------------------------------
function fullSize() {
  const [width, height] = $('resolution').value.split('x').map(Number);
  return { width, height };
}

// The colour picker's value is sRGB-encoded; the renderer's colours are linear
// (it sRGB-encodes its PNG), so the line shows the colour picked: the inverse of
// the IEC 61966-2-1 transfer function.
function linearRgb(hex) {
  return [1, 3, 5].map((i) => {
    const c = parseInt(hex.slice(i, i + 2), 16) / 255;
    return (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4).toFixed(4);
  }).join(',');
}

// The look of a full-size frame: anti-aliasing, feature lines and shadows.
function lookOptions() {
  const o = { antialias: Number($('antialias').value), edges: $('edges').checked, shadows: $('shadows').checked };
  if (o.edges) {
    o.edge_color = linearRgb($('edge-color').value);
    const w = Number($('edge-width').value);
    o.edge_width = Math.min(EDGE_WIDTH_MAX, Math.max(EDGE_WIDTH_MIN, Number.isFinite(w) && w > 0 ? w : 1));
  }
  return o;
}

// A drag-time preview is a quarter-size frame scaled up: anti-aliasing would be
// blurred away by the scaling, and shadows cost a second map and a solve per
// pixel (about a second frame), so previews go without both and orbiting stays
// fluid; the full-size frame on release has them. Feature lines cost one image
// pass and are much of the look, so previews keep them, a quarter as wide so
// that the scaled-up preview shows them as wide as the final frame will.
function previewLook(look) {
  const o = { ...look, antialias: 0, shadows: false };
  if (o.edges) o.edge_width = Math.max(EDGE_WIDTH_MIN, o.edge_width / PREVIEW_DIVISOR);
  return o;
}

function imageOptions() {
  return { method: $('method').value, map_precision: $('map-precision').value, background: $('background').value,
    ...lookOptions() };
}

function requestOptions(job) {
  const { width, height } = fullSize();
  const d = job.final ? 1 : PREVIEW_DIVISOR;
  const image = job.final ? imageOptions() : previewLook(imageOptions());
  const o = { ...image, ...cad.options(), ...job.override, width: Math.round(width / d), height: Math.round(height / d) };
  if (job.camera) o.camera = job.camera;
  else Object.assign(o, { view: job.view, projection: $('projection').value });
  if (job.aovs) o.aovs = aovsFor($('look').value, measure.on || cad.picking);
  return o;
}

function backgroundRgba() {
  const v = $('background').value;
  if (v === 'transparent') return [0, 0, 0, 0];
  return [...v.split(',').map((x) => Number(x) * 255), 255];
}

// ---- frames -------------------------------------------------------------------
async function send(job, signal) {
  const doc = await render(job.fileId, requestOptions(job), signal);
  const blob = new Blob([base64Bytes(doc.image_base64)], { type: doc.content_type });
  const bitmap = await createImageBitmap(blob);
  // The bitmap's own size: a contact sheet is several views of width x height.
  return { width: bitmap.width, height: bitmap.height, blob, bitmap, aov: doc.aovs ? decodeAovs(doc.aovs) : null, stats: doc.statistics };
}

// The import's warnings beside the image (a face left empty, a healed loop).
function showWarnings(list) {
  $('warnings').replaceChildren(...(list || []).map((w) => Object.assign(document.createElement('li'), { textContent: w })));
}

function draw() {
  const frame = state.frame;
  if (!frame) return;
  const look = $('look').value;
  canvas.width = frame.width;
  canvas.height = frame.height;
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, frame.width, frame.height);
  const legendBox = $('legend');
  if (look === 'shaded' || !hasAovsFor(look, frame.aov)) {
    ctx.drawImage(frame.bitmap, 0, 0);
    legendBox.hidden = true;
    canvas.dataset.look = 'shaded';
    return;
  }
  const image = ctx.createImageData(frame.width, frame.height);
  const legend = paint(look, frame.aov, image, backgroundRgba());
  ctx.putImageData(image, 0, 0);
  canvas.dataset.look = look;
  legendBox.hidden = !legend;
  if (legend) {
    drawLegend($('legend-bar'), legend);
    $('legend-min').textContent = fmt(legend.min);
    $('legend-max').textContent = fmt(legend.max);
    $('legend-title').textContent = legend.title;
  }
}

function show(frame, job) {
  if (job.view) state.camera = Camera.fromStatistics(frame.stats.camera);
  canvas.dataset.frames = String(Number(canvas.dataset.frames || 0) + 1);
  if (job.final) {
    state.frame = frame;
    draw();
    cad.frameShown(frame);
    showWarnings(frame.stats.warnings);
    $('save-png').disabled = false;
    $('save-exr').disabled = false;
    showStages($('stages'), $('stage-list'), frame.stats);
    canvas.dataset.final = '1';
    const s = frame.stats;
    let text = `${frame.width}×${frame.height}, ${s.method}, ${s.faces} faces, ${s.pixels_hit} pixels hit, ` +
      `${fmt(s.timings_ms.total)} ms (${s.cache === 'hit' ? 'cached scene' : 'imported'})`;
    // The wall-clock time the user waited for this frame (request to image on screen).
    if (job.startedAt) {
      const elapsed = (performance.now() - job.startedAt) / 1000;
      canvas.dataset.elapsedS = elapsed.toFixed(1);
      text += `; on screen ${elapsed.toFixed(1)} s after the request`;
    }
    if (job.releasedAt) {
      const latency = performance.now() - job.releasedAt;
      canvas.dataset.latencyMs = latency.toFixed(1);
      text += `; full-size frame ${latency.toFixed(0)} ms after the pointer stopped`;
    }
    setStatus(text);
    if (state.pointer && frame.aov) hover(state.pointer);
    measure.frameShown();
  } else {
    canvas.width = frame.width * PREVIEW_DIVISOR;
    canvas.height = frame.height * PREVIEW_DIVISOR;
    const ctx = canvas.getContext('2d');
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.drawImage(frame.bitmap, 0, 0, canvas.width, canvas.height);
    canvas.dataset.final = '0';
    measure.drawOverlay();
  }
}

let busyTimer = 0;
function busy(on, job) {
  clearInterval(busyTimer);
  canvas.dataset.busy = on ? '1' : '0';
  const box = $('busy');
  if (!on || !job.final) {
    box.hidden = true;
    return;
  }
  const t0 = performance.now();
  job.startedAt = t0;
  const what = job.first ? 'Importing and rendering' : 'Rendering';
  const tick = () => { $('busy-text').textContent = `${what}… ${((performance.now() - t0) / 1000).toFixed(1)} s`; };
  tick();
  box.hidden = false;
  busyTimer = setInterval(tick, 100);
}

// The CAD-view controls: a slider moving sends previews, its release the full frame.
const cad = new CadControls($, {
  preview: () => {
    if (!state.fileId) return;
    const job = { fileId: state.fileId, final: false };
    if (!state.view && state.camera) job.camera = state.camera.toOption();
    else job.view = state.view || 'iso';
    scheduler.submit(job);
  },
  final: () => renderFinal(),
  frame: () => state.frame,
  needAovs: askAovs,
  busyElsewhere: () => measure.on,
});
const saveName = (ext) => `${(state.fileName || 'render').replace(/\.[^.]*$/, '')}.${ext}`;
$('save-png').addEventListener('click', () => {
  if (state.frame) saveBlob(state.frame.blob, saveName('png'));
});
// The view on screen as OpenEXR: the service writes every AOV as channels of
// their own (depth, face, normal, (u, v), iterations), so a compositor or a
// script reads the exact per-pixel values; fetched with the key, saved as a blob.
$('save-exr').addEventListener('click', async () => {
  if (!state.fileId) return;
  const button = $('save-exr'), status = $('save-status');
  button.disabled = true;
  status.textContent = 'Rendering the EXR…';
  try {
    const job = { final: true };
    if (!state.view && state.camera) job.camera = state.camera.toOption();
    else job.view = state.view || 'iso';
    const res = await call('/v1/renders', {
      method: 'POST', body: JSON.stringify({ file_id: state.fileId, ...requestOptions(job), format: 'exr' }),
      contentType: 'application/json', accept: 'image/x-exr', retry: true,
    });
    const blob = await res.blob(), name = saveName('exr');
    saveBlob(blob, name);
    status.textContent = `saved ${name} (${blob.size} bytes)`;
  } catch (err) {
    status.textContent = '';
    report(err);
  } finally {
    button.disabled = !state.fileId;
  }
});

const scheduler = new RenderScheduler({
  send, show, busy,
  fail: (error) => { report(error); setStatus('The render failed.'); },
});

// A full-size frame. The AOVs (about 17 bytes a pixel, 8 MB at 800x600; 20
// bytes, 10 MB, the ones measuring reads) come with it only when the view
// shows them or measuring reads them; the shaded view
// fetches them on the first hover, so that a release shows the image without
// waiting for them.
function renderFinal(extra = {}) {
  if (!state.fileId) return;
  const job = { fileId: state.fileId, final: true, aovs: $('look').value !== 'shaded' || measure.on || cad.picking, ...extra };
  // A named view still chosen is fitted again (explode, hidden parts change what
  // it frames); after an orbit, the camera the user left.
  if (!job.view && !state.view && state.camera) job.camera = state.camera.toOption();
  else job.view = job.view || state.view || 'iso';
  scheduler.submit(job);
}

// The frame on screen again, with the AOVs (measuring and picking a face read them).
function askAovs() {
  if (state.frame && !state.frame.stats.views) renderFinal({ aovs: true });
}

// ---- inputs -------------------------------------------------------------------
// Nothing of the last model stays on screen: image, stage times, read-out,
// legend, status (a failed load must not leave them under the new name).
function clearFrame() {
  scheduler.cancelAll();
  state.frame = null;
  state.camera = null;
  canvas.width = canvas.width;  // resets the bitmap to transparent
  canvas.dataset.final = '0';
  canvas.dataset.cleared = String(Number(canvas.dataset.cleared || 0) + 1);
  $('stages').replaceChildren();
  $('stage-list').replaceChildren();
  $('hover').textContent = '';
  $('legend').hidden = true;
  showWarnings([]);
  $('save-png').disabled = true;
  $('save-exr').disabled = true;
  $('save-status').textContent = '';
  cad.setModel(null);
  measure.reset();
  setStatus('');
}

// The page's address names the stored file and the view, so a link reopens them.
function remember() {
  const params = new URLSearchParams();
  if (state.fileId) params.set('file', state.fileId);
  if (state.fileId && state.view) params.set('view', state.view);
  const text = params.toString();
  history.replaceState(null, '', text ? `#${text}` : location.pathname);
}

// A stored file on screen: its first frame, at `view`.
function openStored(fileId, name, fileName, summary, view = 'iso') {
  state.fileId = fileId;
  state.fileName = fileName;
  state.units = summary?.units || '';
  cad.setModel(summary);
  state.view = view;
  $('file-name').textContent = name;
  $('compare').disabled = false;
  pressView(view);
  remember();
  renderFinal({ view, first: true });
  if (measure.on) measure.prepare();
}

async function loadFile(file) {
  if (!file) return;
  clearFrame();
  state.file = file;
  state.fileId = null;
  $('compare').disabled = true;
  const label = `${file.name} (${(file.size / 1024).toFixed(0)} KiB)`;
  $('file-name').textContent = `${label}: uploading…`;
  remember();
  try {
    const stored = await storeFile(file);
    if (state.file !== file) return;  // another file was picked meanwhile
    openStored(stored.id, label, file.name, stored.summary);
    storedFiles.reload();
  } catch (error) {
    if (state.file !== file) return;
    state.file = null;
    $('file-name').textContent = `${label}: not loaded`;
    setStatus('The file could not be loaded.');
    report(error);
  }
}

// A stored file as GET /v1/files{/id} describes it, reopened without an upload.
function openRecord(stored, view = 'iso') {
  clearFrame();
  state.file = null;
  openStored(stored.id, `${stored.filename} (${(stored.bytes / 1024).toFixed(0)} KiB, stored)`, stored.filename, stored.summary, view);
}

// A link with #file=ID&view=V reopens that stored file without uploading it.
async function openFromAddress() {
  const params = new URLSearchParams(location.hash.slice(1));
  const id = params.get('file');
  if (!id) return;
  const view = ['iso', 'front', 'back', 'left', 'right', 'top', 'bottom'].includes(params.get('view')) ? params.get('view') : 'iso';
  try {
    openRecord(await storedFile(id), view);
  } catch (error) {
    report(error);
  }
}

function pressView(name) {
  for (const b of document.querySelectorAll('button.view')) b.setAttribute('aria-pressed', String(b.dataset.view === name));
}

$('file').addEventListener('change', (e) => loadFile(e.target.files[0]));
const drop = $('drop');
for (const target of [drop, canvas]) {
  target.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
  target.addEventListener('dragleave', () => drop.classList.remove('over'));
  target.addEventListener('drop', (e) => {
    e.preventDefault();
    drop.classList.remove('over');
    loadFile(e.dataTransfer.files[0]);
  });
}

for (const b of document.querySelectorAll('button.view')) {
  b.setAttribute('aria-pressed', 'false');
  b.addEventListener('click', () => {
    state.view = b.dataset.view;
    state.camera = null;
    pressView(state.view);
    remember();
    renderFinal({ view: state.view });
  });
}
for (const id of ['resolution', 'method', 'map-precision', 'background', 'antialias', 'shadows'])
  $(id).addEventListener('change', () => renderFinal());
// The line colour and width only matter with the lines on: disabled without them.
const syncLineControls = () => { for (const id of ['edge-color', 'edge-width']) $(id).disabled = !$('edges').checked; };
syncLineControls();  // a reload may restore the checkbox's state
$('edges').addEventListener('change', () => {
  syncLineControls();
  renderFinal();
});
for (const id of ['edge-color', 'edge-width']) $(id).addEventListener('change', () => { if ($('edges').checked) renderFinal(); });
// A contact sheet of the drawing's views (one request: one prepare, four frames)
// with the current image options; a named view or an orbit goes back to one view.
const SHEET_VIEWS = ['front', 'top', 'right', 'iso'];
$('sheet').addEventListener('click', () => {
  if (!state.fileId) return;
  scheduler.submit({ fileId: state.fileId, final: true, aovs: false, override: { views: SHEET_VIEWS, projection: $('projection').value } });
});

// The projection of the named views and of the camera the user orbits (the
// view keeps its size at the target across the switch).
$('projection').addEventListener('change', () => {
  if (state.camera) state.camera.setProjection($('projection').value);
  renderFinal();
});
$('look').addEventListener('change', () => {
  const look = $('look').value, aov = state.frame?.aov;
  if (state.frame && !hasAovsFor(look, aov)) renderFinal();
  else draw();
});

bindInteraction(canvas, {
  move(change) {
    if (!state.camera || !state.fileId) return;
    change(state.camera);
    state.view = null;
    state.dirty = true;
    pressView(null);
    remember();
    scheduler.submit({ fileId: state.fileId, final: false, camera: state.camera.toOption() });
  },
  settle() {
    if (!state.dirty) return;
    state.dirty = false;
    renderFinal({ releasedAt: performance.now() });
  },
  hover,
});
canvas.addEventListener('pointerleave', () => { state.pointer = null; });

// The readout of the pixel under the pointer; fetches the AOVs of the shown
// frame when it has none yet (and reads again when they arrive).
function hover(e) {
  state.pointer = { clientX: e.clientX, clientY: e.clientY };
  const f = state.frame;
  if (!f || canvas.dataset.final !== '1') return;
  if (f.stats.views) {  // a contact sheet: no AOVs to read (its cells are other cameras)
    $('hover').textContent = 'A contact sheet: pick a view to read its pixels.';
    return;
  }
  if (!f.aov) {
    if (!f.aovAsked && canvas.dataset.busy !== '1') {
      f.aovAsked = true;
      renderFinal({ aovs: true });
    }
    $('hover').textContent = 'Reading the AOVs of this view…';
    return;
  }
  const r = canvas.getBoundingClientRect();
  const x = Math.floor(((e.clientX - r.left) * f.width) / r.width), y = Math.floor(((e.clientY - r.top) * f.height) / r.height);
  if (x >= 0 && y >= 0 && x < f.width && y < f.height) $('hover').textContent = describePixel(f.aov, f.width, x, y);
}

// ---- measuring -------------------------------------------------------------------
// On the full-size frame with its AOVs; snapping to the stored model's vertices
// and edges only while the image shows that model as stored (no section,
// explode or hidden part moves or removes them).
const measure = new Measure($, {
  frame: () => state.frame,
  needAovs: askAovs,
  file: () => (state.fileId ? { id: state.fileId, units: state.units } : null),
  snapAllowed: () => Object.keys(cad.options()).length === 0,
  report,
});

// ---- compare methods -------------------------------------------------------------
const COMPARED_METHODS = ['proposed', 'martin'];
// A column per method from the page's template; its fields get ids `${method}-${field}`.
for (const method of COMPARED_METHODS) {
  const column = $('compare-column').content.firstElementChild.cloneNode(true);
  column.id = `compare-${method}`;
  for (const field of column.querySelectorAll('[data-field]')) field.id = `${method}-${field.dataset.field}`;
  column.querySelector('[data-field="name"]').textContent = method;
  column.querySelector('[data-field="histogram"]').setAttribute('aria-label', `Iteration histogram, ${method}`);
  $('compare-grid').append(column);
}
$('compare').addEventListener('click', async () => {
  if (!state.fileId || !state.camera) return;
  const button = $('compare');
  button.disabled = true;
  button.textContent = 'Comparing…';
  const results = {};
  try {
    for (const method of COMPARED_METHODS) {
      const job = { final: true, camera: state.camera.toOption(), override: { method } };
      results[method] = (await render(state.fileId, requestOptions(job))).statistics;
    }
    const { maxCount, maxK } = histogramBounds(results.proposed.newton.iteration_histogram, results.martin.newton.iteration_histogram);
    for (const [method, s] of Object.entries(results)) {
      $(`${method}-newton-ms`).textContent = fmt(s.timings_ms.newton);
      $(`${method}-primary-ms`).textContent = fmt(s.newton.primary_pass_ms);
      $(`${method}-mean`).textContent = s.newton.mean_iterations.toFixed(2);
      showHistogram($(`${method}-histogram`), s.newton.iteration_histogram, maxCount, maxK);
    }
    const ratio = results.martin.timings_ms.newton / (results.proposed.timings_ms.newton || 1);
    setStatus(`Newton stage: proposed ${fmt(results.proposed.timings_ms.newton)} ms, martin ${fmt(results.martin.timings_ms.newton)} ms (martin/proposed ${ratio.toFixed(2)}×)`);
  } catch (err) {
    report(err);
  } finally {
    button.disabled = false;
    button.textContent = 'Compare methods';
  }
});

// ---- API key ------------------------------------------------------------------------
function showKeyState() {
  $('api-key').value = '';
  $('api-key').placeholder = apiKey() ? 'a key is set for this tab' : 'only if the service needs one';
}
$('key-form').addEventListener('submit', (e) => {
  e.preventDefault();
  setApiKey($('api-key').value.trim());
  showKeyState();
});
$('key-forget').addEventListener('click', () => { setApiKey(''); showKeyState(); });
showKeyState();

// ---- jobs and conversions -----------------------------------------------------------
bindJobs({
  form: $('job-form'), files: $('job-files'), list: $('job-list'), report,
  // A named view, not the current camera: the job's files are other parts.
  renderOptions: () => ({ ...imageOptions(), ...fullSize(), view: state.view || 'iso' }),
});
bindConversions({
  form: $('convert-form'), file: $('convert-file'), format: $('convert-format'), result: $('convert-result'),
  currentFile: () => (state.fileId ? { id: state.fileId, name: state.fileName } : null), report,
});

const storedFiles = bindStoredFiles({
  panel: $('stored-box'), list: $('stored-files'), refresh: $('stored-refresh'), open: (f) => openRecord(f), report,
});

openFromAddress();
document.body.dataset.ready = '1';
