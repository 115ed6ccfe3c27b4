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

from .errors import ApiError, error_for

# A model to send: a path, its bytes, or the id of a file already stored (64 hex digits).
Source = Union[str, os.PathLike, bytes]

_FILE_ID = re.compile(r"^[0-9a-f]{64}$")
# Busy answers (429, 503) are retried after Retry-After, at most this many times,
# never waiting longer than this per try: a pipeline should not hang on a full queue.
DEFAULT_RETRIES = 5
MAX_RETRY_WAIT_S = 30.0


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
    def _request(self, method: str, path: str, **kw: Any) -> requests.Response:
        """Sends, retrying busy answers (429, 503) after their Retry-After; raises ApiError
        (typed by status) for any other non-2xx answer."""
        for attempt in range(self.retries + 1):
            resp = self.session.request(method, self.url + path, timeout=self.timeout, **kw)
            if resp.status_code in (429, 503) and attempt < self.retries:
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

    def wait(self, job_id: str, progress: Callable[[dict[str, Any]], None] | None = None,
             interval: float = 0.25, timeout: float | None = None) -> dict[str, Any]:
        """Waits for a job to end (succeeded or failed) and returns its document. `progress` is
        called with the document whenever its state, progress or an output's state changed."""
        deadline = None if timeout is None else time.monotonic() + timeout
        last = None
        while True:
            job = self.job(job_id)
            seen = (job["state"], job["progress"], tuple(o["state"] for o in job["outputs"]))
            if progress and seen != last:
                progress(job)
            last = seen
            if job["state"] in ("succeeded", "failed"):
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


__all__ = ["ApiError", "Client", "Conversion", "Render"]
