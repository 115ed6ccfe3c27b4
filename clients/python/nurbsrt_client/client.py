"""The service's REST API as Python calls: stored files, renders, conversions, jobs."""
from __future__ import annotations

import base64
import json
import os
import pathlib
import re
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator, Union

import requests

from .errors import ApiError, NotFound, Unavailable, error_for

# A model to send: a path, its bytes, or the id of a file already stored (64 hex digits).
Source = Union[str, os.PathLike, bytes]

_FILE_ID = re.compile(r"^[0-9a-f]{64}$")
# Busy answers (429, 503) are retried after Retry-After, at most this many times,
# never waiting longer than this per try: a pipeline should not hang on a full queue.
DEFAULT_RETRIES = 5
MAX_RETRY_WAIT_S = 30.0
# The service writes a comment on a quiet event stream every 15 s: a stream silent
# for four times that is dead, and is reconnected.
EVENT_READ_TIMEOUT_S = 60.0
# Dropped event streams reconnected in a row before giving up (each resumes after the
# last event seen, so nothing is missed or repeated), waiting this long between tries.
EVENT_RECONNECTS = 5
EVENT_RECONNECT_WAIT_S = 1.0
# Job states after which nothing changes.
FINISHED = ("succeeded", "failed", "canceled")


@dataclass
class Render:
    """A render's answer: the image (a contact sheet for several views; empty for layout
    "separate", see `images`), its statistics and the import's warnings."""
    image: bytes
    content_type: str
    statistics: dict[str, Any]
    warnings: list[str]
    images: dict[str, bytes] = field(default_factory=dict)  # layout "separate": view name -> image


@dataclass
class Conversion:
    """A conversion's answer: the converted file and its report (fidelity, warnings, timings)."""
    data: bytes
    content_type: str
    report: dict[str, Any]

    @property
    def warnings(self) -> list[str]:
        return self.report.get("warnings", [])


@dataclass
class Event:
    """One event of a job (GET /v1/jobs/{id}/events): its id (seq 1, 2, ... of the job), its
    type (state, output, artifact, progress) and its data object."""
    id: int
    type: str
    data: dict[str, Any]

    @property
    def terminal(self) -> bool:
        """The job's last event: its state became succeeded, failed or canceled."""
        return self.type == "state" and self.data.get("state") in FINISHED


@dataclass
class Progress:
    """What `wait` reports: the job's state and its outputs finished of the total (a fraction
    0..1), the artifact bytes written, and the event that brought it (None when polled)."""
    state: str
    fraction: float
    outputs_done: int
    outputs_total: int
    artifact_bytes: int
    event: Event | None = None


def parse_sse(lines: Iterator[str]) -> Iterator[tuple[str, str, str]]:
    """Server-sent events (WHATWG HTML, "Server-sent events", interpreting an event stream)
    from the stream's lines: (id, event type, data) of each dispatched event; comments and
    unknown fields are ignored, `data` lines are joined by newlines."""
    event_id, event_type, data = "", "", []
    for line in lines:
        if line == "":
            if data:
                yield event_id, event_type or "message", "\n".join(data)
            event_type, data = "", []
            continue
        if line.startswith(":"):
            continue
        name, _, value = line.partition(":")
        value = value[1:] if value.startswith(" ") else value
        if name == "data":
            data.append(value)
        elif name == "event":
            event_type = value
        elif name == "id" and "\0" not in value:
            event_id = value


def _clean(options: dict[str, Any]) -> dict[str, Any]:
    """Keyword options as the API takes them: None means "the default" and is left out."""
    return {k: v for k, v in options.items() if v is not None}


