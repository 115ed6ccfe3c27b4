// The CAD-view controls of the page: a section plane across an axis or
// through a clicked face (its position along the model's box, flip, caps,
// hatching), the explode factor,
// and per part of the assembly tree: shown, hidden, alone (isolated) or ghosted;
// a click on the image (outside the other picking modes) finds the part under
// the pointer in that list, from the face AOV and the tree's face ranges.
// They become render options (sections, explode, parts); while a slider moves,
// previews; on release, the full frame.

import { Camera } from './camera.js';
import { dot } from './vec3.js';

const AXES = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
// A click is a press and release this close (CSS px); farther, it was an orbit.
const CLICK_SLOP_PX = 4;
// What a part can be; `only` parts are shown alone (everything else hidden).
const PART_STATES = [['shown', 'shown'], ['hide', 'hidden'], ['only', 'alone'], ['ghost', 'ghosted']];

export class CadControls {
  // $: the page's element lookup; preview(): a preview frame; final(): the full frame.
  // frame(): the full-size frame on screen; needAovs(): asks for it again with
  // the AOVs; picking(): whether a click on the image is someone else's (measuring).
  constructor($, { preview, final, frame, needAovs, busyElsewhere }) {
    this.$ = $;
    this.box = null;     // the model's box {min, max}, mm
    this.parts = [];
    // The plane through a clicked face: {point, normal (towards the eye), lo, hi
    // (the box's extent along it), at (the slider's value through the point)}.
    this.facePlane = null;
    this.picking = false;  // the next click on the image sets facePlane
    this.pendingPick = null;  // a part pick waiting for a frame with face ids {px, py, width}
    Object.assign(this, { frame, needAovs, busyElsewhere });
    $('section-axis').addEventListener('change', () => {
      this.facePlane = null;
      this.setPicking($('section-axis').value === 'face');
      this.syncSection();
      if (!this.picking) final();
    });
    for (const id of ['section-flip', 'section-caps', 'section-hatch'])
      $(id).addEventListener('change', () => { this.syncSection(); final(); });
    $('section-pick').addEventListener('click', () => this.setPicking(true));
    this.bindPick($('view'));
    for (const id of ['section-at', 'explode']) {
      $(id).addEventListener('input', () => preview());
      $(id).addEventListener('change', () => final());
    }
    this.final = final;
  }

  // ---- a section plane from a clicked face ------------------------------------
  setPicking(on) {
    this.picking = on;
    const $ = this.$;
    $('view').classList.toggle('picking', on);
    $('section-pick').setAttribute('aria-pressed', String(on));
    $('section-hint').textContent = on ? 'Click a face in the image: the plane goes through that point, across the face\'s normal.' : '';
    const f = this.frame();
    if (on && f && (!f.aov || !f.aov.normal)) this.needAovs();
  }

