// Exact measuring on the image: the distance between two points, the angle
// between two faces' normals, a point's coordinates. A point is the exact
// surface hit under the pointer (the z AOV's hit distance along the camera's
// pixel ray, no mesh), or, snapped within a few pixels, a B-rep vertex or an
// edge point of the model's trim loops evaluated in double (model_edges.js).

import { call, base64Bytes } from './api.js';
import { Camera } from './camera.js';
import { modelEdges, surfacePoint } from './model_edges.js';
import { exactEdgePoint, projectOnSurface } from './edge_point.js';
import { sub, dot, lerp } from './vec3.js';

// A vertex or edge this close to the pointer (CSS pixels) is snapped to.
const SNAP_CSS_PX = 8;
// A vertex or edge point counts as seen when, within this many pixels of it,
// the image shows background or a surface not nearer than it (a silhouette
// corner has background beside it; a hidden one only nearer surfaces).
const VISIBLE_PX = 2;
// ... "not nearer" up to this many pixel sizes of depth (a face seen at a slant
// changes depth by about a pixel size per pixel).
const VISIBLE_DEPTH_PX = 4;
// Relative rounding of a float32 (the z AOV's hit distance): half an ulp.
const FLOAT32_EPS = 2 ** -24;
// Two unit normals rounded to float32 (the normal AOV) turn by at most about
// an ulp each: the angle between them is known to this, in degrees.
const ANGLE_PRECISION_DEG = (4 * FLOAT32_EPS * 180) / Math.PI;
// A vertex is S(u, v) at a loop's corner evaluated in double: its error is the
// model's own, at best OCCT's vertex tolerance (Precision::Confusion, 1e-7 mm).
const MODEL_PRECISION_MM = 1e-7;
// The neighbour face's loop must pass within this many times the two loops'
// tolerances of an edge point, and the exact point lie as near (else the
// loops are not of one edge, or the iteration found another branch).
const EDGE_REACH = 10;
// How many of the nearest other faces' chords are tried as the neighbour.
const EDGE_CANDIDATES = 4;
// Arrow keys move the keyboard cursor by this many image pixels (shift: FAST).
const KEY_STEP = 1, KEY_STEP_FAST = 10;
// A click is a press and release this close (CSS px); farther, it was an orbit.
const CLICK_SLOP_PX = 4;
// The file's declared length units in mm (importer/length_unit.cpp's names).
const UNIT_MM = { mm: 1, cm: 10, m: 1000, km: 1e6, micron: 1e-3, inch: 25.4, foot: 304.8, mile: 1609344, mil: 0.0254, microinch: 2.54e-5 };
// What each kind of measurement needs: picks, and whether vertices and edges snap (an angle needs faces).
const KINDS = { distance: { picks: 2, snap: true }, angle: { picks: 2, snap: false }, point: { picks: 1, snap: true } };


// Decimals that show a value of this precision (mm), at least 3, at most 6.
const decimals = (precision) => Math.min(6, Math.max(3, Math.ceil(-Math.log10(precision))));

// Where on segment ab the point nearest the ray (o, unit d) is, in [0, 1].
function segmentParamNearRay(a, b, o, d) {
  const e = sub(b, a), w = sub(a, o);
  const A = dot(e, e), B = dot(e, d), D = dot(e, w), E = dot(d, w);
  const denom = A - B * B;
  if (!(denom > 1e-12 * A)) return 0;
  return Math.min(1, Math.max(0, (B * E - D) / denom));
}

// Distance of (px, py) to the screen segment pq.
function screenDistance(px, py, p, q) {
  const ex = q.x - p.x, ey = q.y - p.y, l2 = ex * ex + ey * ey;
  const s = l2 > 0 ? Math.min(1, Math.max(0, ((px - p.x) * ex + (py - p.y) * ey) / l2)) : 0;
  return Math.hypot(px - p.x - s * ex, py - p.y - s * ey);
}