class Client:
    """One service. `api_key`: sent as `Authorization: Bearer` when the service needs one."""

    def __init__(self, url: str, api_key: str | None = None, timeout: float = 300.0,
                 retries: int = DEFAULT_RETRIES, session: requests.Session | None = None):
        self.url = url.rstrip("/")
        self.timeout = timeout
        self.retries = retries
        self.session = session or requests.Session()
        if api_key:
            self.session.headers["Authorization"] = f"Bearer {api_key}"

    # ---- transport -------------------------------------------------------------------
    def _request(self, method: str, path: str, read_timeout: float | None = None, retries: int | None = None,
                 **kw: Any) -> requests.Response:
        """Sends, retrying busy answers (429, 503) after their Retry-After (`retries` times, default
        the client's); raises ApiError (typed by status) for any other non-2xx answer.
        `read_timeout`: the longest silence while reading the answer, when not the client's timeout."""
        timeout = self.timeout if read_timeout is None else (self.timeout, read_timeout)
        retries = self.retries if retries is None else retries
        for attempt in range(retries + 1):
            resp = self.session.request(method, self.url + path, timeout=timeout, **kw)
            if resp.status_code in (429, 503) and attempt < retries:
                try:
                    wait = float(resp.headers.get("Retry-After", "1"))
                except ValueError:
                    wait = 1.0
                time.sleep(min(max(wait, 0.1), MAX_RETRY_WAIT_S))
                continue
            break
        if resp.status_code >= 400:
            try:
                problem = resp.json()
            except ValueError:
                problem = None
            raise error_for(resp.status_code, problem if isinstance(problem, dict) else None, resp.text)
        return resp

    @staticmethod
    def _read(source: Source, filename: str | None = None) -> tuple[str, bytes]:
        if isinstance(source, bytes):
            return filename or "model", source
        path = pathlib.Path(source)
        return filename or path.name, path.read_bytes()

    @staticmethod
    def _is_file_id(source: Source) -> bool:
        return isinstance(source, str) and bool(_FILE_ID.match(source)) and not os.path.exists(source)

    def _send_model(self, path: str, source: Source, options: dict[str, Any]) -> requests.Response:
        """POST of a model (stored id: a JSON body; else a multipart upload with an options part)."""
        headers = {"Accept": "application/json"}
        if self._is_file_id(source):
            return self._request("POST", path, json={"file_id": source, **options}, headers=headers)
        name, data = self._read(source)
        files = {"file": (name, data, "application/octet-stream"),
                 "options": (None, json.dumps(options), "application/json")}
        return self._request("POST", path, files=files, headers=headers)

    # ---- stored files ------------------------------------------------------------------
    def upload(self, source: Source, filename: str | None = None) -> dict[str, Any]:
        """Stores a model once (POST /v1/files); the StoredFile, whose `id` renders, conversions
        and jobs take instead of the bytes. The same bytes give the same id."""
        name, data = self._read(source, filename)
        return self._request("POST", "/v1/files", files={"file": (name, data, "application/octet-stream")}).json()

    def file(self, file_id: str) -> dict[str, Any]:
        return self._request("GET", f"/v1/files/{file_id}").json()

    def files(self) -> Iterator[dict[str, Any]]:
        """Every stored file, page after page."""
        cursor = None
        while True:
            page = self._request("GET", "/v1/files", params=_clean({"cursor": cursor})).json()
            yield from page["files"]
            cursor = page.get("next_cursor")
            if not cursor:
                return

    def delete_file(self, file_id: str) -> None:
        self._request("DELETE", f"/v1/files/{file_id}")

    # ---- renders and conversions ---------------------------------------------------------
    def render(self, source: Source, **options: Any) -> Render:
        """Renders a model (path, bytes or stored id) with the API's render options as keyword
        arguments: width, height, view, views, layout, format, antialias, edges, shadows,
        sections, parts, explode, camera, ... (None: the default)."""
        doc = self._send_model("/v1/renders", source, _clean(options)).json()
        images = {i["view"]: base64.b64decode(i["image_base64"]) for i in doc.get("images", [])}
        image = base64.b64decode(doc["image_base64"]) if "image_base64" in doc else b""
        return Render(image, doc["content_type"], doc["statistics"], doc.get("warnings", []), images)

    def convert(self, source: Source, format: str, **options: Any) -> Conversion:
        """Converts a model to `format` (step, iges, brep, stl, glb, obj, vrml, json) with the
        conversion options as keyword arguments (units, step_schema, iges_mode, strict, ...)."""
        doc = self._send_model("/v1/conversions", source, _clean({"format": format, **options})).json()
        return Conversion(base64.b64decode(doc["data_base64"]), doc["content_type"], doc)

    # ---- jobs ------------------------------------------------------------------------------
    def submit_job(self, files: list[Source], outputs: list[dict[str, Any]], callback_url: str | None = None,
                   force: bool = False) -> dict[str, Any]:
        """Submits a batch job: `files` in order (uploads first, then stored ids, as the API numbers
        them), `outputs` as JobOutputSpec objects ({"file": 0, "type": "render", "options": {...}} or
        {"file": 0, "type": "conversion", "format": "stl"}). The Job document."""
        uploads = [f for f in files if not self._is_file_id(f)]
        stored = [f for f in files if self._is_file_id(f)]
        if files != uploads + stored:
            raise ValueError("list the files to upload before the stored ids: the API numbers them so")
        parts: list[tuple[str, tuple[Any, ...]]] = []
        for f in uploads:
            name, data = self._read(f)
            parts.append(("file", (name, data, "application/octet-stream")))
        parts += [("file_id", (None, f)) for f in stored]
        spec = _clean({"outputs": outputs, "callback_url": callback_url, "force": force or None})
        parts.append(("job", (None, json.dumps(spec), "application/json")))
        return self._request("POST", "/v1/jobs", files=parts).json()

    def job(self, job_id: str) -> dict[str, Any]:
        return self._request("GET", f"/v1/jobs/{job_id}").json()

    def _open_events(self, job_id: str, last_event_id: int | None, retries: int | None) -> requests.Response:
        headers = {"Accept": "text/event-stream"}
        if last_event_id is not None:
            headers["Last-Event-ID"] = str(last_event_id)
        return self._request("GET", f"/v1/jobs/{job_id}/events", headers=headers, stream=True,
                             read_timeout=EVENT_READ_TIMEOUT_S, retries=retries)

    def events(self, job_id: str, last_event_id: int | None = None, reconnects: int = EVENT_RECONNECTS,
               busy_retries: int | None = None) -> Iterator[Event]:
        """The job's events as they happen (after `last_event_id`, or from its first), until its
        terminal state event. A dropped connection is reopened with Last-Event-ID (possibly on
        another instance behind a balancer): no event is missed or repeated. Raises NotFound
        for an unknown job, Unavailable when the service refuses a stream `busy_retries` times
        (default: the client's retries) after its Retry-After."""
        last = last_event_id
        failures = 0
        while True:
            got = 0
            try:
                resp = self._open_events(job_id, last, busy_retries)
                try:
                    for sid, kind, data in parse_sse(resp.iter_lines(decode_unicode=True)):
                        event = Event(int(sid), kind, json.loads(data))
                        last, got, failures = event.id, got + 1, 0
                        yield event
                        if event.terminal:
                            return
                finally:
                    resp.close()
            except (requests.ConnectionError, requests.Timeout, requests.exceptions.ChunkedEncodingError):
                failures += 1
                if failures > reconnects:
                    raise
                time.sleep(EVENT_RECONNECT_WAIT_S)
                continue
            # The stream ended before the job's end (the service stopping, say): reopen it,
            # unless it brought nothing and the job is over (every event was seen already).
            if got == 0 and self.job(job_id)["state"] in FINISHED:
                return

    def wait(self, job_id: str, progress: Callable[[Progress], None] | None = None,
             interval: float = 0.25, timeout: float | None = None) -> dict[str, Any]:
        """Waits for a job to end and returns its document. `progress` is called with a
        Progress whenever the job's state or its outputs finished change: fed by the events
        stream, or by polling every `interval` s where the service has none (404) or refuses
        one more stream (503)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        job = self.job(job_id)  # NotFound for an unknown job; a NotFound below means no events endpoint
        try:
            return self._wait_events(job_id, progress, deadline, len(job["outputs"]))
        except (Unavailable, NotFound):
            pass
        return self._wait_polling(job_id, progress, interval, deadline, timeout)

    def _wait_events(self, job_id: str, progress: Callable[[Progress], None] | None,
                     deadline: float | None, outputs: int) -> dict[str, Any]:
        state, numbers = "queued", (0.0, 0, outputs, 0)
        for event in self.events(job_id, busy_retries=0):
            if event.type == "state":
                state = event.data["state"]
            elif event.type == "progress":
                d = event.data
                numbers = (d["fraction"], d["outputs_done"], d["outputs_total"], d["artifact_bytes"])
            if progress and event.type in ("state", "progress"):
                progress(Progress(state, *numbers, event=event))
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError(f"job {job_id} still {state} at its deadline")
        return self.job(job_id)

    def _wait_polling(self, job_id: str, progress: Callable[[Progress], None] | None, interval: float,
                      deadline: float | None, timeout: float | None) -> dict[str, Any]:
        last = None
        while True:
            job = self.job(job_id)
            outs = job["outputs"]
            done = sum(o["state"] in FINISHED for o in outs)
            seen = Progress(job["state"], done / len(outs) if outs else 0.0, done, len(outs),
                            sum(o.get("artifact", {}).get("bytes", 0) for o in outs if o["state"] == "succeeded"))
            if progress and seen != last:
                progress(seen)
            last = seen
            if job["state"] in FINISHED:
                return job
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError(f"job {job_id} still {job['state']} after {timeout} s")
            time.sleep(interval)

    def download(self, output: dict[str, Any] | str, path: str | os.PathLike | None = None) -> bytes:
        """An output's artifact (a JobOutput, or its artifact URL); written to `path` when given."""
        url = output if isinstance(output, str) else output["artifact"]["url"]
        data = self._request("GET", url).content
        if path is not None:
            pathlib.Path(path).write_bytes(data)
        return data

    def cancel(self, job_id: str) -> None:
        self._request("DELETE", f"/v1/jobs/{job_id}")


__all__ = ["ApiError", "Client", "Conversion", "Event", "Progress", "Render", "parse_sse"]
