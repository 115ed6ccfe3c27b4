// The REST API as the page uses it: the API key (kept in sessionStorage, sent
// as a header, never in a URL), fetch with problem+json errors turned into
// readable messages, base64 decoding and downloads.

const KEY_NAME = 'nurbsrt.apiKey';

export function apiKey() {
  return sessionStorage.getItem(KEY_NAME) || '';
}

export function setApiKey(key) {
  if (key) sessionStorage.setItem(KEY_NAME, key);
  else sessionStorage.removeItem(KEY_NAME);
}

// An API error with the problem document's fields (RFC 9457).
export class ApiError extends Error {
  constructor(status, problem) {
    const title = problem?.title || `HTTP ${status}`;
    const detail = problem?.detail ? `: ${problem.detail}` : '';
    super(`${title}${detail}`);
    this.status = status;
    this.code = problem?.code || '';
    this.requestId = problem?.request_id || '';
  }
}

async function problemOf(res) {
  const type = res.headers.get('Content-Type') || '';
  if (!type.includes('json')) return null;
  try {
    return await res.json();
  } catch {
    return null;
  }
}

// fetch() of an API path with the key; throws ApiError for any non-2xx answer.
// A request without side effects (`retry`: GETs, renders, conversions) is sent
// once more when the connection fails: a server may close an idle persistent
// connection just as the browser reuses it, and Chromium does not resend a
// POST whose body is a file (RFC 9112, 9.3.1: a client may retry requests it
// knows to be idempotent). A job is never sent twice.
export async function call(path, { method = 'GET', body, signal, accept = 'application/json', retry = method === 'GET', contentType, lastEventId } = {}) {
  const headers = { Accept: accept };
  if (contentType) headers['Content-Type'] = contentType;
  if (lastEventId) headers['Last-Event-ID'] = lastEventId;
  const key = apiKey();
  if (key) headers.Authorization = `Bearer ${key}`;
  const send = () => fetch(path, { method, body, headers, signal, cache: 'no-store' });
  let res;
  try {
    res = await send();
  } catch (error) {
    if (!retry || error.name === 'AbortError') throw error;
    res = await send();
  }
  if (!res.ok) throw new ApiError(res.status, await problemOf(res));
  return res;
}

// multipart/form-data with the file and a JSON `options` part.
export function uploadForm(file, options) {
  const form = new FormData();
  form.append('file', file, file.name || 'upload');
  if (options) form.append('options', new Blob([JSON.stringify(options)], { type: 'application/json' }));
  return form;
}

// POST /v1/files: the file stored once (StoredFile: id, filename, ...); every
// frame after names it by id instead of sending it again.
export async function storeFile(file, signal) {
  const res = await call('/v1/files', { method: 'POST', body: uploadForm(file, null), signal });
  return res.json();
}

// GET /v1/files/{id}: a stored file's description (a link that reopens it).
export async function storedFile(id, signal) {
  return (await call(`/v1/files/${encodeURIComponent(id)}`, { signal })).json();
}

// POST /v1/renders of a stored file, answered as JSON (RenderResponse).
export async function render(fileId, options, signal) {
  const res = await call('/v1/renders', {
    method: 'POST', body: JSON.stringify({ file_id: fileId, ...options }), contentType: 'application/json', signal, retry: true,
  });
  return res.json();
}

export function base64Bytes(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

// Offers `blob` as a download named `name` (a blob: URL, so the key never
// appears in a URL and the browser does not fetch anything itself).
export function saveBlob(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = url;
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60000);
}

// The file name of a Content-Disposition header, or `fallback`.
export function dispositionName(res, fallback) {
  const m = /filename="([^"]+)"/.exec(res.headers.get('Content-Disposition') || '');
  return m ? m[1] : fallback;
}