export class Measure {
  // $: element lookup; frame(): the full-size frame on screen or null;
  // needAovs(): asks for that frame again with the AOVs; file(): {id, units} or
  // null; snapAllowed(): false while sections, explode or hidden parts change
  // what the stored model's edges would show; report(error).
  constructor($, { frame, needAovs, file, snapAllowed, report }) {
    Object.assign(this, { $, frame, needAovs, file, snapAllowed, report });
    this.canvas = $('view');
    this.overlay = $('measure-overlay');
    this.on = false;
    this.picks = [];      // the picks of the measurement under way
    this.results = [];    // [{kind, value, text, points}]
    this.cursor = null;   // keyboard cursor, image pixels
    this.hovered = null;  // what a click would pick now
    this.models = new Map();  // file id -> Promise of modelEdges()
    this.edges = null;
    $('measure-toggle').addEventListener('click', () => this.toggle());
    $('measure-kind').addEventListener('change', () => this.cancel());
    $('measure-clear').addEventListener('click', () => this.clearResults());
    this.bindPointer();
    // Esc anywhere cancels the measurement under way; a second Esc leaves the mode.
    document.addEventListener('keydown', (e) => {
      if (e.key !== 'Escape' || !this.on) return;
      if (this.picks.length) this.cancel();
      else this.toggle(false);
    });
    // In the mode the image's keys move the cursor and pick, before the orbit keys.
    this.canvas.addEventListener('keydown', (e) => this.key(e), { capture: true });
  }

  kind() { return this.$('measure-kind').value; }

  hint(text) { this.$('measure-hint').textContent = text; }

  toggle(on = !this.on) {
    this.on = on;
    this.$('measure-toggle').setAttribute('aria-pressed', String(on));
    this.canvas.classList.toggle('measuring', on);
    this.picks = [];
    this.hovered = null;
    if (on) {
      this.prepare();
    } else {
      this.hint('');
    }
    this.drawOverlay();
  }

  cancel() {
    this.picks = [];
    if (this.on) this.promptNext();
    this.drawOverlay();
  }

  clearResults() {
    this.results = [];
    this.$('measure-results').replaceChildren();
    this.cancel();
  }

  // A new file: nothing measured on the last one stays.
  reset() {
    this.edges = null;
    for (const k of ['vertices', 'segments', 'modelMs']) delete this.overlay.dataset[k];
    this.hovered = null;
    this.cursor = null;
    this.clearResults();
  }

  // The model's edges for the file on screen and a frame with the AOVs.
  async prepare() {
    const file = this.file();
    if (!file) {
      this.hint('Open a file to measure it.');
      return;
    }
    this.hint('Loading the model\'s edges…');
    // No frame yet: the one on its way asks for the AOVs itself (renderFinal reads `on`).
    const f = this.frame();
    if (f && (!f.aov || !f.aov.normal)) this.needAovs();
    try {
      const t0 = performance.now();
      if (!this.models.has(file.id)) this.models.set(file.id, this.loadModel(file.id));
      const edges = await this.models.get(file.id);
      if (this.file()?.id !== file.id) return;
      this.edges = edges;
      // For the browser test's log: the model's size and the time to have it.
      Object.assign(this.overlay.dataset, { vertices: String(edges.vertices.length), segments: String(edges.segments.length),
        modelMs: (performance.now() - t0).toFixed(0) });
      if (this.on) this.promptNext();
    } catch (error) {
      this.models.delete(file.id);
      this.edges = null;
      this.hint('The model\'s edges could not be read: measuring on surfaces only, without snapping.');
      this.report(error);
    }
  }

  // The stored file's exact faces (NURBS JSON), read once per file.
  async loadModel(id) {
    const res = await call('/v1/conversions', {
      method: 'POST', body: JSON.stringify({ file_id: id, format: 'json' }), contentType: 'application/json', retry: true,
    });
    const doc = JSON.parse(new TextDecoder().decode(base64Bytes((await res.json()).data_base64)));
    return modelEdges(doc);
  }

