// Batch jobs (POST /v1/jobs, followed through GET /v1/jobs/{id}/events with
// GET /v1/jobs/{id} for the table, artifacts downloaded with the key) and
// single conversions (POST /v1/conversions).

import { call, saveBlob, dispositionName, uploadForm, base64Bytes } from './api.js';

const POLL_MS = 500;  // where the events stream is refused (its cap) or breaks
const DONE = new Set(['succeeded', 'failed', 'canceled']);

// The Server-Sent Events of one response, as {id, event, data} (WHATWG HTML,
// "Server-sent events": fields up to a blank line, comments start with ':').
// fetch() and not EventSource, which cannot send the API key's header.
async function* serverSentEvents(res) {
  const reader = res.body.pipeThrough(new TextDecoderStream()).getReader();
  let buffer = '', event = { data: [] };
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    buffer += value;
    let cut;
    while ((cut = buffer.search(/\r?\n/)) >= 0) {
      const line = buffer.slice(0, cut);
      buffer = buffer.slice(cut + (buffer[cut] === '\r' ? 2 : 1));
      if (line === '') {
        if (event.data.length) yield { id: event.id, event: event.event || 'message', data: event.data.join('\n') };
        event = { data: [] };
      } else if (!line.startsWith(':')) {
        const colon = line.indexOf(':');
        const field = colon < 0 ? line : line.slice(0, colon);
        const text = colon < 0 ? '' : line.slice(colon + 1).replace(/^ /, '');
        if (field === 'data') event.data.push(text);
        else if (field === 'id' || field === 'event') event[field] = text;
      }
    }
  }
}

// Follows a job until it ends: each event re-reads the job document for the
// table; progress events give the percentage. A stream that breaks is resumed
// with Last-Event-ID; one refused (503 at its cap) falls back to polling.
async function followJob(job, show) {
  let last = '', progress = null;
  while (!DONE.has(job.state)) {
    let res = null;
    try {
      res = await call(`${job.url}/events`, { accept: 'text/event-stream', ...(last && { lastEventId: last }) });
    } catch (err) {
      if (err.status !== 503) throw err;
    }
    if (!res) {
      await new Promise((r) => setTimeout(r, POLL_MS));
      job = await (await call(job.url)).json();
      show(job, progress);
      continue;
    }
    try {
      for await (const e of serverSentEvents(res)) {
        last = e.id || last;
        if (e.event === 'progress') progress = JSON.parse(e.data);
        if (e.event === 'progress' || e.event === 'state') {
          job = await (await call(job.url)).json();
          show(job, progress);
        }
      }
    } catch (err) {
      if (err.name === 'AbortError') throw err;  // a broken stream: resumed from `last` below
    }
    job = await (await call(job.url)).json();
    show(job, progress);
  }
  return job;
}

function el(tag, props = {}, ...children) {
  const e = document.createElement(tag);
  Object.assign(e, props);
  e.append(...children);
  return e;
}

// The job description for these files and outputs ("render:png", "conversion:stl").
export function jobSpec(fileCount, outputs, renderOptions) {
  const list = [];
  for (let file = 0; file < fileCount; file++)
    for (const out of outputs) {
      const [type, format] = out.split(':');
      if (type === 'render') list.push({ file, type, options: { ...renderOptions, format } });
      else list.push({ file, type, format });
    }
  return { outputs: list };
}

async function download(artifact, status) {
  const res = await call(artifact.url, { accept: '*/*' });
  const blob = await res.blob();
  saveBlob(blob, artifact.name);
  status.textContent = `downloaded ${artifact.name} (${blob.size} bytes)`;
}

function outputRow(job, o, report) {
  const what = o.type === 'render' ? `render ${o.format}` : `→ ${o.format}`;
  const progress = el('progress', { max: 1, value: o.progress || 0 });
  progress.setAttribute('aria-label', `progress of ${job.files[o.file].filename} ${what}`);
  const cell = el('td');
  if (o.artifact) {
    const button = el('button', { type: 'button', textContent: `Download ${o.artifact.name}` });
    button.classList.add('download');
    button.addEventListener('click', () => download(o.artifact, cell.lastChild).catch(report));
    cell.append(button, el('span', { className: 'download-status' }));
  } else if (o.error) {
    cell.append(`${o.error.code}: ${o.error.message}`);
  }
  return el('tr', {}, el('td', { textContent: job.files[o.file].filename }), el('td', { textContent: what }),
    el('td', { textContent: o.state }, ' ', progress), cell);
}

