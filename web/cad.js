// The CAD-view controls of the page: a section plane across an axis (its
// position along the model's box, flip, caps, hatching), the explode factor,
// and per part of the assembly tree: shown, hidden, alone (isolated) or ghosted.
// They become render options (sections, explode, parts); while a slider moves,
// previews; on release, the full frame.

const AXES = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
// What a part can be; `only` parts are shown alone (everything else hidden).
const PART_STATES = [['shown', 'shown'], ['hide', 'hidden'], ['only', 'alone'], ['ghost', 'ghosted']];

export class CadControls {
  // $: the page's element lookup; preview(): a preview frame; final(): the full frame.
  constructor($, { preview, final }) {
    this.$ = $;
    this.box = null;     // the model's box {min, max}, mm
    this.parts = [];
    for (const id of ['section-axis', 'section-flip', 'section-caps', 'section-hatch'])
      $(id).addEventListener('change', () => { this.syncSection(); final(); });
    for (const id of ['section-at', 'explode']) {
      $(id).addEventListener('input', () => preview());
      $(id).addEventListener('change', () => final());
    }
    this.final = final;
  }

  // A new model: its box and tree from the stored file's summary (null: none known).
  setModel(summary) {
    const $ = this.$;
    this.box = summary?.bbox || null;
    this.parts = summary?.parts || [];
    $('section-axis').value = '';
    $('section-at').value = '0.5';
    $('explode').value = '0';
    this.syncSection();
    const list = $('parts');
    list.replaceChildren();
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
    const $ = this.$, off = $('section-axis').value === '';
    for (const id of ['section-at', 'section-flip', 'section-caps', 'section-hatch']) $(id).disabled = off;
  }

  // The render options of the controls (none where they are at rest).
  options() {
    const $ = this.$, o = {};
    const axis = $('section-axis').value;
    if (axis !== '' && this.box) {
      const k = Number(axis), t = Number($('section-at').value);
      const point = [0, 1, 2].map((i) => (this.box.min[i] + this.box.max[i]) / 2);
      point[k] = this.box.min[k] + t * (this.box.max[k] - this.box.min[k]);
      const sign = $('section-flip').checked ? -1 : 1;
      o.sections = [{ point, normal: AXES[k].map((c) => sign * c) }];
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