  promptNext() {
    const k = this.kind(), n = this.picks.length;
    const what = k === 'angle' ? ['the first face', 'the second face'] : k === 'point' ? ['a point'] : ['the first point', 'the second point'];
    const noSnap = KINDS[k].snap && !this.snapAllowed() ? ' Snapping is off while a section, explode or hidden parts change the model.' : '';
    this.hint(`Click ${what[n]} (or move the cursor with the arrow keys and press Enter); Esc cancels.${noSnap}`);
  }

  // ---- picking ----------------------------------------------------------------
  // The frame measured on: full size, one view, with the AOVs.
  usableFrame() {
    const f = this.frame();
    if (!f || f.stats.views || !f.aov || !f.aov.z || this.canvas.dataset.final !== '1') return null;
    return f;
  }

  visible(f, s) {
    if (!(s.t > 0)) return false;  // behind a perspective eye: projected mirrored, never seen
    const ix = Math.floor(s.x), iy = Math.floor(s.y);
    const eps = VISIBLE_DEPTH_PX * f.camera.pixelSize(s.t, f.height);
    for (let y = iy - VISIBLE_PX; y <= iy + VISIBLE_PX; y++) {
      for (let x = ix - VISIBLE_PX; x <= ix + VISIBLE_PX; x++) {
        if (x < 0 || y < 0 || x >= f.width || y >= f.height) continue;
        const i = y * f.width + x;
        if (!f.aov.face[i] || f.aov.z[i] >= s.t - eps) return true;
      }
    }
    return false;
  }

  // The nearest seen vertex within `radius` image pixels of (px, py).
  snapVertex(f, px, py, radius) {
    let best = null;
    for (const v of this.edges.vertices) {
      const s = f.project(v.p);
      const d = Math.hypot(s.x - px, s.y - py);
      if (d <= radius && (!best || d < best.d) && this.visible(f, s)) best = { d, v };
    }
    return best && { kind: 'vertex', point: best.v.p, face: best.v.face, precision: MODEL_PRECISION_MM };
  }

  // The seen edge point nearest the pointer's ray, on the nearest edge within `radius`.
  snapEdge(f, px, py, radius) {
    const ray = f.camera.rayAt(px, py, f.width, f.height);
    // The loop points on this frame, projected once (a large part has 10^5).
    if (f.edges !== this.edges) {
      f.edges = this.edges;
      f.screen = this.edges.points.map(f.project);
    }
    let best = null;
    for (const seg of this.edges.segments) {
      const p = f.screen[seg.ia], q = f.screen[seg.ib];
      const d = screenDistance(px, py, p, q);
      if (d > radius || (best && d >= best.d)) continue;
      const s = segmentParamNearRay(seg.a, seg.b, ray.origin, ray.dir);
      // On the face's surface at the loop's (u, v): exact on a straight edge,
      // within the loop's sampling tolerance on a curved one.
      const [u, v] = lerp(seg.uvA, seg.uvB, s);
      const point = surfacePoint(seg.surface, u, v);
      // Off the true edge by up to the face's trim tolerance, taken to 3D by the segment's length ratio.
      const speed = Math.hypot(...sub(seg.b, seg.a)) / Math.hypot(seg.uvB[0] - seg.uvA[0], seg.uvB[1] - seg.uvA[1]);
      const precision = Math.max(MODEL_PRECISION_MM, seg.toleranceUv * (Number.isFinite(speed) ? speed : 0));
      if (this.visible(f, f.project(point))) best = { d, point, face: seg.face, precision, surface: seg.surface, uv: [u, v] };
    }
    return best && { kind: 'edge', point: best.point, face: best.face, precision: best.precision, surface: best.surface, uv: best.uv };
  }