function renderJob(box, job, report, progress) {
  // A finished job's document is the final word: the events before its end are
  // still being shown one by one (each re-reads the document), so the last
  // progress event seen may lag behind the state read with it.
  const live = progress && !DONE.has(job.state);
  const done = live ? progress.outputs_done : job.outputs.filter((o) => DONE.has(o.state)).length;
  const total = live ? progress.outputs_total : job.outputs.length;
  const percent = total ? Math.floor((100 * done) / total) : 0;
  box.dataset.percent = String(percent);
  const table = el('table', {},
    el('caption', { textContent: `Job ${job.id.slice(0, 8)}: ${job.state}, ${percent} % (${done} of ${total} outputs)` }),
    el('thead', {}, el('tr', {}, ...['File', 'Output', 'State', 'Artifact'].map((h) => el('th', { scope: 'col', textContent: h })))),
    el('tbody', {}, ...job.outputs.map((o) => outputRow(job, o, report))));
  box.replaceChildren(table);
  box.dataset.state = job.state;
}

export function bindJobs({ form, files, list, renderOptions, report }) {
  form.addEventListener('submit', async (e) => {
    e.preventDefault();
    const chosen = [...files.files];
    const outputs = [...form.querySelectorAll('input[name=out]:checked')].map((c) => c.value);
    if (!chosen.length || !outputs.length) {
      report(new Error('Choose at least one file and one output for the job.'));
      return;
    }
    const body = new FormData();
    for (const f of chosen) body.append('file', f, f.name);
    body.append('job', new Blob([JSON.stringify(jobSpec(chosen.length, outputs, renderOptions()))], { type: 'application/json' }));
    const submit = form.querySelector('button[type=submit]');
    submit.disabled = true;
    try {
      let job = await (await call('/v1/jobs', { method: 'POST', body })).json();
      const box = el('div', { className: 'job' });
      box.dataset.id = job.id;
      list.prepend(box);
      renderJob(box, job, report, null);
      const percents = [];  // every percentage shown, for the page's test
      job = await followJob(job, (j, progress) => {
        renderJob(box, j, report, progress);
        percents.push(box.dataset.percent);
        box.dataset.percents = percents.join(',');
      });
    } catch (err) {
      report(err);
    } finally {
      submit.disabled = false;
    }
  });
}

export function bindConversions({ form, file, format, result, currentFile, report }) {
  form.addEventListener('submit', async (e) => {
    e.preventDefault();
    // A file chosen here is uploaded; else the one on screen is named by its stored id.
    const picked = file.files[0], stored = picked ? null : currentFile();
    const input = picked || stored;
    if (!input) {
      report(new Error('Choose a file to convert (or load one to render first).'));
      return;
    }
    result.textContent = `Converting ${input.name}…`;
    try {
      const request = picked ? { body: uploadForm(picked, { format: format.value }) }
        : { body: JSON.stringify({ file_id: stored.id, format: format.value }), contentType: 'application/json' };
      const res = await call('/v1/conversions', { method: 'POST', ...request, retry: true });
      const doc = await res.json();
      const name = dispositionName(res, input.name.replace(/\.[^.]*$/, '') + '.' + format.value);
      const blob = new Blob([base64Bytes(doc.data_base64)], { type: doc.content_type });
      saveBlob(blob, name);
      const t = doc.timings_ms;
      result.textContent = `${doc.input_format} → ${doc.output_format}: ${doc.faces} faces` +
        (doc.triangles ? `, ${doc.triangles} triangles` : '') +
        `, ${blob.size} bytes in ${t.total.toFixed(0)} ms (read ${t.read.toFixed(0)}, write ${t.write.toFixed(0)}); saved as ${name}`;
    } catch (err) {
      result.textContent = '';
      report(err);
    }
  });
}