  bindPick(canvas) {
    let down = null;
    canvas.addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY }; });
    canvas.addEventListener('pointercancel', () => { down = null; });
    canvas.addEventListener('pointerup', (e) => {
      const click = down && Math.hypot(e.clientX - down.x, e.clientY - down.y) <= CLICK_SLOP_PX;
      down = null;
      if (!click || this.busyElsewhere()) return;
      const r = canvas.getBoundingClientRect(), f = this.frame();
      if (!f) return;
      const px = ((e.clientX - r.left) * f.width) / r.width, py = ((e.clientY - r.top) * f.height) / r.height;
      if (this.picking) this.pickFace(f, px, py);
      else if (this.parts.length > 1) this.pickPart(f, px, py);
    });
  }

  // The plane through the exact surface point under image position (px, py)
  // (the pixel ray at the z AOV's distance, as measuring takes it) with the
  // face's exact normal (normal AOV) turned towards the eye, so that the
  // section removes the half nearer the viewer.
  pickFace(f, px, py) {
    const $ = this.$, hint = $('section-hint');
    if (f.stats.views || !f.aov || !f.aov.normal || !f.aov.z) {
      hint.textContent = 'Wait for the full-size frame with its normals, then click again.';
      this.needAovs();
      return;
    }
    const ix = Math.floor(px), iy = Math.floor(py), i = iy * f.width + ix;
    if (ix < 0 || iy < 0 || ix >= f.width || iy >= f.height || !f.aov.face[i]) {
      hint.textContent = 'Nothing there: click a face of the model.';
      return;
    }
    const ray = Camera.fromStatistics(f.stats.camera).rayAt(ix + 0.5, iy + 0.5, f.width, f.height);
    const point = ray.origin.map((o, k) => o + f.aov.z[i] * ray.dir[k]);
    let normal = [0, 1, 2].map((k) => f.aov.normal[3 * i + k]);
    if (dot(normal, ray.dir) > 0) normal = normal.map((c) => -c);
    // The slider spans the model's box along the normal; its value at the point puts the plane through it.
    const along = this.boxCorners().map((c) => dot(c, normal));
    const lo = Math.min(...along), hi = Math.max(...along);
    const at = hi > lo ? (dot(point, normal) - lo) / (hi - lo) : 0.5;
    this.facePlane = { point, normal, lo, hi, at, face: f.aov.face[i] };
    $('section-at').step = 'any';  // the exact value through the point, not a step's
    $('section-at').value = String(at);
    $('section-flip').checked = false;
    this.setPicking(false);
    hint.textContent = `Plane through face ${f.aov.face[i]} at (${point.map((c) => c.toFixed(3)).join(', ')}), ` +
      `normal (${normal.map((c) => c.toFixed(4)).join(', ')}); drag "Section position" to move it along its normal.`;
    this.syncSection();
    this.final();
  }

  // ---- the part under the pointer --------------------------------------------
  // A full-size frame is on screen: a part pick waiting for face ids is made on it.
  frameShown(f) {
    const p = this.pendingPick;
    if (p && f.aov && f.aov.face && f.width === p.width) this.pickPart(f, p.px, p.py);
  }

  // The leaf part that places face `face` (1..N, the face AOV's number).
  partOfFace(face) {
    for (const part of this.parts)
      for (const [first, last] of part.face_ranges || []) if (face >= first && face <= last) return part;
    return null;
  }

  pickPart(f, px, py) {
    const $ = this.$, hint = $('parts-hint');
    const ix = Math.floor(px), iy = Math.floor(py);
    if (f.stats.views || ix < 0 || iy < 0 || ix >= f.width || iy >= f.height) return;
    if (!f.aov || !f.aov.face) {
      // The frame on screen came without face ids: asked for, and the pick is
      // made when they land (frameShown).
      hint.textContent = 'Finding the part…';
      this.pendingPick = { px, py, width: f.width };
      this.needAovs();
      return;
    }
    this.pendingPick = null;
    const face = f.aov.face[iy * f.width + ix];
    const part = face ? this.partOfFace(face) : null;
    for (const li of $('parts').querySelectorAll('li.picked')) li.classList.remove('picked');
    if (!part) {
      hint.textContent = face ? `Face ${face} belongs to no part of the tree.` : 'Nothing there: click a part of the model.';
      return;
    }
    const select = $('parts').querySelector(`select[data-part="${CSS.escape(part.id)}"]`);
    $('parts-box').open = true;
    select.closest('li').classList.add('picked');
    select.focus();
    hint.textContent = `Face ${face}: part ${part.id} ${part.name}.`;
  }

  boxCorners() {
    if (!this.box) return [[0, 0, 0]];
    const { min, max } = this.box, out = [];
    for (let c = 0; c < 8; c++) out.push([c & 1 ? max[0] : min[0], c & 2 ? max[1] : min[1], c & 4 ? max[2] : min[2]]);
    return out;
  }

  // A new model: its box and tree from the stored file's summary (null: none known).
  setModel(summary) {
    const $ = this.$;
    this.facePlane = null;
    this.pendingPick = null;
    this.setPicking(false);
    $('section-at').step = '0.01';
    this.box = summary?.bbox || null;
    this.parts = summary?.parts || [];
    $('section-axis').value = '';
    $('section-at').value = '0.5';
    $('explode').value = '0';
    this.syncSection();
    const list = $('parts');
    list.replaceChildren();
    $('parts-hint').textContent = '';
    for (const part of this.parts) {
      const depth = part.id.split('/').length - 1;
      const item = document.createElement('li');
      item.style.paddingLeft = `${depth}rem`;
      const label = document.createElement('label');
      const select = document.createElement('select');
      select.dataset.part = part.id;
      for (const [value, text] of PART_STATES) select.append(new Option(text, value));
      select.addEventListener('change', () => this.final());
      label.append(select, ` ${part.id} ${part.name} (${part.faces} faces)`);
      item.append(label);
      list.append(item);
    }
    $('parts-box').hidden = this.parts.length < 2;
  }

  syncSection() {
    const $ = this.$, axis = $('section-axis').value, off = axis === '' || (axis === 'face' && !this.facePlane);
    $('section-pick').hidden = axis !== 'face';
    if (axis !== 'face') $('section-at').step = '0.01';
    for (const id of ['section-at', 'section-flip', 'section-caps', 'section-hatch']) $(id).disabled = off;
  }

  // The render options of the controls (none where they are at rest).
  options() {
    const $ = this.$, o = {};
    const axis = $('section-axis').value, t = Number($('section-at').value);
    const sign = $('section-flip').checked ? -1 : 1;
    const fp = axis === 'face' ? this.facePlane : null;
    if (fp) {
      // Moved along its normal by the slider's travel from the clicked point (exactly there at rest).
      const shift = t === fp.at ? 0 : (t - fp.at) * (fp.hi - fp.lo);
      o.sections = [{ point: fp.point.map((c, k) => c + shift * fp.normal[k]), normal: fp.normal.map((c) => sign * c) }];
    } else if (axis !== '' && axis !== 'face' && this.box) {
      const k = Number(axis);
      const point = [0, 1, 2].map((i) => (this.box.min[i] + this.box.max[i]) / 2);
      point[k] = this.box.min[k] + t * (this.box.max[k] - this.box.min[k]);
      o.sections = [{ point, normal: AXES[k].map((c) => sign * c) }];
    }
    if (o.sections) {
      o.section_caps = $('section-caps').checked;
      o.section_hatch = $('section-hatch').checked;
    }
    const explode = Number($('explode').value);
    if (explode > 0) o.explode = explode;
    const parts = { hide: [], only: [], ghost: [] };
    for (const select of $('parts').querySelectorAll('select'))
      if (select.value !== 'shown') parts[select.value].push(select.dataset.part);
    for (const key of Object.keys(parts)) if (!parts[key].length) delete parts[key];
    if (Object.keys(parts).length) o.parts = parts;
    return o;
  }
}