  // The exact surface hit of the pixel under (px, py): its pixel ray at the z AOV's distance.
  surfaceHit(f, px, py) {
    const ix = Math.floor(px), iy = Math.floor(py);
    if (ix < 0 || iy < 0 || ix >= f.width || iy >= f.height) return null;
    const i = iy * f.width + ix, face = f.aov.face[i];
    if (!face) return null;
    const t = f.aov.z[i], ray = f.camera.rayAt(ix + 0.5, iy + 0.5, f.width, f.height);
    const point = ray.origin.map((o, k) => o + t * ray.dir[k]);
    const normal = f.aov.normal ? [0, 1, 2].map((k) => f.aov.normal[3 * i + k]) : null;
    const precision = (f.stats.newton?.tolerance || 0) + t * FLOAT32_EPS;
    return { kind: 'surface', point, face, normal, precision };
  }

  // What a pick at image position (px, py) would take, or null (background).
  locate(px, py) {
    const f = this.usableFrame();
    if (!f) return null;
    if (!f.camera) {
      f.camera = Camera.fromStatistics(f.stats.camera);
      f.project = f.camera.projector(f.width, f.height);
    }
    const radius = (SNAP_CSS_PX * f.width) / (this.canvas.getBoundingClientRect().width || f.width);
    if (KINDS[this.kind()].snap && this.edges && this.$('measure-snap').checked && this.snapAllowed()) {
      const snapped = this.snapVertex(f, px, py, radius) || this.snapEdge(f, px, py, radius);
      if (snapped) return snapped;
    }
    return this.surfaceHit(f, px, py);
  }

  pick(px, py) {
    if (this.frame()?.stats.views) {
      this.hint('A contact sheet: pick a view to measure on it.');
      return;
    }
    if (!this.usableFrame()) {
      this.hint('Wait for the full-size frame (with its AOVs) to measure on it.');
      this.needAovs();
      return;
    }
    let hit = this.locate(px, py);
    if (hit?.kind === 'edge') hit = this.exactEdge(hit);
    if (!hit) {
      this.hint('Nothing there: pick a point on the part.');
      return;
    }
    if (this.kind() === 'angle' && !hit.normal) {
      this.hint('This frame has no normals yet: wait for it and pick again.');
      this.needAovs();
      return;
    }
    this.picks.push(hit);
    if (this.picks.length === KINDS[this.kind()].picks) {
      this.addResult(this.kind(), this.picks);
      this.picks = [];
    }
    this.promptNext();
    this.drawOverlay();
  }

  // An edge point moved onto the true edge, where its face meets the
  // neighbour whose loop passes nearest (edge_point.js); kept as it is where
  // that fails or would move it farther than the loops' tolerances allow.
  exactEdge(hit) {
    // The other faces' chords near the point (a chord is within `sagitta` of its
    // curve), then their surfaces' true distance from it, the nearest first.
    const near = [];
    for (const seg of this.edges.segments) {
      if (seg.face === hit.face) continue;
      const e = sub(seg.b, seg.a), l2 = dot(e, e);
      const s = l2 > 0 ? Math.min(1, Math.max(0, dot(sub(hit.point, seg.a), e) / l2)) : 0;
      const d = Math.hypot(...sub(lerp(seg.a, seg.b, s), hit.point));
      if (d <= this.edges.sagitta + EDGE_REACH * hit.precision) near.push({ d, seg, s });
    }
    near.sort((x, y) => x.d - y.d);
    let best = null;
    for (const { seg, s } of near.slice(0, EDGE_CANDIDATES)) {
      const on = projectOnSurface(seg.surface, hit.point, lerp(seg.uvA, seg.uvB, s));
      const d = Math.hypot(...sub(on.point, hit.point));
      if (!best || d < best.d) best = { d, seg, uv: on.uv };
    }
    if (!best) return hit;
    const seg = best.seg;
    const speed = Math.hypot(...sub(seg.b, seg.a)) / Math.hypot(seg.uvB[0] - seg.uvA[0], seg.uvB[1] - seg.uvA[1]);
    const reach = EDGE_REACH * (hit.precision + seg.toleranceUv * (Number.isFinite(speed) ? speed : 0));
    if (best.d > reach) return hit;
    const exact = exactEdgePoint(hit.point, { surface: hit.surface, uv: hit.uv }, { surface: seg.surface, uv: best.uv });
    if (!exact || Math.hypot(...sub(exact.point, hit.point)) > reach) return hit;
    return { ...hit, point: exact.point, precision: Math.max(MODEL_PRECISION_MM, exact.residual) };
  }

