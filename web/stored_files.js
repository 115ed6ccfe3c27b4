// The stored files (GET /v1/files, newest first): a list to reopen one by id,
// without uploading it again.

import { call } from './api.js';

// One page is enough for a person choosing among recent files (the API's maximum is 100).
const LISTED_FILES = 20;

// list: the <ul>; open(stored): reopens a stored file; report(error).
export function bindStoredFiles({ panel, list, refresh, open, report }) {
  async function load() {
    try {
      const page = await (await call(`/v1/files?limit=${LISTED_FILES}`)).json();
      list.replaceChildren(...page.files.map((f) => {
        const item = document.createElement('li');
        const button = document.createElement('button');
        button.type = 'button';
        button.className = 'reopen';
        button.dataset.file = f.id;
        button.textContent = f.filename;
        button.addEventListener('click', () => open(f));
        const faces = f.summary ? `, ${f.summary.faces} faces` : '';
        item.append(button, ` ${f.format}, ${(f.bytes / 1024).toFixed(0)} KiB${faces}, ${f.created_at.replace('T', ' ').slice(0, 16)}`);
        return item;
      }));
      if (!page.files.length) list.append(Object.assign(document.createElement('li'), { textContent: 'No stored files.' }));
      list.dataset.loaded = String(Number(list.dataset.loaded || 0) + 1);
    } catch (error) {
      report(error);
    }
  }
  // Read when the panel opens (and on demand), not on every page load: the key may not be set yet.
  panel.addEventListener('toggle', () => { if (panel.open) load(); });
  refresh.addEventListener('click', load);
  return { reload: () => { if (panel.open) load(); } };
}