  // ---- results ------------------------------------------------------------------
  // A length in the file's declared unit (and mm when that is another), with the decimals its precision supports.
  length(mm, precision) {
    const unit = this.file()?.units || 'mm', k = UNIT_MM[unit] || 1;
    const d = decimals(precision / k);
    const inUnit = `${(mm / k).toFixed(d)} ${UNIT_MM[unit] ? unit : 'mm'}`;
    return k === 1 ? inUnit : `${inUnit} (${mm.toFixed(decimals(precision))} mm)`;
  }

  describe(hit) {
    const what = { vertex: 'vertex', edge: 'edge point', surface: 'surface point' }[hit.kind];
    return `${what} of face ${hit.face}`;
  }

  addResult(kind, picks) {
    let value, text, precision = null;
    if (kind === 'distance') {
      const [a, b] = picks;
      value = Math.hypot(...sub(a.point, b.point));
      precision = a.precision + b.precision;
      text = `distance ${this.length(value, precision)} ±${precision.toExponential(0)} mm, ${this.describe(a)} to ${this.describe(b)}`;
    } else if (kind === 'angle') {
      const [a, b] = picks;
      const c = dot(a.normal, b.normal) / Math.hypot(...a.normal) / Math.hypot(...b.normal);
      value = (Math.acos(Math.min(1, Math.max(-1, c))) * 180) / Math.PI;
      text = `angle between the normals of faces ${a.face} and ${b.face}: ${value.toFixed(3)}° ±${ANGLE_PRECISION_DEG.toExponential(0)}°`;
    } else {
      const [a] = picks;
      value = a.point;
      precision = a.precision;
      const unit = this.file()?.units || 'mm', k = UNIT_MM[unit] || 1;
      const d = decimals(a.precision / k);
      text = `point (${a.point.map((x) => (x / k).toFixed(d)).join(', ')}) ${UNIT_MM[unit] ? unit : 'mm'} ±${a.precision.toExponential(0)} mm, ${this.describe(a)}`;
    }
    this.results.push({ kind, value, text, points: picks.map((p) => p.point) });
    const item = document.createElement('li');
    item.className = 'measure-result';
    item.dataset.kind = kind;
    item.dataset.value = JSON.stringify(value);
    if (precision !== null) item.dataset.precision = String(precision);
    item.dataset.snaps = picks.map((p) => p.kind).join(' ');
    item.textContent = text;
    this.$('measure-results').append(item);
  }

  // ---- overlay ---------------------------------------------------------------------
  // Markers of the picks, the results' segments and what a click would pick,
  // drawn over the image at the current frame's camera.
  drawOverlay() {
    const o = this.overlay, f = this.usableFrame() || this.frame();
    o.width = this.canvas.width;
    o.height = this.canvas.height;
    const ctx = o.getContext('2d');
    ctx.clearRect(0, 0, o.width, o.height);
    // A preview while orbiting is another camera: no markers until its full frame.
    if (!this.on || !f?.stats?.camera || f.stats.views || this.canvas.dataset.final !== '1') return;
    const at = f.project || Camera.fromStatistics(f.stats.camera).projector(f.width, f.height);
    ctx.lineWidth = 2;
    for (const r of this.results) {
      if (r.kind !== 'distance') continue;
      const [a, b] = r.points.map(at);
      ctx.strokeStyle = '#1f5fbf';
      ctx.beginPath();
      ctx.moveTo(a.x, a.y);
      ctx.lineTo(b.x, b.y);
      ctx.stroke();
    }
    const mark = (p, colour, size) => {
      const s = at(p);
      ctx.strokeStyle = colour;
      ctx.strokeRect(s.x - size, s.y - size, 2 * size, 2 * size);
    };
    for (const r of this.results) for (const p of r.points) mark(p, '#1f5fbf', 4);
    for (const p of this.picks) mark(p.point, '#d9480f', 5);
    if (this.hovered) {
      const h = this.hovered, colour = h.kind === 'surface' ? '#555' : '#2b8a3e', s = at(h.point);
      mark(h.point, colour, h.kind === 'vertex' ? 7 : 5);
      ctx.fillStyle = colour;
      ctx.font = '13px system-ui, sans-serif';
      ctx.fillText(h.kind, s.x + 10, s.y - 10);
    }
    if (this.cursor) {
      ctx.strokeStyle = '#000';
      ctx.lineWidth = 1;
      ctx.beginPath();
      ctx.moveTo(this.cursor.x - 8, this.cursor.y);
      ctx.lineTo(this.cursor.x + 8, this.cursor.y);
      ctx.moveTo(this.cursor.x, this.cursor.y - 8);
      ctx.lineTo(this.cursor.x, this.cursor.y + 8);
      ctx.stroke();
    }
  }

  // Shows what a pick at (px, py) would take: the snap marker and a line of text.
  preview(px, py) {
    const t0 = performance.now();
    this.hovered = this.locate(px, py);
    this.overlay.dataset.locateMs = (performance.now() - t0).toFixed(1);  // the browser test logs it
    this.canvas.dataset.snap = this.hovered ? this.hovered.kind : '';
    this.drawOverlay();
  }

  // ---- input ------------------------------------------------------------------------
  imagePosition(e) {
    const r = this.canvas.getBoundingClientRect(), f = this.frame();
    const w = f ? f.width : this.canvas.width, h = f ? f.height : this.canvas.height;
    return { x: ((e.clientX - r.left) * w) / r.width, y: ((e.clientY - r.top) * h) / r.height };
  }

  bindPointer() {
    let down = null;
    this.canvas.addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY }; });
    this.canvas.addEventListener('pointermove', (e) => {
      if (!this.on || down) return;  // a drag orbits
      const p = this.imagePosition(e);
      this.cursor = null;
      this.preview(p.x, p.y);
    });
    this.canvas.addEventListener('pointerup', (e) => {
      const click = down && Math.hypot(e.clientX - down.x, e.clientY - down.y) <= CLICK_SLOP_PX;
      down = null;
      if (!this.on || !click) return;
      const p = this.imagePosition(e);
      this.pick(p.x, p.y);
    });
    this.canvas.addEventListener('pointercancel', () => { down = null; });
  }

  key(e) {
    if (!this.on) return;
    const f = this.usableFrame();
    const steps = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1] };
    if (steps[e.key] && f) {
      const k = e.shiftKey ? KEY_STEP_FAST : KEY_STEP;
      const c = this.cursor || { x: f.width / 2, y: f.height / 2 };
      this.cursor = { x: Math.min(f.width - 0.5, Math.max(0.5, c.x + k * steps[e.key][0])), y: Math.min(f.height - 0.5, Math.max(0.5, c.y + k * steps[e.key][1])) };
      this.preview(this.cursor.x, this.cursor.y);
    } else if ((e.key === 'Enter' || e.key === ' ') && f) {
      const c = this.cursor || { x: f.width / 2, y: f.height / 2 };
      this.pick(c.x, c.y);
    } else {
      return;
    }
    e.preventDefault();
    e.stopImmediatePropagation();
  }

  // A new frame on screen: the markers follow its camera; a frame without the AOVs measuring needs asks for them.
  frameShown() {
    if (!this.on) return;
    const f = this.frame();
    if (f && !f.stats.views && (!f.aov || !f.aov.normal)) this.needAovs();
    this.drawOverlay();
  }
}
